"""Compiled banded Cholesky solve (numba) for :mod:`vidcap.solve.gauss_newton`.

LAPACK's banded Cholesky through OpenBLAS slows down ten-fold when its threads
compete with other processes for the cores, and the band here is narrow (72), so a
plain single-threaded loop is as fast and steadier. Module-level for numba's
on-disk cache.
"""

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def banded_cholesky_solve(lb, b):
    """Solve A x = b for symmetric positive definite banded A.

    Parameters
    ----------
    lb : numpy.ndarray, shape (n, u + 1)
        Lower band of A: ``lb[i, d] = A[i, i - d]``; overwritten with the factor.
    b : numpy.ndarray, shape (n,)

    Returns
    -------
    x : numpy.ndarray, shape (n,), or an empty array when A is not positive definite.
    """
    n, w = lb.shape
    u = w - 1
    for i in range(n):
        j0 = max(0, i - u)
        for j in range(j0, i + 1):
            s = lb[i, i - j]
            k0 = max(j0, j - u)
            for k in range(k0, j):
                s -= lb[i, i - k] * lb[j, j - k]
            if j == i:
                if s <= 0.0:
                    return np.empty(0)
                lb[i, 0] = math.sqrt(s)
            else:
                lb[i, i - j] = s / lb[j, 0]
    y = np.empty(n)
    for i in range(n):
        s = b[i]
        for k in range(max(0, i - u), i):
            s -= lb[i, i - k] * y[k]
        y[i] = s / lb[i, 0]
    x = np.empty(n)
    for i in range(n - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, min(n, i + u + 1)):
            s -= lb[k, k - i] * x[k]
        x[i] = s / lb[i, 0]
    return x
