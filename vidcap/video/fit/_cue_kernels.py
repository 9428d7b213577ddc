"""Compiled kernel of the cue terms (:func:`vidcap.video.fit.cues.arm_cue_terms`).

The same samples and arithmetic as the numpy path in :mod:`vidcap.video.fit.cues`
(bilinear samples, zero beyond the image), one pass per candidate without the
numpy path's (N, samples, 4) intermediates.
"""

from __future__ import annotations

import math

import numba
import numpy as np


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
