"""Limbs by contour (Algorithms 2-5) and Algorithm 1 again on every limb segment.

Seed 004 section 3.1.4 steps 4-5: the arms from the silhouette left beside the
fitted torso and head (:func:`contour_arms`), the lower legs from scan lines below
the knees and the knee crossing (:func:`contour_lower_legs`); beyond the seed, every
limb segment searched again against the whole silhouette (:func:`refine_limbs`).
"""

from __future__ import annotations

import cv2
import numpy as np

from vidcap.body import SEGMENT_NAMES
from vidcap.video.fit.contour import arm_angles, fit_angle, knees_crossed, leg_curves, limb_curve
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.foreshortening import search_fore
from vidcap.video.fit.limits import (
    LIMITS,
    MAX_BEND,
    THIGH_WIDE,
    THIRTY_DEGREES,
    TWO_PI,
    J,
    S,
    into_range,
)
from vidcap.video.fit.moves import search_angle
from vidcap.video.fit.state import FitState, hang

_ARMS = [S["l_upper_arm"], S["l_lower_arm"], S["r_upper_arm"], S["r_lower_arm"]]


def contour_arms(eng: _MaskEngine, st: FitState) -> FitState:
    """Algorithms 2-4 on the silhouette left beside the torso and head.

    Draws torso, head and arms; writes the arms' ``angles`` (an arm without enough
    pixels of its own hangs along the torso).
    """
    st = st.drawing([S["torso"], S["head"]])
    body = eng.model(st, [S["torso"], S["head"]])
    body = cv2.dilate(body.view(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    rest = eng.sil & ~body
    # Slivers along the torso's edges (the model is not the silhouette's exact
    # shape) are not arms: keep only parts at least ~an arm's width across.
    k = max(2, int(round(1.5 * eng.R[S["l_upper_arm"]])))
    rest = cv2.morphologyEx(rest.view(np.uint8), cv2.MORPH_OPEN,
                            cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))).astype(bool)
    j = eng.joints(st)
    rest[max(int(j[J["pelvis"], 1]), 0) :] = False  # below the pelvis: legs
    ys, xs = np.nonzero(rest)
    axis = j[J["neck"]] - j[J["pelvis"]]
    side = axis[0] * (ys - j[J["pelvis"], 1]) - axis[1] * (xs - j[J["pelvis"], 0])
    # side < 0: image-left of an upward torso axis (cross product, y down).
    min_pixels = max(4.0, (2 * eng.R[S["l_upper_arm"]]) ** 2)
    # Algorithm 4's minimumCornerDistance is 4 points in the seed; we also ask for
    # a third of an upper arm, so a handful of noisy points is not a segment.
    min_dist = max(4, int(round(0.33 * eng.L[S["l_upper_arm"]])))
    angles = st.angles.copy()
    for s, sel in (("l", side < 0), ("r", side > 0)):
        up, lo = S[f"{s}_upper_arm"], S[f"{s}_lower_arm"]
        down = np.mod(angles[S["torso"]] + np.pi, TWO_PI)
        if np.count_nonzero(sel) < min_pixels:
            angles[[up, lo]] = down
            continue
        curve = limb_curve(np.stack([xs[sel], ys[sel]], 1), j[J[f"{s}_shoulder"]])
        if len(curve) < 3:
            angles[[up, lo]] = down
            continue
        lower, upper, _ = arm_angles(curve, min_distance=min_dist)
        angles[up], angles[lo] = upper, lower
    return st.with_entries(angles=(slice(None), angles), drawn=(_ARMS, True))


def contour_lower_legs(eng: _MaskEngine, st: FitState) -> tuple[FitState, bool]:
    """Algorithm 2 on the lower legs, Algorithm 5 for crossing.

    Writes the lower legs' ``angles`` (down where a leg's curve is too short);
    returns the new state and whether the knees cross.
    """
    # From the knees (Table 3.1 height above the lowest silhouette row) down.
    bottom = eng.norm.bottom
    top = bottom - eng.L[S["l_lower_leg"]] - (eng.R[S["l_lower_leg"]] if eng.caps else 0)
    left, right, merged = leg_curves(eng.sil, int(round(top)), bottom, eng.R[S["l_lower_leg"]])
    angles = st.angles.copy()
    for s, curve in (("l", left), ("r", right)):
        seg = S[f"{s}_lower_leg"]
        if len(curve) >= 3:
            a = fit_angle(curve)
            lo, hi = LIMITS[SEGMENT_NAMES[seg]]
            angles[seg] = np.clip(a if a >= np.pi / 2 else a + TWO_PI, lo, hi)
        else:
            angles[seg] = 1.5 * np.pi
    return st.with_entries(angles=(slice(None), angles)), knees_crossed(merged)


def refine_whole_arms(eng: _MaskEngine, st: FitState) -> FitState:
    """Each whole arm (lower arm rigidly attached, straightened) by Algorithm 1 within
    90 degrees of the contour estimate (ties: hanging down), and its length by
    Algorithm 6 (beyond the seed, which avoids Algorithm 1 on the arms for fear of
    occlusion; the contour estimate is the tie-breaker). Writes the arms' ``angles``,
    ``fore``, ``scores``, ``margins``."""
    for s in ("l", "r"):
        up, lo = S[f"{s}_upper_arm"], S[f"{s}_lower_arm"]
        st = st.with_entries(angles=(lo, st.angles[up]), fore=([up, lo], 1.0))
        st, _ = search_angle(eng, st, up, with_segments=(lo,), start=st.angles[up],
                             interval=np.pi, prefer=hang(st))
        st, _ = search_fore(eng, st, up, unit=True)
    return st


def refine_limbs(eng: _MaskEngine, st: FitState, half_width=THIRTY_DEGREES, *,
                 whole_arms=False) -> FitState:
    """Algorithm 1 again on every limb segment against the whole silhouette.

    Within ``half_width`` radians of each one's angle (lower legs: their whole
    range; lower limbs within the flexion limit of their parent, thighs within
    ``THIGH_WIDE``). ``whole_arms``: :func:`refine_whole_arms` first, to undo a
    contour curve that went astray. Writes the limbs' ``angles``, ``scores``,
    ``margins``.
    """
    if whole_arms:
        st = refine_whole_arms(eng, st)
    for seg_name in ("upper_leg", "lower_leg", "upper_arm", "lower_arm"):
        for s in ("l", "r"):
            seg = S[f"{s}_{seg_name}"]
            lo, hi = _refine_limits(st, s, seg_name)
            start = st.angles[seg]
            if lo is not None:
                start = into_range(start, lo, hi)
            # a shin may swing far from its contour estimate (a raised foot), so
            # the lower legs get their whole range; an arm hidden in the torso
            # covers the same pixels at any angle: ties go to hanging down
            width = (hi - lo) if seg_name == "lower_leg" else 2 * half_width
            prefer = hang(st) if seg_name.endswith("arm") else None
            st, _ = search_angle(eng, st, seg, start=start, interval=width, lo=lo, hi=hi,
                                 prefer=prefer)
    return st


def _refine_limits(st: FitState, s: str, seg_name: str):
    """:func:`refine_limbs`' limits of one segment (None, None: Table 3.3's)."""
    if seg_name == "upper_leg":
        return THIGH_WIDE
    if not seg_name.startswith("lower"):
        return None, None
    # the projected elbow/knee bend stays within the flexion limit
    parent = S[f"{s}_upper_{seg_name.split('_')[1]}"]
    lo = st.angles[parent] - MAX_BEND
    hi = st.angles[parent] + MAX_BEND
    if seg_name == "lower_leg":
        lim = LIMITS["l_lower_leg"]
        lo, hi = max(lo, lim[0]), min(hi, lim[1])
        if hi <= lo:
            lo, hi = lim
    return lo, hi


__all__ = ["contour_arms", "contour_lower_legs", "refine_limbs", "refine_whole_arms"]
