"""Compiled kernel of the cue terms (:func:`vidcap.video.fit.cues.arm_cue_terms`).

The same samples and arithmetic as the numpy path in :mod:`vidcap.video.fit.cues`
(bilinear samples, zero beyond the image), one pass per candidate without the
numpy path's (N, samples, 4) intermediates.
"""

from __future__ import annotations

import math

import numba


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
    """Edge strength across a border at ``(ax, ay) +- r (nx, ny)``: both sides summed."""
    total = 0.0
    for side in (-1.0, 1.0):
        px = ax + side * r * nx
        py = ay + side * r * ny
        a = _bilinear(stack, px, py, 1)
        b = _bilinear(stack, px, py, 2)
        c = _bilinear(stack, px, py, 3)
        v = nx * nx * a + 2.0 * nx * ny * b + ny * ny * c
        total += min(math.sqrt(max(v, 0.0)), 1.0)
    return total


@numba.njit(cache=True, nogil=True)
def arm_cue_terms(stack, shoulder, du, dl, len_u, len_l, r_u, r_l, t_skin, t_axis, skin, edge):
    """Skin and edge terms of whole-arm candidates into ``skin`` and ``edge`` (N,);
    see :func:`vidcap.video.fit.cues.arm_cue_terms`."""
    n_skin = t_skin.shape[0] * 3
    n_edge = t_axis.shape[0] * 4
    for b in range(du.shape[0]):
        ex = shoulder[0] + du[b, 0] * len_u
        ey = shoulder[1] + du[b, 1] * len_u
        lx = dl[b, 0] * len_l
        ly = dl[b, 1] * len_l
        nlx, nly = -dl[b, 1], dl[b, 0]
        nux, nuy = -du[b, 1], du[b, 0]
        s = 0.0
        for t in t_skin:
            ax = ex + lx * t
            ay = ey + ly * t
            for k in (-1.0, 0.0, 1.0):
                s += _bilinear(stack, ax + nlx * (0.5 * r_l * k), ay + nly * (0.5 * r_l * k), 0)
        skin[b] = s / n_skin
        e = 0.0
        for t in t_axis:
            e += _border(stack, shoulder[0] + du[b, 0] * len_u * t,
                         shoulder[1] + du[b, 1] * len_u * t, nux, nuy, r_u)
        for t in t_axis:
            e += _border(stack, ex + lx * t, ey + ly * t, nlx, nly, r_l)
        edge[b] = e / n_edge


__all__ = ["arm_cue_terms"]


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
