"""The plate from frames the user names as the empty scene (``--background START:END``).

Why: a clip often shows the empty scene for a while (before the person walks in, after
they leave) and its user knows where. The plate estimated from the clip finds such
stretches itself (:mod:`vidcap.video.emptyscene`), but by a test on the ghost's outline
that can miss (cdnet_office_enter shrunk to 144 rows: median IoU 0.376 against 0.911 at
full size, benchmarks/RESULTS.md). Saying which frames are empty settles it without a
photo of the scene taken apart from the video: the plate is each pixel's median over up
to :data:`N_SAMPLES` frames spread evenly over ``START:END``, used as a given plate is
(``--background plate.png``: no never-seen area, the noise measured on the video by the
silhouette stage).
"""

from __future__ import annotations

import os
import re

import numpy as np

__all__ = ["MAX_BYTES", "N_SAMPLES", "empty_plate", "frame_range", "given_plate_identity"]

#: Frames (at most) the median is taken over.
N_SAMPLES = 25
#: ... and at most this many bytes of them (a 4K clip's 25 frames would be 0.6 GB, and
#: the median sorts a copy): fewer frames for large ones, at least :data:`MIN_SAMPLES`.
MAX_BYTES = 200_000_000
MIN_SAMPLES = 5

_RANGE = re.compile(r"^\s*(\d*)\s*:\s*(\d*)\s*$")


def frame_range(text) -> tuple[int, int | None] | None:
    """``'START:END'`` (either may be left out: ``':80'``, ``'400:'``) as ``(start, end)``
    (``end`` None: to the clip's end, exclusive as in Python), or None when ``text`` is
    no such range (a path to an image), or names an existing file.
    """
    if not isinstance(text, (str, os.PathLike)) or os.path.isfile(text):
        return None
    m = _RANGE.match(os.fspath(text))
    if m is None:
        return None
    return int(m.group(1) or 0), (int(m.group(2)) if m.group(2) else None)


def empty_plate(video, start: int, end: int | None, *, n_samples: int = N_SAMPLES) -> np.ndarray:
    """The plate of the frames ``[start, end)`` of ``video``: each pixel's median.

    Parameters
    ----------
    video : str or path-like
    start, end : int
        Frame indices, 0-based, ``end`` exclusive (None: to the clip's end).
    n_samples : int
        Frames the per-pixel median is taken over (evenly spread; all when fewer; fewer
        for large frames, :data:`MAX_BYTES`).

    Returns
    -------
    numpy.ndarray, shape (H, W, 3), uint8
        BGR; :func:`vidcap.video.background.load_plate` wraps it as a given plate
        (nothing never seen, the noise left to the video).

    Raises
    ------
    InputFileError
        The range holds no frame of the video (one line naming the video, the range
        and its frame count), or is empty, or spans a change of the frame size.
    """
    from vidcap.errors import InputFileError, VideoError
    from vidcap.io.video import NO_FRAMES, iter_frames, probe

    got = f"{start}:{'' if end is None else end}"  # as the user wrote it
    if end is not None and end <= start:
        raise InputFileError(f"--background {got} names no frame: END must be after START "
                             "(frames count from 0, the end is excluded)", video)
    info = probe(video)
    n_frames = info.n_frames  # (the container's count: decoding says the rest)
    n_samples = min(n_samples, max(MIN_SAMPLES, MAX_BYTES // (3 * info.width * info.height)))
    stop = n_frames if end is None else min(int(end), n_frames)
    take = (np.unique(np.linspace(start, stop - 1, min(n_samples, stop - start)).round())
            if 0 <= start < stop else np.zeros(0))
    try:
        frames = [] if not take.size else list(iter_frames(
            video, start=start, stop=stop, only=set(take.astype(int).tolist())))
    except VideoError as exc:
        if exc.problem != NO_FRAMES:
            raise
        frames = []  # none decoded from there on: the container over-counted
    if not frames:
        raise InputFileError(f"--background {got} holds no frame of the video, which has "
                             f"{n_frames} (frames count from 0, the end is excluded)", video)
    if any(f.shape != frames[0].shape for f in frames):
        raise InputFileError(f"the frame size changes within --background {got}; re-encode "
                             "the video at one size", video)
    return np.median(np.stack(frames), axis=0).round().astype(np.uint8)


def given_plate_identity(background, video_id: dict) -> tuple:
    """What identifies a given plate for the stage cache: the image file's identity
    (:func:`vidcap.video.stagecache.video_identity`), or the frame range with the
    video's ``video_id``."""
    from vidcap.video.stagecache import video_identity

    frames = frame_range(background)
    if frames is None:
        return (video_identity(background),)
    return ("frames", list(frames), video_id)
