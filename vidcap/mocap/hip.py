"""Hip joint centres from the pelvis landmarks, and where a gait trial needs them.

A walk swings the thigh in one plane: across it the sphere fit reads soft-tissue
motion as the centre's position. The components along directions in which the thigh
swung less than :data:`MIN_SWING_DEG` come from the Harrington et al. (2007)
regression instead (:func:`regress_hip`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from vidcap.mocap.frames import nanmedian_rows, to_local, unit
from vidcap.mocap.markerset import SegmentSpec
from vidcap.mocap.solution import JointReport

#: A hip centre's component along a direction in which the thigh's markers swung by
#: less than this (angular standard deviation about the centre, degrees) comes from
#: the regression when the marker set has one: over a few degrees the sphere fit
#: reads soft-tissue motion as the centre's position.
MIN_SWING_DEG = 10.0


def hip_regression(asis_left, asis_right, psis) -> tuple[np.ndarray, np.ndarray]:
    """Hip joint centres from pelvis landmarks (Harrington et al., J Biomech 40:595, 2007).

    In the pelvis frame at the mid-ASIS point (x anterior, y superior, z right):
    ``x = -0.24 PD - 9.9 mm``, ``y = -0.30 PW - 10.9 mm``, ``z = +-(0.33 PW + 7.3 mm)``,
    with PW the inter-ASIS distance and PD the mid-ASIS to mid-PSIS distance.

    Parameters
    ----------
    asis_left, asis_right : numpy.ndarray, shape (F, 3)
        Anterior superior iliac spine markers, metres.
    psis : sequence of numpy.ndarray, each (F, 3)
        The two posterior superior iliac spine markers, or one sacrum marker.

    Returns
    -------
    left, right : numpy.ndarray, shape (F, 3)
        Hip centres in the markers' frame, metres (NaN where a marker is missing).
    """
    la, ra = np.asarray(asis_left, float), np.asarray(asis_right, float)
    mid_a = (la + ra) / 2
    mid_p = np.mean([np.asarray(p, float) for p in psis], axis=0)
    z = ra - la
    pw = np.linalg.norm(z, axis=-1)
    z = z / pw[:, None]
    back = mid_a - mid_p
    pd = np.linalg.norm(back, axis=-1)
    x = unit(back - np.sum(back * z, -1)[:, None] * z)
    y = np.cross(z, x)
    ax, ay, az = -0.24 * pd - 0.0099, -0.30 * pw - 0.0109, 0.33 * pw + 0.0073
    base = mid_a + ax[:, None] * x + ay[:, None] * y
    return base - az[:, None] * z, base + az[:, None] * z


def swing_spread(sets: list[np.ndarray], centre: np.ndarray):
    """Eigenvalues (ascending) and eigenvectors of the pooled within-marker covariance
    of the unit directions from ``centre`` to each marker: how far the segment swung
    about the centre along each direction (sin of the angular standard deviation)."""
    acc, n = np.zeros((3, 3)), 0
    for y in sets:
        if len(y) < 2:
            continue
        d = unit(np.asarray(y, float) - centre)
        d = d - d.mean(axis=0)
        acc += d.T @ d
        n += len(d)
    return np.linalg.eigh(acc / max(n, 1))



def regress_hip(v, rep: JointReport, spec: SegmentSpec, root: SegmentSpec, trials,
                 frames, sets) -> tuple[np.ndarray, JointReport, bool]:
    """The hip centre ``v`` (root frame) with its poorly swung components taken from
    :func:`hip_regression` (see :data:`MIN_SWING_DEG`); the report says which."""
    lam, vec = swing_spread(sets, v)
    swing_deg = np.degrees(np.arcsin(np.sqrt(np.clip(lam, 0.0, 1.0))))
    weak = swing_deg < MIN_SWING_DEG
    if not weak.any():  # swung enough every way: the fit stands, no regression needed
        return v, rep, False
    side = root.hip_joints.index(spec.joint)
    local = []
    for ti, t in enumerate(trials):
        idx = [t.index(m) for m in (*root.hip_asis, *root.hip_psis)]
        pts = t.positions[:, idx]
        hip = hip_regression(pts[:, 0], pts[:, 1], list(pts[:, 2:].transpose(1, 0, 2)))[side]
        pf = frames[ti][root.name]
        local.append(to_local(pf.r, pf.o, hip[:, None])[:, 0])
    reg = nanmedian_rows(np.concatenate(local))
    if not np.isfinite(reg).all():
        return v, rep, False
    e = vec[:, weak]
    v = v + e @ (e.T @ (reg - v))
    swing = ", ".join(f"{a:.0f}" for a in swing_deg)
    note = (f"{int(weak.sum())} of 3 directions from the pelvis-landmark regression "
            f"(Harrington 2007): the thigh swung {swing} deg (sd) about the fitted centre, "
            f"under {MIN_SWING_DEG:g} deg there; regression {np.linalg.norm(reg - v) * 1e3:.0f}"
            " mm from the result")
    rep = replace(rep, method=rep.method + "+regression", note=note,
                  center_local_m=[float(a) for a in v])
    return v, rep, True


