"""The coarse-to-fine interval search of seed 004 Algorithms 1 and 6.

One routine serves both: Algorithm 1 searches a segment's image-plane angle within
its joint limits (8 divisions, stop below a 1 degree interval) and Algorithm 6 a
segment's foreshortening ratio (5 divisions, stop below 1 / length in pixels). Each
iteration evaluates the ``divisions + 1`` evenly spaced values of the current
interval centred on the best value so far (clipped to the limits), then shrinks the
interval to two divisions around the winner ("the division that gives the best
covering result merged with its neighbour divisions"). All candidates of one
iteration are scored by a single call of the score function, i.e. one batch.

Deviations from the pseudo-code, where it does not do what the text says:

* Algorithm 6 sets ``endPoint <- beginPoint``, which makes ``length`` 0 and
  ``minimumStepRatio = 1/0``; the text means the segment's length from its begin to
  its *end* point, which is what callers pass as ``min_step = 1 / length``.
* Algorithm 6 iterates ``while ratio < ratioForEnd`` (strict), so the end of the
  interval (ratio 1, an unforeshortened segment, the most common case) is never
  tried in the first iteration; Algorithm 1 uses ``<=``. Both ends are included
  here.
* Algorithm 6 starts the ratio interval at 0, which the text calls "(0, 1)" and
  which would draw a zero-length segment; callers pass ``lo = min_step``.
* Algorithm 1's ``if stepAngle is 0`` guard and its mixed ``stepAngle`` /
  ``StepAngle`` spelling are one variable; the step is always interval/divisions.
* The seed keeps only the best value. We also return the best score among
  candidates outside the winner's neighbouring divisions (the runner-up), so
  callers can report a confidence margin.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

# The compiled search helpers repeat the float operations of the numpy code they
# replace, so a search returns the same values either way (tests/fit/test_fit_search.py).
from vidcap.video.fit.raster import _kernels


@dataclass(frozen=True)
class SearchResult:
    """Outcome of :func:`interval_search`.

    Attributes
    ----------
    value : float
        The value with the highest score.
    score : float
        Its score.
    runner_up : float
        The best score among evaluated values more than one initial step away from
        ``value`` (``-inf`` if there were none).
    evaluations : int
        Number of candidates scored.
    iterations : int
        Number of batches (score-function calls).
    """

    value: float
    score: float
    runner_up: float
    evaluations: int
    iterations: int

    @property
    def margin(self) -> float:
        """``score - runner_up`` (``score`` itself if there was no runner-up)."""
        return self.score - self.runner_up if np.isfinite(self.runner_up) else self.score


def interval_search(
    score: Callable[[np.ndarray], np.ndarray] | None,
    lo: float,
    hi: float,
    *,
    divisions: int = 8,
    min_step: float,
    start: float | None = None,
    interval: float | None = None,
    periodic: float | None = None,
    prefer: float | None = None,
    run: Callable | None = None,
) -> SearchResult:
    """Maximise a 1-D score by coarse-to-fine interval search (seed 004 Alg. 1 and 6).

    Parameters
    ----------
    score : callable or None
        Maps candidate values, shape (B,), to scores, shape (B,). Called once per
        iteration with all of that iteration's candidates (None with ``run``).
    lo, hi : float
        Limits of the value (the joint limits; (0, 1] for foreshortening).
    divisions : int
        Number of divisions of each interval (8 in Alg. 1, 5 in Alg. 6).
    min_step : float
        Stop when the interval is no longer larger than this (1 degree in Alg. 1,
        ``1 / length`` in Alg. 6).
    start : float, optional
        Centre of the first interval (default: the middle of the limits). A warm
        start from the previous frame.
    interval : float, optional
        Width of the first interval (default: ``hi - lo``).
    periodic : float, optional
        The period of the value (``2 pi`` for an angle). When the limits span a
        whole period candidates wrap around instead of being clipped, and the result
        is reduced to ``[lo, lo + period)``.
    prefer : float, optional
        Among equal scores pick the candidate nearest this value (default: the
        centre of the current interval). The seed's strict ``>`` keeps the first
        (lowest) one, which for Algorithm 6 favours the shortest segment when the
        silhouette cannot tell (a limb hidden inside the torso); callers pass
        ``prefer=1`` there.
    run : callable, optional
        Does the whole search in one (compiled) call instead of calling ``score``
        per iteration, given what is set up here:
        ``run(lo, hi, centre, warm, width, period, gap_period, prefer, divisions,
        min_step)`` (the first interval's centre, clipped; ``warm``: it is a start
        and competes; ``period``
        > 0 when candidates wrap, ``gap_period`` > 0 when distances are periodic;
        ``prefer`` NaN for none) returns ``(value, score, runner_up, evaluations,
        iterations)``. ``score`` is then not called.

    Returns
    -------
    SearchResult
    """
    if not hi > lo:
        raise ValueError(f"empty search interval [{lo}, {hi}]")
    if divisions < 2 or not min_step > 0:
        raise ValueError("need divisions >= 2 and min_step > 0")
    lo, hi = float(lo), float(hi)  # Python floats: the same arithmetic, less overhead
    wrap = periodic is not None and hi - lo >= periodic - 1e-12
    width = float(hi - lo if interval is None else min(interval, hi - lo))
    best = 0.5 * (lo + hi) if start is None else float(start)
    if not wrap:
        best = min(max(best, lo), hi)  # np.clip of a scalar
    period = float(periodic) if wrap else 0.0  # candidates wrap around
    gap_period = float(periodic) if periodic is not None else 0.0  # distances do
    if run is not None:
        return SearchResult(*run(lo, hi, best, start is not None, width, period, gap_period,
                                 np.nan if prefer is None else float(prefer), int(divisions),
                                 float(min_step)))
    step = width / divisions
    first_step = step
    best_score = -np.inf
    values, scores = [], []
    iterations = 0
    kernels = _kernels()
    # Always run at least once, even when the first interval is already small.
    while True:
        begin, end = best - width / 2, best + width / 2
        if not wrap:
            begin, end = max(begin, lo), min(end, hi)
        n = math.floor((end - begin) / step + 1e-9) + 1
        # a warm start is itself a candidate, so a search never ends worse than it
        # began (beyond the seed, whose grid may step over the previous value)
        warm = iterations == 0 and start is not None
        cand = _candidates(kernels, begin, step, n, best if warm else None, lo, period)
        s = np.asarray(score(cand), dtype=float)
        iterations += 1
        values.append(cand)
        scores.append(s)
        k = _pick(kernels, cand, s, best if prefer is None else prefer, gap_period)
        sk = float(s[k])
        if sk > best_score + 1e-12:
            best_score, best = sk, float(cand[k])
        width = 2 * width / divisions
        step = 2 * step / divisions
        if not width > min_step:
            break
    runner = _runner_up(kernels, np.concatenate(values), np.concatenate(scores), best, period,
                        first_step * 1.01)
    return SearchResult(best, best_score, runner, int(sum(v.size for v in values)), iterations)


# The steps of one iteration of interval_search, each as a compiled/numpy pair that
# computes the same floats (the compiled helpers repeat the numpy operations).
def _candidates(kernels, begin, step, n, warm, lo, period):
    """``n`` candidates ``step`` apart from ``begin`` (wrapped into ``[lo, lo + period)``
    when ``period`` > 0), and the warm start ``warm`` after them unless it is None."""
    if kernels is None:
        return _candidates_numpy(begin, step, n, warm, lo, period)
    return _candidates_compiled(kernels, begin, step, n, warm, lo, period)


def _candidates_compiled(kernels, begin, step, n, warm, lo, period):
    cand = np.empty(n + (warm is not None))
    if warm is not None:
        kernels.search_grid_start(begin, step, warm, lo, period, cand)
    else:
        kernels.search_grid(begin, step, lo, period, cand)
    return cand


def _candidates_numpy(begin, step, n, warm, lo, period):
    cand = begin + step * np.arange(n)
    if warm is not None:
        cand = np.append(cand, warm)
    if period:
        cand = lo + np.mod(cand - lo, period)
    return cand


def _pick(kernels, cand, s, centre, gap_period) -> int:
    """Index of the best score, ties to the candidate nearest ``centre`` (distances
    periodic when ``gap_period`` > 0)."""
    if kernels is not None:
        return kernels.search_pick(cand, s, float(centre), gap_period)
    top = s >= s.max() - 1e-12
    gap = np.abs(cand[top] - centre)
    if gap_period:
        gap = np.minimum(np.mod(gap, gap_period), gap_period - np.mod(gap, gap_period))
    return int(np.flatnonzero(top)[np.argmin(gap)])


def _runner_up(kernels, values, scores, best, period, far) -> float:
    """The best score among ``values`` more than ``far`` from ``best`` (-inf: none)."""
    if kernels is not None:
        return float(kernels.search_runner(values, scores, best, period, far))
    dist = np.abs(values - best)
    if period:
        dist = np.minimum(dist, period - dist)
    keep = dist > far
    return float(scores[keep].max()) if keep.any() else -np.inf


def _as_shape(x, shape) -> np.ndarray:
    """``x`` as a float array of ``shape`` (``np.broadcast_to`` only when needed)."""
    if isinstance(x, np.ndarray) and x.shape == shape and x.dtype == np.float64:
        return x
    if isinstance(x, (float, int)):
        return np.full(shape, float(x))
    return np.broadcast_to(np.asarray(x, dtype=float), shape)


def interval_search_many(
    score: Callable[[np.ndarray], np.ndarray] | None,
    lo,
    hi,
    *,
    divisions: int = 8,
    min_step: float,
    start=None,
    interval=None,
    periodic: float | None = None,
    prefer=None,
    run: Callable | None = None,
):
    """Run several independent :func:`interval_search` es in lockstep, one batch each step.

    Parameters
    ----------
    score : callable or None
        Maps candidates, shape (N, B), to scores, shape (N, B): row ``k`` holds
        search ``k``'s candidates. Called once per iteration for all N searches
        (not with ``run``).
    lo, hi, start, interval, prefer : array_like, shape (N,) (or scalars)
        As in :func:`interval_search`, per search (a NaN ``prefer``: none).
    divisions, min_step, periodic
        As in :func:`interval_search`, shared (``min_step`` is the smallest one
        wanted; every search runs the same number of iterations).
    run : callable, optional
        Does the whole search in one (compiled) call instead of calling ``score``
        per iteration: ``run(centre, width, lo, hi, clip, period, gap_period, warm,
        prefer, divisions, min_step)`` (arrays (N,) as set up here, ``centre`` overwritten with the
        values found; ``clip``: keep candidates within the limits; ``prefer`` NaN
        for none) returns ``(score, runner_up, iterations)``.

    Returns
    -------
    value, score, runner_up : numpy.ndarray, shape (N,)
    iterations : int
    """
    shape = np.broadcast_shapes(*(np.shape(x) for x in (lo, hi, start, interval, prefer)
                                  if x is not None))
    shape = shape if shape else (1,)
    lo = _as_shape(lo, shape)
    hi = _as_shape(hi, shape)
    if not np.all(hi > lo):
        raise ValueError("empty search interval")
    n_search = lo.size
    wrap = periodic is not None and np.all(hi - lo >= periodic - 1e-12)
    width = hi - lo if interval is None else np.minimum(_as_shape(interval, lo.shape),
                                                        hi - lo)
    width = np.array(width, dtype=float)
    best = 0.5 * (lo + hi) if start is None else np.array(_as_shape(start, lo.shape),
                                                          dtype=float)
    if not wrap:
        best = np.clip(best, lo, hi)
    step = width / divisions
    kernels = _kernels()
    if kernels is None and run is None:
        return _many_numpy(score, lo, hi, best, width, step, wrap, periodic, start is not None,
                           prefer, divisions, min_step)
    period = float(periodic) if wrap else 0.0
    gap_period = float(periodic) if periodic is not None else 0.0
    lo_c, hi_c = np.ascontiguousarray(lo), np.ascontiguousarray(hi)
    pref = np.full(n_search, np.nan) if prefer is None else np.array(
        _as_shape(prefer, lo.shape), dtype=float)
    best = np.array(best, dtype=float)  # a copy: run writes into it
    if run is not None:
        score_, runner, iterations = run(best, np.ascontiguousarray(width, dtype=float),
                                         lo_c, hi_c, not wrap, period, gap_period,
                                         start is not None, pref, int(divisions),
                                         float(min_step))
        return best, score_, runner, iterations
    return _many_compiled(kernels, score, lo_c, hi_c, best, width, step, wrap, period,
                          gap_period, start is not None, pref, divisions, min_step)


def _many_compiled(kernels, score, lo, hi, best, width, step, wrap, period, gap_period, warm,
                   pref, divisions, min_step):
    """:func:`interval_search_many`'s iterations with the compiled grid, pick and
    runner-up helpers (the same floats as :func:`_many_numpy`); ``best`` (N,) is
    written in place."""
    n_search = lo.size
    first_step = step.copy()
    best_score = np.full(n_search, -np.inf)
    values, scores = [], []
    iterations = 0
    while True:
        first = iterations == 0 and warm
        cand = np.empty((n_search, divisions + 1 + first))
        kernels.many_grid(best, width, step, lo, hi, not wrap, period, first, cand)
        s = np.ascontiguousarray(score(cand), dtype=float)
        iterations += 1
        values.append(cand)
        scores.append(s)
        kernels.many_pick(cand, s, pref, gap_period, best, best_score)
        width = 2 * width / divisions
        step = 2 * step / divisions
        if not np.any(width > min_step):
            break
    runner = np.empty(n_search)
    kernels.many_runner(np.concatenate(values, axis=1), np.concatenate(scores, axis=1), best,
                        period, first_step * 1.01, runner)
    return best, best_score, runner, iterations


def _many_numpy(score, lo, hi, best, width, step, wrap, periodic, warm, prefer, divisions,
                min_step):
    """:func:`interval_search_many`'s iterations in numpy."""
    n_search = lo.size
    first_step = step.copy()
    best_score = np.full(n_search, -np.inf)
    rows = np.arange(n_search)
    k = np.arange(divisions + 1)
    values, scores = [], []
    iterations = 0
    while True:
        begin, end = best - width / 2, best + width / 2
        if not wrap:
            begin, end = np.maximum(begin, lo), np.minimum(end, hi)
        cand = begin[:, None] + step[:, None] * k[None, :]
        cand = np.minimum(cand, end[:, None] + 1e-9 * step[:, None])  # clipped: repeats
        if iterations == 0 and warm:
            cand = np.concatenate([cand, best[:, None]], axis=1)  # the start competes too
        if wrap:
            cand = lo[:, None] + np.mod(cand - lo[:, None], periodic)
        s = np.asarray(score(cand), dtype=float)
        iterations += 1
        values.append(cand)
        scores.append(s)
        centre = best if prefer is None else np.where(
            np.isnan(np.broadcast_to(prefer, lo.shape)), best, prefer)  # NaN: no preference
        top = s >= s.max(axis=1, keepdims=True) - 1e-12
        gap = np.abs(cand - centre[:, None])
        if periodic is not None:
            gap = np.minimum(np.mod(gap, periodic), periodic - np.mod(gap, periodic))
        dist = np.where(top, gap, np.inf)
        j = np.argmin(dist, axis=1)
        better = s[rows, j] > best_score + 1e-12
        best_score = np.where(better, s[rows, j], best_score)
        best = np.where(better, cand[rows, j], best)
        width = 2 * width / divisions
        step = 2 * step / divisions
        if not np.any(width > min_step):
            break
    values = np.concatenate(values, axis=1)
    scores = np.concatenate(scores, axis=1)
    dist = np.abs(values - best[:, None])
    if wrap:
        dist = np.minimum(dist, periodic - dist)
    far = dist > first_step[:, None] * 1.01
    runner = np.where(far, scores, -np.inf).max(axis=1)
    return best, best_score, runner, iterations


__all__ = ["SearchResult", "interval_search", "interval_search_many"]
