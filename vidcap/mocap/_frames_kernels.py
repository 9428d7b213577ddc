"""Compiled rotation fit of :func:`vidcap.mocap.frames.kabsch` (imported lazily: numba).

Per frame, the rotation R maximising Σ w (x - x̄)ᵀ R (t - t̄) from the cross-covariance
H = Σ w (t - t̄)(x - x̄)ᵀ, by Horn's quaternion method (Horn, JOSA A 4:629, 1987): R is
the rotation of the unit eigenvector of the largest eigenvalue of a symmetric 4x4 matrix
built from H, found by cyclic Jacobi sweeps. The singular values of H (for the
collinearity test) are the square roots of the eigenvalues of HᵀH, by the same sweeps.
Same results as the SVD path to rounding, one pass without LAPACK calls per frame.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _jacobi(a, v, n):
    """Diagonalise the symmetric n x n ``a`` in place; ``v`` accumulates the rotations."""
    for _ in range(30):
        off = 0.0
        diag = 0.0
        for p in range(n):
            diag += a[p, p] * a[p, p]
            for q in range(p + 1, n):
                off += a[p, q] * a[p, q]
        if off <= 1e-28 * diag or off == 0.0:
            return
        for p in range(n - 1):
            for q in range(p + 1, n):
                apq = a[p, q]
                if apq == 0.0:
                    continue
                theta = (a[q, q] - a[p, p]) / (2.0 * apq)
                t = 1.0 / (abs(theta) + np.sqrt(theta * theta + 1.0))
                if theta < 0.0:
                    t = -t
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = t * c
                for k in range(n):
                    akp = a[k, p]
                    akq = a[k, q]
                    a[k, p] = c * akp - s * akq
                    a[k, q] = s * akp + c * akq
                for k in range(n):
                    apk = a[p, k]
                    aqk = a[q, k]
                    a[p, k] = c * apk - s * aqk
                    a[q, k] = s * apk + c * aqk
                for k in range(n):
                    vkp = v[k, p]
                    vkq = v[k, q]
                    v[k, p] = c * vkp - s * vkq
                    v[k, q] = s * vkp + c * vkq


@njit(cache=True)
def rotations_from_cross(h):
    """Rotations (F, 3, 3) and singular values (F, 3), descending, of cross-covariances
    ``h`` (F, 3, 3) with ``h[f, i, j] = Σ w t_i x_j``: ``x ≈ R t``."""
    f_n = h.shape[0]
    rot = np.empty((f_n, 3, 3))
    sv = np.empty((f_n, 3))
    a = np.empty((4, 4))  # scratch, reused every frame
    v = np.empty((4, 4))
    g = np.empty((3, 3))
    e = np.empty((3, 3))
    for f in range(f_n):
        s = h[f]
        sxx, sxy, sxz = s[0, 0], s[0, 1], s[0, 2]
        syx, syy, syz = s[1, 0], s[1, 1], s[1, 2]
        szx, szy, szz = s[2, 0], s[2, 1], s[2, 2]
        a[0, 0] = sxx + syy + szz
        a[0, 1] = a[1, 0] = syz - szy
        a[0, 2] = a[2, 0] = szx - sxz
        a[0, 3] = a[3, 0] = sxy - syx
        a[1, 1] = sxx - syy - szz
        a[1, 2] = a[2, 1] = sxy + syx
        a[1, 3] = a[3, 1] = szx + sxz
        a[2, 2] = -sxx + syy - szz
        a[2, 3] = a[3, 2] = syz + szy
        a[3, 3] = -sxx - syy + szz
        for i in range(4):
            for j in range(4):
                v[i, j] = 1.0 if i == j else 0.0
        _jacobi(a, v, 4)
        best = 0
        for k in range(1, 4):
            if a[k, k] > a[best, best]:
                best = k
        w, x, y, z = v[0, best], v[1, best], v[2, best], v[3, best]
        nrm = np.sqrt(w * w + x * x + y * y + z * z)
        w, x, y, z = w / nrm, x / nrm, y / nrm, z / nrm
        rot[f, 0, 0] = w * w + x * x - y * y - z * z
        rot[f, 0, 1] = 2.0 * (x * y - w * z)
        rot[f, 0, 2] = 2.0 * (x * z + w * y)
        rot[f, 1, 0] = 2.0 * (x * y + w * z)
        rot[f, 1, 1] = w * w - x * x + y * y - z * z
        rot[f, 1, 2] = 2.0 * (y * z - w * x)
        rot[f, 2, 0] = 2.0 * (x * z - w * y)
        rot[f, 2, 1] = 2.0 * (y * z + w * x)
        rot[f, 2, 2] = w * w - x * x - y * y + z * z
        for i in range(3):  # g = sᵀ s
            for j in range(3):
                g[i, j] = s[0, i] * s[0, j] + s[1, i] * s[1, j] + s[2, i] * s[2, j]
                e[i, j] = 1.0 if i == j else 0.0
        _jacobi(g, e, 3)
        d0, d1, d2 = g[0, 0], g[1, 1], g[2, 2]
        if d0 < d1:
            d0, d1 = d1, d0
        if d1 < d2:
            d1, d2 = d2, d1
        if d0 < d1:
            d0, d1 = d1, d0
        sv[f, 0] = np.sqrt(max(d0, 0.0))
        sv[f, 1] = np.sqrt(max(d1, 0.0))
        sv[f, 2] = np.sqrt(max(d2, 0.0))
    return rot, sv
