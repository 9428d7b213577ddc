"""Clips per second of `vidcap batch` on the local pool and on a 2-worker Dask cluster.

Eight short clips are rendered with vidcap.synth (walk, jacks and arms at several
yaws; 30 frames, 160x120 by default) into a temporary folder, then converted in the
same run, each into its own output folder (no shared stage cache), by:

* the local process pool of 2 processes (``vidcap batch --jobs 2``: processes started
  and vidcap imported inside the timing, as every batch does),
* ``--scheduler local:2`` (a LocalCluster of 2 single-thread workers started inside
  the timing),
* a running loopback cluster of 2 single-thread workers that have each converted a
  clip already (``--scheduler tcp://...`` on a warm cluster: the steady state).

Each row prints wall time, clips per second and its ratio to the local pool; the
BVHs of every executor are checked byte-identical to the pool's. The scheduler's
overhead per task is measured on the warm cluster: the median round trip of an empty
task submitted alone (submit -> result), and the wall time per task of 400 empty
tasks submitted at once (the throughput bound).

Numerics run one thread per process in every executor (OMP/MKL/OpenBLAS threads 1, as
Dask's nanny sets for its workers): the comparison is of scheduling, not of how many
threads each process grabs on a loaded machine.

Run:  python benchmarks/batch_dask.py [--clips 8] [--frames 30]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"  # before numpy loads: the pool's processes fork from this one

import argparse  # noqa: E402
import logging  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vidcap.batch.cluster import run_dask  # noqa: E402
from vidcap.batch.job import ClipTask, convert_clip  # noqa: E402
from vidcap.batch.local import run_local  # noqa: E402
from vidcap.synth import make_motion, synth_clip  # noqa: E402

MOTIONS = ("walk", "jacks", "arms")
WORKERS = 2


def render(folder: Path, n_clips: int, frames: int, size) -> list[Path]:
    """``n_clips`` ground-truth clips cycling through the motions and yaws."""
    clips = []
    for k in range(n_clips):
        motion = MOTIONS[k % len(MOTIONS)]
        rng = np.random.default_rng(k)
        path = folder / f"{motion}_{k}.mp4"
        synth_clip(path, folder / f"{motion}_{k}_truth.npz",
                   make_motion(motion, n_frames=frames, rng=rng), size=size,
                   yaw_deg=60.0 + 15.0 * k, rng=rng, show_progress=False)
        clips.append(path)
    return clips


def timed(rows_iter) -> tuple[float, list[dict]]:
    t0 = time.perf_counter()
    rows = list(rows_iter)
    return time.perf_counter() - t0, rows


def noop() -> None:
    """An empty task."""


def task_overhead(client, n_serial: int = 50, n_bulk: int = 400) -> tuple[float, float]:
    """(median serial round trip, wall per task of a bulk submit), seconds."""
    trips = []
    for _ in range(n_serial):
        t0 = time.perf_counter()
        client.submit(noop, pure=False).result()
        trips.append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    futures = [client.submit(noop, pure=False) for _ in range(n_bulk)]
    client.gather(futures)
    return statistics.median(trips), (time.perf_counter() - t0) / n_bulk


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--clips", type=int, default=8)
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--size", default="160x120")
    args = ap.parse_args(argv)
    from distributed import Client, LocalCluster

    size = tuple(int(v) for v in args.size.split("x"))
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        t0 = time.perf_counter()
        clips = render(d, args.clips, args.frames, size)
        print(f"rendered {len(clips)} clips in {time.perf_counter() - t0:.1f} s", file=sys.stderr)

        def tasks(name):
            (d / name).mkdir()
            return [ClipTask(str(c), str(d / name / (c.stem + ".bvh")),
                             {"height": 1.75, "view": "auto", "jobs": 1}) for c in clips]

        results = {}
        results["local pool, 2 processes (--jobs 2)"] = timed(
            run_local(tasks("pool"), WORKERS)) + ("pool",)
        results["Dask --scheduler local:2 (cluster start timed)"] = timed(
            run_dask(tasks("cold"), f"local:{WORKERS}", outdir=d / "cold")) + ("cold",)
        with LocalCluster(n_workers=WORKERS, threads_per_worker=1, processes=True,
                          host="127.0.0.1", dashboard_address="127.0.0.1:0",
                          silence_logs=logging.ERROR) as cluster, \
                Client(cluster, set_as_default=False) as client:
            (d / "warmup").mkdir()  # the steady state: each worker has converted a clip
            client.run(convert_clip, ClipTask(str(clips[0]), str(d / "warmup" / "w.bvh"),
                                              {"jobs": 1, "cache_dir": None}))
            results["Dask on a running 2-worker cluster (warm)"] = timed(
                run_dask(tasks("warm"), cluster.scheduler_address, outdir=d / "warm")) + ("warm",)
            trip, bulk = task_overhead(client)

        failed = [r for _, rows, _ in results.values() for r in rows if r["status"] != "ok"]
        if failed:
            raise SystemExit(f"clips failed: {failed}")
        reference = {c.stem: (d / "pool" / (c.stem + ".bvh")).read_bytes() for c in clips}
        for _, _, name in results.values():
            for c in clips:
                assert (d / name / (c.stem + ".bvh")).read_bytes() == reference[c.stem], \
                    f"{name}: {c.stem}.bvh differs from the local pool's"
        pool_wall = next(iter(results.values()))[0]
        n_frames = sum(r["frames"] for r in next(iter(results.values()))[1])
        print(f"{len(clips)} clips, {n_frames} frames in all ({args.frames} each, "
              f"{args.size}); {WORKERS} workers; {os.cpu_count()} CPUs on this machine")
        print(f"{'executor':50s} {'wall s':>7s} {'clips/s':>8s} {'vs pool':>8s} "
              f"{'in the job s: first, median':>28s}")
        for label, (wall, rows, _) in results.items():
            first = min(r["seconds"] for r in rows[:WORKERS])
            inside = statistics.median(r["seconds"] for r in rows)
            print(f"{label:50s} {wall:7.2f} {len(clips) / wall:8.3f} {pool_wall / wall:8.2f} "
                  f"{first:13.2f}, {inside:6.2f}")
        print(f"scheduler overhead per task (warm cluster): {trip * 1e3:.1f} ms round trip of "
              f"one empty task; {bulk * 1e3:.2f} ms per task of 400 submitted at once")
        mean_clip = statistics.mean(r["seconds"] for r in next(iter(results.values()))[1])
        print(f"mean clip conversion (inside the job, pool run): {mean_clip:.2f} s; "
              f"the round trip is {100 * trip / mean_clip:.2f} % of it")
        print("BVHs of every executor byte-identical to the local pool's: yes")


if __name__ == "__main__":
    main()
