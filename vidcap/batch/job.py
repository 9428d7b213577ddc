"""The work for one clip of a batch: convert it, never raise, return its summary row."""

from __future__ import annotations

import time
from dataclasses import dataclass, field


@dataclass(frozen=True)
class ClipTask:
    """One clip of a batch.

    Parameters
    ----------
    video : str
        The input video.
    output : str
        The output file; whatever :func:`vidcap.video.pipeline.convert` writes for it.
    options : dict
        Keyword options of :func:`vidcap.video.pipeline.convert` (``height``, ``view``,
        ``jobs``...), the same for every clip of the batch.
    """

    video: str
    output: str
    options: dict = field(default_factory=dict)


def failed_row(task: ClipTask, message: str, seconds: float = 0.0) -> dict:
    """The summary row of a clip that could not be converted."""
    return {"file": task.video, "output": task.output, "frames": 0,
            "seconds": round(seconds, 3), "fps": 0.0, "status": "failed",
            "message": " ".join(message.split())}


def convert_clip(task: ClipTask) -> dict:
    """Convert one clip; never raises, so a bad file never stops the others.

    Parameters
    ----------
    task : ClipTask

    Returns
    -------
    dict
        The clip's summary row: ``file``, ``output``, ``frames``, ``seconds`` (wall
        time), ``fps``, ``status`` (``ok`` or ``failed``) and ``message`` (the
        conversion's notices, or the error).
    """
    from vidcap.video.pipeline import convert

    t0 = time.perf_counter()
    try:
        res = convert(task.video, task.output, progress=False, **task.options)
    except Exception as exc:  # noqa: BLE001 - a bad file must never stop the others
        return failed_row(task, str(exc) or type(exc).__name__, time.perf_counter() - t0)
    seconds = round(time.perf_counter() - t0, 3)
    return {"file": task.video, "output": task.output, "frames": res.n_frames,
            "seconds": seconds, "fps": round(res.n_frames / seconds, 2) if seconds > 0 else 0.0,
            "status": "ok", "message": " ".join("; ".join(res.notices()).split())}
