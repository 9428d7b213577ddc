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


#: Name of the member holding the entry's checksum.
CHECKSUM = "__sha256__"


def _frames(value):
    """The C-order byte blocks of one stored value (a MaskStack frame by frame)."""
    if hasattr(value, "frame_shape"):
        return (np.ascontiguousarray(value[k], dtype=bool) for k in range(len(value)))
    return (np.ascontiguousarray(np.asanyarray(value)),)


def checksum(arrays: dict) -> str:
    """SHA-256 over each array's name, dtype, shape and bytes (sorted by name).

    A :class:`vidcap.video.masks.MaskStack` hashes as the (F, H, W) bool array it is stored
    as, one frame at a time.
    """
    h = hashlib.sha256()
    for name in sorted(arrays):
        value = arrays[name]
        dtype = np.dtype(bool) if hasattr(value, "frame_shape") else np.asanyarray(value).dtype
        h.update(f"{name}|{dtype.str}|{tuple(np.shape(value))}|".encode())
        for block in _frames(value):
            h.update(memoryview(block).cast("B"))
    return h.hexdigest()


class StageCache:
    """``.npz`` stage results in a folder, keyed by parameters (or disabled: ``None``).

    Entries are written atomically (a temporary file renamed into place) and carry a
    SHA-256 of their arrays; an entry that cannot be read, or whose arrays do not match
    their checksum (a disk filled up, a killed run, a flipped bit), is reported with a
    one-line notice through ``log`` and recomputed.
    """

    def __init__(self, folder: str | os.PathLike | None, *, log=None):
        self.folder = None if folder is None else Path(folder)
        self.log = log or (lambda msg: None)

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
            stored = str(hit.pop(CHECKSUM))
            ok = stored == checksum(hit)
            why = "its checksum does not match its contents"
        except Exception as exc:  # noqa: BLE001 - any damage (zip, zlib, npy, a missing
            # checksum) means the same thing: recompute the entry
            ok, why = False, f"{type(exc).__name__}: {' '.join(str(exc).split())[:80]}"
        if not ok:
            self.log(f"notice: cache entry {p} is unreadable ({why}): recomputing it")
            return None
        return hit if all(k in hit for k in required) else None

    def save(self, stage: str, key: str, **arrays) -> None:
        """Store ``arrays`` under (stage, key) atomically, with their checksum; nothing
        when disabled."""
        p = self.path(stage, key)
        if p is not None:
            savez_atomic(p, **arrays, **{CHECKSUM: np.array(checksum(arrays))})


__all__ = ["StageCache", "stage_key", "video_identity"]
