"""Read optical marker trajectories from C3D files (via ``ezc3d``).

What comes out is always the same shape whatever the vendor wrote:

* labels with subject prefixes stripped (``liu:LFWT`` -> ``LFWT``) and surrounding
  blanks removed; blank labels become ``M001``...; duplicate labels are made unique
  (``LASI``, ``LASI~2``) and reported in :attr:`MarkerData.duplicates`;
* positions ``(F, M, 3)`` in **metres**, whatever ``POINT:UNITS`` says (mm, cm, m);
* gaps as NaN: a sample whose residual is negative, or whose coordinates are all
  exactly zero, is a missing sample, not a marker at the lab origin (C3D's own
  convention; the CMU files zero missing samples).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vidcap.errors import C3DError

#: Metres per unit for the ``POINT:UNITS`` strings we understand.
_UNITS = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "dm": 0.1, "in": 0.0254, "inch": 0.0254}


@dataclass(frozen=True)
class MarkerData:
    """Marker trajectories of one C3D trial.

    Attributes
    ----------
    labels : tuple of str, length M
        Unique marker labels, subject prefixes stripped.
    positions : numpy.ndarray, shape (F, M, 3)
        Marker positions in the C3D lab frame, metres; NaN where the marker is missing.
    fps : float
        Point frame rate, Hz.
    first_frame : int
        Number of the first frame as recorded in the file (C3D frames count from 1).
    path : str
        The file read.
    duplicates : tuple of str
        Labels that occurred more than once in the file (each extra copy got a ``~k``
        suffix).
    prefixes : tuple of str
        Subject prefixes that were stripped.
    up : tuple of float
        The lab's vertical: ``+Y`` when ``POINT:Y_SCREEN`` says so, else ``+Z`` (the
        usual C3D convention).
    subject : dict of str to float
        The subject's measurements from the ``PROCESSING`` group, as written there
        (Vicon's are mm and kg: ``LKneeWidth``, ``RAnkleWidth``, ``MarkerDiameter``,
        ``LLegLength``...): its single-number entries, empty when the file has none.
    """

    labels: tuple[str, ...]
    positions: np.ndarray
    fps: float
    first_frame: int = 1
    path: str = ""
    duplicates: tuple[str, ...] = ()
    prefixes: tuple[str, ...] = field(default=())
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    subject: dict = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return self.positions.shape[0]

    def index(self, label: str) -> int:
        """Column of marker ``label`` in :attr:`positions`."""
        return self.labels.index(label)

    def marker(self, label: str) -> np.ndarray:
        """Trajectory of one marker, (F, 3) metres."""
        return self.positions[:, self.index(label)]

    def times(self) -> np.ndarray:
        """Time of each frame from the start of the trial, (F,) seconds."""
        return np.arange(self.n_frames) / self.fps


def clean_labels(raw: list[str]) -> tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]:
    """Strip subject prefixes and blanks, name blank labels, disambiguate duplicates.

    Parameters
    ----------
    raw : list of str
        Labels as stored in ``POINT:LABELS``.

    Returns
    -------
    labels : tuple of str
        Unique cleaned labels, same length and order as ``raw``.
    duplicates : tuple of str
        Cleaned labels that occurred more than once.
    prefixes : tuple of str
        Distinct subject prefixes removed (the part before the last ``:``).
    """
    out, prefixes, seen, dups = [], [], {}, []
    for i, lab in enumerate(raw):
        lab = str(lab).strip()
        if ":" in lab:
            pre, lab = lab.rsplit(":", 1)
            lab = lab.strip()
            if pre.strip() and pre.strip() not in prefixes:
                prefixes.append(pre.strip())
        if not lab:
            lab = f"M{i + 1:03d}"
        if lab in seen:
            seen[lab] += 1
            if lab not in dups:
                dups.append(lab)
            new = f"{lab}~{seen[lab]}"
            while new in seen:
                seen[lab] += 1
                new = f"{lab}~{seen[lab]}"
            seen[new] = 1
            lab = new
        else:
            seen[lab] = 1
        out.append(lab)
    return tuple(out), tuple(dups), tuple(prefixes)


def _param(params, group: str, name: str, default=None):
    try:
        return params[group][name]["value"]
    except (KeyError, TypeError):
        return default


def _subject(params) -> dict:
    """The single finite numbers of the PROCESSING group (subject measurements)."""
    out = {}
    try:
        items = list(params["PROCESSING"].items())
    except (KeyError, TypeError, AttributeError):
        return out
    for name, entry in items:
        try:
            v = np.asarray(entry["value"], dtype=float)
        except (KeyError, TypeError, ValueError):
            continue
        if v.size == 1 and np.isfinite(v).all():
            out[str(name)] = float(v.reshape(()))
    return out


def _unit_scale(units, path) -> float:
    if units is None or len(units) == 0:
        return 1e-3  # C3D's customary default
    u = str(units[0]).strip().lower()
    if u not in _UNITS:
        raise C3DError(f"unknown POINT:UNITS {u!r} (expected mm, cm or m)", path)
    return _UNITS[u]


#: Farther than this from the lab origin no marker of a human motion can be, metres.
MAX_COORDINATE_M = 1e3


def _check_coordinates(xyz: np.ndarray, params, path) -> None:
    """Refuse coordinates no lab records (a 10^38 m marker): an absurd scale or unit."""
    big = np.abs(np.nan_to_num(xyz)).max(initial=0.0)
    if big > MAX_COORDINATE_M:
        scale = _param(params, "POINT", "SCALE", [None])
        units = _param(params, "POINT", "UNITS", [None])
        raise C3DError(f"marker coordinates reach {big:.3g} m: POINT:SCALE"
                       f" ({scale[0] if len(scale) else None}) or POINT:UNITS"
                       f" ({units[0] if len(units) else None}) is wrong", path)


def read_c3d(path: str | os.PathLike) -> MarkerData:
    """Read the marker trajectories of a C3D file.

    Parameters
    ----------
    path : str or path-like
        A ``.c3d`` file.

    Returns
    -------
    MarkerData
        Labels, positions (F, M, 3) in metres with NaN gaps, frame rate.

    Raises
    ------
    C3DError
        The file is missing, cannot be parsed by ezc3d (the parser's reason is in the
        message), or holds no 3D points.
    """
    from vidcap.mocap.c3dcheck import check_c3d
    from vidcap.mocap.c3dchild import read_isolated

    path = Path(path)
    if not path.is_file():
        raise C3DError("no such file", path)
    try:
        check_c3d(path)  # ezc3d trusts the declared sizes: a bad one crashes the process
    except C3DError as exc:
        raise C3DError(f"not a readable C3D file ({exc.problem})", path) from None
    c = read_isolated(path)  # a crash in the C++ parser must not end this process
    params = c["parameters"]
    raw = list(_param(params, "POINT", "LABELS", []) or [])
    pts = c["points"]  # (4, M, F)
    if pts.ndim != 3 or pts.shape[1] == 0 or pts.shape[2] == 0:
        raise C3DError("the file holds no 3D marker points", path)
    M = pts.shape[1]
    # Some files carry more LABELS2.. entries; ezc3d merges them. Pad/trim to M.
    raw = (raw + [""] * M)[:M]
    labels, dups, prefixes = clean_labels(raw)

    rate = _param(params, "POINT", "RATE", None)
    if rate is not None and len(rate):
        fps = float(rate[0])
    else:
        fps = float(c["header"]["frame_rate"])
    if not (np.isfinite(fps) and fps > 0):
        raise C3DError(f"invalid point frame rate {fps!r}", path)
    scale = _unit_scale(_param(params, "POINT", "UNITS", None), path)

    xyz = np.ascontiguousarray(pts[:3].transpose(2, 1, 0)) * scale  # (F, M, 3)
    missing = np.all(pts[:3] == 0.0, axis=0).T | ~np.isfinite(xyz).all(axis=2)
    res = c["residuals"]
    if res is not None:
        if res.shape == (1, M, xyz.shape[0]):
            missing |= (res[0] < 0).T
    xyz[missing] = np.nan
    _check_coordinates(xyz, params, path)
    ysc = _param(params, "POINT", "Y_SCREEN", None)
    up = (0.0, 1.0, 0.0) if ysc is not None and len(ysc) and str(ysc[0]).strip().upper() == "+Y" \
        else (0.0, 0.0, 1.0)
    first = int(c["header"]["first_frame"]) + 1  # ezc3d counts from 0
    return MarkerData(
        labels=labels,
        positions=xyz,
        fps=fps,
        first_frame=first,
        path=str(path),
        duplicates=dups,
        prefixes=prefixes,
        up=up,
        subject=_subject(params),
    )
