"""Compiled kernels of :mod:`vidcap.video.graphcut` (numba; imported lazily from there).

One pass over the person's crop instead of some sixty whole-array numpy calls a frame
(each a few microseconds of overhead on a crop of a few thousand pixels: they, not
the flow, were the cut's cost). Module-level functions so that numba's on-disk cache
(``cache=True``) is found again by later processes.
"""

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def crop_terms(f, inner, near, never, img, lut, l1, tmap, with_never, n_colours):
    """The band, its pixels' data term from the plate, and the scene's colours.

    Parameters
    ----------
    f, inner, near : (h, w) uint8
        The thresholded foreground of the crop, eroded and dilated by the band's disk.
    never : (h, w) bool
        Never-seen pixels of the plate.
    img : (h, w, 3) uint8
        The frame's crop.
    lut : (3, 256) int32
        Per channel, the quantised colour bin of each level divided by the frame's
        gain, already multiplied by the channel's place (``BINS**2``, ``BINS``, 1).
    l1, tmap : (h, w) uint8
        The difference from the plate and the per-pixel threshold.
    with_never : bool
        The never-seen pixels belong to the band.
    n_colours : int
        Quantised colours (``BINS**3``).

    Returns
    -------
    band : (h, w) bool
    qb : (n,) int32
        The band pixels' quantised colours (row order).
    plate : (n,) float32
        ``clip(log2((l1 + 1) / (tmap + 1)), -2, 2)`` at the band pixels.
    nvb : (n,) bool
        Band pixels never seen.
    hist : (n_colours,) float32
        Histogram of the quantised colours of the crop outside the dilated
        foreground and the never-seen area (the scene round the person).
    n_scene : int
        Pixels in ``hist``.
    hist_in : (n_colours,) float32
        Histogram of the quantised colours of the sure person: inside the eroded
        foreground, seen, above the threshold.
    n_in : int
        Pixels in ``hist_in``.
    """
    h, w = f.shape
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
                v = math.log2((l1[y, x] + 1.0) / (tmap[y, x] + 1.0))
                plate[n] = min(2.0, max(-2.0, v))
                nvb[n] = nv
                n += 1
            elif near[y, x] == 0 and not nv:
                hist[q] += 1.0
                n_scene += 1
            elif inner[y, x] > 0 and not nv and l1[y, x] > tmap[y, x]:
                hist_in[q] += 1.0
                n_in += 1
    return band, qb[:n], plate[:n], nvb[:n], hist, n_scene, hist_in, n_in


@numba.njit(cache=True, nogil=True)
def band_graph(band, fixed, img, smooth):
    """The band's 4-neighbour links and the links to fixed pixels folded into the
    terminal ones (:func:`vidcap.video.graphcut._band_cut`).

    Parameters
    ----------
    band, fixed : (h, w) bool
        Band pixels; outside the band, the kept label (person).
    img : (h, w, 3) uint8
    smooth : float
        Weight of the pairwise term.

    Returns
    -------
    ia, ib : (m,) int32
        Band pixel indices (row order) of the links between two band pixels.
    wt : (m,) float64
        Their weights, ``smooth * exp(-beta * |I_p - I_q|^2)``, ``beta`` from the
        mean squared difference over the pairs touching the band.
    src, snk : (n,) float64
        Per band pixel, the summed weights of its links to fixed person / scene
        pixels.
    """
    h, w = band.shape
    idx = np.full((h, w), -1, np.int32)
    n = 0
    for y in range(h):
        for x in range(w):
            if band[y, x]:
                idx[y, x] = n
                n += 1
    total = 0.0
    count = 0
    for y in range(h):
        for x in range(w):
            for dy, dx in ((0, 1), (1, 0)):
                yy, xx = y + dy, x + dx
                if yy >= h or xx >= w or not (band[y, x] or band[yy, xx]):
                    continue
                d2 = 0.0
                for c in range(3):
                    d = float(img[y, x, c]) - float(img[yy, xx, c])
                    d2 += d * d
                total += d2
                count += 1
    beta = 1.0 / max(2.0 * total / count, 1e-6) if count else 0.0
    ia = np.empty(2 * n, np.int32)
    ib = np.empty(2 * n, np.int32)
    wt = np.empty(2 * n, np.float64)
    src = np.zeros(n, np.float64)
    snk = np.zeros(n, np.float64)
    m = 0
    for y in range(h):
        for x in range(w):
            for dy, dx in ((0, 1), (1, 0)):
                yy, xx = y + dy, x + dx
                if yy >= h or xx >= w:
                    continue
                a, b = idx[y, x], idx[yy, xx]
                if a < 0 and b < 0:
                    continue
                d2 = 0.0
                for c in range(3):
                    d = float(img[y, x, c]) - float(img[yy, xx, c])
                    d2 += d * d
                v = smooth * math.exp(-beta * d2)
                if a >= 0 and b >= 0:
                    ia[m] = a
                    ib[m] = b
                    wt[m] = v
                    m += 1
                elif a >= 0:  # cutting the pair costs v when a takes the other label
                    if fixed[yy, xx]:
                        src[a] += v
                    else:
                        snk[a] += v
                elif fixed[y, x]:
                    src[b] += v
                else:
                    snk[b] += v
    return ia[:m], ib[:m], wt[:m], src, snk
