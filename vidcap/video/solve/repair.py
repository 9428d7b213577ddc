"""Frames the clip solve left in a wrong basin, solved again from their neighbours.

Levenberg-Marquardt from the per-segment lift can settle a short run of frames in a
pose the 2D joints do not fit (a turn under heavy 2D noise: limbs crossed the wrong
way, the projection residual 20x the clip's typical frame) that no single sign
reflection leaves. Such runs are found by their per-frame cost (projection, limits,
priors and the smoothness centred on the frame); each is re-started from the
interpolation between the good frames either side and solved again on a window
around it, its edges held (:func:`vidcap.video.solve.gauss_newton.levenberg_marquardt`),
and kept where the window's cost drops.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_dilation

from vidcap.video.solve.gauss_newton import levenberg_marquardt
from vidcap.video.solve.residuals import Problem, temporal, unary

#: A frame is an outlier above this many times the clip's median frame cost, and above
#: :data:`OUTLIER_MIN` (one joint 10 sigmas off: a clip fitted to within its noise has
#: no outlier, however small its median).
OUTLIER_FACTOR = 8.0
OUTLIER_MIN = 50.0
#: Frames solved again either side of an outlier run (2 of them held).
PAD = 6


def frame_costs(problem: Problem, params) -> np.ndarray:
    """Cost of each frame (F,): half its unary residuals squared plus half the
    smoothness residuals squared centred on it."""
    res, joints = unary(problem, params)
    cost = 0.5 * np.sum(res * res, axis=-1)
    F = len(cost)
    if F > 2:
        acc = temporal(problem, joints)[:(F - 2) * 45].reshape(F - 2, 45)
        cost[1:-1] += 0.5 * np.sum(acc * acc, axis=-1)
    return cost


def _runs(mask) -> list[tuple[int, int]]:
    idx = np.flatnonzero(np.diff(np.r_[0, mask.astype(int), 0]))
    return list(zip(idx[::2], idx[1::2], strict=True))


def repair_outliers(problem: Problem, params, *, fixed=None, max_iter: int = 8
                    ) -> tuple[np.ndarray, int]:
    """``params`` (F, 24) with its outlier runs re-solved where that lowers the cost.

    Returns the parameters and how many runs were replaced.
    """
    p = np.array(params, dtype=float)
    F = len(p)
    cost = frame_costs(problem, p)
    bad = cost > max(OUTLIER_FACTOR * float(np.median(cost)), OUTLIER_MIN)
    if fixed is not None:
        bad &= ~np.asarray(fixed, bool)
    if not bad.any() or bad.mean() > 0.5:
        return p, 0
    kept = 0
    for a, b in _runs(binary_dilation(bad, iterations=1)):
        lo, hi = max(0, a - PAD), min(F, b + PAD)
        sub = problem.frames(lo, hi)
        q = p[lo:hi].copy()
        t = np.arange(a, b)
        left, right = (a - 1 if a > 0 else b), (b if b < F else a - 1)
        if left < 0 or right >= F:
            continue
        w = ((t - left) / max(right - left, 1))[:, None] if right != left else np.zeros((b - a, 1))
        q[a - lo:b - lo] = (1 - w) * p[left] + w * p[right]
        hold = np.zeros(hi - lo, bool)
        hold[:2 if lo > 0 else 0] = True
        if hi < F:
            hold[-2:] = True
        before = float(np.sum(frame_costs(sub, p[lo:hi])))
        sol = levenberg_marquardt(sub, q, max_iter=max_iter, fixed=hold)
        if float(np.sum(frame_costs(sub, sol.params))) < before:
            p[lo:hi] = sol.params
            kept += 1
    return p, kept
