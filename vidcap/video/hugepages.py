"""NumPy's transparent huge pages off while vidcap works through a video.

NumPy asks Linux for transparent huge pages (``madvise(MADV_HUGEPAGE)``) on every array
of 4 MB or more. Where the kernel defragments on such a fault (``defrag`` ``madvise``,
the common default), each fresh 2 MB page of a large temporary may first wait for
memory to be compacted: the video stages make many such temporaries (a plate's 24
samples at 1000x1000 are 72 MB, their float residuals 72 MB more) and free them soon
after. On the 2-CPU benchmark machine the plate of a 1000x1000 clip took 0.6-0.7 s
of system CPU without them against 1.4-3.0 s with them (three runs each, alternating;
user CPU the same), and the whole ``vidcap convert`` 1.3 against 2.1-2.4 s. The
values computed are the same: only how the memory is mapped changes.

:func:`small_pages` switches it off for a block and restores NumPy's setting after it;
a user who set ``NUMPY_MADVISE_HUGEPAGE`` keeps their choice.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["small_pages"]


def _switch():
    """NumPy's ``_set_madvise_hugepage`` (it returns the setting it replaces), or None
    where this NumPy has none."""
    try:
        from numpy._core.multiarray import _set_madvise_hugepage
    except ImportError:  # pragma: no cover - NumPy < 2
        try:
            from numpy.core.multiarray import _set_madvise_hugepage
        except ImportError:
            return None
    return _set_madvise_hugepage


@contextmanager
def small_pages() -> Iterator[None]:
    """Within the block, NumPy's new arrays do not ask for transparent huge pages
    (unless ``NUMPY_MADVISE_HUGEPAGE`` is set: then as it says).

    Examples
    --------
    >>> import numpy as np
    >>> with small_pages():
    ...     x = np.zeros((2000, 2000))
    >>> float(x.sum())
    0.0
    """
    switch = None if "NUMPY_MADVISE_HUGEPAGE" in os.environ else _switch()
    if switch is None:
        yield
        return
    before = switch(False)
    try:
        yield
    finally:
        switch(before)
