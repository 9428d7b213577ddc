"""Compiled kernels of :mod:`vidcap.video.fit.raster` (numba; imported lazily from there,
and importing nothing of it: the constants both read are in :mod:`vidcap.video.fit.modes`).

Module-level functions so that numba's on-disk cache (``cache=True``) is reused by
later processes instead of compiling again. No fastmath: :func:`span_setup` and
:func:`span_row` compute a segment's row span with exactly the float operations of
:func:`vidcap.video.fit.raster.segment_spans`, so the compiled and numpy paths cover the
same pixels (tests/fit/test_fit_raster.py checks it).

Loops over rows read a segment's set-up as a tuple of floats, not as the view
``setup[k]``: numba counts references to each array view it makes and to each array
an inlined function takes (atomic increments, which cost more than a row's span).
"""

import math
from pathlib import Path

import numba
import numpy as np

from vidcap.kernelcache import refresh_when_changed
from vidcap.video.fit.modes import (
    SEARCH_LIMB_ANGLE,
    SEARCH_LIMB_RATIO,
    SEARCH_POSE_ANGLES,
    SEARCH_POSE_FORE,
    SEARCH_POSE_SPREAD,
    SEARCH_POSE_TORSO_NECK,
)


@numba.njit(cache=True, nogil=True, inline="always")
def span_setup(x0, y0, x1, y1, r, out):
    """The row-independent part of a segment's row span (:func:`span_row`) into out (9,).

    Segment (x0, y0)-(x1, y1) of half-width r; computed once per segment rather
    than once per row, with the same floats as ``segment_spans``.
    """
    vx = x1 - x0
    vy = y1 - y0
    norm = np.sqrt(vx * vx + vy * vy)
    if norm < 1e-9:
        ux, uy = 1.0, 0.0
    else:
        ux, uy = vx / norm, vy / norm
    if abs(ux) < 1e-12:
        ux = 1e-12
    if abs(uy) < 1e-12:
        uy = 1e-12
    out[0] = 0.5 * (x0 + x1)  # cx
    out[1] = 0.5 * (y0 + y1)  # cy
    out[2] = abs((0.5 * norm + 1e-7) / ux)  # half_a
    out[3] = abs((r + 1e-7) / uy)  # half_c
    out[4] = uy / ux
    out[5] = ux / uy
    out[6] = x0
    out[7] = y0
    out[8] = r


@numba.njit(cache=True, nogil=True, inline="always")
def span_row(q, x1, y1, y, caps):
    """(first, last) covered column (floats, integral) of a segment on row y.

    q: :func:`span_setup` of the segment, whose distal end is (x1, y1); caps: round
    ends. The same floats as ``segment_spans``.
    """
    cx = q[0]
    dyc = y - q[1]
    half_a = q[2]
    half_c = q[3]
    mid_a = cx - dyc * q[4]
    mid_c = cx + dyc * q[5]
    left = max(mid_a - half_a, mid_c - half_c)
    right = min(mid_a + half_a, mid_c + half_c)
    if caps:
        r = q[8]
        x0 = q[6]
        if left > right:
            left, right = np.inf, -np.inf
        d = y - q[7]
        qq = r * r - d * d
        if qq >= 0:
            h = np.sqrt(qq)
            left = min(left, x0 - h)
            right = max(right, x0 + h)
        d = y - y1
        qq = r * r - d * d
        if qq >= 0:
            h = np.sqrt(qq)
            left = min(left, x1 - h)
            right = max(right, x1 + h)
    return (np.ceil(min(max(left, -1e6), 1e6)), np.floor(min(max(right, -1e6), 1e6)))


@numba.njit(cache=True, nogil=True, inline="always")
def span_cols(q, x1, y1, y, caps, w):
    """:func:`span_row` as the columns ``[f, e)`` of an image w pixels wide (ints; e <= f:
    the segment covers nothing on the row)."""
    lo, hi = span_row(q, x1, y1, y, caps)
    f = int(min(max(lo, 0.0), w))
    return f, int(min(max(hi + 1.0, float(f)), w))


@numba.njit(cache=True, nogil=True, inline="always")
def span_cols_flat(q, y0, y1, w, first, last):
    """:func:`span_cols` of a segment without caps on rows y0 <= y < y1 into ``first``,
    ``last`` [y]: the same floats, in a loop without branches (which the compiler
    vectorises)."""
    cx, cy, half_a, half_c, s_a, s_c = q[0], q[1], q[2], q[3], q[4], q[5]
    fw = float(w)
    for y in range(y0, y1):
        dyc = float(y) - cy
        mid_a = cx - dyc * s_a
        mid_c = cx + dyc * s_c
        left = max(mid_a - half_a, mid_c - half_c)
        right = min(mid_a + half_a, mid_c + half_c)
        lo = np.ceil(min(max(left, -1e6), 1e6))
        hi = np.floor(min(max(right, -1e6), 1e6))
        f = min(max(lo, 0.0), fw)
        first[y] = int(f)
        last[y] = int(min(max(hi + 1.0, f), fw))


@numba.njit(cache=True, nogil=True, inline="always")
def row_range(p0, p1, radii, b, y0, y1):
    """Rows y0 <= y < y1 that candidate b's segments may cover (a conservative window).

    Every covered pixel centre lies within a segment's radius of its end points'
    rows (rectangle and capsule alike), so rows outside add nothing.
    """
    lo, hi = np.inf, -np.inf
    for k in range(p0.shape[1]):
        r = radii[k]
        lo = min(lo, p0[b, k, 1] - r, p1[b, k, 1] - r)
        hi = max(hi, p0[b, k, 1] + r, p1[b, k, 1] + r)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return y0, y1
    return max(y0, min(y1, int(np.floor(lo)) - 1)), min(y1, max(y0, int(np.ceil(hi)) + 2))


@numba.njit(cache=True, nogil=True, inline="always")
def insert_run(first, last, n, f, e):
    """Insert the column run ``[f, e)`` into the ``n`` runs sorted by first column
    (insertion sort, a handful of segments per row); returns the new count."""
    j = n
    while j > 0 and first[j - 1] > f:
        first[j] = first[j - 1]
        last[j] = last[j - 1]
        j -= 1
    first[j] = f
    last[j] = e
    return n + 1


@numba.njit(cache=True, nogil=True, inline="always")
def merge_runs(first, last, n):
    """Merge ``n`` runs sorted by first column into disjoint runs, in place; returns
    how many there are."""
    if n == 0:
        return 0
    out = 0
    s, e = first[0], last[0]
    for k in range(1, n):
        if first[k] <= e:
            if last[k] > e:
                e = last[k]
            continue
        first[out] = s
        last[out] = e
        out += 1
        s, e = first[k], last[k]
    first[out] = s
    last[out] = e
    return out + 1


@numba.njit(cache=True, nogil=True, inline="always")
def count_one(p0, p1, radii, b, cum, t, y0, y1, caps, first, last, setup, out):
    """Add candidate b's merged-span weights (table t, rows y0..y1-1) to out (C,).

    setup (K, 11) is scratch: :func:`span_setup` per segment, then the rows it can reach.
    """
    n_k = p0.shape[1]
    w = cum.shape[3] - 1
    n_c = cum.shape[1]
    for k in range(n_k):
        span_setup(p0[b, k, 0], p0[b, k, 1], p1[b, k, 0], p1[b, k, 1], radii[k], setup[k])
        # rows the segment can cover (as row_range; elsewhere its span is empty)
        rad = radii[k]
        setup[k, 9] = np.floor(min(p0[b, k, 1], p1[b, k, 1]) - rad) - 1.0
        setup[k, 10] = np.ceil(max(p0[b, k, 1], p1[b, k, 1]) + rad) + 2.0
    for y in range(y0, y1):
        m = 0
        fy = float(y)
        for k in range(n_k):
            if fy < setup[k, 9] or fy >= setup[k, 10]:
                continue
            q = (setup[k, 0], setup[k, 1], setup[k, 2], setup[k, 3], setup[k, 4],
                 setup[k, 5], setup[k, 6], setup[k, 7], setup[k, 8])  # not a view
            f, e = span_cols(q, p1[b, k, 0], p1[b, k, 1], fy, caps, w)
            if e <= f:
                continue
            m = insert_run(first, last, m, f, e)
        for r in range(merge_runs(first, last, m)):
            for c in range(n_c):
                out[c] += cum[t, c, y, last[r]] - cum[t, c, y, first[r]]


@numba.njit(cache=True, nogil=True)
def counts(p0, p1, radii, table, cum, y0, y1, caps, out):
    """out[b, c] = weights of channel c under candidate b's segments, rows y0..y1-1.

    p0, p1 (B, K, 2), radii (B, K), table (B,) int64, cum (T, C, h, w + 1) int32 row
    prefix sums; spans clipped to the image, sorted and merged per row.
    """
    n_b, n_k = p0.shape[0], p0.shape[1]
    first = np.empty(n_k, np.int64)
    last = np.empty(n_k, np.int64)
    setup = np.empty((n_k, 11))
    for b in range(n_b):
        for c in range(cum.shape[1]):
            out[b, c] = 0
        r0, r1 = row_range(p0, p1, radii[b], b, y0, y1)
        count_one(p0, p1, radii[b], b, cum, table[b], r0, r1, caps, first, last, setup, out[b])


@numba.njit(cache=True, nogil=True, inline="always")
def candidate_scratch(n_k):
    """Scratch for scoring one candidate of K segments: ends p0, p1 (1, K, 2), span runs
    first, last (K,), span set-up (K, 9), counts d (2,)."""
    return (np.empty((1, n_k, 2)), np.empty((1, n_k, 2)), np.empty(n_k, np.int64),
            np.empty(n_k, np.int64), np.empty((n_k, 11)), np.zeros(2, np.int64))


@numba.njit(cache=True, nogil=True, inline="always")
def pose_candidate(jb, prox, dist, fixed, p0, p1, radii, cum, y0, y1, caps, first, last, setup,
                   d, a, m0, i0):
    """Eq. 3.3's terms of a pose whose joints are jb (1, 15, 2) and whose segments
    prox[k] -> dist[k] move (one table); with ``fixed`` (K, 2) given (K rows), the
    segments' distal ends stay there instead."""
    for k in range(prox.shape[0]):
        p0[0, k, 0] = jb[0, prox[k], 0]
        p0[0, k, 1] = jb[0, prox[k], 1]
        if fixed.shape[0] == prox.shape[0]:
            p1[0, k, 0] = fixed[k, 0]
            p1[0, k, 1] = fixed[k, 1]
        else:
            p1[0, k, 0] = jb[0, dist[k], 0]
            p1[0, k, 1] = jb[0, dist[k], 1]
    return candidate_terms(p0, p1, radii, 0, cum, 0, y0, y1, caps, first, last, setup, d, a,
                           m0, i0)


@numba.njit(cache=True, nogil=True)
def similarity_terms(p0, p1, radii, table, cum, y0, y1, caps, a, m_base, i_base, x, q):
    """Eq. 3.3's terms for candidate b: S = exp(x[b]) * q[b] (exp taken by numpy).

    As :func:`counts` with cum's channels (pixels added to the model, of which
    silhouette), against table t = table[b] with radii[t] (T, K), m_base[t] and
    i_base[t] the model and overlap counts of what is not moving, ``a`` the
    silhouette count; x = -p - n and q = 1 - p with the float operations of
    ``similarity_from_counts``.
    """
    n_b = p0.shape[0]
    _, _, first, last, setup, d = candidate_scratch(p0.shape[1])
    for b in range(n_b):
        t = table[b]
        x[b], q[b] = candidate_terms(p0, p1, radii[t], b, cum, t, y0, y1, caps, first, last,
                                     setup, d, a, m_base[t], i_base[t])


@numba.njit(cache=True, nogil=True, inline="always")
def _terms(a, m, i):
    """(-p - n, 1 - p) of Eq. 3.3 from counts, the floats of ``similarity_from_counts``."""
    union = a + m - i
    safe = max(union, 1)
    p = (a - i) / safe
    n = (m - i) / safe
    return -p - n, 1.0 - p


@numba.njit(cache=True, nogil=True, inline="always")
def candidate_terms(p0, p1, radii, b, cum, t, y0, y1, caps, first, last, setup, d, a, m0, i0):
    """Eq. 3.3's terms (:func:`_terms`) for candidate b against table t, whose base model
    has m0 pixels, i0 of them on the silhouette; d (2,) is scratch."""
    d[0] = 0
    d[1] = 0
    r0, r1 = row_range(p0, p1, radii, b, y0, y1)
    count_one(p0, p1, radii, b, cum, t, r0, r1, caps, first, last, setup, d)
    return _terms(a, m0 + d[0], i0 + d[1])


@numba.njit(cache=True, nogil=True, inline="always")
def limb_candidate(ca, cb, sign, k0, k1, start, old_end, p0s, p1s, notown, p0, p1, radii, cum,
                   y0, y1, caps, first, last, setup, d, a, m0, i0):
    """Eq. 3.3's terms of one candidate that moves a limb segment's distal end
    (:func:`limb_terms`); p0, p1 (1, K, 2) are scratch."""
    dx = start[0] + ca * k0 - old_end[0]
    dy = start[1] + (sign * cb) * k1 - old_end[1]
    for k in range(p0s.shape[0]):
        p0[0, k, 0] = p0s[k, 0] + dx * notown[k]
        p0[0, k, 1] = p0s[k, 1] + dy * notown[k]
        p1[0, k, 0] = p1s[k, 0] + dx
        p1[0, k, 1] = p1s[k, 1] + dy
    return candidate_terms(p0, p1, radii, 0, cum, 0, y0, y1, caps, first, last, setup, d, a,
                           m0, i0)


@numba.njit(cache=True, nogil=True)
def limb_terms(ca, cb, sign, k0, k1, start, old_end, p0s, p1s, notown, radii, cum, y0, y1,
               caps, a, m_base, i_base, x, q):
    """:func:`similarity_terms` of candidates that move one limb segment's distal end.

    Candidate b's segment vector is (ca[b] * k0, (sign * cb[b]) * k1) (an angle's cos
    and sin times a length, sign -1; or a ratio times a vector, sign 1, ca = cb, the
    floats of the numpy code); every moving segment (p0s, p1s (K, 2))
    shifts by delta = start + vec[b] - old_end, its proximal end only where
    notown[k] = 1.0 (children; 0.0: the segment itself) - the floats of the numpy
    end-point code. One table (cum (1, 2, h, w + 1), radii (1, K)).
    """
    p0, p1, first, last, setup, d = candidate_scratch(p0s.shape[0])
    for b in range(ca.shape[0]):
        x[b], q[b] = limb_candidate(ca[b], cb[b], sign, k0, k1, start, old_end, p0s, p1s,
                                    notown, p0, p1, radii[0], cum, y0, y1, caps, first, last,
                                    setup, d, a, m_base[0], i_base[0])


@numba.njit(cache=True, nogil=True)
def arm_pair_terms(du, dl, shoulder, len_u, len_l, radii, cum, y0, y1, caps, a, m0, i0, x, q):
    """:func:`similarity_terms` of whole-arm candidates: candidate b's elbow is
    shoulder + du[b] * len_u and its wrist elbow + dl[b] * len_l (du, dl (B, 2): the
    upper and lower arm's directions), the floats of the numpy end-point code; the
    upper and lower arm (radii (2,)) against one table.

    The candidates of one upper arm direction (consecutive rows of du) share its row
    spans and their counts: computed once per direction (the spans :func:`count_one`
    computes), summed over rows as prefix sums. A candidate's own work is the rows its
    lower arm can reach: there the union of the two runs counts the upper arm's, plus
    the lower arm's, less their overlap (integers: the counts of the merged runs).
    """
    w = cum.shape[3] - 1
    n_c = cum.shape[1]
    p0, p1, _, _, setup, d = candidate_scratch(2)
    up_f = np.zeros(y1 + 1, np.int64)  # the current upper arm's run on each row: [f, e)
    up_e = np.zeros(y1 + 1, np.int64)
    up_sum = np.zeros((n_c, y1 + 1), np.int64)  # its counts on rows y0 .. y - 1
    low_f = np.zeros(y1 + 1, np.int64)  # the lower arm's
    low_e = np.zeros(y1 + 1, np.int64)
    prev_x, prev_y = np.nan, np.nan
    for b in range(du.shape[0]):
        ex = shoulder[0] + du[b, 0] * len_u
        ey = shoulder[1] + du[b, 1] * len_u
        p0[0, 0, 0] = shoulder[0]
        p0[0, 0, 1] = shoulder[1]
        p1[0, 0, 0] = ex
        p1[0, 0, 1] = ey
        p0[0, 1, 0] = ex
        p0[0, 1, 1] = ey
        p1[0, 1, 0] = ex + dl[b, 0] * len_l
        p1[0, 1, 1] = ey + dl[b, 1] * len_l
        if not (du[b, 0] == prev_x and du[b, 1] == prev_y):  # a new upper arm
            prev_x, prev_y = du[b, 0], du[b, 1]
            span_setup(shoulder[0], shoulder[1], ex, ey, radii[0], setup[0])
            top = np.floor(min(shoulder[1], ey) - radii[0]) - 1.0
            bottom = np.ceil(max(shoulder[1], ey) + radii[0]) + 2.0
            q_up = (setup[0, 0], setup[0, 1], setup[0, 2], setup[0, 3], setup[0, 4],
                    setup[0, 5], setup[0, 6], setup[0, 7], setup[0, 8])  # not a view
            for y in range(y0, y1):
                up_f[y] = 0
                up_e[y] = 0
                fy = float(y)
                if not (fy < top or fy >= bottom):
                    up_f[y], up_e[y] = span_cols(q_up, ex, ey, fy, caps, w)
                for c in range(n_c):
                    n = 0
                    if up_e[y] > up_f[y]:
                        n = cum[0, c, y, up_e[y]] - cum[0, c, y, up_f[y]]
                    up_sum[c, y + 1] = up_sum[c, y] + n
        # the lower arm, on the rows it can reach (as count_one's)
        span_setup(ex, ey, p1[0, 1, 0], p1[0, 1, 1], radii[1], setup[1])
        top = np.floor(min(ey, p1[0, 1, 1]) - radii[1]) - 1.0
        bottom = np.ceil(max(ey, p1[0, 1, 1]) + radii[1]) + 2.0
        r0, r1 = row_range(p0, p1, radii, 0, y0, y1)
        for c in range(n_c):
            d[c] = up_sum[c, r1] - up_sum[c, r0]
        l0 = int(min(max(top, float(r0)), float(r1)))
        l1 = int(min(max(bottom, float(l0)), float(r1)))
        if caps:
            q_low = (setup[1, 0], setup[1, 1], setup[1, 2], setup[1, 3], setup[1, 4],
                     setup[1, 5], setup[1, 6], setup[1, 7], setup[1, 8])  # not a view
            for y in range(l0, l1):
                low_f[y], low_e[y] = span_cols(q_low, p1[0, 1, 0], p1[0, 1, 1], float(y),
                                               caps, w)
        else:
            span_cols_flat(setup[1], l0, l1, w, low_f, low_e)
        for y in range(l0, l1):
            f, e = low_f[y], low_e[y]
            if e <= f:
                continue
            of, oe = max(f, up_f[y]), min(e, up_e[y])  # the overlap with the upper arm's
            for c in range(n_c):
                d[c] += cum[0, c, y, e] - cum[0, c, y, f]
                if oe > of:
                    d[c] -= cum[0, c, y, oe] - cum[0, c, y, of]
        x[b], q[b] = _terms(a, m0 + d[0], i0 + d[1])


@numba.njit(cache=True, nogil=True)
def search_1d(lo, hi, divisions, min_step, best, warm, width, period, gap_period, prefer,
              has_prefer, mode, limb, pose, radii, still, y0, y1, caps, a, out):
    """A whole ``interval_search`` in one call: its loop, with the same grid, tie-break
    and runner-up kernels, scoring each candidate as :func:`limb_terms` or
    :func:`pose_terms` do, S = exp(-p - n) (1 - p).

    cos, sin and exp are libm's here, numpy's in the Python path: the same values
    except where numpy's SIMD functions differ in the last bit.

    ``best``: the first interval's centre (the warm start when ``warm``), clipped
    as ``interval_search`` does; ``width``: the first interval; ``period`` > 0 when
    candidates wrap, ``gap_period`` > 0 when distances are periodic. ``mode``: one
    of the SEARCH_* kinds. ``limb`` = (sign, k0, k1, start, old_end, p0s, p1s,
    notown) as :func:`limb_terms` takes them; ``pose`` = (idx, coef, neck, length,
    root, angles, fore, spread, lengths, shoulder, hip, order, parent, kind, prox,
    dist): the current pose (root (2,), angles, fore (10,), spread), what a value v
    sets (SEARCH_POSE_ANGLES: angles[idx] = v + coef; SEARCH_POSE_TORSO_NECK: the
    torso angle idx[0] = v and the root = neck - direction(v) * length;
    SEARCH_POSE_FORE: fore[idx] = min(v * coef, 1); SEARCH_POSE_SPREAD: spread = v,
    the moving segments' distal ends held at the limb tuple's p1s) and the moving
    segments' joints prox[k] -> dist[k].
    radii (K,): the moving segments'. ``still`` = (p0, p1, radii, sil, sil_cum, f0, f1):
    the segments that do not move and the silhouette, drawn into the search's one
    table here (:func:`base_tables`, rows y0..y1, filled in f0..f1); ``a`` the
    silhouette's pixels in rows y0..y1. out (5,): value, score, runner-up,
    evaluations, iterations. Needs divisions >= 3 (the interval must shrink).
    """
    sign, k0, k1, start, old_end, p0s, p1s, notown = limb
    sp0, sp1, s_radii, sil, sil_cum, f0, f1 = still
    cum = np.zeros((1, 2, sil.shape[0], sil.shape[1] + 1), np.int32)
    m0, i0 = base_tables(sp0, sp1, s_radii, sil, sil_cum, y0, y1, f0, f1, caps, cum[0])
    (idx, coef, neck, length, root, angles, fore, spread, lengths, shoulder, hip, order,
     parent, kind, prox, dist) = pose
    cap = 64 * (divisions + 2)
    values = np.empty(cap)
    scores = np.empty(cap)
    p0, p1, first, last, setup, d = candidate_scratch(radii.shape[0])
    # one candidate pose (pose modes)
    r1 = np.empty((1, 2))
    ang = angles.copy()
    c1 = np.empty((1, 10))
    s1 = np.empty((1, 10))
    cl = np.empty(1)
    sl = np.empty(1)
    f1 = np.empty((1, 10))
    f1[0] = fore
    sp = np.full(1, spread)
    jb = np.empty((1, 15, 2))
    # the spread's candidates keep the moving segments' distal ends where they are
    fixed = p1s if mode == SEARCH_POSE_SPREAD else np.empty((0, 2))
    torso = 0
    step = width / divisions
    first_step = step
    best_score = -np.inf
    used = 0
    iterations = 0
    while True:
        begin, end = best - width / 2, best + width / 2
        if period <= 0:
            begin, end = max(begin, lo), min(end, hi)
        n = int(math.floor((end - begin) / step + 1e-9)) + 1
        extra = 1 if (iterations == 0 and warm) else 0
        if used + n + extra > cap:
            break
        cand = values[used:used + n + extra]
        s = scores[used:used + n + extra]
        if extra:
            search_grid_start(begin, step, best, lo, period, cand)
        else:
            search_grid(begin, step, lo, period, cand)
        for b in range(cand.shape[0]):
            v = cand[b]
            if mode == SEARCH_LIMB_ANGLE or mode == SEARCH_LIMB_RATIO:
                ca, cb = (math.cos(v), math.sin(v)) if mode == SEARCH_LIMB_ANGLE else (v, v)
                x, q = limb_candidate(ca, cb, sign, k0, k1, start, old_end, p0s, p1s, notown,
                                      p0, p1, radii, cum, y0, y1, caps, first, last, setup, d,
                                      a, m0, i0)
            else:
                r1[0, 0] = root[0]
                r1[0, 1] = root[1]
                if mode == SEARCH_POSE_ANGLES:
                    for t in range(idx.shape[0]):
                        ang[idx[t]] = v + coef[t]
                elif mode == SEARCH_POSE_TORSO_NECK:
                    ang[idx[0]] = v
                    r1[0, 0] = neck[0] - math.cos(v) * length
                    r1[0, 1] = neck[1] - (-math.sin(v)) * length
                elif mode == SEARCH_POSE_FORE:
                    for t in range(idx.shape[0]):
                        f1[0, idx[t]] = min(v * coef[t], 1.0)
                else:  # SEARCH_POSE_SPREAD
                    sp[0] = v
                for t in range(10):
                    c1[0, t] = math.cos(ang[t])
                    s1[0, t] = math.sin(ang[t])
                left = ang[torso] + np.pi / 2
                cl[0] = math.cos(left)
                sl[0] = math.sin(left)
                joints(r1, c1, s1, cl, sl, f1, sp, lengths, shoulder, hip, order, parent, kind,
                       jb)
                x, q = pose_candidate(jb, prox, dist, fixed, p0, p1, radii, cum, y0, y1, caps,
                                      first, last, setup, d, a, m0, i0)
            s[b] = math.exp(x) * q
        used += cand.shape[0]
        iterations += 1
        k = search_pick(cand, s, prefer if has_prefer else best, gap_period)
        if s[k] > best_score + 1e-12:
            best_score, best = s[k], cand[k]
        width = 2 * width / divisions
        step = 2 * step / divisions
        if not width > min_step:
            break
    out[0] = best
    out[1] = best_score
    out[2] = search_runner(values[:used], scores[:used], best, period, first_step * 1.01)
    out[3] = used
    out[4] = iterations


@numba.njit(cache=True, nogil=True)
def pose_terms(root, c, s, c_left, s_left, fore, spread, lengths, shoulder, hip, order, parent,
               kind, prox, dist, radii, cum, y0, y1, caps, a, m_base, i_base, x, q):
    """:func:`similarity_terms` of whole candidate poses (as :func:`joints` places them)
    whose segments prox[k] -> dist[k] (joint indices) move. One table."""
    jb = np.empty((1, 15, 2))
    p0, p1, first, last, setup, d = candidate_scratch(prox.shape[0])
    no_fixed = np.empty((0, 2))
    for b in range(root.shape[0]):
        joints(root[b:b + 1], c[b:b + 1], s[b:b + 1], c_left[b:b + 1], s_left[b:b + 1],
               fore[b:b + 1], spread[b:b + 1], lengths, shoulder, hip, order, parent, kind, jb)
        x[b], q[b] = pose_candidate(jb, prox, dist, no_fixed, p0, p1, radii[0], cum, y0, y1,
                                    caps, first, last, setup, d, a, m_base[0], i_base[0])


@numba.njit(cache=True, nogil=True)
def draw(p0, p1, radii, x0, y0, caps, out):
    """Set out[b] (h, w) where any of candidate b's segments covers a pixel centre.

    The window's top-left pixel is (x0, y0) of the full image (floats, integral).
    """
    n_b, n_k = p0.shape[0], p0.shape[1]
    h, w = out.shape[1], out.shape[2]
    setup = np.empty(9)
    one = np.empty(1)
    for b in range(n_b):
        for k in range(n_k):
            x1, y1 = p1[b, k, 0], p1[b, k, 1]
            span_setup(p0[b, k, 0], p0[b, k, 1], x1, y1, radii[b, k], setup)
            # only the rows this segment can reach (the others have empty spans)
            one[0] = radii[b, k]
            i0, i1 = row_range(p0[b:b + 1, k:k + 1], p1[b:b + 1, k:k + 1], one, 0,
                               int(y0), int(y0) + h)
            q = (setup[0], setup[1], setup[2], setup[3], setup[4],
                 setup[5], setup[6], setup[7], setup[8])  # a tuple: not counted
            for i in range(i0 - int(y0), i1 - int(y0)):
                lo, hi = span_row(q, x1, y1, float(y0 + i), caps)
                f = int(min(max(lo - x0, 0.0), w))
                e = int(min(max(hi - x0 + 1.0, float(f)), w))
                for x in range(f, e):
                    out[b, i, x] = True


@numba.njit(cache=True, nogil=True)
def joints(root, c, s, c_left, s_left, fore, spread, lengths, shoulder, hip, order, parent,
           kind, out):
    """out[b] (15, 2): joints of pose b, with the float operations of ``pose_joints``.

    c, s (B, 10): cos and sin of the segment angles; c_left, s_left (B,): of the torso
    angle + pi/2; joints placed in ``order`` from ``parent``, offset by segment
    ``kind[j] >= 0`` or laterally (-1/-2 shoulder +/-, -3/-4 hip +/-). ``shoulder``
    (2,): the shoulders' lateral offset and their drop down the torso from the neck.
    """
    n_b = root.shape[0]
    for b in range(n_b):
        lx = c_left[b] * spread[b]
        ly = -s_left[b] * spread[b]
        out[b, 0, 0] = root[b, 0]
        out[b, 0, 1] = root[b, 1]
        for q in range(order.shape[0]):
            j = order[q]
            p = parent[j]
            k = kind[j]
            if k >= 0:
                fl = fore[b, k] * lengths[k]
                dx = c[b, k] * fl
                dy = -s[b, k] * fl
            elif k >= -2:
                dx = shoulder[0] * lx
                dy = shoulder[0] * ly
                if k == -2:
                    dx = -dx
                    dy = -dy
                if shoulder[1] != 0.0:
                    # down the torso's axis (segment 0, (cos, -sin) of its angle) from
                    # the neck, in pose_joints' order of operations
                    dx = dx - shoulder[1] * c[b, 0]
                    dy = dy - shoulder[1] * -s[b, 0]
            else:
                dx = hip * lx
                dy = hip * ly
                if k == -4:
                    dx = -dx
                    dy = -dy
            out[b, j, 0] = out[b, p, 0] + dx
            out[b, j, 1] = out[b, p, 1] + dy


@numba.njit(cache=True, nogil=True)
def pose_one(root, angles, fore, spread, lengths, shoulder, hip, order, parent, kind, out):
    """:func:`joints` of one pose (root (2,), angles, fore (10,), spread) into out
    (1, 15, 2), its cos and sin taken here (libm; numpy's in ``pose_joints_batch``)."""
    c = np.empty((1, 10))
    s = np.empty((1, 10))
    for t in range(10):
        c[0, t] = math.cos(angles[t])
        s[0, t] = math.sin(angles[t])
    left = angles[0] + np.pi / 2  # the torso's (segment 0) angle + pi/2
    joints(root.reshape((1, 2)), c, s, np.full(1, math.cos(left)), np.full(1, math.sin(left)),
           fore.reshape((1, 10)), np.full(1, spread), lengths, shoulder, hip, order, parent,
           kind, out)


@numba.njit(cache=True, nogil=True)
def base_tables(p0, p1, radii, sil, sil_cum, y0, y1, f0, f1, caps, cum):
    """Row prefix sums of the pixels outside a drawn model, and on the silhouette.

    The model is the union of segments p0, p1 (K, 2), radii (K,), exactly the pixels
    :func:`draw` sets; for rows f0 <= y < f1 (within y0..y1): cum[0, y, x] counts
    pixels of row y left of x not in the model, cum[1, y, x] those also on the
    silhouette (h, w) bool (sil_cum (h, w + 1): its row prefix sums). Returns (model
    pixels, model pixels on the silhouette) in rows y0 <= y < y1, counted from the
    merged spans; the tables' rows are filled from them too, without visiting pixels
    of the silhouette.
    """
    n_k = p0.shape[0]
    w = sil.shape[1]
    m = 0
    i = 0
    setup = np.empty((n_k, 9))
    reach = np.empty((n_k, 2), np.int64)
    first = np.empty(n_k, np.int64)
    last = np.empty(n_k, np.int64)
    one = np.empty(1)
    for k in range(n_k):
        span_setup(p0[k, 0], p0[k, 1], p1[k, 0], p1[k, 1], radii[k], setup[k])
        one[0] = radii[k]
        reach[k, 0], reach[k, 1] = row_range(p0[k:k + 1].reshape(1, 1, 2),
                                             p1[k:k + 1].reshape(1, 1, 2), one, 0, y0, y1)
    for y in range(y0, y1):
        n = 0
        for k in range(n_k):
            if y < reach[k, 0] or y >= reach[k, 1]:
                continue  # the segment does not reach this row
            q = (setup[k, 0], setup[k, 1], setup[k, 2], setup[k, 3], setup[k, 4],
                 setup[k, 5], setup[k, 6], setup[k, 7], setup[k, 8])  # not a view
            f, e = span_cols(q, p1[k, 0], p1[k, 1], float(y), caps, w)
            if e <= f:
                continue
            n = insert_run(first, last, n, f, e)
        n = merge_runs(first, last, n)
        for r in range(n):
            m += last[r] - first[r]
            i += sil_cum[y, last[r]] - sil_cum[y, first[r]]
        if not f0 <= y < f1:
            continue
        # the table's row from the model's runs: between them the prefix sums follow
        # the columns and the silhouette's own, inside them they stay
        gone = 0  # model pixels left of the column, and those on the silhouette
        gone_sil = 0
        col = 0
        for r in range(n + 1):
            stop = first[r] if r < n else w
            for x in range(col, stop + 1):
                cum[0, y, x] = x - gone
                cum[1, y, x] = sil_cum[y, x] - gone_sil
            if r == n:
                break
            c0 = stop - gone
            c1 = sil_cum[y, stop] - gone_sil
            for x in range(stop + 1, last[r] + 1):
                cum[0, y, x] = c0
                cum[1, y, x] = c1
            gone += last[r] - stop
            gone_sil += sil_cum[y, last[r]] - sil_cum[y, stop]
            col = last[r] + 1
    return m, i


@numba.njit(cache=True, nogil=True, inline="always")
def _mod(a, b):
    """numpy's float ``np.mod(a, b)`` (npy_divmod's remainder), for b > 0."""
    m = np.fmod(a, b)
    if m != 0.0:
        if (b < 0) != (m < 0):
            m += b
    else:
        m = math.copysign(0.0, b)
    return m


@numba.njit(cache=True, nogil=True)
def search_grid(begin, step, lo, period, out):
    """One iteration's candidates of ``interval_search``, as its numpy code makes them.

    out[i] = begin + step * i, wrapped into [lo, lo + period) when period > 0.
    """
    n = out.shape[0]
    for i in range(n):
        out[i] = begin + step * float(i)
    if period > 0:
        for i in range(n):
            out[i] = lo + _mod(out[i] - lo, period)


@numba.njit(cache=True, nogil=True)
def search_grid_start(begin, step, start, lo, period, out):
    """:func:`search_grid` with a warm start appended as the last candidate."""
    n = out.shape[0] - 1
    for i in range(n):
        out[i] = begin + step * float(i)
    out[n] = start
    if period > 0:
        for i in range(n + 1):
            out[i] = lo + _mod(out[i] - lo, period)


@numba.njit(cache=True, nogil=True)
def search_pick(cand, s, centre, period):
    """Index of the best score, ties (within 1e-12) to the candidate nearest ``centre``
    (periodic distance when period > 0; the first of equals), as ``interval_search``."""
    top = -np.inf
    for i in range(s.shape[0]):
        if s[i] > top:
            top = s[i]
    thr = top - 1e-12
    k = -1
    best_gap = np.inf
    for i in range(s.shape[0]):
        if s[i] >= thr:
            gap = abs(cand[i] - centre)
            if period > 0:
                g = _mod(gap, period)
                gap = min(g, period - g)
            if k < 0 or gap < best_gap:
                k = i
                best_gap = gap
    return k


@numba.njit(cache=True, nogil=True)
def search_runner(values, scores, best, period, far):
    """Best score among values more than ``far`` from ``best`` (periodic distance when
    period > 0), -inf if none: ``interval_search``'s runner-up."""
    r = -np.inf
    for i in range(values.shape[0]):
        d = abs(values[i] - best)
        if period > 0:
            d = min(d, period - d)
        if d > far and scores[i] > r:
            r = scores[i]
    return r


@numba.njit(cache=True, nogil=True)
def group_span_tables(p0, p1, radii, caps, segs, child, sil, rows, cum, m_base, i_base):
    """Per searched segment n: the model without segs[n] (and child[n]) as row sums.

    The model is the segments p0, p1 (S, 2), radii (S,), counted from their row spans:
    the pixels :func:`draw` would set (the same spans, rows and rounding). A pixel is
    in base n if more segments cover it than the pair's own (child[n] == segs[n]: a
    leaf, counted once). cum[n, 0] / cum[n, 1]: row prefix sums of pixels not in base
    n / of those on the silhouette (h, w), filled for rows rows[n, 0] <= y < rows[n, 1]
    only (the rows search n's candidates can reach; the pair covers nothing outside
    them, so there base n is every covered pixel); m_base[n], i_base[n]: base n's
    pixels / those on the silhouette, over the whole image. The integers of
    ``raster.group_tables`` of the drawn masks.
    """
    n_seg = p0.shape[0]
    h, w = sil.shape
    span_f = np.zeros((h, n_seg), np.int64)  # per row, segment k covers [f, e)
    span_e = np.zeros((h, n_seg), np.int64)
    setup = np.empty(9)
    one = np.empty(1)
    cover = np.zeros((h, w), np.int64)
    for k in range(n_seg):
        span_setup(p0[k, 0], p0[k, 1], p1[k, 0], p1[k, 1], radii[k], setup)
        one[0] = radii[k]
        i0, i1 = row_range(p0[k:k + 1].reshape(1, 1, 2), p1[k:k + 1].reshape(1, 1, 2), one, 0,
                           0, h)
        for y in range(i0, i1):
            q = (setup[0], setup[1], setup[2], setup[3], setup[4],
                 setup[5], setup[6], setup[7], setup[8])  # not a view
            f, e = span_cols(q, p1[k, 0], p1[k, 1], float(y), caps, w)
            span_f[y, k] = f
            span_e[y, k] = e
            for x in range(f, e):
                cover[y, x] += 1
    # Per row: prefix sums of the pixels no segment covers, and of those on the
    # silhouette: every table's row away from its own pair's spans.
    free = np.zeros((2, h, w + 1), np.int32)
    all_m = 0
    all_i = 0
    for y in range(h):
        c0 = 0
        c1 = 0
        for x in range(w):
            on = np.int64(sil[y, x])
            if cover[y, x] > 0:
                all_m += 1
                all_i += on
            else:
                c0 += 1
                c1 += on
            free[0, y, x + 1] = c0
            free[1, y, x + 1] = c1
    for n in range(segs.shape[0]):
        s, c = segs[n], child[n]
        pair = np.int64(c != s)
        y0 = max(0, min(h, rows[n, 0]))
        y1 = max(y0, min(h, rows[n, 1]))
        m = all_m
        i = all_i
        for y in range(y0, y1):
            fs, es = span_f[y, s], span_e[y, s]
            fc, ec = span_f[y, c], span_e[y, c]
            # the columns the pair covers (own > 0 only there): base n differs from the
            # free pixels only inside them, and its prefix sums by a constant after them
            lo = w
            hi = 0
            if fs < es:
                lo, hi = fs, es
            if pair and fc < ec:
                lo, hi = min(lo, fc), max(hi, ec)
            for x in range(w + 1):
                cum[n, 0, y, x] = free[0, y, x]
                cum[n, 1, y, x] = free[1, y, x]
            d0 = 0
            d1 = 0
            for x in range(lo, hi):  # branch-free: spans are noisy at their edges
                own = np.int64(fs <= x < es) + pair * np.int64(fc <= x < ec)
                cv = cover[y, x]
                on = np.int64(sil[y, x])
                # a pixel only the pair covers leaves base n (it was not free before)
                mine = np.int64(cv > 0) - np.int64(cv > own)
                m -= mine
                i -= mine & on
                d0 += mine
                d1 += mine & on
                cum[n, 0, y, x + 1] += d0
                cum[n, 1, y, x + 1] += d1
            if d0:  # (then the pair covers columns lo..hi - 1: the tail starts after hi)
                for x in range(hi + 1, w + 1):
                    cum[n, 0, y, x] += d0
                    cum[n, 1, y, x] += d1
        m_base[n] = m
        i_base[n] = i


@numba.njit(cache=True, nogil=True)
def many_grid(best, width, step, lo, hi, clip, period, warm, out):
    """One iteration's candidates of ``interval_search_many``, as its numpy code makes
    them: out (N, divisions + 1 [+ 1 if warm: the start, last]); clip: limit to
    [lo, hi]; wrapped into [lo, lo + period) when period > 0."""
    n_s, n_c = out.shape
    n_g = n_c - 1 if warm else n_c
    for r in range(n_s):
        begin = best[r] - width[r] / 2
        end = best[r] + width[r] / 2
        if clip:
            begin = max(begin, lo[r])
            end = min(end, hi[r])
        cap = end + 1e-9 * step[r]
        for i in range(n_g):
            out[r, i] = min(begin + step[r] * float(i), cap)
        if warm:
            out[r, n_g] = best[r]
        if period > 0:
            for i in range(n_c):
                out[r, i] = lo[r] + _mod(out[r, i] - lo[r], period)


@numba.njit(cache=True, nogil=True)
def many_pick(cand, s, prefer, period, best, best_score):
    """Per row, ``search_pick`` (ties to the candidate nearest prefer[r], or to best[r]
    where prefer[r] is NaN), then keep it in best / best_score if it scores higher."""
    for r in range(s.shape[0]):
        centre = best[r] if np.isnan(prefer[r]) else prefer[r]
        k = search_pick(cand[r], s[r], centre, period)
        if s[r, k] > best_score[r] + 1e-12:
            best_score[r] = s[r, k]
            best[r] = cand[r, k]


@numba.njit(cache=True, nogil=True)
def many_runner(values, scores, best, period, far, out):
    """Per row, ``search_runner`` (far[r]: the distance beyond which a value counts)."""
    for r in range(values.shape[0]):
        out[r] = search_runner(values[r], scores[r], best[r], period, far[r])


@numba.njit(cache=True, nogil=True)
def shift_overlap(sil, model, n, out):
    """out[t] = pixels where model[y, x] and sil[y, x + t - n], for t in 0..2n (columns
    outside sil count as empty): the overlap of the model moved right by t - n.

    Visits each model pixel once (every shift of it at once), not every pixel of
    the image once per shift: the model covers a small part of the image.
    """
    h, w = sil.shape
    for t in range(2 * n + 1):
        out[t] = 0
    for y in range(h):
        for x in range(w):
            if model[y, x]:
                # shifts d = t - n with 0 <= x + d < w
                t0 = max(0, n - x)
                t1 = min(2 * n + 1, w - x + n)
                for t in range(t0, t1):
                    out[t] += np.int64(sil[y, x + t - n])


@numba.njit(cache=True, nogil=True)
def group_terms(ca, cb, sign, k0, k1, own0, own1, ch0, ch1, leaf, n_k, radii, cum, y0, y1,
                caps, a, m_base, i_base, x, q):
    """:func:`similarity_terms` of a group search's candidates, (N, B) -> x, q (N * B,).

    Search n's segment runs from own0[n] to own0[n] + (ca[n, b] * k0[n], (sign *
    cb[n, b]) * k1[n]); unless leaf[n], its child (ch0[n], ch1[n]) shifts with the
    segment's end (n_k = 2 segments per candidate, else 1). Table n: cum[n], radii[n],
    m_base[n], i_base[n]. The floats of the numpy code.
    """
    n_s, n_b = ca.shape
    p0, p1, first, last, setup, d = candidate_scratch(n_k)
    for n in range(n_s):
        for b in range(n_b):
            x[n * n_b + b], q[n * n_b + b] = group_candidate(
                n, ca[n, b], cb[n, b], sign, k0, k1, own0, own1, ch0, ch1, leaf, n_k, p0, p1,
                radii, cum, y0, y1, caps, first, last, setup, d, a, m_base, i_base)


@numba.njit(cache=True, nogil=True, inline="always")
def group_candidate(n, ca, cb, sign, k0, k1, own0, own1, ch0, ch1, leaf, n_k, p0, p1, radii,
                    cum, y0, y1, caps, first, last, setup, d, a, m_base, i_base):
    """Eq. 3.3's terms of one candidate of group search n (:func:`group_terms`)."""
    ex = own0[n, 0] + ca * k0[n]
    ey = own0[n, 1] + (sign * cb) * k1[n]
    p0[0, 0, 0] = own0[n, 0]
    p0[0, 0, 1] = own0[n, 1]
    p1[0, 0, 0] = ex
    p1[0, 0, 1] = ey
    if n_k == 2:
        if leaf[n]:
            p0[0, 1, 0] = own0[n, 0]
            p0[0, 1, 1] = own0[n, 1]
            p1[0, 1, 0] = ex
            p1[0, 1, 1] = ey
        else:
            dx = ex - own1[n, 0]
            dy = ey - own1[n, 1]
            p0[0, 1, 0] = ch0[n, 0] + dx
            p0[0, 1, 1] = ch0[n, 1] + dy
            p1[0, 1, 0] = ch1[n, 0] + dx
            p1[0, 1, 1] = ch1[n, 1] + dy
    return candidate_terms(p0, p1, radii[n], 0, cum, n, y0, y1, caps, first, last, setup, d, a,
                           m_base[n], i_base[n])


@numba.njit(cache=True, nogil=True)
def group_search(best, width, lo, hi, clip, period, gap_period, warm, prefer, divisions,
                 min_step, angle, sign, k0, k1, own0, own1, ch0, ch1, leaf, n_k, radii, cum, y0,
                 y1, caps, a, m_base, i_base, best_score, runner):
    """A whole ``interval_search_many`` of a group search in one call.

    Its loop with the same grid, pick and runner-up kernels (:func:`many_grid`,
    :func:`many_pick`, :func:`many_runner`), scoring each candidate as
    :func:`group_terms` does with S = exp(-p - n) (1 - p); cos, sin and exp are
    libm's (see :func:`search_1d`). ``best`` (N,) holds the first intervals' centres
    on entry and the values found on return; ``width`` (N,) the first intervals;
    ``prefer`` (N,) NaN where none. best_score, runner (N,) are written.
    Returns the number of iterations. Needs divisions >= 3.
    """
    n_s = best.shape[0]
    step = width / divisions
    first_step = step.copy()
    n_max = 64
    values = np.empty((n_s, n_max * (divisions + 2)))
    scores = np.empty((n_s, n_max * (divisions + 2)))
    p0, p1, first, last, setup, d = candidate_scratch(n_k)
    for r in range(n_s):
        best_score[r] = -np.inf
    used = 0
    iterations = 0
    while iterations < n_max:
        extra = 1 if (iterations == 0 and warm) else 0
        n_c = divisions + 1 + extra
        cand = np.empty((n_s, n_c))
        s = np.empty((n_s, n_c))
        many_grid(best, width, step, lo, hi, clip, period, extra == 1, cand)
        for n in range(n_s):
            for b in range(n_c):
                v = cand[n, b]
                ca, cb = (math.cos(v), math.sin(v)) if angle else (v, v)
                x, q = group_candidate(n, ca, cb, sign, k0, k1, own0, own1, ch0, ch1, leaf,
                                       n_k, p0, p1, radii, cum, y0, y1, caps, first, last,
                                       setup, d, a, m_base, i_base)
                s[n, b] = math.exp(x) * q
                values[n, used + b] = v
                scores[n, used + b] = s[n, b]
        used += n_c
        iterations += 1
        many_pick(cand, s, prefer, gap_period, best, best_score)
        width = 2 * width / divisions
        step = 2 * step / divisions
        if not np.any(width > min_step):
            break
    many_runner(values[:, :used], scores[:, :used], best, period, first_step * 1.01, runner)
    return iterations


@numba.njit(cache=True, nogil=True)
def group_fit(jp0, jp1, seg_radii, lengths, segs, child, n_k, sil, caps, a, lo, hi, start,
              interval, has_interval, periodic, warm, prefer, divisions, min_step, angle, sign,
              k0, k1, current, best, best_score, runner):
    """A whole group search (``_Fitter.search_group``) from the model's ends, in one call.

    Sets up what the Python path sets up with numpy (the rows each search's candidates
    can reach, :func:`group_span_tables`, the pairs' ends and radii, the first
    intervals as ``interval_search_many`` makes them), with the same floats, then
    runs :func:`group_search`. jp0, jp1 (10, 2): every segment's ends; seg_radii,
    lengths (10,); segs, child (N,): the searched segments and the child each moves
    (itself for a leaf); n_k: 2 if any has a child, else 1. lo, hi, start, interval
    (N,) as ``interval_search_many`` takes them (``start`` read only when ``warm``,
    ``interval`` only with ``has_interval``); periodic 0 for none. best, best_score,
    runner (N,) are written. Returns the number of iterations, or -1 if an interval
    is empty (nothing written). ``current`` (N,): each searched value as it is now
    (the pose the ends show).
    """
    n_s = segs.shape[0]
    h, w = sil.shape
    wrap = periodic > 0
    for n in range(n_s):
        if not hi[n] > lo[n]:
            return -1
        if wrap and not hi[n] - lo[n] >= periodic - 1e-12:
            wrap = False
    r_max = seg_radii.max()
    rows = np.empty((n_s, 2), np.int64)
    own0 = np.empty((n_s, 2))
    own1 = np.empty((n_s, 2))
    ch0 = np.empty((n_s, 2))
    ch1 = np.empty((n_s, 2))
    leaf = np.empty(n_s, np.bool_)
    radii = np.empty((n_s, n_k))
    width = np.empty(n_s)
    for n in range(n_s):
        s, c = segs[n], child[n]
        reach = lengths[s] + (lengths[c] if c != s else 0.0) + r_max + 4
        rows[n, 0] = np.int64(math.floor(jp0[s, 1] - reach))
        rows[n, 1] = np.int64(math.ceil(jp0[s, 1] + reach) + 1)
        for t in range(2):
            own0[n, t], own1[n, t] = jp0[s, t], jp1[s, t]
            ch0[n, t], ch1[n, t] = jp0[c, t], jp1[c, t]
        leaf[n] = c == s
        radii[n, 0] = seg_radii[s]
        if n_k == 2:
            radii[n, 1] = seg_radii[c]
        width[n] = min(interval[n], hi[n] - lo[n]) if has_interval else hi[n] - lo[n]
        best[n] = start[n] if warm else 0.5 * (lo[n] + hi[n])
        if not wrap:
            best[n] = min(max(best[n], lo[n]), hi[n])
        # Tighter rows: every candidate lies within dmax of the first centre (the
        # intervals shrink by 2 / divisions, so the centres wander at most
        # width / 2 * divisions / (divisions - 2)), which moves the segment's end
        # (and the child with it) by at most disp pixels from where it is now.
        dmax = 0.5 * width[n] * divisions / (divisions - 2.0)
        if angle:
            gap = abs(best[n] - current[n]) % (2.0 * np.pi)
            gap = min(gap, 2.0 * np.pi - gap) + dmax
            disp = k0[n] * min(gap, 2.0)  # the chord 2 l sin(gap / 2) <= l min(gap, 2)
        else:
            disp = math.sqrt(k0[n] * k0[n] + k1[n] * k1[n]) * (abs(best[n] - current[n]) + dmax)
        y_lo = min(min(jp0[s, 1], jp1[s, 1]), min(jp0[c, 1], jp1[c, 1]))
        y_hi = max(max(jp0[s, 1], jp1[s, 1]), max(jp0[c, 1], jp1[c, 1]))
        rows[n, 0] = max(rows[n, 0], np.int64(math.floor(y_lo - disp - r_max - 4.0)))
        rows[n, 1] = min(rows[n, 1], np.int64(math.ceil(y_hi + disp + r_max + 4.0)) + 1)
    cum = np.zeros((n_s, 2, h, w + 1), np.int32)
    m_base = np.zeros(n_s, np.int64)
    i_base = np.zeros(n_s, np.int64)
    group_span_tables(jp0, jp1, seg_radii, caps, segs, child, sil, rows, cum, m_base, i_base)
    clip = not wrap
    period = periodic if wrap else 0.0
    return group_search(best, width, lo, hi, clip, period, periodic,
                        warm, prefer, divisions, min_step, angle, sign, k0, k1, own0, own1, ch0,
                        ch1, leaf, n_k, radii, cum, 0, h, caps, a, m_base, i_base, best_score,
                        runner)


@numba.njit(cache=True, nogil=True, inline="always")
def still_segments(jp0, jp1, seg_radii, drawn, moving):
    """The drawn segments not in ``moving`` (K,), in index order: their ends (S, 2) and
    radii (S,), from every segment's ends jp0, jp1 (10, 2) and radii (10,)."""
    is_moving = np.zeros(10, np.bool_)
    for t in range(moving.shape[0]):
        is_moving[moving[t]] = True
    n_still = 0
    for d in range(10):
        if drawn[d] and not is_moving[d]:
            n_still += 1
    sp0 = np.empty((n_still, 2))
    sp1 = np.empty((n_still, 2))
    s_radii = np.empty(n_still)
    k = 0
    for d in range(10):
        if drawn[d] and not is_moving[d]:
            sp0[k, 0], sp0[k, 1] = jp0[d, 0], jp0[d, 1]
            sp1[k, 0], sp1[k, 1] = jp1[d, 0], jp1[d, 1]
            s_radii[k] = seg_radii[d]
            k += 1
    return sp0, sp1, s_radii


@numba.njit(cache=True, nogil=True)
def limb_fit(jp0, jp1, seg_radii, lengths, drawn, seg, child, mode, sign, k0, k1, no_pose, sil,
             sil_cum, a, y0, y1, caps, lo, hi, divisions, min_step, best, warm, width, period,
             gap_period, prefer, has_prefer, out):
    """A whole limb search (``_Fitter.search_angle`` / ``search_fore`` of one limb
    segment) from the model's ends, in one call.

    Sets up what the Python path sets up with numpy (the moving segments: ``seg`` and
    its ``child`` if drawn (-1: none); the still ones: every other drawn segment; the
    rows the candidates can reach), with the same floats, then runs
    :func:`search_1d` (``mode`` SEARCH_LIMB_ANGLE or SEARCH_LIMB_RATIO; ``sign, k0,
    k1`` as its limb tuple; ``no_pose``: its unused pose tuple). jp0, jp1 (10, 2):
    every segment's ends; drawn (10,) bool. The search's arguments as
    :func:`search_1d` takes them; out (5,) is written.
    """
    n_move = 2 if (child >= 0 and drawn[child]) else 1
    moving = np.empty(n_move, np.int64)
    moving[0] = seg
    if n_move == 2:
        moving[1] = child
    sp0, sp1, s_radii = still_segments(jp0, jp1, seg_radii, drawn, moving)
    p0s = np.empty((n_move, 2))
    p1s = np.empty((n_move, 2))
    radii = np.empty(n_move)
    notown = np.empty(n_move)
    total = 0.0
    for t in range(n_move):
        m = moving[t]
        p0s[t, 0], p0s[t, 1] = jp0[m, 0], jp0[m, 1]
        p1s[t, 0], p1s[t, 1] = jp1[m, 0], jp1[m, 1]
        radii[t] = seg_radii[m]
        notown[t] = 0.0 if m == seg else 1.0
        total += lengths[m]
    # the candidates stay within the moving segments' full lengths of the fixed
    # proximal joint: the table is needed only in those rows
    ext = (total + seg_radii.max()) + 4.0
    f0 = max(y0, np.int64(math.floor(jp0[seg, 1] - ext)))
    f1 = min(y1, np.int64(math.ceil(jp0[seg, 1] + ext)) + 1)
    start = jp0[seg].copy()
    old_end = jp1[seg].copy()
    limb = (sign, k0, k1, start, old_end, p0s, p1s, notown)
    still = (sp0, sp1, s_radii, sil, sil_cum, f0, f1)
    search_1d(lo, hi, divisions, min_step, best, warm, width, period, gap_period, prefer,
              has_prefer, mode, limb, no_pose, radii, still, y0, y1, caps, a, out)


@numba.njit(cache=True, nogil=True)
def pose_fit(jp0, jp1, seg_radii, drawn, moving, seg_prox, seg_dist, mode, idx, coef, neck,
             length, fixed, root, angles, fore, spread, lengths, shoulder, hip, order, parent,
             kind, no_limb, sil, sil_cum, a, y0, y1, caps, lo, hi, divisions, min_step, best,
             warm, width, period, gap_period, prefer, has_prefer, out):
    """A whole pose search (``_Fitter.search`` of a pose action: the torso, the head,
    the spread, a whole arm, a torso's or head's foreshortening) in one call.

    Sets up what the Python path sets up with numpy (the still segments: every drawn
    segment not in ``moving`` (K,); the moving segments' joints seg_prox[moving],
    seg_dist[moving] and radii), then runs :func:`search_1d` with the pose tuple
    (idx, coef, neck, length, root, angles, fore, spread, lengths, shoulder, hip,
    order, parent, kind, prox, dist). ``fixed`` (K, 2): the moving segments' distal
    ends held still (SEARCH_POSE_SPREAD; else (1, 2), unused); ``no_limb``: the
    unused limb tuple but for its held ends. jp0, jp1 (10, 2): every segment's ends.
    """
    n_move = moving.shape[0]
    sp0, sp1, s_radii = still_segments(jp0, jp1, seg_radii, drawn, moving)
    prox = np.empty(n_move, np.int64)
    dist = np.empty(n_move, np.int64)
    radii = np.empty(n_move)
    for t in range(n_move):
        prox[t] = seg_prox[moving[t]]
        dist[t] = seg_dist[moving[t]]
        radii[t] = seg_radii[moving[t]]
    sign, k0, k1, start, old_end, p0s, _, notown = no_limb
    limb = (sign, k0, k1, start, old_end, p0s, fixed, notown)
    pose = (idx, coef, neck, length, root, angles, fore, spread, lengths, shoulder, hip, order,
            parent, kind, prox, dist)
    still = (sp0, sp1, s_radii, sil, sil_cum, y0, y1)
    search_1d(lo, hi, divisions, min_step, best, warm, width, period, gap_period, prefer,
              has_prefer, mode, limb, pose, radii, still, y0, y1, caps, a, out)


@numba.njit(cache=True, nogil=True)
def widest_run_middles(band, out):
    """Per row of ``band`` (h, w) bool that has a run of True: the middle column of its
    widest run (ties: the rightmost), as ``row_runs`` and a sort by width would pick
    it, into out[:count]; returns count."""
    h, w = band.shape
    count = 0
    for y in range(h):
        best_w = 0
        mid = 0.0
        x = 0
        while x < w:
            if band[y, x]:
                start = x
                while x < w and band[y, x]:
                    x += 1
                width = x - start
                if width >= best_w:
                    best_w = width
                    mid = 0.5 * (start + (x - 1))
            else:
                x += 1
        if best_w > 0:
            out[count] = mid
            count += 1
    return count


# the SEARCH_* constants are compiled in as literals: numba's cache would not see a
# change to modes.py (vidcap.kernelcache)
refresh_when_changed(globals(), [Path(__file__).with_name("modes.py")])
