"""How often each pixel shows motion, over every frame of the clip (issue 26).

The plate (:mod:`vidcap.video.background`) is estimated from a couple of dozen sampled
frames. For a person who barely moves, which frames are drawn decided the plate: a still
torso is told from scenery as a hole of the motion footprint
(:func:`vidcap.video.regionvote._footprint_plate`) whose ring the limbs cover often, and
that cover was counted over the *samples*. CMU 02_07 11-14 s front (a swordsman who
hardly moves): the ring round the still torso was covered in 0.28 of seed 0's samples and
0.20 of seeds 1-3's, the test asked 0.25, and the row's median IoU was 0.91 or 0.51-0.66
on that alone.

Here the ring's cover is measured over time: every frame (every ``step``-th of a long
clip), decoded at the plate's working resolution while the samples are decoded anyway,
gives per pixel the *share of the clip's time* it differs from its temporal median
(:func:`motion_cover`); a ring's cover is its mean, which no draw moves. Time also tells
the two cases apart better than the samples did: round a body part that never moved the
limbs sweep the ring again and again, while a gap between a passer-by's positions (or a
static object walked round) is covered for a moment.

The footprint itself stays the samples' (the pixels that differ from the samples' median
in some sample). A footprint over time (the pixels that move for at least 3 % of the
frames) was tried and not kept: the same rings, but the footprint's outline moved the
inpainted guess across it and the passes after it; arms 150 deg / room (tuning) 0.970 ->
0.466, 02_07 1-4 s side left 0.809 -> 0.490, pose2sim cam3 (vs MediaPipe) 0.750 -> 0.450
(while arms 3/4 0.905 -> 0.923, 02_06 0.810 -> 0.884, 06_12 side left (validation) 0.760 ->
0.969). Any one frame, as "any sample" would be over every frame, swallowed the still parts
into the footprint (session 23: 02_07 front 0.52-0.65, 05_20 front 0.105).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["channel_max_diff", "coarse_step", "inverse_gains", "motion_cover",
           "thumbnail_step"]

#: Measure the cover of the motion footprint's rings over every frame (the share of time
#: a pixel moves) rather than over the sampled frames
#: (:func:`vidcap.video.regionvote._footprint_plate`).
TIME_COVER = True
#: A hole of the footprint is a body part that never moved when its ring is covered for
#: at least this share of the time (the samples' test asked 0.25 of the samples). On the
#: tuning rows (seeds 0 and 1), every hole of the samples' footprint on the renders lies in
#: the person's never-uncovered truth, its ring covered 0.12-0.46 of the time (02_07 11-14
#: s front 0.19-0.26, 05_20 front 0.12-0.34, arms 3/4 0.14-0.37); the real clips with true
#: masks have no hole there (holes of a footprint over time: scene, rings covered
#: 0.06-0.08 of the time).
MIN_COVER = 0.15
#: At most this many thumbnails (a longer clip: every ``step``-th frame).
MAX_THUMBS = 600


def thumbnail_step(n_frames: int) -> int:
    """Every how many frames a thumbnail is taken so that at most :data:`MAX_THUMBS` are."""
    return max(1, -(-int(n_frames) // MAX_THUMBS))


def coarse_step(h: int, w: int) -> int:
    """Pixel step of the ~32 x 32 grid the frames' exposure gains are measured on."""
    return max(1, int(np.sqrt(h * w / 1024)))


def inverse_gains(thumbs: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """1 / each frame's per-channel exposure gain against ``reference``, (N, 3) float32.

    Parameters
    ----------
    thumbs : numpy.ndarray, shape (N, h, w, 3), uint8
    reference : numpy.ndarray, shape (h', w', 3), float32
        The reference's levels plus one on the :func:`coarse_step` grid (the +1 keeps
        black pixels out of the ratios' zeros).

    The gain is the median over the grid of (frame + 1) / reference, clipped to
    [0.25, 4]."""
    n, h, w = thumbs.shape[:3]
    step = coarse_step(h, w)
    ratio = (thumbs[:, ::step, ::step].astype(np.float32) + 1.0) / reference[None]
    return 1.0 / np.clip(np.median(ratio.reshape(n, -1, 3), axis=1), 0.25, 4.0)


def channel_max_diff(a: np.ndarray, b: np.ndarray, dst=None) -> np.ndarray:
    """max over the channels of ``|a - b|``, (h, w), for two (h, w, 3) images of one
    dtype (written into ``dst`` when given)."""
    c0, c1, c2 = cv2.split(cv2.absdiff(a, b))
    return cv2.max(cv2.max(c0, c1), c2, dst=dst)


def motion_cover(thumbs: np.ndarray, *, max_median: int = 48) -> np.ndarray:
    """Share of the clip's time each pixel differs from its temporal median.

    Parameters
    ----------
    thumbs : numpy.ndarray, shape (N, h, w, 3), uint8
        Every frame (or every ``step``-th) at the working resolution.
    max_median : int
        The temporal median (and the frames' gains) are taken over at most this many of
        them, evenly spread (a robust level needs no more; the median is the cost).

    Returns
    -------
    numpy.ndarray, shape (h, w), float32
        In [0, 1]: the share of the thumbnails in which the pixel (3x3 blurred, per-frame
        gain undone, max over the channels) is farther than five noise standard deviations
        (at least 8 grey levels) from its temporal median, the noise measured robustly
        over all pixels and frames (most are still most of the time).
    """
    n, h, w = thumbs.shape[:3]
    pick = np.unique(np.linspace(0, n - 1, min(n, max_median)).round().astype(int))
    # Per-frame, per-channel gains against the picked frames' median (as the plate's
    # samples are normalised: slow exposure drift is not motion).
    step = coarse_step(h, w)
    inv = inverse_gains(thumbs, np.median(
        thumbs[pick, ::step, ::step].astype(np.float32) + 1.0, axis=0))
    # (frame by frame, in OpenCV: whole-clip float copies and NumPy's max over interleaved
    # channels were most of the cost)
    def level(t):
        b = cv2.GaussianBlur(thumbs[t], (3, 3), 0).astype(np.float32)
        return cv2.multiply(b, (*(float(g) for g in inv[t]), 0.0))

    med = np.median(np.stack([level(t) for t in pick]), axis=0).astype(np.float32)
    dev = np.empty((n, h, w), np.float32)
    for t in range(n):
        channel_max_diff(level(t), med, dst=dev[t])
    noise = 1.4826 * float(np.median(dev[pick, ::2, ::2]))
    tau = max(8.0, 5.0 * noise)
    return (dev > tau).mean(axis=0, dtype=np.float32)
