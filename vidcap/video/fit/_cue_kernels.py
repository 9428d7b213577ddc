"""Compiled kernel of the cue terms (:func:`vidcap.video.fit.cues.arm_cue_terms`).

The same samples and arithmetic as the numpy path in :mod:`vidcap.video.fit.cues`
(bilinear samples, zero beyond the image), one pass per candidate without the
numpy path's (N, samples, 4) intermediates.
"""

from __future__ import annotations

import math
from pathlib import Path

import numba
import numpy as np

from vidcap.kernelcache import refresh_when_changed
from vidcap.video.fit._kernels import arm_pair_terms


@numba.njit(cache=True, nogil=True, inline="always")
def _bilinear(stack, x, y, c):
    """``stack[..., c]`` at ``(x, y)``, bilinear, zero beyond the image."""
    h, w = stack.shape[0], stack.shape[1]
    x0 = math.floor(x)
    y0 = math.floor(y)
    fx = x - x0
    fy = y - y0
    out = 0.0
    for dy in range(2):
        yy = int(y0) + dy
        if yy < 0 or yy >= h:
            continue
        wy = fy if dy else 1.0 - fy
        for dx in range(2):
            xx = int(x0) + dx
            if xx < 0 or xx >= w:
                continue
            wx = fx if dx else 1.0 - fx
            out += wy * wx * stack[yy, xx, c]
    return out


@numba.njit(cache=True, nogil=True, inline="always")
def _border(stack, ax, ay, nx, ny, r):
    """Edge strength across a border at ``(ax, ay) +- r (nx, ny)``: both sides summed.

    The structure tensor's three channels are read with one set of bilinear weights
    (each channel's sum in :func:`_bilinear`'s order: the same floats)."""
    h, w = stack.shape[0], stack.shape[1]
    total = 0.0
    for side in (-1.0, 1.0):
        px = ax + side * r * nx
        py = ay + side * r * ny
        x0 = math.floor(px)
        y0 = math.floor(py)
        fx = px - x0
        fy = py - y0
        a = 0.0
        b = 0.0
        c = 0.0
        for dy in range(2):
            yy = int(y0) + dy
            if yy < 0 or yy >= h:
                continue
            wy = fy if dy else 1.0 - fy
            for dx in range(2):
                xx = int(x0) + dx
                if xx < 0 or xx >= w:
                    continue
                wx = fx if dx else 1.0 - fx
                a += wy * wx * stack[yy, xx, 1]
                b += wy * wx * stack[yy, xx, 2]
                c += wy * wx * stack[yy, xx, 3]
        v = nx * nx * a + 2.0 * nx * ny * b + ny * ny * c
        total += min(math.sqrt(max(v, 0.0)), 1.0)
    return total


@numba.njit(cache=True, nogil=True)
def arm_cue_terms(stack, shoulder, du, dl, len_u, len_l, r_u, r_l, t_skin, t_axis, skin, edge):
    """Skin and edge terms of whole-arm candidates into ``skin`` and ``edge`` (N,);
    see :func:`vidcap.video.fit.cues.arm_cue_terms`.

    The candidates of one upper arm direction (consecutive rows of ``du``, as the
    grids list them) share its border samples: summed once per direction (the same
    partial sum, so the same floats). A lower arm whose samples all read pixels of the
    image (most) is sampled here, in :func:`_bilinear` and :func:`_border`'s order (the
    same floats) but without calls: a call that takes an array counts references to it
    (atomic, a third of the time when each sample was a call)."""
    h, w = stack.shape[0], stack.shape[1]
    n_t, n_a = t_skin.shape[0], t_axis.shape[0]
    n_s = 3 * n_t
    n = n_s + 2 * n_a
    xs, ys, v = np.empty(n), np.empty(n), np.empty(n)
    wt, at = np.empty((4, n)), np.empty((2, n), np.int64)
    prev_x, prev_y = np.nan, np.nan
    e_up = 0.0
    for b in range(du.shape[0]):
        ex = shoulder[0] + du[b, 0] * len_u
        ey = shoulder[1] + du[b, 1] * len_u
        lx = dl[b, 0] * len_l
        ly = dl[b, 1] * len_l
        nlx, nly = -dl[b, 1], dl[b, 0]
        if not (du[b, 0] == prev_x and du[b, 1] == prev_y):  # a new upper arm
            prev_x, prev_y = du[b, 0], du[b, 1]
            nux, nuy = -du[b, 1], du[b, 0]
            e_up = 0.0
            for t in t_axis:
                e_up += _border(stack, shoulder[0] + du[b, 0] * len_u * t,
                                shoulder[1] + du[b, 1] * len_u * t, nux, nuy, r_u)
        for i in range(n_t):  # skin: across the forearm at each t
            ax = ex + lx * t_skin[i]
            ay = ey + ly * t_skin[i]
            for k in range(3):
                off = 0.5 * r_l * (k - 1.0)
                xs[3 * i + k] = ax + nlx * off
                ys[3 * i + k] = ay + nly * off
        for i in range(n_a):  # edges: either side of the axis at each t
            ax = ex + lx * t_axis[i]
            ay = ey + ly * t_axis[i]
            for k in range(2):
                side = 2.0 * k - 1.0
                xs[n_s + 2 * i + k] = ax + side * r_l * nlx
                ys[n_s + 2 * i + k] = ay + side * r_l * nly
        inside = True
        for i in range(n):
            inside &= (xs[i] >= 0.0) & (ys[i] >= 0.0) & (xs[i] < w - 1.0) & (ys[i] < h - 1.0)
        s = 0.0
        e = e_up
        if not inside:  # the samples beyond the image read zero
            for i in range(n_s):
                s += _bilinear(stack, xs[i], ys[i], 0)
            for i in range(n_a):
                e += _border(stack, ex + lx * t_axis[i], ey + ly * t_axis[i], nlx, nly, r_l)
            skin[b] = s / n_s
            edge[b] = e / (4 * n_a)
            continue
        for i in range(n):
            x0 = np.floor(xs[i])
            y0 = np.floor(ys[i])
            fx = xs[i] - x0
            fy = ys[i] - y0
            wt[0, i] = (1.0 - fy) * (1.0 - fx)
            wt[1, i] = (1.0 - fy) * fx
            wt[2, i] = fy * (1.0 - fx)
            wt[3, i] = fy * fx
            at[0, i] = int(y0)
            at[1, i] = int(x0)
        for i in range(n_s):
            yy, xx = at[0, i], at[1, i]
            out = 0.0
            out += wt[0, i] * stack[yy, xx, 0]
            out += wt[1, i] * stack[yy, xx + 1, 0]
            out += wt[2, i] * stack[yy + 1, xx, 0]
            out += wt[3, i] * stack[yy + 1, xx + 1, 0]
            s += out
        for i in range(n_s, n):
            yy, xx = at[0, i], at[1, i]
            ta = 0.0
            tb = 0.0
            tc = 0.0
            for c, (py, px) in enumerate(((yy, xx), (yy, xx + 1), (yy + 1, xx), (yy + 1, xx + 1))):
                ta += wt[c, i] * stack[py, px, 1]
                tb += wt[c, i] * stack[py, px, 2]
                tc += wt[c, i] * stack[py, px, 3]
            v[i] = nlx * nlx * ta + 2.0 * nlx * nly * tb + nly * nly * tc
        for i in range(n_s, n):
            v[i] = min(math.sqrt(max(v[i], 0.0)), 1.0)
        for i in range(n_a):
            total = 0.0
            total += v[n_s + 2 * i]
            total += v[n_s + 2 * i + 1]
            e += total
        skin[b] = s / n_s
        edge[b] = e / (4 * n_a)


@numba.njit(cache=True, nogil=True)
def arm_cue_grid(stack, shoulder, du, dl, lens, r_u, r_l, t_skin, t_axis, skin, edge):
    """:func:`arm_cue_terms` of one grid at several drawn lengths: row f of ``skin``
    and ``edge`` (F, N) with the upper and lower arm ``lens[f]`` (F, 2) long."""
    for f in range(lens.shape[0]):
        arm_cue_terms(stack, shoulder, du, dl, lens[f, 0], lens[f, 1], r_u, r_l, t_skin,
                      t_axis, skin[f], edge[f])


@numba.njit(cache=True, nogil=True)
def arm_j_grid(ua, la, du, dl, shoulder, lens, radii, cum, y0, y1, caps, a, m0, i0, stack,
               r_u, r_l, t_skin, t_axis, prior, held, weights, x, q, skin, edge, j):
    """J of whole-arm candidates at several drawn lengths into ``j`` (F, N), in one
    call: S (:func:`vidcap.video.fit._kernels.arm_pair_terms`, exp(-p - n) (1 - p))
    and the cue terms (:func:`arm_cue_terms`) of each candidate at each length
    ``lens[f]`` (F, 2), and the pull of the prior: J = S + w_skin skin + w_edge edge -
    w_prior (held[0] gap(ua, prior[0]) + held[1] gap(la, prior[1])), ``weights`` =
    (w_skin, w_edge, w_prior), added in the numpy path's order (its floats);
    ``x``, ``q``, ``skin``, ``edge`` (F, N) are scratch. See
    :func:`vidcap.video.fit.cues.search_arm_cues`."""
    for f in range(lens.shape[0]):
        arm_pair_terms(du, dl, shoulder, lens[f, 0], lens[f, 1], radii, cum, y0, y1, caps,
                       a, m0, i0, x[f], q[f])
        arm_cue_terms(stack, shoulder, du, dl, lens[f, 0], lens[f, 1], r_u, r_l, t_skin,
                      t_axis, skin[f], edge[f])
    for b in range(ua.shape[0]):
        gap = held[0] * _gap(ua[b], prior[0]) + held[1] * _gap(la[b], prior[1])
        for f in range(lens.shape[0]):
            sim = math.exp(x[f, b]) * q[f, b]
            j[f, b] = sim + weights[0] * skin[f, b] + weights[1] * edge[f, b] - weights[2] * gap


@numba.njit(cache=True, nogil=True)
def scale_tensor(stack, s):
    """``stack[..., 1:] *= s`` (float32), in place: the edge channels of
    :func:`cue_stack`'s output scaled (numpy's strided multiply is slow here)."""
    h, w = stack.shape[0], stack.shape[1]
    for i in range(h):
        for j in range(w):
            for c in range(1, 4):
                stack[i, j, c] *= s


@numba.njit(cache=True, nogil=True)
def masked_copy(stack, mask, out):
    """``out = stack``, zero where ``mask`` (h, w) is set (every channel)."""
    h, w, c = stack.shape
    for i in range(h):
        for j in range(w):
            m = mask[i, j]
            for k in range(c):
                out[i, j, k] = 0.0 if m else stack[i, j, k]


@numba.njit(cache=True, nogil=True)
def fine_grid(u0, l0, du, dl, max_bend, here, ua, la, dirs_u, dirs_l):
    """:func:`vidcap.video.fit.cues._fine_grid` into ``ua``, ``la`` (N + 1,) and
    ``dirs_u``, ``dirs_l`` (N + 1, 2) of the offsets ``du``, ``dl`` (N,) about
    ``(u0, l0)``, and with ``here`` ``(u0, l0)`` itself last, whatever its bend;
    returns how many pairs it wrote (the first rows)."""
    n = 0
    two_pi = 2 * np.pi
    for i in range(du.shape[0] + 1):
        if i == du.shape[0] and not here:
            break
        last = i == du.shape[0]
        u = u0 if last else u0 + du[i]
        v = l0 if last else l0 + dl[i]
        if last or _gap(v, u) <= max_bend:
            u = np.mod(u, two_pi)
            v = np.mod(v, two_pi)
            ua[n] = u
            la[n] = v
            dirs_u[n, 0] = np.cos(u)
            dirs_u[n, 1] = -np.sin(u)
            dirs_l[n, 0] = np.cos(v)
            dirs_l[n, 1] = -np.sin(v)
            n += 1
    return n


@numba.njit(cache=True, nogil=True)
def _gap(a, b):
    """|a - b| wrapped to [0, pi] (:func:`vidcap.video.fit.limits.angle_gap`)."""
    return abs(np.mod(a - b + np.pi, 2 * np.pi) - np.pi)


@numba.njit(cache=True, nogil=True)
def greedy_apart(ua, la, jj, u0, l0, apart, keep):
    """:func:`vidcap.video.fit.cues._greedy_apart` into ``keep`` (K,): returns how
    many it kept (at most K)."""
    n = ua.shape[0]
    order = np.argsort(-jj, kind="mergesort")  # stable: ties in listed order
    ku = np.empty(keep.shape[0] + 1)
    kl = np.empty(keep.shape[0] + 1)
    ku[0], kl[0] = u0, l0
    m = 0
    for i in range(n):
        if m >= keep.shape[0]:
            break
        k = order[i]
        ok = True
        for j in range(m + 1):
            if _gap(ku[j], ua[k]) + _gap(kl[j], la[k]) < apart:
                ok = False
                break
        if ok:
            keep[m] = k
            m += 1
            ku[m], kl[m] = ua[k], la[k]
    return m


__all__ = ["arm_cue_grid", "arm_cue_terms", "arm_j_grid", "cue_stack", "fine_grid",
           "greedy_apart", "masked_copy", "scale_tensor"]


@numba.njit(cache=True, nogil=True)
def cue_stack(img, gx, gy, sil, inside, table, n_bins, bins, stack, energy):
    """Per pixel: the chromaticity bin (into ``bins``), the skin likelihood from
    ``table`` (empty: none yet) within ``sil``, and the structure tensor ``Jxx, Jxy, Jyy``
    of the Sobel images ``gx``, ``gy`` (h, w, 3) within ``inside`` (into ``stack``,
    unscaled); returns how many of ``energy`` (``Jxx + Jyy`` inside) it filled. See
    :func:`vidcap.video.fit.cues.cue_maps`."""
    h, w = sil.shape
    n = 0
    have = table.shape[0] > 0
    for i in range(h):
        for j in range(w):
            tot = img[i, j, 0] + img[i, j, 1] + img[i, j, 2] + 3.0
            r = (img[i, j, 2] + 1.0) / tot
            g = (img[i, j, 1] + 1.0) / tot
            ri = min(int(r * n_bins), n_bins - 1)
            gi = min(int(g * n_bins), n_bins - 1)
            k = ri * n_bins + gi
            bins[i, j] = k
            stack[i, j, 0] = table[k] if have and sil[i, j] else 0.0
            if inside[i, j]:
                a = 0.0
                b = 0.0
                c = 0.0
                for ch in range(3):
                    x = gx[i, j, ch]
                    y = gy[i, j, ch]
                    a += x * x
                    b += x * y
                    c += y * y
                stack[i, j, 1] = a
                stack[i, j, 2] = b
                stack[i, j, 3] = c
                energy[n] = a + c
                n += 1
            else:
                stack[i, j, 1] = 0.0
                stack[i, j, 2] = 0.0
                stack[i, j, 3] = 0.0
    return n


# arm_pair_terms and its helpers are inlined from _kernels, whose constants come from
# modes: numba's cache would not see a change there (vidcap.kernelcache)
refresh_when_changed(globals(), [Path(__file__).with_name("_kernels.py"),
                                 Path(__file__).with_name("modes.py")])
