"""The fit's searches of one parameter: Algorithm 1 (angles), the lockstep group
search, the lateral spread and the whole-model shift.

Each move takes the engine of the frame (:class:`~vidcap.video.fit.engine._MaskEngine`) and
a :class:`~vidcap.video.fit.state.FitState`, and returns the new state (and, where a caller
reads it, the :class:`~vidcap.video.fit.search.SearchResult`). Algorithm 6
(foreshortening) is :mod:`vidcap.video.fit.foreshortening`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from vidcap.body import SEGMENT_NAMES
from vidcap.video.fit.candidates import NOWHERE, limb_ends, limb_search_compiled, pose_ends, search
from vidcap.video.fit.engine import _MaskEngine, fit_kernels
from vidcap.video.fit.limits import (
    CHILD,
    DESCENDANT_OF,
    LIMITS,
    ONE_DEGREE,
    THIGH_WIDE,
    TWO_PI,
    S,
    into_range,
)
from vidcap.video.fit.modes import SEARCH_POSE_ANGLES, SEARCH_POSE_SPREAD
from vidcap.video.fit.raster import (
    _DIST,
    _PROX,
    _carray,
    direction,
    group_scorer,
    group_span_tables,
    image_angle,
    shift_overlaps,
)
from vidcap.video.fit.search import SearchResult, interval_search_many
from vidcap.video.fit.similarity import similarity_from_counts
from vidcap.video.fit.state import FitState, hang


def search_angle(eng: _MaskEngine, st: FitState, seg: int, *, with_segments=(), lo=None,
                 hi=None, rows=None, start=None, interval=None, min_step=ONE_DEGREE,
                 divisions=8, prefer=None) -> tuple[FitState, SearchResult]:
    """Algorithm 1 on segment ``seg`` (``with_segments`` rotate rigidly with it).

    Reads the whole pose; writes ``angles``, ``scores`` and ``margins`` of ``seg``
    (and ``with_segments``) and draws them. ``lo``, ``hi``: limits, radians (default
    Table 3.3's); ``rows``: the rows scored, normalised px; ``prefer``: the angle
    that wins ties (default: the centre of the interval).
    """
    lim_lo, lim_hi = LIMITS[SEGMENT_NAMES[seg]]
    lo = lim_lo if lo is None else lo
    hi = lim_hi if hi is None else hi
    periodic = TWO_PI if hi - lo >= TWO_PI - 1e-9 else None
    if start is not None and periodic is None:
        # keep a warm start's interval inside the limits (angles are periodic)
        start = into_range(start, lo, hi)
    if prefer is not None and periodic is None:
        prefer = into_range(prefer, lo, hi)
    # the interval search's arguments spelled out, not passed on as **kwargs: a call
    # with ** is not inlined by the interpreter (every move pays it)
    limb = seg >= 2 and not with_segments
    if limb:
        st = st.drawing(seg)
        res = limb_search_compiled(eng, st, seg, "angle", eng.L[seg] * st.fore[seg], rows, lo,
                                   hi, divisions=divisions, min_step=min_step, start=start,
                                   interval=interval, periodic=periodic, prefer=prefer)
        if res is not None:
            return st.with_entries(angles=(seg, np.mod(res.value, TWO_PI)),
                                   scores=(seg, res.score), margins=(seg, res.margin)), res
    together = [seg, *with_segments]
    offsets = st.angles[together] - st.angles[seg]
    st = st.drawing(together)
    moving = np.flatnonzero(st.drawn & DESCENDANT_OF[together].any(axis=0))
    if limb:
        ends = limb_ends(eng, st, seg, moving, "angle", eng.L[seg] * st.fore[seg])
    else:
        def make(v, root, ang, fore, spread):
            ang[:, together] = v[:, None] + offsets
            return root, ang, fore, spread

        ends = pose_ends(eng, st, make, moving, (SEARCH_POSE_ANGLES, together, offsets,
                                                 NOWHERE, 0.0))
    res = search(eng, st, ends, moving, rows, lo, hi, divisions=divisions, min_step=min_step,
                 start=start, interval=interval, periodic=periodic, prefer=prefer)
    return st.with_entries(angles=(together, np.mod(res.value + offsets, TWO_PI)),
                           scores=(together, res.score), margins=(together, res.margin)), res


@dataclass(frozen=True)
class _GroupConstants:
    """What :func:`search_group` needs of its segments alone (cached)."""

    segs: np.ndarray  # (N,) int64
    child: np.ndarray  # (N,) int64: the child each moves (itself for a leaf)
    n_k: int  # 2 if any has a child, else 1
    limits: np.ndarray  # (N, 2) angle limits, radians (thighs: THIGH_WIDE)
    arm: np.ndarray  # (N,) bool: an arm segment (hangs down on ties)


@functools.lru_cache(maxsize=32)
def _group_constants(segs: tuple[int, ...]) -> _GroupConstants:
    s = np.array(segs, dtype=np.int64)
    child = np.array([x if CHILD[x] < 0 else CHILD[x] for x in segs], dtype=np.int64)
    limits = np.array([THIGH_WIDE if "upper_leg" in SEGMENT_NAMES[x]
                       else LIMITS[SEGMENT_NAMES[x]] for x in segs], dtype=float)
    arm = np.array([SEGMENT_NAMES[x].endswith("arm") for x in segs])
    for x in (s, child, limits, arm):
        x.flags.writeable = False
    return _GroupConstants(s, child, 1 if bool((child == s).all()) else 2, limits, arm)


def search_group(eng: _MaskEngine, st: FitState, segs, *, kind="angle", start=None,
                 interval=None, lo=None, hi=None, divisions=8, min_step=ONE_DEGREE,
                 prefer=None) -> FitState:
    """Search one parameter of several limb segments at once (beyond the seed).

    The searches run in lockstep (:func:`interval_search_many`): every
    iteration scores all segments' candidates in one batch, each against the
    model without that segment (and its child), counted from row spans. Each
    segment's search is Algorithm 1 (``kind='angle'``) or Algorithm 6
    (``kind='fore'``) exactly as alone; only the order differs (each sees the
    others as they were when the group started). Draws every segment; writes
    ``angles`` (or ``fore``), ``scores`` and ``margins`` of ``segs``.

    Parameters
    ----------
    segs : sequence of int
        Segments other than the torso (a segment moves itself and, for an upper
        limb, its lower limb).
    """
    consts = _group_constants(tuple(int(x) for x in segs))
    segs = consts.segs
    n = len(segs)
    st = st.drawing(slice(None))
    length = eng.L[segs]
    if kind == "angle":
        lo_a = consts.limits[:, 0] if lo is None else lo
        hi_a = consts.limits[:, 1] if hi is None else hi
        st_a = np.array(st.angles[segs] if start is None else start, dtype=float)
        full = hi_a - lo_a >= TWO_PI - 1e-9
        # a full circle is searched as the circle centred on the start (no wrap);
        # a limited range with the start unwrapped into it
        st_a = np.where(full, st_a, into_range(st_a, lo_a, hi_a))
        lo_a = np.where(full, st_a - np.pi, lo_a)
        hi_a = np.where(full, st_a + np.pi, hi_a)
        if prefer is None:  # hidden arms hang down on ties
            prefer = np.where(consts.arm, hang(st), np.nan)
        form, scale, periodic = "angle", length * st.fore[segs], TWO_PI
    else:
        step = 1.0 / np.maximum(length, 1.0)
        lo_a, hi_a, min_step, prefer = step, np.ones(n), float(step.min()), 1.0
        st_a = st.fore[segs] if start is None else start
        form, periodic = "ratio", None
        scale = direction(st.angles[segs]) * length[:, None]
    kernels = fit_kernels()
    args = (consts, form, scale, lo_a, hi_a, st_a, interval, periodic, prefer, divisions,
            min_step)
    if kernels is not None and divisions >= 3:  # the whole search, one compiled call
        value, best, runner = _group_compiled(kernels, eng, st, *args)
    else:  # batch by batch
        value, best, runner = _group_numpy(eng, st, *args)
    margins = (segs, np.where(np.isfinite(runner), best - runner, best))
    if kind == "angle":
        return st.with_entries(angles=(segs, np.mod(value, TWO_PI)), scores=(segs, best),
                               margins=margins)
    return st.with_entries(fore=(segs, value), scores=(segs, best), margins=margins)


def _group_compiled(kernels, eng, st, consts, form, scale, lo, hi, start, interval, periodic,
                    prefer, divisions, min_step):
    """:func:`search_group`'s search as one compiled call (:func:`_kernels.group_fit`)."""
    n = len(consts.segs)
    current = (st.angles if form == "angle" else st.fore)[consts.segs]
    f64 = np.float64
    if form == "angle":
        sign, k0 = -1.0, _carray(scale, f64)
        k1 = k0
    else:
        sign, k0, k1 = 1.0, _carray(scale[:, 0], f64), _carray(scale[:, 1], f64)
    best, best_score, runner = np.empty(n), np.empty(n), np.empty(n)

    def full(x, default):
        if x is None:
            return np.full(n, default)
        return np.full(n, float(x)) if np.ndim(x) == 0 else _carray(x, f64)

    it = kernels.group_fit(
        *eng.ends(st), eng.R_c, eng.L_c, consts.segs, consts.child, consts.n_k, eng.sil_c,
        bool(eng.caps), int(eng.sil_rows[-1]), full(lo, 0.0), full(hi, 0.0), full(start, 0.0),
        full(interval, 0.0), interval is not None, 0.0 if periodic is None else float(periodic),
        True, full(prefer, np.nan), int(divisions), float(min_step), form == "angle", sign, k0,
        k1, current, best, best_score, runner)
    if it < 0:
        raise ValueError("empty search interval")
    return best, best_score, runner


def _group_numpy(eng, st, consts, form, scale, lo, hi, start, interval, periodic, prefer,
                 divisions, min_step):
    """:func:`search_group`'s search batch by batch (without the compiled kernels, or
    with fewer than 3 divisions)."""
    segs, child = consts.segs, consts.child
    j = eng.joints(st)
    own0, own1 = j[_PROX[segs]], j[_DIST[segs]]
    # every candidate of search n (and the pair as it is) lies within the segment's
    # and its child's full lengths of the segment's proximal joint (angles turn it,
    # ratios are at most 1): its table needs only those rows (+ margins)
    reach = eng.L[segs] + np.where(child != segs, eng.L[child], 0.0) + eng.R.max() + 4
    rows = np.stack([np.floor(own0[:, 1] - reach), np.ceil(own0[:, 1] + reach) + 1], 1)
    cum, m_base, i_base = group_span_tables(j[_PROX], j[_DIST], eng.R, segs, child, eng.sil_c,
                                            rows=rows.astype(np.int64), caps=eng.caps)
    ch0, ch1 = j[_PROX[child]], j[_DIST[child]]
    leaf = child == segs
    radii = np.ascontiguousarray(eng.R[np.stack([segs, child], 1)][:, :consts.n_k])
    scores = group_scorer(form, scale, own0, own1, ch0, ch1, leaf, radii, cum,
                          int(eng.sil_rows[-1]), m_base, i_base, caps=eng.caps)
    value, best, runner, _ = interval_search_many(
        scores, lo, hi, divisions=divisions, min_step=min_step, start=start,
        interval=interval, prefer=prefer, periodic=periodic)
    return value, best, runner


_UPPERS = np.array([S["l_upper_arm"], S["r_upper_arm"], S["l_upper_leg"], S["r_upper_leg"]])


def search_spread(eng: _MaskEngine, st: FitState, *, start=None, interval=None,
                  min_step=0.05) -> tuple[FitState, SearchResult]:
    """Lateral spread of shoulders and hips in [0, 1] (beyond the seed).

    Candidates move the shoulders and hips sideways while the elbows and knees
    stay put (the upper limbs pivot and stretch to reach them), so the limbs
    already fitted are not dragged off the silhouette; afterwards the upper
    limbs' ``angles`` and ``fore`` are recomputed from their new ends. Draws
    every segment; writes ``spread``.
    """
    st = st.drawing(slice(None))
    uppers = _UPPERS
    fixed_ends = eng.joints(st)[_DIST[uppers]]

    def make(v, root, ang, fore, spread):
        return root, ang, fore, v

    general = pose_ends(eng, st, make, uppers)

    def ends(v):
        p0, _ = general(v)
        return p0, np.broadcast_to(fixed_ends, p0.shape)

    ends.action = (SEARCH_POSE_SPREAD, [0], [0.0], NOWHERE, 0.0, fixed_ends)
    res = search(eng, st, ends, uppers, None, 0.0, 1.0, divisions=4, min_step=min_step,
                 start=start, interval=interval, prefer=0.5)
    st = st.replace(spread=res.value)
    vec = fixed_ends - eng.joints(st)[_PROX[uppers]]
    st = st.with_entries(angles=(uppers, image_angle(vec)),
                         fore=(uppers, np.clip(np.hypot(*vec.T) / eng.L[uppers], 1e-3, 1.0)))
    return st, res


def search_root(eng: _MaskEngine, st: FitState, axis: int, half_range: float, *,
                rows=None) -> tuple[FitState, float]:
    """Shift the whole model by whole pixels along x (axis 0) or y (axis 1).

    Beyond the seed (which fixes the torso from ratios and the silhouette's
    middle). All shifts in ``[-half_range, half_range]`` (normalised px) are scored
    in one batch as a 1-D cross-correlation of the drawn model with the silhouette
    (``rows``: only those). Writes ``root``; returns the new state and its S.
    """
    n = max(1, int(round(half_range)))
    model = eng.model(st)
    sil = eng.sil
    r0, r1 = 0, eng.h
    if rows is not None:
        r0 = min(max(0, int(rows[0])), eng.h)
        r1 = max(r0, min(eng.h, int(rows[1])))
        sil, model = sil[r0:r1], model[r0:r1]
    sil = sil if axis == 0 else sil.T
    mod = model if axis == 0 else model.T
    i = shift_overlaps(sil, mod, n)  # (2n+1,)
    scores = similarity_from_counts(eng.pixels(r0, r1), np.count_nonzero(mod), i)
    shifts = np.arange(-n, n + 1)
    best = np.flatnonzero(scores >= scores.max() - 1e-12)
    k = best[np.argmin(np.abs(shifts[best]))]
    root = st.root.copy()
    root[axis] += shifts[k]
    return st.replace(root=root), scores[k]


__all__ = ["search_angle", "search_group", "search_root", "search_spread"]
