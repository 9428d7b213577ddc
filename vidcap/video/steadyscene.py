"""The scene a never-seen pixel shows in a long, steady stretch of the clip (issue 26).

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
one steady state only (the person never left it) keeps its flag.
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


def _two_states(colours, times, tau, guess):
    """Per pixel of ``colours`` (K, P, 3): the scene's steady state as (take (P,) bool,
    members (K, P) bool) -- the samples of the run nearer ``guess`` (P, 3) when the pixel
    has two steady states of different colours and that one is clearly nearer."""
    k, p = colours.shape[:2]
    start, stop = steady_runs(colours, tau)
    length = stop - start + 1
    span = times[stop] - times[start]
    ok = (length >= MIN_SAMPLES) & (span >= MIN_SECONDS)
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
    order = np.arange(k)[:, None]
    members = (order >= start[scene, cols][None]) & (order <= stop[scene, cols][None])
    return take, members


def retake_steady(model, frames: np.ndarray, gains: np.ndarray, times: np.ndarray):
    """The plate re-taken where a never-seen pixel shows the scene in a second steady
    state (module docstring).

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

    Returns
    -------
    vidcap.video.background.BackgroundModel
        With ``plate``, ``never_seen``, ``confidence`` (and ``still_person``) changed
        where re-taken; the same object when nothing is.
    """
    if not STEADY_SCENE or len(frames) < 2 * MIN_SAMPLES or not model.never_seen.any():
        return model
    ys, xs = np.nonzero(model.never_seen)
    g = np.asarray(gains, np.float32)[:, None, :]
    times = np.asarray(times, np.float64)
    tau = float(model.threshold)
    take = np.zeros(len(ys), bool)
    value = np.zeros((len(ys), 3), np.float32)
    share = np.zeros(len(ys), np.float32)
    for s in range(0, len(ys), BLOCK):
        sl = slice(s, s + BLOCK)
        colours = frames[:, ys[sl], xs[sl]].astype(np.float32) / g
        guess = model.plate[ys[sl], xs[sl]].astype(np.float32)
        t, members = _two_states(colours, times, tau, guess)
        take[sl] = t
        masked = np.where(members[..., None], colours, np.nan)
        with np.errstate(all="ignore"):
            value[sl] = np.where(t[:, None], np.nanmedian(masked, axis=0), 0)
        share[sl] = members.mean(axis=0)
    if not take.any():
        return model
    ty, tx = ys[take], xs[take]
    plate = model.plate.copy()
    plate[ty, tx] = np.clip(np.rint(value[take]), 0, 255).astype(np.uint8)
    never = model.never_seen.copy()
    never[ty, tx] = False
    conf = model.confidence.copy()
    conf[ty, tx] = share[take]
    out = {"plate": plate, "never_seen": never, "confidence": conf}
    still = getattr(model, "still_person", None)
    if still is not None:
        still = still.copy()
        still[ty, tx] = False
        out["still_person"] = still
    return replace(model, **out)
