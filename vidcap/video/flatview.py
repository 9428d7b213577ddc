"""What the 3D stage reads of a clip fitted through a camera's perspective.

With ``--camera`` the 2D fit draws the body as a high (or low) camera images it, head
larger than feet (:mod:`vidcap.video.fit.perspective`); the 3D stage's scaled orthography
expects a body whose heights are shrunk alike, so it reads the fitted joints un-warped.
A joint the user placed by hand (an annotation ``joint`` event, pixels on the frame) is
on the same image and is un-warped alike, by its frame's fitted head top and height:
``vidcap convert`` and the annotate page both lift through :func:`flat_view`, so the
page shows what the motion file will get.
"""

from __future__ import annotations

import numpy as np

from vidcap.video.annotations import Annotations, Event
from vidcap.video.fit.perspective import unwarp_joints, unwarp_points

__all__ = ["NO_PERSPECTIVE", "flat_points", "flat_view", "unwarped_joint_events"]

#: ``(k, above_feet)`` of a level camera: nothing is moved.
NO_PERSPECTIVE = (0.0, 1.0)


def flat_view(joints2d, model_height, annotations: Annotations,
              perspective: tuple[float, float] = NO_PERSPECTIVE):
    """The fitted joints, their model heights and the user's joint events un-warped.

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, 2)
        The fitted image joints, pixels (NaN in frames not fitted).
    model_height : numpy.ndarray, shape (F,), or None
        The fitted body's image height per frame, pixels (None: unknown; nothing is
        moved then).
    annotations : Annotations
        The user's events; only ``joint`` events are moved.
    perspective : (float, float)
        The camera's k and the body's ankle share (``above_feet``).

    Returns
    -------
    joints2d : numpy.ndarray, shape (F, 15, 2)
    model_height : numpy.ndarray, shape (F,), or None
    annotations : Annotations
        ``annotations`` itself when nothing moves.
    """
    k, above_feet = perspective
    if k == 0 or model_height is None:
        return joints2d, model_height, annotations
    flat2d, flat_height = unwarp_joints(joints2d, model_height, k, above_feet)
    events = unwarped_joint_events(annotations, joints2d, model_height, perspective)
    return flat2d, flat_height, events


def flat_points(points, joints2d, model_height,
                perspective: tuple[float, float] = NO_PERSPECTIVE) -> np.ndarray:
    """Points on the frame (F, N, 2), the user's placed joints say, as the 3D stage reads
    them: un-warped as each frame's fitted ``joints2d`` are
    (:func:`vidcap.video.fit.perspective.unwarp_points`); as they are for a level camera
    or without the fitted heights (``model_height`` None)."""
    if perspective[0] == 0 or model_height is None:
        return points
    return unwarp_points(points, joints2d, model_height, *perspective)


def unwarped_joint_events(annotations: Annotations, joints2d, model_height,
                          perspective: tuple[float, float]) -> Annotations:
    """``annotations`` with each ``joint`` event's pixel moved as its frame's fitted joints
    are moved (:func:`vidcap.video.fit.perspective.unwarp_points`); an event in a frame
    without a fit (or beyond the clip) is kept as placed."""
    events = annotations.events
    placed = [i for i, e in enumerate(events) if e.type == "joint"]
    if not placed or perspective[0] == 0:
        return annotations
    joints2d = np.asarray(joints2d, float)
    height = np.asarray(model_height, float)
    frames = np.array([events[i].frame for i in placed])
    inside = frames < len(joints2d)
    at = np.minimum(frames, len(joints2d) - 1)
    points = np.array([events[i].value for i in placed], float)[:, None, :]
    moved = flat_points(points, joints2d[at], height[at], perspective)[:, 0]
    moved[~inside] = points[~inside, 0]
    out = list(events)
    for i, uv in zip(placed, moved, strict=True):
        e = events[i]
        out[i] = Event(e.frame, e.type, e.key, (float(uv[0]), float(uv[1])))
    return Annotations(out)
