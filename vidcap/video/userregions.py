"""The user's regions as pixel masks for the silhouette stage (issue 26, build item 5).

Two annotation events (:mod:`vidcap.video.annotations`) tell the silhouette stage what
the image alone gets wrong:

* ``scene_region``: pixels that are never the person, for the whole clip (a lamp, a
  lit wall, a mirror: scenery that differs from the plate in every frame and would
  merge with the person's blob);
* ``person_box``: in one frame, the person is inside this box.

:class:`UserRegions` turns them into one mask per frame of the pixels that *may* be
the person (:meth:`UserRegions.keep`). :func:`vidcap.video.silhouette.silhouette_frame`
clears everything else from the foreground before it picks the person's blob (so a
removed region neither joins the person nor is chosen instead of them, nor counts as
another person) and from the final mask (the edge refinement cannot bring it back).
The frames after a person box follow the blob chosen in it, as they follow the
person from frame to frame anyway.

:func:`region_cache_part` is what the silhouette stage's cache key adds for them:
nothing when there are none (old cache entries stay valid), and the events
themselves otherwise, so adding, moving or deleting a region redoes the silhouettes
while the other events (depth, orientation, joints, sides) never do.
"""

from __future__ import annotations

import json

import cv2
import numpy as np

from vidcap.video.annotations import Annotations, Event


def region_cache_part(annotations: Annotations | None) -> list[dict]:
    """The region events as JSON objects, sorted (empty when there are none): the
    part of the silhouette stage's cache key that depends on the user. A scene region's
    frame (where it was drawn) is left out: it holds for every frame alike."""
    if annotations is None:
        return []
    out = []
    for e in annotations.region_events():
        d = e.to_json()
        if e.type == "scene_region":
            del d["frame"]
        out.append(d)
    return sorted(out, key=lambda d: json.dumps(d, sort_keys=True))


def _fill(mask: np.ndarray, e: Event, value: int) -> None:
    """Draw event ``e``'s shape into ``mask`` (uint8, full resolution) with ``value``."""
    if e.type == "person_box" or e.key.startswith("box"):
        x0, y0, x1, y1 = e.value
        mask[y0:y1, x0:x1] = value
        return
    # polygon points are pixel-edge coordinates: pixel centres are at +0.5, so
    # shift by half a pixel, with 4 bits of sub-pixel precision
    pts = np.round((np.asarray(e.value, float) - 0.5) * 16).astype(np.int32)
    cv2.fillPoly(mask, [pts.reshape(-1, 1, 2)], value, lineType=cv2.LINE_8, shift=4)


class UserRegions:
    """The pixels that may be the person, frame by frame.

    Parameters
    ----------
    annotations : Annotations
        Only its ``scene_region`` and ``person_box`` events count.
    frame_shape : (int, int)
        Height and width of the video's frames, pixels.

    Examples
    --------
    >>> a = Annotations()
    >>> _ = a.add_scene_region(0, box=(0, 0, 2, 4))
    >>> a.add_person_box(1, (1, 1, 4, 3))
    >>> r = UserRegions(a, (4, 4))
    >>> r.keep(0).astype(int).tolist()[0], r.keep(1).astype(int).tolist()[1]
    ([0, 0, 1, 1], [0, 0, 1, 1])
    """

    def __init__(self, annotations: Annotations, frame_shape):
        self.frame_shape = (int(frame_shape[0]), int(frame_shape[1]))
        events = annotations.region_events()
        self.scene = None  # uint8 (H, W): 1 where the person may be, or None
        scene = [e for e in events if e.type == "scene_region"]
        if scene:
            self.scene = np.ones(self.frame_shape, np.uint8)
            for e in scene:
                _fill(self.scene, e, 0)
        self.person_boxes = {e.frame: e.value for e in events if e.type == "person_box"}
        self._work: dict[tuple, np.ndarray] = {}  # the scene mask at work sizes

    def __bool__(self) -> bool:
        return self.scene is not None or bool(self.person_boxes)

    def keep(self, frame: int) -> np.ndarray | None:
        """(H, W) bool: where the person may be in ``frame``; None: anywhere."""
        box = self.person_boxes.get(int(frame))
        if box is None:
            return None if self.scene is None else self.scene.view(bool)
        x0, y0, x1, y1 = box
        out = np.zeros(self.frame_shape, np.uint8)
        out[y0:y1, x0:x1] = 1 if self.scene is None else self.scene[y0:y1, x0:x1]
        return out.view(bool)

    def keep_masks(self, frame: int, work_size) -> tuple[np.ndarray, np.ndarray] | None:
        """:meth:`keep` for :func:`vidcap.video.silhouette.silhouette_frame`: ``(work,
        full)``, ``work`` uint8 0/255 at ``work_size`` ((width, height), or None: the
        full size) and ``full`` (H, W) bool; None when the whole frame may be the person.

        A work pixel may be the person when any full-resolution pixel it covers may
        (a region's border does not eat into the person at half resolution).
        """
        full = self.keep(frame)
        if full is None:
            return None
        scene_only = int(frame) not in self.person_boxes
        if scene_only and work_size in self._work:
            return self._work[work_size], full
        m = full.view(np.uint8)
        if work_size is not None and tuple(work_size) != self.frame_shape[::-1]:
            # any pixel of the cell: the area average above zero
            m = cv2.resize(m * np.uint8(255), tuple(work_size), interpolation=cv2.INTER_AREA)
            m = (m > 0).view(np.uint8)
        work = m * np.uint8(255)
        if scene_only:
            self._work[work_size] = work
        return work, full


__all__ = ["UserRegions", "region_cache_part"]
