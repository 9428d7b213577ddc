"""One frame's fit: the order of seed 004 section 3.1.4, fresh or warm from the last frame.

:func:`fit_normalised` is two short recipes over the moves: :func:`_fit_fresh` (the
seed's order, with the steps beyond it that :mod:`vidcap.video.fit.pose2d` lists) and
:func:`_fit_warm` (tracking from the previous frame's pose). :func:`fit_frame` adds
the fresh fit that challenges a slipping track and the track that challenges a fresh
fit (:func:`track_below_threshold`), and :func:`fit_pose` is the public door: it checks
the options once.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from vidcap.video.fit.armpairs import search_arm_pairs
from vidcap.video.fit.bend import bending, track_bend
from vidcap.video.fit.crossing import choose_crossing
from vidcap.video.fit.cues import apply_cues
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.fold import crouching, fold_thighs
from vidcap.video.fit.foreshortening import fit_foreshortening, search_fore
from vidcap.video.fit.grids import search_arm_grid, search_arm_track, search_leg_grid
from vidcap.video.fit.headzone import clear_head_zone
from vidcap.video.fit.labels import keep_labels
from vidcap.video.fit.legs import (
    fit_upper_legs,
    swap_lower_legs,
    untangle_thighs,
    verify_crossing,
)
from vidcap.video.fit.limbs import contour_arms, contour_lower_legs, refine_limbs
from vidcap.video.fit.limits import REST_DEG, TWO_PI, J, S
from vidcap.video.fit.moves import search_group, search_root, search_spread
from vidcap.video.fit.normalise import NormalisedMask, normalise_mask
from vidcap.video.fit.options import FALLBACK, FitOptions
from vidcap.video.fit.result import FramePose
from vidcap.video.fit.state import FitState
from vidcap.video.fit.torso import (
    fit_torso_head,
    fit_torso_lean,
    place_torso,
    search_torso_about_neck,
)

#: Spread below which shoulders and hips nearly coincide in the image (a side view), so
#: a fresh fit's image-side limb names mean nothing and a track's are kept
#: (:func:`~vidcap.video.fit.labels.keep_labels`); above it a limb's name says which hip or
#: shoulder it hangs from, which the image shows.
SIDE_SPREAD = 0.3
LABEL_TIE = 0.002  # S a fresh fit may lose to keep a track's limb names
#: Spread from which a tracked frame also tries its legs exchanged between the hips
#: (:func:`~vidcap.video.fit.crossing.choose_crossing`): with the hips apart in the
#: image a leg hung from the wrong one misses its hip; nearer a side view the
#: exchange only renames the legs (chosen on the tuning clips, HISTORY.md).
CROSSING_SPREAD = 0.4
#: A fresh fit below this S is fitted again with the torso found by
#: :func:`~vidcap.video.fit.torso.fit_torso_lean` (a body bent forward, crouched, in a
#: lunge; issue 27 item 4), and the better of the two kept: an upright body's fresh fit
#: scores above it, so the second fit costs time only where the image asks for it.
LEAN_BELOW = 0.7
#: ... and so is a fresh fit whose torso leans this far from upright (radians): near the
#: seed's limits (45 degrees) the seed's search about a pelvis placed for an upright
#: body stops short of a deeper bend.
LEAN_FROM = np.deg2rad(35.0)
_UPPERS = [S[f"{s}_upper_{p}"] for p in ("arm", "leg") for s in "lr"]
_LEAVES = [S["head"]] + [S[f"{s}_lower_{p}"] for p in ("arm", "leg") for s in "lr"]


def fit_normalised(eng: _MaskEngine, *, previous: FramePose | None = None,
                   options: FitOptions, start: FitState | None = None,
                   ) -> tuple[FitState, bool, bool]:
    """Fit the model to the engine's silhouette; see :func:`fit_pose`.

    ``start``: :func:`warm_start` of ``previous``, when the caller made it already (made
    here otherwise); not used without ``previous``.

    Returns
    -------
    state : FitState
        The final pose (normalised pixels).
    crossed : bool
        Algorithm 5's verdict (fresh fits only).
    warm : bool
        The fit started from ``previous``.
    """
    searched = options.spread_searched
    if previous is None:
        st = _placed(eng, options)
    else:
        st = warm_start(eng, previous, options) if start is None else start
        if eng.similarity(st) >= options.warm_threshold:
            return _fit_warm(eng, st, options, searched), False, True
    # a fresh fit from the rest pose (where a warm start was tried: at its root and spread)
    st = st.replace(angles=np.deg2rad(REST_DEG), fore=np.ones(10),
                             drawn=np.zeros(10, dtype=bool))
    rest = st
    st, crossed = _fit_fresh(eng, rest, options, searched)
    if eng.similarity(st) < LEAN_BELOW or abs(st.angles[S["torso"]] - np.pi / 2) >= LEAN_FROM:
        lean, lean_crossed = _fit_fresh(eng, rest, options, searched, lean=True)
        if eng.similarity(lean) > eng.similarity(st):
            st, crossed = lean, lean_crossed
    return st, crossed, False


def _placed(eng: _MaskEngine, options: FitOptions) -> FitState:
    """The rest pose at the spread the options fix (0.5 when searched), its pelvis
    placed from the silhouette (:func:`~vidcap.video.fit.torso.place_torso`)."""
    fixed = 0.5 if options.spread_value is None else float(options.spread_value)
    return place_torso(eng, FitState.rest(spread=fixed))


def warm_start(eng: _MaskEngine, previous: FramePose, options: FitOptions) -> FitState:
    """The previous frame's pose (angles, foreshortening, spread) at the pelvis placed
    from this silhouette (:func:`_placed`; a silhouette taller than the body: searched
    up and down). A warm fit starts from it, a fresh fit from its pelvis and spread; below
    the warm threshold :func:`track_below_threshold` tracks from the previous frame's
    pelvis (:func:`_nearer_start`) as well. :func:`fit_frame` makes it once for both."""
    placed = _placed(eng, options)
    searched = options.spread_searched
    st = placed.replace(
        angles=np.array(previous.angles, dtype=float),
        fore=np.array(previous.foreshortening, dtype=float),
        spread=float(previous.spread) if searched else placed.spread,
        drawn=np.ones(10, dtype=bool))
    if eng.taller:
        # the head need not be at the silhouette's top (a shorter silhouette, a
        # crouch, still has the head on top)
        st, _ = search_root(eng, st, 1, 0.25 * eng.H)
    return st


def track_below_threshold(eng: _MaskEngine, st: FitState, previous: FramePose,
                          options: FitOptions, *, start: FitState | None = None,
                          ) -> FitState | None:
    """The previous frame's pose tracked onto this silhouette although its start covers
    it below the warm threshold, when that fits better than ``st`` (the fresh fit
    :func:`fit_normalised` made instead); None otherwise. ``start``: the
    :func:`warm_start` :func:`fit_normalised` was given (made here when None).

    Where a body leans into a balance pose, bends or raises a hand above its head, S
    drops for every pose the model can take, and the start from the last frame's pose
    falls below the threshold although the pose moved by a few degrees; a fresh fit
    then starts from an upright rest pose and ends in another body (pose2sim_balance
    cam1 frames 40-53, MediaPipe's masks: fresh fits at S 0.53, 8-25 % of height off).
    Everything else stays as it was: a frame whose start reaches the threshold is
    tracked from it, and the fresh fit starts from the pelvis placed from the top
    (started from the last pelvis too, the fresh fits lost 0.74 points of held-out PCK
    on side views and the walk_three_quarter sample's 2D error rose 3.5 -> 4.0 %;
    HISTORY.md). Costs a warm fit only where the start is below the threshold.
    """
    if start is None:
        start = warm_start(eng, previous, options)
    start = _nearer_start(eng, start, previous, options)
    tracked = _fit_warm(eng, start, options, options.spread_searched)
    return tracked if eng.similarity(tracked) > eng.similarity(st) else None


def _nearer_start(eng: _MaskEngine, st: FitState, previous: FramePose,
                  options: FitOptions) -> FitState:
    """The warm start ``st`` (the previous pose, its pelvis placed from this silhouette's
    top as for an upright body) or the same pose with the pelvis where the previous
    frame had it, whichever fits the silhouette better.

    The pelvis placed from the top moves with whatever is highest: a hand raised above
    the head lifts it, a body leaning into a balance pose (the head no longer on top)
    drops it, and the previous pose, put there, no longer covers the silhouette, so a
    track that was right is dropped for a fresh fit. A body does not jump between
    frames; its pelvis where it was is the better start there (pose2sim_balance cam1,
    fitted to MediaPipe's masks: frames 34-53 were fitted fresh, upright, 25 % of
    height off). Tried only where the start from the top is below the warm threshold:
    tried everywhere, a track kept its pelvis through frames a fresh fit had read
    better (tfjs_dance, sports2d_walk_turn lost 0.3-0.9 % of height; HISTORY.md).
    """
    if eng.similarity(st) >= options.warm_threshold:
        return st
    pelvis = eng.norm.to_normalised(np.asarray(previous.joints, dtype=float)[J["pelvis"]])
    if not np.isfinite(pelvis).all():
        return st
    kept = st.replace(root=pelvis)
    return kept if eng.similarity(kept) > eng.similarity(st) else st


def _fit_warm(eng: _MaskEngine, st: FitState, options: FitOptions, spread: bool) -> FitState:
    """Tracking: every search starts from the previous frame's pose with a narrow
    interval (2 iterations of Algorithm 1: +-8 degrees in 2 degree steps, then 0.5;
    2 of Algorithm 6); no contour step."""
    st = st.drawing(slice(None))
    st, _ = search_root(eng, st, 0, 0.1 * eng.H)
    step = np.deg2rad(options.warm_step_deg)
    st, _ = search_torso_about_neck(eng, st, start=st.angles[S["torso"]], interval=8 * step,
                                    alone=True)
    if options.track_bend and (crouching(eng) or bending(st)):
        st = track_bend(eng, st)
    st = search_group(eng, st, _UPPERS, interval=8 * step)
    st = search_group(eng, st, _LEAVES, interval=8 * step)
    if spread:
        st, _ = search_spread(eng, st, start=st.spread, interval=0.2, min_step=0.1)
    st = search_group(eng, st, _UPPERS + _LEAVES, kind="fore", interval=0.2, divisions=5)
    if options.leg_grid:
        for s in ("l", "r"):
            st = search_leg_grid(eng, st, s)
    if options.fold_legs and crouching(eng):
        st = fold_thighs(eng, st, tie=options.tie)
        # a crouching torso bends toward the camera too (a fresh fit's Algorithm 6 looks
        # at it; a tracked frame's does not, elsewhere)
        st, _ = search_fore(eng, st, S["torso"], start=st.fore[S["torso"]], interval=0.3)
    if options.arm_track:
        for s in ("l", "r"):
            st = search_arm_track(eng, st, s)
    # no untangle_thighs here: a tracked leg stays on the hip it was found on. Thighs
    # crossing in the image are no error in a three-quarter view (the forward knee
    # passes the other across the narrow hips every step), and undoing them within
    # the tie put the legs on the wrong hips for half of each gait cycle (07_07 at
    # 45 deg: PCK@0.05 89.3 -> 90.8 %, RESULTS.md).
    return st


def polished(eng: _MaskEngine, fresh: FitState, options: FitOptions) -> FitState:
    """A fresh fit ``fresh`` refined by the tracked frame's searches started from it
    (:func:`_fit_warm`), where that scores the higher S; ``fresh`` itself otherwise
    (``FitOptions.polish``, off by default).

    A track and the fresh fit that challenges it (:func:`fit_frame`) are not refined
    alike: the track has been polished by the warm searches frame after frame, the
    fresh fit once by the seed's order, so the fresh fit of a better pose can lose to
    a worse track by the few boundary pixels the warm searches would have gained it.
    Refined, the challenger wins where its pose is the better one, and tracks started
    from different frames meet again. Measured (``pose2d_accuracy.py --perturb`` and
    ``--held-out --hidden solve``, benchmarks/HISTORY.md): the fit's PCK spread over
    one-pixel mask changes fell on the tuning renders and the held-out side views rose
    83.7 -> 85.3 %, but the three-quarter views fell 87.6 -> 86.6 and the mean 88.28 ->
    88.16, so it stays off. Costs one warm fit per challenge."""
    again = _fit_warm(eng, fresh, options, options.spread_searched)
    return again if eng.similarity(again) > eng.similarity(fresh) else fresh


def kept_or_better(eng: _MaskEngine, st: FitState, start: FitState, previous: FramePose,
                   options: FitOptions) -> FitState:
    """A tracked frame's fit ``st`` (from ``start``, :func:`warm_start`: the previous
    pose at the pelvis placed from this silhouette), or, where the previous pose at its
    own pelvis covers this silhouette better, the warm fit from there or that pose
    itself, whichever scores the higher S: a frame fitted again from its own answer
    never loses S.

    The placed pelvis moves with the silhouette's top and middle in whole steps, and the
    warm searches (narrow, each segment against the others as they were) need not climb
    back to where the previous fit stood: the same frame fitted again from its own
    answer drifted, S 0.947 -> 0.895 over five repeats, torso and head 5-13 degrees,
    and an arm across the torso found by the cues 2-5 px from its elbow.
    :func:`fit_frame` judges the track by ``st`` (slipping below the fallback share of
    the previous S: challenged by a fresh fit), not by what this returns: judged by the
    kept pose, a slip went unseen and a wrong track held for ten frames (131_01 at yaw
    110, a tuning render). Costs one S where ``st`` beats the previous pose (a moving
    body, nearly always)."""
    pelvis = eng.norm.to_normalised(np.asarray(previous.joints, dtype=float)[J["pelvis"]])
    if not np.isfinite(pelvis).all():
        return st
    kept = start.replace(root=pelvis)
    if eng.similarity(kept) <= eng.similarity(st):
        return st
    again = _fit_warm(eng, kept, options, options.spread_searched)
    return again if eng.similarity(again) >= eng.similarity(kept) else kept


def _fit_fresh(eng: _MaskEngine, st: FitState, options: FitOptions,
               spread: bool, lean: bool = False) -> tuple[FitState, bool]:
    """The seed's order (torso and head, arms and lower legs by contour, upper legs,
    foreshortening) and, with ``options.refine``, the refinement beyond it.
    ``lean``: the torso and head by :func:`fit_torso_lean` instead of the seed's."""
    st = fit_torso_lean(eng, st) if lean else fit_torso_head(eng, st)
    st = contour_arms(eng, st)
    st, crossed = contour_lower_legs(eng, st)
    if crossed:
        st = swap_lower_legs(st)  # Algorithm 2: swap the lower legs when crossed
    st = st.drawing(slice(None))

    def legs(cur: FitState) -> FitState:
        cur = fit_upper_legs(eng, cur)
        if spread:
            cur, _ = search_spread(eng, cur)
            cur = fit_upper_legs(eng, cur, warm=True, passes=1)
        return cur

    st = legs(st)
    if crossed and options.verify_crossing:
        st = verify_crossing(eng, st, legs, spread=spread, tie=options.tie)
    if options.refine:
        st = _refine(eng, st, options, spread)
    if options.fold_legs and crouching(eng):
        st = fold_thighs(eng, st, tie=options.tie)
    return fit_foreshortening(eng, st, warm=options.refine), crossed


def _refine(eng: _MaskEngine, st: FitState, options: FitOptions, spread: bool) -> FitState:
    """Beyond the seed: the model centred, every limb again (whole arms first), the
    arm grids (each arm, then both together), the torso once more with every limb
    drawn (the arms no longer pull it), crossed thighs untangled, the spread again."""
    st = st.drawing(slice(None))
    st, _ = search_root(eng, st, 0, 0.05 * eng.H)
    st = refine_limbs(eng, st, whole_arms=True)
    if options.arm_grid:
        for s in ("l", "r"):
            st = search_arm_grid(eng, st, s)
        if options.arm_pairs:
            st = search_arm_pairs(eng, st)
    st, _ = search_torso_about_neck(eng, st, start=st.angles[S["torso"]],
                                    interval=np.deg2rad(16))
    st = untangle_thighs(eng, st, tie=options.tie)
    if spread:
        st, _ = search_spread(eng, st, start=st.spread, interval=0.4)
    return st


def fit_frame(norm: NormalisedMask, *, previous: FramePose | None = None,
              challenge: bool = False, options: FitOptions, cues=None,
              heading: np.ndarray | None = None, scratch=None) -> FramePose:
    """:func:`fit_pose` of a normalised silhouette with options already checked.

    ``heading``: where the knees and ankles (left knee, left ankle, right knee, right
    ankle; (4, 2) original pixels) are heading by the last two frames; a tracked frame
    then also tries its legs exchanged between the hips
    (:func:`vidcap.video.fit.crossing.choose_crossing`, legs passing each other).

    ``cues``: ``(image, colour_model)``, the colour frame on ``norm``'s grid
    (:func:`vidcap.video.fit.cues.cue_image`) and the clip's
    :class:`~vidcap.video.fit.cues.ColourModel`: the arms are then placed by the
    frame's cues as well (:func:`vidcap.video.fit.cues.apply_cues`); None: outline only.

    ``scratch``: ``(state, crossed)`` of :func:`fit_normalised` of ``norm`` without a
    previous pose (this frame's fit from scratch), when it was made already (the clip's
    colour model is learned from such fits, :mod:`vidcap.video.fit.cuecolours`): used
    instead of fitting the frame from scratch again (the same fit).
    """
    eng = _MaskEngine(norm, caps=options.caps, body=options.body, foot=options.foot)
    start = None if previous is None else warm_start(eng, previous, options)
    if previous is None and scratch is not None:
        (st, crossed), warm = scratch, False
    else:
        st, crossed, warm = fit_normalised(eng, previous=previous, options=options,
                                           start=start)
    compared = False  # the track already beat this frame's fresh fit
    if previous is not None and not warm:
        tracked = track_below_threshold(eng, st, previous, options, start=start)
        if tracked is not None:
            st, crossed, warm, compared = tracked, False, True, True
    # the track is judged as the warm searches left it, before the previous pose may
    # replace it (:func:`kept_or_better`): a slip must still meet the fresh fit
    tracked_s = eng.similarity(st)
    if warm:
        st = kept_or_better(eng, st, start, previous, options)
    slipping = warm and (challenge or tracked_s < options.fallback * previous.similarity
                         or (options.fallback > 0 and tracked_s < LEAN_BELOW))
    if slipping and not compared:
        # the track is slipping: fit this frame from scratch, keep the better fit
        fresh, fresh_crossed = (fit_normalised(eng, options=options)[:2] if scratch is None
                                else scratch)
        if options.polish:
            fresh = polished(eng, fresh, options)
        if eng.similarity(fresh) > eng.similarity(st):
            if max(previous.spread, fresh.spread) < SIDE_SPREAD:
                # a side view: no image cue names the limbs, the track's names stand
                fresh = keep_labels(eng, fresh, norm.to_normalised(previous.joints),
                                    tie=LABEL_TIE)
            st, crossed, warm = fresh, fresh_crossed, False
    if heading is not None and (warm or not challenge) and st.spread >= CROSSING_SPREAD:
        st = choose_crossing(eng, st, norm.to_normalised(heading),
                             interval=8 * np.deg2rad(options.warm_step_deg))
    if options.head_zone > 0:
        st = clear_head_zone(eng, st, options.head_zone)
    if cues is not None:
        # a tracked frame's arms moved little: searched near where they are, unless
        # challenged or tracked from a start below the warm threshold (then over every
        # angle pair, as a fresh fit's)
        candidates = {}
        st = apply_cues(eng, st, *cues, local=warm and not (challenge or compared),
                        out=candidates)
    else:
        candidates = None
    return FramePose(
        joints=norm.to_original(eng.joints(st)),
        angles=np.mod(st.angles, TWO_PI),
        foreshortening=st.fore.copy(),
        scores=st.scores.copy(),
        margins=st.margins.copy(),
        spread=float(st.spread),
        crossed=bool(crossed),
        similarity=eng.similarity(st),
        warm=bool(warm),
        height_px=norm.body_height / norm.scale,
        arm_candidates=candidates,
    )


def recross(norm: NormalisedMask, fp: FramePose, heading: np.ndarray, *,
            options: FitOptions) -> FramePose:
    """A fitted frame ``fp`` judged again by where its legs were heading
    (:func:`~vidcap.video.fit.crossing.choose_crossing`), e.g. by the frames after it
    (:func:`vidcap.video.fit.tracking.fit_sequence`'s backward sweep): ``fp`` itself
    unless its legs exchanged fit better. ``norm`` must be the silhouette ``fp`` was
    fitted on; ``heading`` (4, 2) original pixels, as :func:`fit_frame` takes it."""
    if fp.spread < CROSSING_SPREAD:
        return fp
    eng = _MaskEngine(norm, caps=options.caps, body=options.body, foot=options.foot)
    st = FitState(norm.to_normalised(fp.joints[0]), np.array(fp.angles, dtype=float),
                  np.array(fp.foreshortening, dtype=float), float(fp.spread),
                  np.array(fp.scores, dtype=float), np.array(fp.margins, dtype=float),
                  np.ones(10, dtype=bool))
    chosen = choose_crossing(eng, st, norm.to_normalised(heading),
                             interval=8 * np.deg2rad(options.warm_step_deg))
    if chosen is st:
        return fp
    return dataclasses.replace(fp, joints=norm.to_original(eng.joints(chosen)),
                               angles=np.mod(chosen.angles, TWO_PI),
                               foreshortening=chosen.fore.copy(), scores=chosen.scores.copy(),
                               margins=chosen.margins.copy(),
                               similarity=eng.similarity(chosen))


def fit_pose(mask: np.ndarray | NormalisedMask, *, previous: FramePose | None = None,
             height: int = 80, refine: bool = True, spread: bool = True,
             verify_crossing: bool = True, caps: bool = False, warm_threshold: float = 0.55,
             fallback: float = FALLBACK, warm_step_deg: float = 2.0,
             challenge: bool = False, arm_grid: bool = True, leg_grid: bool = True,
             arm_track: bool = False, spread_value: float | None = None,
             body_height: float | None = None) -> FramePose:
    """Fit the 2D cylinder model to one silhouette (seed 004 section 3.1.4).

    Parameters
    ----------
    mask : numpy.ndarray, shape (H, W), bool, or NormalisedMask
        The silhouette in the original frame, or already normalised by
        :func:`vidcap.video.fit.raster.normalise_mask` (then ``height`` and ``body_height``
        are not used: a sequence fit reuses a frame's for its refits).
    previous : FramePose, optional
        The previous frame's pose. If it still covers this silhouette with
        similarity >= ``warm_threshold``, every search starts from it with narrow
        intervals (tracking); otherwise the frame is fitted from scratch.
    height : int
        Height in pixels the silhouette is normalised to before fitting.
    refine : bool
        Run the extra Algorithm 1 pass over the limbs (beyond the seed).
    spread : bool
        Search the shoulders' and hips' lateral spread (beyond the seed); if false
        the spread is fixed at 0.5.
    spread_value : float, optional
        Fix the spread at this value in [0, 1] instead (no search);
        :func:`fit_sequence` uses it to refit frames whose spread jumps away from
        their neighbours'.
    verify_crossing : bool
        When Algorithm 5 says the legs cross, keep the swap only if it fits better.
    caps : bool
        Draw segments as capsules (true) or rectangles.
    warm_threshold : float
        Similarity of the previous pose needed to warm-start.
    fallback : float
        A warm fit whose similarity is below ``fallback`` times the previous
        frame's is redone from scratch and the better of the two kept.
    warm_step_deg : float
        First step of a warm angle search in degrees (8 divisions, so the search
        spans +-4 steps around the previous angle, then refines by a quarter).
    challenge : bool
        Also fit a warm-started frame from scratch and keep the better fit (how a
        track escapes a wrong but stable pose; :func:`fit_sequence` does this
        ``reinit_every`` frames after the last fresh fit).
    arm_grid : bool
        With ``refine``, search each whole arm over every (upper, lower) angle pair
        in fresh (not warm-started) fits; near-ties go to a hanging arm
        (:func:`vidcap.video.fit.grids.search_arm_grid`).
    leg_grid : bool
        In warm-started (tracked) fits, search each whole leg over every (thigh,
        shin) angle pair and keep the best if it fits clearly better than the
        tracked leg (:func:`vidcap.video.fit.grids.search_leg_grid`).
    arm_track : bool
        In warm-started fits, search each whole arm over every angle pair at full
        length and keep the best if it fits clearly better than the tracked arm (a
        forearm swinging faster than the track's search reaches;
        :func:`vidcap.video.fit.grids.search_arm_track`).
    body_height : float, optional
        The body's standing height in original pixels, when known apart from the
        silhouette's (a crouch, raised arms).

    Returns
    -------
    FramePose

    Raises
    ------
    ValueError
        If ``mask`` is empty, or an option is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> from vidcap.video.fit import fit_pose
    >>> mask = np.zeros((120, 60), bool)
    >>> mask[10:110, 25:35] = True  # a standing bar: a body seen from the side
    >>> fp = fit_pose(mask)
    >>> fp.joints.shape, bool(fp.similarity > 0.5)
    ((15, 2), True)
    """
    options = FitOptions(height=height, refine=refine, spread=spread,
                         verify_crossing=verify_crossing, caps=caps,
                         warm_threshold=warm_threshold, fallback=fallback,
                         warm_step_deg=warm_step_deg, arm_grid=arm_grid, leg_grid=leg_grid,
                         arm_track=arm_track, spread_value=spread_value, body_height=body_height)
    norm = (mask if isinstance(mask, NormalisedMask)
            else normalise_mask(mask, height=height, body_height=body_height))
    return fit_frame(norm, previous=previous, challenge=challenge, options=options)


__all__ = ["CROSSING_SPREAD", "LABEL_TIE", "SIDE_SPREAD", "fit_frame", "fit_normalised",
           "fit_pose", "polished", "recross", "track_below_threshold", "warm_start"]
