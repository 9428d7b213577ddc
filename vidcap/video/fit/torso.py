"""Torso and head: where the pelvis goes, and Algorithm 1 on the torso and the head.

Seed 004 section 3.1.4 steps 2-3: the pelvis from the Table 3.1 ratios and the
silhouette's horizontal middle (:func:`place_torso`), the torso's angle with the head
attached, then the head's (:func:`fit_torso_head`); beyond the seed, the torso turned
about the neck (:func:`search_torso_about_neck`).
"""

from __future__ import annotations

import numpy as np

from vidcap.video.fit.candidates import pose_ends, search
from vidcap.video.fit.contour import row_runs
from vidcap.video.fit.engine import _MaskEngine, fit_kernels
from vidcap.video.fit.limits import ONE_DEGREE, J, S, median
from vidcap.video.fit.modes import SEARCH_POSE_TORSO_NECK
from vidcap.video.fit.moves import search_angle, search_root
from vidcap.video.fit.raster import _carray, direction
from vidcap.video.fit.search import SearchResult
from vidcap.video.fit.state import FitState

#: Torso directions the searches about the neck may reach (degrees from the image's +x,
#: y up): wider than the seed's Table 3.3 limits (45-135) so a body bent forward or
#: leaning into a crouch or lunge is not clamped at 45 degrees from the vertical
#: (issue 27 item 4). The seed's own search about the pelvis keeps the seed's limits.
TORSO_WIDE = (np.deg2rad(15.0), np.deg2rad(165.0))
#: A row of the silhouette at least this many head radii wide can be the head's; the
#: rows above the first such row are narrower than a head: a raised forearm above it
#: (:func:`head_top`; chosen on pose2sim_balance cam4, the leaning balance poses with a
#: hand above the head).
HEAD_ROW_WIDTH = 1.6


def place_torso(eng: _MaskEngine, st: FitState) -> FitState:
    """Pelvis from the Table 3.1 ratios and the silhouette's horizontal middle.

    Writes ``root`` (normalised px): its y the head and torso lengths below the
    silhouette's top (a silhouette taller than the body: the legs' length above its
    bottom), its x the median over the torso's rows of the middle of each row's
    widest run.
    """
    neck_y = eng.top + eng.L[S["head"]]
    pelvis_y = neck_y + eng.L[S["torso"]]
    if eng.taller:  # stand on the silhouette's bottom
        legs = eng.L[S["l_upper_leg"]] + eng.L[S["l_lower_leg"]]
        pelvis_y = eng.norm.bottom - eng.foot - legs
        neck_y = pelvis_y - eng.L[S["torso"]]
    band = eng.sil[int(round(neck_y)) : int(round(pelvis_y)) + 1]
    kernels = fit_kernels()
    x = _band_middle_numpy(band) if kernels is None else _band_middle_compiled(kernels, band)
    if x is None:
        x = float(np.median(np.nonzero(eng.sil)[1]))
    return st.replace(root=np.array([x, pelvis_y]))


def _band_middle_compiled(kernels, band) -> float | None:
    mid = np.empty(band.shape[0])
    count = kernels.widest_run_middles(_carray(band, np.bool_), mid)
    return median(mid[:count]) if count else None


def _band_middle_numpy(band) -> float | None:
    """The median middle of each row's widest run (ties: the rightmost), None without
    any run."""
    rows, starts, ends = row_runs(band)
    if not rows.size:
        return None
    widest = np.zeros(band.shape[0], dtype=int)
    mid = np.zeros(band.shape[0])
    width = ends - starts + 1
    order = np.lexsort((width, rows))  # per row, widest run last
    widest[rows[order]] = width[order]
    mid[rows[order]] = 0.5 * (starts[order] + ends[order])
    return float(np.median(mid[widest > 0]))


def fit_torso_head(eng: _MaskEngine, st: FitState, *, warm: bool = False) -> FitState:
    """Algorithm 1 on the torso (head attached) about the pelvis, then on the head.

    ``warm``: only the torso about the neck (+-10 degrees) and the head (+-15) from
    their current angles. Writes ``angles``, ``scores``, ``margins`` of torso and
    head, and ``root``.
    """
    top_rows = (0, st.root[1] + 1)
    if warm:
        st, _ = search_torso_about_neck(eng, st, start=st.angles[S["torso"]],
                                        interval=np.deg2rad(20), rows=top_rows)
        neck_y = eng.joints(st)[J["neck"], 1]
        st, _ = search_angle(eng, st, S["head"], rows=(0, neck_y + eng.R[S["torso"]]),
                             start=st.angles[S["head"]], interval=np.deg2rad(30))
        return st
    # The seed: torso with the head attached (Alg. 1) about the pelvis, then the head.
    st = st.with_entries(angles=(S["head"], st.angles[S["torso"]]))
    st, _ = search_angle(eng, st, S["torso"], with_segments=(S["head"],), rows=top_rows)
    neck_y = eng.joints(st)[J["neck"], 1]
    head_rows = (0, neck_y + eng.R[S["torso"]])
    st, _ = search_angle(eng, st, S["head"], rows=head_rows)
    # Beyond the seed: the silhouette's middle is pulled by arms and legs, the head
    # is not. Line the head up with the silhouette (shift the whole model), then
    # turn the torso about the neck so a leaning torso under an upright head is
    # found, and look at the head again.
    st, _ = search_root(eng, st, 0, 0.1 * eng.H, rows=(0, neck_y))
    st, _ = search_torso_about_neck(eng, st, start=st.angles[S["torso"]],
                                    interval=np.deg2rad(40), rows=top_rows)
    st, _ = search_angle(eng, st, S["head"], rows=head_rows, start=st.angles[S["head"]],
                         interval=np.deg2rad(20))
    return st


def head_top(sil: np.ndarray, head_radius: float) -> int | None:
    """The first row of ``sil`` (h, w) bool with a run at least :data:`HEAD_ROW_WIDTH`
    head radii wide (None: no such row): where the head can begin when narrower parts
    (a hand raised above the head) top the silhouette.

    Examples
    --------
    >>> sil = np.zeros((10, 12), bool)
    >>> sil[0:4, 5:7] = True   # a forearm, 2 px wide
    >>> sil[4:10, 3:9] = True  # a head, 6 px wide
    >>> head_top(sil, 3.0), head_top(sil, 1.0)
    (4, 0)
    """
    rows, c0, c1 = row_runs(sil)
    wide = (c1 - c0 + 1) >= HEAD_ROW_WIDTH * head_radius
    return int(rows[wide].min()) if wide.any() else None


def fit_torso_lean(eng: _MaskEngine, st: FitState) -> FitState:
    """The torso and head of a body far from upright (beyond the seed; issue 27 item 4).

    The seed hangs the torso from the pelvis placed by the Table 3.1 ratios, which
    holds for an upright body only: bent forward, crouched or in a lunge the pelvis is
    lower and to one side. The head usually tops the silhouette, so the neck is put one
    head length below the silhouette's top, under the middle of the head's rows, and
    the torso (head attached upright) is turned about it over :data:`TORSO_WIDE`,
    then the head searched. Where rows narrower than a head top the silhouette (a hand
    raised above a leaning body: :func:`head_top` more than half a head below the
    top), the same is tried from the first row as wide as a head, and the better fit
    (S of torso and head) kept. Writes ``angles``, ``scores``, ``margins`` of torso and
    head, and ``root``.
    """
    out = _torso_lean_from(eng, st, eng.top)
    first = head_top(eng.sil, eng.R[S["head"]])
    if first is None or first - eng.norm.top < 0.5 * eng.L[S["head"]]:
        return out
    lower = _torso_lean_from(eng, st, first + (eng.top - eng.norm.top))
    return lower if eng.similarity(lower) > eng.similarity(out) else out


def _torso_lean_from(eng: _MaskEngine, st: FitState, top: float) -> FitState:
    """:func:`fit_torso_lean` with the head's top at row ``top`` (normalised px)."""
    head_len = eng.L[S["head"]]
    band = eng.sil[int(round(top)): int(round(top + head_len)) + 1]
    kernels = fit_kernels()
    x = _band_middle_numpy(band) if kernels is None else _band_middle_compiled(kernels, band)
    if x is None:
        return st
    neck = np.array([x, top + head_len])
    up = np.pi / 2
    length = eng.L[S["torso"]] * st.fore[S["torso"]]
    ang = st.angles.copy()
    ang[S["torso"]] = up
    ang[S["head"]] = up
    st = st.replace(angles=ang, root=neck - direction(up) * length).drawing(
        [S["torso"], S["head"]])
    lo, hi = TORSO_WIDE
    # one step per 5 degrees first: over so wide a range the score has more than one peak
    st, _ = search_torso_about_neck(eng, st, start=up, interval=hi - lo, divisions=30)
    # a bent head is no longer a head length tall: turn it with the torso, search it,
    # move the model to the silhouette, and look at torso and head again, narrower
    st = st.with_entries(angles=(S["head"], st.angles[S["torso"]]))
    st, _ = _search_head(eng, st, interval=np.deg2rad(90))
    st, _ = search_root(eng, st, 1, 0.1 * eng.H)
    st, _ = search_root(eng, st, 0, 0.1 * eng.H)
    for _ in range(2):
        # about the pelvis with the head attached (the seed's move), then about the neck
        st, _ = search_angle(eng, st, S["torso"], with_segments=(S["head"],), lo=lo, hi=hi,
                             start=st.angles[S["torso"]], interval=np.deg2rad(40))
        st, _ = search_torso_about_neck(eng, st, start=st.angles[S["torso"]],
                                        interval=np.deg2rad(40))
        st, _ = _search_head(eng, st, interval=np.deg2rad(40))
    return st


def _search_head(eng: _MaskEngine, st: FitState, *, interval) -> tuple[FitState, SearchResult]:
    """Algorithm 1 on the head about its current angle, within :data:`TORSO_WIDE`."""
    neck_y = eng.joints(st)[J["neck"], 1]
    return search_angle(eng, st, S["head"], rows=(0, neck_y + eng.R[S["torso"]]),
                        lo=TORSO_WIDE[0], hi=TORSO_WIDE[1], start=st.angles[S["head"]],
                        interval=interval)


def search_torso_about_neck(eng: _MaskEngine, st: FitState, *, start, interval, rows=None,
                            alone=False, divisions=8) -> tuple[FitState, SearchResult]:
    """Algorithm 1 on the torso angle with the neck held still (beyond the seed).

    Writes the torso's ``angles``, ``scores``, ``margins`` and ``root`` (the pelvis
    moves). ``alone``: score the torso's candidates with the limbs left where they
    are (they re-attach afterwards); a cheaper approximation for small, warm steps.
    """
    seg = S["torso"]
    st = st.drawing(seg)
    lo, hi = TORSO_WIDE
    neck = eng.joints(st)[J["neck"]].copy()
    length = eng.L[seg] * st.fore[seg]
    moving = [seg] if alone else [d for d in range(10) if st.drawn[d]]

    def make(v, root, ang, fore, spread):
        ang[:, seg] = v
        return neck - direction(v) * length, ang, fore, spread

    ends = pose_ends(eng, st, make, moving, (SEARCH_POSE_TORSO_NECK, [seg], [0.0], neck,
                                             length))
    res = search(eng, st, ends, moving, rows, lo, hi, divisions=divisions, min_step=ONE_DEGREE,
                 start=start, interval=interval)
    st = st.with_entries(angles=(seg, res.value), scores=(seg, res.score),
                         margins=(seg, res.margin))
    return st.replace(root=neck - direction(res.value) * length), res


__all__ = ["HEAD_ROW_WIDTH", "TORSO_WIDE", "fit_torso_head", "fit_torso_lean", "head_top",
           "place_torso",
           "search_torso_about_neck"]
