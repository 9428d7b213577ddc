"""The clip solve as the 3D stage's lift (``vidcap convert --lift solve``).

:func:`vidcap.video.lifting.lift_pose` proposes the orientation and the depth signs and
applies the user's events; with ``method="solve"`` it hands them here: the proposed
signs become the solve's soft prior, the user's depth events its hard signs, the
user's orientation events a tight yaw prior (:func:`vidcap.video.solve.solve_clip`). The
solve's confidence (the clip cost of the other sign) then ranks the checks as the
proposals' margin did (:meth:`vidcap.video.proposals.SignProposal.checks`).
"""

from __future__ import annotations

import numpy as np

from vidcap.body import BodyModel
from vidcap.video.proposals import SignProposal
from vidcap.video.solve.clip import (
    FITTED_CONTACT_FLOOR,
    FITTED_HEADING_WEIGHT,
    FITTED_NOISE_FLOOR,
    FITTED_SIGN_WEIGHT,
    ClipSolve,
    solve_clip,
)
from vidcap.video.solve.residuals import segment_zeta

#: Solve cost (half a sum of squared residuals, each one 2D joint's misfit in units of
#: 1 % of the height) per unit of the proposals' margin: the checks' ``tau`` of 0.2
#: then stands for a cost of 2, one joint two sigmas off.
COST_PER_MARGIN = 10.0
#: Yaw prior's spread (radians) where the orientation was proposed, and where the
#: user set it.
YAW_SIGMA_PROPOSED = 0.5
YAW_SIGMA_USER = 0.15
#: Weight of a 2D joint the user placed, relative to a fitted one's (1): near hard.
USER_JOINT_WEIGHT = 30.0
#: Misfit (in 2D sigmas, 1 % of the height each) at which a fitted joint's weight is
#: divided by sqrt(2) after the first solve (:func:`vidcap.video.solve.clip.robust_weights`,
#: one Cauchy re-weighting): the 2D fit's errors are outliers more than noise (a limb
#: misplaced for a stretch, a joint on the other leg), and a joint far from where the
#: rest of the clip puts it then drags the body less. The user's placed joints keep
#: their weight. Chosen on the tuning renders (``benchmarks/solve_fitted.py``: synth walk
#: at yaw 60 and 120, jacks 30, arms 120): none / 1 / 1.5 / 2 / 3 / 4 gave a mean
#: PA-MPJPE of 115.1 / 112.8 / 112.3 / 113.0 / 112.8 / 113.5 mm; a second re-weighting
#: after the sign sweeps 111.5 mm for one more solve (not kept).
ROBUST_FITTED = 1.5
#: Whether the 3D stage lets the solve choose which 2D arm and leg is the body's left one
#: (:mod:`vidcap.video.solve.labels`; never where the user set the sides, placed a joint
#: or a depth sign; ``LiftResult.joints2d`` then carries its names). Off: on the tuning
#: renders it made the body consistent with its hips but, where the proposed orientation
#: has front and back the wrong way round, consistently mirrored (106.8 -> 119.9 mm;
#: benchmarks/HISTORY.md, "The front/back cue and the fitted-2D settings"). Re-measured
#: with the front/back cue on: tuning renders 86.9 -> 81.5 mm, but the samples
#: 118.8 -> 123.6 and the held-out renders 127.4 -> 136.7, and 154-162 frames per
#: CPU-second (< 200); on top of the names' consistency from the 2D alone
#: (:func:`vidcap.video.lifting.consistent_names`) the tuning renders lose (67.1 -> 70.7 mm).
LABELS = False
#: The lifts ``lift_pose`` offers.
METHODS = ("solve", "segment")


def check_method(method: str) -> None:
    """Raise ValueError unless ``method`` is one of :data:`METHODS`."""
    if method not in METHODS:
        raise ValueError(f"unknown lift method {method!r}; expected one of {list(METHODS)}")


def solve_lift(joints2d, *, fps: float, body: BodyModel, scale, segment_scale, yaw,
               proposal: SignProposal, user_signs, user_orientation, principal_point=None,
               user_joints=None, labels: bool | None = None,
               user_sides_set=None, jobs: int = 1) -> tuple[ClipSolve, SignProposal]:
    """Solve the clip with the 3D stage's proposals and the user's events.

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, 2)
        Body-side named, gap-filled, the user's joints in place, pixels.
    fps : float
    body : BodyModel
    scale, segment_scale, principal_point :
        As :func:`vidcap.video.lift.lift`.
    yaw : numpy.ndarray, shape (F,)
        Radians, from the orientation (the user's where given).
    proposal : SignProposal
        The proposed signs (with the user's fixed): the soft prior.
    user_signs : numpy.ndarray, shape (F, 10)
        The user's depth signs, 0 where none: hard.
    user_orientation : numpy.ndarray of str, shape (F,)
        ``""`` where the user set none.
    user_joints : numpy.ndarray, shape (F, 15, 2), optional
        The user's joints, NaN where none: weighted :data:`USER_JOINT_WEIGHT` times a
        fitted joint.
    labels : bool, optional
        Let the solve choose which 2D arm and leg is the left one
        (:mod:`vidcap.video.solve.labels`), never where the user spoke
        (:func:`held_labels`); default :data:`LABELS`.
    user_sides_set : numpy.ndarray of bool, shape (F, 2), optional
        (Frame, pair: arms, legs) a sides event of the user covers.
    jobs : int
        Processes for the solve (:func:`vidcap.video.solve.clip.solve_clip`).

    Returns
    -------
    solve : ClipSolve
    signs : SignProposal
        The solved signs, the solve's confidence in the proposals' margin units (the
        torso, which the solve does not reflect, keeps the proposals' margin) and the
        solved pose's ``|dZ| / length``; its ``checks()`` rank what to ask about.
    """
    sigma = np.where(np.asarray(user_orientation) != "", YAW_SIGMA_USER, YAW_SIGMA_PROPOSED)
    confidence = None
    if user_joints is not None:
        placed = np.isfinite(np.asarray(user_joints, float)).all(axis=-1)
        confidence = np.where(placed, USER_JOINT_WEIGHT, 1.0)
    sol = solve_clip(joints2d, scale=scale, fps=fps, body=body, yaw=yaw,
                     prior_signs=proposal.signs, hard_signs=user_signs, yaw_sigma=sigma,
                     confidence=confidence, noise_floor=FITTED_NOISE_FLOOR,
                     contact_floor=FITTED_CONTACT_FLOOR,
                     robust=ROBUST_FITTED, sign_weight=FITTED_SIGN_WEIGHT,
                     heading_weight=FITTED_HEADING_WEIGHT,
                     segment_scale=segment_scale, principal_point=principal_point,
                     labels=LABELS if labels is None else labels,
                     held_labels=held_labels(user_signs, user_joints, user_sides_set),
                     jobs=jobs)
    margin = np.where(np.isfinite(sol.confidence), sol.confidence / COST_PER_MARGIN,
                      proposal.margin)
    margin = np.where(np.asarray(user_signs) != 0, np.inf, margin)
    zeta = np.abs(segment_zeta(sol.joints3d, body.segment_lengths()))
    return sol, SignProposal(signs=sol.signs, margin=margin, zeta=np.clip(zeta, 0.0, 1.0))


def held_labels(user_signs, user_joints=None, user_sides_set=None) -> np.ndarray:
    """(F, 2) bool: the (frame, pair: arms, legs) whose 2D names the user fixed, which
    the solve's label choice must keep: a sides event covers it, or the user placed one
    of the pair's joints or set a depth sign on one of its segments there."""
    from vidcap.body import LIMB_PAIR_JOINTS
    from vidcap.video.annotations import PAIRS

    signs = np.asarray(user_signs)
    out = np.zeros((len(signs), len(PAIRS)), bool)
    for col, pair in enumerate(PAIRS):
        left, right = LIMB_PAIR_JOINTS[pair]
        segs = [2, 3, 4, 5] if pair == "arms" else [6, 7, 8, 9]  # body.SEGMENT_NAMES
        out[:, col] = (signs[:, segs] != 0).any(axis=1)
        if user_joints is not None:
            out[:, col] |= np.isfinite(np.asarray(user_joints)[:, left + right]).any(axis=(1, 2))
    if user_sides_set is not None:
        out |= np.asarray(user_sides_set, bool)
    return out


def solved_motion(params, fps: float, *, body: BodyModel, keys=None, smooth_sigma: float = 0.0,
                  ground: str = "image"):
    """The :class:`vidcap.video.motion.MotionResult` of the solve's poses (F, 24): its rotations
    as they are (bone lengths constant by construction), the root lifted so the feet
    stand on the floor (:func:`vidcap.video.motion.place_on_floor`), then keyed and smoothed
    as :func:`vidcap.video.motion.build_motion` does."""
    from vidcap.video.motion import finish_motion, place_on_floor
    from vidcap.video.solve.skeleton import forward_kinematics, params_to_motion

    p = np.array(params, dtype=float)
    joints, _, _ = forward_kinematics(p, body.rest_offsets())
    p[:, 1] += place_on_floor(joints, ground=ground)[:, 0, 1] - joints[:, 0, 1]
    return finish_motion(params_to_motion(p, body, fps), keys=keys, smooth_sigma=smooth_sigma)
