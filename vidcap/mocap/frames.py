"""Segment frames from markers: seed 000 §2.5's constructions, the rigid (Kabsch) fit
with gaps, and the noise a least-squares frame adds to a point rigidly attached to it.

A segment frame is a rotation ``r`` (F, 3, 3; columns = axes, lab frame) and an origin
``o`` (F, 3, metres) per frame; a point with constant local coordinates ``v`` is at
``o + r v`` in the lab (:func:`to_lab`) and lab points ``x`` at ``r^T (x - o)`` locally
(:func:`to_local`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

_EPS = 1e-9


def unit(v: np.ndarray) -> np.ndarray:
    """Unit vectors along the last axis (..., D); NaN where the length is ~0."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > _EPS, v / n, np.nan)


def frame_from_three(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Segment axes from three points (seed 000 §2.5, case 3; case 2 with p2 = the centre).

    The seed's formulas read x = p2 × p1 / |.|, z = p0 × x / |.|, y = z × x with the
    points relative to the frame's origin; as printed the origin is unspecified (and
    p0 relative to itself is 0), so we take the origin at p0 and a = p1 - p0,
    b = p2 - p0: x = (b × a)/|b × a| (normal of the plane), z = (a × x)/|a × x|,
    y = z × x (= -a/|a|). Right-handed: x × y = z.

    Parameters
    ----------
    p0, p1, p2 : numpy.ndarray, shape (..., 3)

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
        Columns x, y, z; NaN where the points are (nearly) collinear or missing.
    """
    a = p1 - p0
    b = p2 - p0
    n = np.cross(b, a)
    scale = np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1)
    with np.errstate(invalid="ignore"):
        bad = ~(np.linalg.norm(n, axis=-1) > 1e-3 * scale)
    x = unit(n)
    z = unit(np.cross(a, x))
    y = np.cross(z, x)
    m = np.stack([x, y, z], axis=-1)
    m[bad] = np.nan
    return m


def frame_from_axis(c: np.ndarray, p0: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Segment axes from one point, the joint centre and an axis (seed 000 §2.5, case 1).

    x is the axis made perpendicular to a = p0 - c, z = (a × x)/|.|, y = z × x.

    Parameters
    ----------
    c, p0, axis : numpy.ndarray, shape (..., 3)

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
    """
    a = unit(p0 - c)
    x = unit(axis - np.sum(axis * a, axis=-1, keepdims=True) * a)
    z = unit(np.cross(a, x))
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-1)


@functools.lru_cache(maxsize=1)
def _kernels():
    """The compiled kernels module (:mod:`vidcap.mocap._frames_kernels`), or None without
    numba (imported on first use: ~0.3 s)."""
    try:
        from vidcap.mocap import _frames_kernels
    except ImportError:  # pragma: no cover - numba is a declared dependency
        return None
    return _frames_kernels


def _rotations_numpy(h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotations R (F, 3, 3) with x ≈ R t from cross-covariances h = Σ w t xᵀ (F, 3, 3),
    and h's singular values (F, 3), descending: the SVD solution (Kabsch 1976)."""
    u, s, vt = np.linalg.svd(h)
    v = np.swapaxes(vt, 1, 2)
    d = np.sign(_det3(u) * _det3(v))  # det(V Uᵀ): a reflection when negative
    d = np.where(d == 0, 1.0, d)
    v[:, :, 2] *= d[:, None]
    return np.matmul(v, np.swapaxes(u, 1, 2)), s


def _rotations(h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_rotations_numpy`'s contract; the compiled quaternion fit when available."""
    compiled = _kernels()
    if compiled is None:
        return _rotations_numpy(h)
    return compiled.rotations_from_cross(np.ascontiguousarray(h, dtype=float))


def _det3(m: np.ndarray) -> np.ndarray:
    """Determinants of a stack of 3x3 matrices (..., 3, 3), by the triple product."""
    return np.sum(m[..., 0] * np.cross(m[..., 1], m[..., 2]), axis=-1)


def kabsch(template: np.ndarray, points: np.ndarray, weights: np.ndarray | None = None
           ) -> tuple[np.ndarray, np.ndarray]:
    """Rigid poses mapping a template onto points with gaps, batched over frames.

    Parameters
    ----------
    template : numpy.ndarray, shape (K, 3)
        Local coordinates of K points.
    points : numpy.ndarray, shape (F, K, 3)
        Observed positions; NaN rows are ignored.
    weights : numpy.ndarray, shape (K,) or (F, K), optional
        Non-negative weight of each point (inverse variance relative to a marker);
        default 1.

    Returns
    -------
    rotation : numpy.ndarray, shape (F, 3, 3)
        ``points ≈ origin + rotation @ template``; NaN where fewer than 3 non-collinear
        points are present.
    origin : numpy.ndarray, shape (F, 3)
    """
    compiled = _kernels()
    if compiled is None:
        return _kabsch_numpy(template, points, weights)
    points = np.ascontiguousarray(points, dtype=float)
    shape = points.shape[:2]
    wf = (np.ones(shape) if weights is None else
          np.ascontiguousarray(np.broadcast_to(np.asarray(weights, dtype=float), shape)))
    r, o, state, aux = compiled.kabsch_frames(np.ascontiguousarray(template, dtype=float),
                                              points, wf, _EPS)
    compiled.kabsch_finish(r, o, state, aux, _EPS)
    return r, o


def _kabsch_numpy(template: np.ndarray, points: np.ndarray, weights: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`kabsch` in numpy (batched over frames; the rotation fit by
    :func:`_rotations`): the path without numba, and the reference for the kernel."""
    w = np.isfinite(points).all(axis=2) & np.isfinite(template).all(axis=1)  # (F, K)
    cnt = w.sum(axis=1)
    wf = w.astype(float)
    if weights is not None:
        wf = wf * np.broadcast_to(np.asarray(weights, dtype=float), w.shape)
        wf = np.where(np.isfinite(wf), wf, 0.0)
        w = wf > 0
        cnt = w.sum(axis=1)
    x = np.where(w[..., None], points, 0.0)
    t = np.where(np.isfinite(template), template, 0.0)
    wt = wf[..., None]
    den = np.maximum(wf.sum(axis=1), _EPS)[:, None]
    xc = (wt * x).sum(1) / den
    tc = (wt * t[None]).sum(1) / den
    # (matmul, not three-operand einsums: this runs once per segment and frame)
    h = np.matmul(np.swapaxes(wt * (t[None] - tc[:, None]), 1, 2), x - xc[:, None])
    r, s = _rotations(h)
    ok = (cnt >= 3) & (s[:, 1] > 1e-6 * np.maximum(s[:, 0], _EPS))
    r[~ok] = np.nan
    origin = xc - np.matmul(r, tc[..., None])[..., 0]
    origin[~ok] = np.nan
    return r, origin


def point_covariance(template: np.ndarray, v: np.ndarray, weights: np.ndarray | None = None
                     ) -> np.ndarray:
    """Covariance of a rigidly attached point predicted by a least-squares (Kabsch) frame.

    For K points with isotropic noise σ² / w_k fitted rigidly, the pose errors are a
    translation with covariance σ² I / Σw and a small rotation with covariance
    σ² Iₘ⁻¹, Iₘ = Σ w_k (|m_k|² I - m_k m_kᵀ) the weighted inertia of the template about
    its weighted centroid. A point v then has covariance
    σ² (I / Σw + [p]ₓ Iₘ⁻¹ [p]ₓᵀ), p = v - centroid, in the frame's own coordinates.

    Parameters
    ----------
    template : numpy.ndarray, shape (K, 3)
        The frame's points in its own coordinates (NaN rows ignored).
    v : numpy.ndarray, shape (3,) or (P, 3)
        The point, or several (the template's inertia inverted once), same coordinates.
    weights : numpy.ndarray, shape (K,), optional

    Returns
    -------
    numpy.ndarray, shape (3, 3) or (P, 3, 3)
        In units of σ² (all inf if undetermined).
    """
    v = np.asarray(v, dtype=float)
    pts = v.reshape(-1, 3)
    out = np.full((len(pts), 3, 3), np.inf)
    c, inv, wsum = _template_inertia(template, weights)
    if c is not None:
        for k, q in enumerate(pts):
            if np.isfinite(q).all():
                p = q - c
                px = np.array([[0.0, -p[2], p[1]], [p[2], 0.0, -p[0]], [-p[1], p[0], 0.0]])
                out[k] = np.eye(3) / wsum + px @ inv @ px.T
    return out[0] if v.ndim == 1 else out


def point_variance(template: np.ndarray, v: np.ndarray, weights: np.ndarray | None = None
                   ) -> float:
    """Trace of :func:`point_covariance` (units of σ²; inf if undetermined)."""
    return float(np.trace(point_covariance(template, v, weights)))


def frame_noise(template: np.ndarray, weights: np.ndarray | None):
    """Weighted centroid (3,) and inverse inertia (3, 3) of a frame's template; (None,
    None) with fewer than 3 points or a singular inertia."""
    c, inv, _ = _template_inertia(template, weights)
    return c, inv


def _template_inertia(template: np.ndarray, weights: np.ndarray | None):
    """The template's weighted centroid (3,), inverse inertia (3, 3) about it and weight
    sum, over its finite rows of positive weight (:func:`point_covariance`); Nones with
    fewer than 3 of them or a singular inertia."""
    t = np.asarray(template, dtype=float)
    w = np.ones(len(t)) if weights is None else np.asarray(weights, dtype=float)
    ok = np.isfinite(t).all(axis=1) & np.isfinite(w) & (w > 0)
    if ok.sum() < 3:
        return None, None, None
    t, w = t[ok], w[ok]
    c = (w[:, None] * t).sum(0) / w.sum()
    m = t - c
    inertia = (w * (m * m).sum(1)).sum() * np.eye(3) - np.einsum("k,ki,kj->ij", w, m, m)
    try:
        return c, np.linalg.inv(inertia), w.sum()
    except np.linalg.LinAlgError:
        return None, None, None


def nanmean_points(y: np.ndarray) -> np.ndarray:
    """``np.nanmean(y, axis=1)`` for points (F, K, 3) -> (F, 3), bit for bit, without
    its warnings and overhead (NaN where a frame has none)."""
    compiled = _kernels()
    if compiled is not None and y.ndim == 3 and y.shape[2] == 3:
        return compiled.mean_over_points(np.ascontiguousarray(y, dtype=float))
    nan = np.isnan(y)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(nan, 0.0, y).sum(axis=1) / (~nan).sum(axis=1)


def to_local(r: np.ndarray, o: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Lab points x (F, K, 3) in frames (r (F,3,3), o (F,3)): r^T (x - o)."""
    compiled = _kernels()
    if compiled is not None and x.ndim == 3 and r.shape[0] == o.shape[0] == x.shape[0]:
        return compiled.points_to_local(np.ascontiguousarray(r, dtype=float),
                                        np.ascontiguousarray(o, dtype=float),
                                        np.ascontiguousarray(x, dtype=float))
    return np.matmul(x - o[:, None], r)  # row k: (x_k - o)ᵀ r = (rᵀ (x_k - o))ᵀ


def to_lab(r: np.ndarray, o: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Constant local point v (3,) per frame in the lab: o + r v, (F, 3)."""
    v = np.asarray(v, dtype=float)
    compiled = _kernels()
    if compiled is not None and v.shape == (3,) and r.shape[0] == o.shape[0]:
        return compiled.point_to_lab(np.ascontiguousarray(r, dtype=float),
                                     np.ascontiguousarray(o, dtype=float), v)
    return o + np.matmul(r, v)


def nanmedian_rows(y: np.ndarray) -> np.ndarray:
    """Median over axis 0 of the rows without NaN (or inf), without warnings (none ->
    NaN); y (N, D) or (N, ...)."""
    compiled = _kernels() if y.ndim == 2 else None
    if compiled is not None:
        return compiled.median_finite_rows(np.ascontiguousarray(y, dtype=float))
    ok = np.isfinite(y).all(axis=-1)
    if not ok.any():
        return np.full(y.shape[1:], np.nan)
    return np.median(y[ok], axis=0)


@dataclass(frozen=True)
class SegFrames:
    """One segment's frames over a trial: rotations ``r`` (F, 3, 3; columns = axes, lab),
    origins ``o`` (F, 3, metres), the template (K, 3) of its points in its own frame
    and their weights (relative inverse variances; None: all 1)."""

    r: np.ndarray  # (F, 3, 3)
    o: np.ndarray  # (F, 3)
    template: np.ndarray  # (K, 3)
    weights: np.ndarray | None = None  # (K,) relative inverse variances, None = all 1

    @property
    def valid(self) -> np.ndarray:
        """(F,) bool: frames whose rotation is known."""
        return np.isfinite(self.r).all(axis=(1, 2))


def frames_from_points(pts: np.ndarray) -> SegFrames:
    """Frames from K >= 3 points (F, K, 3): seed case 3 on the first three, Kabsch fill.

    The template is each point's median position in the frame of the first three
    points (seed 000 §2.5 case 3); every frame with >= 3 points then gets the
    least-squares rigid pose of the template (the seed's construction puts all the
    noise of three points into the axes; this spreads it over all points, and fills
    frames whose primary three points are incomplete).
    """
    compiled = _kernels()
    if compiled is None:
        return _frames_from_points_numpy(pts)
    pts = np.ascontiguousarray(pts, dtype=float)
    template = compiled.three_point_template(pts, _EPS)
    r, o = kabsch(template, pts)
    return SegFrames(r, o, template)


def _frames_from_points_numpy(pts: np.ndarray) -> SegFrames:
    """:func:`frames_from_points` in numpy: the path without numba, and the reference."""
    r = frame_from_three(pts[:, 0], pts[:, 1], pts[:, 2])
    o = pts[:, 0].copy()
    ok = np.isfinite(r).all(axis=(1, 2)) & np.isfinite(o).all(axis=1)
    r[~ok] = np.nan
    o[~ok] = np.nan
    local = to_local(np.where(ok[:, None, None], r, 0.0), np.where(ok[:, None], o, 0.0), pts)
    local[~ok] = np.nan
    template = np.stack([nanmedian_rows(local[:, k]) for k in range(pts.shape[1])])
    if not ok.any():
        return SegFrames(r, o, template)
    has3 = np.isfinite(pts).all(axis=2).sum(axis=1) >= 3
    rf, of = kabsch(template, pts[has3])
    r[has3] = rf
    o[has3] = of
    return SegFrames(r, o, template)


def frames_from_centre_axis(c: np.ndarray, p0: np.ndarray, axis_lab: np.ndarray) -> SegFrames:
    """Frames of a one-marker segment (seed 000 §2.5 case 1): origin at the joint centre
    ``c`` (F, 3), axes from the marker ``p0`` (F, 3) and the lab axis (F, 3)."""
    r = frame_from_axis(c, p0, axis_lab)
    o = c.copy()
    ok = np.isfinite(r).all(axis=(1, 2)) & np.isfinite(o).all(axis=1)
    r[~ok] = np.nan
    o[~ok] = np.nan
    return SegFrames(r, o, np.zeros((0, 3)))



def rigid_residual_var(frames: list[SegFrames], pts: list[np.ndarray]) -> float:
    """Per-coordinate marker noise variance (m²) from rigid-fit residuals of K >= 3 points.

    Each frame's least-squares pose uses 6 of its 3K coordinates, so
    σ̂² = Σ |x - o - R m|² / Σ_frames (3K - 6) (the template's own error neglected).
    """
    ss, dof = 0.0, 0
    compiled = _kernels()
    for f, x in zip(frames, pts, strict=True):
        if compiled is not None:
            s1, d1 = compiled.rigid_residuals(
                np.ascontiguousarray(f.r, dtype=float), np.ascontiguousarray(f.o, dtype=float),
                np.ascontiguousarray(f.template[: x.shape[1]], dtype=float),
                np.ascontiguousarray(x, dtype=float))
            ss, dof = ss + s1, dof + d1
            continue
        pred = f.o[:, None] + np.matmul(f.template[: x.shape[1]], np.swapaxes(f.r, 1, 2))
        res = np.sum((x - pred) ** 2, axis=2)  # (F, K)
        ok = np.isfinite(res)
        k = ok.sum(axis=1)
        use = k >= 3
        ss += float(res[use][ok[use]].sum())
        dof += int(np.sum(3 * k[use] - 6))
    return ss / dof if dof > 0 else 0.0


