"""Joint limits of the solve, as soft barriers (seed 004 Table 3.3 and anatomy).

Table 3.3 bounds the waist and the neck to 45-135 degrees in the image, i.e. the
torso and the head within 45 degrees of upright; in 3D the same bound is put on the
torso's pitch and roll and on the head's angle from the torso's axis. The table's
hip range (thighs within 30 degrees of straight down *in the image*) is a 2D search
window; in 3D the hips get the normal ranges of motion of the American Academy of
Orthopaedic Surgeons (Greene & Heckman 1994): flexion 120, extension 30, abduction
45, adduction 30 degrees; the shoulders extension 60 (an upper arm points behind
the body no further); knees and elbows :data:`vidcap.body.FLEXION_LIMITS_DEG`, the
knee folding backward only, with 15 degrees of sideways play for the model's hinge.

Every angle is read from the world joints and the torso's rotation, in the frame of
the parent segment (a thigh's frame being the minimal rotation of its rest
direction, as the solve's swings are), so the solve and the sign search
(:mod:`vidcap.video.solve.signs`) score a pose the same way.
"""

from __future__ import annotations

import numpy as np

from vidcap.body import FLEXION_LIMITS_DEG, JOINT_INDEX
from vidcap.video.solve.skeleton import N_PARAMS, PITCH, REST_DIRS, SWING_AXES, cross, rodrigues

_J = JOINT_INDEX
_LIMB_JOINTS = {  # (proximal, middle, distal) joints and rest direction of each limb
    ("l", "arm"): ("l_shoulder", "l_elbow", "l_wrist", (-1.0, 0.0, 0.0)),
    ("r", "arm"): ("r_shoulder", "r_elbow", "r_wrist", (1.0, 0.0, 0.0)),
    ("l", "leg"): ("l_hip", "l_knee", "l_ankle", (0.0, -1.0, 0.0)),
    ("r", "leg"): ("r_hip", "r_knee", "r_ankle", (0.0, -1.0, 0.0)),
}
#: Names of the limited angles (radians) and their (low, high) bounds, in order.
LIMITS: tuple[tuple[str, float, float], ...] = tuple(
    (name, np.deg2rad(lo), np.deg2rad(hi)) for name, lo, hi in (
        ("torso_pitch", -45.0, 45.0), ("torso_roll", -45.0, 45.0), ("head", 0.0, 45.0),
        ("l_shoulder_ext", -90.0, 60.0), ("r_shoulder_ext", -90.0, 60.0),
        ("l_elbow", 0.0, FLEXION_LIMITS_DEG["l_elbow"][1]),
        ("r_elbow", 0.0, FLEXION_LIMITS_DEG["r_elbow"][1]),
        ("l_hip_flex", -30.0, 120.0), ("r_hip_flex", -30.0, 120.0),
        ("l_hip_abd", -30.0, 45.0), ("r_hip_abd", -30.0, 45.0),
        ("l_knee", *FLEXION_LIMITS_DEG["l_knee"]), ("r_knee", *FLEXION_LIMITS_DEG["r_knee"]),
        ("l_knee_side", -15.0, 15.0), ("r_knee_side", -15.0, 15.0),
    ))
LIMIT_NAMES = tuple(n for n, _, _ in LIMITS)
_LOW = np.array([lo for _, lo, _ in LIMITS])
_HIGH = np.array([hi for _, _, hi in LIMITS])


def _unit(v):
    return v / np.maximum(np.sqrt(np.sum(v * v, axis=-1, keepdims=True)), 1e-12)


def _into_swing_frame(rest, direction, x):
    """``x`` (..., 3) expressed in the frame of the minimal rotation rest -> direction."""
    v = cross(rest, direction)
    c = np.sum(rest * direction, -1, keepdims=True)
    vx = cross(v, x)
    return x - vx + cross(v, vx) / np.maximum(1.0 + c, 1e-9)


def limit_angles(joints, root, pitch_roll) -> np.ndarray:
    """The limited angles (..., 15) of :data:`LIMITS`, radians.

    Parameters
    ----------
    joints : numpy.ndarray, shape (..., 15, 3)
        World joints, metres.
    root : numpy.ndarray, shape (..., 3, 3)
        The torso's world rotation.
    pitch_roll : numpy.ndarray, shape (..., 2)
        The torso's pitch and roll, radians.
    """
    def local(a, b):  # bone a -> b in the torso's frame, unit
        return _unit(np.einsum("...ji,...j->...i", root, joints[..., _J[b], :]
                               - joints[..., _J[a], :]))

    out = [pitch_roll[..., 0], pitch_roll[..., 1]]
    head = local("neck", "head_top")
    out.append(np.arccos(np.clip(head[..., 1], -1.0, 1.0)))
    limb = {}
    for (side, kind), (a, b, c, rest) in _LIMB_JOINTS.items():
        rest = np.array(rest)
        upper = local(a, b)
        lower = _into_swing_frame(rest, upper, local(b, c))
        limb[side, kind] = upper, lower
    for side in "lr":
        out.append(np.arcsin(np.clip(limb[side, "arm"][0][..., 2], -1.0, 1.0)))
    for side in "lr":
        u, low = limb[side, "arm"]
        rest = np.array(_LIMB_JOINTS[side, "arm"][3])
        out.append(np.arctan2(np.sqrt(np.sum(cross(rest, low) ** 2, axis=-1)), low @ rest))
    for side in "lr":
        t = limb[side, "leg"][0]
        out.append(np.arctan2(-t[..., 2], -t[..., 1]))
    for side, out_sign in (("l", -1.0), ("r", 1.0)):
        t = limb[side, "leg"][0]
        out.append(np.arcsin(np.clip(out_sign * t[..., 0], -1.0, 1.0)))
    for side in "lr":
        s = limb[side, "leg"][1]
        out.append(np.arctan2(s[..., 2], -s[..., 1]))
    for side, out_sign in (("l", -1.0), ("r", 1.0)):
        s = limb[side, "leg"][1]
        out.append(np.arcsin(np.clip(out_sign * s[..., 0], -1.0, 1.0)))
    return np.stack(out, -1)


def limit_excess(angles) -> np.ndarray:
    """How far (radians, >= 0) each angle (..., 15) is outside its bounds."""
    a = np.asarray(angles, dtype=float)
    return np.maximum(a - _HIGH, 0.0) + np.maximum(_LOW - a, 0.0)



#: For each limited angle after the torso's pitch and roll: the swing joint
#: (:data:`vidcap.video.solve.skeleton.SWING_JOINTS` index) whose bone it reads.
#: Every limb angle depends on that one swing only: the shoulders and hips hang from
#: the torso, and a lower limb's angle is read in the frame of its upper limb's
#: swing, which is the lower joint's own swing (the body model's T-pose has every
#: bone along its rest direction).
_ANGLE_SWING = np.array([0, 1, 3, 2, 4, 5, 7, 5, 7, 6, 8, 6, 8])
_ARMS = np.array([(-1.0, 0.0, 0.0), (1.0, 0.0, 0.0)])
_SIDES = np.array([-1.0, 1.0])


def _angles_from_bones(v) -> np.ndarray:
    """The limited angles after the torso's, (..., 13), of the swung bone directions
    v (..., 9, 3) (each swing's rotation times its rest direction), as
    :func:`limit_angles` reads them from the joints."""
    a = v[..., _ANGLE_SWING, :]
    out = np.empty(v.shape[:-2] + (13,))
    out[..., 0] = np.arccos(np.clip(a[..., 0, 1], -1.0, 1.0))
    out[..., 1:3] = np.arcsin(np.clip(a[..., 1:3, 2], -1.0, 1.0))
    low = a[..., 3:5, :]
    out[..., 3:5] = np.arctan2(np.sqrt(np.sum(cross(_ARMS, low) ** 2, axis=-1)),
                               np.sum(low * _ARMS, -1))
    out[..., 5:7] = np.arctan2(-a[..., 5:7, 2], -a[..., 5:7, 1])
    out[..., 7:9] = np.arcsin(np.clip(_SIDES * a[..., 7:9, 0], -1.0, 1.0))
    out[..., 9:11] = np.arctan2(a[..., 9:11, 2], -a[..., 9:11, 1])
    out[..., 11:13] = np.arcsin(np.clip(_SIDES * a[..., 11:13, 0], -1.0, 1.0))
    return out


def _bones(swings) -> np.ndarray:
    """Swung bone directions (..., 9, 3) of the swing parameters (..., 9, 2)."""
    rot = rodrigues(np.einsum("...ka,kac->...kc", swings, SWING_AXES))
    return np.einsum("...ij,...j->...i", rot, REST_DIRS)


def params_limit_angles(params) -> np.ndarray:
    """:func:`limit_angles` of poses ``params`` (..., 24) read from the parameters
    directly (no forward kinematics), (..., 15) radians."""
    p = np.asarray(params, dtype=float)
    sw = p[..., PITCH + 2:].reshape(p.shape[:-1] + (9, 2))
    return np.concatenate([p[..., PITCH:PITCH + 2], _angles_from_bones(_bones(sw))], axis=-1)


def limit_jacobian(params, step: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    """Limit excesses (F, 15) of poses ``params`` (F, 24) and their Jacobian (F, 15, 24).

    Each angle depends on the torso's pitch or roll or on one swing's two columns,
    so the Jacobian takes three evaluations of the swung bones (forward differences
    of ``step`` radians on every swing's first, then second column at once).
    """
    p = np.asarray(params, dtype=float)
    F = p.shape[0]
    sw = p[:, PITCH + 2:].reshape(F, 9, 2)
    batch = np.stack([sw, sw + (step, 0.0), sw + (0.0, step)])
    ang = _angles_from_bones(_bones(batch))  # (3, F, 13)
    exc = limit_excess(np.concatenate([np.broadcast_to(p[:, PITCH:PITCH + 2], (3, F, 2)), ang],
                                      axis=-1))
    jac = np.zeros((F, len(LIMITS), N_PARAMS))
    torso = np.arange(2)
    jac[:, torso, PITCH + torso] = np.sign(np.maximum(p[:, PITCH:PITCH + 2] - _HIGH[:2], 0.0)) \
        - np.sign(np.maximum(_LOW[:2] - p[:, PITCH:PITCH + 2], 0.0))
    rows = np.arange(2, len(LIMITS))
    for c in range(2):
        jac[:, rows, PITCH + 2 + 2 * _ANGLE_SWING + c] = (exc[1 + c, :, 2:] - exc[0, :, 2:]) / step
    return exc[0], jac
