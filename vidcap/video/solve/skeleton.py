"""The solve's parametrisation of the body model and its forward kinematics.

Per frame the pose is 24 numbers (:data:`N_PARAMS`): the root (pelvis) position
``(X, Y, Z)`` in metres, the torso's yaw, pitch and roll (radians), and a *swing*
for each of the nine joints that move a segment (neck, shoulders, elbows, hips,
knees): a rotation vector perpendicular to the segment's rest direction, two
numbers, so no twist about a bone is invented (the seed's 23 degrees of freedom
plus the root's depth, which only foot contact can tell).

The world is the lift's camera-aligned one (:mod:`vidcap.video.lift`: X image right, Y up,
Z toward the camera); the rest pose is the body model's T-pose facing -Z
(:meth:`vidcap.body.BodyModel.rest_offsets`), so a yaw of 0 faces the camera. The
rotations are exactly the BVH's local rotations (:mod:`vidcap.kinematics`), so the
bone lengths are constant by construction.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from vidcap.body import JOINT_INDEX, JOINT_NAMES, PARENT_INDEX, BodyModel

#: Joints carrying a swing, with the child joint whose offset they turn.
SWING_JOINTS: tuple[tuple[str, str], ...] = (
    ("neck", "head_top"),
    ("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"),
    ("r_shoulder", "r_elbow"), ("r_elbow", "r_wrist"),
    ("l_hip", "l_knee"), ("l_knee", "l_ankle"),
    ("r_hip", "r_knee"), ("r_knee", "r_ankle"),
)
#: Columns of the parameter vector.
ROOT_POS = slice(0, 3)
YAW, PITCH, ROLL = 3, 4, 5
N_PARAMS = 6 + 2 * len(SWING_JOINTS)

_REST_DIR = {
    "neck": (0.0, 1.0, 0.0),
    "l_shoulder": (-1.0, 0.0, 0.0), "l_elbow": (-1.0, 0.0, 0.0),
    "r_shoulder": (1.0, 0.0, 0.0), "r_elbow": (1.0, 0.0, 0.0),
    "l_hip": (0.0, -1.0, 0.0), "l_knee": (0.0, -1.0, 0.0),
    "r_hip": (0.0, -1.0, 0.0), "r_knee": (0.0, -1.0, 0.0),
}
#: (9, 3) rest direction of each swing joint's bone, and (9, 2, 3) the two axes
#: perpendicular to it that its swing vector is made of.
REST_DIRS = np.array([_REST_DIR[j] for j, _ in SWING_JOINTS])
SWING_AXES = np.array([((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)) if abs(d[1]) > 0.5
                       else ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)) for d in REST_DIRS])


def swing_slice(joint: str) -> slice:
    """The two parameter columns of ``joint``'s swing."""
    k = [j for j, _ in SWING_JOINTS].index(joint)
    return slice(6 + 2 * k, 8 + 2 * k)


def cross(a, b) -> np.ndarray:
    """a x b over the last axis (3) with broadcasting; ``numpy.cross`` without its
    axis shuffling, which dominates on many small vectors."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)



def _sin_terms(theta):
    """sin t / t, (1 - cos t) / t^2 and (t - sin t) / t^3, with their limits at 0."""
    small = theta < 1e-4
    t = np.where(small, 1.0, theta)
    t2 = t * t
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(t) / t)
    b = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(t)) / t2)
    c = np.where(small, 1.0 / 6.0 - theta**2 / 120.0, (t - np.sin(t)) / (t2 * t))
    return a, b, c


def _rot_from_terms(r, first, second) -> np.ndarray:
    """I + first [r]x + second [r]x^2 for rotation vectors r (..., 3), (..., 3, 3)."""
    x, y, z = r[..., 0], r[..., 1], r[..., 2]
    t2 = x * x + y * y + z * z
    out = np.empty(r.shape[:-1] + (3, 3))
    d = 1.0 - second * t2
    out[..., 0, 0] = d + second * x * x
    out[..., 1, 1] = d + second * y * y
    out[..., 2, 2] = d + second * z * z
    out[..., 0, 1] = second * x * y - first * z
    out[..., 1, 0] = second * x * y + first * z
    out[..., 0, 2] = second * x * z + first * y
    out[..., 2, 0] = second * x * z - first * y
    out[..., 1, 2] = second * y * z - first * x
    out[..., 2, 1] = second * y * z + first * x
    return out


def rodrigues(rotvec) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of rotation vectors (..., 3), radians."""
    r = np.asarray(rotvec, dtype=float)
    a, b, _ = _sin_terms(np.linalg.norm(r, axis=-1))
    return _rot_from_terms(r, a, b)


def left_jacobian(rotvec) -> np.ndarray:
    """Left Jacobians (..., 3, 3) of SO(3)'s exponential: d exp(r) = [J dr]x exp(r)."""
    r = np.asarray(rotvec, dtype=float)
    _, b, c = _sin_terms(np.linalg.norm(r, axis=-1))
    return _rot_from_terms(r, b, c)


def root_rotation(yaw, pitch, roll) -> np.ndarray:
    """World rotation (..., 3, 3) of the torso: R_y(yaw + pi) R_x(pitch) R_z(roll)."""
    def axis(angle, i, j):
        c, s = np.cos(angle), np.sin(angle)
        m = np.zeros(np.shape(angle) + (3, 3))
        m[..., i, i] = c
        m[..., j, j] = c
        m[..., i, j] = -s
        m[..., j, i] = s
        k = 3 - i - j
        m[..., k, k] = 1.0
        return m
    return axis(np.asarray(yaw) + np.pi, 2, 0) @ axis(pitch, 1, 2) @ axis(roll, 0, 1)


def swing_rotations(params) -> np.ndarray:
    """Local rotation matrices (..., 9, 3, 3) of the :data:`SWING_JOINTS`."""
    p = np.asarray(params, dtype=float)
    ab = p[..., 6:].reshape(p.shape[:-1] + (len(SWING_JOINTS), 2))
    return rodrigues(np.einsum("...ka,kac->...kc", ab, SWING_AXES))


def _swing_vectors(params) -> np.ndarray:
    """Rotation vectors (..., 9, 3) of the swings of poses (..., 24)."""
    p = np.asarray(params, dtype=float)
    ab = p[..., 6:].reshape(p.shape[:-1] + (len(SWING_JOINTS), 2))
    return np.einsum("...ka,kac->...kc", ab, SWING_AXES)


def _world(params, offsets):
    """Joints (..., 15, 3), world rotations by joint name, swing vectors (..., 9, 3)."""
    p = np.asarray(params, dtype=float)
    root = root_rotation(p[..., YAW], p[..., PITCH], p[..., ROLL])
    rv = _swing_vectors(p)
    swings = rodrigues(rv)
    world = {"pelvis": root}
    for k, (name, _) in enumerate(SWING_JOINTS):
        parent = JOINT_NAMES[PARENT_INDEX[JOINT_INDEX[name]]]
        world[name] = world[parent] @ swings[..., k, :, :]
    joints = np.empty(p.shape[:-1] + (len(JOINT_NAMES), 3))
    joints[..., 0, :] = p[..., ROOT_POS]
    for j in range(1, len(JOINT_NAMES)):
        parent = PARENT_INDEX[j]
        rot = world[JOINT_NAMES[parent]]
        joints[..., j, :] = joints[..., parent, :] + rot @ offsets[j]
    return joints, world, rv, swings


def forward_kinematics(params, offsets) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World joints of a batch of poses.

    Parameters
    ----------
    params : array_like, shape (..., 24)
        See the module docstring.
    offsets : numpy.ndarray, shape (15, 3)
        Rest offsets of the joints from their parents, metres
        (:meth:`vidcap.body.BodyModel.rest_offsets`).

    Returns
    -------
    joints : numpy.ndarray, shape (..., 15, 3)
        Metres, camera-aligned world.
    root : numpy.ndarray, shape (..., 3, 3)
        The torso's world rotation.
    swings : numpy.ndarray, shape (..., 9, 3, 3)
        The swing joints' local rotations.
    """
    joints, world, _, swings = _world(params, offsets)
    return joints, world["pelvis"], swings


def _descendants(j: int) -> list[int]:
    return [k for k in range(len(JOINT_NAMES)) if k != j and _is_below(k, j)]


def _is_below(k: int, j: int) -> bool:
    while k >= 0:
        if k == j:
            return True
        k = PARENT_INDEX[k]
    return False


#: (24, 15) which joints each parameter column moves (its pivot's descendants).
_MOVES = np.zeros((N_PARAMS, len(JOINT_NAMES)), bool)
_MOVES[:6] = True
for _k, (_name, _) in enumerate(SWING_JOINTS):
    _MOVES[6 + 2 * _k: 8 + 2 * _k, _descendants(JOINT_INDEX[_name])] = True
#: The turning columns' (yaw on) pivot joints, and the (column, joint) pairs a turn
#: moves: the Jacobian's nonzero rotational entries (68 of 315).
_PIVOTS = np.array([0, 0, 0] + [JOINT_INDEX[n] for n, _ in SWING_JOINTS for _ in range(2)])
_TURN_COL, _TURN_JOINT = np.nonzero(_MOVES[3:] & (np.arange(len(JOINT_NAMES)) != 0))
_TURN_COL = _TURN_COL + 3


def kinematics_jacobian(params, offsets):
    """Forward kinematics and d(joints)/d(params) in closed form.

    A column turning a joint about the world axis w moves every joint p below it by
    ``w x (p - pivot)``; a swing's axis is its parent's world rotation times the
    exponential's left Jacobian times the swing's own axis.

    Parameters
    ----------
    params : array_like, shape (F, 24)
    offsets : numpy.ndarray, shape (15, 3)

    Returns
    -------
    joints : (F, 15, 3); root : (F, 3, 3) the torso's world rotation;
    jac : (F, 15, 3, 24) metres per unit of each parameter.
    """
    p = np.asarray(params, dtype=float)
    joints, world, rv, _ = _world(p, offsets)
    F = p.shape[0]
    axes = np.zeros((F, N_PARAMS, 3))
    turn = root_rotation(p[:, YAW], np.zeros(F), np.zeros(F))
    axes[:, YAW] = (0.0, 1.0, 0.0)
    axes[:, PITCH] = turn[:, :, 0]
    c, s = np.cos(p[:, PITCH]), np.sin(p[:, PITCH])
    axes[:, ROLL] = np.einsum("fij,fj->fi", turn, np.stack([0 * c, -s, c], -1))
    lj = left_jacobian(rv)  # (F, 9, 3, 3)
    for k, (name, _) in enumerate(SWING_JOINTS):
        parent = world[JOINT_NAMES[PARENT_INDEX[JOINT_INDEX[name]]]]
        local_axes = np.einsum("fij,aj->fai", lj[:, k], SWING_AXES[k])  # (F, 2, 3)
        axes[:, 6 + 2 * k: 8 + 2 * k] = np.einsum("fij,faj->fai", parent, local_axes)
    rel = joints[:, _TURN_JOINT] - joints[:, _PIVOTS[_TURN_COL - 3]]  # (F, n, 3)
    jac = np.zeros((F, len(JOINT_NAMES), 3, N_PARAMS))
    jac[:, _TURN_JOINT, :, _TURN_COL] = np.swapaxes(cross(axes[:, _TURN_COL], rel), 0, 1)
    for i in range(3):
        jac[:, :, i, i] = 1.0
    return joints, world["pelvis"], jac


def _swing_vector(rest, direction) -> np.ndarray:
    """Rotation vectors (..., 3) of the minimal rotations from ``rest`` to ``direction``."""
    d = direction / np.maximum(np.linalg.norm(direction, axis=-1, keepdims=True), 1e-12)
    axis = np.cross(rest, d)
    s = np.linalg.norm(axis, axis=-1, keepdims=True)
    c = np.sum(rest * d, axis=-1, keepdims=True)
    angle = np.arctan2(s, c)
    return np.where(s > 1e-12, axis / np.maximum(s, 1e-12) * angle, 0.0)


def params_from_joints(joints3d, yaw_hint=None) -> np.ndarray:
    """Parameters (F, 24) whose pose has the directions of ``joints3d`` (F, 15, 3).

    The torso's frame is :func:`vidcap.video.motion.torso_frames`; every swing is the
    minimal rotation onto the observed bone. ``yaw_hint`` (F,) radians picks the
    turn (2 pi k) of the yaw; the yaw is unwrapped over frames.
    """
    from vidcap.video.motion import torso_frames

    j = np.asarray(joints3d, dtype=float)
    F = j.shape[0]
    frames = torso_frames(j)
    euler = Rotation.from_matrix(frames).as_euler("YXZ")
    yaw = np.unwrap(euler[:, 0] - np.pi)
    if yaw_hint is not None:
        hint = np.broadcast_to(np.asarray(yaw_hint, dtype=float), (F,))
        yaw = yaw + 2 * np.pi * np.round(np.median(hint - yaw) / (2 * np.pi))
    p = np.zeros((F, N_PARAMS))
    p[:, ROOT_POS] = j[:, 0]
    p[:, YAW], p[:, PITCH], p[:, ROLL] = yaw, euler[:, 1], euler[:, 2]
    world = {"pelvis": root_rotation(yaw, euler[:, 1], euler[:, 2])}
    for k, (name, child) in enumerate(SWING_JOINTS):
        parent = JOINT_NAMES[PARENT_INDEX[JOINT_INDEX[name]]]
        bone = j[:, JOINT_INDEX[child]] - j[:, JOINT_INDEX[name]]
        local = np.einsum("fji,fj->fi", world[parent], bone)
        rv = _swing_vector(REST_DIRS[k], local)
        p[:, 6 + 2 * k: 8 + 2 * k] = np.einsum("fc,ac->fa", rv, SWING_AXES[k])
        world[name] = world[parent] @ rodrigues(rv)
    return p


def local_quaternions(params, body: BodyModel | None = None) -> np.ndarray:
    """The BVH local rotations (F, 15, 4) (x, y, z, w) of poses ``params`` (F, 24).

    The ankles keep the foot level and pointing the way the torso faces, as
    :func:`vidcap.video.motion.joints_to_motion` does; the other leaf joints have none.
    """
    p = np.asarray(params, dtype=float)
    F = p.shape[0]
    root = root_rotation(p[:, YAW], p[:, PITCH], p[:, ROLL])
    swings = swing_rotations(p)
    mats = np.tile(np.eye(3), (F, len(JOINT_NAMES), 1, 1))
    mats[:, 0] = root
    world = {"pelvis": root}
    for k, (name, _) in enumerate(SWING_JOINTS):
        mats[:, JOINT_INDEX[name]] = swings[:, k]
        parent = JOINT_NAMES[PARENT_INDEX[JOINT_INDEX[name]]]
        world[name] = world[parent] @ swings[:, k]
    heading = root_rotation(p[:, YAW], np.zeros(F), np.zeros(F))
    for side in "lr":
        knee = world[f"{side}_knee"]
        mats[:, JOINT_INDEX[f"{side}_ankle"]] = np.swapaxes(knee, 1, 2) @ heading
    q = Rotation.from_matrix(mats.reshape(-1, 3, 3)).as_quat().reshape(F, len(JOINT_NAMES), 4)
    dots = np.sum(q[1:] * q[:-1], -1)  # consecutive frames in one hemisphere
    q[1:] *= np.cumprod(np.where(dots < 0, -1.0, 1.0), axis=0)[..., None]
    return q


def params_to_motion(params, body: BodyModel, fps: float):
    """The :class:`vidcap.kinematics.Motion` of poses ``params`` (F, 24): the root at
    the pelvis, the solve's rotations as the BVH's (no position-to-rotation step)."""
    from vidcap.kinematics import Motion

    p = np.asarray(params, dtype=float)
    sk = body.skeleton()
    return Motion(sk, p[:, ROOT_POS] - sk.offsets[0], local_quaternions(p, body), fps)
