"""A thigh folded toward or away from the camera (beyond the seed; issue 27 item 4).

In a crouch or a squat seen from the side the thighs often point at the camera: a
thigh is then drawn a third to a half of its length, and the knee sits close to the
hip. The seed finds a segment's angle at its full length and only then its
foreshortening (Algorithm 1, then Algorithm 6); a full-length thigh laid where the
short one is reaches past the knee, so Algorithm 1 turns it elsewhere (along the other
leg, out along the shin) and Algorithm 6, searched from there, never sees the short
thigh. :func:`fold_thighs` searches each thigh's angle again at a few shorter lengths,
its shin re-hung from the new knee, and keeps a fold that fits better.
"""

from __future__ import annotations

from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.foreshortening import search_fore
from vidcap.video.fit.limits import LIMITS, THIGH_WIDE, S
from vidcap.video.fit.moves import search_angle
from vidcap.video.fit.state import FitState

#: Thigh lengths tried (shares of the full length): a thigh turned 55-65 degrees
#: toward the camera. Chosen on the ``--poses`` crouch clips (tuning), HISTORY.md.
FOLD_RATIOS = (0.45,)
#: A silhouette at most this share of the model's height (head top to soles) is a
#: crouch, where :func:`fold_thighs` runs; upright frames skip it (and its cost).
FOLD_BELOW = 0.92


def crouching(eng: _MaskEngine) -> bool:
    """True where the silhouette is shorter than :data:`FOLD_BELOW` of the model's
    height (``eng.H`` plus the feet): a crouch, a squat, a deep lunge."""
    return eng.norm.height < FOLD_BELOW * (eng.H + eng.foot)


def fold_thighs(eng: _MaskEngine, st: FitState, *, tie: float,
                ratios: tuple[float, ...] = FOLD_RATIOS) -> FitState:
    """Each thigh searched again at the shorter ``ratios`` of its length (angle over
    :data:`~vidcap.video.fit.limits.THIGH_WIDE`, then the shin about the new knee
    within its limits, then Algorithm 6 on the thigh near the ratio); a fold is kept
    when it beats the leg in place by more than ``tie`` (S). Ratios not shorter than
    the thigh in place by 0.1 are skipped. Writes the thighs' and shins' ``angles``,
    ``fore``, ``scores``, ``margins``.
    """
    best_s = eng.similarity(st)
    for s in ("l", "r"):
        up, lo = S[f"{s}_upper_leg"], S[f"{s}_lower_leg"]
        best = st
        for r in ratios:
            if r > st.fore[up] - 0.1:
                continue
            cand = st.with_entries(fore=(up, r))
            cand, _ = search_angle(eng, cand, up, lo=THIGH_WIDE[0], hi=THIGH_WIDE[1],
                                   divisions=12)
            cand, _ = search_angle(eng, cand, lo, lo=LIMITS["l_lower_leg"][0],
                                   hi=LIMITS["l_lower_leg"][1], divisions=12)
            cand, _ = search_fore(eng, cand, up, start=r, interval=0.3)
            score = eng.similarity(cand)
            if score > best_s + tie:
                best, best_s = cand, score
        st = best
    return st


__all__ = ["FOLD_BELOW", "FOLD_RATIOS", "crouching", "fold_thighs"]
