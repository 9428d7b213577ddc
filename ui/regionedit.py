"""What the annotate page redoes when the user draws a region (issue 26, build item 5).

A ``scene_region`` (pixels that are never the person, whole clip) or a ``person_box``
(the person is in this box in this frame) changes the silhouettes, so the session
asks the clip for new ones (:attr:`vidcap.ui.session.ClipData.resegment`: the pipeline's
silhouette stage with the regions, :func:`vidcap.video.pipeline.silhouettes_only`), finds
the frames that came out different (:func:`vidcap.video.refit.changed_frames`) and refits
the 2D pose around them only (:func:`vidcap.video.refit.refit_changed`); the 3D stage is
then rerun on the whole clip, as after any edit. :func:`resegment` is safe to run in a
worker thread (it touches no session); :class:`RegionEditing` gives the session its region
edits and adopts the new silhouettes under the session's lock.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from vidcap.video.annotations import Annotations


@dataclass(frozen=True)
class Resegmented:
    """New silhouettes and fit for a clip (see :func:`resegment`).

    Attributes
    ----------
    masks : vidcap.video.masks.MaskStack
    pose : dict
        :data:`vidcap.video.refit.POSE_KEYS` arrays (F, ...), the 2D fit on ``masks``.
    changed : numpy.ndarray of bool, shape (F,)
        Frames whose silhouette changed.
    seconds : float
        Wall time taken.
    """

    masks: object
    pose: dict
    changed: np.ndarray
    seconds: float


def resegment(clip, regions: Annotations, *, progress=None) -> Resegmented:
    """New silhouettes for ``clip`` with the user's ``regions``, and the 2D fit of the
    frames they change.

    Parameters
    ----------
    clip : vidcap.ui.session.ClipData
        With ``resegment`` and ``pose`` set.
    regions : Annotations
        The region events (a snapshot: the caller's set may change meanwhile).
    progress : callable, optional
        ``progress(stage, done, total)``: ``stage`` ``"silhouettes"`` then ``"fit"``.

    Returns
    -------
    Resegmented
    """
    from vidcap.video.masks import MaskStack
    from vidcap.video.refit import changed_frames, refit_changed

    t0 = time.perf_counter()
    n = clip.n_frames
    report = progress or (lambda *a: None)

    def on_masks(start, masks):
        report("silhouettes", min(n, start + len(masks)), n)

    masks = clip.resegment(regions, on_masks)
    if not isinstance(masks, MaskStack):
        masks = MaskStack.from_masks(masks)
    masks = masks[:n]
    old = clip.masks if isinstance(clip.masks, MaskStack) else MaskStack.from_masks(clip.masks)
    changed = changed_frames(old, masks)
    pose = {k: np.array(v, copy=True) for k, v in clip.pose.items()}
    if changed.any():
        pose = refit_changed(masks, pose, changed, fit_kw=clip.fit_kw,
                             progress=lambda done, total: report("fit", done, total))
    return Resegmented(masks, pose, changed, time.perf_counter() - t0)


def adopt(clip, new: Resegmented) -> None:
    """Put ``new``'s silhouettes and fit into ``clip`` (as :func:`vidcap.ui.session.load_clip`
    derives its fields from the pipeline's: frames mostly outside the picture are not
    fitted, the track follows the silhouettes' boxes)."""
    from vidcap.video.person import partly_outside, person_track

    masks, pose = new.masks, new.pose
    outside = partly_outside(masks)
    joints2d = np.array(pose["joints2d"], float)
    height = np.array(pose["model_height"], float)
    joints2d[outside] = np.nan
    height[outside] = np.nan
    boxes = masks.boxes  # y0, y1, x0, x1
    bbox = boxes[:, [2, 0, 3, 1]]
    clip.masks = masks
    clip.pose = pose
    clip.joints2d = joints2d
    clip.model_height = height
    clip.spread = np.asarray(pose["spread"], float)
    clip.fit_score = np.where(outside, 0.0, np.asarray(pose["similarity"], float))
    clip.track = person_track(bbox, masks, exclude=outside)


def region_items(annotations: Annotations) -> list[dict]:
    """The region events as the page lists them (JSON-ready): ``frame``, ``type``,
    ``key`` (for deleting), ``label`` and the shape (``box`` or ``polygon``)."""
    out = []
    for e in annotations.region_events():
        d = e.to_json()
        if "box" in d:
            x0, y0, x1, y1 = d["box"]
            shape = f"box {x0},{y0} - {x1},{y1}"
        else:
            shape = f"area of {len(d['polygon'])} points"
        what = ("not the person (whole clip)" if e.type == "scene_region"
                else f"person here (frame {e.frame})")
        out.append({**d, "key": e.key, "id": f"{e.type}|{e.frame}|{e.key}",
                    "label": f"{what}: {shape}"})
    return out


class RegionEditing:
    """The region edits of :class:`vidcap.ui.session.AnnotateSession` (a mixin: it uses the
    session's ``clip``, ``annotations``, ``_lock``, ``_check_frame``, ``save`` and the
    lift state it rebuilds after new silhouettes)."""

    def _region_edited(self, t0: float) -> float:
        with self._lock:
            self._region_version += 1
            self.regions_stale = self.clip.resegment is not None
        self.save()
        self.last_edit_ms = (time.perf_counter() - t0) * 1000.0
        return self.last_edit_ms

    def add_scene_region(self, frame: int, *, box=None, polygon=None) -> float:
        """Mark pixels that are never the person, for the whole clip (a ``box`` ``(x0,
        y0, x1, y1)`` or a ``polygon`` of ``(x, y)``, video pixels, clipped to the frame;
        ``frame``: where it was drawn). Saved at once; the silhouettes follow with
        :meth:`resegment`. Returns milliseconds taken."""
        t0 = time.perf_counter()
        w, h = self.clip.size
        if box is not None:
            box = self._clip_box(box)
        if polygon is not None:
            polygon = [(round(float(np.clip(x, 0, w)), 1), round(float(np.clip(y, 0, h)), 1))
                       for x, y in polygon]
        with self._lock:
            self.annotations.add_scene_region(self._check_frame(frame), box=box,
                                              polygon=polygon)
        return self._region_edited(t0)

    def add_person_box(self, frame: int, box) -> float:
        """In ``frame``, the person is inside ``box`` (video pixels, clipped to the frame).
        Saved at once; the silhouettes follow with :meth:`resegment`."""
        t0 = time.perf_counter()
        with self._lock:
            self.annotations.add_person_box(self._check_frame(frame), self._clip_box(box))
        return self._region_edited(t0)

    def remove_region(self, frame: int, type_: str, key: str = "") -> float:
        """Delete a region event (as :meth:`region_items` lists it)."""
        from vidcap.video.annotations import REGION_TYPES

        t0 = time.perf_counter()
        if type_ not in REGION_TYPES:
            raise ValueError(f"not a region event: {type_!r}")
        with self._lock:
            if not self.annotations.remove(int(frame), type_, key):
                raise ValueError(f"no {type_} at frame {frame}")
        return self._region_edited(t0)

    def _clip_box(self, box) -> tuple[int, int, int, int]:
        """A dragged box as integer pixel edges within the frame, corners in any order."""
        w, h = self.clip.size
        x0, y0, x1, y1 = (float(v) for v in box)
        x0, x1 = sorted((x0, x1))
        y0, y1 = sorted((y0, y1))
        out = (int(np.clip(np.floor(x0), 0, w - 1)), int(np.clip(np.floor(y0), 0, h - 1)),
               int(np.clip(np.ceil(x1), 1, w)), int(np.clip(np.ceil(y1), 1, h)))
        if out[2] - out[0] < 2 or out[3] - out[1] < 2:
            raise ValueError("the box is too small (drag a rectangle)")
        return out

    def region_items(self) -> list[dict]:
        """The region events for the page's list (:func:`vidcap.ui.regionedit.region_items`)."""
        return region_items(self.annotations)

    def regions_at(self, frame: int) -> list[dict]:
        """The regions drawn over ``frame``: every scene region, the frame's person box."""
        return [r for r in self.region_items()
                if r["type"] == "scene_region" or r["frame"] == int(frame)]

    def resegment(self, progress=None) -> dict | None:
        """Recompute the silhouettes with the current regions and refit the frames they
        change, then re-lift (safe in a worker thread; dropped, returning None, when a
        region was edited meanwhile or the clip cannot recompute).

        Returns
        -------
        dict or None
            ``changed`` (frames whose silhouette changed) and ``seconds``.
        """
        if self.clip.resegment is None:
            return None
        with self._lock:
            version = self._region_version
            snapshot = Annotations(self.annotations.region_events())
        new = resegment(self.clip, snapshot, progress=progress)
        with self._lock:
            if version != self._region_version:
                return None
            adopt(self.clip, new)
            self._prepare_clip()
            self._version += 1  # a deferred refresh running now is of the old clip
            self._recompute()
            self.regions_stale = False
        return {"changed": int(new.changed.sum()), "seconds": round(new.seconds, 2)}


__all__ = ["RegionEditing", "Resegmented", "adopt", "region_items", "resegment"]
