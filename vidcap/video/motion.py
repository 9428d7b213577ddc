"""From 3D joints to a skeletal motion: rotations, keyframes, smoothing, root, floor.

The seed (section 3.1.5) keys 3D poses and interpolates between them linearly. Here
every frame's pose becomes local joint rotations of the body model's skeleton
(:meth:`vidcap.body.BodyModel.skeleton`):

* the pelvis (root) gets the rigid torso frame: up = pelvis -> neck, right = the mean
  of the left -> right shoulder and hip vectors made perpendicular to it;
* every other joint with a child gets the *minimal* rotation that turns its child's
  rest offset onto the observed bone, expressed in its parent's frame (no twist is
  invented);
* the ankles keep the foot horizontal and pointing the way the body faces.

Keyframes (all frames, or those a confidence picks) are interpolated with
:class:`scipy.spatial.transform.Slerp`; an optional Gaussian smoothing of the
rotations and root is reported with its jitter (mean frame-to-frame joint
acceleration) before and after.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.spatial.transform import Rotation, Slerp

from vidcap.body import JOINT_INDEX, JOINT_NAMES, PARENT_INDEX, BodyModel
from vidcap.kinematics import Motion


def _unit(v, eps=1e-12):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.maximum(n, eps)


def minimal_rotation(a, b) -> np.ndarray:
    """Quaternions (x, y, z, w) of the smallest rotations taking directions ``a`` to ``b``.

    Parameters
    ----------
    a, b : array_like, shape (..., 3)
        Directions (need not be unit).

    Returns
    -------
    numpy.ndarray, shape (..., 4)
        For opposite directions, a half turn about an axis perpendicular to ``a``.
    """
    a, b = np.broadcast_arrays(_unit(np.asarray(a, float)), _unit(np.asarray(b, float)))
    w = 1.0 + np.sum(a * b, -1, keepdims=True)
    xyz = np.cross(a, b)
    opposite = w[..., 0] < 1e-8
    if opposite.any():
        perp = np.cross(a, np.array([1.0, 0.0, 0.0]))
        small = np.linalg.norm(perp, axis=-1) < 1e-6
        perp[small] = np.cross(a[small], np.array([0.0, 1.0, 0.0]))
        xyz = np.where(opposite[..., None], _unit(perp), xyz)
        w = np.where(opposite[..., None], 0.0, w)
    return _unit(np.concatenate([xyz, w], -1))


def torso_frames(joints3d) -> np.ndarray:
    """World rotation matrices of the rigid torso, shape (F, 3, 3).

    Columns: body right (+X in the rest pose), up (+Y), back (+Z).
    """
    j = np.asarray(joints3d, float)
    i = JOINT_INDEX
    up = _unit(j[:, i["neck"]] - j[:, i["pelvis"]])
    right = (j[:, i["r_shoulder"]] - j[:, i["l_shoulder"]]) + (j[:, i["r_hip"]] - j[:, i["l_hip"]])
    right = _unit(right - np.sum(right * up, -1, keepdims=True) * up)
    back = np.cross(right, up)
    return np.stack([right, up, back], -1)


def joints_to_motion(joints3d, fps: float, *, body: BodyModel | None = None) -> Motion:
    """Local rotations of the body model's skeleton that reproduce 3D joints.

    Parameters
    ----------
    joints3d : array_like, shape (F, 15, 3)
        Joint positions in metres (Y up), :data:`vidcap.body.JOINT_NAMES` order.
    fps : float
        Frames per second.
    body : BodyModel, optional
        Gives the skeleton's rest offsets (bone lengths).

    Returns
    -------
    Motion
        Root position = the pelvis; forward kinematics reproduce the joint directions
        exactly and the positions wherever the bone lengths equal the model's.
    """
    body = body or BodyModel()
    sk = body.skeleton()
    j = np.asarray(joints3d, float)
    F, J = j.shape[0], len(JOINT_NAMES)
    if j.shape != (F, J, 3):
        raise ValueError(f"joints3d must be (F, {J}, 3), got {j.shape}")
    children = {p: [c for c, q in enumerate(PARENT_INDEX) if q == p] for p in range(J)}
    world = np.empty((F, J, 3, 3))
    local = np.empty((F, J, 4))
    world[:, 0] = torso_frames(j)
    local[:, 0] = Rotation.from_matrix(world[:, 0]).as_quat()
    # heading: yaw-only frame of the torso, for the feet
    back = world[:, 0][:, :, 2].copy()
    back[:, 1] = 0.0
    back = _unit(back + np.array([0, 0, 1e-9]))
    head_up = np.broadcast_to([0.0, 1.0, 0.0], back.shape)
    heading = np.stack([np.cross(head_up, back), head_up, back], -1)
    for k in range(1, J):
        p = PARENT_INDEX[k]
        kids = children[k]
        if kids:
            c = kids[0]
            bone = j[:, c] - j[:, k]
            in_parent = np.einsum("fji,fj->fi", world[:, p], bone)
            q = minimal_rotation(sk.offsets[c], in_parent)
        elif JOINT_NAMES[k].endswith("ankle"):
            q = Rotation.from_matrix(np.swapaxes(world[:, p], 1, 2) @ heading).as_quat()
        else:
            q = np.tile([0.0, 0.0, 0.0, 1.0], (F, 1))
        local[:, k] = q
        world[:, k] = world[:, p] @ Rotation.from_quat(q).as_matrix()
    return Motion(sk, j[:, 0].copy(), _continuous(local), fps)


def _continuous(quats) -> np.ndarray:
    """Flip quaternion signs so consecutive frames lie in the same hemisphere (F, J, 4)."""
    q = np.array(quats, float)
    if q.shape[0] < 2:
        return q
    dots = np.sum(q[1:] * q[:-1], -1)
    flips = np.cumprod(np.where(dots < 0, -1.0, 1.0), axis=0)
    q[1:] *= flips[..., None]
    return q


def jitter(positions, fps: float) -> float:
    """Mean frame-to-frame joint acceleration, m/s^2.

    Parameters
    ----------
    positions : array_like, shape (F, J, 3)
        Joint positions, metres.
    fps : float

    Returns
    -------
    float
        Mean norm of the second difference times fps^2 (0 for fewer than 3 frames).
    """
    p = np.asarray(positions, float)
    if p.shape[0] < 3:
        return 0.0
    acc = (p[2:] - 2 * p[1:-1] + p[:-2]) * fps**2
    return float(np.linalg.norm(acc, axis=-1).mean())


def keyframes_by_confidence(scores, *, min_score: float, max_gap: int = 10) -> np.ndarray:
    """Frames to key: those scoring at least ``min_score``, at most ``max_gap`` apart.

    Parameters
    ----------
    scores : array_like, shape (F,)
        Per-frame confidence (e.g. the 2D fit's similarity).
    min_score : float
    max_gap : int
        Where confident frames are further apart, the best frame of the gap is added.

    Returns
    -------
    numpy.ndarray of int
        Sorted frame indices, always including the first and last frame.
    """
    s = np.asarray(scores, float)
    F = s.size
    keys = set(np.flatnonzero(s >= min_score).tolist()) | {0, F - 1}
    ordered = sorted(keys)
    extra = []
    for a, b in zip(ordered[:-1], ordered[1:], strict=True):
        while b - a > max_gap:
            seg = s[a + 1 : a + max_gap + 1]
            m = a + 1 + int(np.argmax(seg))
            extra.append(m)
            a = m
    return np.array(sorted(keys | set(extra)), dtype=int)


def interpolate_keyframes(motion: Motion, keys) -> Motion:
    """Replace the non-key frames by Slerp (rotations) and linear (root) interpolation.

    Parameters
    ----------
    motion : Motion
    keys : array_like of int
        Key frame indices (sorted, unique; should include 0 and F-1).
    """
    keys = np.unique(np.asarray(keys, int))
    F = motion.n_frames
    if keys.size < 2 or keys.size == F:
        return motion
    t = np.arange(F)
    tq = np.clip(t, keys[0], keys[-1])
    root = np.stack([np.interp(t, keys, motion.root_positions[keys, k]) for k in range(3)], 1)
    rot = np.empty_like(motion.rotations)
    for jn in range(motion.skeleton.n_joints):  # loop over joints, vectorised over frames
        sl = Slerp(keys, Rotation.from_quat(motion.rotations[keys, jn]))
        rot[:, jn] = sl(tq).as_quat()
    return Motion(motion.skeleton, root, _continuous(rot), motion.fps)


def smooth_motion(motion: Motion, sigma: float) -> Motion:
    """Gaussian smoothing (``sigma`` frames) of the root and the hemisphere-aligned
    quaternions, renormalised. ``sigma <= 0`` returns the motion unchanged."""
    if sigma <= 0 or motion.n_frames < 3:
        return motion
    q = _continuous(motion.rotations)
    qs = gaussian_filter1d(q, sigma, axis=0, mode="nearest")
    qs /= np.linalg.norm(qs, axis=-1, keepdims=True)
    root = gaussian_filter1d(motion.root_positions, sigma, axis=0, mode="nearest")
    return Motion(motion.skeleton, root, qs, motion.fps)


def place_on_floor(joints3d, *, ground: str = "image", quantile: float = 0.9) -> np.ndarray:
    """Shift joints vertically so the feet stand on the floor Y = 0, shape (F, 15, 3).

    ``ground='image'``: the floor is the high quantile of the lowest ankle over the
    clip (jumps stay jumps), and no ankle ever goes below it. ``ground='lowest'``:
    every frame's lowest ankle is put on the floor.
    """
    j = np.array(joints3d, float)
    i = JOINT_INDEX
    low = np.minimum(j[:, i["l_ankle"], 1], j[:, i["r_ankle"], 1])
    if ground == "lowest":
        j[..., 1] -= low[:, None]
        return j
    if ground != "image":
        raise ValueError(f"ground must be 'image' or 'lowest', got {ground!r}")
    floor = np.quantile(low, 1.0 - quantile)  # the ankles' usual lowest height
    shift = np.maximum(low - floor, 0.0) - low  # frames below the floor are raised onto it
    j[..., 1] += shift[:, None]
    return j


@dataclass(frozen=True)
class MotionResult:
    """Result of :func:`build_motion`: the motion and its jitter before/after smoothing."""

    motion: Motion
    jitter_before: float
    jitter_after: float
    keys: np.ndarray


def build_motion(
    joints3d,
    fps: float,
    *,
    body: BodyModel | None = None,
    keys=None,
    smooth_sigma: float = 0.0,
    ground: str = "image",
) -> MotionResult:
    """3D joints -> floor-placed, keyframed, optionally smoothed Motion.

    Parameters
    ----------
    joints3d : array_like, shape (F, 15, 3)
        Metres, Y up (e.g. :attr:`vidcap.video.lift.Lift3D.joints3d`, whose X follows the
        subject's image position: the root translation comes from the silhouette).
    fps : float
    body : BodyModel, optional
    keys : array_like of int, optional
        Keyframes (default: every frame).
    smooth_sigma : float
        Gaussian smoothing in frames (0 = none).
    ground : {'image', 'lowest'}
        See :func:`place_on_floor`.
    """
    body = body or BodyModel()
    j = place_on_floor(joints3d, ground=ground)
    return finish_motion(joints_to_motion(j, fps, body=body), keys=keys,
                         smooth_sigma=smooth_sigma)


def finish_motion(motion: Motion, *, keys=None, smooth_sigma: float = 0.0) -> MotionResult:
    """Key, smooth and keep on the floor a floor-placed motion (the end of
    :func:`build_motion`, also used by the clip solve's motion).

    Parameters
    ----------
    motion : Motion
        Feet on the floor Y = 0 (:func:`place_on_floor`).
    keys : array_like of int, optional
        Keyframes (default: every frame).
    smooth_sigma : float
        Gaussian smoothing in frames (0 = none).
    """
    m = motion
    fps = m.fps
    before = jitter(m.positions(), fps)
    if keys is not None:
        m = interpolate_keyframes(m, keys)
    m = smooth_motion(m, smooth_sigma)
    # smoothing/interpolation can sink a foot: keep the feet on or above the floor
    pos = m.positions()
    low = np.minimum(pos[:, JOINT_INDEX["l_ankle"], 1], pos[:, JOINT_INDEX["r_ankle"], 1])
    if (low < 0).any():
        root = m.root_positions.copy()
        root[:, 1] += np.maximum(-low, 0.0)
        m = Motion(m.skeleton, root, m.rotations, fps)
        pos = m.positions()
    after = jitter(pos, fps)
    return MotionResult(m, before, after, np.arange(m.n_frames) if keys is None else keys)
