"""The local executor of ``vidcap batch``: clips on a process pool of this machine."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed

from vidcap.batch.job import ClipTask, convert_clip


def run_local(tasks: Sequence[ClipTask], processes: int,
              job: Callable[[ClipTask], dict] = convert_clip) -> Iterator[dict]:
    """Run ``job`` on every task in ``processes`` processes; yield rows as they finish.

    Parameters
    ----------
    tasks : sequence of ClipTask
    processes : int
        Pool size (at least 1; never more than the tasks).
    job : callable
        The per-clip function (picklable); :func:`vidcap.batch.job.convert_clip`.

    Yields
    ------
    dict
        Each clip's summary row, in completion order.
    """
    if not tasks:
        return
    with ProcessPoolExecutor(max_workers=min(processes, len(tasks))) as pool:
        futures = [pool.submit(job, task) for task in tasks]
        try:
            for future in as_completed(futures):
                yield future.result()
        except BaseException:
            for future in futures:  # Ctrl-C: drop the clips not started yet
                future.cancel()
            raise
