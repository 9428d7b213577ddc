"""Ground-truth clips: pose the body model with a motion, film it, keep the answers.

The renderer makes the test and benchmark inputs of the video path (seed 004): a
person made of the ten cylinders of :mod:`vidcap.body`, moved by a real motion
(BVH or ASF/AMC, retargeted onto our skeleton) or a built-in procedural one, seen
by a fixed scaled-orthographic camera over a textured background, with pixel noise
and optional slow lighting drift. Beside every clip we keep the truth: masks, 2D
and 3D joints, each segment's depth sign, the body orientation label and the camera.

Pipeline
--------
1. :func:`make_motion` -> a :class:`~vidcap.kinematics.Motion` on our skeleton
   (``'walk'``, ``'jacks'``, ``'arms'``, or a file retargeted by :func:`retarget`).
2. :func:`make_camera` -> an :class:`OrthoCamera` framing the whole clip.
3. :func:`render_frame` / :func:`iter_frames` -> BGR frames and body masks.
4. :func:`truth_arrays` -> the truth dictionary saved by :func:`synth_clip`.

Camera model (scaled orthographic, seed 004 Eq. 2.2)
----------------------------------------------------
``uv = camera[:, :3] @ X + camera[:, 3]`` with ``camera[0, :3] = s * right`` and
``camera[1, :3] = s * down`` (image x right, y down, pixels), ``s`` in pixels per
metre; ``view_dir`` is the unit direction the camera looks along (depth grows along
it), so a point is nearer the camera when ``view_dir @ X`` is smaller.

Retargeting
-----------
The source's joints are mapped onto our fifteen by :data:`JOINT_MAPS`. The torso
(root) rotation comes from the source's torso frame (up = pelvis -> neck, lateral
= left -> right hips plus left -> right shoulders), every other joint gets the
minimal rotation (no twist added) that turns our rest bone onto the source's bone
direction, expressed in its parent's frame. The root translation is the source's
pelvis scaled by our leg length over the source's leg length, shifted so that the
lowest ankle over the clip stands on the floor (y = 0).

Our torso is a 40 cm cylinder with the shoulders on its surface; the performer's is
narrower and flatter. A hand resting on the belly, or an elbow against the flank,
lands inside our torso: a pose no body can take, whose arm no camera can see and
whose depth direction means nothing. :func:`keep_arms_out_of_torso` turns such an
arm out to the cylinder's surface (the smallest rotation at the shoulder, then at
the elbow), so the truth is a pose of the model itself.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np
from scipy.spatial.transform import Rotation

from vidcap.body import (
    JOINT_INDEX,
    JOINT_NAMES,
    SEGMENT_JOINTS,
    SEGMENT_NAMES,
    BodyModel,
    orientation_from_yaw,
)
from vidcap.errors import InputFileError, MotionFileError, UsageError
from vidcap.kinematics import Motion, Skeleton
from vidcap.motion import joints_to_motion, minimal_rotation

#: Built-in procedural motions (generated directly on our skeleton).
BUILTIN_MOTIONS: tuple[str, ...] = ("walk", "jacks", "arms")

# --------------------------------------------------------------------------- joint maps
#: How each of our 15 joints is found in a source skeleton, per naming scheme.
#: Each entry maps our joint name to a source joint name, or to a tuple of names of
#: which the first present is used; ``"<name>@end"`` means the End Site of that joint
#: (or its first child when it has none). Source names are matched
#: case-insensitively, ignoring a namespace prefix such as ``mixamorig:``. The first
#: scheme whose joints are all present is used (:func:`detect_joint_map`).
#:
#: =========== ============== ============== ==========================
#: ours        CMU BVH        CMU ASF/AMC    HumanIK
#: =========== ============== ============== ==========================
#: pelvis      Hips           root           Hips
#: neck        Neck           upperneck      Neck
#: head_top    Head@end       head@end       HeadTop_End or Head@end
#: l_shoulder  LeftShoulder   lhumerus       LeftArm
#: l_elbow     LeftElbow      lradius        LeftForeArm
#: l_wrist     LeftWrist      lwrist         LeftHand
#: l_hip       LeftHip        lfemur         LeftUpLeg
#: l_knee      LeftKnee       ltibia         LeftLeg
#: l_ankle     LeftAnkle      lfoot          LeftFoot
#: (right side likewise: Right*, r*)
#: =========== ============== ============== ==========================
#:
#: CMU BVH's ``Neck`` joint and ASF's ``upperneck`` (the near end of the bone) sit at
#: shoulder height, where our neck joint is (the top of the torso cylinder). The
#: HumanIK names (MotionBuilder's) are those of Mixamo, of the widely shared CMU
#: conversion (``LHipJoint``, ``LeftUpLeg``, ``Spine1``, ``Neck1``...) and of many
#: capture suits' BVH exports; their ``Neck`` is the base of the neck too.
JOINT_MAPS = MappingProxyType(
    {
        "vidcap": MappingProxyType({n: n for n in JOINT_NAMES}),
        "cmu_bvh": MappingProxyType(
            {
                "pelvis": "Hips", "neck": "Neck", "head_top": "Head@end",
                "l_shoulder": "LeftShoulder", "l_elbow": "LeftElbow", "l_wrist": "LeftWrist",
                "r_shoulder": "RightShoulder", "r_elbow": "RightElbow",
                "r_wrist": "RightWrist",
                "l_hip": "LeftHip", "l_knee": "LeftKnee", "l_ankle": "LeftAnkle",
                "r_hip": "RightHip", "r_knee": "RightKnee", "r_ankle": "RightAnkle",
            }
        ),
        "cmu_asf": MappingProxyType(
            {
                "pelvis": "root", "neck": "upperneck", "head_top": "head@end",
                "l_shoulder": "lhumerus", "l_elbow": "lradius", "l_wrist": "lwrist",
                "r_shoulder": "rhumerus", "r_elbow": "rradius", "r_wrist": "rwrist",
                "l_hip": "lfemur", "l_knee": "ltibia", "l_ankle": "lfoot",
                "r_hip": "rfemur", "r_knee": "rtibia", "r_ankle": "rfoot",
            }
        ),
        "humanik": MappingProxyType(
            {
                "pelvis": "Hips", "neck": "Neck", "head_top": ("HeadTop_End", "Head@end"),
                "l_shoulder": "LeftArm", "l_elbow": "LeftForeArm", "l_wrist": "LeftHand",
                "r_shoulder": "RightArm", "r_elbow": "RightForeArm", "r_wrist": "RightHand",
                "l_hip": "LeftUpLeg", "l_knee": "LeftLeg", "l_ankle": "LeftFoot",
                "r_hip": "RightUpLeg", "r_knee": "RightLeg", "r_ankle": "RightFoot",
            }
        ),
    }
)


def _norm_name(name: str) -> str:
    return name.rsplit(":", 1)[-1].strip().lower()


def _alternatives(spec) -> tuple[str, ...]:
    """A :data:`JOINT_MAPS` value as its tuple of alternative source names."""
    return (spec,) if isinstance(spec, str) else tuple(spec)


def _missing_names(skeleton: Skeleton, table) -> list[str]:
    have = {_norm_name(n) for n in skeleton.joint_names}
    return [_alternatives(s)[0] for s in table.values()
            if not any(_norm_name(a.split("@")[0]) in have for a in _alternatives(s))]


def detect_joint_map(skeleton: Skeleton, *, source: str | os.PathLike | None = None) -> str:
    """Name of the :data:`JOINT_MAPS` scheme that fits ``skeleton``'s joint names.

    Parameters
    ----------
    skeleton : Skeleton
        The source motion's skeleton.
    source : str or path-like, optional
        The motion file, named in the error message.

    Raises
    ------
    MotionFileError
        If no scheme fits; the message lists what the closest scheme misses.
    """
    best, best_missing = None, None
    for key, table in JOINT_MAPS.items():
        missing = _missing_names(skeleton, table)
        if not missing:
            return key
        if best_missing is None or len(missing) < len(best_missing):
            best, best_missing = key, missing
    raise MotionFileError(
        f"cannot map this skeleton onto the body model: closest naming scheme {best!r} "
        f"lacks joints {', '.join(m.split('@')[0] for m in best_missing)}"
        f" (known schemes: {', '.join(JOINT_MAPS)})",
        source,
    )


def source_joint_positions(
    motion: Motion, table, *, source: str | os.PathLike | None = None
) -> np.ndarray:
    """World positions of our 15 joints found in a source motion.

    Parameters
    ----------
    motion : Motion
        The source motion (any skeleton), metres.
    table : mapping of str to str or tuple of str
        One of :data:`JOINT_MAPS` (ours -> source names).

    Returns
    -------
    numpy.ndarray, shape (F, 15, 3)
        Metres, in :data:`vidcap.body.JOINT_NAMES` order.
    """
    sk = motion.skeleton
    index = {_norm_name(n): i for i, n in enumerate(sk.joint_names)}
    world_r, world_p = motion.world_transforms()
    out = np.empty((motion.n_frames, len(JOINT_NAMES), 3))
    for j, ours in enumerate(JOINT_NAMES):
        names = _alternatives(table[ours])
        spec = next((a for a in names if _norm_name(a.split("@")[0]) in index), names[0])
        name, _, end = spec.partition("@")
        k = index.get(_norm_name(name))
        if k is None:
            raise MotionFileError(f"no joint {name!r} to map onto {ours!r}", source)
        if not end:
            out[:, j] = world_p[:, k]
            continue
        site = sk.end_sites.get(sk.joint_names[k])
        if site is not None and np.linalg.norm(site) > 0:
            out[:, j] = world_p[:, k] + world_r[:, k] @ site
        else:
            kids = sk.children(k)
            if not kids:
                raise MotionFileError(f"joint {name!r} has no End Site or child", source)
            out[:, j] = world_p[:, kids[0]]
    return out


# --------------------------------------------------------------------------- rotations
def _unit(v: np.ndarray, axis: int = -1) -> np.ndarray:
    n = np.linalg.norm(v, axis=axis, keepdims=True)
    return v / np.where(n > 1e-12, n, 1.0)


def _floor_motion(motion: Motion) -> Motion:
    """Shift ``motion`` vertically so its lowest ankle over the clip is at y = 0."""
    pos = motion.positions()
    ank = pos[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 1]
    root = motion.root_positions.copy()
    root[:, 1] -= ank.min()
    return Motion(motion.skeleton, root, motion.rotations, motion.fps)


def _up_fix(pts: np.ndarray) -> np.ndarray:
    """Rotate ``pts`` so the source's up axis (the dominant axis of pelvis -> neck) is +Y."""
    up = np.mean(pts[:, JOINT_INDEX["neck"]] - pts[:, JOINT_INDEX["pelvis"]], axis=0)
    k = int(np.argmax(np.abs(up)))
    if k == 1 and up[1] > 0:
        return pts
    axis = np.zeros(3)
    axis[k] = np.sign(up[k])
    rot = Rotation.from_quat(minimal_rotation(axis, np.array([0.0, 1.0, 0.0])))
    return pts @ rot.as_matrix().T


def retarget(
    motion: Motion,
    body: BodyModel | None = None,
    *,
    source: str | os.PathLike | None = None,
    solid_torso: bool = True,
) -> Motion:
    """Retarget a motion on any mappable skeleton onto our body by bone directions.

    Parameters
    ----------
    motion : Motion
        Source motion (metres; Y up, or Z up which is detected and turned to Y up).
    body : BodyModel, optional
        Target body (default: 1.75 m).
    source : str or path-like, optional
        The motion's file, named in errors.
    solid_torso : bool
        Turn arms that would pass through our (wider) torso out to its surface
        (:func:`keep_arms_out_of_torso`); False keeps every bone direction exactly.

    Returns
    -------
    Motion
        F frames on ``body.skeleton()``, same fps; root translation scaled by our
        leg length / the source's leg length; lowest ankle of the clip at y = 0.

    Raises
    ------
    MotionFileError
        If the skeleton's joints cannot be mapped (see :data:`JOINT_MAPS`).
    """
    body = body or BodyModel()
    table = JOINT_MAPS[detect_joint_map(motion.skeleton, source=source)]
    pts = _up_fix(source_joint_positions(motion, table, source=source))
    J = JOINT_INDEX
    legs = []
    for s in "lr":
        legs.append(
            np.linalg.norm(pts[:, J[f"{s}_knee"]] - pts[:, J[f"{s}_hip"]], axis=-1)
            + np.linalg.norm(pts[:, J[f"{s}_ankle"]] - pts[:, J[f"{s}_knee"]], axis=-1)
        )
    src_leg = float(np.median(np.concatenate(legs)))
    if not src_leg > 0:
        raise MotionFileError("the source's legs have zero length", source)
    out = joints_to_motion(pts, motion.fps, body=body)
    if solid_torso:
        out = joints_to_motion(keep_arms_out_of_torso(out.positions(), body), motion.fps,
                               body=body)
    scaled = Motion(out.skeleton, out.root_positions * (body.pelvis_height / src_leg),
                    out.rotations, out.fps)
    return _floor_motion(scaled)


def keep_arms_out_of_torso(joints3d, body: BodyModel | None = None, *,
                           iterations: int = 8) -> np.ndarray:
    """Turn elbows and wrists that lie inside the torso cylinder out to its surface.

    A point is inside when it is nearer the pelvis-neck axis than the torso's radius,
    between the pelvis and the neck. The upper arm turns about the shoulder toward
    the nearest surface point (the forearm moving with it), then the forearm about
    the elbow; bone lengths are kept, so a few passes settle a point that the first
    turn left just short of the surface.

    Parameters
    ----------
    joints3d : array_like, shape (F, 15, 3)
        Joints of ``body``'s skeleton, metres (bone lengths the model's).
    body : BodyModel, optional
    iterations : int
        Passes of the turn per joint.

    Returns
    -------
    numpy.ndarray, shape (F, 15, 3)
        A copy with the arms moved where needed; every other joint as given.
    """
    body = body or BodyModel()
    j = np.array(joints3d, dtype=float)
    J = JOINT_INDEX
    pel, neck = j[:, J["pelvis"]], j[:, J["neck"]]
    axis = neck - pel
    length = np.linalg.norm(axis, axis=-1)
    axis = axis / np.maximum(length, 1e-12)[:, None]
    r = body.radius("torso")

    def radial(x):
        d = x - pel
        h = np.sum(d * axis, -1)
        q = d - h[:, None] * axis
        return h, q, np.linalg.norm(q, axis=-1)

    for side in "lr":
        sh, el, wr = J[f"{side}_shoulder"], J[f"{side}_elbow"], J[f"{side}_wrist"]
        _, q_sh, rho_sh = radial(j[:, sh])
        outward = q_sh / np.maximum(rho_sh, 1e-12)[:, None]  # the arm's own side
        for pivot, point in ((sh, el), (el, wr)):
            bone = np.linalg.norm(j[:, point] - j[:, pivot], axis=-1)
            for _ in range(iterations):
                h, q, rho = radial(j[:, point])
                inside = (h > 0.0) & (h < length) & (rho < r)
                if not inside.any():
                    break
                away = np.where((rho > 1e-9)[:, None], q / np.maximum(rho, 1e-12)[:, None],
                                outward)
                # aimed a hair outside: the turned bone, shorter than the way to the
                # aim, falls a little short of it
                surface = pel + h[:, None] * axis + (r * (1.0 + 1e-3)) * away
                turned = j[:, pivot] + bone[:, None] * _unit(surface - j[:, pivot])
                moved = np.where(inside[:, None], turned - j[:, point], 0.0)
                j[:, point] += moved
                if point == el:  # the forearm keeps its direction
                    j[:, wr] += moved
    return j


# --------------------------------------------------------------------------- procedural
def _swing(rest_dir, toward, angle) -> Rotation:
    """Rotations by ``angle`` (F,) rad turning ``rest_dir`` toward ``toward``."""
    axis = _unit(np.cross(np.asarray(rest_dir, float), np.asarray(toward, float)))
    return Rotation.from_rotvec(np.asarray(angle, float)[:, None] * axis[None, :])


_DOWN, _UP = np.array([0.0, -1.0, 0.0]), np.array([0.0, 1.0, 0.0])
_FWD, _BACK = np.array([0.0, 0.0, -1.0]), np.array([0.0, 0.0, 1.0])
_LEFT, _RIGHT = np.array([-1.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])


def _pose_motion(body: BodyModel, fps: float, angles: dict, root: np.ndarray) -> Motion:
    """Build a Motion from per-joint rotation lists; floor it per clip."""
    F = root.shape[0]
    rot = np.zeros((F, len(JOINT_NAMES), 4))
    rot[..., 3] = 1.0
    for name, r in angles.items():
        rot[:, JOINT_INDEX[name]] = r.as_quat()
    return Motion(body.skeleton(), root, rot, fps)


def _arm(side: str, abduct, flex, elbow) -> tuple[Rotation, Rotation]:
    """Shoulder and elbow rotations: arm lowered from the T-pose by ``abduct`` (0 = down,
    pi/2 = horizontal, pi = overhead), swung forward by ``flex``, elbow bent forward."""
    out = _LEFT if side == "l" else _RIGHT
    down = _swing(out, _DOWN, np.pi / 2 - np.asarray(abduct, float))  # T-pose -> abducted
    fwd = _swing(_DOWN, _FWD, flex)
    shoulder = fwd * down
    # the forearm's rest direction in the upper arm's frame is `out`; bend it forward,
    # which in that frame is still -Z (the abduction turns about Z).
    el = _swing(out, _FWD, elbow)
    return shoulder, el


def _leg(side: str, flex, knee, abduct=None) -> tuple[Rotation, Rotation]:
    out = _LEFT if side == "l" else _RIGHT
    hip = _swing(_DOWN, _FWD, flex)
    if abduct is not None:
        hip = _swing(_DOWN, out, abduct) * hip
    return hip, _swing(_DOWN, _BACK, knee)


def _per_frame_floor(motion: Motion) -> Motion:
    """Shift each frame vertically so its lowest ankle touches the floor (y = 0)."""
    pos = motion.positions()
    low = pos[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 1].min(axis=1)
    root = motion.root_positions.copy()
    root[:, 1] -= low
    return Motion(motion.skeleton, root, motion.rotations, motion.fps)


def walk_motion(
    body: BodyModel | None = None,
    *,
    n_frames: int = 90,
    fps: float = 30.0,
    rng: np.random.Generator | None = None,
) -> Motion:
    """A procedural walk straight ahead (-Z) on our skeleton.

    Parameters
    ----------
    body : BodyModel, optional
        Target body (default 1.75 m).
    n_frames : int
        Number of frames.
    fps : float
        Frame rate, Hz.
    rng : numpy.random.Generator, optional
        Small variations of cadence (about 0.9 Hz strides), amplitudes and phase;
        ``None`` gives the nominal walk.

    Returns
    -------
    Motion
        Hips swing +-(~20) degrees, knees bend up to ~50 degrees in early swing,
        arms swing opposite to the legs with slightly bent elbows. The root advances
        so the stance foot stays planted (about 1.3 m/s) and each frame's lowest
        ankle is on the floor.
    """
    body = body or BodyModel()
    var = (lambda s: 1.0 + s * rng.standard_normal()) if rng is not None else (lambda s: 1.0)
    phase0 = rng.uniform(0, 2 * np.pi) if rng is not None else 0.0
    cadence = 0.9 * var(0.05)  # strides per second
    hip_amp = np.deg2rad(20.0) * var(0.08)
    knee_amp = np.deg2rad(45.0) * var(0.08)
    arm_amp = np.deg2rad(20.0) * var(0.1)
    t = np.arange(n_frames) / fps
    ph = 2 * np.pi * cadence * t + phase0
    ang = {}
    for side, off in (("l", 0.0), ("r", np.pi)):
        p = ph + off
        hip = hip_amp * np.sin(p) + np.deg2rad(3.0)
        # swing is p in (-pi/2, pi/2) (the thigh moving forward): the knee starts to
        # flex just before toe-off, peaks in early swing and is straight again before
        # heel strike; a little flexion in stance
        knee = np.deg2rad(6.0) + knee_amp * np.clip(np.cos(p + 0.4), 0, None) ** 1.5
        ang[f"{side}_hip"], ang[f"{side}_knee"] = _leg(side, hip, knee)
        arm_flex = -arm_amp * np.sin(p)  # opposite to the same-side leg
        elbow = np.deg2rad(15.0) + 0.5 * arm_amp * (1 - np.sin(p)) * 0.5
        abd = np.full(n_frames, np.deg2rad(8.0))
        ang[f"{side}_shoulder"], ang[f"{side}_elbow"] = _arm(side, abd, arm_flex, elbow)
    # slight forward lean and counter-rotating shoulders
    lean = _swing(_UP, _FWD, np.full(n_frames, np.deg2rad(4.0)))
    twist = Rotation.from_rotvec(np.outer(np.deg2rad(4.0) * np.sin(ph), _UP))
    ang["pelvis"] = twist * lean
    # Advance the body so the stance foot stays planted: the root
    # moves by minus that foot's displacement relative to the root between frames.
    still = _per_frame_floor(_pose_motion(body, fps, ang, np.zeros((n_frames, 3))))
    rel = still.positions()
    ankles = rel[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]]  # (F, 2, 3)
    # the stance leg is the one whose thigh swings backward: the left one when cos(ph) < 0
    stance = np.where(np.cos(ph) < 0, 0, 1)[:-1]
    step = ankles[1:, :, :][np.arange(n_frames - 1), stance] - ankles[:-1][
        np.arange(n_frames - 1), stance
    ]
    root = still.root_positions.copy()
    travel = np.zeros((n_frames, 3))
    travel[1:, [0, 2]] = -np.cumsum(step[:, [0, 2]], axis=0)
    travel -= travel.mean(axis=0)
    root += travel
    return Motion(still.skeleton, root, still.rotations, fps)


def jacks_motion(
    body: BodyModel | None = None,
    *,
    n_frames: int = 90,
    fps: float = 30.0,
    rng: np.random.Generator | None = None,
) -> Motion:
    """Procedural jumping jacks in place on our skeleton.

    Arms go from the sides (abduction ~10 degrees) to overhead (~165 degrees) while
    the legs spread (~14 degrees each) and the body hops a few centimetres; about
    0.8 cycles per second. ``rng`` varies rate, amplitudes and phase slightly.
    Parameters and return as :func:`walk_motion`.
    """
    body = body or BodyModel()
    var = (lambda s: 1.0 + s * rng.standard_normal()) if rng is not None else (lambda s: 1.0)
    phase0 = rng.uniform(0, 2 * np.pi) if rng is not None else 0.0
    rate = 0.8 * var(0.05)
    t = np.arange(n_frames) / fps
    ph = 2 * np.pi * rate * t + phase0
    s = 0.5 * (1 - np.cos(ph))  # 0 closed .. 1 open
    ang = {}
    arm_top = np.deg2rad(165.0) * min(var(0.03), 1.05)
    leg_out = np.deg2rad(14.0) * var(0.1)
    for side in "lr":
        abd = np.deg2rad(10.0) + (arm_top - np.deg2rad(10.0)) * s
        ang[f"{side}_shoulder"], ang[f"{side}_elbow"] = _arm(
            side, abd, np.zeros(n_frames), np.full(n_frames, np.deg2rad(8.0))
        )
        ang[f"{side}_hip"], ang[f"{side}_knee"] = _leg(
            side, np.full(n_frames, np.deg2rad(2.0)), np.deg2rad(4.0) + np.deg2rad(10.0) * s,
            abduct=leg_out * s,
        )
    root = np.zeros((n_frames, 3))
    motion = _per_frame_floor(_pose_motion(body, fps, ang, root))
    hop = 0.06 * var(0.1) * np.abs(np.sin(ph))  # airborne between open and closed
    root = motion.root_positions.copy()
    root[:, 1] += hop
    return Motion(motion.skeleton, root, motion.rotations, fps)


def arms_motion(
    body: BodyModel | None = None,
    *,
    n_frames: int = 90,
    fps: float = 30.0,
    rng: np.random.Generator | None = None,
) -> Motion:
    """Procedural standing figure raising and bending its arms.

    The left arm raises forward (flexion 0 -> ~150 degrees) while its elbow bends up to
    ~100 degrees; the right arm raises sideways (abduction 10 -> ~120 degrees) bending
    out of phase; a slight bend of the knees and a small torso sway. ``rng`` varies
    rates, amplitudes and phases. Parameters and return as :func:`walk_motion`.
    """
    body = body or BodyModel()
    var = (lambda s: 1.0 + s * rng.standard_normal()) if rng is not None else (lambda s: 1.0)
    ph0 = rng.uniform(0, 2 * np.pi, 3) if rng is not None else np.zeros(3)
    t = np.arange(n_frames) / fps
    a = 0.5 * (1 - np.cos(2 * np.pi * 0.35 * var(0.05) * t + ph0[0]))
    b = 0.5 * (1 - np.cos(2 * np.pi * 0.5 * var(0.05) * t + ph0[1]))
    c = 0.5 * (1 - np.cos(2 * np.pi * 0.3 * var(0.05) * t + ph0[2]))
    ang = {}
    ang["l_shoulder"], ang["l_elbow"] = _arm(
        "l", np.full(n_frames, np.deg2rad(8.0)), np.deg2rad(150.0) * var(0.05) * a,
        np.deg2rad(5.0) + np.deg2rad(100.0) * var(0.05) * b,
    )
    ang["r_shoulder"], ang["r_elbow"] = _arm(
        "r", np.deg2rad(10.0) + np.deg2rad(110.0) * var(0.05) * c, np.deg2rad(10.0) * b,
        np.deg2rad(5.0) + np.deg2rad(90.0) * (1 - b),
    )
    for side in "lr":
        ang[f"{side}_hip"], ang[f"{side}_knee"] = _leg(
            side, np.deg2rad(5.0) + np.deg2rad(10.0) * c, np.deg2rad(3.0) + np.deg2rad(20.0) * c
        )
    ang["pelvis"] = _swing(_UP, _RIGHT, np.deg2rad(4.0) * np.sin(2 * np.pi * 0.25 * t))
    return _per_frame_floor(_pose_motion(body, fps, ang, np.zeros((n_frames, 3))))


_PROCEDURAL = {"walk": walk_motion, "jacks": jacks_motion, "arms": arms_motion}


def parse_range(text: str | None) -> tuple[int | None, int | None]:
    """Parse ``"START:END"`` (either may be empty; END exclusive) into integers."""
    if text is None:
        return None, None
    head, sep, tail = str(text).partition(":")
    try:
        if not sep:
            raise ValueError
        a = int(head) if head.strip() else None
        b = int(tail) if tail.strip() else None
    except ValueError:
        raise UsageError(f"--range must be START:END in frames, got {text!r}") from None
    return a, b


def make_motion(
    name_or_path: str | os.PathLike,
    *,
    body: BodyModel | None = None,
    amc: str | os.PathLike | None = None,
    frame_range: tuple[int | None, int | None] | None = None,
    fps: float | None = None,
    n_frames: int = 90,
    rng: np.random.Generator | None = None,
) -> Motion:
    """A motion on our skeleton: a built-in one or a retargeted motion file.

    Parameters
    ----------
    name_or_path : str or path-like
        ``'walk'``, ``'jacks'``, ``'arms'`` (:data:`BUILTIN_MOTIONS`), a ``.bvh`` file
        or an ``.asf`` file (with ``amc``).
    body : BodyModel, optional
        Target body (default 1.75 m).
    amc : str or path-like, optional
        The AMC motion for an ASF skeleton.
    frame_range : (start, stop), optional
        Source frames to keep (stop exclusive; ``None`` = open end), before resampling.
    fps : float, optional
        Output frame rate: resamples a file's motion; the rate of a built-in one
        (default 30).
    n_frames : int
        Frames of a built-in motion (before ``frame_range``).
    rng : numpy.random.Generator, optional
        Variations of a built-in motion.

    Raises
    ------
    VidcapError
        Unknown motion, missing/malformed file, unmappable skeleton, empty range.
    """
    body = body or BodyModel()
    name = str(name_or_path)
    if name in _PROCEDURAL:
        if n_frames < 1:
            raise UsageError(f"need at least one frame, got {n_frames}")
        motion = _PROCEDURAL[name](body, n_frames=n_frames, fps=fps or 30.0, rng=rng)
        return _slice(motion, frame_range, name)
    path = Path(name)
    suffix = path.suffix.lower()
    if not path.exists():
        raise InputFileError(
            f"no such motion file (built-in motions: {', '.join(BUILTIN_MOTIONS)})", path
        )
    if suffix == ".bvh":
        from vidcap.bvh import read_bvh

        src = read_bvh(path)
    elif suffix == ".asf":
        if amc is None:
            raise UsageError("an ASF skeleton needs its motion: pass --amc M.amc", path)
        from vidcap.asf import read_asf_amc

        src = read_asf_amc(path, amc)
    elif suffix == ".amc":
        raise UsageError("pass the .asf skeleton as the motion and this file as --amc", path)
    else:
        raise UsageError("motion must be a .bvh or .asf file or a built-in name", path)
    src = _slice(src, frame_range, path)
    if fps is not None and abs(fps - src.fps) > 1e-6 and src.n_frames > 1:
        src = src.resampled(fps)
    return retarget(src, body, source=path)


def _slice(motion: Motion, frame_range, source) -> Motion:
    if frame_range is None or frame_range == (None, None):
        return motion
    start, stop = frame_range
    F = motion.n_frames
    a = 0 if start is None else (start + F if start < 0 else start)
    b = F if stop is None else (stop + F if stop < 0 else stop)
    a, b = max(a, 0), min(b, F)
    if b <= a:
        raise UsageError(
            f"frame range {start}:{stop} selects no frames of the {F} in the motion", source
        )
    return motion.frames(a, b)


# --------------------------------------------------------------------------- camera
@dataclass(frozen=True)
class OrthoCamera:
    """A scaled orthographic camera.

    Attributes
    ----------
    matrix : numpy.ndarray, shape (2, 4)
        ``uv = matrix[:, :3] @ X + matrix[:, 3]``, pixels (x right, y down).
    view_dir : numpy.ndarray, shape (3,)
        Unit direction the camera looks along; depth = ``view_dir @ X`` (metres).
    size : (int, int)
        Image width and height, pixels.
    """

    matrix: np.ndarray
    view_dir: np.ndarray
    size: tuple[int, int]

    @property
    def pixels_per_metre(self) -> float:
        """Scale s of the projection, pixels per metre."""
        return float(np.linalg.norm(self.matrix[0, :3]))

    def project(self, X: np.ndarray) -> np.ndarray:
        """Project points (..., 3) metres to pixels (..., 2)."""
        X = np.asarray(X, dtype=float)
        return X @ self.matrix[:, :3].T + self.matrix[:, 3]

    def depth(self, X: np.ndarray) -> np.ndarray:
        """Depth (...,) metres along the view direction (larger = farther)."""
        return np.asarray(X, dtype=float) @ self.view_dir


def project(camera: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Project points (..., 3) with a (2, 4) camera matrix to pixels (..., 2)."""
    camera = np.asarray(camera, dtype=float)
    return np.asarray(X, dtype=float) @ camera[:, :3].T + camera[:, 3]


def body_forward(joints3d: np.ndarray) -> np.ndarray:
    """Horizontal unit facing direction of the body per frame, (F, 3), from joints (F, 15, 3)."""
    J = JOINT_INDEX
    lat = (joints3d[:, J["r_hip"]] - joints3d[:, J["l_hip"]]) + (
        joints3d[:, J["r_shoulder"]] - joints3d[:, J["l_shoulder"]]
    )
    fwd = np.cross(np.array([0.0, 1.0, 0.0]), lat)  # up x right = forward (-Z at rest)
    fwd[:, 1] = 0.0
    return _unit(fwd)


def mean_heading(joints3d: np.ndarray) -> np.ndarray:
    """The clip's mean horizontal facing direction (3,), a circular mean of :func:`body_forward`."""
    fwd = body_forward(joints3d)
    m = fwd.sum(axis=0)
    if np.linalg.norm(m) < 1e-6 * len(fwd):
        m = fwd[0]
    return _unit(m)


def body_yaw(joints3d: np.ndarray, view_dir: np.ndarray) -> np.ndarray:
    """Per-frame yaw (F,) radians of the body relative to the camera.

    0 = facing the camera, +pi/2 = facing image-right, pi = facing away (the
    convention of :func:`vidcap.body.orientation_from_yaw`).
    """
    v = np.asarray(view_dir, float).copy()
    v[1] = 0.0
    v = _unit(v)
    right = _unit(np.cross(v, [0.0, 1.0, 0.0]))
    f = body_forward(joints3d)
    return np.arctan2(f @ right, -(f @ v))


def make_camera(
    joints3d: np.ndarray,
    *,
    size: tuple[int, int] = (640, 480),
    yaw_deg: float = 90.0,
    elevation_deg: float = 0.0,
    pixels_per_metre: float | None = None,
    height: float = 1.75,
    fill: float = 0.75,
    margin: float = 0.04,
    floor_frac: float | None = None,
    radius: float = 0.2,
) -> OrthoCamera:
    """A fixed scaled-orthographic camera framing the whole clip.

    Parameters
    ----------
    joints3d : numpy.ndarray, shape (F, 15, 3)
        The body's joints over the clip, metres, Y up.
    size : (int, int)
        Image (width, height), pixels.
    yaw_deg : float
        Yaw of the body relative to the camera, degrees, measured from the clip's
        mean heading: 0 = facing the camera, 90 = side view facing image-right,
        180 = back view, -90 = facing image-left.
    elevation_deg : float
        Downward tilt of the camera, degrees (0 = horizontal view).
    pixels_per_metre : float, optional
        Scale; default: the figure's ``height`` fills ``fill`` of the image height,
        reduced if needed so the whole clip (joints plus ``radius``) stays within
        ``margin`` of the borders.
    height : float
        Standing height of the figure, metres (for the default scale).
    floor_frac : float, optional
        Where the floor under the clip's mean position appears, as a fraction of
        the image height from the top; default: centre the clip's extent vertically.
    radius : float
        Body half-width allowance around the joints for framing, metres.

    Returns
    -------
    OrthoCamera
    """
    W, H = int(size[0]), int(size[1])
    if W < 8 or H < 8:
        raise UsageError(f"image size must be at least 8x8 pixels, got {W}x{H}")
    joints3d = np.asarray(joints3d, dtype=float)
    f = mean_heading(joints3d)
    psi = np.deg2rad(yaw_deg)
    # In the body frame (forward = -Z) the camera looks along (-sin psi, 0, cos psi);
    # rotate that frame about Y so -Z goes to the mean heading f.
    theta = np.arctan2(-f[0], -f[2])  # rotation about Y taking -Z to f
    heading = Rotation.from_rotvec([0.0, theta, 0.0])
    v_h = heading.apply([-np.sin(psi), 0.0, np.cos(psi)])
    el = np.deg2rad(elevation_deg)
    view = _unit(np.cos(el) * v_h - np.sin(el) * np.array([0.0, 1.0, 0.0]))
    right = _unit(np.cross(v_h, [0.0, 1.0, 0.0]))
    down = np.cross(view, right)
    A = np.stack([right, down])  # (2, 3), unit scale
    uv = joints3d.reshape(-1, 3) @ A.T
    lo, hi = uv.min(0) - radius, uv.max(0) + radius
    span = hi - lo
    if pixels_per_metre is None:
        s = fill * H / height
        s = min(s, (1 - 2 * margin) * W / span[0], (1 - 2 * margin) * H / span[1])
    else:
        s = float(pixels_per_metre)
        if not s > 0:
            raise UsageError(f"pixels per metre must be positive, got {pixels_per_metre}")
    tx = W / 2 - s * 0.5 * (lo[0] + hi[0])
    if floor_frac is None:
        ty = H / 2 - s * 0.5 * (lo[1] + hi[1])
    else:
        centre = joints3d[:, JOINT_INDEX["pelvis"]].mean(0)
        centre[1] = 0.0
        ty = floor_frac * H - s * (down @ centre)
    matrix = np.concatenate([s * A, [[tx], [ty]]], axis=1)
    return OrthoCamera(matrix, view, (W, H))


# --------------------------------------------------------------------------- background
def make_background(
    size: tuple[int, int], rng: np.random.Generator, *, horizon: float = 0.8
) -> np.ndarray:
    """A procedurally textured room: a panelled, mottled wall over a planked floor.

    Parameters
    ----------
    size : (int, int)
        (width, height) pixels.
    rng : numpy.random.Generator
        Colours and texture.
    horizon : float
        Where the wall meets the floor, as a fraction of the height from the top.

    Returns
    -------
    numpy.ndarray, shape (H, W, 3) uint8
        BGR; muted greys/beiges/browns, far from the clothing colours.
    """
    import cv2

    W, H = int(size[0]), int(size[1])
    y = np.arange(H)[:, None]
    x = np.arange(W)[None, :]

    def smooth_noise(cells, amp, chroma=0.25):
        # mostly brightness (same in every channel), a little colour
        n = rng.standard_normal((cells[1], cells[0], 1)) + chroma * rng.standard_normal(
            (cells[1], cells[0], 3)
        )
        return amp * cv2.resize(n.astype(np.float32), (W, H), interpolation=cv2.INTER_CUBIC)

    wall = np.array([150, 165, 170], np.float32) + rng.uniform(-12, 12, 3).astype(np.float32)
    floor = np.array([105, 120, 135], np.float32) + rng.uniform(-10, 10, 3).astype(np.float32)
    img = np.where((y < horizon * H)[..., None], wall, floor).astype(np.float32)
    img = img + smooth_noise((6, 5), 8.0) + smooth_noise((W // 8 + 2, H // 8 + 2), 4.0)
    img += rng.normal(0.0, 3.0, (H, W, 1)).astype(np.float32)
    # wall panels: darker vertical seams every ~W/5 px; a skirting board at the horizon
    pitch = max(8, int(W / rng.uniform(4.0, 6.0)))
    seam = ((x + int(rng.integers(pitch))) % pitch) < max(1, W // 320)
    wall_rows = y < horizon * H
    img[np.broadcast_to(seam & wall_rows, (H, W))] -= 18.0
    skirt = (y >= horizon * H - max(2, H // 60)) & (y < horizon * H)
    img[np.broadcast_to(skirt, (H, W))] -= 25.0
    # floor planks: lines converging slightly, alternating tone
    band = ((y - horizon * H) // max(2, H // 24)) % 2 == 1
    img[np.broadcast_to(band & ~wall_rows, (H, W))] -= 6.0
    return np.clip(img, 0, 255).astype(np.uint8)


def load_background(path: str | os.PathLike, size: tuple[int, int]) -> np.ndarray:
    """Read an image file and resize it to ``size`` (width, height); BGR uint8 (H, W, 3)."""
    import cv2

    path = Path(path)
    if not path.is_file():
        raise InputFileError("background image not found", path)
    img = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if img is None:
        raise InputFileError("cannot read the background image (not an image file?)", path)
    return cv2.resize(img, (int(size[0]), int(size[1])), interpolation=cv2.INTER_AREA)


# --------------------------------------------------------------------------- drawing
#: Clothing colours (BGR): a red shirt, dark blue trousers, skin.
SHIRT = (40, 45, 190)
TROUSERS = (95, 45, 25)
SKIN = (120, 160, 215)
_SEGMENT_COLOUR = {
    "torso": SHIRT, "head": SKIN,
    "l_upper_arm": SHIRT, "r_upper_arm": SHIRT, "l_lower_arm": SKIN, "r_lower_arm": SKIN,
    "l_upper_leg": TROUSERS, "r_upper_leg": TROUSERS,
    "l_lower_leg": TROUSERS, "r_lower_leg": TROUSERS,
}
#: Which ends of each cylinder are rounded by a sphere of the segment's radius (the
#: joints inside a limb: shoulders, elbows, hips, knees). The other ends are the flat
#: discs of a cylinder (their projections are ellipses): torso, head, hands, feet end
#: at the joint as the seed's cylinder model does.
_ROUND_ENDS = MappingProxyType(
    {
        "torso": (False, False), "head": (False, False),
        "l_upper_arm": (True, True), "r_upper_arm": (True, True),
        "l_lower_arm": (True, False), "r_lower_arm": (True, False),
        "l_upper_leg": (True, True), "r_upper_leg": (True, True),
        "l_lower_leg": (True, False), "r_lower_leg": (True, False),
    }
)
#: Direction toward the light in camera coordinates (right, down, view): upper left,
#: in front.
_LIGHT = _unit(np.array([-0.45, -0.6, -0.65]))


def _draw_segment(img, zbuf, a, b, za, zb, r, axis_v, colour, round_ends):
    """Z-buffer one shaded cylinder, a -> b in image pixels, into ``img`` (float32).

    ``za``, ``zb`` are the end depths and ``r`` the radius, all in pixels; ``axis_v``
    is the cosine between the 3D axis and the view direction (foreshortening of the
    flat end discs); ``round_ends`` says which ends are spheres instead of discs.
    The body is exact for an orthographic view (a band of half-width r); the depth
    and normals are those of a cylinder lying in the image plane, close enough to
    order overlapping segments and to shade them.
    """
    H, W = zbuf.shape
    lo = np.floor(np.minimum(a, b) - r - 1).astype(int)
    hi = np.ceil(np.maximum(a, b) + r + 1).astype(int)
    x0, y0 = max(lo[0], 0), max(lo[1], 0)
    x1, y1 = min(hi[0], W), min(hi[1], H)
    if x1 <= x0 or y1 <= y0:
        return
    px = np.arange(x0, x1, dtype=np.float32)[None, :] - a[0]
    py = np.arange(y0, y1, dtype=np.float32)[:, None] - a[1]
    ab = (b - a).astype(np.float32)
    L = float(np.hypot(ab[0], ab[1]))
    ux, uy = (float(ab[0]) / L, float(ab[1]) / L) if L > 1e-6 else (1.0, 0.0)
    r2 = r * r
    par = px * ux + py * uy  # along the axis from a, px
    perp = px * uy - py * ux  # signed, across the axis
    perp2 = perp * perp
    h_cyl = np.sqrt(np.clip(1.0 - perp2 / r2, 0.0, 1.0))
    # light on a cylinder: normal across the axis in the image, bulging toward us
    lam_cyl = (perp / r) * (uy * _LIGHT[0] - ux * _LIGHT[1]) - h_cyl * _LIGHT[2]
    inf = np.float32(np.inf)
    inside = (par >= 0) & (par <= L) & (perp2 < r2)
    t = np.clip(par / L, 0.0, 1.0) if L > 1e-6 else np.zeros_like(par)
    depth = np.where(inside, za + t * (zb - za) - h_cyl * r, inf)
    lam = lam_cyl
    cos_a = max(abs(float(axis_v)), 1e-3)
    for end_par, z_end, rounded in ((0.0, za, round_ends[0]), (L, zb, round_ends[1])):
        dpar = par - end_par
        if rounded:  # sphere
            d2 = dpar * dpar + perp2
            cap = d2 < r2
            h = np.sqrt(np.clip(1.0 - d2 / r2, 0.0, 1.0))
            dz = z_end - h * r
            nx = (dpar * ux + perp * uy) / r
            ny = (dpar * uy - perp * ux) / r
            lam_cap = nx * _LIGHT[0] + ny * _LIGHT[1] - h * _LIGHT[2]
        else:  # flat disc seen obliquely: an ellipse, shaded as a face toward us
            cap = (dpar / (r * cos_a)) ** 2 + perp2 / r2 < 1.0
            dz = np.full_like(par, z_end - 0.5 * r * cos_a)
            lam_cap = np.full_like(par, 0.55)
        closer = cap & (dz < depth)
        depth = np.where(closer, dz, depth)
        lam = np.where(closer, lam_cap, lam)
    sub_z = zbuf[y0:y1, x0:x1]
    upd = depth < sub_z
    if not upd.any():
        return
    shade = 0.45 + 0.6 * np.clip(lam, 0.0, 1.0)
    sub_img = img[y0:y1, x0:x1]
    sub_img[upd] = shade[upd][:, None] * np.asarray(colour, np.float32)
    sub_z[upd] = depth[upd]


def render_body(
    joints3d: np.ndarray,
    camera: OrthoCamera,
    body: BodyModel,
    background: np.ndarray,
    *,
    colours: dict | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Draw the posed cylinder body over a background, nearest surface on top.

    Parameters
    ----------
    joints3d : numpy.ndarray, shape (15, 3)
        One frame's joints, metres.
    camera : OrthoCamera
    body : BodyModel
        Radii of the segments.
    background : numpy.ndarray, shape (H, W, 3) uint8
    colours : dict, optional
        BGR colour per segment name (default: shirt, trousers, skin).

    Returns
    -------
    image : numpy.ndarray, shape (H, W, 3) float32
        BGR, 0..255, before noise and lighting.
    mask : numpy.ndarray, shape (H, W) bool
        Pixels covered by the body.
    """
    colours = colours or _SEGMENT_COLOUR
    H, W = background.shape[:2]
    img = background.astype(np.float32)
    zbuf = np.full((H, W), np.inf, np.float32)
    uv = camera.project(joints3d).astype(np.float32)
    z = camera.depth(joints3d)
    s = camera.pixels_per_metre
    for k, name in enumerate(SEGMENT_NAMES):
        p, d = SEGMENT_JOINTS[k]
        bone = joints3d[d] - joints3d[p]
        n = np.linalg.norm(bone)
        axis_v = (bone @ camera.view_dir) / n if n > 1e-9 else 1.0
        # depths in pixels so they compare with the radius in pixels
        _draw_segment(
            img, zbuf, uv[p], uv[d], np.float32(z[p] * s), np.float32(z[d] * s),
            np.float32(body.radius(name) * s), axis_v, colours[name], _ROUND_ENDS[name],
        )
    return img, np.isfinite(zbuf)


def lighting_gains(
    n_frames: int, fps: float, amount: float, rng: np.random.Generator
) -> np.ndarray:
    """Slow global brightness/colour gains (F, 3) around 1 (``amount`` = relative swing).

    One smooth cycle over max(4 s, the clip) with a random phase, plus a smaller
    per-channel tint drift.
    """
    t = np.arange(n_frames) / fps
    period = max(4.0, n_frames / fps)
    ph = rng.uniform(0, 2 * np.pi, 4)
    base = np.sin(2 * np.pi * t / period + ph[0])
    tint = 0.3 * np.sin(2 * np.pi * t[:, None] / period + ph[1:][None, :])
    return 1.0 + amount * (base[:, None] + tint)


def finish_frame(
    image: np.ndarray, rng: np.random.Generator, *, noise: float = 0.0, gain=None
) -> np.ndarray:
    """Apply lighting gain (3,) and Gaussian noise (sigma, grey levels); return uint8."""
    out = image if gain is None else image * np.asarray(gain, np.float32)
    if noise > 0:
        out = out + np.float32(noise) * rng.standard_normal(out.shape, dtype=np.float32)
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


# --------------------------------------------------------------------------- clips
@dataclass(frozen=True)
class Clip:
    """Everything needed to render a clip, and its geometric truth.

    Attributes
    ----------
    motion : Motion
        The motion on our skeleton.
    body : BodyModel
    camera : OrthoCamera
    joints3d : numpy.ndarray, shape (F, 15, 3)
        Metres, Y up.
    background : numpy.ndarray, shape (H, W, 3) uint8
    gains : numpy.ndarray, shape (F, 3)
        Lighting gain per frame and channel.
    noise : float
        Gaussian pixel noise sigma, grey levels.
    """

    motion: Motion
    body: BodyModel
    camera: OrthoCamera
    joints3d: np.ndarray
    background: np.ndarray
    gains: np.ndarray
    noise: float

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return self.joints3d.shape[0]


def prepare_clip(
    motion: Motion,
    *,
    body: BodyModel | None = None,
    size: tuple[int, int] = (640, 480),
    yaw_deg: float = 90.0,
    elevation_deg: float = 0.0,
    pixels_per_metre: float | None = None,
    floor_frac: float | None = None,
    background: np.ndarray | str | os.PathLike | None = None,
    noise: float = 2.0,
    lighting_drift: float = 0.0,
    rng: np.random.Generator | None = None,
) -> Clip:
    """Set up camera, background and lighting for ``motion`` (on our skeleton).

    ``body`` gives the cylinder radii (default: a body as tall as the motion's
    skeleton). See :func:`make_camera` for the camera options. ``background`` is an
    image array (resized if needed), an image file, or ``None`` for
    :func:`make_background`. ``rng`` (default ``default_rng(0)``) drives the
    background texture and the lighting phase. ``noise`` is the Gaussian pixel noise
    sigma (grey levels); ``lighting_drift`` the relative amplitude of a slow global
    brightness/colour change (:func:`lighting_gains`).
    """
    import cv2

    rng = rng if rng is not None else np.random.default_rng(0)
    if tuple(motion.skeleton.joint_names) != JOINT_NAMES:
        raise UsageError("render needs a motion on our skeleton (use retarget())")
    if body is None:  # the body whose skeleton the motion uses (its standing height)
        off = np.linalg.norm(motion.skeleton.offsets, axis=1)
        J = JOINT_INDEX
        body = BodyModel(height=float(off[J["neck"]] + off[J["head_top"]] + off[J["l_knee"]]
                                      + off[J["l_ankle"]]))
    if noise < 0 or lighting_drift < 0:
        raise UsageError("noise and lighting drift must not be negative")
    joints3d = motion.positions()
    camera = make_camera(
        joints3d, size=size, yaw_deg=yaw_deg, elevation_deg=elevation_deg,
        pixels_per_metre=pixels_per_metre, height=body.height, floor_frac=floor_frac,
        radius=body.radius("torso"),
    )
    W, H = camera.size
    if background is None:
        ank = joints3d[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]].reshape(-1, 3)
        floor_v = float(np.median(camera.project(ank)[:, 1]))
        horizon = float(np.clip(floor_v / H - 0.08, 0.3, 0.95))
        bg = make_background((W, H), rng, horizon=horizon)
    elif isinstance(background, np.ndarray):
        bg = background
        if bg.ndim != 3 or bg.shape[2] != 3:
            raise UsageError(f"background must be (H, W, 3) BGR, got {bg.shape}")
        if bg.shape[:2] != (H, W):
            bg = cv2.resize(bg, (W, H), interpolation=cv2.INTER_AREA)
        bg = bg.astype(np.uint8)
    else:
        bg = load_background(background, (W, H))
    gains = lighting_gains(motion.n_frames, motion.fps, lighting_drift, rng)
    return Clip(motion, body, camera, joints3d, bg, gains.astype(np.float32), float(noise))


def render_frame(clip: Clip, i: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Frame ``i`` of ``clip``: BGR uint8 (H, W, 3) with noise, and its mask (H, W) bool."""
    img, mask = render_body(clip.joints3d[i], clip.camera, clip.body, clip.background)
    return finish_frame(img, rng, noise=clip.noise, gain=clip.gains[i]), mask


def iter_frames(
    clip: Clip, rng: np.random.Generator, *, show_progress: bool | None = None
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Yield ``(frame, mask)`` for every frame of ``clip`` (see :func:`render_frame`)."""
    from vidcap.fileio import progress

    for i in progress(range(clip.n_frames), desc="rendering", unit="frame",
                      enabled=show_progress):
        yield render_frame(clip, i, rng)


def depth_signs(joints3d: np.ndarray, view_dir: np.ndarray) -> np.ndarray:
    """+1 where a segment's distal end is nearer the camera than its proximal end, else -1.

    Parameters
    ----------
    joints3d : numpy.ndarray, shape (F, 15, 3)
    view_dir : numpy.ndarray, shape (3,)

    Returns
    -------
    numpy.ndarray, shape (F, 10) int8
    """
    dz = (joints3d[:, SEGMENT_JOINTS[:, 1]] - joints3d[:, SEGMENT_JOINTS[:, 0]]) @ view_dir
    return np.where(dz < 0, 1, -1).astype(np.int8)


def truth_arrays(clip: Clip, masks: np.ndarray) -> dict[str, np.ndarray]:
    """The truth of ``clip`` as the arrays saved by :func:`synth_clip`.

    Keys: ``joint_names`` (15,), ``masks`` (F, H, W) bool, ``joints2d`` (F, 15, 2) px,
    ``joints3d`` (F, 15, 3) m, ``depth_signs`` (F, 10) int8, ``segment_names`` (10,),
    ``orientation`` (F,) str, ``yaw_deg`` (F,), ``camera`` (2, 4), ``view_dir`` (3,),
    ``fps`` ().
    """
    cam = clip.camera
    yaw = body_yaw(clip.joints3d, cam.view_dir)
    return {
        "joint_names": np.array(JOINT_NAMES),
        "masks": np.asarray(masks, dtype=bool),
        "joints2d": cam.project(clip.joints3d),
        "joints3d": clip.joints3d,
        "depth_signs": depth_signs(clip.joints3d, cam.view_dir),
        "segment_names": np.array(SEGMENT_NAMES),
        "orientation": np.asarray(orientation_from_yaw(yaw)).astype(str).reshape(-1),
        "yaw_deg": np.rad2deg(yaw),
        "camera": cam.matrix,
        "view_dir": cam.view_dir,
        "fps": np.float64(clip.motion.fps),
    }


def render_clip(
    motion: Motion,
    *,
    rng: np.random.Generator | None = None,
    show_progress: bool | None = False,
    **options,
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Render ``motion`` (on our skeleton) in memory.

    Parameters
    ----------
    motion : Motion
        On ``BodyModel(...).skeleton()`` (see :func:`make_motion`).
    rng : numpy.random.Generator, optional
        Background, lighting and noise (default ``default_rng(0)``).
    **options
        :func:`prepare_clip` options (``body``, ``size``, ``yaw_deg``,
        ``elevation_deg``, ``pixels_per_metre``, ``floor_frac``, ``background``,
        ``noise``, ``lighting_drift``).

    Returns
    -------
    frames : numpy.ndarray, shape (F, H, W, 3) uint8
        BGR.
    truth : dict
        :func:`truth_arrays`.
    """
    rng = rng if rng is not None else np.random.default_rng(0)
    clip = prepare_clip(motion, rng=rng, **options)
    W, H = clip.camera.size
    frames = np.empty((clip.n_frames, H, W, 3), np.uint8)
    masks = np.empty((clip.n_frames, H, W), bool)
    for i, (frame, mask) in enumerate(iter_frames(clip, rng, show_progress=show_progress)):
        frames[i], masks[i] = frame, mask
    return frames, truth_arrays(clip, masks)


def synth_clip(
    out_video: str | os.PathLike,
    truth_path: str | os.PathLike,
    motion: Motion | str | os.PathLike = "walk",
    *,
    bvh_path: str | os.PathLike | None = None,
    rng: np.random.Generator | None = None,
    show_progress: bool | None = None,
    crf: int = 18,
    **options,
) -> dict[str, np.ndarray]:
    """Render a clip to a video file and save its truth (both atomically).

    Parameters
    ----------
    out_video : str or path-like
        H.264 video to write (via :class:`vidcap.video.VideoWriter`).
    truth_path : str or path-like
        ``.npz`` truth (:func:`truth_arrays` keys), via
        :func:`vidcap.fileio.savez_atomic`.
    motion : Motion or str or path-like
        A motion on our skeleton, or anything :func:`make_motion` takes (then built
        with ``body`` and ``rng``).
    bvh_path : str or path-like, optional
        Also write the motion (on our skeleton) as BVH.
    rng : numpy.random.Generator, optional
        Default ``default_rng(0)``.
    **options
        :func:`prepare_clip` options.

    Returns
    -------
    dict
        The saved truth arrays.
    """
    from vidcap.fileio import savez_atomic
    from vidcap.video import VideoWriter

    rng = rng if rng is not None else np.random.default_rng(0)
    if not isinstance(motion, Motion):
        motion = make_motion(motion, body=options.get("body"), rng=rng)
    clip = prepare_clip(motion, rng=rng, **options)
    W, H = clip.camera.size
    if W % 2 or H % 2:
        raise UsageError(f"H.264 needs an even image size, got {W}x{H}", out_video)
    masks = np.empty((clip.n_frames, H, W), bool)
    with VideoWriter(out_video, motion.fps, crf=crf) as writer:
        for i, (frame, mask) in enumerate(iter_frames(clip, rng, show_progress=show_progress)):
            writer.write(frame)
            masks[i] = mask
    truth = truth_arrays(clip, masks)
    savez_atomic(truth_path, **truth)
    if bvh_path is not None:
        from vidcap.bvh import write_bvh

        write_bvh(bvh_path, motion)
    return truth
