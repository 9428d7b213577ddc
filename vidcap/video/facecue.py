"""Front or back from the face: a frontal face where the fit put the head.

An orthographic view of joints cannot tell a body facing the camera from its mirror
image turned away (:mod:`vidcap.video.frontback`). A face can: a body facing the
camera shows one, a body turned away shows the back of its head. This module looks for
a frontal face, with the Haar cascade OpenCV ships
(``cv2.data.haarcascades``: no model file to fetch), in a box round the fitted head of
a sparse set of frames (the detector is the cost; the body turns slowly), and reports
per frame whether it found one.

Only a face found is evidence: a face too small, blurred, lit from behind or turned a
little away is missed as easily as a back of the head, so no face says nothing
(:func:`vidcap.video.proposals.propose_front` reads it that way). Renders of the
cylinder model (``vidcap synth``) have no faces: the cascade finds none there, and the
arm cue decides as without this one.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np

from vidcap.body import JOINT_INDEX

#: Seconds between the frames searched: the body turns slowly (a half turn takes a
#: second or more), and a detection costs 0.5-2 ms.
FACE_STEP_S = 0.25
#: The box searched, centred on the fitted head's middle, as a multiple of the head's
#: image length (neck to crown): the fit's head is a few percent of the height off.
BOX_HEADS = 1.6
#: The head's length (px) in the box as searched: the face is 0.35-0.5 of the fitted
#: head's length (the model's neck sits between the shoulders), so about 22-32 px,
#: at the cascade's 24 px window, and the crop stays small (102 px) whatever the
#: frame's size.
HEAD_PX = 64.0
#: A face's size bounds, in head lengths: smaller or larger ones are not this head's.
FACE_MIN, FACE_MAX = 0.3, 1.0
#: Detections of the cascade that must overlap (its ``minNeighbors``): 5 finds no face on
#: cylinder renders and few in clothing or background.
NEIGHBOURS = 5
#: Heads smaller than this (px, neck to crown) are not searched: their faces are a few
#: pixels wide and the cascade's window, upscaled, sees blur.
MIN_HEAD_PX = 12.0

@functools.cache
def _cascade():
    """The frontal-face cascade, loaded once per process (read only)."""
    return cv2.CascadeClassifier(cv2.data.haarcascades + "haarcascade_frontalface_default.xml")


def head_boxes(joints2d, *, box_heads: float = BOX_HEADS) -> np.ndarray:
    """The square searched round each frame's fitted head, (F, 3) ``x_c, y_c, half``
    px (NaN where the head's joints are missing).

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Fitted 2D joints, pixels.
    box_heads : float
        The box's side in head lengths.
    """
    j2 = np.asarray(joints2d, dtype=float)
    neck, top = j2[:, JOINT_INDEX["neck"]], j2[:, JOINT_INDEX["head_top"]]
    centre = 0.5 * (neck + top)
    half = 0.5 * box_heads * np.linalg.norm(top - neck, axis=-1)
    return np.column_stack([centre, half])


def read_bounds(joints2d, shape, *, fps: float, step_s: float = FACE_STEP_S) -> np.ndarray:
    """The box of the pixels :func:`face_seen` reads in each frame of ``shape`` (H, W),
    (F, 4) ``x_min, x_max, y_min, y_max`` px (inclusive; ``inf, -inf`` where none)."""
    from vidcap.video.frontback import pixel_bounds

    box = head_boxes(joints2d)
    F = len(box)
    searched = search_frames(F, fps, step_s) & _searchable(box)
    x = np.stack([box[:, 0] - box[:, 2], box[:, 0] + box[:, 2]], -1)
    y = np.stack([box[:, 1] - box[:, 2], box[:, 1] + box[:, 2]], -1)
    H, W = shape[:2]
    x = np.where(searched[:, None], np.clip(np.floor(x), 0, W - 1), -1)
    y = np.where(searched[:, None], np.clip(np.floor(y), 0, H - 1), -1)
    return pixel_bounds(x, y, shape)


def search_frames(n_frames: int, fps: float, step_s: float = FACE_STEP_S) -> np.ndarray:
    """Which of ``n_frames`` frames are searched, (F,) bool: one every ``step_s``."""
    step = max(1, int(round(step_s * fps)))
    out = np.zeros(n_frames, bool)
    out[::step] = True
    return out


def _searchable(box) -> np.ndarray:
    return np.isfinite(box).all(-1) & (box[:, 2] * 2.0 / BOX_HEADS >= MIN_HEAD_PX)


def _crop(frame: np.ndarray, box) -> np.ndarray | None:
    """The grey box ``x_c, y_c, half`` of ``frame`` (H, W, 3) resized so a head is
    :data:`HEAD_PX` long (edge pixels repeated where the box leaves the frame), or None
    where it lies wholly outside."""
    H, W = frame.shape[:2]
    xc, yc, half = box
    x0, x1 = int(np.floor(xc - half)), int(np.ceil(xc + half))
    y0, y1 = int(np.floor(yc - half)), int(np.ceil(yc + half))
    if x1 <= 0 or y1 <= 0 or x0 >= W or y0 >= H:
        return None
    sub = frame[max(y0, 0):min(y1, H), max(x0, 0):min(x1, W)]
    sub = cv2.copyMakeBorder(sub, max(-y0, 0), max(y1 - H, 0), max(-x0, 0), max(x1 - W, 0),
                             cv2.BORDER_REPLICATE)
    side = int(round(HEAD_PX * BOX_HEADS))
    grey = cv2.cvtColor(sub, cv2.COLOR_BGR2GRAY)
    grey = cv2.resize(grey, (side, side), interpolation=cv2.INTER_AREA
                      if grey.shape[0] > side else cv2.INTER_LINEAR)
    return cv2.equalizeHist(grey)


def detect_face(grey: np.ndarray) -> bool:
    """Whether the cascade finds a frontal face of a head's size in ``grey`` (a
    :func:`_crop` box, ``HEAD_PX * BOX_HEADS`` square)."""
    lo, hi = int(FACE_MIN * HEAD_PX), int(FACE_MAX * HEAD_PX)
    found = _cascade().detectMultiScale(grey, scaleFactor=1.1, minNeighbors=NEIGHBOURS,
                                        minSize=(lo, lo), maxSize=(hi, hi))
    return len(found) > 0


def tap_faces(frames, joints2d, out, *, fps: float, step_s: float = FACE_STEP_S):
    """Yield ``frames`` on unchanged while looking for a face in the searched ones (so
    another cue can read the same pass over a video), writing :func:`face_seen`'s
    answer into ``out`` (F,) float, NaN-filled by the caller."""
    box = head_boxes(joints2d)
    todo = search_frames(len(box), fps, step_s) & _searchable(box)
    for k, frame in enumerate(frames):
        if k < len(todo) and todo[k] and frame is not None:
            grey = _crop(np.asarray(frame), box[k])
            if grey is not None:
                out[k] = float(detect_face(grey))
        yield frame


def face_seen(frames, joints2d, *, fps: float, step_s: float = FACE_STEP_S) -> np.ndarray:
    """Whether a frontal face is found in the fitted head's box, per frame.

    Parameters
    ----------
    frames : iterable of numpy.ndarray, shape (H, W, 3) uint8
        The clip's colour frames (BGR), in order, one per row of ``joints2d``; ``None``
        for a frame not available. Consumed to its end.
    joints2d : array_like, shape (F, 15, 2)
        Fitted 2D joints, pixels; NaN where none.
    fps : float
        Frames per second (one frame searched every ``step_s``).
    step_s : float
        Seconds between the frames searched.

    Returns
    -------
    numpy.ndarray, shape (F,)
        1.0 where a face was found, 0.0 where one was looked for and none found, NaN
        where none was looked for (frames between the searched ones, heads smaller
        than :data:`MIN_HEAD_PX`, frames not available).

    Examples
    --------
    A grey clip has no face in it:

    >>> import numpy as np
    >>> from vidcap.body import BodyModel
    >>> rest = BodyModel().rest_positions()
    >>> j2 = np.repeat(np.c_[160 + 150 * rest[:, 0], 300 - 150 * rest[:, 1]][None], 8, 0)
    >>> seen = face_seen([np.full((320, 320, 3), 128, np.uint8)] * 8, j2, fps=8.0)
    >>> seen[:4]
    array([ 0., nan,  0., nan])
    """
    out = np.full(len(np.asarray(joints2d)), np.nan)
    for _ in tap_faces(frames, joints2d, out, fps=fps, step_s=step_s):
        pass
    return out
