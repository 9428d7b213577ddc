"""Compiled kernels of :mod:`vidcap.video.graphcut` (numba; imported lazily from there).

One pass over the person's crop instead of some sixty whole-array numpy calls a frame
(each a few microseconds of overhead on a crop of a few thousand pixels: they, not
the flow, were the cut's cost). Module-level functions so that numba's on-disk cache
(``cache=True``) is found again by later processes.
"""

import math

import numba
import numpy as np

#: Squared colour differences under this have their link weight memoised per frame.
MEMO = 4096


@numba.njit(cache=True, nogil=True)
def plate_table():
    """(256, 256) float32: ``clip(log2((a + 1) / (b + 1)), -2, 2)`` for every difference
    ``a`` and threshold ``b`` (uint8): the plate's data term, looked up per band pixel
    (a logarithm per pixel was a third of :func:`crop_terms`)."""
    out = np.empty((256, 256), np.float32)
    for a in range(256):
        for b in range(256):
            v = math.log2((a + 1.0) / (b + 1.0))
            out[a, b] = min(2.0, max(-2.0, v))
    return out


@numba.njit(cache=True, nogil=True)
def colour_lut(gain, bins):
    """(3, 256) int32: per channel, the bin of each level divided by ``gain`` (3,)
    float32 (:func:`vidcap.video.appearance.colour_model`'s bins, ``floor(min(v / gain,
    255) / 256 * bins)``, the division in float32), times the channel's place in the
    colour's index (``bins**2``, ``bins``, 1)."""
    out = np.empty((3, 256), np.int32)
    for c in range(3):
        place = bins ** (2 - c)
        for i in range(256):
            v = np.float32(i) / gain[c]
            v = min(max(v, np.float32(0.0)), np.float32(255.0))
            out[c, i] = ((np.int32(np.uint8(v)) * bins) >> 8) * place
    return out


@numba.njit(cache=True, nogil=True)
def crop_terms(f, inner, near, never, img, gain, bins, ptab, l1, tmap, with_never):
    """The band, its pixels' data term from the plate, and the scene's colours.

    Parameters
    ----------
    f, inner, near : (h, w) uint8
        The thresholded foreground of the crop, eroded and dilated by the band's disk.
    never : (h, w) bool
        Never-seen pixels of the plate.
    img : (h, w, 3) uint8
        The frame's crop.
    gain : (3,) float32
        The frame's gain (colours are quantised divided by it, :func:`colour_lut`).
    bins : int
        Bins per channel (``BINS``; ``bins**3`` quantised colours).
    ptab : (256, 256) float32
        :func:`plate_table`.
    l1, tmap : (h, w) uint8
        The difference from the plate and the per-pixel threshold.
    with_never : bool
        The never-seen pixels belong to the band.

    Returns
    -------
    band : (h, w) bool
    qb : (n,) int32
        The band pixels' quantised colours (row order).
    plate : (n,) float32
        ``clip(log2((l1 + 1) / (tmap + 1)), -2, 2)`` at the band pixels.
    nvb : (n,) bool
        Band pixels never seen.
    hist : (bins**3,) float32
        Histogram of the quantised colours of the crop outside the dilated
        foreground and the never-seen area (the scene round the person).
    n_scene : int
        Pixels in ``hist``.
    hist_in : (bins**3,) float32
        Histogram of the quantised colours of the sure person: inside the eroded
        foreground, seen, above the threshold.
    n_in : int
        Pixels in ``hist_in``.
    """
    h, w = f.shape
    lut = colour_lut(gain, bins)
    n_colours = bins ** 3
    band = np.zeros((h, w), np.bool_)
    qb = np.empty(h * w, np.int32)
    plate = np.empty(h * w, np.float32)
    nvb = np.empty(h * w, np.bool_)
    hist = np.zeros(n_colours, np.float32)
    hist_in = np.zeros(n_colours, np.float32)
    n = 0
    n_scene = 0
    n_in = 0
    for y in range(h):
        for x in range(w):
            q = lut[0, img[y, x, 0]] + lut[1, img[y, x, 1]] + lut[2, img[y, x, 2]]
            nv = never[y, x]
            if (near[y, x] > 0 and inner[y, x] == 0) or (with_never and nv):
                band[y, x] = True
                qb[n] = q
                plate[n] = ptab[l1[y, x], tmap[y, x]]
                nvb[n] = nv
                n += 1
            elif near[y, x] == 0 and not nv:
                hist[q] += 1.0
                n_scene += 1
            elif inner[y, x] > 0 and not nv and l1[y, x] > tmap[y, x]:
                hist_in[q] += 1.0
                n_in += 1
    return band, qb[:n], plate[:n], nvb[:n], hist, n_scene, hist_in, n_in


@numba.njit(cache=True, nogil=True, inline="always")
def _d2(img, y, x, yy, xx):
    """Squared colour distance of two pixels (an integer)."""
    a = np.int32(img[y, x, 0]) - np.int32(img[yy, xx, 0])
    b = np.int32(img[y, x, 1]) - np.int32(img[yy, xx, 1])
    c = np.int32(img[y, x, 2]) - np.int32(img[yy, xx, 2])
    return a * a + b * b + c * c


@numba.njit(cache=True, nogil=True)
def _neighbour_d2(idx, ys, xs, img):
    """Per band pixel ``(ys, xs)``, the squared colour differences to its neighbours
    above, left, right and below, (n, 4) int32 (-1: none, or a band pixel above / left,
    whose own pair it is), their sum and their count (the pairs touching the band)."""
    h, w = idx.shape
    n = len(ys)
    d2 = np.full((n, 4), -1, np.int32)
    total = 0
    count = 0
    for k in range(n):
        y, x = ys[k], xs[k]
        if y > 0 and idx[y - 1, x] < 0:
            q = _d2(img, y - 1, x, y, x)
            d2[k, 0] = q
            total += q
            count += 1
        if x > 0 and idx[y, x - 1] < 0:
            q = _d2(img, y, x - 1, y, x)
            d2[k, 1] = q
            total += q
            count += 1
        if x + 1 < w:
            q = _d2(img, y, x, y, x + 1)
            d2[k, 2] = q
            total += q
            count += 1
        if y + 1 < h:
            q = _d2(img, y, x, y + 1, x)
            d2[k, 3] = q
            total += q
            count += 1
    return d2, total, count


@numba.njit(cache=True, nogil=True)
def band_graph(band, fixed, img, smooth, e):
    """The band's 4-neighbour links, the links to fixed pixels folded into the
    terminal ones (:func:`vidcap.video.graphcut._band_cut`), and the terminal links.

    Only the band's pixels are visited (a pair touching the band has a band pixel at
    one end): the outline's few thousand pixels, not the crop's tens of thousands.
    The links come out in the order of a row-major pass over the crop's pairs (the
    flow's search, and so its cut among equal ones, follows that order), and each
    pixel's folded links are summed in that order too (above, left, right, below),
    so the weights are the same bit for bit; ``beta``'s sum is of integers (exact in
    any order).

    Parameters
    ----------
    band : (h, w) bool
        Band pixels.
    fixed : (h, w) uint8
        Outside the band, the kept label (non-zero: person).
    img : (h, w, 3) uint8
    smooth : float
        Weight of the pairwise term.
    e : (n,) float32
        Evidence for the person per band pixel (row order).

    Returns
    -------
    ia, ib : (m,) int32
        Band pixel indices (row order) of the links between two band pixels.
    wt : (m,) float64
        Their weights, ``smooth * exp(-beta * |I_p - I_q|^2)``, ``beta`` from the
        mean squared difference over the pairs touching the band.
    src, snk : (n,) float64
        Per band pixel, the terminal links: ``max(e, 0)`` and ``max(-e, 0)`` plus the
        summed weights of its links to fixed person / scene pixels.
    """
    h, w = band.shape
    n = len(e)
    ys = np.empty(n, np.int32)
    xs = np.empty(n, np.int32)
    idx = np.full((h, w), -1, np.int32)
    k = 0
    for y in range(h):
        for x in range(w):
            if band[y, x]:
                idx[y, x] = k
                ys[k] = y
                xs[k] = x
                k += 1
    d2, total, count = _neighbour_d2(idx, ys, xs, img)
    beta = 1.0 / max(2.0 * float(total) / count, 1e-6) if count else 0.0
    # The weight of each small squared difference computed once (they repeat: the
    # differences are integers, most of them small; exp was half of this kernel).
    memo = np.full(MEMO, -1.0)
    ia = np.empty(2 * n, np.int32)
    ib = np.empty(2 * n, np.int32)
    wt = np.empty(2 * n, np.float64)
    src = np.empty(n, np.float64)
    snk = np.empty(n, np.float64)
    m = 0
    for k in range(n):
        y, x = ys[k], xs[k]
        s = 0.0
        t = 0.0
        for j in range(4):
            q = d2[k, j]
            if q < 0:
                continue
            if q < MEMO:
                v = memo[q]
                if v < 0:
                    v = smooth * math.exp(-beta * float(q))
                    memo[q] = v
            else:
                v = smooth * math.exp(-beta * float(q))
            if j == 0:
                yy, xx = y - 1, x
            elif j == 1:
                yy, xx = y, x - 1
            elif j == 2:
                yy, xx = y, x + 1
            else:
                yy, xx = y + 1, x
            b = idx[yy, xx]
            if b >= 0:  # (right or below: the pair's first pixel is this one)
                ia[m] = k
                ib[m] = b
                wt[m] = v
                m += 1
            elif fixed[yy, xx] > 0:  # cutting the pair costs v when k takes the other label
                s += v
            else:
                t += v
        src[k] = max(e[k], 0.0) + s
        snk[k] = max(-e[k], 0.0) + t
    return ia[:m], ib[:m], wt[:m], src, snk


@numba.njit(cache=True, nogil=True)
def labels_present(lab, n):
    """(n,) bool: which of the labels 0..n-1 occur in ``lab`` (h, w) int32."""
    out = np.zeros(n, np.bool_)
    h, w = lab.shape
    for y in range(h):
        for x in range(w):
            out[lab[y, x]] = True
    return out


@numba.njit(cache=True, nogil=True)
def paint_band(out, band, person):
    """Write the cut's labels into the crop ``out`` (h, w) uint8, in place: 255 where
    ``person`` (n,) bool, else 0, at the ``band`` (h, w) pixels in row order."""
    h, w = band.shape
    k = 0
    for y in range(h):
        for x in range(w):
            if band[y, x]:
                out[y, x] = 255 if person[k] else 0
                k += 1


@numba.njit(cache=True, nogil=True)
def smooth_first_two(g, hist):
    """The histogram (b, b, b) float32 smoothed along its first two axes by the (b, b)
    matrix ``g``: ``np.einsum("bj,ajk->abk", g, np.einsum("ai,ijk->ajk", g, hist))``
    with einsum's float32 sums (the terms added one by one in index order; a zero
    weight adds nothing, so only ``g``'s non-zero band is visited)."""
    b = hist.shape[0]
    lo = np.empty(b, np.int64)
    hi = np.empty(b, np.int64)
    for a in range(b):  # the non-zero band of each row of g
        lo[a] = b
        hi[a] = -1
        for i in range(b):
            if g[a, i] != 0:
                lo[a] = min(lo[a], i)
                hi[a] = max(hi[a], i)
    t1 = np.zeros((b, b, b), np.float32)
    for a in range(b):
        for i in range(lo[a], hi[a] + 1):
            ga = g[a, i]
            for j in range(b):
                for k in range(b):
                    t1[a, j, k] += ga * hist[i, j, k]
    t2 = np.zeros((b, b, b), np.float32)
    for a in range(b):
        for c in range(b):
            for j in range(lo[c], hi[c] + 1):
                gc = g[c, j]
                for k in range(b):
                    t2[a, c, k] += gc * t1[a, j, k]
    return t2
