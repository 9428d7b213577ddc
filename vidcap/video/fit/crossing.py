"""Legs passing each other in a track: the hypothesis that each leg hangs from the other hip.

Seen three-quarter on, the knees pass each other in the image every step, and for a
few frames the thighs cross. The silhouette scores crossed thighs and thighs that
part again alike (the same pixels, give or take the thighs' overlap), and a warm
search starting from legs side by side keeps them side by side: the track bounces
each knee back at the crossing, and from then on the leg hangs from the wrong hip
(HISTORY.md: 468 of 870 held-out hip misses). The clip says which is right: a knee
swinging forward keeps going. :func:`choose_crossing` (tracked frames) therefore
also tries the legs exchanged between the hips, knees and ankles where they are
(:func:`exchange_legs`), refined, and keeps the hypothesis whose knees are nearer
where the last two frames say they are heading, S and that distance weighed
together.
"""

from __future__ import annotations

import numpy as np

from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.limits import THIGH_WIDE, J, S
from vidcap.video.fit.moves import search_group
from vidcap.video.fit.raster import image_angle
from vidcap.video.fit.state import FitState

_UPPER = [S["l_upper_leg"], S["r_upper_leg"]]
_LOWER = [S["l_lower_leg"], S["r_lower_leg"]]
_HIPS = [J["l_hip"], J["r_hip"]]
_KNEES = [J["l_knee"], J["r_knee"]]
_ANKLES = [J["l_ankle"], J["r_ankle"]]
#: the points whose heading judges the legs: left knee and ankle, right knee and ankle
_LEG_POINTS = [J["l_knee"], J["l_ankle"], J["r_knee"], J["r_ankle"]]
_EXCHANGED = [2, 3, 0, 1]  # the same points, the legs exchanged
_ANKLES_EXCHANGED = [0, 3, 2, 1]  # ... the ankles exchanged
_KNEES_EXCHANGED = [2, 1, 0, 3]  # ... the knees exchanged
#: S one body height of distance from where the knees and ankles are heading is
#: worth: the legs' joints 2 % of the height off the heading cost 0.02 * 1.0 of S.
HEADING_WEIGHT = 1.0



def _reach(start: np.ndarray, target: np.ndarray, full: np.ndarray):
    """Image angles and foreshortening (at most 1) of segments of full lengths ``full``
    (2,) turned from joints ``start`` (2, 2) toward ``target`` (2, 2), pixels: a target
    beyond a segment's length is reached as far as it goes."""
    v = target - start
    fore = np.clip(np.hypot(v[:, 0], v[:, 1]) / full, 1.0 / np.maximum(full, 1.0), 1.0)
    return image_angle(v), fore

def exchange_legs(eng: _MaskEngine, st: FitState) -> FitState:
    """``st`` with each leg hung from the other hip, the knees and ankles kept.

    Each thigh is turned and foreshortened to reach the other leg's knee from its own
    hip (foreshortening at most 1: a knee beyond the thigh's length is reached as far
    as it goes); the lower legs exchange their angles and foreshortening.

    Parameters
    ----------
    eng : _MaskEngine
        The frame's engine (segment lengths).
    st : FitState
        The pose.

    Returns
    -------
    FitState
        The legs exchanged (every segment drawn).
    """
    j = eng.joints(st)
    # each hip to the other leg's knee
    upper, fore = _reach(j[_HIPS], j[_KNEES[::-1]], eng.L[_UPPER])
    upper = into_thigh_range(upper)
    return st.with_entries(angles=(_UPPER + _LOWER, np.r_[upper, st.angles[_LOWER[::-1]]]),
                           fore=(_UPPER + _LOWER, np.r_[fore, st.fore[_LOWER[::-1]]]),
                           drawn=(slice(None), True))


def exchange_ankles(eng: _MaskEngine, st: FitState) -> FitState:
    """``st`` with each lower leg turned to the other leg's ankle from its own knee
    (the legs crossing below the knees instead of bending toward each other; the
    knees and thighs kept, foreshortening at most 1).

    Parameters
    ----------
    eng : _MaskEngine
        The frame's engine (segment lengths).
    st : FitState
        The pose.

    Returns
    -------
    FitState
        The ankles exchanged (every segment drawn).
    """
    j = eng.joints(st)
    # each knee to the other leg's ankle
    lower, fore = _reach(j[_KNEES], j[_ANKLES[::-1]], eng.L[_LOWER])
    return st.with_entries(angles=(_LOWER, lower), fore=(_LOWER, fore),
                           drawn=(slice(None), True))


def exchange_knees(eng: _MaskEngine, st: FitState) -> FitState:
    """``st`` with each thigh turned to the other leg's knee and each lower leg on to
    its own leg's ankle (:func:`exchange_legs` then :func:`exchange_ankles`)."""
    return exchange_ankles(eng, exchange_legs(eng, st))


def into_thigh_range(angles: np.ndarray) -> np.ndarray:
    """Thigh angles clipped into the tracked fit's wide hip limits (radians)."""
    lo, hi = THIGH_WIDE
    return np.clip(np.mod(angles, 2 * np.pi), lo, hi)


def leg_distance(eng: _MaskEngine, st: FitState, heading: np.ndarray) -> float:
    """Mean distance of ``st``'s knees and ankles from ``heading`` (4, 2: left knee,
    left ankle, right knee, right ankle), in body heights (the normalised
    silhouette's height)."""
    k = eng.joints(st)[_LEG_POINTS]
    return float(np.hypot(*(k - heading).T).mean() / eng.H)


def choose_crossing(eng: _MaskEngine, st: FitState, heading: np.ndarray, *,
                    interval: float, weight: float = HEADING_WEIGHT) -> FitState:
    """The tracked pose ``st`` or its legs exchanged (:func:`exchange_legs`), whichever
    scores better by S minus ``weight`` times the knees' and ankles' distance from
    ``heading``.

    Parameters
    ----------
    eng : _MaskEngine
        The frame's engine.
    st : FitState
        The tracked (warm) fit of this frame.
    heading : numpy.ndarray, shape (4, 2)
        Where the left knee and ankle and the right knee and ankle are heading (the
        last frame's carried on by their last frame-to-frame step), normalised pixels.
    interval : float
        The exchanged legs' refinement: angles searched +- ``interval`` (radians).
    weight : float
        S per body height of distance.

    Returns
    -------
    FitState
        ``st`` unless the exchanged legs score better. Only tried where the legs as
        fitted are nearer the heading exchanged than as they are (a bounce at the
        crossing): elsewhere ``st`` is returned at no cost.
    """
    k = eng.joints(st)[_LEG_POINTS]
    if not (np.isfinite(heading).all() and np.isfinite(k).all()):
        return st
    kept = np.hypot(*(k - heading).T).sum()

    def score(cur: FitState) -> float:
        return eng.similarity(cur) - weight * leg_distance(eng, cur, heading)

    best, best_score = st, None
    for order, exchange in ((_EXCHANGED, exchange_legs), (_ANKLES_EXCHANGED, exchange_ankles),
                            (_KNEES_EXCHANGED, exchange_knees)):
        if np.hypot(*(k[order] - heading).T).sum() >= kept:
            continue  # the fit's legs are nearer where they were heading as they are
        x = exchange(eng, st)
        x = search_group(eng, x, _UPPER, interval=interval)
        x = search_group(eng, x, _LOWER, interval=interval)
        x = search_group(eng, x, _UPPER + _LOWER, kind="fore", interval=0.2, divisions=5)
        if best_score is None:
            best_score = score(st)
        sx = score(x)
        if sx > best_score:
            best, best_score = x, sx
    return best


def exchange_nearer(joints: np.ndarray, heading: np.ndarray) -> bool:
    """Are the legs of ``joints`` (15, 2) nearer ``heading`` (4, 2, the same units)
    with their legs, ankles or knees exchanged than as they are? (What
    :func:`choose_crossing` tries; False where either holds NaN.)"""
    k = np.asarray(joints, dtype=float)[_LEG_POINTS]
    if not (np.isfinite(heading).all() and np.isfinite(k).all()):
        return False
    kept = np.hypot(*(k - heading).T).sum()
    return any(np.hypot(*(k[order] - heading).T).sum() < kept
               for order in (_EXCHANGED, _ANKLES_EXCHANGED, _KNEES_EXCHANGED))


def legs_heading(prev_joints: np.ndarray | None,
                 before_joints: np.ndarray | None) -> np.ndarray | None:
    """Where the knees and ankles are heading: the last frame's carried on by their
    last frame-to-frame step, (4, 2) pixels (left knee, left ankle, right knee, right
    ankle), or None without two frames."""
    if prev_joints is None or before_joints is None:
        return None
    k1, k0 = prev_joints[_LEG_POINTS], before_joints[_LEG_POINTS]
    out = 2.0 * k1 - k0
    return out if np.isfinite(out).all() else None


__all__ = ["HEADING_WEIGHT", "choose_crossing", "exchange_ankles", "exchange_knees",
           "exchange_legs", "exchange_nearer", "leg_distance",
           "legs_heading"]
