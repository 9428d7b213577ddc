"""Scaled orthographic lifting of 2D joints to 3D (seed 004 section 2.3 and 3.1.5).

Under scaled orthographic projection (seed 004 Eq. 2.1) a point (X, Y, Z) maps to
(u, v) = s (X, Y). For a segment of known length ``l`` whose ends project
``(du, dv)`` apart, its relative depth is (Eq. 2.2)

    dZ = +/- sqrt(l^2 - (du^2 + dv^2) / s^2),

the sign being the one thing the image does not tell (seed Figure 2.2). Eq. 2.2 as
printed has no sign; the "+/-" is the seed's own text ("two distinct solutions").

Frames
------
Output joints are in a *camera-aligned world*: X = image right, Y = up (image y is
down, so Y = -v / s), Z = toward the camera (right-handed). A depth sign of +1 means
the segment's distal joint is nearer the camera than its proximal one (dZ > 0).
The body's yaw ``psi`` is 0 when it faces the camera and +pi/2 when it faces image
right (as :func:`vidcap.body.orientation_from_yaw`); its forward direction is
``(sin psi, 0, cos psi)`` and its left ``(cos psi, 0, -sin psi)``.

The tree is walked from the pelvis: torso and head by Eq. 2.2; shoulders and hips
are rigid parts of the torso (body model), placed with the torso's axis and the
body's yaw; each limb segment then hangs from its 3D proximal joint with the image
vector of its 2D joints and the depth of Eq. 2.2. Where the image length exceeds
the model length (noise, wrong scale) the depth is clamped to 0, the in-plane vector
is shortened to the model length, and the frame/segment is reported.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vidcap.body import (
    JOINT_INDEX,
    JOINT_NAMES,
    ORIENTATIONS,
    SEGMENT_INDEX,
    SEGMENT_JOINTS,
    SEGMENT_NAMES,
    BodyModel,
    segment_vectors,
)
from vidcap.video.quantreg import quantile_fit

#: Segments walked down the tree after the torso is placed: (segment, proximal joint).
_TORSO_CHAIN = ("torso", "head")
_LIMBS = ("l_upper_arm", "l_lower_arm", "r_upper_arm", "r_lower_arm",
          "l_upper_leg", "l_lower_leg", "r_upper_leg", "r_lower_leg")

#: Indices that swap every ``l_*`` joint with its ``r_*`` twin.
SWAP_JOINTS = np.array(
    [JOINT_INDEX[("r_" + n[2:]) if n.startswith("l_") else ("l_" + n[2:]) if n.startswith("r_")
                 else n] for n in JOINT_NAMES], dtype=np.intp)
#: Indices that swap every ``l_*`` segment with its ``r_*`` twin.
SWAP_SEGMENTS = np.array(
    [SEGMENT_INDEX[("r_" + n[2:]) if n.startswith("l_") else ("l_" + n[2:]) if n.startswith("r_")
                   else n] for n in SEGMENT_NAMES], dtype=np.intp)

#: Half-width of the six orientation sectors: side labels within 30 degrees of a side view.
_SIDE_HALF = np.deg2rad(30.0)


@dataclass(frozen=True)
class Lift3D:
    """Result of :func:`lift`.

    Attributes
    ----------
    joints3d : numpy.ndarray, shape (F, 15, 3)
        Joint positions in metres in the camera-aligned world (X right, Y up, Z toward
        the camera), pelvis of frame 0 at X = 0, Y = 0 (see :func:`vidcap.video.motion`
        for root placement on the floor).
    scale : float or numpy.ndarray, shape (F,)
        Pixels per metre used (per frame where the subject's distance changes).
    yaw : numpy.ndarray, shape (F,)
        Body yaw in radians (0 = facing the camera, +pi/2 = facing image right).
    clamped : numpy.ndarray, shape (F, 10), bool
        Segments whose image length exceeded the model length (depth set to 0).
    excess : numpy.ndarray, shape (F, 10)
        Image length / (segment scale * model length) - 1 where positive, else 0.
    """

    joints3d: np.ndarray
    scale: float | np.ndarray
    yaw: np.ndarray
    clamped: np.ndarray
    excess: np.ndarray


def _check_joints2d(joints2d) -> np.ndarray:
    j = np.asarray(joints2d, dtype=float)
    if j.ndim != 3 or j.shape[1:] != (len(JOINT_NAMES), 2):
        raise ValueError(f"joints2d must be (F, {len(JOINT_NAMES)}, 2), got {j.shape}")
    if not np.isfinite(j).all():
        raise ValueError("joints2d has non-finite values")
    return j


def _frame_scale(scale, n_frames: int) -> np.ndarray:
    """``scale`` (pixels per metre: one, or one per frame) as an (F,) array."""
    s = np.asarray(scale, dtype=float)
    if s.ndim == 0:
        s = np.full(n_frames, float(s))
    if s.shape != (n_frames,):
        raise ValueError(f"scale must be a number or ({n_frames},), got shape {s.shape}")
    if not np.all(s > 0):
        raise ValueError("scale must be positive")
    return s


def _chain_ratio(j: np.ndarray, body: BodyModel) -> np.ndarray:
    """Per frame, the image length of head + torso + mean leg over the model's, px/m."""
    px = np.linalg.norm(segment_vectors(j), axis=-1)  # (F, 10)
    m = body.segment_lengths()
    i = SEGMENT_INDEX
    legs = ("l_upper_leg", "l_lower_leg", "r_upper_leg", "r_lower_leg")
    chain_px = px[:, i["head"]] + px[:, i["torso"]] + 0.5 * sum(px[:, i[s]] for s in legs)
    chain_m = m[i["head"]] + m[i["torso"]] + 0.5 * sum(m[i[s]] for s in legs)
    return chain_px / chain_m


def estimate_scale(joints2d, body: BodyModel | None = None, *, quantile: float = 0.9) -> float:
    """Scale ``s`` of the orthographic projection from the subject's image height.

    The image "height" of a frame is the length of the chain head + torso + mean leg
    (upper + lower) in pixels; divided by the same chain of the model in metres it is
    ``s`` whenever that chain lies in the image plane, and less when it is
    foreshortened or bent, so a high quantile over frames is taken.

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Image joints in pixels.
    body : BodyModel, optional
        Subject's body model (default 1.75 m, Table 3.1 ratios).
    quantile : float
        Quantile over frames (0-1).

    Returns
    -------
    float
        Pixels per metre.
    """
    body = body or BodyModel()
    j = _check_joints2d(joints2d)
    s = float(np.quantile(_chain_ratio(j, body), quantile))
    if not s > 0:
        raise ValueError("cannot estimate the image scale: the figure has no height")
    return s


def _bspline_design(t: np.ndarray, knots: np.ndarray, k: int):
    """The B-spline design matrix, as ``scipy.interpolate.BSpline.design_matrix``.

    Row i holds the k + 1 basis functions of degree k that are non-zero at t[i]
    (Cox-de Boor, "The NURBS Book" algorithm A2.2, vectorised over t); written out
    here because importing ``scipy.interpolate`` costs ~0.35 s, which every
    ``vidcap convert`` would pay. t (F,) within [knots[k], knots[-k-1]]; returns a
    CSR matrix (F, len(knots) - k - 1).
    """
    from scipy.sparse import csr_matrix

    t = np.asarray(t, dtype=float)
    n_basis = len(knots) - k - 1
    # the knot span of each t: knots[span] <= t < knots[span + 1] (the last one closed)
    span = np.clip(np.searchsorted(knots, t, side="right") - 1, k, n_basis - 1)
    values = np.zeros((len(t), k + 1))
    values[:, 0] = 1.0
    left = np.empty((len(t), k + 1))
    right = np.empty((len(t), k + 1))
    for j in range(1, k + 1):
        left[:, j] = t - knots[span + 1 - j]
        right[:, j] = knots[span + j] - t
        saved = np.zeros(len(t))
        for r in range(j):
            temp = values[:, r] / (right[:, r + 1] + left[:, j - r])
            values[:, r] = saved + right[:, r + 1] * temp
            saved = left[:, j - r] * temp
        values[:, j] = saved
    cols = span[:, None] - k + np.arange(k + 1)[None, :]
    rows = np.repeat(np.arange(len(t)), k + 1)
    return csr_matrix((values.ravel(), (rows, cols.ravel())), shape=(len(t), n_basis))


def estimate_scales(joints2d, body: BodyModel | None = None, *, window: int = 91,
                    quantile: float = 0.9, min_change: float = 0.1):
    """Scale per frame, for a subject whose distance from the camera changes.

    Scaled orthography (Eq. 2.1) holds per frame (weak perspective): a subject
    walking toward the camera grows in the image. The per-frame ratio of
    :func:`estimate_scale` is the scale where the chain lies in the image plane and
    less where it is foreshortened or bent, so the scale is its upper ``quantile``
    as a smooth function of time: a quantile regression of its logarithm on
    quadratic B-splines with a knot every ``window`` frames (a linear programme,
    solved exactly by :func:`vidcap.video.quantreg.quantile_fit`).
    When that changes by less than ``min_change`` over the clip (a fraction), the
    subject keeps its distance within what the estimate can tell (on fitted joints
    gait and pose move it by up to about 5 %) and the clip's single scale is
    returned.

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Image joints in pixels.
    body : BodyModel, optional
    window : int
        Frames between knots (about 3 s at 30 fps by default; a shorter clip is one
        quadratic piece).
    quantile : float
        As in :func:`estimate_scale`.
    min_change : float
        Smallest max / min - 1 of the per-frame scales taken as a real change.

    Returns
    -------
    float or numpy.ndarray, shape (F,)
        Pixels per metre: one number, or one per frame.
    """
    body = body or BodyModel()
    j = _check_joints2d(joints2d)
    single = estimate_scale(j, body, quantile=quantile)
    F = j.shape[0]
    n_pieces = max(1, int(np.floor((F - 1) / max(int(window), 2))))
    ratio = _chain_ratio(j, body)
    good = ratio > 0
    if good.sum() < 4 * (n_pieces + 3):
        return single
    t = np.arange(F, dtype=float)
    k = 2  # quadratic pieces: smooth, with few wiggles where the pose, not the distance, changes
    inner = np.linspace(0.0, F - 1.0, n_pieces + 1)
    knots = np.r_[[inner[0]] * k, inner, [inner[-1]] * k]
    basis = _bspline_design(t, knots, k)  # (F, n_pieces + 3), sparse
    y = np.log(ratio[good])
    b = basis[good].toarray()
    beta = quantile_fit(b, y, quantile)  # a few ms, exact; no scipy.optimize import
    if beta is None:
        beta = _quantile_lp(b, y, quantile)
        if beta is None:
            return single
    s = np.exp(basis @ beta)
    if not np.all(np.isfinite(s) & (s > 0)) or s.max() / s.min() - 1.0 < min_change:
        return single
    return s


def _quantile_lp(b, y, quantile: float) -> np.ndarray | None:
    """The quantile regression of ``y`` (n,) on ``b`` (n, m) as a linear programme
    (HiGHS), where :func:`vidcap.video.quantreg.quantile_fit` certifies no vertex;
    None when it fails."""
    from scipy.optimize import linprog
    from scipy.sparse import csr_matrix, eye, hstack

    n, m = b.shape
    # min q sum(u+) + (1 - q) sum(u-)  s.t.  B beta + u+ - u- = y,  u+, u- >= 0
    cost = np.r_[np.zeros(m), np.full(n, quantile), np.full(n, 1.0 - quantile)]
    a_eq = hstack([csr_matrix(b), eye(n), -eye(n)], format="csr")
    bounds = [(None, None)] * m + [(0.0, None)] * (2 * n)
    res = linprog(cost, A_eq=a_eq, b_eq=y, bounds=bounds, method="highs")
    return res.x[:m] if res.success else None


def depth_magnitudes(joints2d, scale, body: BodyModel | None = None):
    """|dZ| of every segment (Eq. 2.2) and whether it was clamped.

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Image joints, pixels.
    scale : float or array_like, shape (F,)
        Pixels per metre (per frame: :func:`estimate_scales`).
    body : BodyModel, optional

    Returns
    -------
    dz : numpy.ndarray, shape (F, 10)
        Absolute relative depth in metres.
    ratio : numpy.ndarray, shape (F, 10)
        Image length / (scale * model length): the foreshortening ratio (1 = in the
        image plane; may exceed 1 where clamped).
    """
    body = body or BodyModel()
    j = _check_joints2d(joints2d)
    lengths = body.segment_lengths()
    s = _frame_scale(scale, j.shape[0])[:, None]
    proj = np.linalg.norm(segment_vectors(j), axis=-1) / s  # metres in the image plane
    ratio = proj / lengths
    dz = np.sqrt(np.clip(lengths**2 - proj**2, 0.0, None))
    return dz, ratio


def torso_width_ratio(joints2d, scale, body: BodyModel | None = None) -> np.ndarray:
    """Horizontal foreshortening of the torso from the image shoulder and hip spans.

    ``scale``: pixels per metre, one or (F,).

    Returns
    -------
    numpy.ndarray, shape (F,)
        ``|u_lsh - u_rsh| + |u_lhip - u_rhip|`` over ``scale`` times the model's
        shoulder + hip spans, clipped to [0, 1]: ``|cos(yaw)|`` for an upright body.
    """
    body = body or BodyModel()
    j = _check_joints2d(joints2d)
    i = JOINT_INDEX
    span = (np.abs(j[:, i["l_shoulder"], 0] - j[:, i["r_shoulder"], 0])
            + np.abs(j[:, i["l_hip"], 0] - j[:, i["r_hip"], 0]))
    full = 2.0 * (body.shoulder_half_width + body.hip_half_width) * _frame_scale(scale, len(j))
    return np.clip(span / full, 0.0, 1.0)


def yaw_from_orientation(orientation, width_ratio) -> np.ndarray:
    """Body yaw from the six orientation labels and the torso's horizontal foreshortening.

    ``|cos(yaw)|`` is the torso width ratio; the label gives the quadrant (front: cos
    > 0, back: cos < 0; right: sin > 0) and bounds the angle to its 60-degree sector.
    For the pure side labels (``left``, ``right``) the front/back sense is unknown
    and the yaw is taken as exactly -/+ 90 degrees.

    Parameters
    ----------
    orientation : array_like of str, shape (F,)
        Labels from :data:`vidcap.body.ORIENTATIONS`.
    width_ratio : array_like, shape (F,)
        See :func:`torso_width_ratio`.

    Returns
    -------
    numpy.ndarray, shape (F,)
        Yaw in radians.
    """
    labels = np.asarray(orientation).astype(str)
    rho = np.clip(np.asarray(width_ratio, dtype=float), 0.0, 1.0)
    bad = sorted(set(labels.ravel()) - set(ORIENTATIONS))
    if bad:
        raise ValueError(f"unknown orientation label(s) {bad}; expected one of {ORIENTATIONS}")
    a = np.clip(np.arccos(rho), 0.0, np.pi / 2 - _SIDE_HALF)  # angle from the camera axis
    right = np.char.endswith(labels, "right")
    back = np.char.startswith(labels, "back")
    side = (labels == "left") | (labels == "right")
    mag = np.where(back, np.pi - a, a)
    mag = np.where(side, np.pi / 2, mag)
    return np.where(right, mag, -mag)


def swap_sides(joints2d) -> np.ndarray:
    """Swap every ``l_*`` joint with its ``r_*`` twin, shape preserved (..., 15, D)."""
    return np.asarray(joints2d)[..., SWAP_JOINTS, :]


def faces_camera(yaw) -> np.ndarray:
    """Which frames face the camera beyond the side sector (cos yaw > sin 30 degrees):
    there the body's left shows on the image's right, so image-side names swap.

    Parameters
    ----------
    yaw : array_like, shape (F,)
        Body yaw, radians.

    Returns
    -------
    numpy.ndarray of bool, shape (F,)
    """
    return np.cos(np.asarray(yaw, dtype=float)) > np.sin(_SIDE_HALF)


def assign_sides(joints2d, yaw, swap=None) -> np.ndarray:
    """Rename image-side limbs (``l_*`` = on the image's left) to the body's sides.

    A body facing the camera (cos yaw > 0) shows its left on the image's right, so
    its image-left limbs are its right ones and are swapped; a body seen from behind
    keeps the image's naming; in a side view (|yaw| within 30 degrees of 90) the
    image gives no side and the fitter's (tracked) naming is kept.

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Image-side named joints.
    yaw : array_like, shape (F,)
        Body yaw, radians.
    swap : array_like of bool, shape (F,), optional
        Which frames face the camera (their names swapped), where something other
        than the yaw's sector says so (a side view whose front the colour frame shows).

    Returns
    -------
    numpy.ndarray, shape (F, 15, 2)
        Body-side named joints.
    """
    j = _check_joints2d(joints2d)
    swap = faces_camera(yaw) if swap is None else np.asarray(swap, bool)
    out = j.copy()
    out[swap] = j[swap][:, SWAP_JOINTS]
    return out


def body_axes(yaw) -> tuple[np.ndarray, np.ndarray]:
    """Forward and left unit vectors of a body with the given yaw, each (F, 3)."""
    yaw = np.asarray(yaw, dtype=float)
    s, c, z = np.sin(yaw), np.cos(yaw), np.zeros_like(yaw)
    return np.stack([s, z, c], -1), np.stack([c, z, -s], -1)


def lift(
    joints2d,
    signs,
    yaw,
    *,
    body: BodyModel | None = None,
    scale=None,
    principal_point=None,
    segment_scale=None,
) -> Lift3D:
    """Lift body-side named 2D joints to 3D with depth signs (seed 004 Eq. 2.2).

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Image joints in pixels (x right, y down), named by the body's sides (see
        :func:`assign_sides` for the image-side naming of the 2D fitter).
    signs : array_like, shape (F, 10)
        Depth sign per segment (+1 distal joint nearer the camera, -1 farther; 0 is
        taken as +1), :data:`vidcap.body.SEGMENT_NAMES` order.
    yaw : array_like, shape (F,)
        Body yaw in radians (:func:`yaw_from_orientation`).
    body : BodyModel, optional
        Subject's lengths (default 1.75 m).
    scale : float or array_like, shape (F,), optional
        Pixels per metre, one or per frame (:func:`estimate_scales`); default
        :func:`estimate_scale`.
    principal_point : (float, float), optional
        Where the camera's axis meets the image, pixels (the frame's centre). Only
        used with per-frame scales: the root's position in metres is then ``(u -
        c) / s`` per frame (weak perspective); default the pelvis' median image
        position.
    segment_scale : float or array_like, shape (F,), optional
        Pixels per metre at which each frame's segments are read, when that differs
        from ``scale`` (which then places the root only): a 2D fit draws its model at
        each frame's silhouette height, so its segments are that frame's model
        lengths times their foreshortening (see
        :func:`vidcap.video.lifting.model_scales`). Default ``scale``.

    Returns
    -------
    Lift3D
    """
    body = body or BodyModel()
    j2 = _check_joints2d(joints2d)
    F = j2.shape[0]
    sg = np.asarray(signs)
    if sg.shape != (F, len(SEGMENT_NAMES)):
        raise ValueError(f"signs must be (F, 10) = ({F}, 10), got {sg.shape}")
    sg = np.where(sg < 0, -1.0, 1.0)
    yaw = np.broadcast_to(np.asarray(yaw, dtype=float), (F,))
    per_frame = scale is not None and np.ndim(scale) > 0
    s = estimate_scale(j2, body) if scale is None else (
        _frame_scale(scale, F) if per_frame else float(scale))
    sf = s[:, None, None] if per_frame else s
    if segment_scale is not None:
        sf = _frame_scale(segment_scale, F)[:, None, None]
    lengths = body.segment_lengths()

    # image vectors in metres, Y up
    vec = segment_vectors(j2) / sf
    vec[..., 1] *= -1.0
    proj = np.linalg.norm(vec, axis=-1)
    ratio = proj / lengths
    clamped = ratio > 1.0 + 1e-9
    shrink = np.where(clamped, 1.0 / np.maximum(ratio, 1e-12), 1.0)
    vec = vec * shrink[..., None]
    dz = np.sqrt(np.clip(lengths**2 - (proj * shrink) ** 2, 0.0, None)) * sg
    seg3 = np.concatenate([vec, dz[..., None]], axis=-1)  # (F, 10, 3)

    J = np.zeros((F, len(JOINT_NAMES), 3))
    ji, si = JOINT_INDEX, SEGMENT_INDEX
    if per_frame:  # weak perspective: u - c = s X per frame
        c = (np.median(j2[:, ji["pelvis"]], axis=0) if principal_point is None
             else np.asarray(principal_point, dtype=float))
        pel = (j2[:, ji["pelvis"]] - c) / s[:, None]
    else:
        pel = j2[:, ji["pelvis"]] / s
    J[:, ji["pelvis"], 0] = pel[:, 0] - pel[0, 0]
    J[:, ji["pelvis"], 1] = -(pel[:, 1] - pel[0, 1])
    J[:, ji["neck"]] = J[:, ji["pelvis"]] + seg3[:, si["torso"]]
    J[:, ji["head_top"]] = J[:, ji["neck"]] + seg3[:, si["head"]]

    # rigid torso: lateral axis from the yaw, made perpendicular to the torso axis
    _, left = body_axes(yaw)
    axis = seg3[:, si["torso"]] / lengths[si["torso"]]
    lat = left - np.sum(left * axis, -1, keepdims=True) * axis
    n = np.linalg.norm(lat, axis=-1, keepdims=True)
    lat = np.where(n > 1e-9, lat / np.maximum(n, 1e-12), left)
    sw, hw = body.shoulder_half_width, body.hip_half_width
    # (the shoulder joints below the torso's top corners, down its axis, as the body's
    # rest pose puts them)
    top = J[:, ji["neck"]] - body.shoulder_drop * axis
    J[:, ji["l_shoulder"]] = top + sw * lat
    J[:, ji["r_shoulder"]] = top - sw * lat
    J[:, ji["l_hip"]] = J[:, ji["pelvis"]] + hw * lat
    J[:, ji["r_hip"]] = J[:, ji["pelvis"]] - hw * lat

    for name in _LIMBS:  # proximal before distal (upper before lower)
        k = si[name]
        p, d = SEGMENT_JOINTS[k]
        J[:, d] = J[:, p] + seg3[:, k]

    excess = np.clip(ratio - 1.0, 0.0, None)
    return Lift3D(joints3d=J, scale=s, yaw=np.array(yaw), clamped=clamped, excess=excess)


def project(joints3d, scale, origin=(0.0, 0.0)) -> np.ndarray:
    """Scaled orthographic projection (Eq. 2.1) back to pixels, (F, J, 3) -> (F, J, 2).

    ``u = origin_u + s X``, ``v = origin_v - s Y`` (image y down); ``scale`` one
    number or one per frame, (F,).
    """
    p = np.asarray(joints3d, dtype=float)
    scale = np.asarray(scale, dtype=float)
    if scale.ndim:
        scale = scale.reshape((-1,) + (1,) * (p.ndim - 2))
    out = np.empty(p.shape[:-1] + (2,))
    out[..., 0] = origin[0] + scale * p[..., 0]
    out[..., 1] = origin[1] - scale * p[..., 1]
    return out
