"""End-to-end speed of `vidcap convert` on a 300-frame 640x480 clip (issue 7 benchmark).

A walk is rendered with vidcap.synth (300 frames, 640x480, 30 fps) into a temporary
folder. Measured in the same run: decode only (PyAV, every frame), the background
plate estimation, and the conversion given that plate (silhouettes, 2D pose, 3D
lift, motion, BVH write; no cache), with its per-stage times, with the 2D fit on
vidcap's default number of processes (``--jobs``) and again on one (``jobs=1``).
A plate given as an image has no colour models, so the silhouettes' graph cut (on by
default) does not run there; the last row is the conversion as ``vidcap convert``
runs it by default, its estimated plate (with the colour models) already in the stage
cache: the cut runs, the plate's time is left out. Wall-clock times. Target: >= 100
fps excluding plate estimation.

``--ensemble N``: the 2D fit as N fits joined per joint (``vidcap convert --ensemble``).

Run:  python benchmarks/convert_speed.py [--frames 300] [--cues outline|all] [--ensemble N]
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vidcap.io.video import iter_frames  # noqa: E402
from vidcap.synth import synth_clip  # noqa: E402
from vidcap.video.background import estimate_background  # noqa: E402
from vidcap.video.fit.parallel import default_jobs  # noqa: E402
from vidcap.video.pipeline import convert  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--jobs", type=int, default=None,
                    help="fitting processes (default: vidcap's default, the usable CPUs)")
    ap.add_argument("--cues", default=None, choices=("outline", "all"),
                    help="the 2D fit's cues (default: vidcap convert's)")
    ap.add_argument("--ensemble", type=int, default=1, metavar="N",
                    help="fits joined per joint in the 2D fit (vidcap convert --ensemble; "
                    "default 1)")
    args = ap.parse_args(argv)
    fit_kw = {} if args.cues is None else {"cues": args.cues}
    if args.ensemble != 1:
        fit_kw["ensemble"] = args.ensemble
    import cv2

    from vidcap.synth import make_motion

    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        video = d / "walk.mp4"
        motion = make_motion("walk", n_frames=args.frames, rng=np.random.default_rng(0))
        synth_clip(video, d / "truth.npz", motion, size=(640, 480), yaw_deg=90.0,
                   rng=np.random.default_rng(0), show_progress=False)
        t0 = time.perf_counter()
        n = sum(1 for _ in iter_frames(video))
        t_decode = time.perf_counter() - t0
        t0 = time.perf_counter()
        plate = estimate_background(video, rng=np.random.default_rng(0), progress=False)
        t_plate = time.perf_counter() - t0
        cv2.imwrite(str(d / "plate.png"), plate.plate)
        (t_conv, cpu_conv), res = _timed(
            convert, video, d / "walk.bvh", background=d / "plate.png", cache_dir=None,
            progress=False, jobs=args.jobs, proportions="seed", **fit_kw)
        (t_serial, cpu_serial), serial = _timed(
            convert, video, d / "walk1.bvh", background=d / "plate.png", cache_dir=None,
            progress=False, jobs=1, proportions="seed", **fit_kw)
        cache_dir, cut_on = _cache_plate(video, d)
        (t_cut, cpu_cut), cut = _timed(convert, video, d / "walk2.bvh", cache_dir=cache_dir,
                                       progress=False, jobs=args.jobs, proportions="seed",
                                       **fit_kw)
    jobs = default_jobs() if args.jobs is None else args.jobs
    rows = [("decode only", t_decode, None), ("plate estimation", t_plate, None),
            (f"convert given the plate ({jobs} fitting processes)", t_conv, cpu_conv)]
    rows += [(f"  stage: {k}", v, None) for k, v in res.timings.items() if k != "plate"]
    rows += [("convert given the plate (1 process, jobs=1)", t_serial, cpu_serial)]
    rows += [(f"  stage: {k}", v, None) for k, v in serial.timings.items() if k != "plate"]
    rows += [(f"convert, estimated plate cached (graph cut: {cut_on})", t_cut, cpu_cut)]
    rows += [(f"  stage: {k}", v, None) for k, v in cut.timings.items() if k != "plate"]
    print(f"{n} frames, 640x480; --ensemble {args.ensemble}; load {os.getloadavg()[0]:.1f}")
    print("step | seconds | fps | x decode time | CPU s (all processes)")
    print("--- | --- | --- | --- | ---")
    for name, t, cpu in rows:
        print(f"{name} | {t:.2f} | {n / t:.0f} | {t / t_decode:.1f} | "
              + ("" if cpu is None else f"{cpu:.2f}"))
    print(f"\nconvert excluding plate estimation: {n / t_conv:.0f} fps with {jobs} fitting "
          f"processes, {n / t_serial:.0f} fps with one, {n / t_cut:.0f} fps on the estimated "
          f"plate (graph cut: {cut_on}; target >= 100)")
    d2 = np.linalg.norm(res.image_joints2d - serial.image_joints2d, axis=-1)
    j3, s3 = res.lifted.joints3d, serial.lifted.joints3d
    d3 = np.linalg.norm(j3 - s3, axis=-1)
    rel = np.linalg.norm((j3 - j3[:, :1]) - (s3 - s3[:, :1]), axis=-1)
    print(f"{jobs} processes vs 1 (the fit in chunks, the 3D solve in halves from 200 frames): "
          f"{np.mean(d2.max(1) > 1e-6):.0%} of frames differ in 2D; 2D joints median "
          f"{np.median(d2):.2f} px, max {d2.max():.1f} px; 3D joints median "
          f"{np.median(d3) * 1000:.1f} mm, root-relative {np.median(rel) * 1000:.1f} mm")


def _timed(fn, *args, **kw):
    """``((wall s, CPU s of this process and its finished children), fn(*args, **kw))``:
    on a shared machine the wall time swings with the others' load, the CPU time less."""
    def cpu():
        own, kids = (resource.getrusage(w) for w in (resource.RUSAGE_SELF,
                                                      resource.RUSAGE_CHILDREN))
        return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime

    c0, t0 = cpu(), time.perf_counter()
    out = fn(*args, **kw)
    return (time.perf_counter() - t0, cpu() - c0), out


def _cache_plate(video: Path, d: Path):
    """A stage cache holding the estimated plate only (as after a first ``vidcap
    convert`` that stopped after the plate), so that ``convert`` with default options
    runs without the plate's time: the cache folder and whether the cut runs."""
    from vidcap.video import pipeline
    from vidcap.video.annotations import Annotations
    from vidcap.video.stagecache import StageCache

    cache_dir = d / "cache"
    graph_cut, still, k_plate, _ = pipeline._stage_keys(video, None, Annotations(), None,
                                                        lambda m: None)
    pipeline._plate_stage(StageCache(cache_dir), k_plate, video, None, progress=False,
                          log=lambda m: None, colour_models=graph_cut, still_person=still)
    return cache_dir, graph_cut


if __name__ == "__main__":
    main()
