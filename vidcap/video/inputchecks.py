"""Inputs the silhouette stage cannot work on, each told in one line (issue 26).

Checked on the frames sampled for the background plate, before any work: too few
frames, every frame black or white, a camera that moves. (Nobody in view and a
person who never moves are told by :func:`vidcap.video.background.estimate_background`
itself: nothing differs between the samples; a frame size that changes mid-stream by
:func:`vidcap.video.background.sample_frames` and :func:`vidcap.video.silhouette.iter_silhouettes`.)
"""

from __future__ import annotations

import cv2
import numpy as np

from vidcap.errors import BackgroundError

__all__ = ["camera_shift", "check_samples", "plate_notice"]

#: Fewest frames a plate is estimated from (fewer: give --background).
MIN_FRAMES = 4
#: Median shift between consecutive samples, per cent of the frame's long side,
#: above which the camera is taken to move (a pan, a hand-held phone) ...
MAX_SHIFT = 1.0
#: ... when it also changes at least this share of the frame (a person moving over a
#: plain wall shifts the correlation peak too, but changes little of the frame).
MIN_CHANGED = 0.25


def check_samples(frames: np.ndarray, name=None) -> None:
    """Raise :class:`vidcap.errors.BackgroundError` for frames no plate can come from.

    Parameters
    ----------
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The sampled frames (all of them for a short video).
    name : str or path-like, optional
        The video, for the message.
    """
    k = len(frames)
    if k < 2:
        raise BackgroundError(
            "only one frame: a background cannot be estimated from a single frame; "
            "give a photo of the empty scene (--background plate.png)", name)
    if k < MIN_FRAMES:
        raise BackgroundError(
            f"only {k} frames: too few to tell the person from the background; give a "
            "photo of the empty scene (--background plate.png)", name)
    sub = frames[:, ::4, ::4]
    if np.percentile(sub, 99.5) <= 12:
        raise BackgroundError("every frame is black: nothing to see (lens cap, no signal?)",
                              name)
    if np.percentile(sub, 0.5) >= 243:
        raise BackgroundError("every frame is white: nothing to see (overexposed?)", name)
    shift, changed = camera_shift(frames)
    if shift > MAX_SHIFT and changed > MIN_CHANGED:
        raise BackgroundError(
            f"the camera moves (the whole scene shifts by about {shift:.1f}% of the frame "
            "between sampled frames): vidcap needs a fixed camera (a tripod)", name)


def camera_shift(frames: np.ndarray) -> tuple[float, float]:
    """Median global shift between consecutive frames, and the share that changes.

    Phase correlation of the grey frames at a 160-pixel long side: the scene behind
    a moving person does not shift, so the peak stays at zero for a fixed camera.

    Parameters
    ----------
    frames : numpy.ndarray, shape (K, H, W, 3), uint8

    Returns
    -------
    shift : float
        Per cent of the frame's long side (about 0 for a fixed camera).
    changed : float
        Median share of pixels whose grey level changes by more than 8 between
        consecutive frames.
    """
    k, hh, ww = frames.shape[:3]
    s = min(1.0, 160 / max(hh, ww))
    size = (max(8, round(ww * s)), max(8, round(hh * s)))
    grey = [cv2.resize(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), size,
                       interpolation=cv2.INTER_AREA).astype(np.float32) for f in frames]
    win = cv2.createHanningWindow(size, cv2.CV_32F)
    pairs = list(zip(grey[:-1], grey[1:], strict=True))
    if not pairs:
        return 0.0, 0.0
    shifts = [np.hypot(*cv2.phaseCorrelate(a, b, win)[0]) for a, b in pairs]
    changed = [float((np.abs(a - b) > 8).mean()) for a, b in pairs]
    return float(100.0 * np.median(shifts) / max(size)), float(np.median(changed))


#: Share of the frame never seen uncovered above which the plate is called uncertain.
UNCERTAIN_SHARE = 0.01


def plate_notice(model) -> str | None:
    """A one-line notice when the plate is a guess over a noticeable area, else None.

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
    """
    share = float(model.never_seen_fraction)
    if share <= UNCERTAIN_SHARE:
        return None
    return (f"notice: the background behind {100 * share:.1f}% of the frame was never seen "
            "uncovered (someone stays there throughout), so the silhouettes there are a "
            "guess; a photo of the empty scene (--background plate.png), or the frames "
            "that show it empty (--background START:END), settles it")
