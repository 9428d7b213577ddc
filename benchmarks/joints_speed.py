"""Speed: all joint centres of 07_01.c3d solved after loading (target <= 0.2 s).

Run: /work/venv/bin/python benchmarks/joints_speed.py
Reference measured in the same run: reading the C3D file (ezc3d).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

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
    print("target: solve_joints <= 0.2 s:", "PASS" if t_solve <= 0.2 else "FAIL")


if __name__ == "__main__":
    main()
