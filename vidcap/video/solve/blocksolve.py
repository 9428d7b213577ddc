"""Solve the clip's block-banded normal equations (LAPACK's banded Cholesky).

``J^T J`` of the clip solve couples each frame with the two frames either side
(second differences): a symmetric band of half-width ``3 P - 1`` in frame order
(``P`` parameters per frame). It is written into LAPACK's lower band storage, in
LAPACK's own (column-major) memory order so that LAPACK reads it without a transposed
copy, and factorised by one ``pbtrf`` call (``scipy.linalg.solveh_banded``), in time
linear in the clip's length. One call replaces the earlier block Cholesky over frame
pairs, whose several hundred small ``scipy.linalg`` calls per solve cost more in
Python overhead than the arithmetic (5x slower on 300 frames).
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import as_strided
from scipy.linalg import LinAlgError, solveh_banded


def lower_band(blocks) -> np.ndarray:
    """H's lower band storage (3 P, F P) (``ab[i - j, j] = H[i, j]``, ``ab[0]`` the
    diagonal), Fortran-ordered, from its blocks (3, F, P, P): (f, f), (f, f + 1),
    (f, f + 2), zero past the end.

    In column-major storage entry (c, r) of block (s, f) (``H[(f + s) P + r, f P + c]``)
    sits at ``(f P + c) (3 P) + s P + r - c``: for each block diagonal ``s`` one strided
    copy whose rows ``r`` are contiguous. The diagonal blocks' entries below their
    diagonal (``r < c``) would land in the previous column, past its band: they are not
    written (the band's far corner stays zero; the ``s = 2`` copy that shares a place
    with it comes after).
    """
    _, F, P, _ = blocks.shape
    n = F * P
    kd = 3 * P - 1
    buf = np.zeros(n * (kd + 1))
    item = buf.itemsize
    keep = np.triu(np.ones((P, P), bool))  # (c, r) with r >= c
    for s in range(min(3, F)):
        view = as_strided(buf[s * P:], shape=(F - s, P, P),
                          strides=(P * (kd + 1) * item, kd * item, item), writeable=True)
        if s == 0:
            np.copyto(view, blocks[0], where=keep)
        else:
            view[...] = blocks[s, :F - s]
    return buf.reshape(n, kd + 1).T


def solve_band(ab, rhs) -> np.ndarray | None:
    """Solve H x = rhs, H in lower band storage (:func:`lower_band`), rhs (F, P);
    None when H is not positive definite. ``ab`` is left as it was."""
    try:
        x = solveh_banded(ab, np.ravel(rhs), check_finite=False, lower=True)
    except LinAlgError:
        return None
    return x.reshape(np.shape(rhs))


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
    return solve_band(lower_band(np.asarray(blocks, dtype=float)), rhs)
