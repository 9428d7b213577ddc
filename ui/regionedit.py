"""What the annotate page redoes when the user draws a region (issue 26, build item 5).

A ``scene_region`` (pixels that are never the person, whole clip) or a ``person_box``
(the person is in this box in this frame) changes the silhouettes, so the session
asks the clip for new ones (:attr:`vidcap.ui.session.ClipData.resegment`: the pipeline's
silhouette stage with the regions, :func:`vidcap.video.pipeline.silhouettes_only`), finds
the frames that came out different (:func:`vidcap.video.refit.changed_frames`) and refits
the 2D pose around them only (:func:`vidcap.video.refit.refit_changed`); the 3D stage is
then rerun on the whole clip, as after any edit. All of it is safe to run in a worker
thread: nothing here touches the session.
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
        pose = refit_changed(masks, pose, changed,
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


__all__ = ["Resegmented", "adopt", "region_items", "resegment"]
