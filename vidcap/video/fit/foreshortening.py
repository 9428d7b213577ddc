"""Algorithm 6: the foreshortening (drawn / full length) of segments.

Each move takes the frame's engine and a :class:`~vidcap.video.fit.state.FitState` and
returns the new state; ratios are in (0, 1], searched from ``1 / length`` (normalised
px) up, ties to 1 (an unforeshortened segment).
"""

from __future__ import annotations

import numpy as np

from vidcap.video.fit.candidates import NOWHERE, limb_ends, limb_search_compiled, pose_ends, search
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.modes import SEARCH_POSE_FORE
from vidcap.video.fit.raster import DESCENDANTS, direction
from vidcap.video.fit.search import SearchResult
from vidcap.video.fit.state import FitState


def search_fore(eng: _MaskEngine, st: FitState, seg: int, *, start=None, interval=None,
                divisions=5, unit=False) -> tuple[FitState, SearchResult]:
    """Algorithm 6 on segment ``seg`` (its descendants move with its end).

    Draws ``seg``; writes its ``fore``, ``scores`` and ``margins``. ``unit``: scale
    the segment and its child limb segment together (a whole limb's
    foreshortening, beyond the seed; writes both ``fore`` only).
    """
    st = st.drawing(seg)
    moving = [d for d in DESCENDANTS[seg] if st.drawn[d]]
    length = max(eng.L[seg], 1.0)
    if unit:
        together = list(DESCENDANTS[seg])
        base = st.fore[together].copy()
        length = max(float((eng.L[together] * base).sum()), 1.0)

        def make(v, root, ang, fore, spread):
            fore[:, together] = np.minimum(v[:, None] * base, 1.0)
            return root, ang, fore, spread

        ends = pose_ends(eng, st, make, moving, (SEARCH_POSE_FORE, together, base, NOWHERE,
                                                 0.0))
        res = search(eng, st, ends, moving, None, 1.0 / length, 1.0, divisions=divisions,
                     min_step=1.0 / length, prefer=1.0)
        return st.with_entries(fore=(together, np.minimum(res.value * base, 1.0))), res
    step = 1.0 / length
    if seg >= 2:
        u = direction(st.angles[seg]) * eng.L[seg]
        res = limb_search_compiled(eng, st, seg, "ratio", u, None, step, 1.0,
                                   divisions=divisions, min_step=step, start=start,
                                   interval=interval, prefer=1.0)
        if res is not None:
            return st.with_entries(fore=(seg, res.value), scores=(seg, res.score),
                                   margins=(seg, res.margin)), res
        ends = limb_ends(eng, st, seg, moving, "ratio", u)
    else:
        def make(v, root, ang, fore, spread):
            fore[:, seg] = v
            return root, ang, fore, spread

        ends = pose_ends(eng, st, make, moving, (SEARCH_POSE_FORE, [seg], [1.0], NOWHERE, 0.0))
    res = search(eng, st, ends, moving, None, step, 1.0, divisions=divisions, min_step=step,
                 start=start, interval=interval, prefer=1.0)
    return st.with_entries(fore=(seg, res.value), scores=(seg, res.score),
                           margins=(seg, res.margin)), res


def fit_foreshortening(eng: _MaskEngine, st: FitState, *, warm: bool = False,
                       interval: float = 0.4) -> FitState:
    """Algorithm 6 on every segment in turn (``warm``: from each one's current ratio,
    within ``interval``)."""
    for seg in range(10):
        kw = dict(start=st.fore[seg], interval=interval) if warm else {}
        st, _ = search_fore(eng, st, seg, **kw)
    return st


__all__ = ["fit_foreshortening", "search_fore"]
