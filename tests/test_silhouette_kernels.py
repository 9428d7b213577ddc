"""The silhouette stage's compiled passes give what the OpenCV / numpy calls they
replace give, bit for bit (vidcap/video/_silhouette_kernels.py, and the graph cut's
band links in vidcap/video/_graphcut_kernels.py)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from vidcap.video import _graphcut_kernels as G
from vidcap.video import _silhouette_kernels as K


def _images(seed, h=50, w=70):
    rng = np.random.default_rng(seed)
    img = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    # a plate near the frame (shadows: darker, same colour), elsewhere unrelated
    dark = np.clip(img * rng.uniform(0.5, 1.05, (h, w, 1)) + rng.normal(0, 2, (h, w, 3)),
                   0, 255)
    other = rng.integers(0, 256, (h, w, 3))
    plate = np.where(rng.random((h, w, 1)) < 0.7, dark, other).astype(np.uint8)
    return rng, img, plate


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_l1_matches_opencvs_saturating_channel_sum(seed):
    _, img, plate = _images(seed)
    b, g, r = cv2.split(cv2.absdiff(img, plate))
    want = cv2.add(cv2.add(b, g), r)
    assert (want == 255).any() and (want < 255).any()
    out = np.empty(want.shape, np.uint8)
    K.l1_sum(cv2.absdiff(img, plate), out)
    np.testing.assert_array_equal(out, want)


@pytest.mark.parametrize("scaled", [False, True])
def test_drop_shadows_matches_the_float32_numpy_test(scaled):
    _, img, plate = _images(3)
    planes = cv2.split(plate.astype(np.float32) + 1.0)
    g = np.array([1.03, 0.96, 1.0], np.float32)
    zones, thr = ((0.6, 0.95, 0.2), (0.7, 0.99, 0.5)), 13.9
    f = cv2.split(img.astype(np.float32))
    b = [q * float(gc) for q, gc in zip(planes, g, strict=True)] if scaled else planes
    alpha = (f[0] * b[0] + f[1] * b[1] + f[2] * b[2]) / (b[0] * b[0] + b[1] * b[1]
                                                         + b[2] * b[2])
    cd = np.abs(f[0] - alpha * b[0]) + np.abs(f[1] - alpha * b[1]) + np.abs(f[2] - alpha
                                                                            * b[2])
    shadow = np.zeros(alpha.shape, bool)
    for lo, hi, share in zones:
        shadow |= (alpha > lo) & (alpha < hi) & (cd < share * thr)
    assert 50 < shadow.sum() < shadow.size - 50
    limits = np.array([(lo, hi, s * thr) for lo, hi, s in zones], np.float32)
    fg = np.full(shadow.shape, 255, np.uint8)
    l1 = np.full(shadow.shape, 9, np.uint8)
    K.drop_shadows(img, *planes, g if scaled else np.ones(3, np.float32), limits, fg, l1,
                   True)
    np.testing.assert_array_equal(fg == 0, shadow)
    np.testing.assert_array_equal(l1 == 0, shadow)


def test_edge_passes_match_the_numpy_expressions():
    rng, img, plate = _images(4)
    l1 = rng.integers(0, 256, (50, 70), dtype=np.uint8)
    inner = (rng.random(l1.shape) < 0.5).astype(np.uint8)
    masked, inner255 = np.empty_like(l1), np.empty_like(l1)
    K.interior(l1, inner, masked, inner255)
    np.testing.assert_array_equal(masked, cv2.bitwise_and(l1, l1, mask=inner))
    np.testing.assert_array_equal(inner255, inner * np.uint8(255))
    num = cv2.blur(masked, (13, 13))
    den = cv2.blur(inner255, (13, 13))
    tf = rng.integers(0, 60, l1.shape, dtype=np.uint8)
    for floor in (0, 40):
        want = (l1 > (np.maximum(tf, np.uint8(floor)) if floor else tf)) & (
            l1 * den.astype(np.float32) >= (255.0 * 0.3) * num.astype(np.float32))
        out = np.empty_like(l1)
        K.edge_keep(l1, den, num, tf, floor, np.float32(255.0 * 0.3), out)
        np.testing.assert_array_equal(out, want.view(np.uint8))
    m = (rng.random(l1.shape) < 0.5).astype(np.uint8)
    near = np.maximum(m, inner)
    want = m.copy()
    band = cv2.subtract(near, inner)
    np.copyto(want, out, where=(band > 0) & (den > 0))
    K.copy_in_band(m, out, near, inner, den)
    np.testing.assert_array_equal(m, want)


def _band_graph_reference(band, fixed, img, smooth, e):
    """Every 4-neighbour pair of the crop in row order (the kernel visits only the
    band's pixels)."""
    h, w = band.shape
    idx = np.full((h, w), -1)
    idx[band] = np.arange(band.sum())
    pairs = []
    for y in range(h):
        for x in range(w):
            for yy, xx in ((y, x + 1), (y + 1, x)):
                if yy < h and xx < w and (band[y, x] or band[yy, xx]):
                    d = img[y, x].astype(float) - img[yy, xx]
                    pairs.append((y, x, yy, xx, float(d @ d)))
    d2 = np.array([p[4] for p in pairs])
    beta = 1.0 / max(2.0 * d2.sum() / len(d2), 1e-6)
    ia, ib, wt = [], [], []
    src, snk = np.zeros(len(e)), np.zeros(len(e))
    for y, x, yy, xx, q in pairs:
        v = smooth * np.exp(-beta * q)
        a, b = idx[y, x], idx[yy, xx]
        if a >= 0 and b >= 0:
            ia.append(a), ib.append(b), wt.append(v)
        elif a >= 0:
            (src if fixed[yy, xx] else snk)[a] += v
        else:
            (src if fixed[y, x] else snk)[b] += v
    return (np.array(ia), np.array(ib), np.array(wt), np.maximum(e, 0) + src,
            np.maximum(-e, 0) + snk)


def test_band_graph_gives_every_link_of_the_band_in_row_order():
    rng = np.random.default_rng(6)
    img = rng.integers(0, 256, (30, 40, 3), dtype=np.uint8)
    img[5:25, 10:30] = rng.integers(0, 3, (20, 20, 3))  # small differences: memoised
    fixed = np.zeros((30, 40), np.uint8)
    fixed[8:22, 12:28] = 255
    band = (cv2.dilate(fixed, np.ones((5, 5))) > 0) & (cv2.erode(fixed, np.ones((5, 5))) == 0)
    band[0, :] = True  # the crop's edge
    e = rng.normal(0, 1, band.sum()).astype(np.float32)
    got = G.band_graph(band, fixed, img, 1.0, e)
    want = _band_graph_reference(band, fixed > 0, img, 1.0, e)
    for a, b in zip(got, want, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-14, atol=0)
    assert len(got[0]) > 100 and (got[3] > np.maximum(e, 0)).any()


def _colour_lut_numpy(gain, bins):
    """The colour bins as the numpy path computed them (before the kernel)."""
    v = np.arange(256, dtype=np.float32)[None, :] / np.asarray(gain, np.float32)[:, None]
    q = (np.clip(v, 0, 255).astype(np.uint8).astype(np.int32) * bins) >> 8
    return q * np.array([[bins * bins], [bins], [1]], np.int32)


def test_colour_lut_and_plate_table_match_numpy():
    rng = np.random.default_rng(7)
    for gain in [np.ones(3), *rng.uniform(0.25, 4.0, (20, 3))]:
        np.testing.assert_array_equal(G.colour_lut(np.asarray(gain, np.float32), 16),
                                      _colour_lut_numpy(gain, 16))
    a, b = np.mgrid[:256, :256]
    want = np.clip(np.log2((a + 1.0) / (b + 1.0)), -2, 2).astype(np.float32)
    np.testing.assert_allclose(G.plate_table(), want, rtol=1e-7, atol=0)


def test_smooth_first_two_sums_as_einsum_does():
    from vidcap.video.graphcut import _smoothing

    g = _smoothing(16)
    rng = np.random.default_rng(8)
    for _ in range(20):
        hist = np.zeros(16 ** 3, np.float32)
        hist[rng.integers(0, hist.size, 300)] = rng.integers(1, 3000, 300)
        hist = hist.reshape(16, 16, 16)
        want = np.einsum("bj,ajk->abk", g, np.einsum("ai,ijk->ajk", g, hist))
        np.testing.assert_array_equal(G.smooth_first_two(g, hist), want)
