"""The Dask executor of ``vidcap batch``: one task per clip on a ``distributed`` cluster.

The workers read the inputs and write the outputs themselves, so both must be on a
filesystem every worker shares with this machine; :func:`check_workers` proves it
on one worker before any clip is submitted. Retries are Dask's own: a worker that
dies mid-clip has its task rescheduled, and a clip whose workers die on every try
(``distributed.scheduler.allowed-failures``, 3 by default) ends as a failed row.
"""

from __future__ import annotations

import contextlib
import logging
import os
import tempfile
from collections.abc import Callable, Iterator, Sequence
from dataclasses import replace
from pathlib import Path

from vidcap.batch.job import ClipTask, convert_clip, failed_row
from vidcap.errors import UsageError

INSTALL_HINT = "the Dask executor needs Dask: pip install 'vidcap[dask]'"


def parse_scheduler(text: str, default_workers: int) -> tuple[str, int | str]:
    """Read ``--scheduler``.

    Returns
    -------
    ("local", n_workers) for ``local`` or ``local:N``, else ("address", text).
    """
    if text == "local" or text.startswith("local:"):
        count = text.partition(":")[2] or str(default_workers)
        if not count.isdigit() or int(count) < 1:
            raise UsageError(f"--scheduler local:N needs a worker count of at least 1, "
                             f"got {text!r}")
        return "local", int(count)
    return "address", text


@contextlib.contextmanager
def connect(scheduler: str, *, default_workers: int = 1, timeout: float = 10.0):
    """Yield a ``distributed.Client`` on ``scheduler`` (``tcp://HOST:PORT`` or ``local[:N]``).

    ``local[:N]`` starts a ``LocalCluster`` of N single-thread worker processes on
    the loopback interface and stops it afterwards; the scheduler's HTTP server (which
    Dask always starts) takes a free loopback port, never the user's 8787.

    Raises
    ------
    vidcap.errors.UsageError
        Dask is not installed, or the scheduler does not answer within ``timeout`` s.
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise UsageError(INSTALL_HINT) from None
    kind, value = parse_scheduler(scheduler, default_workers)
    with contextlib.ExitStack() as stack:
        if kind == "local":
            import dask

            # One clip in hand per single-thread worker: a clip queued behind another
            # would count as "suspicious" when its neighbour kills the worker, and a
            # healthy clip could end failed (allowed-failures). Clips are long, so
            # queuing on the worker saves nothing.
            stack.enter_context(dask.config.set({"distributed.scheduler.worker-saturation": 1.0}))
            cluster = stack.enter_context(LocalCluster(
                n_workers=value, threads_per_worker=1, processes=True, host="127.0.0.1",
                dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR))
            address = cluster.scheduler_address
        else:
            address = value
            check_scheduler(address, timeout)
        client = Client(address, timeout=timeout, set_as_default=False)
        stack.callback(client.close)
        yield client


def check_scheduler(address: str, timeout: float) -> None:
    """Fail in one line naming ``address`` unless a Dask scheduler answers there in time.

    Done with a bare handshake before the ``Client`` exists: a ``Client`` that fails
    half-way through its start-up blocks the exit while it tries to close.
    """
    import asyncio

    from distributed.comm import connect as dask_connect

    async def handshake():
        comm = await dask_connect(address, timeout=timeout)
        await comm.close()

    try:
        asyncio.run(asyncio.wait_for(handshake(), timeout + 1.0))
    except (ValueError, TypeError) as exc:
        raise UsageError(f"cannot use this scheduler address ({exc}); give tcp://HOST:PORT "
                         "or local[:N]", address) from None
    except Exception:  # noqa: BLE001 - refused, timed out, or not a Dask scheduler
        raise UsageError(f"cannot reach the Dask scheduler (no answer within {timeout:g} s)",
                         address) from None


def worker_access(video: str, outdir: str, clip_jobs: int = 1) -> str:
    """On a worker: ``""`` if it can read ``video``, write in ``outdir`` and (for
    ``clip_jobs`` > 1) start processes of its own; else why not."""
    import multiprocessing
    import socket

    host = socket.gethostname()
    if clip_jobs > 1 and multiprocessing.current_process().daemon:
        return (f"--clip-jobs {clip_jobs}: the Dask workers (on {host}) may not start "
                "processes; start them with DASK_DISTRIBUTED__WORKER__DAEMON=False, or "
                "leave --clip-jobs at 1")
    if not os.access(video, os.R_OK):
        return (f"{video}: a Dask worker (on {host}) cannot read this input; inputs and "
                "outputs must be on a filesystem every worker shares")
    try:
        fd, probe = tempfile.mkstemp(prefix=".vidcap-probe-", dir=outdir)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        return (f"{outdir}: a Dask worker (on {host}) cannot write here ({exc.strerror}); "
                "inputs and outputs must be on a filesystem every worker shares")
    return ""


def check_workers(client, video: str, outdir: str, timeout: float,
                  clip_jobs: int = 1) -> None:
    """Fail in one line unless a worker can read ``video``, write in ``outdir`` and
    run ``clip_jobs`` processes per clip (see :func:`worker_access`).

    Raises
    ------
    vidcap.errors.UsageError
        No worker answered within ``timeout`` s, a worker cannot import vidcap, or
        the paths are not shared with the workers.
    """
    from distributed import TimeoutError as DaskTimeout

    future = client.submit(worker_access, video, outdir, clip_jobs, pure=False)
    try:
        problem = future.result(timeout=timeout)
    except (DaskTimeout, TimeoutError):
        future.cancel()
        raise UsageError(f"no Dask worker ran the start-up check within {timeout:g} s: "
                         "does the scheduler have workers?", client.scheduler.address) from None
    except Exception as exc:  # noqa: BLE001 - e.g. vidcap missing on the worker
        raise UsageError(f"a Dask worker cannot run vidcap ({type(exc).__name__}: {exc}); "
                         "install the same vidcap on every worker",
                         client.scheduler.address) from None
    if problem:
        raise UsageError(problem)


def run_dask(tasks: Sequence[ClipTask], scheduler: str, *, outdir: str | os.PathLike,
             default_workers: int = 1, timeout: float = 10.0,
             job: Callable[[ClipTask], dict] = convert_clip) -> Iterator[dict]:
    """Run ``job`` on every task as one Dask task each; yield rows as they finish.

    Parameters
    ----------
    tasks : sequence of ClipTask
        Paths may be relative to this process's folder: workers get them absolute.
    scheduler : str
        ``tcp://HOST:PORT`` of a running scheduler, or ``local[:N]``.
    outdir : str or path-like
        The batch's output folder (checked writable from a worker first).
    default_workers : int
        Workers of ``local`` without a count.
    timeout : float
        Seconds to wait for the scheduler, and for a worker to run the start-up check.
    job : callable
        The per-clip function; :func:`vidcap.batch.job.convert_clip`.

    Yields
    ------
    dict
        Each clip's summary row (with the paths as given), in completion order.
        Ctrl-C cancels every submitted task before it propagates.
    """
    if not tasks:
        return
    with connect(scheduler, default_workers=default_workers, timeout=timeout) as client:
        from distributed import KilledWorker, as_completed

        absolute = [replace(t, video=os.path.abspath(t.video), output=os.path.abspath(t.output))
                    for t in tasks]
        check_workers(client, absolute[0].video, str(Path(outdir).absolute()), timeout,
                      clip_jobs=int(tasks[0].options.get("jobs") or 1))
        futures = [client.submit(job, t, pure=False) for t in absolute]
        given = {f.key: t for f, t in zip(futures, tasks, strict=True)}
        try:
            for future in as_completed(futures, loop=client.loop):
                task = given[future.key]
                try:
                    row = future.result()
                except KilledWorker:
                    row = failed_row(task, "every Dask worker that ran this clip died "
                                     "(tries bounded by distributed.scheduler.allowed-failures)")
                except Exception as exc:  # noqa: BLE001 - one clip never stops the others
                    row = failed_row(task, f"on a Dask worker: {exc or type(exc).__name__}")
                yield {**row, "file": task.video, "output": task.output}
        except BaseException:  # Ctrl-C, or the caller stopped early: drop the rest
            client.cancel(futures)
            raise
