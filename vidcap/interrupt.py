"""Ctrl-C and SIGTERM: stop at once, leave nothing behind.

The CLI turns SIGTERM into the same ``KeyboardInterrupt`` as SIGINT, so one path
unwinds both: every ``finally`` on the way out runs (:func:`vidcap.fileio.atomic_path`
removes its temporary file, so no partial output is left), then :func:`stop_children`
kills whatever worker processes this one started (the 2D fit's pool, a batch's
executor) and the process exits with status 130 without waiting for them.
"""

from __future__ import annotations

import os
import signal
import sys

#: The exit status of an interrupted command (128 + SIGINT), as shells report it.
EXIT_INTERRUPTED = 130


def install() -> None:
    """Make SIGTERM raise ``KeyboardInterrupt`` like SIGINT (main thread only)."""
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    signal.signal(signal.SIGINT, signal.default_int_handler)


def _children_of(pid: int) -> list[int]:
    """Processes whose parent is ``pid``, forked by any of its threads (Linux ``/proc``;
    elsewhere [])."""
    kids: list[int] = []
    try:
        tasks = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return kids
    for tid in tasks:
        try:
            with open(f"/proc/{pid}/task/{tid}/children") as fh:
                kids.extend(int(p) for p in fh.read().split())
        except OSError:
            pass
    return kids


def descendants(pid: int | None = None) -> list[int]:
    """Every process below ``pid`` (default: this one), parents before children."""
    out, todo = [], [os.getpid() if pid is None else pid]
    while todo:
        kids = _children_of(todo.pop())
        out.extend(kids)
        todo.extend(kids)
    return out


def stop_children() -> None:
    """SIGKILL every process below this one (workers are stateless: their results are
    lost with the run anyway), children first so none is re-parented and missed."""
    procs = descendants()
    for pid in procs:
        try:
            os.kill(pid, signal.SIGSTOP)  # freeze the tree first: no new forks
        except OSError:
            pass
    for pid in reversed(procs):
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
    for pid in procs:
        try:
            os.waitpid(pid, os.WNOHANG)  # reap our direct children
        except OSError:
            pass


def exit_interrupted() -> None:
    """Stop the children, flush, and leave now with :data:`EXIT_INTERRUPTED` (no atexit
    handler may wait on a worker)."""
    stop_children()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(EXIT_INTERRUPTED)
