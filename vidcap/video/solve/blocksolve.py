"""Solve the clip's block-banded normal equations (block Cholesky over frame pairs).

``J^T J`` of the clip solve couples each frame with the two frames either side
(second differences). Taken two frames at a time it is block tridiagonal with
48 x 48 blocks, which a block Cholesky (the block Thomas algorithm) solves in time
linear in the clip's length with small dense factorisations only: no compiled code to
load, and no multi-threaded BLAS on a large band (which slows down ten-fold when its
threads compete with other processes for the cores).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import LinAlgError, cholesky, solve_triangular


def _pairs(blocks):
    """Diagonal and super-diagonal blocks (n, 2P, 2P) of frame pairs, F padded to even."""
    _, F, P, _ = blocks.shape
    n = (F + 1) // 2
    b = np.zeros((3, 2 * n, P, P))
    b[:, :F] = blocks
    if F % 2:
        b[0, F] = np.eye(P)  # a padding frame that solves to 0
    d = np.zeros((n, 2 * P, 2 * P))
    d[:, :P, :P] = b[0, 0::2]
    d[:, P:, P:] = b[0, 1::2]
    d[:, :P, P:] = b[1, 0::2]
    d[:, P:, :P] = np.swapaxes(b[1, 0::2], 1, 2)
    c = np.zeros((n, 2 * P, 2 * P))
    c[:, :P, :P] = b[2, 0::2]
    c[:, P:, :P] = b[1, 1::2]
    c[:, P:, P:] = b[2, 1::2]
    return d, c


def solve_block_banded(blocks, rhs) -> np.ndarray | None:
    """Solve H x = rhs for the symmetric positive definite block-banded H.

    Parameters
    ----------
    blocks : numpy.ndarray, shape (3, F, P, P)
        H's blocks (f, f), (f, f + 1), (f, f + 2) (zero where past the end).
    rhs : numpy.ndarray, shape (F, P)

    Returns
    -------
    numpy.ndarray, shape (F, P), or None when H is not positive definite.
    """
    F, P = rhs.shape
    d, c = _pairs(blocks)
    n = d.shape[0]
    b = np.zeros((2 * n, P))
    b[:F] = rhs
    b = b.reshape(n, 2 * P)
    chol = np.empty_like(d)
    w = np.empty_like(c)
    z = np.empty((n, 2 * P))
    s = d[0]
    prev = np.zeros(2 * P)
    try:
        for i in range(n):  # over frame pairs; the blocks are dense 48 x 48
            chol[i] = cholesky(s, lower=True, check_finite=False)
            z[i] = solve_triangular(chol[i], b[i] - prev, lower=True, check_finite=False)
            if i + 1 < n:
                w[i] = solve_triangular(chol[i], c[i], lower=True, check_finite=False)
                s = d[i + 1] - w[i].T @ w[i]
                prev = w[i].T @ z[i]
    except LinAlgError:
        return None
    x = np.empty((n, 2 * P))
    nxt = np.zeros(2 * P)
    for i in range(n - 1, -1, -1):
        x[i] = solve_triangular(chol[i], z[i] - nxt, lower=True, trans="T", check_finite=False)
        if i > 0:
            nxt = w[i - 1] @ x[i]
    return x.reshape(2 * n, P)[:F]
