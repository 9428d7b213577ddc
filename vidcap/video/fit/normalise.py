"""Silhouette normalisation: crop to the bounding box, resize to a fixed body height.

:func:`normalise_mask` crops a silhouette to its bounding box and resizes it to a
fixed height (plus a margin), so the fitter's cost does not grow with the frame
size (seed 004 section 4.2: "we normalize the silhouette to a fixed size"). It is
the project's one normaliser; it shares the rasteriser's pixel convention
(:mod:`vidcap.video.fit.raster`: pixel ``(row i, column j)`` centred on ``(j, i)``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class NormalisedMask:
    """A silhouette cropped and scaled to a fixed body height.

    Attributes
    ----------
    mask : numpy.ndarray, shape (h, w), bool
        The normalised silhouette, including a margin of empty pixels around it.
    scale : float
        Normalised pixels per original pixel (vertical; the horizontal scale differs
        by the rounding of the width, see ``scale_xy``).
    scale_xy : numpy.ndarray, shape (2,)
        Normalised pixels per original pixel along x and y.
    offset : numpy.ndarray, shape (2,)
        Original-frame ``(x, y)`` of the normalised image's origin, so
        ``original = normalised / scale_xy + offset``.
    top, bottom : int
        Rows of the silhouette's first and last pixel in the normalised image.
    body : float or None
        The body's standing height (top of head to ankles) in normalised pixels when
        it was given apart from the silhouette's (None: the silhouette's height).
    """

    mask: np.ndarray
    scale: float
    scale_xy: np.ndarray
    offset: np.ndarray
    top: int
    bottom: int
    body: float | None = None

    @property
    def height(self) -> float:
        """Height of the silhouette in normalised pixels."""
        return float(self.bottom - self.top + 1)

    @property
    def body_height(self) -> float:
        """The body's standing height in normalised pixels, which the model is scaled
        to: ``body`` if given, else the silhouette's height (an upright body)."""
        return self.height if self.body is None else float(self.body)

    @functools.cached_property
    def count_tables(self) -> tuple[np.ndarray, np.ndarray]:
        """What the fitter counts pixels from, computed once per silhouette.

        Returns
        -------
        row_totals : numpy.ndarray, shape (h + 1,), int64
            Silhouette pixels in rows ``[0, y)``.
        prefix : numpy.ndarray, shape (2, h, w + 1), int32
            :func:`row_prefix_sums` of ``[ones, mask]``: channel 0 counts pixels,
            channel 1 silhouette pixels. Shared: not to be written to (left
            writeable because the compiled kernels are specialised for writeable
            arrays).
        """
        h, w = self.mask.shape
        prefix = np.empty((2, h, w + 1), np.int32)
        prefix[0] = np.arange(w + 1, dtype=np.int32)  # the prefix sums of a row of ones
        prefix[1, :, 0] = 0
        np.cumsum(self.mask, axis=1, dtype=np.int32, out=prefix[1, :, 1:])
        row_totals = np.zeros(h + 1, np.int64)
        np.cumsum(prefix[1, :, -1], out=row_totals[1:])
        return row_totals, prefix

    def to_original(self, points: np.ndarray) -> np.ndarray:
        """Map normalised ``(..., 2)`` points ``(x, y)`` to original-frame pixels."""
        return np.asarray(points, dtype=float) / self.scale_xy + self.offset

    def to_normalised(self, points: np.ndarray) -> np.ndarray:
        """Map original-frame ``(..., 2)`` points ``(x, y)`` to normalised pixels."""
        return (np.asarray(points, dtype=float) - self.offset) * self.scale_xy


def normalise_mask(mask: np.ndarray, *, height: int = 80, margin: float = 0.25,
                   body_height: float | None = None, origin=(0, 0)) -> NormalisedMask:
    """Crop a silhouette to its bounding box and resize it to a fixed height.

    Parameters
    ----------
    mask : numpy.ndarray, shape (H, W), bool
        The silhouette in the original frame (or a part of the frame holding all of
        it, see ``origin``).
    height : int
        Height of the silhouette's bounding box after resizing, in pixels; with
        ``body_height``, the height the body is resized to instead.
    margin : float
        Empty border added on every side, as a fraction of ``height``, so a model
        that overreaches the silhouette is still counted as negative error.
    body_height : float, optional
        The body's standing height in original pixels, when it is known apart from
        this silhouette (a crouch makes the silhouette shorter, raised arms taller).
    origin : (int, int)
        Original-frame ``(y, x)`` of ``mask``'s top-left pixel, when ``mask`` is a crop
        of the frame (:meth:`vidcap.video.masks.MaskStack.crop`): the result is the same as
        for the whole frame.

    Returns
    -------
    NormalisedMask

    Raises
    ------
    ValueError
        If ``mask`` is not 2-D or has no foreground pixel.
    """
    mask = np.asarray(mask)
    if mask.ndim != 2:
        raise ValueError(f"mask must be (H, W), got shape {mask.shape}")
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        raise ValueError("mask is empty")
    r0, r1 = rows[0], rows[-1] + 1
    cols = np.flatnonzero(mask[r0:r1].any(axis=0))  # only the rows with the silhouette
    c0, c1 = cols[0], cols[-1] + 1
    crop = mask[r0:r1, c0:c1].astype(np.float32)
    if body_height is None:
        n_rows, body = height, None
    else:
        if not body_height > 0:
            raise ValueError(f"body_height must be positive, got {body_height}")
        n_rows, body = max(1, int(round((r1 - r0) * height / body_height))), float(height)
    s = n_rows / (r1 - r0)
    w = max(1, int(round((c1 - c0) * s)))
    interp = cv2.INTER_AREA if s < 1 else cv2.INTER_LINEAR
    small = cv2.resize(crop, (w, n_rows), interpolation=interp) >= 0.5
    pad = int(round(margin * max(height, n_rows)))
    out = np.zeros((n_rows + 2 * pad, w + 2 * pad), dtype=bool)
    out[pad : pad + n_rows, pad : pad + w] = small
    # Pixel centres: original x_o = c0 + (x_n - pad + 0.5) / s - 0.5.
    sx = w / (c1 - c0)
    c0, r0 = c0 + int(origin[1]), r0 + int(origin[0])  # from here on, frame pixels
    offset = np.array([c0 - 0.5 - (pad - 0.5) / sx, r0 - 0.5 - (pad - 0.5) / s])
    return NormalisedMask(out, float(s), np.array([sx, s]), offset, pad, pad + n_rows - 1,
                          body)


__all__ = ["NormalisedMask", "normalise_mask"]
