"""What the cues inside the outline cost `vidcap convert`, in CPU time (issue 27).

A 300-frame 640x480 side-view walk is rendered with vidcap.synth and its plate estimated
once (a temporary folder). Then ``convert`` given that plate (no cache, the seed's body,
as ``convert_speed.py``) runs in a child process for each of ``--cues outline`` and
``--cues all``, on vidcap's default processes (2 here) and on one (``jobs=1``), for this
checkout and, with ``--ref TREE``, for another checkout in the same run (interleaved,
``--repeat`` times; the least is printed, so a first run's kernel compilation is left
out). CPU time is the child's and its workers' (``RUSAGE_CHILDREN``), including the
interpreter's start and the kernels' load (the same in every row), so it holds on a
shared machine where wall time does not. Printed:
CPU seconds, the ratio all / outline per tree and jobs, and how many frames' 2D joints
the chunked fit (2 processes) and the serial one (``jobs=1``) give differently.

Run:  python benchmarks/cues_speed.py [--ref TREE] [--repeat 3] [--frames 300]
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _child(d: Path, cues: str, jobs: int, tag: str) -> None:
    """One convert (in a child process, vidcap from PYTHONPATH): its 2D joints saved."""
    from vidcap.video.pipeline import convert

    res = convert(d / "walk.mp4", d / f"{tag}.bvh", background=d / "plate.png", cache_dir=None,
                  progress=False, jobs=jobs, proportions="seed", cues=cues)
    np.save(d / f"{tag}.npy", res.image_joints2d)


def _render(d: Path, frames: int) -> None:
    import cv2

    sys.path.insert(0, str(ROOT))
    from vidcap.synth import make_motion, synth_clip
    from vidcap.video.background import estimate_background

    motion = make_motion("walk", n_frames=frames, rng=np.random.default_rng(0))
    synth_clip(d / "walk.mp4", d / "truth.npz", motion, size=(640, 480), yaw_deg=90.0,
               rng=np.random.default_rng(0), show_progress=False)
    plate = estimate_background(d / "walk.mp4", rng=np.random.default_rng(0), progress=False)
    cv2.imwrite(str(d / "plate.png"), plate.plate)


def _run(tree: Path, d: Path, cues: str, jobs: int, tag: str) -> float:
    """CPU seconds of one child convert (its workers included)."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child", str(d), cues,
                    str(jobs), tag],
                   env=env, check=True, cwd=tree)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ref", type=Path, default=None, help="another checkout, same run")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--frames", type=int, default=300)
    args = ap.parse_args(argv)
    trees = [("this", ROOT)] + ([("ref", args.ref.resolve())] if args.ref else [])
    cpu: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        _render(d, args.frames)
        for _ in range(args.repeat):
            for jobs in (2, 1):
                for cues in ("outline", "all"):
                    for name, tree in trees:
                        tag = f"{name}_{cues}_{jobs}"
                        cpu.setdefault(tag, []).append(_run(tree, d, cues, jobs, tag))
        differ = {}
        for name, _ in trees:
            for cues in ("outline", "all"):
                a, b = (np.load(d / f"{name}_{cues}_{j}.npy") for j in (2, 1))
                gap = np.abs(a - b)
                gap[np.isnan(a) & np.isnan(b)] = 0.0  # no fit in either
                gap = np.nan_to_num(gap, nan=np.inf)
                differ[name, cues] = float(np.mean(gap.max(axis=(1, 2)) > 1e-6))
    print(f"vidcap convert, {args.frames} frames 640x480 given the plate: CPU seconds "
          f"(least of {args.repeat}, child process and its workers)")
    print("every run:", {k: [round(x, 2) for x in v] for k, v in cpu.items()})
    print("tree | jobs | outline | all | all / outline | chunked vs serial frames differ "
          "(outline / all)")
    print("--- | --- | --- | --- | --- | ---")
    for name, tree in trees:
        for jobs in (2, 1):
            o = float(np.min(cpu[f"{name}_outline_{jobs}"]))
            a = float(np.min(cpu[f"{name}_all_{jobs}"]))
            dif = (f"{differ[name, 'outline']:.0%} / {differ[name, 'all']:.0%}"
                   if jobs == 2 else "")
            print(f"{name} ({tree}) | {jobs} | {o:.2f} | {a:.2f} | {a / o:.2f} | {dif}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        _child(Path(sys.argv[2]), sys.argv[3], int(sys.argv[4]), sys.argv[5])
        raise SystemExit(0)
    raise SystemExit(main())
