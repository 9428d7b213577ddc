"""Moment sums of point sets for the closed-form sphere fits of
:mod:`vidcap.mocap.spherefit`: n, mean, M2 = Σ y yᵀ, M3 = Σ y |y|² about the mean.

One backend per case, chosen in one line: for D = 3 a fused pass of a small numba kernel
(single sets above :data:`_COMPILED_MIN_ROWS` rows, and stacks); otherwise the equivalent
chunked (one set) or blocked (stacks) numpy code. Rows with NaN are dropped and counted.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from vidcap.errors import FitError

_CHUNK_ROWS = 8192  # rows per chunk of the one-pass moment loop (fits L2 with its buffers)
_COMPILED_MIN_ROWS = 2048  # single fits with at least this many rows use the compiled kernel
_BATCH_BYTES = 1 << 20  # bytes of points per block in the batched moment path


# --------------------------------------------------------------------------- moments
@dataclass(frozen=True)
class _Moments:
    """Central moment sums of point sets: n, mean, M2 = Σ y yᵀ, M3 = Σ y |y|², y = x - x̄."""

    n: np.ndarray  # (...,) float
    mean: np.ndarray  # (..., D)
    m2: np.ndarray  # (..., D, D)
    m3: np.ndarray  # (..., D)
    dropped: np.ndarray  # (...,) int


def _central_from_raw(n, p, s1, q, t):
    """Central sums from sums about a reference point p (z = x - p).

    With m = s1/n:  M2 = Q - n m mᵀ  and
    M3 = Σ (z-m)|z-m|² = T - 2 Q m - m tr Q + 2 n m |m|²  (expand and use Σz = n m).
    """
    nn = np.maximum(n, 1.0)
    m = s1 / nn[..., None]
    m2 = q - nn[..., None, None] * m[..., :, None] * m[..., None, :]
    trq = np.trace(q, axis1=-2, axis2=-1)
    mm = np.einsum("...i,...i->...", m, m)
    m3 = (
        t
        - 2.0 * np.einsum("...ij,...j->...i", q, m)
        - m * trq[..., None]
        + 2.0 * (nn * mm)[..., None] * m
    )
    return p + m, m2, m3


# --------------------------------------------------------------------------- compiled kernels
def _kernel_source():
    """Load the numba kernels (called once, lazily: importing numba costs ~0.3 s)."""
    from vidcap.mocap._spherefit_kernels import sums3_batch, sums3_single

    return sums3_single, sums3_batch


@functools.lru_cache(maxsize=1)
def _kernels():
    """The compiled D = 3 moment kernels, or None when numba is unavailable.

    Pure-numpy paths give the same results (to rounding) for every D; the kernels only
    make the D = 3 case (every mocap marker) one fused pass over the data.
    """
    try:
        return _kernel_source()
    except ImportError:  # pragma: no cover - numba is a declared dependency
        return None


def _unpack_sums3(o: np.ndarray):
    """(..., 12) kernel sums -> s1 (..., 3), q (..., 3, 3), t (..., 3)."""
    s1 = o[..., 0:3]
    q = o[..., [3, 4, 5, 4, 6, 7, 5, 7, 8]].reshape(*o.shape[:-1], 3, 3)
    t = o[..., 9:12]
    return s1, q, t


def _raw_compiled(x: np.ndarray):
    """Sums about p = x[0] of a C-contiguous (N, 3) array in one compiled pass, or None on NaN."""
    kern = _kernels()
    p = x[0].copy()
    out = np.empty(12)
    kern[0](x.reshape(-1), p, out)
    if not np.isfinite(out).all():
        return None
    s1, q, t = _unpack_sums3(out)
    return p, s1, q, t


def _raw_chunked(x: np.ndarray, chunk: int = _CHUNK_ROWS):
    """One pass over a C-contiguous (N, D) array: sums about p = x[0], or None on NaN/inf.

    Each chunk is shifted by p into an L2-resident buffer.  The products needed
    (z_a z_b for every pair, and z |z|²) are formed as *flat* contiguous
    element-wise products of the interleaved buffer with itself shifted by
    s = 0 … D-1 positions (position a of row i then holds z_a z_(a+s)); the
    per-column sums are BLAS matrix-vector products with a vector of ones.  This
    avoids numpy's slow small-inner-dimension broadcasting and BLAS's slow
    skinny matrix-matrix products.
    """
    n, d = x.shape
    p = x[0].copy()
    xf = x.reshape(-1)
    k = min(chunk, n)
    tile = np.tile(p, k)
    zbuf = np.zeros(d * k + d)  # padding so shifted views stay in bounds
    prod = np.empty(d * k)
    ones_k = np.ones(k)
    ones_d = np.ones(d)
    s1 = np.zeros(d)
    pair = np.zeros((d, d))  # pair[s, a] = Σ z_a z_(a+s)
    t = np.zeros(d)
    for start in range(0, n, k):
        m = min(k, n - start)
        md = m * d
        z = zbuf[:md]
        np.subtract(xf[start * d : start * d + md], tile[:md], out=z)
        zmat = z.reshape(m, d)
        ones = ones_k[:m]
        s1 += zmat.T @ ones
        np.multiply(z, z, out=prod[:md])
        sq = prod[:md].reshape(m, d)
        pair[0] += sq.T @ ones
        t += zmat.T @ (sq @ ones_d)
        for s in range(1, d):
            np.multiply(z, zbuf[s : md + s], out=prod[:md])
            pair[s] += prod[:md].reshape(m, d).T @ ones
    if not (np.isfinite(s1).all() and np.isfinite(t).all()):
        return None
    q = np.empty((d, d))
    for s in range(d):
        for a in range(d - s):
            q[a, a + s] = q[a + s, a] = pair[s, a]
    return p, s1, q, t


def _moments(x: np.ndarray) -> _Moments:
    """Central moment sums of point sets x, shape (..., N, D); NaN rows dropped."""
    x = np.asarray(x, dtype=float)
    if x.ndim < 2:
        raise FitError(f"points must have shape (..., N, D), got shape {x.shape}")
    *lead, nrow, d = x.shape
    if d < 2:
        raise FitError(f"points must have D >= 2 coordinates, got D = {d}")
    compiled = d == 3 and nrow >= _COMPILED_MIN_ROWS and _kernels() is not None
    if x.ndim == 2 and (compiled or nrow >= 4 * _CHUNK_ROWS):
        one_pass = _raw_compiled if compiled else _raw_chunked
        xc = np.ascontiguousarray(x)
        raw = one_pass(xc)
        dropped = 0
        if raw is None:  # NaN or inf somewhere: drop NaN rows and go again
            good = ~np.isnan(xc).any(axis=1)
            dropped = int(nrow - good.sum())
            xc = np.ascontiguousarray(xc[good])
            _check_count(np.array(len(xc)), d)
            if not np.isfinite(xc).all():
                raise FitError("points contain non-finite values (inf) after dropping NaN rows")
            raw = one_pass(xc)
        p, s1, q, t = raw
        nn = np.array(float(len(xc)))
        mean, m2, m3 = _central_from_raw(nn, p, s1, q, t)
        return _Moments(nn, mean, m2, m3, np.array(dropped))
    return _moments_batched(x.reshape(-1, nrow, d), tuple(lead))


def _moments_batched(x: np.ndarray, lead: tuple) -> _Moments:
    """Moments of a stack (B, N, D): compiled kernel for D = 3, else numpy blocks of sets."""
    b, nrow, d = x.shape
    kern = _kernels() if d == 3 and nrow > 0 else None
    if kern is None:
        p, s1, q, t, cnt, dropped = _raw_batched_numpy(x)
    else:
        out = np.empty((b, 15))
        kern[1](np.ascontiguousarray(x).reshape(b, nrow * 3), out)
        p = out[:, :3]
        s1, q, t = _unpack_sums3(out[:, 3:])
        cnt = np.full(b, float(nrow))
        dropped = np.zeros(b, dtype=np.int64)
        bad = ~np.isfinite(out).all(axis=1)
        if bad.any():  # sets with NaN rows (or inf): the numpy path drops and counts them
            p, s1, q, t = (np.array(a) for a in (p, s1, q, t))
            p[bad], s1[bad], q[bad], t[bad], cnt[bad], dropped[bad] = _raw_batched_numpy(x[bad])
    mean, m2, m3 = _central_from_raw(cnt, p, s1, q, t)
    return _Moments(
        cnt.reshape(lead),
        mean.reshape(*lead, d),
        m2.reshape(*lead, d, d),
        m3.reshape(*lead, d),
        dropped.reshape(lead),
    )


def _raw_batched_numpy(x: np.ndarray):
    """Sums about each set's first usable row of a stack (B, N, D), in cache-sized blocks.

    Returns p, s1, q, t (as :func:`_raw_chunked`, with a leading B axis), the usable
    counts (B,) and the dropped-row counts (B,).
    """
    b, nrow, d = x.shape
    s1 = np.empty((b, d))
    q = np.empty((b, d, d))
    t = np.empty((b, d))
    p = np.empty((b, d))
    cnt = np.full(b, float(nrow))
    dropped = np.zeros(b, dtype=np.int64)
    ones = np.ones(nrow)
    step = max(1, _BATCH_BYTES // max(1, nrow * d * 8))
    for s in range(0, b, step):
        xs = x[s : s + step]
        ref = xs[:, 0, :]
        if np.isnan(ref).any():
            ref = None
        z = xs - xs[:, :1, :] if ref is not None else None
        sq = None if z is None else np.einsum("bni,bni->bn", z, z)
        if z is None or not np.isfinite(sq).all():
            # slow path for this block: drop NaN rows by zero weights
            good = ~np.isnan(xs).any(axis=2)
            first = np.argmax(good, axis=1)
            ref = np.take_along_axis(xs, first[:, None, None], axis=1)[:, 0, :]
            ref = np.where(np.isnan(ref), 0.0, ref)
            z = np.where(good[..., None], xs - ref[:, None, :], 0.0)
            if not np.isfinite(z).all():
                raise FitError("points contain non-finite values (inf) after dropping NaN rows")
            sq = np.einsum("bni,bni->bn", z, z)
            cnt[s : s + step] = good.sum(axis=1)
            dropped[s : s + step] = nrow - good.sum(axis=1)
        p[s : s + step] = ref
        s1[s : s + step] = ones @ z
        q[s : s + step] = np.matmul(z.transpose(0, 2, 1), z)
        t[s : s + step] = np.matmul(sq[:, None, :], z)[:, 0, :]
    return p, s1, q, t, cnt, dropped


def _merge(a: _Moments, b: _Moments) -> _Moments:
    """Pébay-style merge of two sets of central sums (exact, no cancellation).

    With n = na + nb, δ = x̄b - x̄a, α = -δ nb/n (x̄a - x̄) and β = δ na/n:
    M2 = M2a + M2b + na nb/n δδᵀ;
    M3 = Σ over the two sets of  M3k + 2 M2k γk + tr(M2k) γk + nk |γk|² γk,  γ ∈ {α, β}.
    """
    n = a.n + b.n
    if n == 0:
        return a
    delta = b.mean - a.mean
    alpha = -delta * (b.n / n)
    beta = delta * (a.n / n)
    mean = a.mean - alpha
    m2 = a.m2 + b.m2 + (a.n * b.n / n) * np.outer(delta, delta)
    m3 = a.m3 + b.m3
    for mk, nk, g in ((a, a.n, alpha), (b, b.n, beta)):
        m3 = m3 + 2.0 * mk.m2 @ g + np.trace(mk.m2) * g + nk * (g @ g) * g
    return _Moments(n, mean, m2, m3, a.dropped + b.dropped)


def _check_count(n: np.ndarray, d: int, errors: str = "raise") -> np.ndarray:
    """Raise FitError when some set has fewer than D+1 usable points (unless errors='nan')."""
    bad = np.asarray(n) < d + 1
    if errors == "raise" and bad.any():
        idx = np.argwhere(bad)[0] if np.ndim(n) else ()
        where = f" (set {tuple(int(i) for i in idx)})" if np.ndim(n) else ""
        raise FitError(
            f"a sphere fit in {d} dimensions needs at least {d + 1} usable points, "
            f"got {int(np.asarray(n)[tuple(idx)])}{where} after dropping NaN rows"
        )
    return bad
