"""A frame's exposure gain applied to the plate by table lookup.

The silhouette stage scales the plate to each frame's exposure (a gain per channel,
:func:`vidcap.video.silhouette._gain`) three or four times a frame: for the whole work
image, for the edge band's box at full resolution and for the reflection test.
``cv2.multiply`` by a scalar converts every byte to floating point; the product of a byte
and a fixed gain takes only 256 values, so they are computed once (by ``cv2.multiply``
itself, on the 256 byte values: the same rounding and saturation, bit for bit) and
looked up with ``cv2.LUT`` (3-5x faster on a 640x480 frame).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["GainedPlate", "apply_gain", "gain_table"]

#: Every byte value, once per channel: (256, 1, 3) uint8.
_BYTES = np.repeat(np.arange(256, dtype=np.uint8).reshape(256, 1, 1), 3, axis=2)


def gain_table(gain) -> np.ndarray:
    """The table of ``cv2.multiply(byte, gain)`` for every byte and channel.

    Parameters
    ----------
    gain : array_like, shape (3,)
        Per-channel gain (B, G, R), dimensionless.

    Returns
    -------
    numpy.ndarray, shape (256, 1, 3), uint8
        Row v holds ``saturate(round(v * gain[c]))`` per channel c, as OpenCV rounds.
    """
    g = np.asarray(gain, np.float64)
    return cv2.multiply(_BYTES, (float(g[0]), float(g[1]), float(g[2]), 0.0))


def apply_gain(image: np.ndarray, gain) -> np.ndarray:
    """``cv2.multiply(image, (*gain, 0))`` for a 3-channel uint8 image, by table lookup.

    Parameters
    ----------
    image : numpy.ndarray, shape (H, W, 3), uint8
        A plate or a crop of one (any strides).
    gain : array_like, shape (3,)
        Per-channel gain (B, G, R).

    Returns
    -------
    numpy.ndarray, shape (H, W, 3), uint8
        A new array, equal to the product ``cv2.multiply`` gives, bit for bit.

    Examples
    --------
    >>> import numpy as np, cv2
    >>> img = np.arange(48, dtype=np.uint8).reshape(4, 4, 3) * 5
    >>> g = (1.07, 0.93, 1.5)
    >>> bool((apply_gain(img, g) == cv2.multiply(img, (*g, 0.0))).all())
    True
    """
    return cv2.LUT(image, gain_table(gain))


class GainedPlate:
    """A plate at one frame's exposure, computed crop by crop as the frame's stages ask.

    The full-resolution stages of a silhouette (the edge band,
    :func:`vidcap.video.edgeband.edge_by_contrast`, then the reflection test,
    :func:`vidcap.video.reflection.drop_reflection`) each scaled their crop of the plate,
    the reflection test twice, and each crop lies inside the edge band's: a crop inside
    the last one computed is cut from it (the lookup is per pixel: the same bytes).
    At 1000x1000 that is ~0.3 s of the silhouettes' CPU over 394 frames.

    Parameters
    ----------
    plate : numpy.ndarray, shape (H, W, 3), uint8
    gain : array_like, shape (3,), or None
        The frame's per-channel gain (B, G, R); None: the plate as it is.
    """

    def __init__(self, plate: np.ndarray, gain=None):
        self.plate = plate
        self.table = None if gain is None else gain_table(gain)
        self._last = None  # ((y0, y1, x0, x1), the crop at the gain)

    def crop(self, y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
        """``plate[y0:y1, x0:x1]`` at the gain (a view of the plate or of a crop computed
        before: do not write to it)."""
        if self.table is None:
            return self.plate[y0:y1, x0:x1]
        if self._last is not None:
            (a0, a1, b0, b1), done = self._last
            if a0 <= y0 and y1 <= a1 and b0 <= x0 and x1 <= b1:
                return done[y0 - a0:y1 - a0, x0 - b0:x1 - b0]
        done = cv2.LUT(self.plate[y0:y1, x0:x1], self.table)
        self._last = ((y0, y1, x0, x1), done)
        return done
