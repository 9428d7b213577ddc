"""The 2D fit on a person seated for seconds: the scale probe (vidcap.video.fit.lowbody).

    python benchmarks/pose2d_seated.py [--frames 90]

Renders of ``vidcap synth``'s ``sit`` motion (a figure seated on an unseen chair,
gesturing; 640x480, 30 fps, true silhouettes) seated throughout and standing for one
second before sitting down, side / three-quarter / front, fitted tracked on the outline
(``vidcap convert``'s default cues) with the probe (the default) and without it
(``fit_sequence(low_body=False)``, the reference, same run); the seed's body, as the
held-out renders. Per clip: PCK@0.05 and the
median error (fractions of the standing height from the camera's scale), the model's
height over the true standing height (median), and CPU ms per frame. Upright controls
(walk, jacks, arm raises) show the probe leaves a standing body's fit as it was.

Tuning: the seated clips with the motion's default draw (no ``rng``) at yaws 90, 45 and 0,
and the three controls, were looked at while the probe's constants were chosen. The rows
marked validation (other draws of the gestures' rates and phases, other yaws, a longer
stand before sitting) were not.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidcap.synth import make_motion, render_clip  # noqa: E402
from vidcap.video.fit.pose2d import fit_sequence  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from pose2d_accuracy import side_agnostic_errors, summarise  # noqa: E402


def clips(frames: int):
    """(name, use, motion, yaws)."""
    from vidcap.synth.procedural import sit_motion

    yield "seated", "tuning", sit_motion(n_frames=frames), (90, 45, 0)
    yield "stand, sit", "tuning", sit_motion(n_frames=2 * frames, stand_s=1.0), (90, 45, 0)
    for seed, yaws in ((5, (60, 20)), (6, (75, 135))):
        yield (f"seated rng {seed}", "validation",
               sit_motion(n_frames=frames, rng=np.random.default_rng(seed)), yaws)
    yield ("stand, sit rng 7", "validation",
           sit_motion(n_frames=2 * frames, stand_s=1.5, rng=np.random.default_rng(7)), (30, 110))
    for name in ("walk", "jacks", "arms"):
        yield (name, "control (tuning)",
               make_motion(name, n_frames=frames, rng=np.random.default_rng(1)), (90, 45, 0))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=90, help="frames of a seated clip (30 fps)")
    args = ap.parse_args(argv)
    print("Tracked 2D fit (outline) on seated renders, 640x480, true silhouettes: with the "
          "scale probe (default) / without it (reference, same run)")
    print(f"{'clip':18} {'use':17} {'yaw':>4}  {'PCK@0.05':>15}  {'median / H':>15}  "
          f"{'model / true H':>15}  {'CPU ms/frame':>13}")
    sums = {}
    for name, use, motion, yaws in clips(args.frames):
        for yaw in yaws:
            _, truth = render_clip(motion, yaw_deg=yaw, size=(640, 480), noise=0.0,
                                   rng=np.random.default_rng(0))
            masks, tj = truth["masks"], truth["joints2d"]
            # the standing height, px, from the camera's scale (the seed's body: head top
            # to ankles, the model's height)
            stature = 1.75 * np.linalg.norm(truth["camera"][0, :3])
            cells = []
            for low in (True, False):
                t0 = time.process_time()
                pose = fit_sequence(masks, cues="outline", low_body=low)
                ms = (time.process_time() - t0) / len(masks) * 1e3
                s = summarise(side_agnostic_errors(pose.joints2d, tj)[0] / stature)
                cells.append((s["pck05"], s["median"],
                              np.nanmedian(pose.model_height) / stature, ms))
            (p1, m1, h1, t1), (p0, m0, h0, t0_) = cells
            sums.setdefault(use, []).append((p1, p0))
            print(f"{name:18} {use:17} {yaw:>4g}  {p1:6.1%} / {p0:6.1%}  {m1:6.3f} / {m0:6.3f}  "
                  f"{h1:6.2f} / {h0:6.2f}  {t1:5.1f} / {t0_:5.1f}", flush=True)
    for use, rows in sums.items():
        r = np.asarray(rows)
        print(f"mean {use:21} PCK@0.05 {r[:, 0].mean():6.2%} with the probe, "
              f"{r[:, 1].mean():6.2%} without ({len(r)} clips)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
