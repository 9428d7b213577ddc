"""Speed of the clip solve (issue 33): frames per CPU-second of ``vidcap.video.solve``'s banded
Levenberg-Marquardt, against ``scipy.optimize.least_squares`` ('trf', ``jac_sparsity``,
``x_scale='jac'``) on the same residuals from the same warm start, at equal accuracy
(PA-MPJPE of the result), and a BLAS reference measured in the same run (on a shared
machine wall time waits for the cores: CPU time, one thread, is the figure to compare).

Clip: the built-in walk at yaw 45, true 2D plus 2 % noise, true signs as the prior; the
continuous solve to convergence (what the two optimisers share), and the whole solve as
``vidcap convert`` runs it (first LM, sign sweeps and re-solves, outlier repair).

Run:  python benchmarks/solve_speed.py [--frames 300] [--lsq-frames 100]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]

from lift_accuracy import truth_in_camera_frame  # noqa: E402
from lift_solve_tables import pa_mpjpe_mm  # noqa: E402

from vidcap.body import BodyModel  # noqa: E402
from vidcap.synth import make_motion, prepare_clip, truth_arrays  # noqa: E402
from vidcap.video.lift import estimate_scale  # noqa: E402
from vidcap.video.solve.clip import (  # noqa: E402
    FITTED_HEADING_WEIGHT,
    FITTED_SIGN_WEIGHT,
    make_problem,
    solve_problem,
    warm_start,
)
from vidcap.video.solve.gauss_newton import levenberg_marquardt  # noqa: E402
from vidcap.video.solve.residuals import residuals, sparsity  # noqa: E402
from vidcap.video.solve.skeleton import forward_kinematics  # noqa: E402
from vidcap.video.solve.stage import ROBUST_FITTED  # noqa: E402


def _clip(body, frames):
    m = make_motion("walk", body=body, fps=30.0, n_frames=frames, rng=np.random.default_rng(0))
    clip = prepare_clip(m, body=body, yaw_deg=45.0, rng=np.random.default_rng(1))
    t = truth_arrays(clip, np.zeros((m.n_frames, 1, 1), bool))
    s = estimate_scale(t["joints2d"], body)
    j2 = t["joints2d"] + np.random.default_rng(3).normal(0, 0.02 * body.height * s,
                                                         t["joints2d"].shape)
    pb = make_problem(j2, scale=s, fps=30.0, body=body, yaw=np.deg2rad(t["yaw_deg"]),
                      prior_signs=t["depth_signs"])
    return pb, warm_start(pb, j2, scale=s, body=body), truth_in_camera_frame(t)


def _timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def main(argv=None) -> int:
    from scipy.optimize import least_squares
    from threadpoolctl import threadpool_limits

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--lsq-frames", type=int, default=100)
    args = ap.parse_args(argv)
    body = BodyModel()
    print("solver | frames | CPU s | wall s | frames per CPU-s | PA-MPJPE mm | cost")
    print("--- | --- | --- | --- | --- | --- | ---")
    for frames in sorted({args.lsq_frames, args.frames}):
        pb, p0, true3 = _clip(body, frames)
        with threadpool_limits(1):
            sol, wall, cpu = _timed(lambda pb=pb, p0=p0: levenberg_marquardt(pb, p0, max_iter=30))
        joints, _, _ = forward_kinematics(sol.params, pb.offsets)
        print(f"banded LM (vidcap.video.solve), to convergence | {frames} | {cpu:.2f} | "
              f"{wall:.2f} | {frames / cpu:.0f} | {pa_mpjpe_mm(joints, true3):.0f} | "
              f"{sol.cost:.1f}")
        whole, wall, cpu = _timed(lambda pb=pb, p0=p0: solve_problem(pb, p0))
        print(f"the whole solve (LM, sign sweeps, re-solves, repair) | {frames} | {cpu:.2f} | "
              f"{wall:.2f} | {frames / cpu:.0f} | {pa_mpjpe_mm(whole.joints3d, true3):.0f} | "
              f"{whole.cost:.1f}")
        for label, kw in (("the whole solve as the 3D stage runs it (robust, sign weight 1, "
                           "heading)",
                           dict(robust=ROBUST_FITTED)),
                          ("the same with the limbs' names chosen (labels=True)",
                           dict(robust=ROBUST_FITTED, labels=True))):
            stage_pb = replace(pb, sign_weight=FITTED_SIGN_WEIGHT,
                               heading_weight=FITTED_HEADING_WEIGHT)
            whole, wall, cpu = _timed(lambda pb=stage_pb, p0=p0, kw=kw: solve_problem(pb, p0, **kw))
            print(f"{label} | {frames} | {cpu:.2f} | {wall:.2f} | {frames / cpu:.0f} | "
                  f"{pa_mpjpe_mm(whole.joints3d, true3):.0f} | {whole.cost:.1f}")
        if frames != args.lsq_frames:
            continue
        jac = sparsity(pb)

        def fun(x, pb=pb, frames=frames):
            return residuals(pb, x.reshape(frames, -1))

        with threadpool_limits(1):
            res, wall, cpu = _timed(lambda fun=fun, p0=p0, jac=jac: least_squares(
                fun, p0.ravel(), jac_sparsity=jac, method="trf", x_scale="jac",
                tr_solver="lsmr", ftol=1e-4, max_nfev=200))
        joints, _, _ = forward_kinematics(res.x.reshape(frames, -1), pb.offsets)
        print(f"least_squares trf + jac_sparsity | {frames} | {cpu:.2f} | {wall:.2f} | "
              f"{frames / cpu:.0f} | {pa_mpjpe_mm(joints, true3):.0f} | {res.cost:.1f}")
    a = np.random.default_rng(0).random((400, 400))
    _, wall, cpu = _timed(lambda: [a @ a for _ in range(20)])
    print(f"\nreference, 20 products of 400 x 400 matrices: CPU {cpu:.3f} s, wall {wall:.3f} s "
          f"(wall / CPU {wall / cpu:.1f}: how much the machine's other jobs slow this run)")
    print("target: >= 200 frames per second on 2 cores (300 frames <= 1.5 s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
