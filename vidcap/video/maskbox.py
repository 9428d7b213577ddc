"""The bounding box of a mask's pixels, widened and clipped to the frame.

Several plate passes work only round the person (a dilation, a ghost test, a re-take):
the same values as over the whole frame at the cost of the person's area. This is the
box they all take.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["padded_box"]


def padded_box(mask: np.ndarray, ry: int, rx: int | None = None
               ) -> tuple[slice, slice] | None:
    """The bounding box of ``mask``'s non-zero pixels and ``ry`` rows, ``rx`` columns
    round it, clipped to the frame.

    Parameters
    ----------
    mask : numpy.ndarray, shape (H, W), uint8
    ry : int
        Rows added above and below, pixels.
    rx : int, optional
        Columns added left and right, pixels (default ``ry``).

    Returns
    -------
    tuple of slice or None
        ``(rows, columns)`` to index (H, W, ...) arrays with; None when ``mask`` is
        empty.
    """
    x, y, bw, bh = cv2.boundingRect(mask)
    if bw == 0 or bh == 0:
        return None
    rx = ry if rx is None else rx
    h, w = mask.shape[:2]
    return (slice(max(0, y - ry), min(h, y + bh + ry)),
            slice(max(0, x - rx), min(w, x + bw + rx)))
