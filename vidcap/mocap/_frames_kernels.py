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


@njit(cache=True, inline="always")
def _quat_to_rot(rot, f, w, x, y, z):
    """Write the rotation matrix of the unit quaternion ``(w, x, y, z)`` into ``rot[f]``."""
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
        _quat_to_rot(rot, f, w, x, y, z)
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


@njit(cache=True)
def _adjugate4(a00, a01, a02, a03, a11, a12, a13, a22, a23, a33, adj):
    """The adjugate of the symmetric 4x4 matrix with upper triangle a00..a33 into
    ``adj`` (4, 4), from its twelve 2x2 minors (Laplace expansion); returns the
    determinant."""
    a10, a20, a30, a21, a31, a32 = a01, a02, a03, a12, a13, a23
    s0 = a00 * a11 - a10 * a01
    s1 = a00 * a12 - a10 * a02
    s2 = a00 * a13 - a10 * a03
    s3 = a01 * a12 - a11 * a02
    s4 = a01 * a13 - a11 * a03
    s5 = a02 * a13 - a12 * a03
    c5 = a22 * a33 - a32 * a23
    c4 = a21 * a33 - a31 * a23
    c3 = a21 * a32 - a31 * a22
    c2 = a20 * a33 - a30 * a23
    c1 = a20 * a32 - a30 * a22
    c0 = a20 * a31 - a30 * a21
    adj[0, 0] = a11 * c5 - a12 * c4 + a13 * c3
    adj[0, 1] = -a01 * c5 + a02 * c4 - a03 * c3
    adj[0, 2] = a31 * s5 - a32 * s4 + a33 * s3
    adj[0, 3] = -a21 * s5 + a22 * s4 - a23 * s3
    adj[1, 0] = -a10 * c5 + a12 * c2 - a13 * c1
    adj[1, 1] = a00 * c5 - a02 * c2 + a03 * c1
    adj[1, 2] = -a30 * s5 + a32 * s2 - a33 * s1
    adj[1, 3] = a20 * s5 - a22 * s2 + a23 * s1
    adj[2, 0] = a10 * c4 - a11 * c2 + a13 * c0
    adj[2, 1] = -a00 * c4 + a01 * c2 - a03 * c0
    adj[2, 2] = a30 * s4 - a31 * s2 + a33 * s0
    adj[2, 3] = -a20 * s4 + a21 * s2 - a23 * s0
    adj[3, 0] = -a10 * c3 + a11 * c1 - a12 * c0
    adj[3, 1] = a00 * c3 - a01 * c1 + a02 * c0
    adj[3, 2] = -a30 * s3 + a31 * s1 - a32 * s0
    adj[3, 3] = a20 * s3 - a21 * s1 + a22 * s0
    return s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0


@njit(cache=True)
def _rotation_newton(s, e0, adj, rot, f):
    """Horn's rotation of cross-covariance ``s`` (3, 3) into ``rot[f]`` the fast way;
    False (nothing written) where it is ill-determined and the Jacobi sweeps of
    :func:`rotations_from_cross` must do. ``adj`` (4, 4) is scratch.

    The largest eigenvalue λ of Horn's symmetric, traceless 4x4 matrix N by Newton's
    method on its characteristic polynomial λ⁴ - 2|S|² λ² - 8 det(S) λ + det(N) from
    ``e0`` >= λ (Theobald's QCP, Acta Cryst A 61:478, 2005): the steps from above the
    largest root decrease monotonically and stop where rounding turns them back. Its
    eigenvector q (the unit quaternion) is the largest column of adj(N - λI) =
    Π(λ_k - λ) q qᵀ.
    """
    sxx, sxy, sxz = s[0, 0], s[0, 1], s[0, 2]
    syx, syy, syz = s[1, 0], s[1, 1], s[1, 2]
    szx, szy, szz = s[2, 0], s[2, 1], s[2, 2]
    n00 = sxx + syy + szz
    n01 = syz - szy
    n02 = szx - sxz
    n03 = sxy - syx
    n11 = sxx - syy - szz
    n12 = sxy + syx
    n13 = szx + sxz
    n22 = -sxx + syy - szz
    n23 = syz + szy
    n33 = -sxx - syy + szz
    c2 = -2.0 * (sxx * sxx + sxy * sxy + sxz * sxz + syx * syx + syy * syy + syz * syz
                 + szx * szx + szy * szy + szz * szz)
    c1 = -8.0 * (sxx * (syy * szz - syz * szy) - sxy * (syx * szz - syz * szx)
                 + sxz * (syx * szy - syy * szx))
    c0 = _adjugate4(n00, n01, n02, n03, n11, n12, n13, n22, n23, n33, adj)
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
    # det N's rounding moves λ by ~ ε λ²/gap, the adjugate's column by that over the gap
    # (ε (λ/gap)²); the Rayleigh quotient of that column is λ to ~ ε λ, and the column
    # at it is q to ~ ε λ/gap, what the Jacobi sweeps reach.
    for _ in range(2):
        _adjugate4(n00 - lam, n01, n02, n03, n11 - lam, n12, n13, n22 - lam, n23, n33 - lam,
                   adj)
        best = 0
        for j in range(1, 4):
            if abs(adj[j, j]) > abs(adj[best, best]):
                best = j
        # |adj_jj| max >= Π|λ_k - λ| / 4: where the nearest other eigenvalue is within
        # ~1e-4 λ (degenerate, or nearly: collinear points, mirrored sets) the sweeps do it
        if not (abs(adj[best, best]) > 1e-4 * lam * lam * lam):
            return False
        w, x, y, z = adj[0, best], adj[1, best], adj[2, best], adj[3, best]
        nrm = np.sqrt(w * w + x * x + y * y + z * z)
        w, x, y, z = w / nrm, x / nrm, y / nrm, z / nrm
        lam = (w * (n00 * w + n01 * x + n02 * y + n03 * z)
               + x * (n01 * w + n11 * x + n12 * y + n13 * z)
               + y * (n02 * w + n12 * x + n22 * y + n23 * z)
               + z * (n03 * w + n13 * x + n23 * y + n33 * z))
    _quat_to_rot(rot, f, w, x, y, z)
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


#: :func:`kabsch_frames` states per frame: no pose, a pose, and (bits) the rotation or
#: the rank test left to :func:`rotations_from_cross` (see :func:`kabsch_finish`).
NO_POSE, POSE, SWEEP_ROTATION, SWEEP_RANK = 0, 1, 2, 4


@njit(cache=True)
def kabsch_frames(template, points, weights, eps):
    """:func:`vidcap.mocap.frames.kabsch` fused per frame: rotations (F, 3, 3), origins
    (F, 3), states (F,) and, for the frames whose state has a SWEEP bit, the
    cross-covariance, x̄ and t̄ (F, 15) to finish them with (:func:`kabsch_finish`).

    template (K, 3), points (F, K, 3), weights (F, K): a point counts where it, its
    template row and its weight are finite and the weight is > 0. NaN poses where
    fewer than 3 points count or the rank test (s₂ > 1e-6 s₁) fails. The rotation from
    :func:`_rotation_newton` with the bound e0 = (Σw|t - t̄|² + Σw|x - x̄|²)/2 >= λ
    (Σ w xᵀRt <= Σ w |x||t|); the rank test from :func:`_rank2_clear`.
    """
    f_n, k_n = points.shape[0], points.shape[1]
    rot = np.empty((f_n, 3, 3))
    org = np.empty((f_n, 3))
    state = np.zeros(f_n, dtype=np.int8)
    aux = np.empty((f_n, 15))
    adj = np.empty((4, 4))
    h = np.empty((3, 3))
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
        st = NO_POSE
        if cnt >= 3:
            den = max(den, eps)
            for i in range(3):
                sx = 0.0
                sw = 0.0
                for k in range(k_n):
                    if use[k]:
                        sx += weights[f, k] * points[f, k, i]
                        sw += weights[f, k] * template[k, i]
                xc[i] = sx / den
                tc[i] = sw / den
            ga = 0.0
            gb = 0.0
            h[:, :] = 0.0
            for k in range(k_n):
                if use[k]:
                    wk = weights[f, k]
                    for i in range(3):
                        ti = template[k, i] - tc[i]
                        ga += wk * ti * ti
                        xi = points[f, k, i] - xc[i]
                        gb += wk * xi * xi
                        for j in range(3):
                            h[i, j] += wk * ti * (points[f, k, j] - xc[j])
            rank = _rank2_clear(h)
            if rank >= 0:
                st = POSE if rank > 0 else SWEEP_RANK
                if not _rotation_newton(h, 0.5 * (ga + gb), adj, rot, f):
                    st |= SWEEP_ROTATION
                if st != POSE:
                    for i in range(3):
                        for j in range(3):
                            aux[f, 3 * i + j] = h[i, j]
                        aux[f, 9 + i] = xc[i]
                        aux[f, 12 + i] = tc[i]
        state[f] = st
        if st == POSE:
            for i in range(3):
                org[f, i] = xc[i] - (rot[f, i, 0] * tc[0] + rot[f, i, 1] * tc[1]
                                     + rot[f, i, 2] * tc[2])
        elif st == NO_POSE:
            rot[f] = np.nan
            org[f] = np.nan
    return rot, org, state, aux


def kabsch_finish(rot, org, state, aux, eps):
    """The frames :func:`kabsch_frames` left to the Jacobi sweeps (their SWEEP bits), in
    place: the rotation and/or the rank test from :func:`rotations_from_cross`, then
    the origin. Plain Python around one compiled call: such frames are rare, and
    calling the sweeps from inside the fused kernel would cost seconds of compiling."""
    idx = np.flatnonzero(state > POSE)
    if idx.size == 0:
        return
    st = state[idx]
    r1, sv = rotations_from_cross(np.ascontiguousarray(aux[idx, :9]).reshape(-1, 3, 3))
    prev = rot[idx]
    r = np.where((st & SWEEP_ROTATION)[:, None, None] > 0, r1, prev)
    ok = ((st & SWEEP_RANK) == 0) | (sv[:, 1] > 1e-6 * np.maximum(sv[:, 0], eps))
    r[~ok] = np.nan
    xc, tc = aux[idx, 9:12], aux[idx, 12:15]
    o = xc - np.matmul(r, tc[..., None])[..., 0]
    o[~ok] = np.nan
    rot[idx] = r
    org[idx] = o
    state[idx] = np.where(ok, POSE, NO_POSE)


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
