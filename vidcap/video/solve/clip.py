"""One kinematic solve over the clip: 2D joints -> joint rotations (issue 33).

The skeleton of the body model with fixed bone lengths (:mod:`vidcap.video.solve.skeleton`)
is fitted to the 2D joints of every frame at once (:mod:`vidcap.video.solve.residuals`:
projection, joint limits, temporal smoothness, foot contact, depth signs), starting
from the seed's per-segment lift (:func:`vidcap.video.lift.lift`) with the proposed signs;
then every limb's reflection through the image plane is chosen over the clip
(:mod:`vidcap.video.solve.signs`) and the clip solved again from there; runs of frames
left in a wrong basin are re-started from their neighbours
(:mod:`vidcap.video.solve.repair`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vidcap.body import BodyModel
from vidcap.video.lift import lift
from vidcap.video.solve.contact import foot_contacts
from vidcap.video.solve.gauss_newton import levenberg_marquardt
from vidcap.video.solve.labels import choose_labels, relabel
from vidcap.video.solve.repair import repair_outliers
from vidcap.video.solve.residuals import Problem, solved_signs
from vidcap.video.solve.signs import sweep_signs
from vidcap.video.solve.skeleton import forward_kinematics, params_from_joints
from vidcap.video.solve.split import SPLIT_MIN_FRAMES, solve_split

#: Default 2D uncertainty of a joint, as a fraction of body height.
SIGMA_2D = 0.01
#: Levenberg-Marquardt iterations of the first solve, before the first sign sweep.
FIRST_ITER = 8


@dataclass(frozen=True)
class ClipSolve:
    """Result of :func:`solve_clip`.

    Attributes
    ----------
    params : (F, 24) the poses (:mod:`vidcap.video.solve.skeleton`).
    joints3d : (F, 15, 3) their joints, metres, camera-aligned world.
    signs : (F, 10) int8, the solved depth signs (+1 distal joint nearer the camera).
    confidence : (F, 10) clip cost of the other sign (:mod:`vidcap.video.solve.signs`).
    contact : (F, 2) bool, planted ankles used (all False when contact was off), as
        the solve named the legs.
    cost : float, iterations : int.
    swapped : (F, 2) bool, the arms (column 0) and legs (1) whose 2D names the solve
        exchanged (:mod:`vidcap.video.solve.labels`).
    """

    params: np.ndarray
    joints3d: np.ndarray
    signs: np.ndarray
    confidence: np.ndarray
    contact: np.ndarray
    cost: float
    iterations: int
    swapped: np.ndarray | None = None


def image_targets(joints2d, scale, segment_scale=None, principal_point=None) -> np.ndarray:
    """The joints' world (X, Y) that the image shows, (F, 15, 2) metres.

    The pelvis is placed at ``scale`` (pixels per metre, one or (F,)) about
    ``principal_point`` (default the pelvis' median image position); the other joints
    about the pelvis at ``segment_scale`` (default ``scale``), as
    :func:`vidcap.video.lift.lift` reads them. Y is up.
    """
    j = np.asarray(joints2d, dtype=float)
    F = j.shape[0]
    s_root = np.broadcast_to(np.asarray(scale, dtype=float), (F,))[:, None]
    s_seg = s_root if segment_scale is None else np.broadcast_to(
        np.asarray(segment_scale, dtype=float), (F,))[:, None]
    c = (np.median(j[:, 0], axis=0) if principal_point is None
         else np.asarray(principal_point, dtype=float))
    pel = (j[:, 0] - c) / s_root
    rel = (j - j[:, :1]) / s_seg[..., None]
    out = pel[:, None] + rel
    out[..., 1] *= -1.0
    return out


#: Weight of the in-plane prior (``Problem.plane_weight``) at 1 % of the height of 2D
#: noise; it grows as the square root of the measured noise
#: (:func:`vidcap.video.solve.noise.noise_fraction`) and is 0 on noise-free joints.
#: A segment's 2D length changes as sqrt(1 - zeta^2): near the image plane a depth of
#: zeta = 0.3 shortens it by 5 %, less than 2D noise of 1-2 % of the height does, so the
#: image cannot tell zeta in [-0.3, 0.3] apart and the sign prior (a guess there) and
#: the noise decide where the segment goes. The prior takes the middle of what the
#: image allows; out of the plane the 2D length pins zeta and the prior moves it by
#: < 0.01. Chosen on the synth walk, arms and jacks at 1-4 % noise (3 of 2, 3, 4; linear
#: in the noise instead of its root was too strong at 4 %); the mocap clips validated it.
PLANE_WEIGHT = 3.0
#: Weight (1 / m) of a planted ankle's frame-to-frame motion on noise-free 2D; it grows
#: with the measured noise, (1 + noise / 1 % of the height) times (chosen on the synth
#: walk, arms and jacks: 100 -> 300 at 2 % noise takes sliding 7.6 -> 3.1 mm/frame at equal
#: PA-MPJPE; 1000 costs 4 mm of it).
CONTACT_WEIGHT = 100.0
#: Weight of the pose prior (``Problem.prior_weight``, :mod:`vidcap.video.solve.prior`) at
#: 1 % of the height of 2D noise, growing as (noise / 1 %) ** PRIOR_POWER, the noise
#: taken as at least PRIOR_NOISE_FLOOR. Like the in-plane prior it speaks where the
#: image leaves a pose open, which the noise measures. Chosen on the synth walk, arms
#: and jacks at yaw 90 and 45 with 1-4 % noise (three noise draws at 2 %): weights 0.3,
#: 0.5, 1 and 3, powers 0.5 and 1, with and without the prior's Cauchy tail.
PRIOR_WEIGHT = 0.5
PRIOR_POWER = 0.5
#: The noise (fraction of the height) the pose prior assumes at least for joints from
#: vidcap's 2D fit (``noise_floor`` of :func:`make_problem`, passed by the 3D stage and the
#: annotate app's re-solves): the fit's errors are correlated over frames (a swapped leg,
#: a misplaced arm for a stretch), so the second-difference measure reads them low. Chosen
#: on renders of the synth walk (yaw 60, 120), jacks (30) and arms (120) through the 2D
#: fit: floor 0, 1, 2, 4, 6, 8, 12 % gave PA-MPJPE 129, 126, 124, 118, 116, 116, 117 mm.
#: ``solve_clip`` itself uses no floor (true 2D plus noise: the measure is right there).
FITTED_NOISE_FLOOR = 0.06
#: The noise (fraction of the height) the contact weight assumes at least for joints from
#: vidcap's 2D fit (``contact_floor`` of :func:`make_problem`, passed where
#: ``FITTED_NOISE_FLOOR`` is): the fit's ankles wander for runs of frames, which the
#: second-difference measure reads as 0-0.3 % of the height, and at the weight that
#: reading gives (100 / m) a planted foot followed them (the side-view sample walk slid
#: 5.1 mm/frame, the arms sample 6.9). Chosen on the tuning renders and the samples
#: (benchmarks/solve_fitted.py's set, front/back and limb-order cues on): floor 0 / 1 / 2 /
#: 3 % gave a mean PA-MPJPE of 69.6 / 69.4 / 69.3 / 70.2 mm and foot sliding of
#: walk_side 5.1 / 3.9 / 2.8 / 2.2, walk_three_quarter 2.7 / 2.2 / 1.8 / 1.4 mm/frame
#: (arms 72.9 -> 74.1 mm at 2 %: its true ankles move 2.8 mm/frame, the rendered body
#: is floored per frame).
FITTED_CONTACT_FLOOR = 0.02
#: Weight of the proposed depth signs (``Problem.sign_weight``, default 5) for joints
#: from vidcap's 2D fit (passed by the 3D stage and the annotate app's re-solves): the
#: proposals are the per-segment lift's reading of the same fitted joints, wrong where
#: they are, and at the default they held the solve there. Chosen on the tuning
#: renders (benchmarks/solve_fitted.py, with the robust re-weighting): weights 0 / 1 / 2 /
#: 5 / 12 gave a mean PA-MPJPE of 106.7 / 106.8 / 108.8 / 112.6 / 117.0 mm; 1 keeps the
#: proposals as a tie-breaker. The user's depth events stay hard (``hard_weight``).
FITTED_SIGN_WEIGHT = 1.0
#: Weight (1 / m) of the pelvis' frame-to-frame motion across the torso's prior facing
#: in a clip with planted feet (``Problem.heading_weight``,
#: :func:`vidcap.video.solve.residuals.heading_rows`) for joints from vidcap's 2D fit
#: (passed where ``FITTED_SIGN_WEIGHT`` is; ``solve_clip`` itself uses none). In a walk
#: seen at three quarters the solve kept both thighs toward the camera where one swings
#: back (the image cannot tell a thigh's two reflections apart, and the joint limits and
#: the pose prior lean forward); walking the way the body faces gives the pelvis' motion
#: in depth, and a planted ankle held still then moves the stance thigh from front to
#: back. Chosen on the tuning renders and walk_three_quarter
#: (``benchmarks/solve_fitted.py --front --legs``): 0 / 200 / 400 / 800 gave a mean
#: PA-MPJPE of 68.4 / 67.4 / 67.1 / 67.1 mm (walk_three_quarter 103 / 105 / 103 / 104);
#: 200, not 400: at 400 the re-solve after the sign sweep takes 8 iterations, not 3
#: (the stage solve of ``benchmarks/solve_speed.py``'s walk, 300 frames, load ~8:
#: 192-219 frames per CPU-second without, 195-225 at 200, 172-178 at 400, under the
#: 200 of issue 33).
#: Not on true 2D plus noise: there the contact weight is lower (100 / m at no noise) and
#: a prior yaw a few degrees off drags the planted feet (foot sliding on two validation
#: clips 3.7-3.9 -> 6.8-7.8 mm/frame at no noise), though the mean PA-MPJPE at 2 % fell
#: 46 -> 43 mm (benchmarks/HISTORY.md, "The legs' depth signs on fitted 2D").
FITTED_HEADING_WEIGHT = 200.0


def make_problem(joints2d, *, scale, fps: float, body: BodyModel | None = None, yaw,
                 prior_signs=None, hard_signs=None, confidence=None, yaw_sigma=0.5,
                 segment_scale=None, principal_point=None, contact="auto",
                 noise_floor: float = 0.0, contact_floor: float = 0.0,
                 **weights) -> Problem:
    """The :class:`Problem` of a clip of 2D joints (F, 15, 2), body-side named.

    ``yaw`` (F,) radians and ``yaw_sigma`` (one or (F,), radians) the torso's yaw
    prior; ``prior_signs``/``hard_signs`` (F, 10) in {-1, 0, 1}; ``confidence`` (F,
    15) each 2D joint's weight (default 1); ``contact`` 'auto' (:func:`foot_contacts`), 'off', or
    an (F, 2) bool array; ``weights`` override :class:`Problem`'s weights (the in-plane
    prior's, the contact's and the pose prior's defaults grow with the 2D joints' measured
    noise: :data:`PLANE_WEIGHT`, :data:`CONTACT_WEIGHT`, :data:`PRIOR_WEIGHT`, the last
    with the noise taken as at least ``noise_floor``: :data:`FITTED_NOISE_FLOOR`; the
    contact's with it taken as at least ``contact_floor``: :data:`FITTED_CONTACT_FLOOR`).
    """
    body = body or BodyModel()
    j = np.asarray(joints2d, dtype=float)
    F = j.shape[0]
    conf = np.ones((F, 15)) if confidence is None else np.asarray(confidence, float)
    zeros = np.zeros((F, 10), np.int8)
    geometry = scale if segment_scale is None else segment_scale
    if isinstance(contact, str):
        if contact not in ("auto", "off"):
            raise ValueError(f"contact must be 'auto', 'off' or an (F, 2) array, got {contact!r}")
        contact = (foot_contacts(j, geometry, fps) if contact == "auto"
                   else np.zeros((F, 2), bool))
    if not {"plane_weight", "contact_weight", "prior_weight"} <= set(weights):
        from vidcap.video.solve.noise import noise_fraction

        noise = noise_fraction(j, geometry, body)
        weights.setdefault("plane_weight", PLANE_WEIGHT * float(np.sqrt(noise / 0.01)))
        weights.setdefault("prior_weight", PRIOR_WEIGHT * float(
            (max(noise, noise_floor) / 0.01) ** PRIOR_POWER))
        # a planted foot holds against the noisy 2D's pull, which grows with the noise
        weights.setdefault("contact_weight",
                           CONTACT_WEIGHT * (1.0 + max(noise, contact_floor) / 0.01))
    return Problem(
        offsets=body.rest_offsets(), lengths=body.segment_lengths(),
        target=image_targets(j, scale, segment_scale, principal_point),
        weight=conf / (SIGMA_2D * body.height),
        prior_signs=zeros if prior_signs is None else np.sign(prior_signs).astype(np.int8),
        hard_signs=zeros if hard_signs is None else np.sign(hard_signs).astype(np.int8),
        yaw=np.broadcast_to(np.asarray(yaw, float), (F,)).copy(),
        yaw_weight=1.0 / np.broadcast_to(np.asarray(yaw_sigma, float), (F,)),
        contact=np.asarray(contact, bool), **weights)


def warm_start(problem: Problem, joints2d, *, scale, body: BodyModel, segment_scale=None,
               principal_point=None) -> np.ndarray:
    """Parameters (F, 24) of the seed's per-segment lift with the prior signs (the hard
    ones where given), the root on the image's pelvis."""
    signs = np.where(problem.hard_signs != 0, problem.hard_signs, problem.prior_signs)
    out = lift(joints2d, np.where(signs == 0, 1, signs), problem.yaw, body=body, scale=scale,
               principal_point=principal_point, segment_scale=segment_scale)
    p = params_from_joints(out.joints3d, problem.yaw)
    p[:, :2] = problem.target[:, 0]
    p[:, 2] = 0.0
    return p


def solve_clip(joints2d, *, scale, fps: float, body: BodyModel | None = None, yaw,
               prior_signs=None, hard_signs=None, confidence=None, yaw_sigma=0.5,
               segment_scale=None, principal_point=None, contact="auto", sweeps: int = 2,
               max_iter: int = 30, robust: float | None = None, noise_floor: float = 0.0,
               contact_floor: float = 0.0, labels: bool = False, held_labels=None,
               jobs: int = 1, **weights) -> ClipSolve:
    """Fit the skeleton to a clip's 2D joints (see the module docstring).

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Pixels, body-side named (:func:`vidcap.video.lift.assign_sides`), no gaps.
    scale : float or array_like, shape (F,)
        Pixels per metre of the root (:func:`vidcap.video.lift.estimate_scales`).
    fps : float
    body : BodyModel, optional
        The subject's bone lengths (default 1.75 m, Table 3.1).
    yaw : array_like, shape (F,)
        The torso's yaw prior, radians (:func:`vidcap.video.lift.yaw_from_orientation`).
    prior_signs, hard_signs : array_like, shape (F, 10), optional
        Proposed depth signs (soft) and the user's (hard), 0 where none.
    confidence : array_like, shape (F, 15), optional
        Weight of each 2D joint (1: a fitted joint; less where it is doubtful, more
        where the user placed it).
    yaw_sigma : float or array_like, shape (F,)
        The yaw prior's spread, radians.
    segment_scale, principal_point :
        As :func:`vidcap.video.lift.lift`.
    contact : 'auto', 'off' or array_like of bool, shape (F, 2)
    sweeps : int
        Rounds of sign choice and re-solve after the first solve.
    max_iter : int
        Levenberg-Marquardt iterations per solve.
    robust : float, optional
        After the first solve, re-weight the 2D joints by their misfit
        (:func:`robust_weights`, this many sigmas) and solve again; the joints whose
        ``confidence`` is above 1 (the user's) keep their weight.
    noise_floor : float
        The 2D noise (fraction of the height) the pose prior assumes at least
        (:data:`FITTED_NOISE_FLOOR` for joints from the 2D fit).
    contact_floor : float
        The 2D noise the contact weight assumes at least (:data:`FITTED_CONTACT_FLOOR`
        for joints from the 2D fit).
    labels : bool
        Choose which 2D arm and leg is the left one per frame
        (:func:`vidcap.video.solve.labels.choose_labels`).
    held_labels : array_like of bool, shape (F, 2), optional
        (Frame, pair: arms, legs) whose names are the user's: never exchanged.
    jobs : int
        Processes: 2 or more solves a long clip in two halves at once
        (:func:`vidcap.video.solve.split.solve_split`).
    **weights
        Override :class:`vidcap.video.solve.residuals.Problem`'s weights.

    Returns
    -------
    ClipSolve
    """
    body = body or BodyModel()
    j2 = np.asarray(joints2d, dtype=float)
    pb = make_problem(j2, scale=scale, fps=fps, body=body, yaw=yaw, prior_signs=prior_signs,
                      hard_signs=hard_signs, confidence=confidence, yaw_sigma=yaw_sigma,
                      segment_scale=segment_scale, principal_point=principal_point,
                      contact=contact, noise_floor=noise_floor,
                      contact_floor=contact_floor, **weights)
    p0 = warm_start(pb, j2, scale=scale, body=body, segment_scale=segment_scale,
                    principal_point=principal_point)
    kept = None if confidence is None else np.asarray(confidence, float) > 1.0
    return solve_problem(pb, p0, sweeps=sweeps, max_iter=max_iter, robust=robust,
                         labels=labels, held_labels=held_labels, robust_kept=kept, jobs=jobs)


def solve_problem(problem: Problem, params, *, sweeps: int = 2, max_iter: int = 30,
                  fixed=None, robust: float | None = None, labels: bool = False,
                  held_labels=None, robust_kept=None, jobs: int = 1) -> ClipSolve:
    """Solve ``problem`` from ``params`` (F, 24): LM, then ``sweeps`` rounds of sign
    choice (:func:`vidcap.video.solve.signs.sweep_signs`) and LM; ``fixed`` (F,) bool
    frames are held (a local re-solve's boundary); with ``labels`` the arms' and legs'
    names are chosen after the first LM (:func:`vidcap.video.solve.labels.choose_labels`,
    never on ``held_labels`` (F, 2)); with ``robust`` the joints are re-weighted by
    their misfit after it (:func:`robust_weights`), but for ``robust_kept`` (F, 15).
    With ``jobs`` > 1 a clip of :data:`vidcap.video.solve.split.SPLIT_MIN_FRAMES` or more
    (and no ``fixed`` frames) is solved in two halves on two processes
    (:func:`vidcap.video.solve.split.solve_split`).

    BLAS runs on one thread here: the solve's dense blocks are 48 x 48, where more
    threads only add waiting, ten-fold when other processes hold the cores."""
    from threadpoolctl import threadpool_limits

    kw = dict(sweeps=sweeps, max_iter=max_iter, robust=robust, labels=labels,
              held_labels=held_labels, robust_kept=robust_kept)
    with threadpool_limits(1):
        if jobs > 1 and fixed is None and problem.n_frames >= SPLIT_MIN_FRAMES:
            return solve_split(_solve_problem, problem, params, **kw)
        return _solve_problem(problem, params, fixed=fixed, **kw)[0]


def robust_weights(problem: Problem, joints, scale: float, *, kept=None) -> Problem:
    """``problem`` with each 2D joint's weight divided by sqrt(1 + (e / scale)^2), e its
    misfit at ``joints`` in units of its own sigma (one re-weighting step of a Cauchy
    loss): a joint the 2D fit put far from where the rest of the clip says it is
    counts less, and the smoothness and the other joints carry its frame. ``kept``
    (F, 15) bool: joints whose weight stays (the user's placed joints: near hard)."""
    from dataclasses import replace

    e = np.linalg.norm(joints[..., :2] - problem.target, axis=-1) * problem.weight
    w = problem.weight / np.sqrt(1.0 + (e / scale) ** 2)
    if kept is not None:
        w = np.where(kept, problem.weight, w)
    return replace(problem, weight=w)


def _solve_problem(problem: Problem, params, *, sweeps: int, max_iter: int, fixed,
                   robust: float | None = None, labels: bool = False,
                   held_labels=None, robust_kept=None) -> tuple[ClipSolve, Problem]:
    """:func:`solve_problem` in this process; also the problem as it was last solved
    (robust weights and exchanged names applied)."""
    # the first solve only brings the clip near enough for the sign sweep to read it;
    # the re-solve after the sweep finishes (a full first solve: 2x the time, equal
    # accuracy on the tuning clips)
    sol = levenberg_marquardt(problem, params, max_iter=min(max_iter, FIRST_ITER), fixed=fixed)
    p, iters = sol.params, sol.iterations
    joints, root, _ = forward_kinematics(p, problem.offsets)
    if robust:
        problem = robust_weights(problem, joints, robust, kept=robust_kept)
        # like the first solve, only near enough for the sweep (a full solve here: 1.6x
        # the time of the whole solve at equal accuracy on the tuning renders)
        sol = levenberg_marquardt(problem, p, max_iter=min(max_iter, FIRST_ITER), fixed=fixed)
        p, iters = sol.params, iters + sol.iterations
        joints, root, _ = forward_kinematics(p, problem.offsets)
    swapped = np.zeros((len(p), 2), bool)
    if labels:
        swapped, p = choose_labels(problem, p, held=held_labels, fixed=fixed)
        if swapped.any():
            problem = relabel(problem, swapped)
            joints, root, _ = forward_kinematics(p, problem.offsets)
    sw = None
    for _ in range(sweeps):
        sw = sweep_signs(problem, joints, root, p)
        flip = sw.flipped.any(axis=1)
        if fixed is not None:
            flip &= ~np.asarray(fixed, bool)
        if not flip.any():
            break
        q = p.copy()
        q[flip] = params_from_joints(sw.joints[flip], p[flip, 3])
        q[flip, :3] = p[flip, :3]
        sol = levenberg_marquardt(problem, q, max_iter=max_iter, fixed=fixed)
        p, iters = sol.params, iters + sol.iterations
        joints, root, _ = forward_kinematics(p, problem.offsets)
        sw = None
    p2, repaired = repair_outliers(problem, p, fixed=fixed)
    if repaired:  # the windows were solved with their edges held: now the whole clip
        sol = levenberg_marquardt(problem, p2, max_iter=max_iter, fixed=fixed)
        p, iters = sol.params, iters + sol.iterations
        joints, root, _ = forward_kinematics(p, problem.offsets)
        sw = None
    if sw is None:  # the loop's last sweep, when nothing moved since, is this one
        sw = sweep_signs(problem, joints, root, p)
    return ClipSolve(p, joints, solved_signs(joints, problem.lengths), sw.confidence,
                     problem.contact.copy(), sol.cost, iters, swapped), problem
