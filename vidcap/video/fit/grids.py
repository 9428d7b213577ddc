"""Whole-limb grids: one arm or leg scored at every (upper, lower) angle pair at once.

Beyond the seed. Algorithm 1 searches one angle within an interval, so a forearm or
a shin far from its current estimate is never reached, and an arm inside the
torso's silhouette covers the same pixels at any angle. :func:`search_arm_grid` and
:func:`search_leg_grid` score every pair of image-plane angles a grid step apart
(bend within the flexion limit) in one batch against the rest of the model, refine
the winner with Algorithm 1 (and 6) and keep it by :func:`~vidcap.video.fit.state.
keep_if_better`.
"""

from __future__ import annotations

import functools

import numpy as np

from vidcap.video.fit.candidates import scorer, still_tables
from vidcap.video.fit.engine import _MaskEngine, fit_kernels
from vidcap.video.fit.foreshortening import search_fore
from vidcap.video.fit.limits import LIMITS, MAX_BEND, THIGH_WIDE, TWO_PI, J, S
from vidcap.video.fit.moves import search_angle
from vidcap.video.fit.raster import _carray, direction
from vidcap.video.fit.state import FitState, hang, keep_if_better


@functools.lru_cache(maxsize=8)
def pair_grid(step_deg: float, legs: bool = False):
    """Every (upper, lower) angle pair ``step_deg`` apart whose elbow (knee) bend is
    within the flexion limit: the candidates of :func:`search_arm_grid` (any
    direction) or, with ``legs``, of :func:`search_leg_grid` (thigh within
    ``THIGH_WIDE``, shin within the lower leg's limits: both point down), radians,
    each (N,), and their directions (:func:`direction`), each (N, 2) (read-only:
    shared by every call)."""
    if legs:
        def within(lim):  # whole degrees from the limits, as the arms' grid
            lo, hi = np.round(np.rad2deg(lim), 6)
            return np.deg2rad(np.arange(lo, hi + 1e-9, step_deg))

        up, low = within(THIGH_WIDE), within(LIMITS["l_lower_leg"])
    else:
        up = low = np.deg2rad(np.arange(0.0, 360.0, step_deg))
    ua, la = (g.ravel() for g in np.meshgrid(up, low, indexing="ij"))
    bend = np.abs(np.angle(np.exp(1j * (la - ua))))
    keep = bend <= MAX_BEND + 1e-9
    ua, la = ua[keep], la[keep]
    du, dl = direction(ua), direction(la)
    for x in (ua, la, du, dl):
        x.flags.writeable = False
    return ua, la, du, dl


def search_arm_grid(eng: _MaskEngine, st: FitState, s: str, *, prior=None, step_deg=15.0,
                    tie_px=10.0, fine_deg=10.0) -> FitState:
    """Search one whole arm over every (upper, lower) angle pair at once (beyond the seed).

    Among the candidates within ``tie_px`` pixels' worth of similarity of the best,
    the one closest to ``prior`` wins (the previous frame's arm when tracking, else
    an arm hanging along the torso), so a hidden arm is carried rather than put at
    an arbitrary angle. The winner is refined by Algorithm 1 (+-``fine_deg``) and
    kept unless the arm already in place fits better by more than the tie. Writes
    the arm's ``angles``, ``scores`` and ``margins``.

    Parameters
    ----------
    s : {'l', 'r'}
        Which arm (image-left/right label).
    prior : tuple of float, optional
        ``(upper, lower)`` angles in radians preferred among near-ties.
    """
    if prior is None:
        prior = (hang(st), hang(st))
    return _search_pair_grid(eng, st, S[f"{s}_upper_arm"], S[f"{s}_lower_arm"],
                             J[f"{s}_shoulder"], pair_grid(float(step_deg)), prior,
                             tie_px=tie_px, fine_deg=fine_deg, keep_px=tie_px)


#: The (upper, lower arm) foreshortening :func:`search_arm_track` scores its candidates
#: at: full length, so a forearm the track had shrunk is found again at its length
#: (scoring the upper arm foreshortened too folded forearms into the torso: HISTORY.md).
ARM_TRACK_FORE = (1.0, 1.0)


def search_arm_track(eng: _MaskEngine, st: FitState, s: str, *, step_deg=15.0, tie_px=10.0,
                     fine_deg=10.0, upper_deg=30.0) -> FitState:
    """A tracked frame's whole arm over every (upper, lower) angle pair (beyond the seed).

    A tracked frame searches each arm segment within +-16 degrees of the previous
    frame's, so a forearm that swings faster (a raise or a wave at 20 degrees a frame)
    is left behind, and the track then shrinks it (Algorithm 6) rather than turn it.
    Here the arm is scored at every angle pair ``step_deg`` apart, the upper arm
    within ``upper_deg`` of the track's, at full length (its
    foreshortening reset to 1, so a forearm the track had shrunk can be found again
    at its length), the winner refined by Algorithm 1 (+-``fine_deg``) and
    Algorithm 6, and kept only when it fits better than the arm in place by more than
    ``tie_px`` pixels' worth of S; near-ties go to the candidate nearest the arm in
    place, so an arm inside the torso's outline (the same pixels at any angle) stays
    where the track carried it. Writes the arm's ``angles``, ``fore``, ``scores``,
    ``margins``.

    Parameters
    ----------
    s : {'l', 'r'}
        Which arm (its label: image side, or the track's).
    """
    up, lo = S[f"{s}_upper_arm"], S[f"{s}_lower_arm"]
    grid = pair_grid(float(step_deg))
    # the upper arm near the track's (it turns slowly about the shoulder, and an upper
    # arm swung across the torso's outline, the forearm hanging beyond it, can fit a
    # walk's silhouette a little better than the arm it is), the forearm anywhere
    # (a hair over: the grid's angles are whole degrees in floats)
    reach = float(np.deg2rad(upper_deg)) + 1e-9
    near = np.abs(np.angle(np.exp(1j * (grid[0] - st.angles[up])))) <= reach
    grid = tuple(g[near] for g in grid)
    return _search_pair_grid(eng, st, up, lo, J[f"{s}_shoulder"], grid,
                             (st.angles[up], st.angles[lo]), tie_px=tie_px, fine_deg=fine_deg,
                             keep_px=-tie_px, lengths=True, skip_within=np.deg2rad(step_deg),
                             at_fore=ARM_TRACK_FORE, bend_limit=True)


def search_leg_grid(eng: _MaskEngine, st: FitState, s: str, *, step_deg=15.0, tie_px=3.0,
                    fine_deg=10.0) -> FitState:
    """Search one whole leg over every (thigh, shin) angle pair at once (beyond the seed).

    A tracked frame searches each leg segment within +-8 degrees of the previous
    frame's, so a leg that swung further between frames (a knee raised across the
    other leg, a kick, a step seen from three-quarter view) is lost. Here every
    thigh direction within ``THIGH_WIDE`` and shin direction within the lower leg's
    limits, ``step_deg`` apart, is scored in one batch; near-ties (``tie_px``
    pixels' worth of similarity) go to the candidate closest to the leg in place.
    The winner is refined by Algorithm 1 (+-``fine_deg``) and Algorithm 6, and kept
    only if it fits better than the leg in place by more than the tie (a leg is
    rarely hidden whole). A winner within one grid step of the leg in place is
    what the track's own search already found, and is not refined (the grid then
    costs one compiled batch). Writes the leg's ``angles``, ``fore``, ``scores``,
    ``margins``.

    Parameters
    ----------
    s : {'l', 'r'}
        Which leg (its label: image side, or the track's).
    """
    up, lo = S[f"{s}_upper_leg"], S[f"{s}_lower_leg"]
    return _search_pair_grid(eng, st, up, lo, J[f"{s}_hip"], pair_grid(float(step_deg), legs=True),
                             (st.angles[up], st.angles[lo]), tie_px=tie_px, fine_deg=fine_deg,
                             keep_px=-tie_px, upper_range=THIGH_WIDE, lengths=True,
                             skip_within=np.deg2rad(step_deg))


def _pair_scores(eng, st, up, lo, root, grid):
    """S of every candidate of ``grid`` (N,): the limb ``up``, ``lo`` hanging from
    ``root`` at each angle pair, the rest of the model as in ``st``."""
    kernels = fit_kernels()
    if kernels is None:
        return _pair_scores_numpy(eng, st, up, lo, root, grid)
    return _pair_scores_compiled(kernels, eng, st, up, lo, root, grid)


def _pair_ends(st, eng, up, lo, root, grid):
    _, _, du, dl = grid
    len_u, len_l = eng.L[up] * st.fore[up], eng.L[lo] * st.fore[lo]

    def ends(idx):
        k = idx.astype(int)
        mid = root + du[k] * len_u
        tip = mid + dl[k] * len_l
        p0 = np.stack([np.broadcast_to(root, mid.shape), mid], axis=1)
        p1 = np.stack([mid, tip], axis=1)
        return p0, p1

    return ends


def _pair_scores_numpy(eng, st, up, lo, root, grid):
    ends = _pair_ends(st, eng, up, lo, root, grid)
    return scorer(eng, st, ends, [up, lo])(np.arange(len(grid[0]), dtype=float))


def _pair_scores_compiled(kernels, eng, st, up, lo, root, grid):
    # the candidates' ends built inside the compiled pass (the same floats)
    ua, _, du, dl = grid
    ends = _pair_ends(st, eng, up, lo, root, grid)
    (r0, r1), cum, a, m_base, i_base = still_tables(eng, st, ends, np.array([up, lo]), None)
    score, q = np.empty(len(ua)), np.empty(len(ua))
    kernels.arm_pair_terms(du, dl, _carray(root, np.float64), float(eng.L[up] * st.fore[up]),
                           float(eng.L[lo] * st.fore[lo]), _carray(eng.R[[up, lo]], np.float64),
                           cum, r0, r1, bool(eng.caps), a, int(m_base[0]), int(i_base[0]),
                           score, q)
    np.exp(score, out=score)  # S = exp(-p - n) (1 - p), as _similarity_terms
    score *= q
    return score


def _search_pair_grid(eng, st, up, lo, base, grid, prior, *, tie_px, fine_deg, keep_px,
                      upper_range=(0.0, TWO_PI), lengths=False, skip_within=0.0,
                      at_fore=None, bend_limit=False) -> FitState:
    """The whole-limb grid of :func:`search_arm_grid` and :func:`search_leg_grid`.

    ``up``, ``lo``: the limb's segments; ``base``: the joint it hangs from;
    ``grid``: :func:`pair_grid`'s candidates; ``prior``: (upper, lower)
    radians preferred among candidates within ``tie_px`` pixels' worth of S of
    the best. The refined winner replaces the limb in place unless it fits
    worse than it by more than ``keep_px`` pixels' worth (negative: unless it
    fits better by more than ``-keep_px``), or within that and farther from
    ``prior``. ``upper_range``: the upper segment's refinement limits;
    ``lengths``: also refine both segments' foreshortening (Algorithm 6).
    ``skip_within``: radians (upper + lower); a winner this close to ``prior``
    is left unrefined and the limb in place kept. ``at_fore``: the (upper, lower)
    foreshortening the candidates are scored at and refined from, instead of the
    limb's own; ``bend_limit``: the
    lower segment's refinement stays within the flexion limit's bend of the upper.
    """
    prior = np.asarray(prior, dtype=float)
    st = st.drawing([up, lo])
    ua, la = grid[0], grid[1]
    root = eng.joints(st)[base]
    probe = st if at_fore is None else st.with_entries(fore=([up, lo], list(at_fore)))
    score = _pair_scores(eng, probe, up, lo, root, grid)
    n_sil = max(int(eng.sil_rows[-1]), 1)
    per_px = 2.0 * float(score.max()) / n_sil  # S worth one pixel, about

    def distance(u, low):
        return (np.abs(np.angle(np.exp(1j * (u - prior[0]))))
                + np.abs(np.angle(np.exp(1j * (low - prior[1])))))

    near = np.flatnonzero(score >= score.max() - tie_px * per_px)
    k = near[np.argmin(distance(ua[near], la[near]))]
    if distance(ua[k], la[k]) < skip_within:
        return st  # the limb in place is (near) the winner: nothing to refine
    fine = np.deg2rad(fine_deg)

    def refine(cur: FitState) -> FitState:
        if at_fore is not None:
            cur = probe
        cur = cur.with_entries(angles=([up, lo], [ua[k], la[k]]))
        cur, _ = search_angle(eng, cur, up, with_segments=(lo,), start=ua[k],
                              interval=2 * fine, lo=upper_range[0], hi=upper_range[1],
                              prefer=ua[k])
        if lengths:
            bounds = {}
            if bend_limit:  # the lower segment within the flexion limit of the upper
                u = float(cur.angles[up])
                bounds = {"lo": u - MAX_BEND, "hi": u + MAX_BEND}
            cur, _ = search_angle(eng, cur, lo, start=la[k], interval=2 * fine, prefer=la[k],
                                  **bounds)
            cur, _ = search_fore(eng, cur, up)
            cur, _ = search_fore(eng, cur, lo)
        else:
            cur, _ = search_angle(eng, cur, lo, start=la[k], interval=2 * fine, lo=0.0,
                                  hi=TWO_PI, prefer=la[k])
        return cur

    def farther(new: FitState, kept: FitState) -> bool:
        return distance(new.angles[up], new.angles[lo]) > distance(kept.angles[up],
                                                                  kept.angles[lo])

    return keep_if_better(eng.similarity, st, refine, tie=keep_px * per_px,
                          prefer_kept=farther)


__all__ = ["pair_grid", "search_arm_grid", "search_arm_track", "search_leg_grid"]
