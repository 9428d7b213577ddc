"""The symmetric two-frame centre (SCoRE, Ehrig et al. 2006) and hinge axis (SARA,
Ehrig et al. 2007), for a joint whose child segment has frames of its own."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from vidcap.mocap.frames import to_lab
from vidcap.mocap.jointfit import axis_along_bone
from vidcap.mocap.solution import JointReport


def score(rp: np.ndarray, tp: np.ndarray, rc: np.ndarray, tc: np.ndarray, *,
          rot_cov_p=None, rot_cov_c=None, centroid_p=None, centroid_c=None) -> dict:
    """Symmetrical centre of rotation estimation (SCoRE, Ehrig et al. 2006) and the
    hinge axis of SARA (Ehrig et al. 2007), in closed form.

    The joint centre is a point fixed in both segments: c_p in the parent's frame
    and c_c in the child's. Minimise Σ_k |R_pk c_p + t_pk - R_ck c_c - t_ck|², a linear
    least-squares problem in x = (c_p, c_c): with A_k = [R_pk, -R_ck], b_k = t_ck - t_pk,
    (Σ A_kᵀ A_k) x = Σ A_kᵀ b_k. For a hinge the normal matrix has a (near) null vector
    (a_p, a_c): the hinge axis in both frames (SARA); every point of the axis fits.

    Parameters
    ----------
    rp, rc : numpy.ndarray, shape (F, 3, 3)
        Parent and child frames (columns = axes, lab); frames with NaN are skipped.
    tp, tc : numpy.ndarray, shape (F, 3)
        Their origins, lab.

    rot_cov_p, rot_cov_c : numpy.ndarray, shape (3, 3), optional, keyword-only
        Covariance (rad², in the segment's own axes) of each frame's small rotation
        error, for the noise correction below; with them ``centroid_p/_c`` (3,), the
        points about which the frames were fitted (their rotation and that point's
        position are then uncorrelated).

    Noise correction (ours, not in Ehrig et al.): with R̂ = R exp([ε]ₓ), ε ~ (0, Σ),
    E[R̂] = R (I - K/2), K = tr(Σ) I - Σ, so the normal equations built from noisy
    frames shrink every rotation by (I - K/2), which biases the centre by O(σ²/θ²)
    for a range of motion θ. About the centroids (positions independent of the
    rotation errors) the expected cross term is (I - K_p/2) Σ R_pᵀR_c (I - K_c/2) and
    the right-hand side's parts are shrunk by (I - K/2): both are un-shrunk here.

    Returns
    -------
    dict
        ``x`` (6,) least-squares solution (the minimum-norm one along the weakest
        direction), ``null`` (6,) unit eigenvector of the smallest eigenvalue,
        ``eig`` (6,) eigenvalues ascending, ``s2`` residual variance per coordinate
        (m²), ``n`` frames used; ``x`` is None when fewer than 10 frames are usable.
    """
    ok = (np.isfinite(rp).all(axis=(1, 2)) & np.isfinite(rc).all(axis=(1, 2))
          & np.isfinite(tp).all(axis=1) & np.isfinite(tc).all(axis=1))
    n = int(ok.sum())
    if n < 10:
        return {"x": None, "n": n}
    rp, tp, rc, tc = rp[ok], tp[ok], rc[ok], tc[ok]
    shift = np.zeros(6)
    dp = dc = np.eye(3)
    if rot_cov_p is not None and rot_cov_c is not None:
        tp = to_lab(rp, tp, centroid_p)
        tc = to_lab(rc, tc, centroid_c)
        shift = np.concatenate([centroid_p, centroid_c])
        dp = np.linalg.inv(np.eye(3) - 0.5 * (np.trace(rot_cov_p) * np.eye(3) - rot_cov_p))
        dc = np.linalg.inv(np.eye(3) - 0.5 * (np.trace(rot_cov_c) * np.eye(3) - rot_cov_c))
    # (the sums over frames as one (3F, 3) product each: Σ_f R_pᵀ R_c = P̃ᵀ C̃)
    rp_rows, rc_rows = rp.reshape(-1, 3), rc.reshape(-1, 3)
    cross = dp @ (rp_rows.T @ rc_rows) @ dc  # Σ R_pᵀ R_c
    m = np.zeros((6, 6))
    m[:3, :3] = n * np.eye(3)
    m[3:, 3:] = n * np.eye(3)
    m[:3, 3:] = -cross
    m[3:, :3] = -cross.T
    b = tc - tp
    rhs = np.concatenate([dp @ (rp_rows.T @ b.reshape(-1)),
                          -dc @ (rc_rows.T @ b.reshape(-1))])
    lam, vec = np.linalg.eigh(m)
    coef = vec.T @ rhs
    inv = np.where(lam > 1e-9 * lam[-1], 1.0 / np.maximum(lam, 1e-300), 0.0)
    x_full = vec @ (coef * inv)
    x_min = vec[:, 1:] @ (coef[1:] * inv[1:])  # without the weakest direction
    res = to_lab(rp, tp, x_full[:3]) - to_lab(rc, tc, x_full[3:])
    s2 = float(np.sum(res ** 2) / max(3 * n - 6, 1))
    x_full, x_min = x_full + shift, x_min + shift
    return {"x": x_full, "x_min": x_min, "null": vec[:, 0], "eig": lam, "s2": s2, "n": n}



def refine_score(sc: dict, rep: JointReport, anchor, max_axial_std_mm: float,
                  child_points: np.ndarray, anchor_what: str = "", bone_guard: bool = True):
    """The SCoRE/SARA centre in (parent, child) frames and the updated report.

    ``child_points`` (N, 3): the child's markers in the parent's frame (metres), which
    tell the bone's direction from ``anchor`` (:func:`axis_along_bone`).
    """
    lam, null, s2 = sc["eig"], sc["null"], sc["s2"]
    n_p = float(np.linalg.norm(null[:3]))
    # standard deviation of the parent-frame centre along the weakest direction
    std = (float(np.sqrt(s2 / lam[0]) * n_p) if lam[0] > 1e-12 * lam[-1]
           else float("inf"))
    hinge = anchor is not None and np.isfinite(anchor).all() and n_p > 0.3 and (
        rep.kind == "hinge" or std * 1e3 > max_axial_std_mm) and (
        not bone_guard or axis_along_bone(null[:3] / n_p, anchor, [child_points]) is None)
    if hinge:
        # SARA: the axis is the null direction; the point on it nearest the parent's
        # proximal joint (the hinge rule, see solve_joints)
        x = sc["x_min"]
        t = float((anchor - x[:3]) @ null[:3]) / n_p ** 2
        x = x + t * null
        axis = null[:3] / n_p
        kind, method = "hinge", "score+sara+axis-rule"
        note = (f"SARA axis; centre along it (std {std * 1e3:.0f} mm from the fit) placed "
                f"nearest {anchor_what or f'the {rep.parent_segment} proximal joint'}")
    else:
        x = sc["x"] if lam[0] > 1e-9 * lam[-1] else sc["x_min"]
        axis = np.asarray(rep.axis, dtype=float) if rep.axis is not None else None
        kind, method, note = rep.kind, "score", rep.note
    rep = replace(rep, kind=kind, method=method, note=note, axial_std_mm=std * 1e3,
                  axis=None if axis is None else [float(a) for a in axis],
                  center_local_m=[float(a) for a in x[:3]])
    return x[:3], x[3:], axis, rep


