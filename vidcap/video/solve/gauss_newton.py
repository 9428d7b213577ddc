"""Levenberg-Marquardt on the clip's banded normal equations.

The Jacobian (:func:`vidcap.video.solve.residuals.linearise`) couples a frame's
parameters with those of the two frames either side (second differences), so
``J^T J`` is block-pentadiagonal in frame order: it is assembled here block by block
from the per-frame Jacobians (never as a sparse product), a band of half-width
3 * 24 - 1, solved by LAPACK's banded Cholesky (:mod:`vidcap.video.solve.blocksolve`),
linear in the clip's length.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vidcap.video.solve.blocksolve import lower_band, solve_band
from vidcap.video.solve.residuals import (
    Linearisation,
    Problem,
    contact_pairs,
    heading_rows,
    linearise,
    residuals,
)
from vidcap.video.solve.skeleton import N_PARAMS

P = N_PARAMS


@dataclass(frozen=True)
class Solution:
    """Result of :func:`levenberg_marquardt`: params (F, 24), cost, iterations."""

    params: np.ndarray
    cost: float
    iterations: int


def normal_equations(problem: Problem, lin: Linearisation):
    """Blocks of J^T J and J^T r.

    The second differences and the planted ankles' motion are sums of the joints'
    rows with fixed coefficients, so their part of block (f, f + s) is
    ``joints_f^T diag(d_s[f]) joints_{f+s}`` with one weight per joint coordinate
    (``d_s``, gathered first): one product per block diagonal.

    Returns
    -------
    blocks : (3, F, 24, 24) the blocks (f, f), (f, f + 1), (f, f + 2) (zero past the end).
    grad : (F, 24).
    """
    pb = problem
    ju, jp = lin.unary, lin.joints
    F, U, _ = ju.shape
    blocks = np.zeros((3, F, P, P))
    jut = np.swapaxes(ju, 1, 2)
    jpt = np.swapaxes(jp, 1, 2)
    grad = (jut @ lin.r[:F * U].reshape(F, U, 1))[..., 0]
    at = F * U
    d0 = np.zeros((F, 45))  # weights of joints_f^T joints_f, per coordinate
    d1 = np.zeros((F, 45))  # of joints_f^T joints_{f+1}
    q = np.zeros((F, 45))  # d(residuals)/d(joints_f)^T r
    if F > 2:
        w2 = pb.acc_weight ** 2
        d0[:-2] += w2  # the [1, -2, 1] weights' squares each frame takes part with
        d0[1:-1] += 4.0 * w2
        d0[2:] += w2
        d1[:-2] -= 2.0 * w2  # residual centred at f + 1: (f, f+1) weights 1 * -2
        d1[1:-1] -= 2.0 * w2  # centred at f: -2 * 1
        blocks[2, :-2] = w2 * (jpt[:-2] @ jp[2:])
        s = pb.acc_weight * lin.r[at:at + (F - 2) * 45].reshape(F - 2, 45)
        q[:-2] += s
        q[1:-1] -= 2.0 * s
        q[2:] += s
        at += (F - 2) * 45
    f, ank = contact_pairs(pb.contact)
    if f.size:
        w2 = pb.contact_weight ** 2
        coord = 3 * ank[:, None] + np.arange(3)
        s = pb.contact_weight * lin.r[at:at + 3 * f.size].reshape(-1, 3)
        # (frame, coordinate) pairs are distinct within each line (one pair per frame
        # and ankle): plain indexed adds
        d0[f[:, None], coord] += w2
        d0[f[:, None] - 1, coord] += w2
        d1[f[:, None] - 1, coord] -= w2
        q[f[:, None], coord] += s
        q[f[:, None] - 1, coord] -= s
        at += 3 * f.size
    blocks[0] = jut @ ju + jpt @ (d0[..., None] * jp)
    blocks[1, :-1] = jpt[:-1] @ (d1[:-1, :, None] * jp[1:])
    grad += (jpt @ q[..., None])[..., 0]
    hf, across = heading_rows(pb)
    if hf.size:  # one row per frame f >= 1: across . (pelvis_f - pelvis_{f-1})
        a = pb.heading_weight * np.einsum("nc,nci->ni", across, jp[hf, :3])
        b = pb.heading_weight * np.einsum("nc,nci->ni", across, jp[hf - 1, :3])
        s = lin.r[at:at + hf.size]
        blocks[0, hf] += a[:, :, None] * a[:, None, :]
        blocks[0, hf - 1] += b[:, :, None] * b[:, None, :]
        blocks[1, hf - 1] -= b[:, :, None] * a[:, None, :]
        grad[hf] += a * s[:, None]
        grad[hf - 1] -= b * s[:, None]
    return blocks, grad


def levenberg_marquardt(problem: Problem, params, *, max_iter: int = 30, rtol: float = 1e-3,
                        damping: float = 1e-3, fixed=None) -> Solution:
    """Minimise the clip's residuals from ``params`` (F, 24).

    Parameters
    ----------
    problem : Problem
    params : array_like, shape (F, 24)
        The start (a warm one: the per-segment lift's pose).
    max_iter : int
    rtol : float
        Stop when a step lowers the cost by less than this fraction.
    damping : float
        Initial Marquardt damping, relative to the normal matrix's diagonal.
    fixed : array_like of bool, shape (F,), optional
        Frames whose parameters are held (the boundary of a local re-solve).

    Returns
    -------
    Solution
    """
    p = np.array(params, dtype=float)
    F = p.shape[0]
    hold = np.zeros(F, bool) if fixed is None else np.asarray(fixed, bool)
    pin = np.repeat(np.where(hold, 1e12, 0.0), P)
    lin = linearise(problem, p)
    c = 0.5 * float(lin.r @ lin.r)
    mu = damping
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007 - the count is reported
        blocks, grad = normal_equations(problem, lin)
        g = grad.reshape(-1)
        g[pin > 0] = 0.0
        ab = lower_band(blocks)
        diag = ab[0].copy()  # (F P,) the normal matrix's diagonal
        improved = False
        for _ in range(8):
            ab[0] = diag + mu * (diag + 1e-6) + pin
            step = solve_band(ab, -g)
            if step is None:  # not positive definite: damp more
                mu *= 10.0
                continue
            trial = p + step.reshape(F, P)
            r_new = residuals(problem, trial)
            c_new = 0.5 * float(r_new @ r_new)
            if c_new < c:
                improved = True
                break
            mu *= 5.0
        if not improved:
            break
        done = c - c_new < rtol * c
        p, c = trial, c_new
        mu = max(mu / 3.0, 1e-9)
        if done:
            break
        lin = linearise(problem, p, r=r_new, unary_rows=lin.unary.shape[1])
    return Solution(p, c, it)
