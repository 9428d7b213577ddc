"""Compiled per-pixel passes of the silhouette stage (:mod:`vidcap.video.silhouette`;
numba, imported lazily from there).

Each replaces a run of whole-array OpenCV and numpy calls on the same pixels (a
channel split and two saturating adds; a mask, a cast and two products before a
comparison) by one pass with the same integer and float32 arithmetic: the same
masks bit for bit, without the intermediates. The box filters and medians stay
OpenCV's. The kernels write into arrays they are given and return nothing (no
results to box when a signal lands while they run).
"""

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def l1_sum(diff, out):
    """``out = min(255, diff[..., 0] + diff[..., 1] + diff[..., 2])``: the L1
    difference, as ``cv2.add(cv2.add(b, g), r)`` of the split channels (saturating;
    the sum of non-negative terms saturates once or never).

    Parameters
    ----------
    diff : (h, w, 3) uint8
        Absolute differences per channel.
    out : (h, w) uint8
        Written.
    """
    h, w = out.shape
    for y in range(h):
        for x in range(w):
            s = np.int32(diff[y, x, 0]) + np.int32(diff[y, x, 1]) + np.int32(diff[y, x, 2])
            out[y, x] = 255 if s > 255 else s


@numba.njit(cache=True, nogil=True)
def interior(l1, inner, masked, inner255):
    """``masked = l1`` where ``inner`` else 0 (``cv2.bitwise_and(l1, l1, mask=inner)``)
    and ``inner255 = inner * 255`` (uint8, wrapping as numpy's product does), all
    (h, w) uint8."""
    h, w = l1.shape
    for y in range(h):
        for x in range(w):
            i = inner[y, x]
            masked[y, x] = l1[y, x] if i else 0
            inner255[y, x] = np.uint8((np.int32(i) * 255) & 255)


@numba.njit(cache=True, nogil=True)
def edge_keep(l1, den, num, tf, floor, share255, out):
    """``out = (l1 > max(tf, floor)) & (l1 * den >= share255 * num)`` as 0 / 1, the
    products in float32 as numpy computes ``l1 * den.astype(float32) >= share255 *
    num.astype(float32)`` (``share255`` a Python float, so float32 there too).

    Parameters
    ----------
    l1, den, num, tf : (h, w) uint8
        The difference, the interior's share of the box (x 255), the interior's mean
        difference (box means), the threshold.
    floor : int
        The frame's threshold floor (0: none).
    share255 : float32
    out : (h, w) uint8
        Written.
    """
    h, w = l1.shape
    fl = np.uint8(floor)
    for y in range(h):
        for x in range(w):
            t = tf[y, x]
            if fl > t:
                t = fl
            v = l1[y, x]
            keep = v > t and (np.float32(v) * np.float32(den[y, x])
                              >= share255 * np.float32(num[y, x]))
            out[y, x] = 1 if keep else 0


@numba.njit(cache=True, nogil=True)
def copy_in_band(m, fg, near, inner, den):
    """``m = fg`` where ``near > inner`` (the band: ``cv2.subtract(near, inner)`` non-zero)
    and ``den > 0``, in place; all (h, w) uint8."""
    h, w = m.shape
    for y in range(h):
        for x in range(w):
            if near[y, x] > inner[y, x] and den[y, x] > 0:
                m[y, x] = fg[y, x]


@numba.njit(cache=True, nogil=True)
def drop_shadows(img, pb, pg, pr, gain, zones, fg, l1, with_l1):
    """Zero ``fg`` (and ``l1`` when ``with_l1``) in place where a pixel is a shadow:
    darker than the plate by a common factor ``alpha`` in every channel with the
    plate's colour (Horprasert et al. 1999), in one of two ``zones``. The arithmetic
    is numpy's over the split float32 planes, in float32, term by term in the same
    order (a gain of exactly 1 leaves the plate as it is). Branch-free per pixel.

    Parameters
    ----------
    img : (h, w, 3) uint8
        The frame's crop.
    pb, pg, pr : (h, w) float32
        The plate's channels plus 1, same crop.
    gain : (3,) float32
        The plate's scale per channel (ones when the frame is not scaled).
    zones : (2, 3) float32
        Per zone ``alpha`` above, ``alpha`` below, chromatic distortion below.
    fg, l1 : (h, w) uint8
        Changed in place.
    with_l1 : bool
    """
    h, w = fg.shape
    g0, g1, g2 = gain[0], gain[1], gain[2]
    lo0, hi0, c0 = zones[0, 0], zones[0, 1], zones[0, 2]
    lo1, hi1, c1 = zones[1, 0], zones[1, 1], zones[1, 2]
    for y in range(h):
        for x in range(w):
            f0 = np.float32(img[y, x, 0])
            f1 = np.float32(img[y, x, 1])
            f2 = np.float32(img[y, x, 2])
            b0 = pb[y, x] * g0
            b1 = pg[y, x] * g1
            b2 = pr[y, x] * g2
            alpha = (f0 * b0 + f1 * b1 + f2 * b2) / (b0 * b0 + b1 * b1 + b2 * b2)
            cd = abs(f0 - alpha * b0) + abs(f1 - alpha * b1) + abs(f2 - alpha * b2)
            s = (((alpha > lo0) & (alpha < hi0) & (cd < c0))
                 | ((alpha > lo1) & (alpha < hi1) & (cd < c1)))
            fg[y, x] = 0 if s else fg[y, x]
            if with_l1:
                l1[y, x] = 0 if s else l1[y, x]

