"""The stage cache: ``.npz`` results of the expensive stages in a folder, keyed by
what they depend on.

A key is a short hash of its parts (:func:`stage_key`): the video's identity
(:func:`video_identity`: absolute path, size, modification time), the stage's
parameters and the key of the stage before it, so changing an option or the video
redoes exactly the stages that depend on it.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from vidcap.fileio import savez_atomic


def video_identity(video: str | os.PathLike) -> dict:
    """What identifies a video file for the cache: absolute path, size in bytes and
    modification time in nanoseconds (a JSON-ready dict)."""
    video = Path(video)
    st = video.stat()
    return {"path": str(video.resolve()), "size": st.st_size, "mtime_ns": st.st_mtime_ns}


def stage_key(*parts) -> str:
    """A 16-hex-digit key for ``parts`` (anything :func:`json.dumps` can write, other
    values by ``str``; dict order does not matter)."""
    text = json.dumps(parts, sort_keys=True, default=str)
    return hashlib.sha1(text.encode()).hexdigest()[:16]


class StageCache:
    """``.npz`` stage results in a folder, keyed by parameters (or disabled: ``None``)."""

    def __init__(self, folder: str | os.PathLike | None):
        self.folder = None if folder is None else Path(folder)

    def path(self, stage: str, key: str) -> Path | None:
        """The entry's file, or None when caching is disabled."""
        return None if self.folder is None else self.folder / f"{stage}-{key}.npz"

    def load(self, stage: str, key: str, *, required: tuple[str, ...] = ()) -> dict | None:
        """The stored arrays by name, or None: no entry, a damaged one, or one written
        by an older version that lacks one of the ``required`` arrays (all redone)."""
        p = self.path(stage, key)
        if p is None or not p.exists():
            return None
        try:
            with np.load(p, allow_pickle=False) as z:
                hit = {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError):  # a damaged cache entry is just redone
            return None
        return hit if all(k in hit for k in required) else None

    def save(self, stage: str, key: str, **arrays) -> None:
        """Store ``arrays`` under (stage, key) atomically; nothing when disabled."""
        p = self.path(stage, key)
        if p is not None:
            savez_atomic(p, **arrays)


__all__ = ["StageCache", "stage_key", "video_identity"]
