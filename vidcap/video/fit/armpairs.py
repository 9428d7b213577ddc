"""Both arms searched together (beyond the seed; issue 27, three-quarter views).

:func:`~vidcap.video.fit.grids.search_arm_grid` searches one arm at a time with the other
fixed. Where a bit of the silhouette lies at the torso's edge (the near arm's elbow
bulging at the front of the chest in a three-quarter view), both arms compete for it:
the far arm, its shoulder hidden inside the torso, can fold across the chest to cover
it for free (every pixel it draws inside the torso is already the model's), and once it
has, the near arm gains nothing by reaching for it; S alone prefers the fold as soon
as the near arm, hung from its fitted shoulder, covers the bulge a few pixels worse.
:func:`search_arm_pairs` scores pairs of arm hypotheses together, so the near arm
taking the bulge (the far arm hanging, inside the torso) is compared with the far arm
taking it, with a prior that says what S cannot: an arm segment the torso hides turns
away from hanging only where the silhouette pays for it (:data:`PRIOR_PX` per radian,
weighted by the share of the segment inside the torso). Searched in pairs without the
prior, S itself chose the fold more often (walk_three_quarter's 3D 112 -> 140 mm).
"""

from __future__ import annotations

import numpy as np

from vidcap.video.fit.candidates import scorer
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.grids import _pair_scores, pair_grid
from vidcap.video.fit.limits import TWO_PI, J, S, angle_gap
from vidcap.video.fit.moves import search_angle
from vidcap.video.fit.raster import direction
from vidcap.video.fit.state import FitState, hang

#: The prior's weight: pixels' worth of S per radian an arm segment hidden by the torso
#: turns away from hanging (a point of the segment is hidden where its whole width is
#: inside the torso's rectangle). Chosen on the tuning renders of
#: ``benchmarks/pose2d_attribution.py --hidden solve`` (PCK@0.05 of 15 clips: without the
#: pair search 94.66 %; 10 / 12 / 15 / 20: 94.88 / 95.21 / 95.48 / 95.53) and the
#: walk_three_quarter sample's 3D (PA-MPJPE 112 mm; 116 / 103 / 103 / 100); from 13 up
#: the side view's forearm folded up just past the torso's edge is hung instead
#: (``test_arm_grid_finds_folded_forearm``), so 12. RESULTS.md.
PRIOR_PX = 12.0
_ARMS = {s: (S[f"{s}_upper_arm"], S[f"{s}_lower_arm"], J[f"{s}_shoulder"]) for s in "lr"}


def _apart(ua: np.ndarray, la: np.ndarray, top: int, step: float) -> list[int]:
    """Indices of up to ``top`` of the (upper, lower) angle pairs ``ua``, ``la`` (each
    (N,), radians, best first), each more than two grid steps (``step`` degrees) from
    every one picked before it in one of its angles: the best left, then everything
    within two steps of it out of the running."""
    gap = 2 * np.deg2rad(step) - 1e-9
    picks: list[int] = []
    alive = np.ones(len(ua), dtype=bool)
    while len(picks) < top and alive.any():
        i = int(np.argmax(alive))
        picks.append(i)
        alive &= np.maximum(angle_gap(ua, ua[i]), angle_gap(la, la[i])) > gap
    return picks


def _arm_candidates(eng: _MaskEngine, st: FitState, s: str, top: int, step: float,
                    prior: np.ndarray) -> np.ndarray:
    """(K, 2) (upper, lower) angles: arm ``s``'s ``top`` best grid pairs scored with
    the other arm left out of the model (each at least two grid steps from the ones
    before it), the arm in place and ``prior``."""
    up, lo, base = _ARMS[s]
    ou, ol, _ = _ARMS["r" if s == "l" else "l"]
    probe = st.with_entries(drawn=([ou, ol], False)).drawing([up, lo])
    grid = pair_grid(float(step))
    score = _pair_scores(eng, probe, up, lo, eng.joints(st)[base], grid)
    order = np.argsort(-score, kind="stable")
    # Each pick puts at most the 5 x 5 grid pairs within two steps of it out of the
    # running, so the first top * 25 + 1 of the order hold the same picks as the whole
    # grid (the greedy choice reads only what lies before it); the rest is read only
    # when the prefix runs out.
    picks = _apart(grid[0][order[:top * 25 + 1]], grid[1][order[:top * 25 + 1]], top, step)
    if len(picks) < top:
        picks = _apart(grid[0][order], grid[1][order], top, step)
    ua, la = grid[0][order], grid[1][order]
    out = [(ua[i], la[i]) for i in picks]
    out += [(st.angles[up], st.angles[lo]), tuple(prior)]
    return np.array(out, dtype=float)


def _pair_ends(eng: _MaskEngine, st: FitState, cl: np.ndarray, cr: np.ndarray):
    """``ends(values)`` of every (left, right) candidate pair, ``values`` their flat
    indices into ``len(cl) x len(cr)``: the four arm segments' ends, each (B, 4, 2)."""
    j = eng.joints(st)
    ls, rs = j[_ARMS["l"][2]], j[_ARMS["r"][2]]
    lens = {s: (eng.L[_ARMS[s][0]] * st.fore[_ARMS[s][0]],
                eng.L[_ARMS[s][1]] * st.fore[_ARMS[s][1]]) for s in "lr"}
    n_r = len(cr)

    def arm(c, shoulder, s):
        elbow = shoulder + direction(c[:, 0]) * lens[s][0]
        wrist = elbow + direction(c[:, 1]) * lens[s][1]
        return elbow, wrist

    def ends(values):
        k = np.asarray(values).astype(int)
        el, wl = arm(cl[k // n_r], ls, "l")
        er, wr = arm(cr[k % n_r], rs, "r")
        b = len(k)
        p0 = np.stack([np.broadcast_to(ls, (b, 2)), el, np.broadcast_to(rs, (b, 2)), er], 1)
        p1 = np.stack([el, wl, er, wr], 1)
        return np.ascontiguousarray(p0), np.ascontiguousarray(p1)

    return ends


_ALONG = np.array([0.25, 0.5, 0.75, 1.0])  # where a segment is tested for the torso


def _hidden_cost(eng: _MaskEngine, st: FitState, s: str, c: np.ndarray, h: float) -> np.ndarray:
    """(K,): radians arm ``s`` at the (upper, lower) angle pairs ``c`` (K, 2) turns away
    from hanging (``h``) where the silhouette cannot see it: each segment's turn weighted
    by its share hidden by the torso's rectangle (of points along it, those whose whole
    width is inside); the state's shoulder and foreshortening."""
    up, lo, base = _ARMS[s]
    j = eng.joints(st)
    shoulder, pel = j[base], j[J["pelvis"]]
    ab = j[J["neck"]] - pel
    elbow = shoulder + direction(c[:, 0]) * (eng.L[up] * st.fore[up])
    wrist = elbow + direction(c[:, 1]) * (eng.L[lo] * st.fore[lo])
    p0 = np.stack([np.broadcast_to(shoulder, elbow.shape), elbow], 1)  # (K, 2, 2)
    p1 = np.stack([elbow, wrist], 1)
    q = p0[:, :, None] + _ALONG[:, None] * (p1 - p0)[:, :, None] - pel  # (K, 2, 4, 2)
    t = np.clip((q @ ab) / max(float(ab @ ab), 1e-9), 0.0, 1.0)
    r = q - t[..., None] * ab
    d = np.sqrt((r * r).sum(-1))
    share = (d < (eng.R[S["torso"]] - eng.R[[up, lo]])[:, None]).mean(-1)  # (K, 2)
    return angle_gap(c[:, 0], h) * share[:, 0] + angle_gap(c[:, 1], h) * share[:, 1]


def search_arm_pairs(eng: _MaskEngine, st: FitState, *, step_deg: float = 15.0, top: int = 6,
                     prior_px: float = PRIOR_PX, fine_deg: float = 10.0) -> FitState:
    """Both arms over pairs of their best hypotheses, scored together.

    Each arm's ``top`` best (upper, lower) angle pairs of the whole-arm grid
    (:func:`~vidcap.video.fit.grids.pair_grid`, ``step_deg`` apart), each scored with the
    other arm left out, plus the arm in place and the arm hanging, are paired with the
    other arm's and every pair scored with both arms drawn, less a prior: ``prior_px``
    pixels' worth of S per radian an arm segment turns away from hanging, weighted by
    the share of the segment the torso's rectangle hides (points along it whose whole
    width is inside: there the silhouette cannot see it). The best pair is refined by
    Algorithm 1 (+-``fine_deg``, each arm's upper segment with its forearm, then the
    forearm) and kept where it scores above the arms in place by the same measure.
    Writes the arms' ``angles``, ``scores`` and ``margins``.
    """
    h = hang(st)
    prior = np.array([h, h])
    cl = _arm_candidates(eng, st, "l", top, step_deg, prior)
    cr = _arm_candidates(eng, st, "r", top, step_deg, prior)
    segs = [_ARMS["l"][0], _ARMS["l"][1], _ARMS["r"][0], _ARMS["r"][1]]
    st = st.drawing(segs)
    score = scorer(eng, st, _pair_ends(eng, st, cl, cr), segs)(
        np.arange(len(cl) * len(cr), dtype=float))
    n_sil = max(int(eng.sil_rows[-1]), 1)
    weight = prior_px * 2.0 * float(score.max()) / n_sil  # S per radian hidden
    cost = (_hidden_cost(eng, st, "l", cl, h)[:, None]
            + _hidden_cost(eng, st, "r", cr, h)[None, :]).ravel()
    k = int(np.argmax(score - weight * cost))
    n_r = len(cr)
    chosen = np.concatenate([cl[k // n_r], cr[k % n_r]])
    if np.all(angle_gap(chosen, st.angles[segs]) < 1e-9):
        return st
    fine = np.deg2rad(fine_deg)

    def measure(cur: FitState) -> float:
        a = cur.angles[segs]
        return eng.similarity(cur) - weight * float(
            _hidden_cost(eng, cur, "l", a[None, :2], h)[0]
            + _hidden_cost(eng, cur, "r", a[None, 2:], h)[0])

    cur = st.with_entries(angles=(segs, chosen))
    for s in "lr":
        up, lo, _ = _ARMS[s]
        cur, _ = search_angle(eng, cur, up, with_segments=(lo,), start=cur.angles[up],
                              interval=2 * fine, lo=0.0, hi=TWO_PI, prefer=cur.angles[up])
        cur, _ = search_angle(eng, cur, lo, start=cur.angles[lo], interval=2 * fine,
                              lo=0.0, hi=TWO_PI, prefer=cur.angles[lo])
    return cur if measure(cur) > measure(st) else st


__all__ = ["search_arm_pairs"]
