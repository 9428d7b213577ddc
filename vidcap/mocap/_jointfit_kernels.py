"""Compiled per-marker statistics of :mod:`vidcap.mocap.jointfit` (imported lazily: numba).

One pass (two for the angles) over a marker's samples (N, 3) in its parent's frame, for
the fit's residual and range of motion, the centre's Fisher information and the spread
across the plane of motion. Each equals the numpy expression it replaces (kept in
jointfit.py as the path without numba) to rounding: sums run in order, not pairwise.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def radial_residual_angles(y, c, radius, nrm, hinge, eps):
    """Σ (|d| - radius)² and the angles (degrees, (N,)) of the directions d/|d| from
    their normalised mean, d = y - c (projected off ``nrm`` when ``hinge``)."""
    n = y.shape[0]
    u = np.empty((n, 3))
    res2 = 0.0
    m0 = m1 = m2 = 0.0
    for i in range(n):
        a0 = y[i, 0] - c[0]
        a1 = y[i, 1] - c[1]
        a2 = y[i, 2] - c[2]
        if hinge:
            p = a0 * nrm[0] + a1 * nrm[1] + a2 * nrm[2]
            a0 -= p * nrm[0]
            a1 -= p * nrm[1]
            a2 -= p * nrm[2]
        dist = np.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        res2 += (dist - radius) ** 2
        dm = max(dist, eps)
        u[i, 0] = a0 / dm
        u[i, 1] = a1 / dm
        u[i, 2] = a2 / dm
        m0 += u[i, 0]
        m1 += u[i, 1]
        m2 += u[i, 2]
    ang = np.empty(n)
    if n == 0:
        return res2, ang
    m0, m1, m2 = m0 / n, m1 / n, m2 / n
    mn = np.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
    if mn > eps:
        m0, m1, m2 = m0 / mn, m1 / mn, m2 / mn
    else:
        m0 = m1 = m2 = np.nan
    for i in range(n):
        dot = u[i, 0] * m0 + u[i, 1] * m1 + u[i, 2] * m2
        ang[i] = np.degrees(np.arccos(min(max(dot, -1.0), 1.0)))
    return res2, ang


@njit(cache=True)
def direction_sums(y, c, eps):
    """Σ u (3,) and Σ u uᵀ (3, 3) of the unit directions u = (y - c)/|y - c| (0 where
    |y - c| <= eps or not finite)."""
    s = np.zeros(3)
    q = np.zeros((3, 3))
    for i in range(y.shape[0]):
        a0 = y[i, 0] - c[0]
        a1 = y[i, 1] - c[1]
        a2 = y[i, 2] - c[2]
        r = np.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        if not (r > eps):
            continue
        u0 = a0 / r
        u1 = a1 / r
        u2 = a2 / r
        if not (np.isfinite(u0) and np.isfinite(u1) and np.isfinite(u2)):
            continue
        s[0] += u0
        s[1] += u1
        s[2] += u2
        q[0, 0] += u0 * u0
        q[0, 1] += u0 * u1
        q[0, 2] += u0 * u2
        q[1, 1] += u1 * u1
        q[1, 2] += u1 * u2
        q[2, 2] += u2 * u2
    q[1, 0] = q[0, 1]
    q[2, 0] = q[0, 2]
    q[2, 1] = q[1, 2]
    return s, q


@njit(cache=True)
def scatter(y):
    """Σ (y - ȳ)(y - ȳ)ᵀ (3, 3) of the samples y (N, 3), N >= 1."""
    n = y.shape[0]
    mean = np.zeros(3)
    for i in range(n):
        for j in range(3):
            mean[j] += y[i, j]
    for j in range(3):
        mean[j] /= n
    q = np.zeros((3, 3))
    for i in range(n):
        a0 = y[i, 0] - mean[0]
        a1 = y[i, 1] - mean[1]
        a2 = y[i, 2] - mean[2]
        q[0, 0] += a0 * a0
        q[0, 1] += a0 * a1
        q[0, 2] += a0 * a2
        q[1, 1] += a1 * a1
        q[1, 2] += a1 * a2
        q[2, 2] += a2 * a2
    q[1, 0] = q[0, 1]
    q[2, 0] = q[0, 2]
    q[2, 1] = q[1, 2]
    return q
