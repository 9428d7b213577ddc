"""Compiled moment kernels of :mod:`vidcap.mocap.spherefit` (imported lazily).

They live at module level so numba's on-disk cache (``cache=True``) is found again by
later processes; kernels defined inside a function are recompiled in every process.
"""

import numba

# 'reassoc' lets LLVM split each running sum into SIMD partial sums (the loop then runs at
# ~2x the speed of reading the points); 'contract' allows FMA.  No 'nnan'/'ninf': a NaN or
# inf in the data must propagate to the sums, which is how callers detect it.
FASTMATH = {"reassoc", "contract"}

@numba.njit(cache=True, nogil=True, fastmath=FASTMATH, inline="always")
def sums3(xf, start, n, p0, p1, p2, out):
    """Raw sums of z = x - p over rows start..start+n of a flat (3N,) array, into out[0:12].

    out = [Σz (3), Σzzᵀ upper (00, 01, 02, 11, 12, 22), Σ|z|²z (3)].
    """
    s0 = s1 = s2 = 0.0
    q00 = q01 = q02 = q11 = q12 = q22 = 0.0
    t0 = t1 = t2 = 0.0
    for i in range(start, start + n):
        a = xf[3 * i] - p0
        b = xf[3 * i + 1] - p1
        c = xf[3 * i + 2] - p2
        r = a * a + b * b + c * c
        s0 += a
        s1 += b
        s2 += c
        q00 += a * a
        q01 += a * b
        q02 += a * c
        q11 += b * b
        q12 += b * c
        q22 += c * c
        t0 += r * a
        t1 += r * b
        t2 += r * c
    out[0] = s0
    out[1] = s1
    out[2] = s2
    out[3] = q00
    out[4] = q01
    out[5] = q02
    out[6] = q11
    out[7] = q12
    out[8] = q22
    out[9] = t0
    out[10] = t1
    out[11] = t2

@numba.njit(cache=True, nogil=True, fastmath=FASTMATH)
def sums3_single(xf, p, out):
    sums3(xf, 0, xf.shape[0] // 3, p[0], p[1], p[2], out)

@numba.njit(cache=True, nogil=True, fastmath=FASTMATH)
def sums3_batch(xb, out):
    """xb (B, 3N) C-contiguous; out (B, 15) = [p (3), sums (12)] with p = first row."""
    nrow = xb.shape[1] // 3
    for k in range(xb.shape[0]):
        row = xb[k]
        o = out[k]
        o[0] = row[0]
        o[1] = row[1]
        o[2] = row[2]
        sums3(row, 0, nrow, row[0], row[1], row[2], o[3:])

