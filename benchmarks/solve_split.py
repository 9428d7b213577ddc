"""The clip solve in one process against two halves on two processes (issue 33, speed).

Long renders of CMU motions (the iClone HumanIK conversions under
``$VIDCAP_DATA/mocap/cmu_iclone_humanik/``, benchmarks/DATA.md; 640x480 at 30 fps,
one yaw each) go through ``vidcap convert`` once (``jobs=1``); the 3D stage's clip
problem is then solved both ways from the same start: in this process
(:func:`vidcap.video.solve.clip.solve_problem`, ``jobs=1``) and in two halves at once
(``jobs=2``, :mod:`vidcap.video.solve.split`). Columns: PA-MPJPE of each against the
render's truth (mm, 12 limb joints), how far apart the two are relative to the pelvis,
and wall-clock seconds of each solve (best of ``--repeat``; on an idle 2-core machine the
halves run side by side).

Run:  VIDCAP_DATA=/path python benchmarks/solve_split.py [--clips 002_08:60,005_04:90] [--repeat 2]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

#: (trial, yaw in degrees): none of them tuned on (the split's constants were set
#: before any was run).
CLIPS = ("002_08:60", "005_04:90", "006_11:45", "001_14:120", "005_17:30", "005_10:135")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--clips", default=",".join(CLIPS), help="TRIAL:YAW,... (default: %(default)s)")
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args(argv)
    data = Path(os.environ.get("VIDCAP_DATA", "/nonexistent")) / "mocap" / "cmu_iclone_humanik"
    if not data.is_dir():
        print(f"skipped: needs {data} (VIDCAP_DATA; benchmarks/get_data.sh)")
        return
    print("clip | frames | PA-MPJPE one process mm | two halves mm | apart, pelvis-relative "
          "median mm | one process s | two halves s")
    print("--- | --- | --- | --- | --- | --- | ---")
    sums = np.zeros(4)
    with tempfile.TemporaryDirectory() as tmp:
        for spec in args.clips.split(","):
            trial, yaw = spec.split(":")
            row = _row(data / f"{trial}_humanik.bvh", float(yaw), Path(tmp), args.repeat)
            sums += [row[1], row[2], row[4], row[5]]
            print(f"{trial} yaw {yaw} | {row[0]} | {row[1]:.1f} | {row[2]:.1f} | {row[3]:.1f} | "
                  f"{row[4]:.2f} | {row[5]:.2f}")
    n = len(args.clips.split(","))
    print(f"mean | | {sums[0] / n:.1f} | {sums[1] / n:.1f} | | {sums[2] / n:.2f} | "
          f"{sums[3] / n:.2f}")


def _row(bvh: Path, yaw: float, tmp: Path, repeat: int):
    from lift_accuracy import truth_in_camera_frame
    from lift_solve_tables import pa_mpjpe_mm

    import vidcap.video.solve.clip as clip
    from vidcap.synth import make_motion, synth_clip
    from vidcap.video.pipeline import convert

    video, truth = tmp / f"{bvh.stem}.mp4", tmp / f"{bvh.stem}.npz"
    motion = make_motion(bvh, fps=30.0, frame_range=(0, 2400))
    synth_clip(video, truth, motion, size=(640, 480), yaw_deg=yaw,
               rng=np.random.default_rng(0), show_progress=False)
    true3 = truth_in_camera_frame(dict(np.load(truth)))
    seen = {}
    solve = clip.solve_problem

    def keep(problem, params, **kw):  # the 3D stage's problem, as convert builds it
        seen.update(problem=problem, params=params, kw=kw)
        return solve(problem, params, **kw)

    clip.solve_problem = keep
    try:
        convert(video, tmp / "out.bvh", cache_dir=None, progress=False, jobs=1)
    finally:
        clip.solve_problem = solve
    kw = {k: v for k, v in seen["kw"].items() if k != "jobs"}
    out, secs = {}, {}
    for jobs in (1, 2):
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            out[jobs] = solve(seen["problem"], seen["params"], jobs=jobs, **kw)
            best = min(best, time.perf_counter() - t0)
        secs[jobs] = best
    n = min(len(true3), len(out[1].joints3d))
    a, b = out[1].joints3d[:n], out[2].joints3d[:n]
    apart = np.linalg.norm((a - a[:, :1]) - (b - b[:, :1]), axis=-1)
    return (n, pa_mpjpe_mm(a, true3[:n]), pa_mpjpe_mm(b, true3[:n]),
            float(np.median(apart) * 1e3), secs[1], secs[2])


if __name__ == "__main__":
    main()
