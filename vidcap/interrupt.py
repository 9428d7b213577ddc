"""Ctrl-C and SIGTERM: stop at once, leave nothing behind.

The CLI turns SIGTERM into the same ``KeyboardInterrupt`` as SIGINT, so one path
unwinds both: every ``finally`` on the way out runs (:func:`vidcap.fileio.atomic_path`
removes its temporary file, so no partial output is left), then :func:`stop_children`
kills whatever worker processes this one started (the 2D fit's pool, a batch's
executor) and the process exits with status 130 without waiting for them.

An exception raised from a signal handler is lost when the signal lands inside a
ctypes callback (numba's compiler calls back into Python from LLVM): Python prints it
as "Exception ignored" and carries on; inside a numba dispatcher it comes back as
another exception (``SystemError: ... returned a result with an exception set``), which
the CLI, seeing :func:`received`, reports as the interruption it is. So the signal also
arms a deadline, :data:`GRACE_S`; if the process has not left by then (or Python reports
the interrupt as lost), :func:`stop_now` removes the temporary outputs still open and
exits 130.
"""

from __future__ import annotations

import os
import signal
import sys

#: The exit status of an interrupted command (128 + SIGINT), as shells report it.
EXIT_INTERRUPTED = 130

#: Seconds the ``KeyboardInterrupt`` may take to unwind before the process is stopped
#: outright (the promise to the user is 2 s).
GRACE_S = 1.0

#: Temporary files of outputs being written (:func:`vidcap.fileio.atomic_path` adds and
#: discards them), removed by :func:`stop_now`.
temporaries: set[str] = set()


def install() -> None:
    """Make SIGTERM raise ``KeyboardInterrupt`` like SIGINT, with the deadline
    :data:`GRACE_S` behind it (main thread only)."""
    signal.signal(signal.SIGTERM, _on_signal)
    signal.signal(signal.SIGINT, _on_signal)
    signal.signal(signal.SIGALRM, stop_now)
    sys.unraisablehook = _unraisable


_received = False


def received() -> bool:
    """Whether SIGINT or SIGTERM reached this process (since :func:`install`)."""
    return _received


def _on_signal(signum, frame) -> None:
    global _received
    _received = True
    if signal.getitimer(signal.ITIMER_REAL)[0] == 0.0:  # the first signal sets the deadline
        signal.setitimer(signal.ITIMER_REAL, GRACE_S)
    raise KeyboardInterrupt


def _unraisable(info) -> None:
    """Python could not raise the interrupt where the signal landed: stop in moments
    instead (and do not print its traceback); anything else is reported as usual."""
    if info.exc_type is not None and issubclass(info.exc_type, KeyboardInterrupt):
        signal.setitimer(signal.ITIMER_REAL, 0.01)
        return
    sys.__unraisablehook__(info)


def stop_now(signum=None, frame=None) -> None:
    """Remove the open temporary outputs, say "interrupted", stop the children and leave
    with :data:`EXIT_INTERRUPTED` (after the unwinding, or when it did not come in time)."""
    signal.setitimer(signal.ITIMER_REAL, 0.0)  # said once
    for path in list(temporaries):
        try:
            os.unlink(path)
        except OSError:
            pass
    try:
        print("vidcap: interrupted", file=sys.stderr)
    except (OSError, ValueError):
        pass
    exit_interrupted()


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
