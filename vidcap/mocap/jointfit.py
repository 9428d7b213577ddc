"""One joint centre in its parent's frame from the child's markers: the multi-sphere fit
(MGDK/UGDK, :func:`vidcap.mocap.spherefit.mgdk`), its range of motion and residual, the
hinge rule for a centre not observable along one axis, and the flag-and-fallback when
the fit cannot be trusted."""

from __future__ import annotations

import functools

import numpy as np

from vidcap.errors import FitError
from vidcap.mocap.frames import _EPS, unit
from vidcap.mocap.markerset import SegmentSpec
from vidcap.mocap.solution import JointReport
from vidcap.mocap.spherefit import mgdk


@functools.lru_cache(maxsize=1)
def _kernels():
    """The compiled per-marker statistics (:mod:`vidcap.mocap._jointfit_kernels`), or
    None without numba: the numpy expressions below are then used."""
    try:
        from vidcap.mocap import _jointfit_kernels
    except ImportError:  # pragma: no cover - numba is a declared dependency
        return None
    return _jointfit_kernels


def cap_and_residual(sets: list[np.ndarray], center, radius, normal):
    """RMS radial residual (m) and 98th-percentile cap angle (deg) over marker sets."""
    radius = np.broadcast_to(np.asarray(radius, dtype=float), (len(sets),))
    hinge = normal is not None and np.isfinite(normal).all()
    compiled = _kernels()
    res2, n, caps = 0.0, 0, []
    for y, rp in zip(sets, radius, strict=True):
        if compiled is not None:
            r2, ang = compiled.radial_residual_angles(
                np.ascontiguousarray(y, dtype=float), np.asarray(center, dtype=float),
                float(rp), np.asarray(normal if hinge else np.zeros(3), dtype=float),
                hinge, _EPS)
            res2 += r2
            n += len(ang)
            caps.append(float(np.percentile(ang, 98)) if len(ang) else 0.0)
            continue
        d = y - center
        if hinge:
            d = d - (d @ normal)[:, None] * normal
        dist = np.linalg.norm(d, axis=1)
        res2 += float(np.sum((dist - rp) ** 2))
        n += len(dist)
        u = d / np.maximum(dist, _EPS)[:, None]
        mean = unit(u.mean(axis=0))
        ang = np.degrees(np.arccos(np.clip(u @ mean, -1.0, 1.0)))
        caps.append(float(np.percentile(ang, 98)) if len(ang) else 0.0)
    return (np.sqrt(res2 / n) if n else np.nan), (max(caps) if caps else 0.0)


def weak_axis(sets: list[np.ndarray], center: np.ndarray, sigma: float):
    """Direction and standard deviation (m) of the worst-determined centre coordinate.

    Fisher information of the centre with the per-marker radii eliminated:
    J = σ⁻² Σ_p N_p Cov_p(u) with u the unit directions from the centre (the
    multi-radius version of the bound in :func:`vidcap.mocap.spherefit.crlb`).
    """
    # Σ_p N_p Cov_p(u) = Σ_all u uᵀ - Σ_p N_p ū_p ū_pᵀ, with all markers at once
    sets = [y for y in sets if len(y) > 1]
    if not sets:
        return np.full(3, np.nan), float("inf")
    compiled = _kernels()
    if compiled is not None:
        info = np.zeros((3, 3))
        for y in sets:
            s, q = compiled.direction_sums(np.ascontiguousarray(y, dtype=float),
                                           np.asarray(center, dtype=float), _EPS)
            info += q - np.outer(s, s) / len(y)
        w, v = np.linalg.eigh(info / max(sigma, 1e-12) ** 2)
        return v[:, 0], float(np.inf if w[0] <= 0 else 1.0 / np.sqrt(w[0]))
    lens = np.array([len(y) for y in sets])
    u = unit(np.concatenate(sets) - center)
    u = np.where(np.isfinite(u), u, 0.0)
    sums = np.add.reduceat(u, np.r_[0, np.cumsum(lens)[:-1]], axis=0)  # (P, 3)
    info = u.T @ u - np.einsum("pi,pj,p->ij", sums, sums, 1.0 / lens)
    w, v = np.linalg.eigh(info / max(sigma, 1e-12) ** 2)
    std = np.inf if w[0] <= 0 else 1.0 / np.sqrt(w[0])
    return v[:, 0], float(std)


def pooled_covariance(sets: list[np.ndarray]) -> np.ndarray:
    """The markers' pooled within-marker covariance (3, 3), m²: Σ_p Σ_i (y - ȳ_p)(y - ȳ_p)ᵀ
    over all samples, / their count; ``sets`` non-empty (N_p, 3) arrays."""
    compiled = _kernels()
    if compiled is None:
        return sum(np.cov(y.T, bias=True) * len(y) for y in sets) / sum(map(len, sets))
    return (sum(compiled.scatter(np.ascontiguousarray(y, dtype=float)) for y in sets)
            / sum(map(len, sets)))


def axis_along_bone(axis, anchor, child_sets, *, max_deg: float = 45.0) -> float | None:
    """The angle (degrees) between a hinge axis and the bone, when it is under ``max_deg``.

    The bone runs from ``anchor`` (the parent's proximal joint, parent frame, metres)
    to the centroid of the child's markers (``child_sets``: arrays (N_k, 3) in the
    parent frame). A knee, elbow, ankle or wrist flexes about an axis across its bone;
    an axis along it means the motion is rotation about the limb's length (or noise
    in a parent frame built from few markers), where the hinge rule would put the
    centre next to the parent joint. None when the axis is across the bone or when
    anything needed is missing.
    """
    if axis is None or anchor is None or not np.isfinite(anchor).all():
        return None
    pts = [np.asarray(y, float) for y in child_sets if len(y)]
    if not pts:
        return None
    bone = np.concatenate(pts).mean(axis=0) - anchor
    norm = float(np.linalg.norm(bone)) * float(np.linalg.norm(axis))
    if not np.isfinite(norm) or norm <= 0:
        return None
    angle = float(np.degrees(np.arccos(min(1.0, abs(float(bone @ axis)) / norm))))
    return angle if angle < max_deg else None


def fit_joint(spec: SegmentSpec, parent: str, sets: list[np.ndarray], fallback_local,
               frames_used: int, *, noise_mm, min_cap_deg, planar_cond, anchor,
               max_axial_std_mm, hinge_ratio, frame_cov=None, anchor_what="",
               bone_guard=True) -> tuple:
    """Fit one joint centre in the parent's frame; returns (v (3,), axis or None, report).

    ``frame_cov`` (3, 3), in units of σ²: the extra noise the parent's frame adds to a
    child marker expressed in it (:func:`point_covariance`), added to the marker's
    own σ² I for UGDK when ``noise_mm`` is given.
    """
    usable = [y for y in sets if len(y) >= 4]
    note = ""
    fit = None
    if usable:
        try:
            cov = None
            if noise_mm is not None:
                extra = np.zeros((3, 3)) if frame_cov is None else frame_cov
                cov = (float(noise_mm) * 1e-3) ** 2 * (np.eye(3) + extra)
            fit = mgdk(usable, cov, planar_cond=planar_cond)
        except FitError as exc:
            note = f"fit failed ({exc})"
    else:
        note = "fewer than 4 samples of every marker"
    method = "mgdk" if noise_mm is None else "mgdk+ugdk"
    if fit is not None:
        kind = {"circle": "hinge"}.get(fit.kind, fit.kind)
        center = np.asarray(fit.center, dtype=float)
        normal = np.asarray(fit.normal, dtype=float) if kind == "hinge" else None
        if np.isfinite(center).all():
            rms, cap = cap_and_residual(usable, center, fit.radius, normal)
        else:
            rms, cap = np.nan, 0.0
        cond = float(fit.condition)
        if kind == "still" or not np.isfinite(center).all():
            note = "the markers did not move relative to the parent"
        elif cap < min_cap_deg:
            note = f"too little motion (cap angle {cap:.1f} deg < {min_cap_deg:g})"
    else:
        kind, center, normal = "still", np.full(3, np.nan), None
        rms, cap, cond = np.nan, 0.0, np.inf
    flagged = bool(note)
    axial_std = np.nan
    if not flagged and fit is not None:
        sigma = float(noise_mm) * 1e-3 if noise_mm is not None else float(rms)
        axis_w, axial_std = weak_axis(usable, center, sigma)
        if kind == "hinge":
            axis_w = normal
        # out-of-plane spread of the markers (pooled within-marker covariance)
        lam, vec = np.linalg.eigh(pooled_covariance(usable))
        thin = np.sqrt(max(lam[0], 0.0)) < hinge_ratio * sigma
        if thin and kind != "hinge":
            axis_w = vec[:, 0]
        rule = (anchor is not None and np.isfinite(anchor).all()
                and (kind == "hinge" or thin or axial_std * 1e3 > max_axial_std_mm))
        # (an anchor at the joint itself, landmarks straddling it, cannot slide it away)
        along = axis_along_bone(axis_w, anchor, usable) if rule and bone_guard else None
        if along is not None:
            # The rule below is for a bone flexing about an axis across it; an axis
            # within 45 degrees of the bone (rotation about the bone's own length, or
            # a badly defined parent frame) would slide the centre along the limb
            # toward the parent joint: no hinge to trust, so the fallback stands in.
            flagged = True
            note = (f"motion about an axis {along:.0f} deg from the bone, not across it: "
                    "the centre is not observable")
        elif rule:
            # Motion (nearly) about one axis: the centre's position along that axis is not
            # observable. Place it at the point of the axis nearest the anchor: landmarks
            # straddling the joint where the set names them, else the parent's proximal
            # joint (for a long bone flexing about an axis across it - knee, elbow, ankle,
            # wrist - that is where the bone's long axis meets the hinge axis).
            center = center + ((anchor - center) @ axis_w) * axis_w
            normal = axis_w
            kind = "hinge"
            method += "+axis-rule"
            note = (f"centre along the hinge axis (std {axial_std * 1e3:.0f} mm from the fit) "
                    f"placed nearest {anchor_what or f'the {parent} proximal joint'}")
    if flagged:
        v = fallback_local
        what = (f"centroid of {', '.join(spec.fallback)}" if spec.fallback
                else f"centroid of the {spec.name} markers")
        note += f"; fallback: {what} (constant in the {parent} frame)"
        method = "fallback"
    else:
        v = center
    report = JointReport(
        joint=spec.joint, segment=spec.name, parent_segment=parent, kind=kind, method=method,
        frames_used=int(frames_used), rms_residual_m=float(rms), condition=cond,
        cap_angle_deg=float(cap), axis=None if normal is None else [float(a) for a in normal],
        center_local_m=[float(a) for a in v], flagged=flagged, note=note,
        axial_std_mm=float(axial_std * 1e3),
    )
    return v, (normal if not flagged else None), report


