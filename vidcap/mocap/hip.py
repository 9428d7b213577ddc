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


def davis_hip_regression(asis_left, asis_right, psis, subject: dict
                         ) -> tuple[np.ndarray, np.ndarray] | None:
    """Plug-in-Gait's hip joint centres (Davis et al., Hum Mov Sci 10:575, 1991, as the
    Plug-in-Gait manual gives them), from the pelvis markers and the subject's
    measurements; None when ``subject`` lacks the leg lengths.

    In the pelvis frame at the mid-ASIS point (x anterior, y to the left, z up), with
    C = 0.115 L - 15.3 mm (L the mean leg length), θ = 0.5 rad, β = 0.314 rad, A the
    ASIS-trochanter distance (0.1288 L - 48.56 mm when not measured), r the marker
    radius and W the inter-ASIS distance:
    ``x = (-A - r) cos β + C cos θ sin β``, ``y = ±(W/2 - C sin θ)``,
    ``z = (-A - r) sin β - C cos θ cos β``.

    Parameters
    ----------
    asis_left, asis_right : numpy.ndarray, shape (F, 3)
        Metres.
    psis : sequence of numpy.ndarray, each (F, 3)
        The two PSIS markers, or one sacrum marker.
    subject : dict
        PROCESSING measurements (mm): ``LLegLength``, ``RLegLength``, optionally
        ``InterAsisDistance``, ``L/RAsisTrocanterDistance``, ``MarkerDiameter``.

    Returns
    -------
    (left, right) : numpy.ndarray, shape (F, 3), metres; or None
    """
    legs = [subject.get("LLegLength"), subject.get("RLegLength")]
    if not all(v is not None and v > 0 for v in legs):
        return None
    la, ra = np.asarray(asis_left, float), np.asarray(asis_right, float)
    mid_a = (la + ra) / 2
    mid_p = np.mean([np.asarray(p, float) for p in psis], axis=0)
    y = unit(la - ra)
    back = mid_a - mid_p
    x = unit(back - np.sum(back * y, -1)[:, None] * y)
    z = np.cross(x, y)
    mean_leg = 0.5 * (legs[0] + legs[1])
    c = 0.115 * mean_leg - 15.3
    theta, beta = 0.5, 0.314
    radius = 0.5 * (subject.get("MarkerDiameter") or 14.0)
    width = subject.get("InterAsisDistance") or 0.0
    half = (np.full(len(la), width / 2) if width > 0
            else np.linalg.norm(la - ra, axis=-1) * 1e3 / 2)
    out = []
    for sign, leg, key in ((1.0, legs[0], "LAsisTrocanterDistance"),
                           (-1.0, legs[1], "RAsisTrocanterDistance")):
        a = subject.get(key) or 0.0
        a = a if a > 0 else 0.1288 * leg - 48.56
        hx = (-a - radius) * np.cos(beta) + c * np.cos(theta) * np.sin(beta)
        hz = (-a - radius) * np.sin(beta) - c * np.cos(theta) * np.cos(beta)
        hy = sign * (half - c * np.sin(theta))
        out.append(mid_a + 1e-3 * (hx * x + hy[:, None] * y + hz * z))
    return out[0], out[1]


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



def estimated_leg_lengths(trial, root: SegmentSpec) -> dict:
    """Leg lengths (mm) as Plug-in-Gait measures them (ASIS to medial malleolus), read
    from the trial: the 90th percentile over frames of the ASIS to lateral-malleolus
    marker distance (the leg at its straightest); {} without ``root.hip_ankles``."""
    if len(root.hip_ankles) != 2 or len(root.hip_asis) != 2:
        return {}
    out = {}
    for key, asis, ankle in zip(("LLegLength", "RLegLength"), root.hip_asis,
                                root.hip_ankles, strict=True):
        d = np.linalg.norm(trial.marker(asis) - trial.marker(ankle), axis=1)
        d = d[np.isfinite(d)]
        if len(d):
            out[key] = float(np.percentile(d, 90)) * 1e3
    return out if len(out) == 2 else {}


def pelvis_regression(trial, root: SegmentSpec) -> tuple[tuple[np.ndarray, np.ndarray], str]:
    """Both hip centres per frame (lab, metres) from the root's regression model, and a
    note of which model and which measurements.

    ``root.hip_model == 'davis'`` uses :func:`davis_hip_regression` with the C3D's leg
    lengths or, absent, :func:`estimated_leg_lengths`; otherwise (or when neither is
    available) :func:`hip_regression`.
    """
    idx = [trial.index(m) for m in (*root.hip_asis, *root.hip_psis)]
    pts = trial.positions[:, idx]
    args = pts[:, 0], pts[:, 1], list(pts[:, 2:].transpose(1, 0, 2))
    if root.hip_model == "davis":
        subject = dict(getattr(trial, "subject", {}) or {})
        both = davis_hip_regression(*args, subject)
        if both is not None:
            return both, "Plug-in-Gait/Davis 1991, the file's leg lengths"
        est = estimated_leg_lengths(trial, root)
        both = davis_hip_regression(*args, {**subject, **est}) if est else None
        if both is not None:
            legs = "/".join(f"{est[k]:.0f}" for k in ("LLegLength", "RLegLength"))
            return both, f"Plug-in-Gait/Davis 1991, leg lengths {legs} mm from the markers"
    return hip_regression(*args), "Harrington 2007"


def regress_hip(v, rep: JointReport, spec: SegmentSpec, root: SegmentSpec, trials,
                 frames, sets) -> tuple[np.ndarray, JointReport, bool]:
    """The hip centre ``v`` (root frame) with its poorly swung components taken from
    :func:`hip_regression` (see :data:`MIN_SWING_DEG`); the report says which. A fit
    that was rejected (a static trial: the thigh did not move) gives way to the
    regression whole."""
    lam, vec = swing_spread(sets, v)
    swing_deg = np.degrees(np.arcsin(np.sqrt(np.clip(lam, 0.0, 1.0))))
    weak = swing_deg < MIN_SWING_DEG
    if rep.flagged:
        weak[:] = True
    if not weak.any():  # swung enough every way: the fit stands, no regression needed
        return v, rep, False
    side = root.hip_joints.index(spec.joint)
    local, models = [], set()
    for ti, t in enumerate(trials):
        hips, model = pelvis_regression(t, root)
        models.add(model)
        pf = frames[ti][root.name]
        local.append(to_local(pf.r, pf.o, hips[side][:, None])[:, 0])
    reg = nanmedian_rows(np.concatenate(local))
    if not np.isfinite(reg).all():
        return v, rep, False
    if rep.flagged:
        note = (f"the pelvis-landmark regression ({'; '.join(sorted(models))}): "
                f"{rep.note.split(';')[0]}")
        rep = replace(rep, method="regression", note=note, flagged=False,
                      center_local_m=[float(a) for a in reg])
        return reg, rep, True
    e = vec[:, weak]
    v = v + e @ (e.T @ (reg - v))
    swing = ", ".join(f"{a:.0f}" for a in swing_deg)
    note = (f"{int(weak.sum())} of 3 directions from the pelvis-landmark regression "
            f"({'; '.join(sorted(models))}): the thigh swung {swing} deg (sd) about the "
            f"fitted centre, under {MIN_SWING_DEG:g} deg there; regression "
            f"{np.linalg.norm(reg - v) * 1e3:.0f} mm from the result")
    rep = replace(rep, method=rep.method + "+regression", note=note,
                  center_local_m=[float(a) for a in v])
    return v, rep, True


