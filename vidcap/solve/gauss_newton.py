"""Levenberg-Marquardt on the clip's banded normal equations.

The Jacobian (:func:`vidcap.solve.residuals.linearise`) couples a frame's
parameters with those of the two frames either side (second differences), so
``J^T J`` is block-pentadiagonal in frame order: it is assembled here block by block
from the per-frame Jacobians (never as a sparse product) into the band of half-width
3 * 24 - 1, factored by a compiled banded Cholesky (:mod:`vidcap.solve._banded`),
linear in the clip's length.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vidcap.solve._banded import banded_cholesky_solve
from vidcap.solve.residuals import Linearisation, Problem, contact_pairs, linearise, residuals
from vidcap.solve.skeleton import N_PARAMS

P = N_PARAMS
_HALF_BAND = 3 * P - 1


@dataclass(frozen=True)
class Solution:
    """Result of :func:`levenberg_marquardt`: params (F, 24), cost, iterations."""

    params: np.ndarray
    cost: float
    iterations: int


def normal_equations(problem: Problem, lin: Linearisation):
    """Blocks of J^T J and J^T r.

    Returns
    -------
    blocks : (3, F, 24, 24) the blocks (f, f), (f, f + 1), (f, f + 2) (zero past the end).
    grad : (F, 24).
    """
    pb = problem
    ju, jp = lin.unary, lin.joints
    F, U, _ = ju.shape
    blocks = np.zeros((3, F, P, P))
    blocks[0] = np.einsum("fui,fuj->fij", ju, ju)
    grad = np.einsum("fui,fu->fi", ju, lin.r[:F * U].reshape(F, U))
    at = F * U
    if F > 2:
        w2 = pb.acc_weight ** 2
        g0 = np.einsum("fci,fcj->fij", jp, jp)
        coef = np.zeros(F)  # sum of squared [1, -2, 1] weights each frame takes part with
        coef[:-2] += 1.0
        coef[1:-1] += 4.0
        coef[2:] += 1.0
        blocks[0] += w2 * coef[:, None, None] * g0
        g1 = np.einsum("fci,fcj->fij", jp[:-1], jp[1:])  # (F-1)
        c1 = np.zeros(F - 1)
        c1[:-1] += -2.0  # residual centred at f + 1: (f, f+1) weights 1 * -2
        c1[1:] += -2.0  # centred at f: -2 * 1
        blocks[1, :-1] += w2 * c1[:, None, None] * g1
        blocks[2, :-2] += w2 * np.einsum("fci,fcj->fij", jp[:-2], jp[2:])
        s = lin.r[at:at + (F - 2) * 45].reshape(F - 2, 45)
        q = np.zeros((F, 45))
        q[:-2] += s
        q[1:-1] -= 2.0 * s
        q[2:] += s
        grad += pb.acc_weight * np.einsum("fci,fc->fi", jp, q)
        at += (F - 2) * 45
    f, ank = contact_pairs(pb.contact)
    if f.size:
        w2 = pb.contact_weight ** 2
        coord = 3 * ank[:, None] + np.arange(3)
        a = jp[f[:, None], coord]  # (n, 3, 24) at f
        b = jp[(f - 1)[:, None], coord]  # at f - 1
        np.add.at(blocks[0], f, w2 * np.einsum("nci,ncj->nij", a, a))
        np.add.at(blocks[0], f - 1, w2 * np.einsum("nci,ncj->nij", b, b))
        np.add.at(blocks[1], f - 1, -w2 * np.einsum("nci,ncj->nij", b, a))
        s = lin.r[at:at + 3 * f.size].reshape(-1, 3)
        np.add.at(grad, f, pb.contact_weight * np.einsum("nci,nc->ni", a, s))
        np.add.at(grad, f - 1, -pb.contact_weight * np.einsum("nci,nc->ni", b, s))
    return blocks, grad


def _band(blocks) -> np.ndarray:
    """The upper band (72, F * 24) of the block matrix: ``ab[u + i - j, j] = H[i, j]``."""
    F = blocks.shape[1]
    n = F * P
    ab = np.zeros((_HALF_BAND + 1, n))
    a = np.arange(P)[:, None]
    b = np.arange(P)[None, :]
    for d in range(3):
        rows = _HALF_BAND + a - b - P * d  # (24, 24)
        keep = (rows >= 0) & (rows <= _HALF_BAND)
        fr = np.arange(F - d)
        cols = (fr[:, None, None] + d) * P + b  # (F-d, 1, 24) column j
        vals = blocks[d, :F - d]
        rr = np.broadcast_to(rows, vals.shape)[:, keep]
        cc = np.broadcast_to(cols, vals.shape)[:, keep]
        ab[rr, cc] = vals[:, keep]
    return ab


def levenberg_marquardt(problem: Problem, params, *, max_iter: int = 30, rtol: float = 1e-4,
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
    hold = np.repeat(np.zeros(F, bool) if fixed is None else np.asarray(fixed, bool), P)
    lin = linearise(problem, p)
    c = 0.5 * float(lin.r @ lin.r)
    mu = damping
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007 - the count is reported
        blocks, grad = normal_equations(problem, lin)
        g = grad.ravel()
        g[hold] = 0.0
        ab = _band(blocks)
        diag = ab[-1].copy()
        improved = False
        for _ in range(8):
            ab[-1] = diag + mu * (diag + 1e-6) + np.where(hold, 1e12, 0.0)
            step = banded_cholesky_solve(np.ascontiguousarray(ab[::-1].T), -g)
            if step.size == 0:  # not positive definite: damp more
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
        lin = linearise(problem, p)
    return Solution(p, c, it)
