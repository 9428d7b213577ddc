"""Numba's on-disk kernel cache, dropped when a module the kernels compile in changes.

Numba keys a ``cache=True`` kernel's cached machine code on its own source file only
(the file's modification time and size). A kernel that inlines a function of another
module, or reads another module's constants (compiled in as literals), keeps its cached
code when only that other module changes: after a ``git pull`` that touched
``fit/_kernels.py`` but not ``fit/_cue_kernels.py``, the cue kernel would go on running
the old ``arm_pair_terms``, silently (numba's documentation lists this among the cache's
limitations). :func:`refresh_when_changed` closes the gap: a kernel module names the
files its kernels compile in, and their contents' hash is kept beside numba's cache;
when it differs, that module's cached kernels are flushed and compile afresh once.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Mapping
from pathlib import Path

__all__ = ["refresh_when_changed"]


def _digest(files: Iterable[Path]) -> str:
    """SHA-256 of the files' names and bytes, in the order given."""
    h = hashlib.sha256()
    for f in files:
        h.update(f.name.encode())
        h.update(Path(f).read_bytes())
    return h.hexdigest()


def refresh_when_changed(namespace: Mapping[str, object], depends_on: Iterable[Path]) -> bool:
    """Flush the cached code of every numba kernel in ``namespace`` when the files it
    depends on have changed since the cache was last checked.

    Parameters
    ----------
    namespace : mapping
        The kernel module's ``globals()``, called after its kernels are defined (numba
        reads the cache lazily, at a kernel's first call, so flushing here is in time).
    depends_on : iterable of Path
        The other source files whose functions or constants the kernels compile in.

    Returns
    -------
    bool
        True when the caches were flushed (the files changed, or no stamp existed).

    Notes
    -----
    The stamp is ``<module>.deps`` in numba's cache folder for the module. Where that
    folder cannot be written, or numba's cache object is not where this numba keeps it,
    nothing is done: the kernels then behave as numba alone makes them.
    """
    module = namespace.get("__name__")
    own = [v for v in namespace.values()  # not the kernels it imports: theirs is theirs
           if getattr(getattr(v, "py_func", None), "__module__", None) == module]
    caches = [c for c in (getattr(v, "_cache", None) for v in own)
              if getattr(c, "cache_path", None) is not None and hasattr(c, "flush")]
    if not caches:
        return False
    stem = Path(str(namespace.get("__file__", "kernels"))).stem
    stamp = Path(caches[0].cache_path) / f"{stem}.deps"
    try:
        digest = _digest(Path(p) for p in depends_on)
        if stamp.is_file() and stamp.read_text() == digest:
            return False
        for cache in caches:
            cache.flush()
        stamp.parent.mkdir(parents=True, exist_ok=True)
        tmp = stamp.with_name(f"{stamp.name}.{os.getpid()}.tmp")
        tmp.write_text(digest)
        os.replace(tmp, stamp)  # whole or not at all, should two processes race
    except OSError:  # a read-only install: numba falls back on its own, so do we
        return False
    return True
