"""Where the person is in each frame, read from the silhouettes: the frames where they
are mostly outside the picture (:func:`partly_outside`) and their horizontal track
(:func:`person_track`, the walking direction the orientation proposal uses)."""

from __future__ import annotations

import numpy as np

from vidcap.video.masks import frames_with_pixels, pixel_counts, touches_border


def partly_outside(masks, *, min_share: float = 0.7, min_reference: int = 5) -> np.ndarray:
    """Frames where much of the person is outside the image, (F,) bool.

    A silhouette that reaches the image's border and covers less than ``min_share``
    of the person's usual area (the median over the frames that do not reach it) is
    a person walking out of (or into) the picture. The 2D model fitted to what is
    left of them is mostly guesswork (a synthetic walk leaving the frame: 2D error
    6-81 % of the body's height in those frames, against 1-2 % before), so the
    pipeline fills such frames from their neighbours, as frames without a person.
    Gait moves the area by about 15 %; a person cut for the whole clip (feet below
    the frame) has no reference and nothing is dropped.

    Parameters
    ----------
    masks : MaskStack or numpy.ndarray, shape (F, H, W) bool
    min_share : float
        Share of the usual area below which a border-touching frame is dropped.
    min_reference : int
        Fewest frames clear of the border that make a usable reference area.

    Returns
    -------
    numpy.ndarray of bool, shape (F,)
    """
    area = pixel_counts(masks)
    edge = touches_border(masks)
    clear = (area > 0) & ~edge
    if clear.sum() < min_reference:
        return np.zeros(len(area), bool)
    return edge & (area < min_share * np.median(area[clear]))


def person_track(bbox, masks, *, exclude=None) -> np.ndarray | None:
    """Horizontal centre of the person's box per frame, gaps interpolated.

    Parameters
    ----------
    bbox : array_like, shape (F, 4)
        ``x0, y0, x1, y1`` per frame (pixels).
    masks : MaskStack or numpy.ndarray, shape (F, H, W) bool
        Frames with an empty mask count as gaps.
    exclude : array_like of bool, shape (F,), optional
        More frames to treat as gaps (:func:`partly_outside`).

    Returns
    -------
    numpy.ndarray, shape (F,), or None
        Pixels; None when no frame shows the person or ``bbox`` is malformed.
    """
    bb = np.asarray(bbox, float)
    if bb.ndim != 2 or bb.shape[1] != 4:
        return None
    seen = frames_with_pixels(masks)
    if exclude is not None:
        seen = seen & ~np.asarray(exclude, bool)
    track = np.where(seen, 0.5 * (bb[:, 0] + bb[:, 2]), np.nan)
    ok = np.isfinite(track)
    if not ok.any():
        return None
    t = np.arange(len(track))
    return np.interp(t, t[ok], track[ok])

__all__ = ["partly_outside", "person_track"]
