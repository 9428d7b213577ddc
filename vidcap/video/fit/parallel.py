"""Fitting a clip in chunks on several cores (beyond the seed).

:func:`fit_sequence_chunked` splits a clip into consecutive chunks, fits each with
:func:`vidcap.video.fit.pose2d.fit_sequence` in a worker process and joins the results.

Tracked fitting (the default) carries every frame's pose into the next, so a chunk
cannot start where the previous one ends: each chunk after the first starts
``overlap`` frames early, from scratch, and those frames are fitted twice. The
overlap frames are dropped from the later chunk, so by the frame where a chunk's
output begins its track has settled (it began with a fresh fit and has had a
challenge, see ``reinit_every``). Chunk starts are multiples of ``reinit_every``, so
the frames challenged by a fresh fit are the same as in one serial pass.

Left and right
--------------
In tracked mode ``l_*``/``r_*`` label limbs from the frame where a track began
(:mod:`vidcap.video.fit.pose2d`), so two chunks may label the same leg differently (the
legs of a side view cross every step). Each chunk's arm pair and leg pair are
relabelled (:func:`reconcile_labels`) to whichever labelling agrees better with the
chunk before it, so labels follow limbs across the whole clip as in one serial pass.
The overlap frames are where the later chunk's track has not settled yet (its first
challenge is at its first output frame): judged by them alone, a chunk whose track
settled into the serial pass's at that frame was as often named the other way round.
So each tracked chunk but the last fits :data:`TAIL` frames past its end, and where
those frames (both chunks settled) tell one labelling clearly, they decide.

Workers are processes. Where ``os.fork`` is (Linux, macOS), one process loads the
compiled kernels (numba's start-up, ~1 s of CPU) and forks the workers, which inherit
them, so the start-up is paid once instead of once per worker; elsewhere they are a
``concurrent.futures.ProcessPoolExecutor``'s, each loading its own. Masks are sent as
:class:`vidcap.video.masks.MaskStack` crops, and the colour frames for the cues as
:class:`vidcap.video.fit.cueframes.FrameCrops` (each frame's silhouette box, ~20-60 KB).
A :class:`FitPool` starts the workers ahead of the fit, so they get ready while the
caller does other work. Each worker reports every frame it finishes, so one progress bar
advances smoothly over the whole clip.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import queue as queue_mod
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from vidcap.video.fit.cueframes import FrameCrops, as_frame_crops
from vidcap.video.fit.ensemble import fit_ensemble
from vidcap.video.fit.labels import LIMB_PAIRS
from vidcap.video.fit.result import Pose2D
from vidcap.video.fit.tracking import REINIT_EVERY, fit_sequence, sequence_colours
from vidcap.video.masks import MaskStack, mask_frames

#: Most worker processes :func:`default_jobs` picks.
MAX_JOBS = 8
#: Frames each tracked chunk but the last fits past its end, to name the next chunk's
#: limbs by (:func:`reconcile_labels`).
TAIL = 2
#: The tail decides when one labelling's distance is below this share of the other's.
_TAIL_CLEAR = 0.5

_PER_SEGMENT = ("angles", "foreshortening", "scores", "margins")
_PER_FRAME = ("joints2d", "angles", "foreshortening", "scores", "margins", "spread",
              "similarity", "warm", "model_height")


def default_jobs() -> int:
    """Worker processes to use: the CPUs this process may run on, at most :data:`MAX_JOBS`."""
    try:
        n = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        n = os.cpu_count() or 1
    return max(1, min(n, MAX_JOBS))


def chunk_bounds(n_frames: int, jobs: int, *, overlap: int = 10, align: int = 10,
                 min_chunk: int = 60, per_job: int = 1) -> list[tuple[int, int, int]]:
    """How :func:`fit_sequence_chunked` splits a clip.

    Parameters
    ----------
    n_frames : int
        Frames in the clip.
    jobs : int
        Worker processes: about one chunk per worker.
    overlap : int
        Frames each chunk after the first starts before its output begins.
    align : int
        Chunk outputs begin at multiples of this (``reinit_every``), so chunk starts
        are too when ``overlap`` is a multiple of it.
    min_chunk : int
        Fewest output frames per chunk; a clip shorter than two such chunks is one
        chunk (fitted serially).
    per_job : int
        Chunks per worker (at most): more, shorter chunks let a streamed fit
        (:class:`StreamedFit`) start sooner and leave less to fit after the last
        frame arrives, at the cost of ``overlap`` frames fitted twice per chunk.

    Returns
    -------
    list of (start, begin, end)
        Each chunk fits frames ``start..end-1`` and outputs ``begin..end-1``
        (``start = begin - overlap``, ``0`` for the first); the outputs tile the clip.
    """
    jobs = max(1, int(jobs))
    align = max(1, int(align))
    n_chunks = min(jobs * max(1, int(per_job)), n_frames // max(1, min_chunk))
    if n_chunks < 2:
        return [(0, 0, n_frames)]
    size = int(math.ceil(n_frames / n_chunks / align)) * align
    begins = list(range(0, n_frames, size))
    ends = begins[1:] + [n_frames]
    return [(max(0, b - overlap), b, e) for b, e in zip(begins, ends, strict=True)]


def reconcile_labels(prev: dict, cur: dict, *, tail: int = 0) -> dict:
    """Relabel ``cur``'s limb pairs to agree with ``prev`` over the frames both fitted.

    Parameters
    ----------
    prev, cur : dict
        Per-frame arrays (the keys of :meth:`Pose2D.arrays`; ``joints2d`` (F, 15, 2)
        and the per-segment arrays (F, 10)) of the same overlap frames, from the
        chunk before and from this chunk.
    tail : int
        The last ``tail`` of those frames are where both chunks' tracks have settled
        (the chunk before fitted them past its end, :data:`TAIL`): a labelling whose
        distance there is below half the other's is chosen by them alone.

    Returns
    -------
    dict
        ``{"arms": bool, "legs": bool}``: whether this chunk's image-left and
        image-right arms (legs) should swap labels, i.e. whether the swapped
        labelling's joints are closer to ``prev``'s, summed over the frames (the tail's,
        where it is clear, else all of them).
    """
    out = {}
    a, b = np.asarray(prev["joints2d"], float), np.asarray(cur["joints2d"], float)
    for name, ((jl, _), (jr, _)) in LIMB_PAIRS.items():
        both = jl + jr
        keep = np.nansum(np.linalg.norm(a[:, both] - b[:, both], axis=-1), axis=1)
        swap = np.nansum(np.linalg.norm(a[:, both] - b[:, jr + jl], axis=-1), axis=1)
        k_t, s_t = keep[len(keep) - tail:].sum(), swap[len(swap) - tail:].sum()
        if tail > 0 and min(k_t, s_t) < _TAIL_CLEAR * max(k_t, s_t):
            out[name] = bool(s_t < k_t)
        else:
            out[name] = bool(swap.sum() < keep.sum())
    return out


def swap_labels(arrays: dict, swaps: dict) -> dict:
    """``arrays`` (per-frame, as in :func:`reconcile_labels`) with limb pairs relabelled.

    Returns a new dict; ``swaps`` is what :func:`reconcile_labels` returns.
    """
    out = {k: (np.array(v, copy=True) if k in _PER_FRAME else v) for k, v in arrays.items()}
    for name, ((jl, sl), (jr, sr)) in LIMB_PAIRS.items():
        if not swaps.get(name):
            continue
        out["joints2d"][:, jl + jr] = arrays["joints2d"][:, jr + jl]
        for key in _PER_SEGMENT:
            out[key][:, sl + sr] = arrays[key][:, sr + sl]
    return out


def warm_up() -> None:
    """Load the compiled kernels in this process by fitting a tiny synthetic figure.

    Loading numba's cached kernels costs ~0.5-0.8 s of CPU per process: a
    :class:`FitPool`'s workers do it as they start, while the parent is still busy
    (e.g. extracting silhouettes), so their first chunk starts with the kernels loaded.
    """
    from vidcap.video.fit.raster import draw_pose, model_dimensions, pose_joints

    lengths, radii, shoulder, hip = model_dimensions(60.0)
    angles = np.deg2rad([90, 90, 250, 290, 280, 300, 260, 275, 285, 265])
    frames = []
    for dx in (0.0, 2.0):
        j = pose_joints(np.array([40.0 + dx, 40.0]), angles, np.ones(10), 0.4, lengths,
                        shoulder, hip)
        frames.append(draw_pose(j, radii, (90, 80), caps=False))
    fit_sequence(np.array(frames), reinit_every=0, spread_window=0)


# ----------------------------------------------------------------------------- workers
_QUEUE = None
#: How much lower than its parent a worker runs (``os.nice`` increment).
_WORKER_NICENESS = 5


def _init_worker(q, warm: bool = False) -> None:
    global _QUEUE
    _QUEUE = q
    # one core each: no BLAS or OpenMP threads competing with the other workers
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"
    # below the parent: it makes the frames the workers wait for (the pipeline's
    # silhouettes), so while it runs it should not share a core with them
    try:
        os.nice(_WORKER_NICENESS)
    except (AttributeError, OSError):  # pragma: no cover - not POSIX
        pass
    if warm:
        warm_up()


def _ready() -> bool:
    return True


# --------------------------------------------------------- workers forked from a warm one
def _worker_loop(tasks, results) -> None:
    """Run ``(id, fn, args)`` tasks until a None; each result goes back as
    ``(id, True, value)`` or ``(id, False, exception)``."""
    while True:
        try:
            item = tasks.get()
        except EOFError:  # the parent has gone (it held the last writing end)
            return
        if item is None:
            return
        tid, fn, args = item
        try:
            out = (tid, True, fn(*args))
        except BaseException as exc:  # noqa: BLE001 - reported to the caller's future
            out = (tid, False, exc)
        try:
            results.put(out)
        except Exception as exc:  # noqa: BLE001 - e.g. an exception that does not pickle
            results.put((tid, False, RuntimeError(f"a fitting worker's result could not "
                                                  f"be sent back ({exc!r})")))


def _zygote(tasks, results, progress, jobs: int, warm: bool) -> None:
    """Load the kernels once, then fork the ``jobs`` workers (they inherit them) and
    wait for them, telling the parent when one stops abnormally."""
    import signal

    # Ctrl-C is the parent's to handle: it stops the workers as it closes the pool
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        _init_worker(progress, warm)
    except Exception:  # noqa: BLE001 - each chunk then reports the failure itself
        pass
    # only the parent writes tasks: when it goes, the workers' reads end (EOF)
    tasks._writer.close()
    pids = []
    for _ in range(jobs):
        pid = os.fork()
        if pid == 0:  # a worker
            code = 1
            try:
                results._reader.close()
                _worker_loop(tasks, results)
                code = 0
            finally:
                os._exit(code)
        pids.append(pid)
    tasks._reader.close()
    results._reader.close()
    try:
        # nothing was written to ``results`` before the forks (no queue thread copied)
        results.put(("pids", pids))
        for _ in pids:
            pid, status = os.wait()
            if status:
                results.put(("died", pid, status))
        results.put(("exit",))
    except (BrokenPipeError, EOFError):  # the parent has gone: nobody to tell
        pass


class _ForkedPool:
    """The part of ``ProcessPoolExecutor`` :class:`StreamedFit` uses (``submit``,
    ``shutdown``), with the workers forked from one process that has loaded the
    compiled kernels, so numba's start-up (~1 s of CPU) is paid once, not per worker.
    Needs ``os.fork``."""

    def __init__(self, jobs: int, progress, ctx, *, warm: bool = True):
        import itertools
        import threading

        self.jobs = jobs
        self._tasks, self._results = ctx.SimpleQueue(), ctx.SimpleQueue()
        self._proc = ctx.Process(target=_zygote, name="vidcap-fit",
                                 args=(self._tasks, self._results, progress, jobs, warm),
                                 daemon=True)
        self._proc.start()
        self._futures: dict = {}
        self._ids = itertools.count()
        self._lock = threading.Lock()
        self._pids: list[int] = []
        self._closed = False
        self._submitted = False
        self._collector = threading.Thread(target=self._collect, name="vidcap-fit-results",
                                           daemon=True)
        self._collector.start()

    def submit(self, fn, *args):
        from concurrent.futures import Future

        if self._closed:
            raise RuntimeError("the fitting pool is closed")
        fut = Future()
        fut.set_running_or_notify_cancel()
        tid = next(self._ids)
        with self._lock:
            self._futures[tid] = fut
            self._submitted = True
        self._tasks.put((tid, fn, args))
        return fut

    def _fail_all(self, exc: BaseException) -> None:
        with self._lock:
            pending, self._futures = self._futures, {}
        for fut in pending.values():
            if not fut.done():
                fut.set_exception(exc)

    def _collect(self) -> None:
        while True:
            try:
                msg = self._results.get()
            except (EOFError, OSError):
                msg = ("exit",)
            if msg[0] == "pids":
                self._pids = list(msg[1])
            elif msg[0] == "died":
                self._fail_all(RuntimeError(
                    f"a fitting worker stopped abnormally (process {msg[1]}, wait status "
                    f"{msg[2]})"))
            elif msg[0] == "exit":
                self._fail_all(RuntimeError("the fitting workers have stopped"))
                return
            else:
                tid, ok, value = msg
                with self._lock:
                    fut = self._futures.pop(tid, None)
                if fut is not None:
                    (fut.set_result if ok else fut.set_exception)(value)

    def check(self) -> None:
        """Fail the pending futures if the workers' parent process has gone."""
        if not self._proc.is_alive():
            self._fail_all(RuntimeError(f"the fitting workers have stopped (exit code "
                                        f"{self._proc.exitcode})"))

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        import signal

        if not self._closed:
            self._closed = True
            with self._lock:
                busy = any(not f.done() for f in self._futures.values())
            if cancel_futures and (busy or not self._submitted):
                # nobody will read these (or no work came): stop the workers now
                if not self._pids:  # not forked yet
                    self._proc.terminate()
                for pid in self._pids:
                    try:
                        os.kill(pid, signal.SIGTERM)
                    except OSError:
                        pass
            if self._proc.is_alive():
                for _ in range(self.jobs):
                    self._tasks.put(None)
        if wait:
            self._proc.join()
            if self._collector.is_alive():  # a stopped zygote said nothing: wake it
                self._collector.join(timeout=0.2)
                if self._collector.is_alive():
                    self._results.put(("exit",))
            self._collector.join(timeout=5.0)


def _kill_tree(pids) -> None:
    """SIGKILL processes and everything below them (frozen first: none forks away)."""
    import signal

    from vidcap.interrupt import descendants

    tree = [q for pid in pids for q in (pid, *descendants(pid))]
    for sig in (signal.SIGSTOP, signal.SIGKILL):
        for pid in tree:
            try:
                os.kill(pid, sig)
            except OSError:
                pass


class FitPool:
    """Worker processes for :func:`fit_sequence_chunked`, started ahead of the fit.

    The workers start (and load the compiled kernels, :func:`warm_up`) as soon as the
    pool is created, so a caller can create it, do other work (the pipeline extracts
    silhouettes) and then fit without waiting for the workers to get ready. Use as a
    context manager; pass it as ``pool=`` to :func:`fit_sequence_chunked`. Where
    ``os.fork`` is, the kernels are loaded once and the workers forked from that
    process (see the module docstring); a worker that dies fails the fit with an error
    rather than leaving it waiting, and the workers end when the caller's process does.

    Parameters
    ----------
    jobs : int
        Worker processes.
    warm : bool
        Start every worker now and load its kernels (:func:`warm_up`); false: workers
        start with their first chunk.
    """

    def __init__(self, jobs: int, *, warm: bool = True):
        self.jobs = max(1, int(jobs))
        ctx = _context()
        self.queue = ctx.Queue()
        if ctx.get_start_method() == "fork" and hasattr(os, "fork"):
            # numba's start-up imports scipy.linalg (its BLAS check: ~0.15 s of the
            # zygote's ~0.55 s warm-up); the pipeline's 3D solve needs it here anyway,
            # so it is imported before the fork and the zygote inherits it
            import scipy.linalg  # noqa: F401

            # one process loads the kernels and forks the workers, which inherit them
            self.executor = _ForkedPool(self.jobs, self.queue, ctx, warm=warm)
            return
        self.executor = ProcessPoolExecutor(max_workers=self.jobs, mp_context=ctx,
                                            initializer=_init_worker,
                                            initargs=(self.queue, warm))
        if warm:
            for _ in range(self.jobs):  # start every worker now
                self.executor.submit(_ready)

    def __enter__(self) -> FitPool:
        return self

    def __exit__(self, exc_type, *_) -> None:
        if exc_type is not None:
            self.kill()
        self.close()

    def close(self) -> None:
        """Stop the workers (waits for running chunks)."""
        self.executor.shutdown(wait=True, cancel_futures=True)

    def kill(self) -> None:
        """Stop the workers now, dropping their chunks (an error or Ctrl-C: nobody will
        read them); :meth:`close` afterwards returns at once."""
        ex = self.executor
        if isinstance(ex, _ForkedPool):
            _kill_tree([ex._proc.pid, *ex._pids])
        else:  # pragma: no cover - platforms without fork
            _kill_tree(list(getattr(ex, "_processes", {}) or {}))
        self.executor.shutdown(wait=False, cancel_futures=True)


def _fit_chunk(masks: MaskStack, frames, skip: int, tracked: bool, kw: dict,
               stop: int | None = None) -> dict:
    """Fit one chunk in a worker (``frames``: its :class:`FrameCrops`, or None);
    reports each frame from ``skip`` on (to ``stop``, the tail left out) to the queue."""

    def report(it, total):
        for k in it:
            yield k
            if skip <= k < (total if stop is None else stop) and _QUEUE is not None:
                _QUEUE.put(1)

    pose = fit_ensemble(masks, tracked=tracked, progress=report, frames=frames, **kw)
    return pose.arrays()


def _context():
    """Fork where it is safe and fast (Linux), else the platform's default."""
    if sys.platform.startswith("linux") and "fork" in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("fork")
    return multiprocessing.get_context()  # pragma: no cover


def fit_sequence_chunked(masks, *, jobs: int | None = None, tracked: bool = True,
                         progress=None, overlap: int = 10, min_chunk: int = 60,
                         per_job: int = 1, pool: FitPool | None = None, frames=None,
                         workers: int | None = None, **kw) -> Pose2D:
    """:func:`vidcap.video.fit.pose2d.fit_sequence` in chunks on ``jobs`` worker processes.

    Parameters
    ----------
    masks : numpy.ndarray, shape (F, H, W), bool, or MaskStack
        Silhouettes in original-frame pixels.
    jobs : int, optional
        Worker processes (default :func:`default_jobs`), and the processes the chunks
        are planned for (:func:`chunk_bounds`). 1, or a clip shorter than two chunks
        of ``min_chunk`` frames, runs ``fit_sequence`` in this process.
    tracked : bool
        As in ``fit_sequence``; per-frame fitting (False) needs no overlap.
    progress : callable, optional
        As in ``fit_sequence``: wraps an iterator over the frames as they finish.
    overlap : int
        Frames each chunk after the first fits before its output begins (see the
        module docstring; a multiple of ``reinit_every`` keeps the challenge frames
        of a serial pass).
    min_chunk : int
        Fewest output frames per chunk.
    per_job : int
        Chunks per worker, at most (:func:`chunk_bounds`).
    pool : FitPool, optional
        Workers started beforehand (``jobs`` defaults to its size); default: a pool
        made for this call.
    frames : numpy.ndarray, shape (F, H, W, 3), uint8, or FrameCrops, optional
        The colour frames for the cues (``fit_sequence``'s ``frames``): cut to the
        silhouettes' boxes (:class:`~vidcap.video.fit.cueframes.FrameCrops`) once
        here, and each chunk's crops sent to its worker.
    workers : int, optional
        Worker processes for chunks planned for ``jobs`` (default ``jobs``; ignored
        with ``pool``). 1: the chunks are fitted here, one after another, and joined as
        the workers' would be: the same result as on any number of processes (a
        tracked chunk's fit depends on where it starts, so one serial pass differs).
    **kw
        Passed to ``fit_sequence`` (``reinit_every``, ``height``, ``cues``, ...);
        ``ensemble``: each chunk fitted as :func:`vidcap.video.fit.ensemble.fit_ensemble`.

    Returns
    -------
    Pose2D
        As from ``fit_sequence``; tracked labels reconciled across chunks.
    """
    masks = mask_frames(masks)
    if frames is not None:
        frames = as_frame_crops(frames, masks, height=kw.get("height", 80))
    if jobs is None:
        jobs = pool.jobs if pool is not None else default_jobs()
    jobs = max(1, int(jobs))
    own = pool is None
    if own:
        bounds = _bounds(len(masks), jobs, tracked, overlap, min_chunk, per_job, kw)
        if len(bounds) < 2:
            return fit_ensemble(masks, tracked=tracked, progress=progress, frames=frames,
                                **kw)
        workers = jobs if workers is None else max(1, int(workers))
        if workers == 1:
            return _fit_here(masks, frames, bounds, tracked, progress, kw)
        pool = FitPool(min(workers, len(bounds)), warm=False)
    try:
        fit = StreamedFit(pool, len(masks), jobs=jobs, tracked=tracked, overlap=overlap,
                          min_chunk=min_chunk, per_job=per_job, **kw)
        return fit.finish(masks, frames=frames, progress=progress)
    finally:
        if own:
            pool.close()


def _fit_here(masks: MaskStack, frames, bounds, tracked: bool, progress, kw) -> Pose2D:
    """The chunks ``bounds`` fitted in this process one after another and joined, as
    :class:`StreamedFit`'s workers fit them (the clip's colour model learned once)."""
    colours = sequence_colours(masks, frames, **kw)
    if colours is not None:
        kw = {**kw, "colours": colours}
    parts = []

    def fitted():
        for chunk in bounds:
            s, b, e = chunk
            f = _fit_end(bounds, chunk, tracked)
            # bit-packed crops, as the workers are sent them
            sil = masks[s:f] if isinstance(masks, MaskStack) else MaskStack.from_masks(masks[s:f])
            parts.append(_fit_chunk(sil, None if frames is None else frames[s:f], b - s,
                                    tracked, kw, e - s))
            yield from range(b, e)

    for _ in (fitted() if progress is None else progress(fitted(), total=len(masks))):
        pass
    return _join(bounds, parts, len(masks), tracked)


def _bounds(n, jobs, tracked, overlap, min_chunk, per_job, kw):
    """:func:`chunk_bounds` as :func:`fit_sequence_chunked` calls it."""
    align = int(kw.get("reinit_every", REINIT_EVERY)) or 1
    return chunk_bounds(n, jobs, overlap=overlap if tracked else 0, align=align,
                        min_chunk=min_chunk, per_job=per_job)


class StreamedFit:
    """:func:`fit_sequence_chunked` for frames that arrive over time.

    Each chunk but the last goes to a worker as soon as its frames are there
    (:meth:`feed`), so the fit of the first chunks runs while later frames are still
    being made (the pipeline extracts silhouettes meanwhile); :meth:`finish` sends
    the rest and joins the chunks. The result equals ``fit_sequence_chunked`` of all
    the frames with the same pool and options.

    Parameters
    ----------
    pool : FitPool
    n_frames : int
        Frames expected (chunks are planned for it; if the clip turns out to have
        another number, :meth:`finish` plans again and refits what no longer fits
        the plan).
    jobs, tracked, overlap, min_chunk, per_job, **kw
        As in :func:`fit_sequence_chunked` (``jobs`` default: the pool's size).
    """

    def __init__(self, pool: FitPool, n_frames: int, *, jobs: int | None = None,
                 tracked: bool = True, overlap: int = 10, min_chunk: int = 60,
                 per_job: int = 1, **kw):
        self.pool, self.tracked, self.kw = pool, bool(tracked), kw
        self.jobs = max(1, int(pool.jobs if jobs is None else jobs))
        self.overlap, self.min_chunk, self.per_job = overlap, min_chunk, per_job
        self.bounds = _bounds(int(n_frames), self.jobs, self.tracked, overlap, min_chunk,
                              per_job, kw)
        self.futures = {}  # (start, begin, end) -> Future

    def _colours(self, masks, frames, n: int | None) -> bool:
        """The clip's colour model for the cues into ``self.kw`` (learned once, from the
        clip's first frames: every chunk reads the same, as one serial fit does); False
        while the frames it is learned from are not all in (``n``: the frames so far,
        None: all)."""
        if frames is None or self.kw.get("colours") is not None:
            return True
        colours = sequence_colours(masks, frames, n=n, **self.kw)
        if colours is not None:
            self.kw = {**self.kw, "colours": colours}
        return colours is not None or self.kw.get("cues", "all") != "all"

    def _submit(self, chunk, masks, frames, bounds) -> None:
        s, b, end = chunk
        e = _fit_end(bounds, chunk, self.tracked)
        # sent as bit-packed crops, whatever the frames came as
        sil = masks[s:e] if isinstance(masks, MaskStack) else MaskStack.from_masks(masks[s:e])
        self.futures[chunk] = self.pool.executor.submit(
            _fit_chunk, sil, None if frames is None else frames[s:e], b - s, self.tracked,
            self.kw, end - s)

    def feed(self, masks, frames: FrameCrops | None = None) -> None:
        """Send every planned chunk but the last whose frames are all in ``masks`` (the
        frames so far, from frame 0: a MaskStack, a list or an array of (H, W) bool)
        and in ``frames`` (their colour crops for the cues, or None: the outline
        only)."""
        n = len(masks) if frames is None else min(len(masks), len(frames))
        if not self._colours(masks, frames, n):
            return
        for chunk in self.bounds[:-1]:
            if chunk not in self.futures and _fit_end(self.bounds, chunk, self.tracked) <= n:
                self._submit(chunk, masks, frames, self.bounds)

    def finish(self, masks, *, frames=None, progress=None) -> Pose2D:
        """Fit what is left of all ``masks`` (F, H, W) (``frames``: their colour frames
        or :class:`FrameCrops`, as fed) and join the chunks."""
        masks = mask_frames(masks)
        if frames is not None:
            frames = as_frame_crops(frames, masks, height=self.kw.get("height", 80))
        n = len(masks)
        bounds = _bounds(n, self.jobs, self.tracked, self.overlap, self.min_chunk,
                         self.per_job, self.kw)
        if len(bounds) < 2:
            return fit_ensemble(masks, tracked=self.tracked, progress=progress,
                                frames=frames, **self.kw)
        self._colours(masks, frames, None)
        for chunk in bounds:
            if chunk not in self.futures:
                self._submit(chunk, masks, frames, bounds)
        futures = [self.futures[c] for c in bounds]
        q = self.pool.queue

        def finished():
            done = 0
            while done < n:
                try:
                    done += q.get(timeout=0.05)
                except queue_mod.Empty:
                    if all(f.done() for f in futures):
                        break
                    check = getattr(self.pool.executor, "check", None)
                    if check is not None:  # dead workers take their chunks with them
                        check()
                    continue
                yield done - 1
            yield from range(done, n)  # reports still in flight when the last chunk ended

        for _ in (finished() if progress is None else progress(finished(), total=n)):
            pass
        parts = [f.result() for f in futures]
        return _join(bounds, parts, n, self.tracked)


def _fit_end(bounds, chunk, tracked: bool) -> int:
    """The frame after the last one ``chunk`` (one of ``bounds``) fits: its end, and
    :data:`TAIL` frames more for a tracked chunk but the last (within the clip)."""
    if not tracked or chunk == bounds[-1]:
        return chunk[2]
    return min(chunk[2] + TAIL, bounds[-1][2])


def _join(bounds, parts, n, tracked) -> Pose2D:
    """The chunks' fits as one :class:`Pose2D` (labels reconciled over the overlaps and
    the tails)."""
    out = {k: np.empty((n, *np.shape(v)[1:]), dtype=np.asarray(v).dtype)
           for k, v in parts[0].items() if k in _PER_FRAME}
    tail = {k: out[k][:0] for k in out}  # the chunk before's frames past its end
    for (s, b, e), part in zip(bounds, parts, strict=True):
        if tracked and b > s:
            prev = {k: np.concatenate([out[k][s:b], tail[k]]) for k in out}
            cur = {k: part[k][: b - s + len(tail["joints2d"])] for k in out}
            part = swap_labels(part, reconcile_labels(prev, cur, tail=len(tail["joints2d"])))
        for k in out:
            out[k][b:e] = part[k][b - s:e - s]
        tail = {k: np.asarray(part[k][e - s:]) for k in out}
    return Pose2D(tuple(str(x) for x in parts[0]["joint_names"]), out["joints2d"],
                  out["angles"], out["foreshortening"], out["scores"], out["margins"],
                  out["spread"], out["similarity"], out["warm"], bool(tracked),
                  tuple(str(x) for x in parts[0]["segment_names"]),
                  model_height=out.get("model_height"))


__all__ = ["MAX_JOBS", "FitPool", "StreamedFit", "chunk_bounds", "default_jobs",
           "fit_sequence_chunked", "reconcile_labels", "swap_labels", "warm_up"]
