"""Ground-truth renderer: rendering speed and retargeting fidelity.

Run from the repository root:  python benchmarks/synth.py [--frames 60] [--size 640x480]

Prints two tables:
1. milliseconds per frame for drawing the body (z-buffered cylinders), the full frame
   (plus noise and lighting), and, as the reference measured in the same run, H.264
   encoding of the same frames with vidcap.io.video.VideoWriter;
2. for the real CMU motions in ../shared/data/motion/, the angle between each of our
   bones and the source's after retargeting (median and max over frames and segments,
   degrees) and the retargeting time per frame.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from vidcap.body import SEGMENT_JOINTS
from vidcap.io.video import VideoWriter
from vidcap.synth import (
    JOINT_MAPS,
    detect_joint_map,
    make_motion,
    prepare_clip,
    render_body,
    render_frame,
    retarget,
    source_joint_positions,
)

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "motion"


def _timed(fn, repeat=1):
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def speed(n_frames: int, size: tuple[int, int]) -> None:
    rng = np.random.default_rng(0)
    motion = make_motion("walk", n_frames=n_frames, rng=rng)
    clip = prepare_clip(motion, size=size, yaw_deg=60, noise=2.0, lighting_drift=0.05, rng=rng)
    t_body, _ = _timed(lambda: [render_body(clip.joints3d[i], clip.camera, clip.body,
                                            clip.background) for i in range(n_frames)], 3)
    t_full, frames = _timed(lambda: [render_frame(clip, i, rng)[0] for i in range(n_frames)], 3)
    with tempfile.TemporaryDirectory() as d:
        def encode():
            with VideoWriter(Path(d) / "x.mp4", 30.0) as w:
                for f in frames:
                    w.write(f)
        t_enc, _ = _timed(encode, 3)
    ref = t_enc / n_frames * 1e3
    print(f"\nRendering speed, {n_frames} frames of {size[0]}x{size[1]} (best of 3)")
    print(f"{'stage':<34}{'ms/frame':>10}{'x encode':>10}")
    rows = (("body (z-buffered cylinders)", t_body), ("full frame (+noise, lighting)", t_full),
            ("H.264 encode (reference)", t_enc))
    for name, t in rows:
        ms = t / n_frames * 1e3
        print(f"{name:<34}{ms:>10.2f}{ms / ref:>10.2f}")


def fidelity() -> None:
    from vidcap.io.asf import read_asf_amc
    from vidcap.io.bvh import read_bvh

    cases = []
    if (DATA / "131_01.bvh").exists():
        cases.append(("131_01.bvh", lambda: read_bvh(DATA / "131_01.bvh")))
    if (DATA / "07.asf").exists():
        cases.append(("07.asf+07_07.amc",
                      lambda: read_asf_amc(DATA / "07.asf", DATA / "07_07.amc")))
    if not cases:
        print("\n(no ../shared/data/motion: retargeting table skipped)")
        return
    print("\nRetargeting onto the 1.75 m body: angle between our bones and the source's (deg)")
    print(f"{'motion':<20}{'frames':>8}{'median':>10}{'max':>10}{'ms/frame':>10}")
    for name, load in cases:
        src = load()
        t, out = _timed(lambda src=src: retarget(src), 3)
        ours = out.positions()
        theirs = source_joint_positions(src, JOINT_MAPS[detect_joint_map(src.skeleton)])
        a = ours[:, SEGMENT_JOINTS[:, 1]] - ours[:, SEGMENT_JOINTS[:, 0]]
        b = theirs[:, SEGMENT_JOINTS[:, 1]] - theirs[:, SEGMENT_JOINTS[:, 0]]
        cos = np.sum(a * b, -1) / np.linalg.norm(a, axis=-1) / np.linalg.norm(b, axis=-1)
        ang = np.degrees(np.arccos(np.clip(cos, -1, 1)))
        print(f"{name:<20}{src.n_frames:>8}{np.median(ang):>10.4f}{ang.max():>10.4f}"
              f"{t / src.n_frames * 1e3:>10.3f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--size", default="640x480")
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    speed(args.frames, size)
    fidelity()


if __name__ == "__main__":
    main()
