"""The clip solve on two processes: two overlapping halves, joined at the middle.

The solve is one process's work (its 48 x 48 blocks run slower on more BLAS threads)
and on 300 frames a third of ``vidcap convert``'s time, while the second core waits.
Both halves of the clip, each :data:`OVERLAP` frames past the middle, are solved as a
whole clip would be (:func:`vidcap.video.solve.clip.solve_problem`: LM, robust
weights, sign sweeps, repair), the first in a forked child, the second here. The
poses are joined at the middle frame, and the :data:`SEAM` frames either side of the
join are solved again with the frames just beyond them held (as an annotate edit's
window, :mod:`vidcap.video.solve.local`), so the motion stays continuous across it.

Each half sees the clip's second differences, contacts and sign runs up to its own
end; the overlap keeps those ends away from the frames it keeps. Where ``os.fork`` is
missing, or the child fails, the first half is solved here instead.
"""

from __future__ import annotations

import multiprocessing
import sys
from dataclasses import replace

import numpy as np

from vidcap.video.solve.residuals import PER_FRAME, Problem, residuals, solved_signs
from vidcap.video.solve.skeleton import forward_kinematics

#: Fewest frames a clip is split at: below, the fork and the seam cost more than half
#: a solve saves (on 300 frames the solve is 1.2-1.5 s, the fork ~20 ms).
SPLIT_MIN_FRAMES = 200
#: Frames each half solves past the middle (the sign sweep's runs and the repair's
#: windows reach a few frames; the second differences two).
OVERLAP = 20
#: Frames either side of the join solved again after it.
SEAM = 12
#: Frames held beyond the seam window (the second differences reach two frames).
_HOLD = 2


def solve_split(solve, problem: Problem, params, **kw):
    """``solve(problem, params, fixed=None, **kw)`` in two halves at once (see the module
    docstring).

    Parameters
    ----------
    solve : callable
        Solves a clip in this process and returns its
        :class:`~vidcap.video.solve.clip.ClipSolve` and the problem as last solved
        (robust weights, exchanged names), as ``vidcap.video.solve.clip`` does.
    problem : Problem
    params : array_like, shape (F, 24)
        The start.
    **kw
        ``solve``'s options (``sweeps``, ``max_iter``, ``robust``, ``labels``,
        ``held_labels`` (F, 2), ``robust_kept`` (F, 15)).

    Returns
    -------
    ClipSolve
        For the whole clip; ``iterations`` counts both halves' and the seam's.
    """
    F = problem.n_frames
    mid = F // 2
    first, second = (0, mid + OVERLAP), (mid - OVERLAP, F)
    params = np.asarray(params, dtype=float)
    child = _start(_half, solve, problem, params, first, kw)
    a = None
    try:
        b = _half(solve, problem, params, second, kw)
        a = _finish(child)
    finally:
        _stop(child, done=a is not None)
    if a is None:  # no fork here, or the child failed
        a = _half(solve, problem, params, first, kw)
    return _join(solve, a, b, mid, second[0], kw)


def _cut(x, start: int, stop: int):
    """``x``'s frames ``start:stop`` (None stays None)."""
    return None if x is None else np.asarray(x)[start:stop]


def _half(solve, problem: Problem, params, bounds, kw):
    """``solve`` of frames ``bounds`` = [start, stop) alone: (ClipSolve, last problem)."""
    start, stop = bounds
    part = dict(kw, held_labels=_cut(kw.get("held_labels"), start, stop),
                robust_kept=_cut(kw.get("robust_kept"), start, stop))
    return solve(problem.frames(start, stop), params[start:stop], fixed=None, **part)


def _join(solve, a, b, mid: int, b_start: int, kw):
    """The halves' results (``a`` from frame 0, ``b`` from ``b_start``) joined at ``mid``,
    with the seam solved again."""
    (sa, pa), (sb, pb) = a, b
    k = mid - b_start  # frame ``mid`` in the second half

    def cat(x, y):
        return None if x is None or y is None else np.concatenate([x[:mid], y[k:]])

    problem = _cat_problems(pa, pb, mid, k)
    p = cat(sa.params, sb.params)
    confidence = cat(sa.confidence, sb.confidence)
    iters = sa.iterations + sb.iterations
    lo, hi = max(0, mid - SEAM - _HOLD), min(problem.n_frames, mid + SEAM + _HOLD)
    fixed = np.zeros(hi - lo, bool)
    fixed[:_HOLD] = fixed[-_HOLD:] = True
    seam, _ = solve(problem.frames(lo, hi), p[lo:hi], fixed=fixed,
                    sweeps=kw.get("sweeps", 2), max_iter=kw.get("max_iter", 30))
    p[lo:hi] = seam.params
    confidence[lo + _HOLD:hi - _HOLD] = seam.confidence[_HOLD:-_HOLD]
    iters += seam.iterations
    joints, _, _ = forward_kinematics(p, problem.offsets)
    r = residuals(problem, p)
    swapped = cat(sa.swapped, sb.swapped)
    return replace(sa, params=p, joints3d=joints, signs=solved_signs(joints, problem.lengths),
                   confidence=confidence, contact=problem.contact.copy(),
                   cost=0.5 * float(r @ r), iterations=iters, swapped=swapped)


def _cat_problems(pa: Problem, pb: Problem, mid: int, k: int) -> Problem:
    """``pa``'s frames to ``mid`` then ``pb``'s from ``k``: the per-frame fields joined,
    the clip's (offsets, lengths, the terms' weights) ``pa``'s."""
    return replace(pa, **{name: np.concatenate([getattr(pa, name)[:mid], getattr(pb, name)[k:]])
                          for name in PER_FRAME})


# --------------------------------------------------------------------------- the child
def _start(fn, *args):
    """A forked child running ``fn(*args)`` and sending its result back, as
    (process, connection); None where it cannot start (no ``os.fork``, or this process
    is a daemonic worker, which may have no children)."""
    if not sys.platform.startswith("linux") or "fork" not in \
            multiprocessing.get_all_start_methods():
        return None  # pragma: no cover - the first half is then solved here
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_run_child, args=(send, fn, args), name="vidcap-solve",
                       daemon=True)
    try:
        proc.start()
    except (AssertionError, OSError):  # a daemonic process (no children), or no memory
        recv.close()
        return None
    finally:
        send.close()
    return proc, recv


def _run_child(conn, fn, args) -> None:
    """The child: ``fn(*args)`` under one BLAS thread, its result or None sent back.
    Ctrl-C is the parent's to handle (it kills the child on its way out)."""
    import signal

    from threadpoolctl import threadpool_limits

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with threadpool_limits(1):
            out = fn(*args)
    except Exception:  # noqa: BLE001 - the parent solves this half itself
        out = None
    conn.send(out)
    conn.close()


def _finish(child):
    """The child's result (None when there is no child or it failed)."""
    if child is None:
        return None
    proc, conn = child
    try:
        return conn.recv()
    except (EOFError, OSError):  # it died: the parent solves its half
        return None


def _stop(child, *, done: bool) -> None:
    """Make sure the child is gone: once it has sent its result (``done``) it is let
    exit, else (an error or Ctrl-C in the parent) killed."""
    if child is None:
        return
    proc, conn = child
    conn.close()
    if done:
        proc.join(timeout=2.0)
    if proc.is_alive():
        proc.kill()
    proc.join()
