"""The person's mirror image in a glossy floor or desk, cut from the silhouette.

A polished floor (a shopping centre, CAVIAR) or a varnished desk (CDnet office) shows
the person upside down below their feet or below the edge the body disappears behind.
Against the plate, that mirror image differs from the scene just as the person does,
only weaker: where the surface reflected the scene behind the person before, it now
reflects the person, so its difference from the plate is a fraction ``rho < 1`` of
the difference of the mirrored body pixel (``frame - plate`` at ``(x, y0 + d)`` is
about ``rho`` times that at ``(x, y0 - d)`` for a mirror line ``y0``). The
silhouette stage keeps it (it differs from the plate) and the mask grows a tail
below the feet: CAVIAR1's man standing at a shop window, IoU 0.66 with the truth.

:func:`drop_reflection` looks for that line on the mask's row profile: for each
candidate row ``y0`` in the lower half of the mask, the rows below it are compared
with their mirror rows above it, and the reflection is the longest run of rows
starting right under ``y0`` in which every row is *weak* against its mirror row:
its mean difference under :data:`WEAK` times the mirror row's, in the same direction
(the mean difference vectors' cosine above :data:`SAME_DIRECTION`), and of the same
hue where the mirror row's change is coloured (the difference minus its grey part).
Only pixels of those rows that are themselves weak against their mirror row are cut.
A run must start at the line: legs darker than the floor but lighter than the shirt
are weak against the shirt only far below the waist, under rows of legs that are not
(CDnet office, the jeans under the red T-shirt), and are kept.
"""

from __future__ import annotations

import numpy as np

__all__ = ["CUT_REFLECTIONS", "drop_reflection"]

#: On in :func:`vidcap.video.silhouette.extract_silhouettes` (the benchmark's
#: ``--no-reflections`` switches it off to compare).
CUT_REFLECTIONS = True

#: A reflected row's mean difference from the plate is under this share of its
#: mirror row's. Chosen on the tuning clips (benchmarks/silhouettes_real.py): 0.6
#: to 0.65 change no frame of ido_walk, sbi_candela, sbi_cavignal or
#: cdnet_office_stand and lift sbi_caviar1 (p10 0.681 -> 0.833) and
#: cdnet_office_enter (0.775 -> 0.794); 0.7 cuts a striding leg on sbi_candela
#: (frame 13, 0.91 -> 0.77), 0.8 cuts ido_walk's legs.
WEAK = 0.65
#: Cosine between a reflected row's mean difference vector (B, G, R) and its
#: mirror row's.
SAME_DIRECTION = 0.9
#: The hue test applies where the mirror row's change has a coloured part (the
#: difference minus its mean over channels) of at least this share of its length;
#: the two coloured parts' cosine must then exceed :data:`SAME_HUE`.
COLOURED = 0.25
SAME_HUE = 0.5
#: Rows (at least) a reflection must span, and the share of the mask's pixels its
#: rows must hold.
MIN_ROWS = 3
MIN_SHARE = 0.15
#: Masks smaller than this (pixels) are left alone.
MIN_PIXELS = 50


def drop_reflection(mask: np.ndarray, frame: np.ndarray, plate: np.ndarray,
                    gain=None) -> int:
    """Cut the person's mirror image below them from ``mask``, in place.

    Parameters
    ----------
    mask : numpy.ndarray, shape (H, W), uint8 (0 / 1) or bool
        The person's mask; changed in place.
    frame : numpy.ndarray, shape (H, W, 3), uint8
        The frame (BGR).
    plate : numpy.ndarray, shape (H, W, 3), uint8
        The background plate.
    gain : array-like, shape (3,), optional
        The frame's per-channel exposure relative to the plate (B, G, R; default 1).

    Returns
    -------
    int
        Pixels cut (0 when no reflection was found).
    """
    rows_any = np.flatnonzero(mask.any(axis=1))
    if len(rows_any) == 0:
        return 0
    top, bot = int(rows_any[0]), int(rows_any[-1])
    cols_any = np.flatnonzero(mask[top:bot + 1].any(axis=0))
    x0, x1 = int(cols_any[0]), int(cols_any[-1]) + 1
    m = mask[top:bot + 1, x0:x1].astype(bool)
    n = m.sum(axis=1).astype(np.float32)
    total = float(n.sum())
    height = bot - top + 1
    if total < MIN_PIXELS or height < 2 * MIN_ROWS + 2:
        return 0
    ref = plate[top:bot + 1, x0:x1].astype(np.float32)
    if gain is not None:
        ref *= np.asarray(gain, np.float32)[:3]
    diff = frame[top:bot + 1, x0:x1].astype(np.float32) - ref
    diff *= m[..., None]
    mag = np.abs(diff).sum(axis=-1)  # per-pixel L1 difference (0 outside the mask)
    per_row = np.maximum(n, 1.0)
    level = mag.sum(axis=1) / per_row  # (height,) mean L1 difference of the row
    vec = diff.sum(axis=1) / per_row[:, None]  # (height, 3) mean difference vector
    length = np.linalg.norm(vec, axis=1)
    unit = vec / np.maximum(length, 1e-6)[:, None]
    hue = vec - vec.mean(axis=1, keepdims=True)
    hue_len = np.linalg.norm(hue, axis=1)
    hue_unit = hue / np.maximum(hue_len, 1e-6)[:, None]
    coloured = hue_len >= COLOURED * length

    # Every candidate line y0 (rows of the box) against every distance d below it.
    lines = np.arange(height - 1 - MIN_ROWS, height // 2, -1)
    if len(lines) == 0:
        return 0
    d = np.arange(1, height)
    below = lines[:, None] + d[None, :]
    above = lines[:, None] - d[None, :]
    valid = (below < height) & (above >= 0)
    b, a = np.where(valid, below, 0), np.where(valid, above, 0)
    weak = valid & (level[b] < WEAK * level[a]) & (n[b] > 0) & (n[a] > 0)
    weak &= np.einsum("ijk,ijk->ij", unit[b], unit[a]) > SAME_DIRECTION
    weak &= ~coloured[a] | (np.einsum("ijk,ijk->ij", hue_unit[b], hue_unit[a]) > SAME_HUE)
    # The run of weak rows starting right under each line.
    run = np.where(weak.all(axis=1), weak.shape[1], np.argmin(weak, axis=1))
    counts = np.concatenate([np.zeros((len(lines), 1), np.float32),
                             np.cumsum(n[b] * valid, axis=1)], axis=1)
    pixels = counts[np.arange(len(lines)), run]
    pixels[run < MIN_ROWS] = 0
    best = int(np.argmax(pixels))
    if pixels[best] < MIN_SHARE * total:
        return 0
    y0, length_run = int(lines[best]), int(run[best])
    rb = np.arange(y0 + 1, y0 + 1 + length_run)
    ra = 2 * y0 - rb
    cut = m[rb] & (mag[rb] < WEAK * level[ra][:, None])
    sub = mask[top:top + 1 + y0 + length_run, x0:x1][y0 + 1:]
    sub[cut] = 0
    return int(cut.sum())
