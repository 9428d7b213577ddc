"""Marker sets: which marker rides on which segment, and the segment tree.

A marker set is a small TOML file (the built-in ones live in
``vidcap/mocap/markersets/*.toml``)::

    name = "cmu41"
    description = "CMU Graphics Lab 41-marker full-body set"

    [segments.pelvis]                 # the first segment is the root (>= 3 markers)
    joint = "pelvis"                  # the BVH root joint
    markers = ["LFWT", "RFWT", "LBWT", "RBWT"]
    origin = ["l_hip", "r_hip"]       # root joint = mean of these child joint centres
    side = ["l_hip", "r_hip"]         # left-to-right vector -> +X in the T-pose

    [segments.l_upper_leg]
    parent = "pelvis"
    joint = "l_hip"                   # joint between parent and this segment
    markers = ["LTHI", "LKNE"]
    tip = "l_knee"                    # what the segment points at in the T-pose...
    rest = "-y"                       # ...and in which direction (x, -x, y, -y, z, -z)
    fallback = ["LKNE"]               # optional: markers whose centroid stands in for
                                      # the joint centre when the joint barely moves
    end = { joint = "l_toe", markers = ["LTOE"] }   # optional extra leaf joint

Optional keys beyond these (Plug-in-Gait and the ``anatomical`` set use them)::

    [segments.pelvis]
    markers = ["LASI", "RASI", "LPSI", "RPSI", "SACR"]
    optional = ["LPSI", "RPSI", "SACR"]   # markers a file may lack without a warning
                                          # (a protocol's variants)
    hip_regression = { asis = ["LASI", "RASI"], psis = ["LPSI", "RPSI"], sacrum = "SACR",
                       hips = ["l_hip", "r_hip"] }   # root only: pelvis landmarks for the
                                          # hips' regression (skeleton.py); the sacrum
                                          # may stand in for the PSIS pair

    [segments.l_lower_leg]            # the segment whose joint (the knee) it places
    axis_anchor = ["L_FLE", "L_FME"]  # the parent's landmarks that straddle a hinge
                                      # joint: its centre along the axis
    chord = { wand = "LTHI", marker = "LKNE", width = "LKneeWidth" }
                                      # Plug-in-Gait's anatomical centre (anatomical.py):
                                      # from the parent's joint, its wand and the lateral
                                      # marker, offset by half the PROCESSING width

Joint names follow ``design.md`` (``l_hip``, ``l_knee``...); extra joints
(``spine``, ``l_toe``...) are allowed. Segments are listed parents first.
"""

from __future__ import annotations

import functools
import os
import tomllib
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path

from vidcap.errors import VidcapError

_DIRS = {"x": (1, 0, 0), "-x": (-1, 0, 0), "y": (0, 1, 0), "-y": (0, -1, 0),
         "z": (0, 0, 1), "-z": (0, 0, -1)}


class MarkerSetError(VidcapError):
    """A marker-set TOML file is malformed or does not fit the data."""


@dataclass(frozen=True)
class SegmentSpec:
    """One rigid segment of a marker set.

    Attributes
    ----------
    name : str
        Segment name.
    parent : str or None
        Parent segment (None for the root).
    joint : str
        Joint between the parent and this segment (for the root: the root joint).
    markers : tuple of str
        Markers rigidly attached to the segment.
    tip : str or None
        Joint (child joint or end) the segment points at in the T-pose.
    rest : tuple of float
        Unit direction of ``tip`` from ``joint`` in the T-pose (Y up, -Z forward,
        the body's left is -X).
    side : tuple of str
        Two joints whose left-to-right vector becomes +X in the T-pose (optional).
    fallback : tuple of str
        Markers whose centroid is the joint centre when the fit fails (optional).
    end_joint : str or None
        Name of an extra leaf joint at the centroid of ``end_markers``.
    end_markers : tuple of str
    origin : tuple of str
        Root only: child joints whose mean is the root joint's position.
    optional : tuple of str
        Markers of ``markers`` that a file may lack without it being reported or
        counting against the set's detection (one protocol's variants: Plug-in-Gait's
        SACR in place of LPSI/RPSI).
    hip_asis, hip_psis : tuple of str
        Root only: the left and right anterior and posterior superior iliac spine
        markers, for the hip-centre regression of
        :func:`vidcap.mocap.skeleton.hip_regression`; empty when the set has none. Once
        restricted to a file (:meth:`MarkerSet.restricted`), ``hip_psis`` may be the
        one sacrum marker that stands in for the pair.
    hip_model : str
        Root only: ``'harrington'`` (Harrington et al. 2007, from the pelvis alone) or
        ``'davis'`` (Plug-in-Gait's, from the subject's leg lengths in the C3D or,
        failing them, the ASIS-to-``hip_ankles`` distances).
    hip_ankles : tuple of str
        Root only: the (left, right) lateral malleolus markers for that estimate.
    hip_sacrum : tuple of str
        Root only: a sacrum marker (one name) that stands in for ``hip_psis``.
    hip_joints : tuple of str
        The (left, right) hip joints the regression is for.
    axis_anchor : tuple of str
        The parent's landmarks straddling a hinge joint (lateral, medial): their midpoint
        places the centre along the hinge axis.
    chord : tuple of str
        (wand, marker): the markers of Plug-in-Gait's chord construction of this joint
        (:func:`vidcap.mocap.anatomical.chord_centre`), with the parent's joint;
        empty when the set has none.
    chord_width : str
        The ``PROCESSING`` parameter with the joint's width (mm), e.g. ``LKneeWidth``.
    """

    name: str
    parent: str | None
    joint: str
    markers: tuple[str, ...]
    tip: str | None = None
    rest: tuple[float, float, float] = (0.0, -1.0, 0.0)
    side: tuple[str, ...] = ()
    fallback: tuple[str, ...] = ()
    end_joint: str | None = None
    end_markers: tuple[str, ...] = ()
    origin: tuple[str, ...] = ()
    optional: tuple[str, ...] = ()
    hip_asis: tuple[str, ...] = ()
    hip_psis: tuple[str, ...] = ()
    hip_joints: tuple[str, ...] = ()
    hip_sacrum: tuple[str, ...] = ()
    hip_model: str = "harrington"
    hip_ankles: tuple[str, ...] = ()
    axis_anchor: tuple[str, ...] = ()
    chord: tuple[str, ...] = ()
    chord_width: str = ""


@dataclass(frozen=True)
class MarkerSet:
    """A named marker set: segments in parent-first order (the first is the root)."""

    name: str
    description: str
    segments: tuple[SegmentSpec, ...]
    source: str = ""

    @property
    def root(self) -> SegmentSpec:
        """The root segment."""
        return self.segments[0]

    def segment(self, name: str) -> SegmentSpec:
        """The segment called ``name``."""
        for s in self.segments:
            if s.name == name:
                return s
        raise KeyError(name)

    def markers(self) -> tuple[str, ...]:
        """Every marker the set names (segment and end markers), in order, unique."""
        out: list[str] = []
        for s in self.segments:
            for m in (*s.markers, *s.end_markers, *s.fallback):
                if m not in out:
                    out.append(m)
        return tuple(out)

    def segment_markers(self) -> tuple[str, ...]:
        """Markers attached to segments that every file should have (what matters for
        detection): optional ones left out."""
        return tuple(m for s in self.segments for m in s.markers if m not in s.optional)

    def joints(self) -> tuple[str, ...]:
        """Every joint: one per segment, then the end joints."""
        return tuple(s.joint for s in self.segments) + tuple(
            s.end_joint for s in self.segments if s.end_joint
        )

    def restricted(self, available: set[str]) -> tuple[MarkerSet, dict[str, list[str]]]:
        """This set without markers absent from the data.

        Segments left without markers are dropped together with their descendants.

        Returns
        -------
        markerset : MarkerSet
        missing : dict of str to list of str
            Absent markers per segment (only segments that lost some).
        """
        missing: dict[str, list[str]] = {}
        kept: list[SegmentSpec] = []
        names: set[str] = set()
        for s in self.segments:
            gone = [m for m in (*s.markers, *s.end_markers)
                    if m not in available and m not in s.optional]
            if gone:
                missing[s.name] = gone
            if s.parent is not None and s.parent not in names:
                continue
            mk = tuple(m for m in s.markers if m in available)
            if not mk:
                continue
            end = tuple(m for m in s.end_markers if m in available)
            # the regression needs both ASIS and the PSIS pair or, instead, the sacrum
            psis = s.hip_psis if all(m in available for m in s.hip_psis) else tuple(
                m for m in s.hip_sacrum if m in available)
            regress = (bool(s.hip_asis) and all(m in available for m in s.hip_asis)
                       and bool(psis))
            kept.append(replace(
                s, markers=mk, fallback=tuple(m for m in s.fallback if m in available),
                end_joint=s.end_joint if end else None, end_markers=end,
                optional=tuple(m for m in s.optional if m in available),
                hip_asis=s.hip_asis if regress else (), hip_psis=psis if regress else (),
                hip_joints=s.hip_joints if regress else (),
                axis_anchor=s.axis_anchor if all(m in available for m in s.axis_anchor)
                else (),
                chord=s.chord if all(m in available for m in s.chord) else (),
                hip_ankles=s.hip_ankles if all(m in available for m in s.hip_ankles) else (),
            ))
            names.add(s.name)
        return MarkerSet(self.name, self.description, tuple(kept), self.source), missing


def _strs(value, what, path) -> tuple[str, ...]:
    if value is None:
        return ()
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise MarkerSetError(f"{what} must be a list of strings", path)
    return tuple(v.strip() for v in value)


def parse_markerset(text: str, *, source: str = "<toml>") -> MarkerSet:
    """Parse a marker-set TOML document.

    Raises
    ------
    MarkerSetError
        Malformed TOML, unknown parents, duplicate joints, a root with < 3 markers.
    """
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise MarkerSetError(f"not valid TOML ({exc})", source) from None
    segs = doc.get("segments")
    if not isinstance(segs, dict) or not segs:
        raise MarkerSetError("no [segments.*] tables", source)
    out: list[SegmentSpec] = []
    seen_seg: set[str] = set()
    seen_joint: set[str] = set()
    for i, (name, t) in enumerate(segs.items()):
        if not isinstance(t, dict):
            raise MarkerSetError(f"segments.{name} must be a table", source)
        parent = t.get("parent")
        if i == 0 and parent is not None:
            raise MarkerSetError(f"the first segment ({name}) is the root and has no parent",
                                 source)
        if i > 0 and parent not in seen_seg:
            raise MarkerSetError(
                f"segments.{name}: parent {parent!r} must be a segment listed before it", source
            )
        joint = t.get("joint", name if i == 0 else None)
        if not isinstance(joint, str) or not joint:
            raise MarkerSetError(f"segments.{name}: missing joint name", source)
        markers = _strs(t.get("markers"), f"segments.{name}.markers", source)
        if not markers:
            raise MarkerSetError(f"segments.{name}: no markers", source)
        if i == 0 and len(markers) < 3:
            raise MarkerSetError(f"root segment {name} needs at least 3 markers", source)
        optional = _strs(t.get("optional"), f"segments.{name}.optional", source)
        reg = t.get("hip_regression") or {}
        if not isinstance(reg, dict) or (reg and i > 0):
            raise MarkerSetError(f"segments.{name}.hip_regression must be a table, on the "
                                 "root segment", source)
        asis = _strs(reg.get("asis"), f"segments.{name}.hip_regression.asis", source)
        psis = _strs(reg.get("psis"), f"segments.{name}.hip_regression.psis", source)
        hips = _strs(reg.get("hips"), f"segments.{name}.hip_regression.hips", source)
        sacrum = _strs(reg.get("sacrum"), f"segments.{name}.hip_regression.sacrum", source)
        if reg and (len(asis) != 2 or len(psis) != 2 or len(hips) != 2 or len(sacrum) > 1
                    or set(asis + psis + sacrum) - set(markers)):
            raise MarkerSetError(f"segments.{name}.hip_regression needs asis and psis "
                                 "(left, right) among the segment's markers, hips (left, "
                                 "right) and at most one sacrum marker", source)
        model = str(reg.get("model", "harrington"))
        if model not in ("harrington", "davis"):
            raise MarkerSetError(f"segments.{name}.hip_regression.model must be 'harrington' "
                                 "or 'davis'", source)
        if set(optional) - set(markers):
            raise MarkerSetError(f"segments.{name}.optional names markers not in its "
                                 f"markers: {sorted(set(optional) - set(markers))}", source)
        rest = str(t.get("rest", "-y")).lower()
        if rest not in _DIRS:
            raise MarkerSetError(f"segments.{name}.rest must be one of {sorted(_DIRS)}", source)
        chord_t = t.get("chord") or {}
        chord = (_strs(chord_t.get("wand"), f"segments.{name}.chord.wand", source)
                 + _strs(chord_t.get("marker"), f"segments.{name}.chord.marker", source)
                 ) if isinstance(chord_t, dict) else ()
        if chord_t and (len(chord) != 2 or i == 0):
            raise MarkerSetError(f"segments.{name}.chord must be a table with one wand and "
                                 "one marker, on a non-root segment", source)
        end = t.get("end") or {}
        if not isinstance(end, dict):
            raise MarkerSetError(f"segments.{name}.end must be a table", source)
        end_joint = end.get("joint")
        for j in (joint, end_joint):
            if j is None:
                continue
            if j in seen_joint:
                raise MarkerSetError(f"joint {j!r} is defined twice", source)
            seen_joint.add(j)
        out.append(SegmentSpec(
            name=name, parent=parent, joint=joint, markers=markers,
            tip=t.get("tip"), rest=tuple(float(v) for v in _DIRS[rest]),
            side=_strs(t.get("side"), f"segments.{name}.side", source),
            fallback=_strs(t.get("fallback"), f"segments.{name}.fallback", source),
            end_joint=end_joint,
            end_markers=_strs(end.get("markers"), f"segments.{name}.end.markers", source),
            origin=_strs(t.get("origin"), f"segments.{name}.origin", source),
            optional=optional, hip_asis=asis, hip_psis=psis, hip_joints=hips,
            hip_sacrum=sacrum, hip_model=model,
            hip_ankles=_strs(reg.get("ankles"), f"segments.{name}.hip_regression.ankles",
                             source),
            axis_anchor=_strs(t.get("axis_anchor"), f"segments.{name}.axis_anchor", source),
            chord=chord, chord_width=str(chord_t.get("width", "")),
        ))
        seen_seg.add(name)
    return MarkerSet(str(doc.get("name", Path(source).stem)), str(doc.get("description", "")),
                     tuple(out), source)


def builtin_markersets() -> dict[str, MarkerSet]:
    """The marker sets shipped with vidcap, by name (a new dict of the frozen sets)."""
    return dict(_builtin_markersets())


@functools.lru_cache(maxsize=1)
def _builtin_markersets() -> tuple[tuple[str, MarkerSet], ...]:
    """The shipped TOML files parsed once per process (~10 ms, every solve asked for
    them to detect its set)."""
    out = {}
    for f in sorted(resources.files("vidcap.mocap").joinpath("markersets").iterdir(),
                    key=lambda p: p.name):
        if f.name.endswith(".toml"):
            ms = parse_markerset(f.read_text(encoding="utf-8"), source=f.name)
            out[ms.name] = ms
    return tuple(out.items())


def load_markerset(name_or_path: str | os.PathLike) -> MarkerSet:
    """A built-in marker set by name, or a TOML file by path.

    Raises
    ------
    MarkerSetError
        Unknown name, missing or malformed file.
    """
    sets = builtin_markersets()
    key = str(name_or_path)
    if key in sets:
        return sets[key]
    p = Path(key)
    if p.suffix.lower() == ".toml" or p.exists():
        if not p.is_file():
            raise MarkerSetError("no such marker-set file", p)
        try:
            text = p.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise MarkerSetError(f"cannot read ({exc})", p) from None
        return parse_markerset(text, source=str(p))
    raise MarkerSetError(
        f"unknown marker set {key!r}; built-in sets: {', '.join(sets)} (or give a .toml file)"
    )


def detect_markerset(labels, *, path=None) -> MarkerSet:
    """Pick the built-in marker set that fits the labels.

    A set is a candidate when at least 3 of its root markers are present (what the
    root's frame needs) and at least 75 % of its non-optional segment markers are.
    The candidate covering the largest share of its markers wins; then the one with
    more markers. A tie is ambiguous.

    Raises
    ------
    MarkerSetError
        No built-in set fits, or several fit equally well (use ``--markerset``).
    """
    have = set(labels)
    scored = []
    for ms in builtin_markersets().values():
        seg = ms.segment_markers()
        if sum(m in have for m in ms.root.markers) < 3:
            continue
        share = sum(m in have for m in seg) / len(seg)
        if share >= 0.75:
            scored.append((share, sum(m in have for m in seg), ms))
    if not scored:
        raise MarkerSetError(
            "no built-in marker set matches the marker labels; pass --markerset FILE.toml "
            "(see vidcap joints --list-markersets; --draft-markerset FILE.toml drafts one "
            "from the trial)", path,
        )
    scored.sort(key=lambda s: (s[0], s[1]), reverse=True)
    if len(scored) > 1 and scored[0][:2] == scored[1][:2]:
        raise MarkerSetError(
            f"marker labels fit several marker sets ({scored[0][2].name}, {scored[1][2].name});"
            " choose one with --markerset", path,
        )
    return scored[0][2]
