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


@njit(cache=True, inline="always")
def _horn(s, a):
    """Horn's symmetric, traceless 4x4 matrix of the cross-covariance ``s`` into ``a``."""
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


@njit(cache=True, inline="always")
def _det3(a, r0, r1, r2, c0, c1, c2):
    """Determinant of the 3x3 submatrix of ``a`` on rows r0..r2 and columns c0..c2."""
    return (a[r0, c0] * (a[r1, c1] * a[r2, c2] - a[r1, c2] * a[r2, c1])
            - a[r0, c1] * (a[r1, c0] * a[r2, c2] - a[r1, c2] * a[r2, c0])
            + a[r0, c2] * (a[r1, c0] * a[r2, c1] - a[r1, c1] * a[r2, c0]))


@njit(cache=True, inline="always")
def _cofactor(a, i, j):
    """Cofactor (i, j) of the 4x4 ``a``: the signed determinant without row i, column j."""
    r0 = 1 if i == 0 else 0
    r1 = 2 if i <= 1 else 1
    r2 = 3 if i <= 2 else 2
    c0 = 1 if j == 0 else 0
    c1 = 2 if j <= 1 else 1
    c2 = 3 if j <= 2 else 2
    d = _det3(a, r0, r1, r2, c0, c1, c2)
    return d if (i + j) % 2 == 0 else -d


@njit(cache=True, inline="always")
def _quat_rotation(w, x, y, z, rot, f):
    """The rotation of the unit quaternion (w, x, y, z) into ``rot[f]``."""
    rot[f, 0, 0] = w * w + x * x - y * y - z * z
    rot[f, 0, 1] = 2.0 * (x * y - w * z)
    rot[f, 0, 2] = 2.0 * (x * z + w * y)
    rot[f, 1, 0] = 2.0 * (x * y + w * z)
    rot[f, 1, 1] = w * w - x * x + y * y - z * z
    rot[f, 1, 2] = 2.0 * (y * z - w * x)
    rot[f, 2, 0] = 2.0 * (x * z - w * y)
    rot[f, 2, 1] = 2.0 * (y * z + w * x)
    rot[f, 2, 2] = w * w - x * x - y * y + z * z


@njit(cache=True)
def _rotation_newton(s, e0, a, rot, f):
    """Horn's rotation of cross-covariance ``s`` (3, 3) into ``rot[f]`` the fast way;
    False (nothing written) where it is ill-determined and the Jacobi sweeps must do.

    The largest eigenvalue of Horn's matrix N by Newton's method on its characteristic
    polynomial λ⁴ - 2|S|² λ² - 8 det(S) λ + det(N) from ``e0`` >= it (Theobald's QCP,
    Acta Cryst A 61:478, 2005), then its eigenvector as the largest column of the
    adjugate of N - λI. Newton's steps from above the largest root decrease
    monotonically; they stop where rounding turns them back.
    """
    _horn(s, a)
    c2 = 0.0
    for i in range(3):
        for j in range(3):
            c2 += s[i, j] * s[i, j]
    c2 = -2.0 * c2
    c1 = -8.0 * (s[0, 0] * (s[1, 1] * s[2, 2] - s[1, 2] * s[2, 1])
                 - s[0, 1] * (s[1, 0] * s[2, 2] - s[1, 2] * s[2, 0])
                 + s[0, 2] * (s[1, 0] * s[2, 1] - s[1, 1] * s[2, 0]))
    c0 = (a[0, 0] * _det3(a, 1, 2, 3, 1, 2, 3) - a[0, 1] * _det3(a, 1, 2, 3, 0, 2, 3)
          + a[0, 2] * _det3(a, 1, 2, 3, 0, 1, 3) - a[0, 3] * _det3(a, 1, 2, 3, 0, 1, 2))
    lam = e0
    if not (lam > 0.0) or not np.isfinite(lam):
        return False
    converged = False
    for _ in range(200):
        l2 = lam * lam
        p = (l2 + c2) * l2 + c1 * lam + c0
        dp = (4.0 * l2 + 2.0 * c2) * lam + c1
        if not (dp > 0.0):
            break
        step = p / dp
        if not (step > 1e-15 * lam):  # at the root to rounding (or stepped past it)
            if step > 0.0:
                lam -= step
            converged = True
            break
        lam -= step
    if not converged or not (lam > 0.0):
        return False
    for i in range(4):
        a[i, i] -= lam
    best, cbest = 0, 0.0
    for j in range(4):
        cjj = abs(_cofactor(a, j, j))
        if cjj > cbest:
            best, cbest = j, cjj
    # adj(N - λI) = Π(λ_k - λ) q qᵀ, so cbest >= Π|λ_k - λ| / 4. The eigenvector's error
    # is ~ ε (λ/gap)² (det N's rounding moves λ by ~ ε λ²/gap): with the nearest other
    # eigenvalue closer than a few % of λ the sweeps do it, to ~ ε λ/gap.
    if not (cbest > 1e-2 * lam * lam * lam):
        return False
    w = _cofactor(a, 0, best)
    x = _cofactor(a, 1, best)
    y = _cofactor(a, 2, best)
    z = _cofactor(a, 3, best)
    nrm = np.sqrt(w * w + x * x + y * y + z * z)
    _quat_rotation(w / nrm, x / nrm, y / nrm, z / nrm, rot, f)
    return True


@njit(cache=True)
def _rank2_clear(s):
    """Whether the second singular value of ``s`` (3, 3) is clearly above (1) or below
    (-1) 1e-6 times the first, from invariants of G = SᵀS without its eigenvalues
    (0: too close to call). With μ1 >= μ2 >= μ3 its eigenvalues, t = tr G and m the
    sum of its principal 2x2 minors (= the squared 2x2 minors of S):
    t/3 <= μ1 <= t and μ1 μ2 <= m <= 3 μ1 μ2, so m / 3t² <= μ2/μ1 <= 9 m / t²."""
    t = 0.0
    for i in range(3):
        for j in range(3):
            t += s[i, j] * s[i, j]
    m = 0.0
    for r0 in range(3):
        for r1 in range(r0 + 1, 3):
            for c0 in range(3):
                for c1 in range(c0 + 1, 3):
                    d = s[r0, c0] * s[r1, c1] - s[r0, c1] * s[r1, c0]
                    m += d * d
    if not (t > 0.0):
        return -1
    ratio = m / (t * t)
    if ratio / 3.0 > 1.01e-12:
        return 1
    if 9.0 * ratio < 0.99e-12:
        return -1
    return 0


@njit(cache=True)
def kabsch_frames(template, points, weights, eps):
    """:func:`vidcap.mocap.frames.kabsch` fused per frame: rotations (F, 3, 3) and
    origins (F, 3), NaN where fewer than 3 points or a rank-deficient fit.

    template (K, 3), points (F, K, 3), weights (F, K): a point counts where it, its
    template row and its weight are finite and the weight is > 0. The rotation from
    :func:`_rotation_newton` with the bound e0 = (Σw|t - t̄|² + Σw|x - x̄|²)/2 >= λ
    (Σ w xᵀRt <= Σ w |x||t|), else from :func:`rotations_from_cross`'s sweeps; the
    rank test (s₂ > 1e-6 s₁) from :func:`_rank2_clear`, else the sweeps' singular values.
    """
    f_n, k_n = points.shape[0], points.shape[1]
    rot = np.empty((f_n, 3, 3))
    org = np.empty((f_n, 3))
    a = np.empty((4, 4))
    h = np.zeros((1, 3, 3))
    use = np.empty(k_n, dtype=np.bool_)
    xc = np.empty(3)
    tc = np.empty(3)
    for f in range(f_n):
        cnt = 0
        den = 0.0
        for k in range(k_n):
            wk = weights[f, k]
            ok = np.isfinite(wk) and wk > 0.0
            for i in range(3):
                ok = ok and np.isfinite(points[f, k, i]) and np.isfinite(template[k, i])
            use[k] = ok
            if ok:
                cnt += 1
                den += wk
        good = cnt >= 3
        if good:
            den = max(den, eps)
            for i in range(3):
                sx = 0.0
                st = 0.0
                for k in range(k_n):
                    if use[k]:
                        sx += weights[f, k] * points[f, k, i]
                        st += weights[f, k] * template[k, i]
                xc[i] = sx / den
                tc[i] = st / den
            ga = 0.0
            gb = 0.0
            for i in range(3):
                for j in range(3):
                    h[0, i, j] = 0.0
            for k in range(k_n):
                if use[k]:
                    wk = weights[f, k]
                    for i in range(3):
                        ti = template[k, i] - tc[i]
                        ga += wk * ti * ti
                        xi = points[f, k, i] - xc[i]
                        gb += wk * xi * xi
                        for j in range(3):
                            h[0, i, j] += wk * ti * (points[f, k, j] - xc[j])
            s = h[0]
            rank = _rank2_clear(s)
            fast = _rotation_newton(s, 0.5 * (ga + gb), a, rot, f)
            if not fast or rank == 0:
                r1, sv = rotations_from_cross(h)
                if not fast:
                    rot[f] = r1[0]
                if rank == 0:
                    rank = 1 if sv[0, 1] > 1e-6 * max(sv[0, 0], eps) else -1
            good = rank > 0
        if good:
            for i in range(3):
                org[f, i] = xc[i] - (rot[f, i, 0] * tc[0] + rot[f, i, 1] * tc[1]
                                     + rot[f, i, 2] * tc[2])
        else:
            rot[f] = np.nan
            org[f] = np.nan
    return rot, org


@njit(cache=True)
def three_point_template(pts, eps):
    """The template of :func:`vidcap.mocap.frames.frames_from_points`: per point, the
    median over frames of its coordinates in the frame of the first three points
    (:func:`vidcap.mocap.frames.frame_from_three`), frames where those are missing or
    collinear and rows with a missing coordinate skipped; (K, 3), NaN where no frame."""
    f_n, k_n = pts.shape[0], pts.shape[1]
    local = np.empty((k_n, 3, f_n))
    cnt = np.zeros(k_n, dtype=np.int64)
    r = np.empty((3, 3))
    for f in range(f_n):
        ax = pts[f, 1, 0] - pts[f, 0, 0]
        ay = pts[f, 1, 1] - pts[f, 0, 1]
        az = pts[f, 1, 2] - pts[f, 0, 2]
        bx = pts[f, 2, 0] - pts[f, 0, 0]
        by = pts[f, 2, 1] - pts[f, 0, 1]
        bz = pts[f, 2, 2] - pts[f, 0, 2]
        nx = by * az - bz * ay
        ny = bz * ax - bx * az
        nz = bx * ay - by * ax
        na = np.sqrt(ax * ax + ay * ay + az * az)
        nb = np.sqrt(bx * bx + by * by + bz * bz)
        nn = np.sqrt(nx * nx + ny * ny + nz * nz)
        if not (nn > 1e-3 * (na * nb)) or not (nn > eps):
            continue
        x0, x1, x2 = nx / nn, ny / nn, nz / nn
        zx = ay * x2 - az * x1
        zy = az * x0 - ax * x2
        zz = ax * x1 - ay * x0
        nzn = np.sqrt(zx * zx + zy * zy + zz * zz)
        if not (nzn > eps):
            continue
        zx, zy, zz = zx / nzn, zy / nzn, zz / nzn
        r[0, 0], r[1, 0], r[2, 0] = x0, x1, x2
        r[0, 1] = zy * x2 - zz * x1
        r[1, 1] = zz * x0 - zx * x2
        r[2, 1] = zx * x1 - zy * x0
        r[0, 2], r[1, 2], r[2, 2] = zx, zy, zz
        ok = True
        for i in range(3):
            ok = ok and np.isfinite(pts[f, 0, i])
            for j in range(3):
                ok = ok and np.isfinite(r[i, j])
        if not ok:
            continue
        for k in range(k_n):
            d0 = pts[f, k, 0] - pts[f, 0, 0]
            d1 = pts[f, k, 1] - pts[f, 0, 1]
            d2 = pts[f, k, 2] - pts[f, 0, 2]
            if not (np.isfinite(d0) and np.isfinite(d1) and np.isfinite(d2)):
                continue
            n = cnt[k]
            for j in range(3):
                local[k, j, n] = d0 * r[0, j] + d1 * r[1, j] + d2 * r[2, j]
            cnt[k] = n + 1
    out = np.full((k_n, 3), np.nan)
    for k in range(k_n):
        if cnt[k] > 0:
            for j in range(3):
                out[k, j] = np.median(local[k, j, :cnt[k]])
    return out


@njit(cache=True)
def median_finite_rows(y):
    """Per column, the median of ``y`` (N, D) over the rows without NaN or inf; (D,),
    NaN when there are none. The median of an even count is the mean of the middle two,
    as numpy's."""
    n, d = y.shape
    ok = np.empty(n, dtype=np.bool_)
    cnt = 0
    for i in range(n):
        good = True
        for j in range(d):
            good = good and np.isfinite(y[i, j])
        ok[i] = good
        if good:
            cnt += 1
    out = np.full(d, np.nan)
    if cnt == 0:
        return out
    col = np.empty(cnt)
    for j in range(d):
        c = 0
        for i in range(n):
            if ok[i]:
                col[c] = y[i, j]
                c += 1
        out[j] = np.median(col)
    return out


@njit(cache=True)
def points_to_local(r, o, x):
    """rᵀ (x - o) per frame: lab points x (F, K, 3) in frames r (F, 3, 3), o (F, 3)."""
    f_n, k_n = x.shape[0], x.shape[1]
    out = np.empty((f_n, k_n, 3))
    for f in range(f_n):
        for k in range(k_n):
            d0 = x[f, k, 0] - o[f, 0]
            d1 = x[f, k, 1] - o[f, 1]
            d2 = x[f, k, 2] - o[f, 2]
            for j in range(3):
                out[f, k, j] = d0 * r[f, 0, j] + d1 * r[f, 1, j] + d2 * r[f, 2, j]
    return out


@njit(cache=True)
def point_to_lab(r, o, v):
    """o + r v per frame: a constant local point v (3,) in frames r (F, 3, 3), o (F, 3)."""
    f_n = r.shape[0]
    out = np.empty((f_n, 3))
    for f in range(f_n):
        for i in range(3):
            out[f, i] = o[f, i] + (r[f, i, 0] * v[0] + r[f, i, 1] * v[1] + r[f, i, 2] * v[2])
    return out


@njit(cache=True)
def rigid_residuals(r, o, template, x):
    """Σ |x - o - r m|² over the frames with >= 3 of the K points x (F, K, 3) present, and
    those frames' Σ (3 k - 6) degrees of freedom; m = template[:K]."""
    ss = 0.0
    dof = 0
    for f in range(x.shape[0]):
        part = 0.0
        k_ok = 0
        for k in range(x.shape[1]):
            e = 0.0
            for i in range(3):
                pred = o[f, i] + (r[f, i, 0] * template[k, 0] + r[f, i, 1] * template[k, 1]
                                  + r[f, i, 2] * template[k, 2])
                e += (x[f, k, i] - pred) ** 2
            if np.isfinite(e):
                part += e
                k_ok += 1
        if k_ok >= 3:
            ss += part
            dof += 3 * k_ok - 6
    return ss, dof


@njit(cache=True)
def mean_over_points(y):
    """``np.nanmean(y, axis=1)`` of y (F, K, 3): per frame and coordinate, the sum in
    point order of the values that are not NaN over their count (NaN when none)."""
    f_n, k_n = y.shape[0], y.shape[1]
    out = np.empty((f_n, 3))
    for f in range(f_n):
        for i in range(3):
            tot = 0.0
            cnt = 0
            for k in range(k_n):
                v = y[f, k, i]
                if not np.isnan(v):
                    tot += v
                    cnt += 1
            out[f, i] = tot / cnt if cnt > 0 else np.nan
    return out
