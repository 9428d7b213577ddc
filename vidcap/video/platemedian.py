"""Per-pixel medians of sampled frames, skipping excluded samples (the plate's core).

Shared by :mod:`vidcap.video.background` (the first plate) and :mod:`vidcap.video.platepass`
(the plate re-taken outside the person), so neither imports the other.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["masked_median", "normalised_u8", "robust_plate"]


def normalised_u8(frames, gains, scaled: bool | None = None) -> np.ndarray:
    """Frames divided by their per-channel gains, uint8 (K, H, W, 3); ``scaled``: whether
    they are divided at all (default: unless every gain is within 0.005 of 1; a caller
    normalising some of the frames passes what all of them say)."""
    if np.abs(gains - 1).max() < 0.005 if scaled is None else not scaled:
        return frames
    return np.stack([cv2.multiply(f, tuple(float(v) for v in 1 / g) + (0.0,))
                     for f, g in zip(frames, gains, strict=True)])

def masked_median(x: np.ndarray, excl: np.ndarray | None) -> np.ndarray:
    """Per-pixel median over axis 0 of uint8 ``x`` (K, H, W, 3), skipping ``excl``.

    One fixed-rank partition: with m samples included, the first z excluded become
    0 and the rest 255, which puts the included samples' median at the middle rank.
    """
    k = len(x)
    mid = (k - 1) // 2
    if excl is not None and excl.any():
        # (small integer types throughout: at 4K these arrays are 75 M elements)
        m = k - excl.sum(axis=0, dtype=np.int16)
        z = (mid - (np.maximum(m, 1) - 1) // 2).astype(np.int16)
        rank = np.cumsum(excl, axis=0, dtype=np.int16)
        sentinel = np.where(rank <= z, np.uint8(0), np.uint8(255))
        x = x.copy()
        np.copyto(x, sentinel[..., None], where=excl[..., None])
    if k > 9:
        return np.partition(x, mid, axis=0)[mid]
    # Few samples (the full-resolution plate): an odd-even transposition sort of the
    # k frames by element-wise min / max, k * (k - 1) / 2 contiguous passes, is ~3x
    # faster than partitioning along the strided first axis; the same values.
    v = list(x)
    for p in range(k):
        for i in range(p % 2, k - 1, 2):
            v[i], v[i + 1] = np.minimum(v[i], v[i + 1]), np.maximum(v[i], v[i + 1])
    return v[mid]

def robust_plate(frames, gains, weights, *, max_samples=9) -> np.ndarray:
    """Per-pixel median of the background samples, (H, W, 3) uint8.

    At full resolution the median runs over at most ``max_samples`` evenly picked
    samples (the cost is linear in them); pixels with no background sample among
    those take the median over all samples.
    """
    excl = weights <= 0
    k = len(frames)
    if k <= max_samples:
        return masked_median(normalised_u8(frames, gains), excl)
    # Only the samples (and the lost pixels) the medians read are normalised: at
    # 1000x1000, 24 whole samples cost ~0.3 s of CPU for 9 read.
    scaled = not np.abs(gains - 1).max() < 0.005
    sub = np.unique(np.linspace(0, k - 1, max_samples).round().astype(int))
    plate = masked_median(normalised_u8(frames[sub], gains[sub], scaled), excl[sub])
    lost = excl[sub].all(axis=0) & ~excl.all(axis=0)
    if lost.any():
        ys, xs = np.nonzero(lost)
        x = normalised_u8(frames[:, ys, xs][:, None], gains, scaled)
        plate[ys, xs] = masked_median(x, excl[:, ys, xs][:, None])[0]
    return plate


# the names background.py has always used
_normalised_u8, _masked_median, _robust_plate = normalised_u8, masked_median, robust_plate
