"""How long one edit on the annotate page takes (the issue's target: < 100 ms).

"page edit": what the page waits for: the annotation event, resolving all events, re-solving
the frames the edit reaches (the clip solve, ``vidcap.video.solve.local``; with ``--lift
segment`` re-lifting the clip with the current proposals), the atomic save. "full 3D
stage": what the page then runs in a worker thread and redraws (``vidcap.video.lifting.lift_pose``:
the proposals with the user's signs as constraints and the whole clip's solve), measured
once per clip length.

Run from the repository root: ``python benchmarks/annotate_edit.py [--lift=segment]``. Uses
the sample clip's ground truth as stage results, tiled to longer clips; prints a table whose
reference is the bare per-segment lift of the whole clip measured in the same run.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "tests" / "ui")]

from clips import truth_clip  # noqa: E402
from vidcap.ui.session import AnnotateSession, ClipData  # noqa: E402

from vidcap.video.lift import lift  # noqa: E402

TARGET_MS = 100.0


def tiled(clip: ClipData, reps: int) -> ClipData:
    return ClipData(video=clip.video, fps=clip.fps, read_frame=clip.read_frame,
                    joints2d=np.tile(clip.joints2d, (reps, 1, 1)), masks=None,
                    fit_score=np.tile(clip.fit_score, reps), image_sides=clip.image_sides,
                    size=clip.size)


def main() -> None:
    lift_method = "segment" if "--lift=segment" in sys.argv[1:] else "solve"
    base = truth_clip("walk_side")
    print(f"lift: {lift_method}")
    print(f"{'frames':>7} {'page edit ms':>13} {'CPU ms':>7} {'max/target':>11}"
          f" {'full 3D stage ms':>17} {'lift-only ms':>13} {'page edit/lift':>15}")
    for reps in (1, 5, 20, 50):
        clip = tiled(base, reps)
        F = clip.n_frames
        frames = np.linspace(0, F - 1, 12).astype(int)
        with tempfile.TemporaryDirectory() as tmp:
            s = AnnotateSession(clip, Path(tmp) / "a.json", defer_refresh=True,
                                lift=lift_method)
            times, cpu = [], []
            for n, f in enumerate(frames):  # the page answers each edit at once
                c0 = time.process_time()
                times.append(s.set_depth(int(f), "l_lower_arm", 1 if n % 2 else -1))
                cpu.append((time.process_time() - c0) * 1000)
            t0 = time.perf_counter()
            s.refresh()  # then the worker's full stage, once
            full = [(time.perf_counter() - t0) * 1000]
        t0 = time.perf_counter()
        for _ in range(5):
            lift(s.joints2d, s.signs, s.yaw, scale=s.scale)
        lift_ms = (time.perf_counter() - t0) / 5 * 1000
        med, mx = float(np.median(times)), float(np.max(times))
        print(f"{F:>7} {med:>13.1f} {np.median(cpu):>7.1f} {mx / TARGET_MS:>11.2f}"
              f" {np.median(full):>17.1f} {lift_ms:>13.2f} {med / lift_ms:>15.1f}")


if __name__ == "__main__":
    main()
