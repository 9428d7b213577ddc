"""The colour frames the fit's cues read, kept small: each cut to the person's box.

The cues (:mod:`vidcap.video.fit.cues`) read the colour frame on the normalised
silhouette's ~80-pixel grid, near the silhouette only (their maps are zero outside
it). A whole clip of full frames is far more than that: 640x480 colour is 0.9 MB a
frame. :class:`FrameCrops` keeps each frame's silhouette box with a small margin,
averaged over ``d`` x ``d`` pixels where the person is tall enough that the grid is
still two crop pixels or more per normalised pixel (typically 20-60 KB a frame), and
hands the cue image of any normalisation of that frame out
(:meth:`FrameCrops.cue_image`). The pipeline makes the crops as it extracts the
silhouettes and sends each chunk of frames' crops with its silhouettes to the fit's
workers (:mod:`vidcap.video.fit.parallel`); :func:`vidcap.video.fit.tracking.fit_sequence`
turns whole frames it is given into crops the same way, so a serial and a chunked
fit read the same pixels.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import cv2
import numpy as np

from vidcap.video.fit.normalise import NormalisedMask

#: Crop margin around the silhouette box: this fraction of the box's height, at least
#: ``_MARGIN_PX`` pixels. The cue maps are zero one normalised pixel outside the
#: silhouette, and their Sobel filter and resampling reach two more (about 8 frame
#: pixels at the usual scale); beyond the crop its border pixels are repeated.
_MARGIN = 0.06
_MARGIN_PX = 8
#: The crop keeps at least this many of its pixels per normalised pixel (``d`` is the
#: largest whole factor that does).
_OVERSAMPLE = 1.5


class FrameCrops(Sequence):
    """Colour frames (F, H, W, 3) BGR uint8, each kept as its silhouette's box.

    Parameters
    ----------
    shape : (int, int), optional
        Frame height and width, pixels (default: the first frame's).
    height : int
        The fit's normalised silhouette height (``fit_sequence``'s ``height``): the
        crops are averaged down no further than it needs.
    """

    def __init__(self, shape=None, *, height: int = 80):
        self.frame_shape = None if shape is None else (int(shape[0]), int(shape[1]))
        self.height = int(height)
        self.crops: list = []  # (h, w, 3) uint8, or None (no silhouette)
        self.origins: list = []  # (x0, y0) frame px of each crop's first pixel
        self.factors: list = []  # d: frame pixels per crop pixel, each way

    @classmethod
    def from_frames(cls, frames, masks, *, height: int = 80) -> FrameCrops:
        """Crops of ``frames`` (F, H, W, 3) around the silhouettes ``masks`` (F, H, W)
        bool (or a :class:`vidcap.video.masks.MaskStack`)."""
        boxes = getattr(masks, "boxes", None)
        out = None
        for k, frame in enumerate(frames):
            frame = np.asarray(frame)
            if out is None:
                out = cls(frame.shape[:2], height=height)
            box = tuple(boxes[k]) if boxes is not None else _box(np.asarray(masks[k]))
            out.append(frame, box)
        if out is None:
            return cls(np.shape(masks)[1:3], height=height)
        return out

    def append(self, frame: np.ndarray, box) -> None:
        """Add one frame (H, W, 3) uint8 and its silhouette box ``(y0, y1, x0, x1)``
        (empty, ``y0 == y1``, when the frame has no silhouette)."""
        if self.frame_shape is None:
            self.frame_shape = tuple(frame.shape[:2])
        if frame.shape[:2] != self.frame_shape:
            raise ValueError(f"a {frame.shape[:2]} frame among {self.frame_shape} ones")
        y0, y1, x0, x1 = (int(v) for v in box)
        if y1 <= y0 or x1 <= x0:
            self.crops.append(None)
            self.origins.append((0, 0))
            self.factors.append(1)
            return
        H, W = self.frame_shape
        m = max(_MARGIN_PX, int(np.ceil(_MARGIN * (y1 - y0))))
        y0, y1, x0, x1 = max(y0 - m, 0), min(y1 + m, H), max(x0 - m, 0), min(x1 + m, W)
        d = max(1, int((y1 - y0) / (_OVERSAMPLE * self.height)))
        y1, x1 = y0 + max(d, (y1 - y0) // d * d), x0 + max(d, (x1 - x0) // d * d)
        crop = np.ascontiguousarray(frame[y0:y1, x0:x1])
        if d > 1 and crop.shape[0] >= d and crop.shape[1] >= d:
            # a whole factor: INTER_AREA's exact d x d box average
            crop = cv2.resize(crop, (crop.shape[1] // d, crop.shape[0] // d),
                              interpolation=cv2.INTER_AREA)
        else:
            d = 1
        self.crops.append(crop)
        self.origins.append((x0, y0))
        self.factors.append(d)

    def extend(self, other: FrameCrops) -> None:
        """Append every frame of another :class:`FrameCrops` of the same frame size."""
        if self.frame_shape is None:
            self.frame_shape = other.frame_shape
        if other.frame_shape != self.frame_shape and other.frame_shape is not None:
            raise ValueError(f"{other.frame_shape} frames added to {self.frame_shape} ones")
        self.crops.extend(other.crops)
        self.origins.extend(other.origins)
        self.factors.extend(other.factors)

    def __len__(self) -> int:
        return len(self.crops)

    def __getitem__(self, key):
        if isinstance(key, slice):
            out = FrameCrops(self.frame_shape, height=self.height)
            out.crops, out.origins = self.crops[key], self.origins[key]
            out.factors = self.factors[key]
            return out
        raise TypeError("FrameCrops are sliced (frames s:e), not indexed; "
                        "use cue_image(k, norm)")

    @property
    def nbytes(self) -> int:
        """Bytes held by the crops."""
        return int(sum(c.nbytes for c in self.crops if c is not None))

    def cue_image(self, k: int, norm: NormalisedMask) -> np.ndarray:
        """Frame ``k`` on ``norm``'s grid, as :func:`vidcap.video.fit.cues.cue_image`
        gives it of the whole frame (the same but for pixels beyond the crop, which
        repeat its border)."""
        from vidcap.video.fit.cues import cue_image

        crop = self.crops[k]
        if crop is None:
            return np.zeros((*norm.mask.shape, 3), np.float32)
        (x0, y0), d = self.origins[k], self.factors[k]
        # crop pixel j's centre is frame pixel x0 + j d + (d - 1) / 2
        shift = np.array([x0, y0], float) + (d - 1) / 2.0
        on_crop = dataclasses.replace(norm, scale_xy=norm.scale_xy * d,
                                      offset=(norm.offset - shift) / d)
        return cue_image(crop, on_crop)


def _box(mask: np.ndarray) -> tuple[int, int, int, int]:
    rows = np.flatnonzero(mask.any(axis=1))
    if not rows.size:
        return (0, 0, 0, 0)
    cols = np.flatnonzero(mask[rows[0]:rows[-1] + 1].any(axis=0))
    return (int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1)


def crops_from_video(video, masks, *, height: int = 80, progress=None) -> FrameCrops:
    """:class:`FrameCrops` of ``video``'s frames (decoded with
    :func:`vidcap.io.video.iter_frames`) around the silhouettes ``masks`` (F, H, W)
    (a :class:`vidcap.video.masks.MaskStack` or an array), for the frames both have.
    ``progress``: wraps an iterator (``progress(it, total=F)``)."""
    from vidcap.io.video import iter_frames

    crops = FrameCrops(np.shape(masks)[1:3], height=height)
    boxes = getattr(masks, "boxes", None)
    frames = iter_frames(video, stop=len(masks))
    for k, frame in enumerate(frames if progress is None else progress(frames,
                                                                       total=len(masks))):
        box = tuple(boxes[k]) if boxes is not None else _box(np.asarray(masks[k]))
        crops.append(frame, box)
    return crops


def as_frame_crops(frames, masks, *, height: int = 80) -> FrameCrops:
    """``frames`` as :class:`FrameCrops` (whole frames (F, H, W, 3) are cut around
    ``masks``; crops are returned as they are)."""
    if isinstance(frames, FrameCrops):
        return frames
    return FrameCrops.from_frames(frames, masks, height=height)


__all__ = ["FrameCrops", "as_frame_crops", "crops_from_video"]
