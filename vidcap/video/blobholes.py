"""The holes of the person's blob that are not the person: large ones stay open."""

from __future__ import annotations

import cv2
import numpy as np

#: A hole of the person's blob larger than this share of the blob stays open: the
#: gap between legs apart, closed below by a plate error along the floor, is not
#: the person (small holes are: clothes the colour of the wall behind).
MAX_HOLE_SHARE = 0.12


def open_large_holes(mask: np.ndarray, contour: np.ndarray, fg: np.ndarray, p) -> None:
    """Clear, in ``mask`` (H, W) uint8 at full resolution, the large holes of the blob
    ``contour`` (work resolution, in the foreground ``fg``); ``p``: the silhouette
    stage's parameters (``work_size``, and ``fx``, ``fy``: full pixels per work pixel)."""
    x, y, w, h = cv2.boundingRect(contour)
    blob = np.zeros((h, w), np.uint8)
    cv2.drawContours(blob, [contour - np.array([x, y], np.int32)], 0, 1, cv2.FILLED)
    holes = blob & (fg[y:y + h, x:x + w] == 0)
    limit = MAX_HOLE_SHARE * cv2.countNonZero(blob)
    if cv2.countNonZero(holes) <= limit:
        return  # no hole can be large (most frames: labelling them cost ~0.2 ms)
    n, lab, st, _ = cv2.connectedComponentsWithStats(holes, connectivity=4)
    big = np.flatnonzero(st[1:, cv2.CC_STAT_AREA] > limit) + 1
    if not len(big):
        return
    hole = np.isin(lab, big).astype(np.uint8)
    if p.work_size is None:
        mask[y:y + h, x:x + w][hole > 0] = 0
        return
    X0, Y0 = int(round(x * p.fx)), int(round(y * p.fy))
    X1 = min(mask.shape[1], int(round((x + w) * p.fx)))
    Y1 = min(mask.shape[0], int(round((y + h) * p.fy)))
    full = cv2.resize(hole, (X1 - X0, Y1 - Y0), interpolation=cv2.INTER_NEAREST)
    mask[Y0:Y1, X0:X1][full > 0] = 0
