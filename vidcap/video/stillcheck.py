"""A warning for silhouettes that came out nearly empty because nothing moved (issue 26).

A person who holds one pose for the whole clip is the scene as far as a plate estimated
from the clip can tell: every sample shows them, the plate takes them in and what
differs from it is noise, a hand's twitch, a fold of cloth. The silhouette stage still
"finds" a person in every frame (the largest blob of those small differences), so the
result looks complete and is nearly empty. What gives it away is the silhouettes' size:
a standing person fills a good part of the frame's height, and over a clip the boxes
round them cover more than a speck of the frame.
"""

from __future__ import annotations

import numpy as np

__all__ = ["still_warning"]

#: The silhouettes' median height under this share of the frame's height ...
MAX_HEIGHT = 0.2
#: ... and the union of their boxes over the clip under this share of the frame: a
#: held pose rendered over a real plate (``vidcap synth`` frozen, or swaying by a few
#: frames of arm motion) gives heights 0.05-0.11 and boxes over 0.3-0.9 % of the frame;
#: the benchmarks' real clips 0.19-0.83 and 4-60 %.
MAX_COVER = 0.03


def still_warning(bbox: np.ndarray, frame_hw: tuple[int, int]) -> str | None:
    """One line for the user when the silhouettes are small and stay in one small spot.

    Parameters
    ----------
    bbox : numpy.ndarray, shape (F, 4), int
        The person's box per frame, ``x0, y0, x1, y1`` (exclusive ends), -1 without a
        person.
    frame_hw : tuple of int
        The frame's height and width, pixels.

    Returns
    -------
    str or None
        The warning, or None when the silhouettes look like a person who moved.
    """
    h, w = int(frame_hw[0]), int(frame_hw[1])
    b = np.asarray(bbox, np.int64).reshape(-1, 4)
    found = (b[:, 0] >= 0) & (b[:, 2] > b[:, 0]) & (b[:, 3] > b[:, 1])
    if h <= 0 or w <= 0 or not found.any():
        return None  # (no person at all: the frames without one are told of elsewhere)
    fb = b[found]
    heights = (fb[:, 3] - fb[:, 1]) / h
    # (the union of the boxes by a 2D difference image: +1 at each box's top left
    # and bottom right, -1 at the other two corners, summed along both axes)
    x0, y0 = np.clip(fb[:, 0], 0, w), np.clip(fb[:, 1], 0, h)
    x1, y1 = np.clip(fb[:, 2], 0, w), np.clip(fb[:, 3], 0, h)
    diff = np.zeros((h + 1, w + 1), np.int64)
    np.add.at(diff, (y0, x0), 1)
    np.add.at(diff, (y1, x1), 1)
    np.add.at(diff, (y0, x1), -1)
    np.add.at(diff, (y1, x0), -1)
    cover = float((diff.cumsum(0).cumsum(1)[:h, :w] > 0).mean())
    height = float(np.median(heights))
    if height >= MAX_HEIGHT or cover >= MAX_COVER:
        return None
    return (f"warning: the silhouettes are nearly empty (median {100 * height:.0f} % of the "
            f"frame's height, {100 * cover:.1f} % of the frame over the whole clip): a "
            "person who keeps still is taken into the background estimated from the clip; "
            "give a photo of the empty scene with --background plate.png")
