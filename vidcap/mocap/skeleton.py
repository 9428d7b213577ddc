"""Joint centres and a skeleton from marker trajectories (seed 000 §2.3-2.6, seed 001 §9).

The procedure, for a marker set (:mod:`vidcap.mocap.markerset`) and one or more trials:

1. The root segment's frame, per frame, from >= 3 of its markers.
2. Down the tree, for each child segment: its markers are expressed in the parent's
   frame over all frames (and all pooled trials); there they move on spheres about
   the joint centre, which MGDK (UGDK-corrected with ``noise_mm``) fits once
   (:func:`vidcap.mocap.spherefit.mgdk`). Planar motion is a hinge: the axis is
   reported. The per-frame centre is ``c_jk = x_jk + M_jk v_j`` (seed 000 §2.5),
   with ``x_jk``/``M_jk`` the parent's origin/axes and ``v_j`` the fitted centre.
3. The child's frame per frame from three points (seed 000 §2.5 case 3) - its own
   markers, the solved centre counting as a point (case 2) - or from one marker,
   the centre and the hinge axis (case 1).

Gaps: a frame where the primary three points of a segment are not all present is
filled by a least-squares rigid fit (Kabsch) of the segment's template (the median
local coordinates of all its points) to whichever >= 3 points are present. Samples
with a marker missing simply drop out of the sphere fit.

Everything is vectorised over frames; the only Python loops run over segments,
markers and trials.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from vidcap.errors import FitError, VidcapError
from vidcap.mocap.c3d import MarkerData
from vidcap.mocap.markerset import MarkerSet, MarkerSetError, SegmentSpec, detect_markerset
from vidcap.mocap.spherefit import PLANAR_COND, mgdk

_EPS = 1e-9


@dataclass(frozen=True)
class JointReport:
    """Fit quality of one joint.

    Attributes
    ----------
    joint, segment : str
        The joint and the (child) segment whose markers located it.
    parent_segment : str or None
        The frame the centre is constant in (None for the root joint).
    kind : str
        ``'sphere'``, ``'hinge'``, ``'still'`` (from the fit), ``'root'`` or ``'end'``.
    method : str
        ``'mgdk'``, ``'mgdk+ugdk'``, ``'fallback'`` (marker centroid), ``'markers'``.
    frames_used : int
        Frames with a parent frame and at least one of the child's markers.
    rms_residual_m : float
        RMS of |y - c| - r over all samples (in-plane distance for a hinge), metres.
    condition : float
        Condition number of the pooled covariance (large: planar or little motion).
    cap_angle_deg : float
        Range of motion: the largest (98th percentile) angle of a marker's direction
        from the centre to its mean direction, over the child's markers, degrees.
    axis : list of float or None
        Hinge axis in the parent's frame (unit), for ``kind == 'hinge'``.
    center_local_m : list of float
        The centre in the parent segment's frame, metres.
    flagged : bool
        True when the fit was rejected and the fallback used.
    note : str
        Why it was flagged, and which fallback; or how a hinge centre was placed.
    axial_std_mm : float
        Standard deviation (Cramér-Rao, at the fitted centre and the residual noise)
        of the worst-determined coordinate of the centre, mm.
    """

    joint: str
    segment: str
    parent_segment: str | None
    kind: str
    method: str
    frames_used: int
    rms_residual_m: float
    condition: float
    cap_angle_deg: float
    axis: list | None
    center_local_m: list
    flagged: bool = False
    note: str = ""
    axial_std_mm: float = float("nan")

    def as_dict(self) -> dict:
        """JSON-ready dict (NaN/inf become None)."""
        d = asdict(self)
        for k, v in d.items():
            if isinstance(v, float) and not np.isfinite(v):
                d[k] = None
        return d


@dataclass(frozen=True)
class JointSolution:
    """Joint centres of the first trial, plus what is needed to build a skeleton.

    Attributes
    ----------
    markerset : MarkerSet
        The (restricted) marker set used.
    joint_names : tuple of str, length J
    joint_parents : tuple of int, length J
        Parent joint index, -1 for the root.
    joint_segment : tuple of str, length J
        The segment whose frame a joint's own rotation is (its distal segment; ends:
        the segment they ride on).
    positions : numpy.ndarray, shape (F, J, 3)
        Joint centres in the C3D lab frame, metres, NaN where unknown.
    segment_names : tuple of str, length S
    rotations : numpy.ndarray, shape (F, S, 3, 3)
        Segment frames (columns = axes, lab frame), NaN where unknown.
    origins : numpy.ndarray, shape (F, S, 3)
        Segment frame origins, lab frame, metres.
    local_points : dict of str to dict of str to numpy.ndarray (3,)
        Per segment: constant positions of its joints (proximal, children, end) in
        its own frame, metres.
    reports : tuple of JointReport
    fps : float
    up : numpy.ndarray, shape (3,)
        The lab's up direction.
    missing_markers : dict of str to list of str
        Markers the set names that the file lacks, per segment.
    """

    markerset: MarkerSet
    joint_names: tuple[str, ...]
    joint_parents: tuple[int, ...]
    joint_segment: tuple[str, ...]
    positions: np.ndarray
    segment_names: tuple[str, ...]
    rotations: np.ndarray
    origins: np.ndarray
    local_points: dict
    reports: tuple[JointReport, ...]
    fps: float
    up: np.ndarray
    missing_markers: dict = field(default_factory=dict)

    def report(self, joint: str) -> JointReport:
        """The report of ``joint``."""
        for r in self.reports:
            if r.joint == joint:
                return r
        raise KeyError(joint)

    def position(self, joint: str) -> np.ndarray:
        """Trajectory of one joint, (F, 3) metres."""
        return self.positions[:, self.joint_names.index(joint)]


# --------------------------------------------------------------------------- frames
def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > _EPS, v / n, np.nan)


def frame_from_three(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Segment axes from three points (seed 000 §2.5, case 3; case 2 with p2 = the centre).

    The seed's formulas read x = p2 × p1 / |.|, z = p0 × x / |.|, y = z × x with the
    points relative to the frame's origin; as printed the origin is unspecified (and
    p0 relative to itself is 0), so we take the origin at p0 and a = p1 - p0,
    b = p2 - p0: x = (b × a)/|b × a| (normal of the plane), z = (a × x)/|a × x|,
    y = z × x (= -a/|a|). Right-handed: x × y = z.

    Parameters
    ----------
    p0, p1, p2 : numpy.ndarray, shape (..., 3)

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
        Columns x, y, z; NaN where the points are (nearly) collinear or missing.
    """
    a = p1 - p0
    b = p2 - p0
    n = np.cross(b, a)
    scale = np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1)
    with np.errstate(invalid="ignore"):
        bad = ~(np.linalg.norm(n, axis=-1) > 1e-3 * scale)
    x = _unit(n)
    z = _unit(np.cross(a, x))
    y = np.cross(z, x)
    m = np.stack([x, y, z], axis=-1)
    m[bad] = np.nan
    return m


def frame_from_axis(c: np.ndarray, p0: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Segment axes from one point, the joint centre and an axis (seed 000 §2.5, case 1).

    x is the axis made perpendicular to a = p0 - c, z = (a × x)/|.|, y = z × x.

    Parameters
    ----------
    c, p0, axis : numpy.ndarray, shape (..., 3)

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
    """
    a = _unit(p0 - c)
    x = _unit(axis - np.sum(axis * a, axis=-1, keepdims=True) * a)
    z = _unit(np.cross(a, x))
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-1)


def kabsch(template: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rigid poses mapping a template onto points with gaps, batched over frames.

    Parameters
    ----------
    template : numpy.ndarray, shape (K, 3)
        Local coordinates of K points.
    points : numpy.ndarray, shape (F, K, 3)
        Observed positions; NaN rows are ignored.

    Returns
    -------
    rotation : numpy.ndarray, shape (F, 3, 3)
        ``points ≈ origin + rotation @ template``; NaN where fewer than 3 non-collinear
        points are present.
    origin : numpy.ndarray, shape (F, 3)
    """
    w = np.isfinite(points).all(axis=2) & np.isfinite(template).all(axis=1)  # (F, K)
    cnt = w.sum(axis=1)
    x = np.where(w[..., None], points, 0.0)
    t = np.where(np.isfinite(template), template, 0.0)
    wt = w[..., None].astype(float)
    den = np.maximum(cnt, 1)[:, None]
    xc = (wt * x).sum(1) / den
    tc = (wt * t[None]).sum(1) / den
    h = np.einsum("fk,fki,fkj->fij", w.astype(float), t[None] - tc[:, None], x - xc[:, None])
    u, s, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(np.einsum("fji,fkj->fik", vt, u)))
    d = np.where(d == 0, 1.0, d)
    corr = np.ones((len(d), 3))
    corr[:, 2] = d
    r = np.einsum("fji,fj,fkj->fik", vt, corr, u)
    ok = (cnt >= 3) & (s[:, 1] > 1e-6 * np.maximum(s[:, 0], _EPS))
    r[~ok] = np.nan
    origin = xc - np.einsum("fij,fj->fi", r, tc)
    origin[~ok] = np.nan
    return r, origin


def _to_local(r: np.ndarray, o: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Lab points x (F, K, 3) in frames (r (F,3,3), o (F,3)): r^T (x - o)."""
    return np.einsum("fij,fki->fkj", r, x - o[:, None])


def _to_lab(r: np.ndarray, o: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Constant local point v (3,) per frame in the lab: o + r v, (F, 3)."""
    return o + np.einsum("fij,j->fi", r, v)


def _nanmedian_rows(y: np.ndarray) -> np.ndarray:
    """Median over axis 0 ignoring NaN, without warnings (all-NaN -> NaN)."""
    ok = np.isfinite(y).all(axis=-1)
    if not ok.any():
        return np.full(y.shape[1:], np.nan)
    return np.median(y[ok], axis=0)


@dataclass
class _SegFrames:
    r: np.ndarray  # (F, 3, 3)
    o: np.ndarray  # (F, 3)
    template: np.ndarray  # (K, 3)

    @property
    def valid(self) -> np.ndarray:
        return np.isfinite(self.r).all(axis=(1, 2))


def _frames_from_points(pts: np.ndarray) -> _SegFrames:
    """Frames from K >= 3 points (F, K, 3): seed case 3 on the first three, Kabsch fill."""
    r = frame_from_three(pts[:, 0], pts[:, 1], pts[:, 2])
    o = pts[:, 0].copy()
    ok = np.isfinite(r).all(axis=(1, 2)) & np.isfinite(o).all(axis=1)
    r[~ok] = np.nan
    o[~ok] = np.nan
    local = _to_local(np.where(ok[:, None, None], r, 0.0), np.where(ok[:, None], o, 0.0), pts)
    local[~ok] = np.nan
    template = np.stack([_nanmedian_rows(local[:, k]) for k in range(pts.shape[1])])
    if not ok.any():
        return _SegFrames(r, o, template)
    # Every frame with >= 3 points: the least-squares rigid pose of the template (the
    # seed's construction puts all the noise of three points into the axes; this spreads
    # it over all points, and fills frames whose primary three points are incomplete).
    has3 = np.isfinite(pts).all(axis=2).sum(axis=1) >= 3
    rf, of = kabsch(template, pts[has3])
    r[has3] = rf
    o[has3] = of
    return _SegFrames(r, o, template)


def _frames_case1(c: np.ndarray, p0: np.ndarray, axis_lab: np.ndarray) -> _SegFrames:
    r = frame_from_axis(c, p0, axis_lab)
    o = c.copy()
    ok = np.isfinite(r).all(axis=(1, 2)) & np.isfinite(o).all(axis=1)
    r[~ok] = np.nan
    o[~ok] = np.nan
    return _SegFrames(r, o, np.zeros((0, 3)))


# --------------------------------------------------------------------------- fits
def _cap_and_residual(sets: list[np.ndarray], center, radius, normal):
    """RMS radial residual (m) and 98th-percentile cap angle (deg) over marker sets."""
    radius = np.broadcast_to(np.asarray(radius, dtype=float), (len(sets),))
    hinge = normal is not None and np.isfinite(normal).all()
    res2, n, caps = 0.0, 0, []
    for y, rp in zip(sets, radius, strict=True):
        d = y - center
        if hinge:
            d = d - (d @ normal)[:, None] * normal
        dist = np.linalg.norm(d, axis=1)
        res2 += float(np.sum((dist - rp) ** 2))
        n += len(dist)
        u = d / np.maximum(dist, _EPS)[:, None]
        mean = _unit(u.mean(axis=0))
        ang = np.degrees(np.arccos(np.clip(u @ mean, -1.0, 1.0)))
        caps.append(float(np.percentile(ang, 98)) if len(ang) else 0.0)
    return (np.sqrt(res2 / n) if n else np.nan), (max(caps) if caps else 0.0)


def _weak_axis(sets: list[np.ndarray], center: np.ndarray, sigma: float):
    """Direction and standard deviation (m) of the worst-determined centre coordinate.

    Fisher information of the centre with the per-marker radii eliminated:
    J = σ⁻² Σ_p N_p Cov_p(u) with u the unit directions from the centre (the
    multi-radius version of the bound in :func:`vidcap.mocap.spherefit.crlb`).
    """
    info = np.zeros((3, 3))
    for y in sets:
        u = _unit(y - center)
        u = u[np.isfinite(u).all(axis=1)]
        if len(u) > 1:
            info += len(u) * np.cov(u.T, bias=True)
    w, v = np.linalg.eigh(info / max(sigma, 1e-12) ** 2)
    std = np.inf if w[0] <= 0 else 1.0 / np.sqrt(w[0])
    return v[:, 0], float(std)


def _fit_joint(spec: SegmentSpec, parent: str, sets: list[np.ndarray], fallback_local,
               frames_used: int, *, noise_mm, min_cap_deg, planar_cond, anchor,
               max_axial_std_mm, hinge_ratio) -> tuple:
    """Fit one joint centre in the parent's frame; returns (v (3,), axis or None, report)."""
    usable = [y for y in sets if len(y) >= 4]
    note = ""
    fit = None
    if usable:
        try:
            cov = None if noise_mm is None else (float(noise_mm) * 1e-3) ** 2
            fit = mgdk(usable, cov, planar_cond=planar_cond)
        except FitError as exc:
            note = f"fit failed ({exc})"
    else:
        note = "fewer than 4 samples of every marker"
    method = "mgdk" if noise_mm is None else "mgdk+ugdk"
    if fit is not None:
        kind = {"circle": "hinge"}.get(fit.kind, fit.kind)
        center = np.asarray(fit.center, dtype=float)
        normal = np.asarray(fit.normal, dtype=float) if kind == "hinge" else None
        if np.isfinite(center).all():
            rms, cap = _cap_and_residual(usable, center, fit.radius, normal)
        else:
            rms, cap = np.nan, 0.0
        cond = float(fit.condition)
        if kind == "still" or not np.isfinite(center).all():
            note = "the markers did not move relative to the parent"
        elif cap < min_cap_deg:
            note = f"too little motion (cap angle {cap:.1f} deg < {min_cap_deg:g})"
    else:
        kind, center, normal = "still", np.full(3, np.nan), None
        rms, cap, cond = np.nan, 0.0, np.inf
    flagged = bool(note)
    axial_std = np.nan
    if not flagged and fit is not None:
        sigma = float(noise_mm) * 1e-3 if noise_mm is not None else float(rms)
        axis_w, axial_std = _weak_axis(usable, center, sigma)
        if kind == "hinge":
            axis_w = normal
        # out-of-plane spread of the markers (pooled within-marker covariance)
        pooled = sum(np.cov(y.T, bias=True) * len(y) for y in usable) / sum(map(len, usable))
        lam, vec = np.linalg.eigh(pooled)
        thin = np.sqrt(max(lam[0], 0.0)) < hinge_ratio * sigma
        if thin and kind != "hinge":
            axis_w = vec[:, 0]
        if (anchor is not None and np.isfinite(anchor).all()
                and (kind == "hinge" or thin or axial_std * 1e3 > max_axial_std_mm)):
            # Motion (nearly) about one axis: the centre's position along that axis is not
            # observable. Place it at the point of the axis nearest the parent's proximal
            # joint (for a long bone flexing about an axis across it - knee, elbow, ankle,
            # wrist - that is where the bone's long axis meets the hinge axis).
            center = center + ((anchor - center) @ axis_w) * axis_w
            normal = axis_w
            kind = "hinge"
            method += "+axis-rule"
            note = (f"centre along the hinge axis (std {axial_std * 1e3:.0f} mm from the fit) "
                    f"placed nearest the {parent} proximal joint")
    if flagged:
        v = fallback_local
        what = (f"centroid of {', '.join(spec.fallback)}" if spec.fallback
                else f"centroid of the {spec.name} markers")
        note += f"; fallback: {what} (constant in the {parent} frame)"
        method = "fallback"
    else:
        v = center
    report = JointReport(
        joint=spec.joint, segment=spec.name, parent_segment=parent, kind=kind, method=method,
        frames_used=int(frames_used), rms_residual_m=float(rms), condition=cond,
        cap_angle_deg=float(cap), axis=None if normal is None else [float(a) for a in normal],
        center_local_m=[float(a) for a in v], flagged=flagged, note=note,
        axial_std_mm=float(axial_std * 1e3),
    )
    return v, (normal if not flagged else None), report


# --------------------------------------------------------------------------- solve
def _lab_up(trial: MarkerData) -> np.ndarray:
    up = getattr(trial, "up", None)
    return np.array([0.0, 0.0, 1.0]) if up is None else np.asarray(up, dtype=float)


def solve_joints(
    trials: MarkerData | Sequence[MarkerData],
    markerset: MarkerSet | None = None,
    *,
    noise_mm: float | None = None,
    min_cap_deg: float = 10.0,
    planar_cond: float = PLANAR_COND,
    hinge_rule: bool = True,
    max_axial_std_mm: float = 2.0,
    hinge_ratio: float = 3.0,
) -> JointSolution:
    """Joint centres of a marker-set skeleton (seed 000 §2.3-2.6).

    Parameters
    ----------
    trials : MarkerData or sequence of MarkerData
        The trial to solve first; any further trials (same subject and marker set)
        are pooled for the sphere fits only.
    markerset : MarkerSet, optional
        Detected from the first trial's labels when omitted.
    noise_mm : float, optional, keyword-only
        Marker noise standard deviation (mm, isotropic): the fits use UGDK's
        noise-corrected covariance C - σ² I. None: plain MGDK.
    min_cap_deg : float, keyword-only
        A joint whose markers sweep a cap smaller than this (degrees) about the fitted
        centre is flagged and falls back to its marker centroid: a sphere fit's error
        grows like σ/(r θ²) as the cap angle θ shrinks.
    planar_cond : float, keyword-only
        Condition number above which motion counts as planar (a hinge).
    hinge_rule : bool, keyword-only
        For a joint whose parent is a long bone (a non-root segment with this one
        child), when the motion is planar or the centre's worst coordinate has a
        Cramér-Rao standard deviation above ``max_axial_std_mm``, place the centre on
        the fitted axis at the point nearest the parent's proximal joint centre
        (reported as ``method='mgdk+axis-rule'``).
    max_axial_std_mm : float, keyword-only
        See ``hinge_rule``.
    hinge_ratio : float, keyword-only
        Motion counts as (nearly) planar for ``hinge_rule`` when the markers' spread
        across their plane of motion (√ of the smallest eigenvalue of the pooled
        within-marker covariance) is below ``hinge_ratio`` times the noise (σ from
        ``noise_mm``, else the RMS radial residual): out-of-plane scatter that noise
        alone explains.

    Returns
    -------
    JointSolution

    Raises
    ------
    MarkerSetError
        No marker set fits, or the root has fewer than 3 of its markers.
    """
    trials = [trials] if isinstance(trials, MarkerData) else list(trials)
    if not trials:
        raise VidcapError("no trials given")
    main = trials[0]
    if markerset is None:
        markerset = detect_markerset(main.labels, path=main.path)
    available = set(main.labels)
    for t in trials[1:]:
        available &= set(t.labels)
    ms, missing = markerset.restricted(available)
    if not ms.segments or ms.segments[0].name != markerset.root.name or len(ms.root.markers) < 3:
        raise MarkerSetError(
            f"marker set {markerset.name}: the root segment {markerset.root.name} needs >= 3 "
            f"of its markers {list(markerset.root.markers)}; missing: "
            f"{missing.get(markerset.root.name, [])}", main.path,
        )
    seg_names = tuple(s.name for s in ms.segments)
    frames: list[dict[str, _SegFrames]] = [{} for _ in trials]
    centres: list[dict[str, np.ndarray]] = [{} for _ in trials]  # joint -> (F, 3) lab
    axes: dict[str, np.ndarray | None] = {}
    fitted_v: dict[str, np.ndarray] = {}  # joint -> local centre in parent frame
    reports: list[JointReport] = []

    def markers_of(t: MarkerData, names) -> np.ndarray:
        return t.positions[:, [t.index(m) for m in names]]

    root = ms.root
    for ti, t in enumerate(trials):
        frames[ti][root.name] = _frames_from_points(markers_of(t, root.markers))

    for s in ms.segments[1:]:
        # 1. The joint centre in the parent's frame, pooled over trials.
        sets: list[list[np.ndarray]] = [[] for _ in s.markers]
        fb: list[np.ndarray] = []
        used = 0
        for ti, t in enumerate(trials):
            pf = frames[ti][s.parent]
            y = _to_local(pf.r, pf.o, markers_of(t, s.markers))  # (F, m, 3), NaN where missing
            ok = np.isfinite(y).all(axis=2)
            used += int(ok.any(axis=1).sum())
            for k in range(len(s.markers)):
                sets[k].append(y[ok[:, k], k])
            fbn = s.fallback or s.markers
            fy = _to_local(pf.r, pf.o, markers_of(t, fbn))
            fb.append(np.nanmean(fy, axis=1) if np.isfinite(fy).any() else fy[:, 0])
        sets_c = [np.concatenate(a) for a in sets]
        fallback_local = _nanmedian_rows(np.concatenate(fb))
        pspec = ms.segment(s.parent)
        n_siblings = sum(1 for q in ms.segments if q.parent == s.parent)
        anchor = None
        if pspec.parent is not None and n_siblings == 1 and hinge_rule:
            pf0 = frames[0][s.parent]
            anchor = _nanmedian_rows(
                _to_local(pf0.r, pf0.o, centres[0][pspec.joint][:, None])[:, 0])
        v, axis, rep = _fit_joint(s, s.parent, sets_c, fallback_local, used,
                                  noise_mm=noise_mm, min_cap_deg=min_cap_deg,
                                  planar_cond=planar_cond, anchor=anchor,
                                  max_axial_std_mm=max_axial_std_mm,
                                  hinge_ratio=hinge_ratio)
        fitted_v[s.joint] = v
        axes[s.joint] = axis
        reports.append(rep)
        # 2. Per-frame centre and the segment's own frames, per trial.
        for ti, t in enumerate(trials):
            pf = frames[ti][s.parent]
            c = _to_lab(pf.r, pf.o, v)
            centres[ti][s.joint] = c
            mk = markers_of(t, s.markers)
            if len(s.markers) >= 3:
                frames[ti][s.name] = _frames_from_points(mk)
            elif len(s.markers) == 2:
                frames[ti][s.name] = _frames_from_points(np.concatenate([mk, c[:, None]], 1))
            else:
                # case 1: one marker, the centre and an axis: the hinge axis if there is
                # one, else the parent's axis most perpendicular to the marker direction
                if axis is not None:
                    a_loc = axis
                else:
                    dloc = _unit(_nanmedian_rows(_to_local(pf.r, pf.o, mk)[:, 0] - 0) - v)
                    a_loc = np.eye(3)[int(np.argmin(np.abs(dloc)))] if np.isfinite(dloc).all() \
                        else np.eye(3)[0]
                a_lab = np.einsum("fij,j->fi", pf.r, a_loc)
                frames[ti][s.name] = _frames_case1(c, mk[:, 0], a_lab)

    # 3. Constant local points per segment (first trial), root joint and ends.
    f0, c0 = frames[0], centres[0]
    local_points: dict[str, dict[str, np.ndarray]] = {n: {} for n in seg_names}
    for s in ms.segments[1:]:
        local_points[s.parent][s.joint] = fitted_v[s.joint]
        sf = f0[s.name]
        local_points[s.name][s.joint] = _nanmedian_rows(
            _to_local(sf.r, sf.o, c0[s.joint][:, None])[:, 0])
    rf = f0[root.name]
    origin_j = [j for j in root.origin if j in local_points[root.name]]
    if origin_j:
        v_root = np.mean([local_points[root.name][j] for j in origin_j], axis=0)
        how = f"mean of {', '.join(origin_j)}"
    else:
        v_root = np.nanmean(rf.template[: len(root.markers)], axis=0)
        how = f"centroid of {', '.join(root.markers)}"
    local_points[root.name][root.joint] = v_root
    c0[root.joint] = _to_lab(rf.r, rf.o, v_root)
    reports.insert(0, JointReport(
        joint=root.joint, segment=root.name, parent_segment=None, kind="root", method="markers",
        frames_used=int(rf.valid.sum()), rms_residual_m=np.nan, condition=np.nan,
        cap_angle_deg=np.nan, axis=None, center_local_m=[float(a) for a in v_root],
        note=how))
    for s in ms.segments:
        if not s.end_joint:
            continue
        sf = f0[s.name]
        loc = _to_local(np.where(sf.valid[:, None, None], sf.r, 0.0),
                        np.where(sf.valid[:, None], sf.o, 0.0),
                        markers_of(main, s.end_markers))
        loc[~sf.valid] = np.nan
        v_end = _nanmedian_rows(np.nanmean(loc, axis=1) if np.isfinite(loc).any() else loc[:, 0])
        local_points[s.name][s.end_joint] = v_end
        c0[s.end_joint] = _to_lab(sf.r, sf.o, v_end)
        reports.append(JointReport(
            joint=s.end_joint, segment=s.name, parent_segment=s.name, kind="end",
            method="markers", frames_used=int(sf.valid.sum()), rms_residual_m=np.nan,
            condition=np.nan, cap_angle_deg=np.nan, axis=None,
            center_local_m=[float(a) for a in v_end],
            note=f"centroid of {', '.join(s.end_markers)}"))

    names, parents, jseg = [], [], []
    joint_of = {s.name: s.joint for s in ms.segments}
    for s in ms.segments:
        names.append(s.joint)
        parents.append(-1 if s.parent is None else names.index(joint_of[s.parent]))
        jseg.append(s.name)
    for s in ms.segments:
        if s.end_joint:
            names.append(s.end_joint)
            parents.append(names.index(s.joint))
            jseg.append(s.name)
    positions = np.stack([c0[n] for n in names], axis=1)
    rot = np.stack([f0[n].r for n in seg_names], axis=1)
    org = np.stack([f0[n].o for n in seg_names], axis=1)
    order = {r.joint: i for i, r in enumerate(reports)}
    reports.sort(key=lambda r: names.index(r.joint) if r.joint in names else order[r.joint])
    return JointSolution(
        markerset=ms, joint_names=tuple(names), joint_parents=tuple(parents),
        joint_segment=tuple(jseg), positions=positions, segment_names=seg_names,
        rotations=rot, origins=org, local_points=local_points, reports=tuple(reports),
        fps=main.fps, up=_lab_up(main), missing_markers=missing,
    )


# --------------------------------------------------------------------------- to a Motion
def lab_to_yup(up) -> np.ndarray:
    """Rotation taking lab coordinates to Y-up coordinates (3, 3).

    The lab's ``up`` becomes +Y; the lab axis most perpendicular to it (X first)
    becomes +X. For the usual Z-up C3D lab: (x, y, z) -> (x, z, -y).
    """
    y = _unit(np.asarray(up, dtype=float))
    cand = np.eye(3)[np.argsort(np.abs(np.eye(3) @ y), kind="stable")[0]]
    x = _unit(cand - (cand @ y) * y)
    z = np.cross(x, y)
    return np.stack([x, y, z])


def _project_so3(m: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(m)
    d = np.sign(np.linalg.det(u @ vt)) or 1.0
    return u @ np.diag([1.0, 1.0, d]) @ vt


def _align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest rotation taking unit a to unit b (3, 3)."""
    from scipy.spatial.transform import Rotation

    v = np.cross(a, b)
    s, c = np.linalg.norm(v), float(a @ b)
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        perp = np.eye(3)[int(np.argmin(np.abs(a)))]
        return Rotation.from_rotvec(np.pi * _unit(np.cross(a, perp))).as_matrix()
    return Rotation.from_rotvec(v / s * np.arctan2(s, c)).as_matrix()


def _two_vector_frame(primary, secondary) -> np.ndarray:
    e1 = _unit(primary)
    e2 = _unit(secondary - (secondary @ e1) * e1)
    return np.stack([e1, e2, np.cross(e1, e2)], axis=1)


def _fill_nearest(valid: np.ndarray) -> np.ndarray:
    """Index of the nearest valid frame for every frame (F,); -1 when none is valid."""
    idx = np.flatnonzero(valid)
    if idx.size == 0:
        return np.full(valid.shape, -1)
    f = np.arange(valid.size)
    pos = np.clip(np.searchsorted(idx, f), 1, max(idx.size - 1, 1))
    if idx.size == 1:
        return np.full(valid.shape, idx[0])
    left, right = idx[pos - 1], idx[pos]
    return np.where(np.abs(f - left) <= np.abs(right - f), left, right)


def solution_to_motion(sol: JointSolution):
    """The marker-derived skeleton as a :class:`vidcap.kinematics.Motion`.

    Bones join the joint centres (constant lengths: the fitted centres are constant
    in their segments' frames, so each bone is the median distance over frames);
    each joint's rotation is its segment's frame times a constant alignment chosen so
    that the rest pose is a T-pose (Y up, -Z forward, left arm toward -X, metres),
    with zero twist at the trial's mean pose. Frames where a segment's frame is
    unknown hold the nearest known frame's rotation.

    Parameters
    ----------
    sol : JointSolution

    Returns
    -------
    Motion
        Joints named as in ``sol.joint_names``; root at the root joint.
    """
    from scipy.spatial.transform import Rotation

    from vidcap.kinematics import Motion, Skeleton

    ms = sol.markerset
    g = lab_to_yup(sol.up)
    F, S = sol.rotations.shape[:2]
    sidx = {n: i for i, n in enumerate(sol.segment_names)}
    valid = np.isfinite(sol.rotations).all(axis=(2, 3))  # (F, S)
    # fill unknown segment frames from the nearest known frame
    rots = sol.rotations.copy()
    for s in range(S):
        near = _fill_nearest(valid[:, s])
        rots[:, s] = np.eye(3) if near[0] < 0 else rots[near, s]
    lp = sol.local_points
    align: dict[str, np.ndarray] = {}
    up_lab = np.asarray(sol.up, dtype=float)
    for spec in ms.segments:
        i = sidx[spec.name]
        pts = lp[spec.name]
        base = pts[spec.joint]
        rest = np.asarray(spec.rest, dtype=float)
        side = None
        if len(spec.side) == 2 and all(j in pts for j in spec.side):
            side = pts[spec.side[1]] - pts[spec.side[0]]
        tip = pts[spec.tip] - base if spec.tip in pts else None
        if spec.parent is None:
            up_loc = _unit(np.median(
                np.einsum("fij,i->fj", sol.rotations[valid[:, i], i], up_lab), axis=0))
            if side is None:
                side = np.eye(3)[int(np.argmin(np.abs(up_loc)))]
            e = _two_vector_frame(side, up_loc)  # local images of rest +X, +Y
            align[spec.name] = e  # columns: rest x, y, z in local coordinates
        elif side is not None and tip is not None:
            e = _two_vector_frame(tip, side)
            f = _two_vector_frame(rest, np.array([1.0, 0.0, 0.0]))
            align[spec.name] = e @ f.T
        else:
            p = sidx[spec.parent]
            both = valid[:, i] & valid[:, p]
            if both.any():
                rel = np.einsum("fji,fjk->fik", sol.rotations[both, p], sol.rotations[both, i])
                q = _project_so3(rel.mean(axis=0))
            else:
                q = np.eye(3)
            a_p = align[spec.parent]
            if tip is not None and np.isfinite(tip).all() and np.linalg.norm(tip) > _EPS:
                m = a_p.T @ q @ _unit(tip)
                t = _align(rest, m)
            else:
                t = np.eye(3)
            align[spec.name] = q.T @ a_p @ t
    # skeleton offsets
    names = sol.joint_names
    J = len(names)
    offsets = np.zeros((J, 3))
    seg_of_joint = {s.joint: s.name for s in ms.segments}
    for j, name in enumerate(names):
        p = sol.joint_parents[j]
        if p < 0:
            continue
        pseg = seg_of_joint[names[p]]
        pts = lp[pseg]
        offsets[j] = align[pseg].T @ (pts[name] - pts[names[p]])
    offsets = np.where(np.isfinite(offsets), offsets, 0.0)
    # world rotations per joint, then local
    world = np.empty((F, J, 3, 3))
    for j, name in enumerate(names):
        seg = sol.joint_segment[j]
        if name in seg_of_joint:
            world[:, j] = np.einsum("ij,fjk,kl->fil", g, rots[:, sidx[seg]], align[seg])
        else:  # end joints take their parent's rotation (local identity)
            world[:, j] = world[:, sol.joint_parents[j]]
    local = world.copy()
    for j in range(1, J):
        p = sol.joint_parents[j]
        local[:, j] = np.einsum("fji,fjk->fik", world[:, p], world[:, j])
    quat = Rotation.from_matrix(local.reshape(-1, 3, 3)).as_quat().reshape(F, J, 4)
    root = np.einsum("ij,fj->fi", g, sol.positions[:, 0])
    near = _fill_nearest(np.isfinite(root).all(axis=1))
    root = np.zeros_like(root) if near[0] < 0 else root[near]
    ends = {}
    for j, name in enumerate(names):
        if j not in sol.joint_parents:
            length = np.linalg.norm(offsets[j])
            d = _unit(offsets[j]) if length > _EPS else np.array([0.0, 1.0, 0.0])
            ends[name] = d * max(0.25 * length, 0.02)
    # depth-first joint order, as a BVH file lists them
    parents = sol.joint_parents
    perm: list[int] = []
    stack = [0]
    while stack:
        j = stack.pop()
        perm.append(j)
        stack.extend(reversed([k for k in range(J) if parents[k] == j]))
    inv = {old: new for new, old in enumerate(perm)}
    skel = Skeleton(tuple(names[j] for j in perm),
                    tuple(-1 if parents[j] < 0 else inv[parents[j]] for j in perm),
                    offsets[perm], ends)
    return Motion(skel, root, quat[:, perm], sol.fps)
