"""Limb labels: which limb of a pair is called ``l_*`` and which ``r_*``.

A fresh fit names limbs by image side; a track keeps the names it started with
through crossings (:mod:`vidcap.video.fit.pose2d`, "Left and right"). Where a fresh fit
takes over a track, :func:`keep_labels` gives its limbs the track's names.
"""

from __future__ import annotations

import numpy as np

from vidcap.body import LIMB_PAIR_JOINTS
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.limits import S
from vidcap.video.fit.moves import search_group
from vidcap.video.fit.state import FitState, keep_if_better

#: (joints, segments) of the image-left and image-right member of each limb pair.
LIMB_PAIRS = {
    pair: tuple((joints, [S[f"{side}_{p}_{pair[:-1]}"] for p in ("upper", "lower")])
                for side, joints in zip("lr", LIMB_PAIR_JOINTS[pair], strict=True))
    for pair in ("arms", "legs")
}


def keep_labels(eng: _MaskEngine, st: FitState, reference: np.ndarray, *,
                tie: float) -> FitState:
    """Give a fresh fit's limbs the labels a track gave them.

    A track keeps the names it started with through crossings, so where a fresh fit
    takes over a track (a slipping warm fit, a challenge) its pairs can come out
    swapped against the frames before, and the 3D stage, which reads one limb as the
    body's left for the whole clip, would put that leg on the other hip from then
    on. Each pair (arms, legs) is swapped (``angles``, ``fore``, ``scores``,
    ``margins``) when the swapped labelling's joints are closer to ``reference``
    (15, 2), the previous frame's joints in this fit's pixels, and the swapped pose
    fits within ``tie`` as well (with the shoulders or hips apart, a limb drawn from
    the other one is a different pose: it is settled there first).
    """
    j = eng.joints(st)  # the fit as it came: swapping one pair moves no other's joints
    for (jl, sl), (jr, sr) in LIMB_PAIRS.values():
        both = jl + jr
        keep = np.linalg.norm(j[both] - reference[both], axis=-1).sum()
        swap = np.linalg.norm(j[jr + jl] - reference[both], axis=-1).sum()
        if not swap < keep:
            continue

        def swapped(cur: FitState, sl=sl, sr=sr) -> FitState:
            s_kept = eng.similarity(cur)
            pair = sl + sr
            cur = cur.with_entries(**{name: (pair, getattr(cur, name)[sr + sl])
                                      for name in ("angles", "fore", "scores", "margins")})
            if eng.similarity(cur) < s_kept - tie:
                # each limb now hangs from the other shoulder (hip): settle it there
                cur = search_group(eng, cur, [sl[0], sr[0]], interval=np.deg2rad(16))
                cur = search_group(eng, cur, [sl[1], sr[1]], interval=np.deg2rad(16))
            return cur

        st = keep_if_better(eng.similarity, st, swapped, tie=tie)
    return st


__all__ = ["LIMB_PAIRS", "keep_labels"]
