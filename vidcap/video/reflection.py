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
its mean difference under :data:`WEAK` times the mirror row's (the first few rows,
where the feet touch the floor, under :data:`START_WEAK`), in the same direction
(the mean difference vectors' cosine above :data:`SAME_DIRECTION`), and of the same
hue where the mirror row's change is coloured (the difference minus its grey part);
most of the run's pixels must also be of another colour than their mirror rows
(:data:`OTHER_COLOUR`, :data:`OTHER_SHARE`; a run that fails this is cut short to its
longest start that passes, :data:`SHORTEN_RUN`). Only pixels of those
rows that are themselves weak against their mirror row are cut (rows are summed in
bins of the silhouette stage's work scale).

What looks the same and is kept: a run must start at the line, so legs weaker than
the shirt only far below the waist, under rows of legs that are not (CDnet office, the
jeans under the red T-shirt), stay; black trousers against a dark floor below the wall
line (Sports2D) differ weakly from the plate, in the same direction as above the line,
but keep the trousers' colour (6 of its 300 frames still lose them). Legs of the
jacket's colour, only lighter, on a plain floor would still be cut (none among the
benchmark's clips). Cost: a one-line test on the row profile stops most frames; +7-14 %
CPU on the silhouettes of a 640x480 walker (~0.2 ms a frame).
"""

from __future__ import annotations

import cv2
import numpy as np

from vidcap.video.gaintable import GainedPlate

__all__ = ["CUT_REFLECTIONS", "drop_reflection"]

#: On in :func:`vidcap.video.silhouette.extract_silhouettes` (the benchmark's
#: ``--no-reflections`` switches it off to compare).
CUT_REFLECTIONS = True

#: A reflected row's mean difference from the plate is under this share of its
#: mirror row's. Chosen on the tuning clips (benchmarks/silhouettes_real.py, before
#: the colour test): 0.6 to 0.65 change no frame of ido_walk, sbi_candela,
#: sbi_cavignal or cdnet_office_stand and lift sbi_caviar1 (p10 0.681 -> 0.833) and
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
#: A run is a reflection when at least :data:`OTHER_SHARE` of its pixels lie in bins
#: whose mean colour differs from their mirror bin's by more than :data:`OTHER_COLOUR`
#: times their own difference from the plate (L1): a reflection takes the surface's
#: colour, tinted; trousers carried on below a floor line keep theirs. Chosen on the
#: tuning clips: without it sports2d_walk_turn's lower legs go (0.845 / 0.807 ->
#: 0.712 / 0.664 against MediaPipe); with 0.5 and 1.0 it stays 0.845 / 0.807 (6 of 300
#: frames lose ~0.14), sbi_caviar1 0.984 / 0.806, cdnet_office_enter 0.906 / 0.794;
#: 0.5 and 0.75: sports2d p10 0.798; 0.7 and 0.75: sbi_caviar1 0.949 / 0.681; the
#: test on every bin of the run (0.75): sbi_caviar1 0.939 / 0.785, cdnet_office_enter
#: 0.901 / 0.776.
OTHER_COLOUR = 1.0
OTHER_SHARE = 0.5
#: Rows (at least) a reflection must span, and the share of the mask's pixels its
#: rows must hold.
MIN_ROWS = 3
MIN_SHARE = 0.15
#: Rows are summed in bins so that the mask spans at most this many, which keeps the
#: pairwise tables small.
MAX_BINS = 256
#: Masks smaller than this (pixels) are left alone.
MIN_PIXELS = 50
#: The run's first :data:`START_SHARE` of the mask's bins need only be under this share
#: of their mirror bins' level (and their pixels are cut under it): where the feet touch
#: a polished floor its mirror image is strongest. sbi_caviar1 (tuning) standing at the
#: shop window: the rows right under his feet 0.72-0.78 of the legs' difference, then
#: 0.4-0.6; under :data:`WEAK` alone no run starts at the line (frame 170: 680 false
#: pixels). With 0.8: sbi_caviar1 0.981 / 0.793 -> 0.983 / 0.828, cdnet_office_enter
#: 0.911 / 0.817 -> 0.915 / 0.840 (the desk's reflection of his jeans), sbi_caviar2
#: (validation) 0.863 -> 0.868, ido_walk unchanged; with :data:`SHORTEN_RUN` on, 0.75
#: gave caviar1 0.983 / 0.833 and office_enter 0.914 / 0.837, 0.8 0.983 / 0.837 and
#: 0.915 / 0.840, 0.85 0.979 / 0.839 and 0.915 / 0.841 (wt-sil6). None: off
#: (:data:`WEAK` for the whole run).
START_WEAK: float | None = 0.8
#: ... share of the mask's bins (at least one) from the line.
START_SHARE = 0.06
#: A run that fails the colour test (:data:`OTHER_SHARE`) as a whole is cut short at
#: its longest start that passes it, instead of dropped. A glossy floor with a dark
#: band across it (sbi_caviar1, tuning: the man standing at the shop window) mirrors
#: his dark trousers on the light floor in the floor's tint, then on the dark band in
#: about the trousers' own colour: the band's bins fail the test, the whole run held
#: 0.42-0.49 of its pixels in other colours, and the reflection stayed (frame 206: 1,050
#: false pixels, IoU 0.69 -> 0.86 cut short). **Off** (wt-sil6): alone sbi_caviar1 p10
#: 0.793 -> 0.799 but sports2d_walk_turn (tuning, against MediaPipe's masks) p10 0.806 ->
#: 0.801; with :data:`START_WEAK` caviar1 0.983 / 0.828 -> 0.983 / 0.837 but walk_turn
#: 0.806 -> 0.792 (frames 20, 85, 251: her black trousers under the floor line cut; rows
#: of a low level against the dark floor pass the colour test on small colour shifts).
SHORTEN_RUN = False


def _cosines(u: np.ndarray) -> np.ndarray:
    """(n, n) dot products of the rows of ``u`` (n, 3): three outer products (faster
    than a matrix product or a broadcast sum at this size)."""
    return (np.multiply.outer(u[:, 0], u[:, 0]) + np.multiply.outer(u[:, 1], u[:, 1])
            + np.multiply.outer(u[:, 2], u[:, 2]))


def drop_reflection(mask: np.ndarray, frame: np.ndarray, plate: np.ndarray,
                    gain=None, row_step: int = 1, rect=None) -> int:
    """Cut the person's mirror image below them from ``mask``, in place.

    Parameters
    ----------
    mask : numpy.ndarray, shape (H, W), uint8 (0 / 1) or bool
        The person's mask; changed in place.
    frame : numpy.ndarray, shape (H, W, 3), uint8
        The frame (BGR).
    plate : numpy.ndarray, shape (H, W, 3), uint8, or GainedPlate
        The background plate, or the plate at the frame's exposure already
        (:class:`vidcap.video.gaintable.GainedPlate`; then ``gain`` is not used).
    gain : array-like, shape (3,), optional
        The frame's per-channel exposure relative to the plate (B, G, R; default 1).
    row_step : int
        Rows summed per bin (the silhouette stage passes its work scale: a 640x480
        frame is thresholded at half size); more when the mask spans over
        :data:`MAX_BINS` bins.
    rect : (int, int, int, int), optional
        The mask's bounding rectangle ``(x, y, w, h)`` when the caller has it.

    Returns
    -------
    int
        Pixels cut (0 when no reflection was found).
    """
    m8 = mask.view(np.uint8) if mask.dtype == bool else mask
    x0, top, w, height = cv2.boundingRect(m8) if rect is None else rect
    if w == 0 or height < 2 * MIN_ROWS + 2:
        return 0
    m = m8[top:top + height, x0:x0 + w]
    box = frame[top:top + height, x0:x0 + w]
    if not isinstance(plate, GainedPlate):
        plate = GainedPlate(plate, None if gain is None else
                            tuple(float(v) for v in np.asarray(gain, np.float64)))

    def scaled(r0):
        """The plate's rows from ``r0`` on, at the frame's exposure."""
        return plate.crop(top + r0, top + height, x0, x0 + w)

    def row_level(r0, rows):
        """The summed L1 difference over the mask per row, rows ``r0`` on against the
        plate rows ``rows`` (the channels summed as columns: a 3-channel row reduction
        is slow in OpenCV)."""
        ad = cv2.absdiff(box[r0:], rows)
        adm = cv2.bitwise_and(ad, ad, mask=m[r0:])
        return cv2.reduce(adm.reshape(height - r0, -1), 1, cv2.REDUCE_SUM,
                          dtype=cv2.CV_32F)[:, 0]

    # Per-row sums (OpenCV reductions), binned so the tables stay small.
    n_row = cv2.reduce(m, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32F)[:, 0]
    total = float(n_row.sum())
    if total < MIN_PIXELS:
        return 0
    step = max(int(row_step), -(-height // MAX_BINS))
    nb = -(-height // step)

    def binned(v, first=0):  # ``v``: the rows from bin ``first`` on
        if step == 1:
            return v
        k = nb - first
        pad = k * step - len(v)
        v = np.concatenate([v, np.zeros((pad,) + v.shape[1:], v.dtype)]) if pad else v
        return v.reshape((k, step) + v.shape[1:]).sum(axis=1)

    n = binned(n_row)
    per_bin = np.maximum(n, 1.0)
    min_bins = max(1, -(-MIN_ROWS // step))
    # A run starts with the bin right under a line weaker than the bin right above it:
    # no such line in the lower half, no reflection (most frames stop here; only the
    # lower half's differences are summed for it).
    mid = nb // 2
    if nb - 1 - min_bins <= mid:
        return 0
    gate = WEAK if START_WEAK is None else max(WEAK, START_WEAK)
    lower = binned(row_level(mid * step, scaled(mid * step)), mid) / per_bin[mid:]
    if not np.any(lower[2:nb - min_bins + 1 - mid] < gate * lower[:nb - min_bins - 1 - mid]):
        return 0
    ref = scaled(0)  # once for the rest (the lower half alone above)
    level = binned(row_level(0, ref)) / per_bin
    seen = n > 0
    # weak_pair[i, j]: bin i is weak against bin j. The level alone first: most of the
    # remaining frames stop here (no run of bins weaker than their mirror bins).
    weak_pair = (level[:, None] < WEAK * level[None, :]) & seen[:, None] & seen[None, :]
    start = None
    if START_WEAK is not None:
        k = max(1, round(START_SHARE * nb))
        start = ((level[:, None] < START_WEAK * level[None, :]) & seen[:, None]
                 & seen[None, :], k)
    found = _best_run(weak_pair, n, min_bins, MIN_SHARE * total, start=start)
    if found is None:
        return 0
    # (nb, 3) mean frame colour, and the mean difference from the plate
    colour = binned(_row_sums(box, m)).astype(np.float32) / per_bin[:, None]
    vec = colour - binned(_row_sums(ref, m)).astype(np.float32) / per_bin[:, None]
    # Not the same clothes carried on: a reflection's colour is the surface's, tinted;
    # legs against a darker floor are weaker than the shirt against a white wall but of
    # the shirt's colour (sports2d_walk_turn: black trousers).
    far = np.abs(colour[:, None, :] - colour[None, :, :]).sum(axis=-1)
    other = far > OTHER_COLOUR * level[:, None]
    length = np.linalg.norm(vec, axis=1)
    hue = vec - vec.mean(axis=1, keepdims=True)
    hue_len = np.linalg.norm(hue, axis=1)
    alike = _cosines(vec / np.maximum(length, 1e-6)[:, None]) > SAME_DIRECTION
    coloured = hue_len >= COLOURED * length
    alike &= ~coloured[None, :] | (
        _cosines(hue / np.maximum(hue_len, 1e-6)[:, None]) > SAME_HUE)
    weak_pair &= alike
    if start is not None:
        start = (start[0] & alike, start[1])
    found = _best_run(weak_pair, n, min_bins, MIN_SHARE * total, other, start)
    if found is None:
        return 0
    return _cut_run(found, box, ref, m, level, step, start)


def _row_sums(image: np.ndarray, m: np.ndarray) -> np.ndarray:
    """(rows, 3) int32 sums of the 3-channel ``image``'s pixels under the mask ``m``,
    per row: ``cv2.reduce`` gives the same integers as NumPy's ``sum(axis=1)`` about 8x
    faster (NumPy's strided reduction with a cast took ~4 ms a 700x300 box at
    1000x1000)."""
    masked = cv2.bitwise_and(image, image, mask=m)
    return cv2.reduce(masked, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S)[:, 0]


def _cut_run(found, box, ref, m, level, step: int, start) -> int:
    """Clear the pixels of the run ``found`` = (line bin, run length) in the mask box
    ``m`` that are weak against their mirror bins' ``level``; the pixels cut."""
    y0, length_run = found
    r0, r1 = (y0 + 1) * step, min(len(m), (y0 + 1 + length_run) * step)
    rows = np.arange(r0, r1) // step
    mirror = 2 * y0 - rows  # each row's mirror bin
    # the rows' per-pixel L1 difference
    mag = cv2.absdiff(box[r0:r1], ref[r0:r1]).astype(np.int16).sum(axis=-1)
    factor = np.full(len(rows), WEAK, np.float32)
    if start is not None:
        factor[rows - y0 <= start[1]] = START_WEAK
    cut = (m[r0:r1] > 0) & (mag < (factor * level[mirror])[:, None])
    m[r0:r1][cut] = 0
    return int(cut.sum())


def _best_run(weak_pair: np.ndarray, n: np.ndarray, min_bins: int, min_pixels: float,
              other=None, start=None):
    """The line (bin) whose run of bins weak against their mirror bins, starting right
    under it, holds the most mask pixels: ``(line, run length)``, or None when no run
    spans ``min_bins`` and ``min_pixels``. Lines in the lower half of the mask only."""
    nb = len(n)
    lines = np.arange(nb - 1 - min_bins, nb // 2, -1)
    if len(lines) == 0:
        return None
    d = np.arange(1, nb - lines[-1])
    below = lines[:, None] + d[None, :]
    above = lines[:, None] - d[None, :]
    valid = (below < nb) & (above >= 0)
    b, a = np.where(valid, below, 0), np.where(valid, above, 0)
    weak = valid & weak_pair[b, a]
    if start is not None:  # (pair table, bins): the run's first bins may be less weak
        weak |= valid & start[0][b, a] & (d[None, :] <= start[1])
    run = np.where(weak.all(axis=1), weak.shape[1], np.argmin(weak, axis=1))
    counts = np.concatenate([np.zeros((len(lines), 1), np.float32),
                             np.cumsum(n[b] * valid, axis=1)], axis=1)
    pixels = counts[np.arange(len(lines)), run]
    pixels[run < min_bins] = 0
    if other is not None:  # most of the run's pixels of another colour than their mirror
        col = np.concatenate([np.zeros((len(lines), 1), np.float32),
                              np.cumsum(n[b] * (valid & other[b, a]), axis=1)], axis=1)
        if SHORTEN_RUN:
            # The longest start of the run (>= min_bins) that passes the test.
            at = np.arange(counts.shape[1])
            ok = ((col >= OTHER_SHARE * counts) & (at <= run[:, None])
                  & (at >= min_bins))
            run = counts.shape[1] - 1 - np.argmax(ok[:, ::-1], axis=1)
            pixels = np.where(ok.any(axis=1), counts[np.arange(len(lines)), run], 0)
        else:
            pixels[col[np.arange(len(lines)), run] < OTHER_SHARE * pixels] = 0
    best = int(np.argmax(pixels))
    if pixels[best] < min_pixels:
        return None
    return int(lines[best]), int(run[best])
