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

Hips from a trial with little hip motion (a walk swings the thigh in one plane): the
fitted centre is then not observable across that plane and soft tissue pulls it 5-6
cm laterally (Plug-in-Gait and Qualisys gait trials in ``../shared``). Where the
marker set names the pelvis landmarks (``hip_regression``), the centre's components
along directions in which the thigh swung less than :data:`MIN_SWING_DEG` come from
the Harrington et al. (2007) regression (:func:`hip_regression`) instead.

Gaps: a frame where the primary three points of a segment are not all present is
filled by a least-squares rigid fit (Kabsch) of the segment's template (the median
local coordinates of all its points) to whichever >= 3 points are present. Samples
with a marker missing simply drop out of the sphere fit.

Everything is vectorised over frames; the only Python loops run over segments,
markers and trials.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from vidcap.errors import FitError, VidcapError
from vidcap.mocap.c3d import MarkerData
from vidcap.mocap.markerset import MarkerSet, MarkerSetError, SegmentSpec, detect_markerset
from vidcap.mocap.spherefit import PLANAR_COND, mgdk

_EPS = 1e-9

#: A hip centre's component along a direction in which the thigh's markers swung by
#: less than this (angular standard deviation about the centre, degrees) comes from
#: the regression when the marker set has one: over a few degrees the sphere fit
#: reads soft-tissue motion as the centre's position.
MIN_SWING_DEG = 10.0


def hip_regression(asis_left, asis_right, psis) -> tuple[np.ndarray, np.ndarray]:
    """Hip joint centres from pelvis landmarks (Harrington et al., J Biomech 40:595, 2007).

    In the pelvis frame at the mid-ASIS point (x anterior, y superior, z right):
    ``x = -0.24 PD - 9.9 mm``, ``y = -0.30 PW - 10.9 mm``, ``z = +-(0.33 PW + 7.3 mm)``,
    with PW the inter-ASIS distance and PD the mid-ASIS to mid-PSIS distance.

    Parameters
    ----------
    asis_left, asis_right : numpy.ndarray, shape (F, 3)
        Anterior superior iliac spine markers, metres.
    psis : sequence of numpy.ndarray, each (F, 3)
        The two posterior superior iliac spine markers, or one sacrum marker.

    Returns
    -------
    left, right : numpy.ndarray, shape (F, 3)
        Hip centres in the markers' frame, metres (NaN where a marker is missing).
    """
    la, ra = np.asarray(asis_left, float), np.asarray(asis_right, float)
    mid_a = (la + ra) / 2
    mid_p = np.mean([np.asarray(p, float) for p in psis], axis=0)
    z = ra - la
    pw = np.linalg.norm(z, axis=-1)
    z = z / pw[:, None]
    back = mid_a - mid_p
    pd = np.linalg.norm(back, axis=-1)
    x = _unit(back - np.sum(back * z, -1)[:, None] * z)
    y = np.cross(z, x)
    ax, ay, az = -0.24 * pd - 0.0099, -0.30 * pw - 0.0109, 0.33 * pw + 0.0073
    base = mid_a + ax[:, None] * x + ay[:, None] * y
    return base - az[:, None] * z, base + az[:, None] * z


def _swing_spread(sets: list[np.ndarray], centre: np.ndarray):
    """Eigenvalues (ascending) and eigenvectors of the pooled within-marker covariance
    of the unit directions from ``centre`` to each marker: how far the segment swung
    about the centre along each direction (sin of the angular standard deviation)."""
    acc, n = np.zeros((3, 3)), 0
    for y in sets:
        if len(y) < 2:
            continue
        d = _unit(np.asarray(y, float) - centre)
        d = d - d.mean(axis=0)
        acc += d.T @ d
        n += len(d)
    return np.linalg.eigh(acc / max(n, 1))


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


def kabsch(template: np.ndarray, points: np.ndarray, weights: np.ndarray | None = None
           ) -> tuple[np.ndarray, np.ndarray]:
    """Rigid poses mapping a template onto points with gaps, batched over frames.

    Parameters
    ----------
    template : numpy.ndarray, shape (K, 3)
        Local coordinates of K points.
    points : numpy.ndarray, shape (F, K, 3)
        Observed positions; NaN rows are ignored.
    weights : numpy.ndarray, shape (K,) or (F, K), optional
        Non-negative weight of each point (inverse variance relative to a marker);
        default 1.

    Returns
    -------
    rotation : numpy.ndarray, shape (F, 3, 3)
        ``points ≈ origin + rotation @ template``; NaN where fewer than 3 non-collinear
        points are present.
    origin : numpy.ndarray, shape (F, 3)
    """
    w = np.isfinite(points).all(axis=2) & np.isfinite(template).all(axis=1)  # (F, K)
    cnt = w.sum(axis=1)
    wf = w.astype(float)
    if weights is not None:
        wf = wf * np.broadcast_to(np.asarray(weights, dtype=float), w.shape)
        wf = np.where(np.isfinite(wf), wf, 0.0)
        w = wf > 0
        cnt = w.sum(axis=1)
    x = np.where(w[..., None], points, 0.0)
    t = np.where(np.isfinite(template), template, 0.0)
    wt = wf[..., None]
    den = np.maximum(wf.sum(axis=1), _EPS)[:, None]
    xc = (wt * x).sum(1) / den
    tc = (wt * t[None]).sum(1) / den
    h = np.einsum("fk,fki,fkj->fij", wf, t[None] - tc[:, None], x - xc[:, None])
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


def point_covariance(template: np.ndarray, v: np.ndarray, weights: np.ndarray | None = None
                     ) -> np.ndarray:
    """Covariance of a rigidly attached point predicted by a least-squares (Kabsch) frame.

    For K points with isotropic noise σ² / w_k fitted rigidly, the pose errors are a
    translation with covariance σ² I / Σw and a small rotation with covariance
    σ² Iₘ⁻¹, Iₘ = Σ w_k (|m_k|² I - m_k m_kᵀ) the weighted inertia of the template about
    its weighted centroid. A point v then has covariance
    σ² (I / Σw + [p]ₓ Iₘ⁻¹ [p]ₓᵀ), p = v - centroid, in the frame's own coordinates.

    Parameters
    ----------
    template : numpy.ndarray, shape (K, 3)
        The frame's points in its own coordinates (NaN rows ignored).
    v : numpy.ndarray, shape (3,)
        The point, same coordinates.
    weights : numpy.ndarray, shape (K,), optional

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        In units of σ² (all inf if undetermined).
    """
    t = np.asarray(template, dtype=float)
    w = np.ones(len(t)) if weights is None else np.asarray(weights, dtype=float)
    ok = np.isfinite(t).all(axis=1) & np.isfinite(w) & (w > 0)
    if ok.sum() < 3 or not np.isfinite(v).all():
        return np.full((3, 3), np.inf)
    t, w = t[ok], w[ok]
    c = (w[:, None] * t).sum(0) / w.sum()
    m = t - c
    inertia = (w * (m * m).sum(1)).sum() * np.eye(3) - np.einsum("k,ki,kj->ij", w, m, m)
    try:
        inv = np.linalg.inv(inertia)
    except np.linalg.LinAlgError:
        return np.full((3, 3), np.inf)
    p = np.asarray(v, dtype=float) - c
    px = np.array([[0.0, -p[2], p[1]], [p[2], 0.0, -p[0]], [-p[1], p[0], 0.0]])
    return np.eye(3) / w.sum() + px @ inv @ px.T


def point_variance(template: np.ndarray, v: np.ndarray, weights: np.ndarray | None = None
                   ) -> float:
    """Trace of :func:`point_covariance` (units of σ²; inf if undetermined)."""
    return float(np.trace(point_covariance(template, v, weights)))


def _frame_noise(template: np.ndarray, weights: np.ndarray | None):
    """Weighted centroid (3,) and inverse inertia (3, 3) of a frame's template."""
    t = np.asarray(template, dtype=float)
    w = np.ones(len(t)) if weights is None else np.asarray(weights, dtype=float)
    ok = np.isfinite(t).all(axis=1) & np.isfinite(w) & (w > 0)
    if ok.sum() < 3:
        return None, None
    t, w = t[ok], w[ok]
    c = (w[:, None] * t).sum(0) / w.sum()
    m = t - c
    inertia = (w * (m * m).sum(1)).sum() * np.eye(3) - np.einsum("k,ki,kj->ij", w, m, m)
    try:
        return c, np.linalg.inv(inertia)
    except np.linalg.LinAlgError:
        return None, None


def score(rp: np.ndarray, tp: np.ndarray, rc: np.ndarray, tc: np.ndarray, *,
          rot_cov_p=None, rot_cov_c=None, centroid_p=None, centroid_c=None) -> dict:
    """Symmetrical centre of rotation estimation (SCoRE, Ehrig et al. 2006) and the
    hinge axis of SARA (Ehrig et al. 2007), in closed form.

    The joint centre is a point fixed in both segments: c_p in the parent's frame
    and c_c in the child's. Minimise Σ_k |R_pk c_p + t_pk - R_ck c_c - t_ck|², a linear
    least-squares problem in x = (c_p, c_c): with A_k = [R_pk, -R_ck], b_k = t_ck - t_pk,
    (Σ A_kᵀ A_k) x = Σ A_kᵀ b_k. For a hinge the normal matrix has a (near) null vector
    (a_p, a_c): the hinge axis in both frames (SARA); every point of the axis fits.

    Parameters
    ----------
    rp, rc : numpy.ndarray, shape (F, 3, 3)
        Parent and child frames (columns = axes, lab); frames with NaN are skipped.
    tp, tc : numpy.ndarray, shape (F, 3)
        Their origins, lab.

    rot_cov_p, rot_cov_c : numpy.ndarray, shape (3, 3), optional, keyword-only
        Covariance (rad², in the segment's own axes) of each frame's small rotation
        error, for the noise correction below; with them ``centroid_p/_c`` (3,), the
        points about which the frames were fitted (their rotation and that point's
        position are then uncorrelated).

    Noise correction (ours, not in Ehrig et al.): with R̂ = R exp([ε]ₓ), ε ~ (0, Σ),
    E[R̂] = R (I - K/2), K = tr(Σ) I - Σ, so the normal equations built from noisy
    frames shrink every rotation by (I - K/2), which biases the centre by O(σ²/θ²)
    for a range of motion θ. About the centroids (positions independent of the
    rotation errors) the expected cross term is (I - K_p/2) Σ R_pᵀR_c (I - K_c/2) and
    the right-hand side's parts are shrunk by (I - K/2): both are un-shrunk here.

    Returns
    -------
    dict
        ``x`` (6,) least-squares solution (the minimum-norm one along the weakest
        direction), ``null`` (6,) unit eigenvector of the smallest eigenvalue,
        ``eig`` (6,) eigenvalues ascending, ``s2`` residual variance per coordinate
        (m²), ``n`` frames used; ``x`` is None when fewer than 10 frames are usable.
    """
    ok = (np.isfinite(rp).all(axis=(1, 2)) & np.isfinite(rc).all(axis=(1, 2))
          & np.isfinite(tp).all(axis=1) & np.isfinite(tc).all(axis=1))
    n = int(ok.sum())
    if n < 10:
        return {"x": None, "n": n}
    rp, tp, rc, tc = rp[ok], tp[ok], rc[ok], tc[ok]
    shift = np.zeros(6)
    dp = dc = np.eye(3)
    if rot_cov_p is not None and rot_cov_c is not None:
        tp = tp + np.einsum("fij,j->fi", rp, centroid_p)
        tc = tc + np.einsum("fij,j->fi", rc, centroid_c)
        shift = np.concatenate([centroid_p, centroid_c])
        dp = np.linalg.inv(np.eye(3) - 0.5 * (np.trace(rot_cov_p) * np.eye(3) - rot_cov_p))
        dc = np.linalg.inv(np.eye(3) - 0.5 * (np.trace(rot_cov_c) * np.eye(3) - rot_cov_c))
    cross = dp @ np.einsum("fji,fjk->ik", rp, rc) @ dc  # Σ R_pᵀ R_c
    m = np.zeros((6, 6))
    m[:3, :3] = n * np.eye(3)
    m[3:, 3:] = n * np.eye(3)
    m[:3, 3:] = -cross
    m[3:, :3] = -cross.T
    b = tc - tp
    rhs = np.concatenate([dp @ np.einsum("fji,fj->i", rp, b),
                          -dc @ np.einsum("fji,fj->i", rc, b)])
    lam, vec = np.linalg.eigh(m)
    coef = vec.T @ rhs
    inv = np.where(lam > 1e-9 * lam[-1], 1.0 / np.maximum(lam, 1e-300), 0.0)
    x_full = vec @ (coef * inv)
    x_min = vec[:, 1:] @ (coef[1:] * inv[1:])  # without the weakest direction
    res = (np.einsum("fij,j->fi", rp, x_full[:3]) + tp
           - np.einsum("fij,j->fi", rc, x_full[3:]) - tc)
    s2 = float(np.sum(res ** 2) / max(3 * n - 6, 1))
    x_full, x_min = x_full + shift, x_min + shift
    return {"x": x_full, "x_min": x_min, "null": vec[:, 0], "eig": lam, "s2": s2, "n": n}


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
    weights: np.ndarray | None = None  # (K,) relative inverse variances, None = all 1

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
    # Σ_p N_p Cov_p(u) = Σ_all u uᵀ - Σ_p N_p ū_p ū_pᵀ, with all markers at once
    sets = [y for y in sets if len(y) > 1]
    if not sets:
        return np.full(3, np.nan), float("inf")
    lens = np.array([len(y) for y in sets])
    u = _unit(np.concatenate(sets) - center)
    u = np.where(np.isfinite(u), u, 0.0)
    sums = np.add.reduceat(u, np.r_[0, np.cumsum(lens)[:-1]], axis=0)  # (P, 3)
    info = u.T @ u - np.einsum("pi,pj,p->ij", sums, sums, 1.0 / lens)
    w, v = np.linalg.eigh(info / max(sigma, 1e-12) ** 2)
    std = np.inf if w[0] <= 0 else 1.0 / np.sqrt(w[0])
    return v[:, 0], float(std)


def _axis_along_bone(axis, anchor, child_sets, *, max_deg: float = 45.0) -> float | None:
    """The angle (degrees) between a hinge axis and the bone, when it is under ``max_deg``.

    The bone runs from ``anchor`` (the parent's proximal joint, parent frame, metres)
    to the centroid of the child's markers (``child_sets``: arrays (N_k, 3) in the
    parent frame). A knee, elbow, ankle or wrist flexes about an axis across its bone;
    an axis along it means the motion is rotation about the limb's length (or noise
    in a parent frame built from few markers), where the hinge rule would put the
    centre next to the parent joint. None when the axis is across the bone or when
    anything needed is missing.
    """
    if axis is None or anchor is None or not np.isfinite(anchor).all():
        return None
    pts = [np.asarray(y, float) for y in child_sets if len(y)]
    if not pts:
        return None
    bone = np.concatenate(pts).mean(axis=0) - anchor
    norm = float(np.linalg.norm(bone)) * float(np.linalg.norm(axis))
    if not np.isfinite(norm) or norm <= 0:
        return None
    angle = float(np.degrees(np.arccos(min(1.0, abs(float(bone @ axis)) / norm))))
    return angle if angle < max_deg else None


def _fit_joint(spec: SegmentSpec, parent: str, sets: list[np.ndarray], fallback_local,
               frames_used: int, *, noise_mm, min_cap_deg, planar_cond, anchor,
               max_axial_std_mm, hinge_ratio, frame_cov=None, anchor_what="",
               bone_guard=True) -> tuple:
    """Fit one joint centre in the parent's frame; returns (v (3,), axis or None, report).

    ``frame_cov`` (3, 3), in units of σ²: the extra noise the parent's frame adds to a
    child marker expressed in it (:func:`point_covariance`), added to the marker's
    own σ² I for UGDK when ``noise_mm`` is given.
    """
    usable = [y for y in sets if len(y) >= 4]
    note = ""
    fit = None
    if usable:
        try:
            cov = None
            if noise_mm is not None:
                extra = np.zeros((3, 3)) if frame_cov is None else frame_cov
                cov = (float(noise_mm) * 1e-3) ** 2 * (np.eye(3) + extra)
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
        rule = (anchor is not None and np.isfinite(anchor).all()
                and (kind == "hinge" or thin or axial_std * 1e3 > max_axial_std_mm))
        # (an anchor at the joint itself, landmarks straddling it, cannot slide it away)
        along = _axis_along_bone(axis_w, anchor, usable) if rule and bone_guard else None
        if along is not None:
            # The rule below is for a bone flexing about an axis across it; an axis
            # within 45 degrees of the bone (rotation about the bone's own length, or
            # a badly defined parent frame) would slide the centre along the limb
            # toward the parent joint: no hinge to trust, so the fallback stands in.
            flagged = True
            note = (f"motion about an axis {along:.0f} deg from the bone, not across it: "
                    "the centre is not observable")
        elif rule:
            # Motion (nearly) about one axis: the centre's position along that axis is not
            # observable. Place it at the point of the axis nearest the anchor: landmarks
            # straddling the joint where the set names them, else the parent's proximal
            # joint (for a long bone flexing about an axis across it - knee, elbow, ankle,
            # wrist - that is where the bone's long axis meets the hinge axis).
            center = center + ((anchor - center) @ axis_w) * axis_w
            normal = axis_w
            kind = "hinge"
            method += "+axis-rule"
            note = (f"centre along the hinge axis (std {axial_std * 1e3:.0f} mm from the fit) "
                    f"placed nearest {anchor_what or f'the {parent} proximal joint'}")
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


def _rigid_residual_var(frames: list[_SegFrames], pts: list[np.ndarray]) -> float:
    """Per-coordinate marker noise variance (m²) from rigid-fit residuals of K >= 3 points.

    Each frame's least-squares pose uses 6 of its 3K coordinates, so
    σ̂² = Σ |x - o - R m|² / Σ_frames (3K - 6) (the template's own error neglected).
    """
    ss, dof = 0.0, 0
    for f, x in zip(frames, pts, strict=True):
        pred = f.o[:, None] + np.einsum("fij,kj->fki", f.r, f.template[: x.shape[1]])
        res = np.sum((x - pred) ** 2, axis=2)  # (F, K)
        ok = np.isfinite(res)
        k = ok.sum(axis=1)
        use = k >= 3
        ss += float(res[use][ok[use]].sum())
        dof += int(np.sum(3 * k[use] - 6))
    return ss / dof if dof > 0 else 0.0


def _regress_hip(v, rep: JointReport, spec: SegmentSpec, root: SegmentSpec, trials,
                 frames, sets) -> tuple[np.ndarray, JointReport, bool]:
    """The hip centre ``v`` (root frame) with its poorly swung components taken from
    :func:`hip_regression` (see :data:`MIN_SWING_DEG`); the report says which."""
    from dataclasses import replace

    lam, vec = _swing_spread(sets, v)
    swing_deg = np.degrees(np.arcsin(np.sqrt(np.clip(lam, 0.0, 1.0))))
    weak = swing_deg < MIN_SWING_DEG
    if not weak.any():  # swung enough every way: the fit stands, no regression needed
        return v, rep, False
    side = root.hip_joints.index(spec.joint)
    local = []
    for ti, t in enumerate(trials):
        idx = [t.index(m) for m in (*root.hip_asis, *root.hip_psis)]
        pts = t.positions[:, idx]
        hip = hip_regression(pts[:, 0], pts[:, 1], list(pts[:, 2:].transpose(1, 0, 2)))[side]
        pf = frames[ti][root.name]
        local.append(_to_local(pf.r, pf.o, hip[:, None])[:, 0])
    reg = _nanmedian_rows(np.concatenate(local))
    if not np.isfinite(reg).all():
        return v, rep, False
    e = vec[:, weak]
    v = v + e @ (e.T @ (reg - v))
    swing = ", ".join(f"{a:.0f}" for a in swing_deg)
    note = (f"{int(weak.sum())} of 3 directions from the pelvis-landmark regression "
            f"(Harrington 2007): the thigh swung {swing} deg (sd) about the fitted centre, "
            f"under {MIN_SWING_DEG:g} deg there; regression {np.linalg.norm(reg - v) * 1e3:.0f}"
            " mm from the result")
    rep = replace(rep, method=rep.method + "+regression", note=note,
                  center_local_m=[float(a) for a in v])
    return v, rep, True


def _refine_score(sc: dict, rep: JointReport, anchor, max_axial_std_mm: float,
                  child_points: np.ndarray, anchor_what: str = "", bone_guard: bool = True):
    """The SCoRE/SARA centre in (parent, child) frames and the updated report.

    ``child_points`` (N, 3): the child's markers in the parent's frame (metres), which
    tell the bone's direction from ``anchor`` (:func:`_axis_along_bone`).
    """
    from dataclasses import replace

    lam, null, s2 = sc["eig"], sc["null"], sc["s2"]
    n_p = float(np.linalg.norm(null[:3]))
    # standard deviation of the parent-frame centre along the weakest direction
    std = (float(np.sqrt(s2 / lam[0]) * n_p) if lam[0] > 1e-12 * lam[-1]
           else float("inf"))
    hinge = anchor is not None and np.isfinite(anchor).all() and n_p > 0.3 and (
        rep.kind == "hinge" or std * 1e3 > max_axial_std_mm) and (
        not bone_guard or _axis_along_bone(null[:3] / n_p, anchor, [child_points]) is None)
    if hinge:
        # SARA: the axis is the null direction; the point on it nearest the parent's
        # proximal joint (the hinge rule, see solve_joints)
        x = sc["x_min"]
        t = float((anchor - x[:3]) @ null[:3]) / n_p ** 2
        x = x + t * null
        axis = null[:3] / n_p
        kind, method = "hinge", "score+sara+axis-rule"
        note = (f"SARA axis; centre along it (std {std * 1e3:.0f} mm from the fit) placed "
                f"nearest {anchor_what or f'the {rep.parent_segment} proximal joint'}")
    else:
        x = sc["x"] if lam[0] > 1e-9 * lam[-1] else sc["x_min"]
        axis = np.asarray(rep.axis, dtype=float) if rep.axis is not None else None
        kind, method, note = rep.kind, "score", rep.note
    rep = replace(rep, kind=kind, method=method, note=note, axial_std_mm=std * 1e3,
                  axis=None if axis is None else [float(a) for a in axis],
                  center_local_m=[float(a) for a in x[:3]])
    return x[:3], x[3:], axis, rep


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
    score_refine: bool = True,
    noise_correct: bool = True,
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
    score_refine : bool, keyword-only
        For a child segment with >= 3 markers (frames of its own), replace the MGDK
        centre by the symmetric two-frame fit (:func:`score`, SCoRE; SARA's axis and
        the ``hinge_rule`` for hinges), and take each frame's centre as the
        inverse-variance mean of the parent's and the child's prediction
        (:func:`point_variance`); the parent's prediction also enters the child's
        least-squares frame as a weighted point (seed 000 §2.5: a solved centre counts
        as a point). MGDK's fit still decides the kind, flags and fallbacks.
    noise_correct : bool, keyword-only
        Remove the O(σ²) shrinkage bias of SCoRE due to noisy frames (see
        :func:`score`), with σ from ``noise_mm`` or else estimated from the child's
        rigid-fit residuals, and the frames' rotation noise predicted from their
        templates (:func:`point_covariance`).

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
            with warnings.catch_warnings():  # frames without any of them stay NaN
                warnings.simplefilter("ignore", RuntimeWarning)
                fb.append(np.nanmean(fy, axis=1) if np.isfinite(fy).any() else fy[:, 0])
        sets_c = [np.concatenate(a) for a in sets]
        fallback_local = _nanmedian_rows(np.concatenate(fb))
        pspec = ms.segment(s.parent)
        n_siblings = sum(1 for q in ms.segments if q.parent == s.parent)
        anchor, anchor_what = None, ""
        pf0 = frames[0][s.parent]
        if s.axis_anchor and hinge_rule:
            # landmarks straddling the joint (epicondyles, malleoli, styloids): their
            # midpoint is the joint's anatomical centre along its axis
            anchor = _nanmedian_rows(np.nanmean(
                _to_local(pf0.r, pf0.o, markers_of(trials[0], s.axis_anchor)), axis=1))
            anchor_what = f"the {'/'.join(s.axis_anchor)} midpoint"
        elif pspec.parent is not None and n_siblings == 1 and hinge_rule:
            anchor = _nanmedian_rows(
                _to_local(pf0.r, pf0.o, centres[0][pspec.joint][:, None])[:, 0])
            anchor_what = f"the {s.parent} proximal joint"
        # the noise the parent's frame adds to the child's markers in its coordinates
        # (mean over the markers of the propagated covariance, units of σ²)
        covs = [point_covariance(pf0.template, y.mean(axis=0), pf0.weights)
                for y in sets_c if len(y)]
        frame_cov = np.mean(covs, axis=0) if covs else None
        if frame_cov is not None and not np.isfinite(frame_cov).all():
            frame_cov = None
        v, axis, rep = _fit_joint(s, s.parent, sets_c, fallback_local, used,
                                  noise_mm=noise_mm, min_cap_deg=min_cap_deg,
                                  planar_cond=planar_cond, anchor=anchor,
                                  anchor_what=anchor_what, bone_guard=not s.axis_anchor,
                                  max_axial_std_mm=max_axial_std_mm,
                                  hinge_ratio=hinge_ratio, frame_cov=frame_cov)
        # 1b. With >= 3 markers the child has frames of its own: refine symmetrically
        # (SCoRE / SARA) and combine both segments' predictions of the centre per frame.
        raw = ([_frames_from_points(markers_of(t, s.markers)) for t in trials]
               if len(s.markers) >= 3 else None)
        v_child = None
        if raw is not None and not rep.flagged and score_refine:
            # marker noise: a-priori, else from the child's rigid-fit residuals
            if noise_mm is not None:
                sig2_m = (float(noise_mm) * 1e-3) ** 2
            else:
                sig2_m = _rigid_residual_var(raw, [markers_of(t, s.markers) for t in trials])
            pf0 = frames[0][s.parent]
            cen_p, inv_p = _frame_noise(pf0.template, pf0.weights)
            cen_c, inv_c = _frame_noise(raw[0].template, None)
            kw = {}
            if noise_correct and cen_p is not None and cen_c is not None:
                kw = dict(rot_cov_p=sig2_m * inv_p, rot_cov_c=sig2_m * inv_c,
                          centroid_p=cen_p, centroid_c=cen_c)
            sc = score(np.concatenate([frames[ti][s.parent].r for ti in range(len(trials))]),
                       np.concatenate([frames[ti][s.parent].o for ti in range(len(trials))]),
                       np.concatenate([f.r for f in raw]), np.concatenate([f.o for f in raw]),
                       **kw)
            if sc["x"] is not None:
                v, v_child, axis, rep = _refine_score(sc, rep, anchor, max_axial_std_mm,
                                                      np.concatenate(sets_c), anchor_what,
                                                      not s.axis_anchor)
        if s.parent == root.name and s.joint in root.hip_joints and not rep.flagged:
            v, rep, moved = _regress_hip(v, rep, s, root, trials, frames, sets_c)
            if moved:
                v_child = None  # the parent's prediction only: the child's is the fit's
        fitted_v[s.joint] = v
        axes[s.joint] = axis
        reports.append(rep)
        # 2. Per-frame centre and the segment's own frames, per trial.
        for ti, t in enumerate(trials):
            pf = frames[ti][s.parent]
            c = _to_lab(pf.r, pf.o, v)
            mk = markers_of(t, s.markers)
            if v_child is not None:
                # inverse-variance mean of the parent's and the child's prediction; the
                # parent's prediction is also a weighted point of the child's frame
                var_p = point_variance(pf.template, v, pf.weights)
                cf = raw[ti]
                var_c = point_variance(cf.template, v_child)
                # the parent's prediction as a point of the child's frame, weighted by
                # its variance relative to a marker's; the variance is scaled to the
                # observed parent/child mismatch (3 s² = σ²(var_p + var_c)), so a joint
                # that is not a fixed point (a spine standing for several joints)
                # counts for little
                sig2_eff = max(3.0 * sc["s2"] / (var_p + var_c), sig2_m)
                w_pt = 3.0 * sig2_m / max(sig2_eff * var_p, 1e-300) if sig2_m > 0 else 0.0
                cc = _to_lab(cf.r, cf.o, v_child)
                wp = np.where(np.isfinite(c).all(1), 1.0 / var_p, 0.0)[:, None]
                wc = np.where(np.isfinite(cc).all(1), 1.0 / var_c, 0.0)[:, None]
                with np.errstate(invalid="ignore", divide="ignore"):
                    both = (np.where(wp > 0, c, 0.0) * wp + np.where(wc > 0, cc, 0.0) * wc) \
                        / (wp + wc)
                centres[ti][s.joint] = np.where(wp + wc > 0, both, np.nan)
                tmpl = np.concatenate([cf.template, v_child[None]])
                wts = np.concatenate([np.ones(len(cf.template)), [w_pt]])
                pts = np.concatenate([mk, c[:, None]], axis=1)
                r2, o2 = kabsch(tmpl, pts, wts)
                frames[ti][s.name] = _SegFrames(r2, o2, tmpl, wts)
                continue
            centres[ti][s.joint] = c
            if len(s.markers) >= 3:
                frames[ti][s.name] = raw[ti]
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
