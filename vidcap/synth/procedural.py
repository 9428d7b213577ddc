"""Built-in procedural motions, generated directly on our skeleton: a walk, jumping
jacks, arm gestures and a seated figure (:func:`walk_motion`, :func:`jacks_motion`,
:func:`arms_motion`, :func:`sit_motion`)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from vidcap.body import (
    JOINT_INDEX,
    JOINT_NAMES,
    BodyModel,
)
from vidcap.kinematics import Motion
from vidcap.synth._geometry import unit

#: Built-in procedural motions (generated directly on our skeleton).
BUILTIN_MOTIONS: tuple[str, ...] = ("walk", "jacks", "arms", "sit")


def _swing(rest_dir, toward, angle) -> Rotation:
    """Rotations by ``angle`` (F,) rad turning ``rest_dir`` toward ``toward``."""
    axis = unit(np.cross(np.asarray(rest_dir, float), np.asarray(toward, float)))
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


def sit_motion(
    body: BodyModel | None = None,
    *,
    n_frames: int = 90,
    fps: float = 30.0,
    rng: np.random.Generator | None = None,
    stand_s: float = 0.0,
) -> Motion:
    """Procedural figure seated on an (unseen) chair, gesturing with both arms.

    Hips flexed ~88 degrees and knees ~90 (the shins upright, the feet on the floor),
    the trunk leaning forward ~8 degrees and swaying; the arms move in front of and
    beside the body (shoulders 12-32 degrees out, 35-70 forward, elbows 60-110).
    ``stand_s`` > 0: standing that long first, then sitting down over one second (the
    body then stays seated). ``rng`` varies rates and phases slightly. Parameters and
    return as :func:`walk_motion`.
    """
    body = body or BodyModel()
    var = (lambda s: 1.0 + s * rng.standard_normal()) if rng is not None else (lambda s: 1.0)
    phase0 = rng.uniform(0, 2 * np.pi) if rng is not None else 0.0
    t = np.arange(n_frames) / fps
    seat = np.clip((t - stand_s) / 1.0, 0.0, 1.0) if stand_s > 0 else np.ones(n_frames)
    seat = 0.5 - 0.5 * np.cos(np.pi * seat)  # 0 standing .. 1 seated
    ph = 2 * np.pi * 0.4 * var(0.05) * t + phase0
    ang = {}
    for side, sign, lag in (("l", 1.0, 0.0), ("r", -1.0, 1.7)):
        ang[f"{side}_hip"], ang[f"{side}_knee"] = _leg(
            side, np.deg2rad(88.0) * seat, np.deg2rad(90.0) * seat,
            abduct=np.deg2rad(6.0) * seat)
        wave = lambda rate, shift: 0.5 + 0.5 * np.sin(rate * ph + shift)  # noqa: E731
        ang[f"{side}_shoulder"], ang[f"{side}_elbow"] = _arm(
            side, np.deg2rad(12.0) + np.deg2rad(20.0) * wave(1.0, lag),
            np.deg2rad(35.0) + np.deg2rad(35.0) * wave(0.7, 0.5 + 2.0 * lag / 1.7),
            np.deg2rad(60.0) + np.deg2rad(50.0) * wave(1.3, sign))
    lean = np.deg2rad(8.0) * seat + np.deg2rad(4.0) * np.sin(0.5 * ph) * seat
    ang["pelvis"] = _swing(_UP, _FWD, lean)
    return _per_frame_floor(_pose_motion(body, fps, ang, np.zeros((n_frames, 3))))
