"""Other blobs that never move are scene, not a second person (issue 26, Build 4).

Besides the followed person, the silhouette stage reports other person-sized blobs
(:attr:`vidcap.video.silhouette.Silhouettes.others`). A second person moves; a region the
plate gets wrong (a lit wall, a screen, a reflection the self-lit test missed)
differs from the plate in nearly every frame at the same place. Only moving blobs
should make the "more than one person" warning.
"""

from __future__ import annotations

import numpy as np

__all__ = ["static_rows"]

#: Boxes overlapping by this IoU are the same place.
SAME_PLACE_IOU = 0.7
#: A blob at the same place in at least this share of the frames is static.
STATIC_SHARE = 0.5


def static_rows(others: np.ndarray, n_frames: int, *, block: int = 2048) -> np.ndarray:
    """Which rows of ``others`` are blobs that stay put.

    Parameters
    ----------
    others : numpy.ndarray, shape (N, 6), int
        ``frame, x0, y0, x1, y1, area`` per blob (x1, y1 exclusive).
    n_frames : int
        Frames of the clip.
    block : int
        Rows compared at a time (memory: ``block * N`` IoUs).

    Returns
    -------
    numpy.ndarray, shape (N,), bool
        True where a box at nearly the same place (IoU >= :data:`SAME_PLACE_IOU`)
        occurs in at least :data:`STATIC_SHARE` of the frames (and in 3 or more).
    """
    others = np.asarray(others, np.int64).reshape(-1, 6)
    n = len(others)
    out = np.zeros(n, bool)
    need = max(3, int(np.ceil(STATIC_SHARE * n_frames)))
    if n < need:
        return out
    frame = others[:, 0]
    box = others[:, 1:5].astype(np.float64)
    area = (box[:, 2] - box[:, 0]) * (box[:, 3] - box[:, 1])
    for s in range(0, n, block):
        b = box[s:s + block, None]
        ix = np.clip(np.minimum(b[..., 2], box[:, 2]) - np.maximum(b[..., 0], box[:, 0]), 0, None)
        iy = np.clip(np.minimum(b[..., 3], box[:, 3]) - np.maximum(b[..., 1], box[:, 1]), 0, None)
        inter = ix * iy
        iou = inter / np.maximum(area[s:s + block, None] + area[None] - inter, 1e-9)
        same = iou >= SAME_PLACE_IOU
        # distinct frames with a box at the same place
        for i, row in enumerate(same):
            out[s + i] = len(np.unique(frame[row])) >= need
    return out
