"""Linear quantile regression with few unknowns, solved exactly by basis exchange.

``min_beta sum_i rho_q(y_i - b_i . beta)`` (``rho_q(u) = q u`` for u > 0, ``(q - 1) u``
below) is a linear programme whose optimum is a vertex: ``m`` (the unknowns) of the
points fitted exactly. From a start vertex each step reads the subgradient's
multipliers of the fitted points, lets the one outside ``[q - 1, q]`` leave and walks
along the edge that frees it to the kink where the objective stops falling (the
weighted median of the crossings), whose point enters (Barrodale and Roberts' simplex
step for L1 regression, with the quantile's weights; Koenker, "Quantile Regression",
2005, sec. 6.2). With a handful of unknowns and a few hundred points this takes a few
milliseconds, where ``scipy.optimize.linprog`` costs ~0.1 s to import alone, which
every ``vidcap convert`` paid for the scale estimate (:func:`vidcap.video.lift.estimate_scales`).

The result is certified: returned only when the multipliers of the final vertex prove
it optimal (no point left with a zero residual outside the basis, so the
subgradient condition is exact); otherwise None, for the caller's general solver.
"""

from __future__ import annotations

import numpy as np


def quantile_fit(design, y, quantile: float, *, max_steps: int = 500) -> np.ndarray | None:
    """The exact minimiser of the quantile loss, or None where not certified.

    Parameters
    ----------
    design : array_like, shape (n, m)
        The regressors (dense), rank m.
    y : array_like, shape (n,)
    quantile : float
        In (0, 1).
    max_steps : int
        Basis exchanges at most.

    Returns
    -------
    numpy.ndarray, shape (m,), or None
        The coefficients of an optimal vertex, or None when the start is singular, the
        steps run out, or the vertex is degenerate (a point off the basis fitted
        exactly: its multiplier, hence optimality, is not read here).
    """
    b = np.asarray(design, dtype=float)
    y = np.asarray(y, dtype=float)
    q = float(quantile)
    n, m = b.shape
    basis = _start_basis(b, y)
    if basis is None:
        return None
    for _ in range(max_steps):
        try:
            beta = np.linalg.solve(b[basis], y[basis])
        except np.linalg.LinAlgError:
            return None
        r = y - b @ beta
        off = np.ones(n, bool)
        off[basis] = False
        if np.any(r[off] == 0.0):
            return None  # degenerate vertex
        psi = np.where(r[off] > 0.0, q, q - 1.0)
        # the fitted points' multipliers: sum_off psi_i b_i + b_basis^T lam = 0
        lam = np.linalg.solve(b[basis].T, -(psi @ b[off]))
        over = np.maximum(lam - q, q - 1.0 - lam)  # > 0 outside [q - 1, q]
        k = int(np.argmax(over))
        if over[k] <= 1e-9:
            return beta
        # the edge that moves point k off its fit, the way the objective falls:
        # B_basis u = e_k moves r_k by -1 per unit; lam_k < q - 1 wants r_k < 0
        e = np.zeros(m)
        e[k] = 1.0
        u = np.linalg.solve(b[basis], e)
        if lam[k] > q:
            u = -u
        slope = -over[k]  # the objective's slope along u at the start
        idx = np.flatnonzero(off)
        du = b[idx] @ u  # r_i changes by -du_i per unit
        with np.errstate(divide="ignore", invalid="ignore"):
            step = r[idx] / du
        cross = (du != 0.0) & (step > 0.0)
        if not cross.any():
            return None  # unbounded: not for a design of full rank
        idx, step, gain = idx[cross], step[cross], np.abs(du[cross])
        order = np.argsort(step, kind="stable")
        total = slope + np.cumsum(gain[order])  # the slope past each crossing
        enter = idx[order[int(np.argmax(total >= 0.0))]] if (total >= 0.0).any() else None
        if enter is None:
            return None
        basis = basis.copy()
        basis[k] = enter
    return None


def _start_basis(b, y) -> np.ndarray | None:
    """``m`` points nearest the least-squares fit whose rows are independent."""
    n, m = b.shape
    beta = np.linalg.lstsq(b, y, rcond=None)[0]
    chosen: list[int] = []
    for i in np.argsort(np.abs(y - b @ beta), kind="stable"):
        trial = chosen + [int(i)]
        if np.linalg.matrix_rank(b[trial]) == len(trial):
            chosen = trial
            if len(chosen) == m:
                return np.array(chosen)
    return None
