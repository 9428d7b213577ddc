"""The plate's per-pixel medians read only the samples they use, with the same values."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from vidcap.video.platemedian import masked_median, robust_plate


def _all_normalised_plate(frames, gains, weights, max_samples=9):
    """robust_plate as it was: every sample normalised first, then the subset read."""
    if np.abs(gains - 1).max() < 0.005:
        x = frames
    else:
        x = np.stack([cv2.multiply(f, tuple(float(v) for v in 1 / g) + (0.0,))
                      for f, g in zip(frames, gains, strict=True)])
    excl = weights <= 0
    k = len(x)
    if k <= max_samples:
        return masked_median(x, excl)
    sub = np.unique(np.linspace(0, k - 1, max_samples).round().astype(int))
    plate = masked_median(x[sub], excl[sub])
    lost = excl[sub].all(axis=0) & ~excl.all(axis=0)
    ys, xs = np.nonzero(lost)
    plate[ys, xs] = masked_median(x[:, ys, xs][:, None], excl[:, ys, xs][:, None])[0]
    return plate


@pytest.mark.parametrize("k", [5, 24])
@pytest.mark.parametrize("drift", [0.0, 0.003, 0.08])
def test_robust_plate_normalising_only_what_it_reads_gives_the_same_plate(k, drift):
    """Lost pixels (excluded in every subsampled sample, included in another) and gains
    near 1 in the subset but not in all samples (the scaling is decided on all)."""
    rng = np.random.default_rng(11)
    frames = rng.integers(0, 256, (k, 17, 13, 3), dtype=np.uint8)
    gains = (1 + rng.uniform(-drift, drift, (k, 3))).astype(np.float32)
    gains[-2] = 1.02  # not a subsampled one for k=24: scaled all the same
    weights = (rng.random((k, 17, 13)) > 0.4).astype(np.uint8)
    sub = np.unique(np.linspace(0, k - 1, 9).round().astype(int))
    weights[np.ix_(sub, [2, 3], [4])] = 0  # lost in the subset...
    weights[np.setdiff1d(np.arange(k), sub)[:1], 2, 4] = 1  # ...one other sample has it
    got = robust_plate(frames, gains, weights)
    assert np.array_equal(got, _all_normalised_plate(frames, gains, weights))
