"""Speed: all joint centres of a 41-marker trial solved after loading (target: 3,000
frames <= 0.2 s, issue 32; 07_01.c3d's 316 frames, issue 4).

Run: python benchmarks/joints_speed.py
The 3,000-frame trial is 07_01.c3d played forward, backward, forward... (continuous
motion, the same markers and gaps). Reference measured in the same run: reading the
C3D file (ezc3d), and one batched 3x3 SVD over the 3,000 frames (the Kabsch step's
kernel, which every segment frame needs at least once).
"""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidcap.mocap.c3d import read_c3d  # noqa: E402
from vidcap.mocap.skeleton import solution_to_motion, solve_joints  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "c3d"


def best(fn, repeat=7):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main() -> None:
    path = DATA / "07_01.c3d"
    t_load, data = best(lambda: read_c3d(path))
    t_solve, sol = best(lambda: solve_joints(data))
    t_bvh, _ = best(lambda: solution_to_motion(sol))
    F, J = sol.positions.shape[:2]
    print(f"07_01.c3d: {F} frames, {len(data.labels)} markers, {J} joints "
          f"({sum(r.kind not in ('root', 'end') for r in sol.reports)} fitted)")
    print(f"{'step':28s} {'seconds':>9s} {'x load':>7s} {'x target':>8s}")
    for name, t in [("read_c3d (reference)", t_load), ("solve_joints (all joints)", t_solve),
                    ("solution_to_motion", t_bvh)]:
        print(f"{name:28s} {t:9.4f} {t / t_load:7.2f} {t / 0.2:8.2f}")
    print("target: solve_joints (316 frames) <= 0.2 s:", "PASS" if t_solve <= 0.2 else "FAIL")
    reps = -(-3000 // data.n_frames)
    pos = np.concatenate([data.positions if k % 2 == 0 else data.positions[::-1]
                          for k in range(reps)])[:3000]
    big = dataclasses.replace(data, positions=np.ascontiguousarray(pos))
    mats = np.random.default_rng(0).normal(size=(3000, 3, 3))
    t_svd, _ = best(lambda: np.linalg.svd(mats))
    t_big, _ = best(lambda: solve_joints(big), repeat=5)
    print(f"\n3,000 frames ({len(big.labels)} markers):")
    print(f"{'step':28s} {'seconds':>9s} {'x svd':>7s} {'x target':>8s}")
    for name, t in [("svd of 3000 3x3 (reference)", t_svd), ("solve_joints (all joints)", t_big)]:
        print(f"{name:28s} {t:9.4f} {t / t_svd:7.1f} {t / 0.2:8.2f}")
    print("target: 3,000 frames <= 0.2 s:", "PASS" if t_big <= 0.2 else "FAIL")


if __name__ == "__main__":
    main()
