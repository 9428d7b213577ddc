"""Solve the clip's block-banded normal equations (LAPACK's banded Cholesky).

``J^T J`` of the clip solve couples each frame with the two frames either side
(second differences): a symmetric band of half-width ``3 P - 1`` in frame order
(``P`` parameters per frame). It is written into LAPACK's upper band storage with
precomputed indices and factorised by one ``pbtrf`` call (``scipy.linalg.solveh_banded``),
in time linear in the clip's length. One call replaces the earlier block Cholesky
over frame pairs, whose several hundred small ``scipy.linalg`` calls per solve cost
more in Python overhead than the arithmetic (5x slower on 300 frames).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.linalg import LinAlgError, solveh_banded


@lru_cache(maxsize=16)
def _band_index(F: int, P: int) -> tuple[np.ndarray, np.ndarray]:
    """Flat indices (into blocks (3, F, P, P), into the band (3 P, F P)) of the
    entries on or above the diagonal."""
    kd = 3 * P - 1
    n = F * P
    s, f, r, c = np.meshgrid(np.arange(3), np.arange(F), np.arange(P), np.arange(P),
                             indexing="ij")
    i = f * P + r
    j = (f + s) * P + c
    keep = (j < n) & (i <= j)
    src = np.flatnonzero(keep.ravel())
    dst = ((kd + i - j) * n + j)[keep]
    return src, dst


def upper_band(blocks) -> np.ndarray:
    """H's upper band storage (3 P, F P) (``ab[3P - 1 + i - j, j] = H[i, j]``) from its
    blocks (3, F, P, P): (f, f), (f, f + 1), (f, f + 2), zero past the end."""
    _, F, P, _ = blocks.shape
    src, dst = _band_index(F, P)
    ab = np.zeros(3 * P * F * P)
    ab[dst] = blocks.reshape(-1)[src]
    return ab.reshape(3 * P, F * P)


def solve_band(ab, rhs) -> np.ndarray | None:
    """Solve H x = rhs, H in upper band storage (:func:`upper_band`), rhs (F, P);
    None when H is not positive definite. ``ab`` is left as it was."""
    try:
        x = solveh_banded(ab, np.ravel(rhs), check_finite=False, lower=False)
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
    return solve_band(upper_band(np.asarray(blocks, dtype=float)), rhs)
