"""Legs: Algorithm 1 on the upper legs, the knee-crossing swap and the thighs' hips.

Seed 004 section 3.1.4 step 6: the upper legs with their lower legs as one unit
(:func:`fit_upper_legs`), after Algorithm 5's swap of the lower legs when the knees
cross (:func:`swap_lower_legs`). Beyond the seed: the swap kept only if it fits
better (:func:`verify_crossing`), and crossed thighs of a fresh fit moved to the
other hips (:func:`untangle_thighs`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.limits import THIGH_WIDE, J, S
from vidcap.video.fit.moves import search_angle
from vidcap.video.fit.state import FitState, keep_if_better

_LOWER_LEGS = [S["l_lower_leg"], S["r_lower_leg"]]
_UPPER_LEGS = [S["l_upper_leg"], S["r_upper_leg"]]


def fit_upper_legs(eng: _MaskEngine, st: FitState, *, warm: bool = False,
                   passes: int = 2) -> FitState:
    """Algorithm 1 on each upper leg (Table 3.3's hip limits), its lower leg hanging
    from the knee at its own angle; ``passes`` rounds, all but the first (and the
    first too with ``warm``) within +-10 degrees of the current angle. Writes the
    thighs' ``angles``, ``scores``, ``margins``."""
    rows = (st.root[1] - eng.R[S["torso"]], eng.h)
    for _ in range(passes):
        for s in ("l", "r"):
            up = S[f"{s}_upper_leg"]
            kw = dict(start=st.angles[up], interval=np.deg2rad(20)) if warm else {}
            # the lower leg keeps its (contour) angle and hangs from the knee
            st, _ = search_angle(eng, st, up, rows=rows, **kw)
        warm = True
    return st


def knee_bend(st: FitState) -> float:
    """Sum of the image-plane knee bends (radians) of ``st``."""
    d = st.angles[_LOWER_LEGS] - st.angles[_UPPER_LEGS]
    return float(np.abs(np.angle(np.exp(1j * d))).sum())


def swap_lower_legs(st: FitState) -> FitState:
    """Algorithm 2's swap of the lower legs' ``angles`` (when the knees cross)."""
    return st.with_entries(angles=(_LOWER_LEGS, st.angles[_LOWER_LEGS[::-1]]))


def verify_crossing(eng: _MaskEngine, st: FitState, legs: Callable[[FitState], FitState], *,
                    spread: bool, tie: float) -> FitState:
    """Keep Algorithm 5's swap only if it covers the silhouette better (beyond the seed).

    ``st`` has the lower legs swapped and ``legs`` (:func:`fit_upper_legs` and the
    spread) applied; the unswapped legs get the same treatment (from spread 0.5 when
    ``spread`` is searched) and win unless they fit worse by more than ``tie``. An X
    at the knees looks the same as two legs bent toward each other (Algorithm 5 also
    fires on some bent knees), so near-ties go to the straighter legs (smaller
    image-plane knee bends).
    """
    def other(kept: FitState) -> FitState:
        cur = swap_lower_legs(kept)
        cur = cur.replace(spread=kept.spread if not spread else 0.5)
        return legs(cur)

    def straighter_kept(new: FitState, kept: FitState) -> bool:
        return knee_bend(new) >= knee_bend(kept)

    return keep_if_better(eng.similarity, st, other, tie=tie, prefer_kept=straighter_kept)


def _segments_cross(a0, a1, b0, b1) -> bool:
    """Do 2D segments a0-a1 and b0-b1 intersect (proper crossing)?"""
    def side(p, q, r):
        return np.sign((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))

    return (side(a0, a1, b0) * side(a0, a1, b1) < 0) and (side(b0, b1, a0) * side(b0, b1, a1) < 0)


def untangle_thighs(eng: _MaskEngine, st: FitState, *, tie: float) -> FitState:
    """Swap whole legs between the hips when the thighs cross (beyond the seed).

    With the hips apart (spread > 0.3), thighs that cross each other in a fresh
    fit most likely mean the image-left hip was given the image-right leg; the
    swapped legs (re-searched +-15 degrees) are kept unless they fit worse by more
    than ``tie``. Only fresh fits are untangled: a track keeps each leg on its hip,
    crossings included (:func:`vidcap.video.fit.frame.fit_normalised`).
    """
    j = eng.joints(st)
    if st.spread <= 0.3 or not _segments_cross(j[J["l_hip"]], j[J["l_knee"]],
                                                j[J["r_hip"]], j[J["r_knee"]]):
        return st

    def swapped(cur: FitState) -> FitState:
        legs_l = [S["l_upper_leg"], S["l_lower_leg"]]
        legs_r = [S["r_upper_leg"], S["r_lower_leg"]]
        cur = cur.with_entries(angles=(legs_l + legs_r, cur.angles[legs_r + legs_l]),
                               fore=(legs_l + legs_r, cur.fore[legs_r + legs_l]))
        for seg in (S["l_upper_leg"], S["r_upper_leg"], S["l_lower_leg"], S["r_lower_leg"]):
            limits = THIGH_WIDE if seg in _UPPER_LEGS else (None, None)
            cur, _ = search_angle(eng, cur, seg, start=cur.angles[seg],
                                  interval=np.deg2rad(30), lo=limits[0], hi=limits[1])
        return cur

    return keep_if_better(eng.similarity, st, swapped, tie=tie)


__all__ = ["fit_upper_legs", "knee_bend", "swap_lower_legs", "untangle_thighs",
           "verify_crossing"]
