"""The scene a pixel shows in a long, steady stretch of the clip (issue 26).

A person who stands in one place for most of the clip and then steps aside
(cdnet_office_stand: he reads for six seconds, then moves half a body to the left)
leaves pixels that no sample shows uncovered while he stands there, and that the
later samples show as the wall, unchanged, for seconds. The plate's passes flag them
never seen (the person box's still parts) and inpaint a guess; the guess is not the
wall, so the silhouettes keep a ghost of him where he stood.

Per never-seen pixel, over the plate's samples in time order: a *steady state* is a
run of consecutive samples whose colours agree with the run's first (L1 within the
plate's foreground threshold) for at least :data:`MIN_SAMPLES` samples and
:data:`MIN_SECONDS`. A pixel with two steady states of different colours saw two
things that each stayed: the person standing and the scene after (or before) them.
The state nearer the plate's inpainted guess (which comes from the seen scene round
the never-seen area) is the scene, when it is clearly nearer (:data:`NEARER`); the
plate is re-taken from its samples and the pixel is no longer never seen. A pixel with
one steady state only (the person never left it) keeps its flag (:data:`STEADY_SCENE`).

The same steady states check the plate where it was seen (:data:`UNSTEADY_PLATE`): a
man walks slowly down a corridor towards the camera (sbi_hallmonitor), his white shirt
over the chair and the cabinet at its end in most samples, and the vote keeps a blend of
shirt there that no two consecutive samples show, while the chair stood unchanged in
the first half of the clip. Where the plate's colour is in no steady stretch, the vote
was unsure of it (confidence under :data:`MAX_CONFIDENCE`), and another colour is
steady over at least half the samples from a clip end, leaving a few samples to
something else, the plate is re-taken from that state. Not where the plate's colour
shows on both sides of the state (the scene seen between a still torso's moments), nor
where the state leaves no clip end (a person who came and stood, the scene at the
ends: onebyone_room), nor a colour only a drift away (:data:`UNSTEADY_FAR`), nor one
the clip's colour models find more the person's than the scene's (a sleeve that stayed
while the scene showed once: :data:`MAX_PERSON_LLR`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["retake_steady", "steady_runs"]

#: Re-take never-seen pixels from a second steady state (run by
#: :func:`vidcap.video.background.estimate_background` after the unseen flags, with the
#: still-person passes). Off: built on cdnet_office_stand (tuning), where of the 2029
#: pixels it re-takes 1687 are scene the truth uncovers later (the wall he stood before)
#: and 308 are his legs (covered in > 90 % of the frames: two steady poses), the late
#: frames' ghost shrinks (frame 299: 3247 -> 2636 false pixels) but the legs go (943 ->
#: 1102 missed): median / p10 IoU 0.799 / 0.607 -> 0.781 / 0.625. silhouettes_real.py
#: --quick --no-mediapipe --only ROW, off -> on, one sitting (wt-still, session 30):
#: tuning 05_12 0-3 s 3/4 back 0.921 / 0.853 -> 0.929 / 0.911, 05_18 2-5 s side 0.957 /
#: 0.841 -> 0.960 / 0.859, 05_05 0-3 s side 0.908 / 0.847 -> 0.911 / 0.858, 02_04 0-3 s
#: 0.961 -> 0.959, 02_07 1-4 s side left p10 0.797 -> 0.793; validation 05_10 2-5 s 3/4 p10
#: 0.925 -> 0.916; the other rows run unchanged (benchmarks/HISTORY.md, Silhouettes). The
#: row it was built for loses its median: off.
STEADY_SCENE = False
#: A steady state spans at least this many samples ...
MIN_SAMPLES = 5
#: ... and this many seconds (first to last sample of the run).
MIN_SECONDS = 1.0
#: The scene's state must be this many times nearer (L1) the inpainted guess than the
#: other state.
NEARER = 0.5
#: Re-take seen plate pixels whose colour no two consecutive samples show (a colour that
#: only passed by, or a blend of several) from the pixel's longest steady state (run
#: first among the still-person passes). On: silhouettes_real.py --quick --no-mediapipe
#: --only real / --only plate, off -> on, one sitting (wt-still, session 30), median /
#: p10 IoU: sbi_hallmonitor_away (validation) 0.819 -> 0.843 (--seed 1: 0.851 -> 0.863),
#: sbi_caviar1 0.983 / 0.828 -> 0.988 / 0.823; the other 26 real rows and the 64 renders
#: within 0.003 (p10 0.01); pose2d_real.py --no-all --only cam1 (the whole clip's plate:
#: 1.1 % of its pixels change) human row 10.3 -> 9.3 % of height, outline row 17.0 ->
#: 17.6 (tfjs_dance 4.7 -> 4.4, squats the same). Built on sbi_hallmonitor (tuning),
#: where without the colour test below it gave 0.314 / 0.278 -> 0.381 / 0.228 but cost
#: mmskeleton_taichi (tuning) 0.815 -> 0.753 (a
#: dark sleeve steady in 21 of 24 samples from the start undid the scene colour
#: regionvote.SCENE_RING took from the one sample that shows it); with it hallmonitor
#: stays 0.315 (the chair's colour is the man's trousers' to the colour models). Each
#: guard below was added for a tuning row the rule broke (benchmarks/HISTORY.md,
#: Silhouettes). Cost: 0.07 s on a 640x480 render's plate, 0.28 s on the 1000x1000
#: onebyone clip's, 2.8-3.5 s on pose2sim cam1's 1920x1080 (a quarter of its plate the
#: vote was unsure of); the colour models are not learned again after it.
UNSTEADY_PLATE = True
#: ... where the plate's confidence is under this, ...
MAX_CONFIDENCE = 0.5
#: ... when that state's colour is this many thresholds (L1) from the plate's (the
#: exposure drifts a little apart from the frame's gain: a colour a drift away is no
#: other thing).
UNSTEADY_FAR = 3.0
#: ... and when that state spans at least this share of the samples.
UNSTEADY_SHARE = 0.5
#: ... leaving at least this many samples out, and when the clip's colour models do
#: not find the state's colour this much (log ratio) more the person's than the scene's.
MIN_OTHER = 3
MAX_PERSON_LLR = 0.0
#: Pixels handled per block (the agreement matrix is K x K per pixel).
BLOCK = 20_000


def steady_runs(colours: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray]:
    """Each sample's run of consecutive samples that agree with it.

    Parameters
    ----------
    colours : numpy.ndarray, shape (K, P, 3), float32
        The samples' colours at P pixels, in time order.
    tau : float
        Two colours agree when their L1 distance is at most this.

    Returns
    -------
    start, stop : numpy.ndarray, shape (K, P), int
        For anchor sample ``i`` at each pixel, the first and last sample (inclusive)
        of the unbroken run round ``i`` whose colours all agree with sample ``i``'s.
    """
    k = len(colours)
    agree = np.abs(colours[:, None] - colours[None]).sum(axis=-1) <= tau  # (K, K, P)
    idx = np.arange(k)
    start = np.repeat(idx[:, None], colours.shape[1], axis=1)
    stop = start.copy()
    fwd = np.ones((k, colours.shape[1]), bool)
    bwd = fwd.copy()
    for d in range(1, k):  # (a loop over the run's length, not over pixels)
        i = idx[idx + d < k]
        fwd[i] &= agree[i, i + d]
        stop[i] += fwd[i]
        j = idx[idx - d >= 0]
        bwd[j] &= agree[j, j - d]
        start[j] -= bwd[j]
    return start, stop


def _steady_states(colours, times, tau):
    """:func:`steady_runs` of ``colours`` (K, P, 3) with each run's length and whether it
    is a steady state (:data:`MIN_SAMPLES`, :data:`MIN_SECONDS`): (start, stop, length,
    ok), each (K, P)."""
    start, stop = steady_runs(colours, tau)
    length = stop - start + 1
    ok = (length >= MIN_SAMPLES) & (times[stop] - times[start] >= MIN_SECONDS)
    return start, stop, length, ok


def _members(start, stop, anchor):
    """(K, P) bool: per pixel, the samples of the run round sample ``anchor`` (P,)."""
    cols = np.arange(start.shape[1])
    order = np.arange(len(start))[:, None]
    return (order >= start[anchor, cols][None]) & (order <= stop[anchor, cols][None])


def _two_states(colours, times, tau, guess):
    """Per pixel of ``colours`` (K, P, 3): the scene's steady state as (take (P,) bool,
    members (K, P) bool, None) -- the samples of the run nearer ``guess`` (P, 3) when the
    pixel has two steady states of different colours and that one is clearly nearer."""
    p = colours.shape[1]
    start, stop, length, ok = _steady_states(colours, times, tau)
    score = np.where(ok, length, 0)
    a = np.argmax(score, axis=0)  # the longest steady state
    cols = np.arange(p)
    ca = colours[a, cols]
    differs = np.abs(colours - ca[None]).sum(axis=-1) > tau
    b = np.argmax(np.where(differs, score, 0), axis=0)  # the longest of another colour
    both = ok[a, cols] & ok[b, cols] & differs[b, cols]
    cb = colours[b, cols]
    da = np.abs(ca - guess).sum(axis=-1)
    db = np.abs(cb - guess).sum(axis=-1)
    scene = np.where(da <= db, a, b)
    near, far = np.minimum(da, db), np.maximum(da, db)
    take = both & (near < NEARER * far)
    return take, _members(start, stop, scene), None


def _longest_steady(colours, times, tau, plate):
    """Per pixel of ``colours`` (K, P, 3) whose ``plate`` colour (P, 3) no two consecutive
    samples show: (take (P,) bool, members (K, P) bool, median (P, 3)), the longest steady
    state when it is one (:data:`MIN_SAMPLES`, :data:`MIN_SECONDS`) and its colours'
    median."""
    k, p = colours.shape[:2]
    start, stop, length, ok = _steady_states(colours, times, tau)
    a = np.argmax(np.where(ok, length, 0), axis=0)
    cols = np.arange(p)
    order = np.arange(k)[:, None]
    members = _members(start, stop, a)
    # the plate's colour on both sides of the steady state: the scene seen between a
    # still torso's moments, not a passer-by before or after the scene
    shown = np.abs(colours - plate[None]).sum(axis=-1) <= tau
    before = (shown & (order < start[a, cols][None])).any(axis=0)
    after = (shown & (order > stop[a, cols][None])).any(axis=0)
    value = np.nanmedian(np.where(members[..., None], colours, np.nan), axis=0)
    far = np.abs(value - plate).sum(axis=-1) > UNSTEADY_FAR * tau
    # (the scene stays for much of the clip; a dancer's limb is steady for a moment)
    # (and something else passes in a few samples more: one sample of another colour
    # before a long steady state is the scene before a person who came and stayed)
    long = (length[a, cols] >= UNSTEADY_SHARE * k) & (length[a, cols] <= k - MIN_OTHER)
    # (the scene before someone came or after they went reaches a clip end; a person who
    # came and stood, breathing, does not: the scene shows there at the ends)
    long &= (start[a, cols] == 0) | (stop[a, cols] == k - 1)
    return ok[a, cols] & ~(before & after) & far & long, members, value


def _unsteady_candidates(model, frames, gains):
    """(rows, columns) of the seen plate pixels the vote was unsure of whose colour no two
    consecutive samples show (within the threshold), outside self-lit pixels."""
    # (where the vote saw the scene in most samples and a later pass put another colour
    # in, that pass knew better: a still torso's rim, steady in every sample)
    maybe = ~model.never_seen & (model.confidence < MAX_CONFIDENCE)
    lit = getattr(model, "self_lit", None)
    if lit is not None:
        maybe &= ~lit
    ys, xs = np.nonzero(maybe)
    if not len(ys):
        return ys, xs
    colours = frames[:, ys, xs].astype(np.float32) / np.asarray(gains, np.float32)[:, None]
    agree = np.abs(colours - model.plate[ys, xs].astype(np.float32)).sum(axis=-1) \
        <= float(model.threshold)
    pair = (agree[1:] & agree[:-1]).any(axis=0)
    # (only where a steady state of half the samples from a clip end can be: its samples
    # agree with its anchor, so neighbours agree within twice the threshold; this keeps
    # the K x K test to a few pixels of a large frame)
    near = np.abs(np.diff(colours, axis=0)).sum(axis=-1) <= 2 * float(model.threshold)
    need = int(np.ceil(UNSTEADY_SHARE * len(frames))) - 1
    lead = np.logical_and.accumulate(near, axis=0).sum(axis=0)
    trail = np.logical_and.accumulate(near[::-1], axis=0).sum(axis=0)
    keep = ~pair & ((lead >= need) | (trail >= need))
    return ys[keep], xs[keep]


def retake_steady(model, frames: np.ndarray, gains: np.ndarray, times: np.ndarray, *,
                  never: bool = True, unsteady: bool = True):
    """The plate re-taken where the samples' steady states say it is not the scene
    (module docstring): a never-seen pixel that shows the scene in a second steady state
    (:data:`STEADY_SCENE`), a seen one whose plate colour no steady stretch shows while
    another colour stays (:data:`UNSTEADY_PLATE`).

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
        The plate so far (its ``never_seen`` pixels hold an inpainted guess).
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The samples it was estimated from, in time order.
    gains : numpy.ndarray, shape (K, 3)
        Their per-channel gains relative to the plate.
    times : numpy.ndarray, shape (K,)
        The samples' times, seconds.
    never, unsteady : bool
        Which of the two rules run (each also needs its switch).

    Returns
    -------
    vidcap.video.background.BackgroundModel
        With ``plate``, ``never_seen``, ``confidence`` (and ``still_person``) changed
        where re-taken; the same object when nothing is.
    """
    never, unsteady = never and STEADY_SCENE, unsteady and UNSTEADY_PLATE
    if len(frames) < 2 * MIN_SAMPLES or not (never or unsteady):
        return model
    times = np.asarray(times, np.float64)
    parts = []
    if never and model.never_seen.any():
        ys, xs = np.nonzero(model.never_seen)
        parts.append(_decided(model, frames, gains, times, ys, xs, _two_states))
    if unsteady:
        ys, xs = _unsteady_candidates(model, frames, gains)
        if len(ys):
            parts.append(_scene_coloured(model, _decided(model, frames, gains, times, ys, xs,
                                                         _longest_steady)))
    parts = [p for p in parts if len(p[0])]
    if not parts:
        return model
    ty, tx, value, share = (np.concatenate(c) for c in zip(*parts, strict=True))
    plate = model.plate.copy()
    plate[ty, tx] = np.clip(np.rint(value), 0, 255).astype(np.uint8)
    never = model.never_seen.copy()
    never[ty, tx] = False
    conf = model.confidence.copy()
    conf[ty, tx] = share
    out = {"plate": plate, "never_seen": never, "confidence": conf}
    still = getattr(model, "still_person", None)
    if still is not None:
        still = still.copy()
        still[ty, tx] = False
        out["still_person"] = still
    return replace(model, **out)


def _scene_coloured(model, part):
    """``part`` (rows, columns, colours, shares) without the colours the clip's colour
    models (``model.colours``, when learned) find more the person's than the scene's."""
    if model.colours is None or not len(part[0]):
        return part
    from vidcap.video.appearance import log_ratio

    keep = log_ratio(part[2], model.colours[0], model.colours[1]) <= MAX_PERSON_LLR
    return tuple(a[keep] for a in part)


def _decided(model, frames, gains, times, ys, xs, decide):
    """The pixels (``ys``, ``xs``) that ``decide`` (:func:`_two_states`,
    :func:`_longest_steady`: take, members, the members' median or None) re-takes: their
    rows, columns, new colours (N, 3) (the median of the chosen state's samples) and the
    share of samples in that state."""
    g = np.asarray(gains, np.float32)[:, None, :]
    tau = float(model.threshold)
    take = np.zeros(len(ys), bool)
    value = np.zeros((len(ys), 3), np.float32)
    share = np.zeros(len(ys), np.float32)
    for s in range(0, len(ys), BLOCK):
        sl = slice(s, s + BLOCK)
        colours = frames[:, ys[sl], xs[sl]].astype(np.float32) / g
        t, members, median = decide(colours, times, tau,
                                    model.plate[ys[sl], xs[sl]].astype(np.float32))
        take[sl] = t
        if median is None:  # (a rule that did not need it: made here)
            masked = np.where(members[..., None], colours, np.nan)
            with np.errstate(all="ignore"):
                median = np.nanmedian(masked, axis=0)
        value[sl] = np.where(t[:, None], median, 0)
        share[sl] = members.mean(axis=0)
    return ys[take], xs[take], value[take], share[take]
