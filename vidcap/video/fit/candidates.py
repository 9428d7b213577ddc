"""Scoring a move's candidates: end points, count tables, and the search that runs them.

A move (:mod:`vidcap.video.fit.moves`) describes its candidates by an ``ends`` function,
``ends(values) -> (p0, p1)``, each (B, K, 2): the end points of the ``moving``
segments for every candidate value. ``ends`` may carry what the compiled pass needs
instead: ``ends.limb`` (one limb segment's distal end moved, :func:`limb_ends`),
``ends.pose`` and ``ends.action`` (whole candidate poses, :func:`pose_ends`).
:func:`search` runs :func:`~vidcap.video.fit.search.interval_search` over them, as one
compiled call where it can (:func:`_search_compiled`) and batch by batch with
:func:`scorer` otherwise; :func:`limb_search_compiled` is the same for one limb
segment's own angle or ratio. Both paths give the same floats.
"""

from __future__ import annotations

import numpy as np

from vidcap.video.fit.engine import _MaskEngine, fit_kernels
from vidcap.video.fit.limits import CHILD, DIST64, PROX64
from vidcap.video.fit.modes import SEARCH_LIMB_ANGLE, SEARCH_LIMB_RATIO
from vidcap.video.fit.raster import (
    _DIST,
    _KERNEL_TABLES,
    _PROX,
    _carray,
    base_tables,
    direction,
    limb_scorer,
    pose_joints_batch,
    pose_scorer,
    span_similarity,
)
from vidcap.video.fit.search import SearchResult, interval_search
from vidcap.video.fit.state import FitState

# placeholders for the kind of candidate a compiled search does not use (the kernel
# takes both; their types match the real ones, so one compiled version serves)
_NO_LIMB = (0.0, 0.0, 0.0, np.zeros(2), np.zeros(2), np.zeros((1, 2)), np.zeros((1, 2)),
            np.zeros(1))
_NO_POSE = (np.zeros(1, np.int64), np.zeros(1), np.zeros(2), 0.0, np.zeros(2), np.zeros(10),
            np.zeros(10), 0.0, np.zeros(10), np.zeros(2), 0.0, *_KERNEL_TABLES,
            np.zeros(1, np.int64),
            np.zeros(1, np.int64))
NOWHERE = np.zeros(2)  # no neck (an action that does not turn the torso about it)


def searched(out: np.ndarray) -> tuple[float, float, float, int, int]:
    """A compiled search's out (5,) as ``run`` returns it to :func:`interval_search`:
    value, score, runner-up, evaluations, iterations."""
    return float(out[0]), float(out[1]), float(out[2]), int(out[3]), int(out[4])


def still_segments(eng: _MaskEngine, st: FitState, ends, moving, rows):
    """What a search adds its candidates to: the rows searched, the rows its
    candidates can reach, the segments that do not move ((K, 2) ends, (K,) radii)
    and the silhouette's pixels in those rows."""
    r0, r1 = eng.rows(rows)
    still = st.drawn.copy()
    still[moving] = False
    still = np.flatnonzero(still)
    j = eng.joints(st)
    limb = getattr(ends, "limb", None)
    reach = None
    if limb is not None:
        # a limb's candidates stay within its moving segments' full lengths of the
        # fixed proximal joint: the table is needed only in those rows
        y, ext = limb[2][1], float(eng.L[moving].sum() + eng.R.max()) + 4.0
        reach = (int(np.floor(y - ext)), int(np.ceil(y + ext)) + 1)
    return (r0, r1), reach, j[_PROX[still]], j[_DIST[still]], eng.R[still], eng.pixels(r0, r1)


def still_tables(eng: _MaskEngine, st: FitState, ends, moving, rows):
    """The still segments of a search, drawn once (not per candidate): row prefix
    sums of the pixels a candidate may add to the model, the counts of what does
    not move, and the silhouette's pixels in the rows searched."""
    (r0, r1), reach, p0, p1, radii, a = still_segments(eng, st, ends, moving, rows)
    cum, m_base, i_base = base_tables(p0, p1, radii, eng.sil, rows=(r0, r1), reach=reach,
                                      sil_cum=eng.sil_cum[1], caps=eng.caps)
    return (r0, r1), cum, a, np.array([m_base], np.int64), np.array([i_base], np.int64)


def search(eng: _MaskEngine, st: FitState, ends, moving, rows, lo, hi, *, divisions,
           min_step, start=None, interval=None, periodic=None, prefer=None) -> SearchResult:
    """:func:`interval_search` of the candidates ``ends`` describes: one compiled call
    that also sets the search up when ``ends`` carries a pose ``action``
    (:func:`_search_compiled`), else batch by batch with :func:`scorer`."""
    action = getattr(ends, "action", None)
    kernels = fit_kernels()
    moving = np.asarray(moving, dtype=np.int64)
    r0, r1 = eng.rows(rows)
    if kernels is None or divisions < 3 or action is None or r1 <= r0:
        return interval_search(scorer(eng, st, ends, moving, rows), lo, hi, divisions=divisions,
                               min_step=min_step, start=start, interval=interval,
                               periodic=periodic, prefer=prefer)
    return _search_compiled(kernels, eng, st, action, moving, (r0, r1), lo, hi,
                            divisions=divisions, min_step=min_step, start=start,
                            interval=interval, periodic=periodic, prefer=prefer)


def _search_compiled(kernels, eng, st, action, moving, rows, lo, hi, *, divisions, min_step,
                     start, interval, periodic, prefer):
    """:func:`search` of a pose action as one compiled call (:func:`_kernels.pose_fit`)."""
    r0, r1 = rows
    mode, idx, coef, neck, length = action[:5]
    # the spread's candidates hold the moving segments' distal ends still
    fixed = _carray(action[5], np.float64) if len(action) > 5 else _NO_LIMB[6]
    jp0, jp1 = eng.ends(st)
    a = eng.pixels(r0, r1)
    f64 = np.float64
    pose = (np.asarray(idx, np.int64), np.asarray(coef, f64), np.asarray(neck, f64),
            float(length), fixed, _carray(st.root, f64), _carray(st.angles, f64),
            _carray(st.fore, f64), float(st.spread), eng.L_c, eng.shoulder,
            float(eng.hip), *_KERNEL_TABLES)

    def run(lo_, hi_, centre, warm, width, period, gap_period, pref, divisions_, min_step_):
        out = np.empty(5)
        kernels.pose_fit(jp0, jp1, eng.R_c, st.drawn, moving, PROX64, DIST64, mode, *pose,
                         _NO_LIMB, eng.sil_c, eng.sil_cum[1], a, r0, r1, bool(eng.caps), lo_,
                         hi_, divisions_, min_step_, centre, warm, width, period, gap_period,
                         0.0 if np.isnan(pref) else pref, not np.isnan(pref), out)
        return searched(out)

    return interval_search(None, lo, hi, divisions=divisions, min_step=min_step, start=start,
                           interval=interval, periodic=periodic, prefer=prefer, run=run)


def scorer(eng: _MaskEngine, st: FitState, ends, moving, rows=None):
    """Score function for :func:`interval_search`.

    ``ends(values) -> (p0, p1)``, each (B, K, 2), gives the end points of the
    ``moving`` segments for every candidate; every other drawn segment is drawn
    once into a base mask. Counts outside the candidates' bounding window are
    constant and computed once, so a batch only draws and counts its window.
    """
    moving = np.asarray(moving, dtype=int)
    (r0, r1), cum, a, m_base, i_base = still_tables(eng, st, ends, moving, rows)
    radii = eng.R[moving][None]  # (1, K): one table
    limb = getattr(ends, "limb", None)
    tables = {}
    pose = getattr(ends, "pose", None)
    # candidate end points built inside the compiled pass where possible
    if limb is not None:
        limbs = limb_scorer(*limb, radii, cum, a, m_base, i_base, rows=(r0, r1), caps=eng.caps)

        def score_limbs(values):
            return limbs(np.asarray(values, dtype=float))

        return score_limbs
    if pose is not None:
        poses = pose_scorer(eng.L, eng.shoulder, eng.hip, moving, radii, cum, a, m_base,
                            i_base, rows=(r0, r1), caps=eng.caps)

        def score_poses(values):
            return poses(*pose(np.asarray(values, dtype=float)))

        return score_poses

    def score(values):
        p0, p1 = ends(np.asarray(values, dtype=float))
        n_b = len(p0)
        if n_b not in tables:
            tables[n_b] = np.zeros(n_b, np.int64)
        # each candidate's rows are limited to its segments' extent in the kernel
        return span_similarity(_carray(p0, np.float64), _carray(p1, np.float64), radii,
                               cum, a, m_base, i_base, rows=(r0, r1), table=tables[n_b],
                               caps=eng.caps)

    return score


def pose_ends(eng: _MaskEngine, st: FitState, make, moving, action=None):
    """End points from whole candidate poses (torso, head, spread, root searches).

    ``make(v, root, ang, fore, spread) -> (root, ang, fore, spread)`` sets the
    candidates' parameters from the values ``v`` (B,) in the (B, ...) copies of
    ``st``'s. ``action``: what ``make`` does, for the compiled search
    (:func:`search`): ``(mode, idx, coef, neck, length[, fixed])`` with ``mode``
    one of ``vidcap.video.fit.modes.SEARCH_POSE_*`` (``fixed`` (K, 2): the moving segments'
    distal ends, held still by ``SEARCH_POSE_SPREAD``).
    """
    moving = np.asarray(moving, dtype=int)

    def poses(v):
        n = len(v)
        return make(v, np.repeat(st.root[None], n, 0), np.repeat(st.angles[None], n, 0),
                    np.repeat(st.fore[None], n, 0), np.full(n, st.spread))

    def ends(v):
        jb = pose_joints_batch(*poses(v), eng.L, eng.shoulder, eng.hip)
        return jb[:, _PROX[moving]], jb[:, _DIST[moving]]

    ends.pose = poses  # what the scorer's compiled pass needs instead
    ends.action = action
    return ends


def limb_search_compiled(eng: _MaskEngine, st: FitState, seg, form, scale, rows, lo, hi, *,
                         divisions, min_step, start=None, interval=None, periodic=None,
                         prefer=None) -> SearchResult | None:
    """One limb segment's angle (``form='angle'``, ``scale`` its drawn length) or
    foreshortening (``'ratio'``, ``scale`` its full (2,) vector) searched as one
    compiled call that also sets the search up (:func:`_kernels.limb_fit`); None
    where that call does not apply (then :func:`search` of :func:`limb_ends` does
    it, with the same floats)."""
    kernels = fit_kernels()
    if kernels is None or divisions < 3:
        return None
    r0, r1 = eng.rows(rows)
    if r1 <= r0:
        return None
    jp0, jp1 = eng.ends(st)
    if form == "angle":
        mode, sign, k0, k1 = SEARCH_LIMB_ANGLE, -1.0, float(scale), float(scale)
    else:
        mode, sign, k0, k1 = SEARCH_LIMB_RATIO, 1.0, float(scale[0]), float(scale[1])
    a = eng.pixels(r0, r1)
    child = CHILD[seg]

    def run(lo_, hi_, centre, warm, width, period, gap_period, pref, divisions_, min_step_):
        out = np.empty(5)
        kernels.limb_fit(jp0, jp1, eng.R_c, eng.L_c, st.drawn, seg, child, mode, sign, k0, k1,
                         _NO_POSE, eng.sil_c, eng.sil_cum[1], a, r0, r1, bool(eng.caps), lo_,
                         hi_, divisions_, min_step_, centre, warm, width, period, gap_period,
                         0.0 if np.isnan(pref) else pref, not np.isnan(pref), out)
        return searched(out)

    return interval_search(None, lo, hi, divisions=divisions, min_step=min_step, start=start,
                           interval=interval, periodic=periodic, prefer=prefer, run=run)


def limb_ends(eng: _MaskEngine, st: FitState, seg, moving, form, scale):
    """End points when one limb segment's distal end moves (its children follow).

    The segment's new proximal -> distal vector is ``direction(v) * scale``
    (``form='angle'``) or ``v[:, None] * scale`` (``form='ratio'``).
    """
    if form == "angle":
        def vector(v):
            return direction(v) * scale
    else:
        def vector(v):
            return v[:, None] * scale

    j = eng.joints(st)
    moving = np.asarray(moving, dtype=int)
    p0s, p1s = j[_PROX[moving]], j[_DIST[moving]]
    own = moving == seg
    start, old_end = j[_PROX[seg]], j[_DIST[seg]]

    def ends(v):
        delta = start + vector(v) - old_end  # (B, 2)
        p0 = p0s[None] + delta[:, None] * ~own[None, :, None]
        p1 = p1s[None] + delta[:, None]
        return p0, p1

    ends.limb = (form, scale, start, old_end, p0s, p1s, own)  # for the compiled pass
    return ends


__all__ = ["limb_ends", "limb_search_compiled", "pose_ends", "scorer", "search"]
