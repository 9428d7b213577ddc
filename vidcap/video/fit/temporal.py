"""A solve over the clip: the path through per-frame candidates that balances each
frame's cost against the cost of moving between frames (Viterbi).

:func:`best_path` is the dynamic programme over any candidates. :func:`label_path`
uses it for the limb labels of a tracked fit: per frame and limb pair (arms, legs)
two candidates, the labels as fitted and swapped, which draw the same pixels. A
track keeps its labels through crossings, but where a fresh fit takes over (a
slipping track, a challenge) its image-side names can come out swapped against the
frames before, for that frame or from then on; the solve relabels such stretches
so the joints move least across their ends, while labels carried by a warm start
stay linked to the frame they came from.
"""

from __future__ import annotations

import numpy as np

from vidcap.body import JOINT_INDEX
from vidcap.video.fit.labels import LIMB_PAIRS

#: Cost, in body heights per joint, of changing labels across a warm start (a track
#: carries its limbs' names from the frame it started from).
LINK_COST = 0.05
#: Cost of swapping a frame's labels for nothing: ties keep the labels as fitted.
_SWAP_TIE = 1e-9


def best_path(unary: np.ndarray, transition: np.ndarray) -> tuple[np.ndarray, float]:
    """The candidate per frame that minimises the total cost (Viterbi).

    Parameters
    ----------
    unary : numpy.ndarray, shape (F, K)
        Cost of candidate k in frame f (finite).
    transition : numpy.ndarray, shape (F - 1, K, K)
        ``transition[f, a, b]``: cost of candidate a in frame f followed by candidate
        b in frame f + 1 (finite).

    Returns
    -------
    path : numpy.ndarray, shape (F,), int
        The chosen candidate per frame (ties: the lower index).
    cost : float
        Its total cost.

    Examples
    --------
    >>> import numpy as np
    >>> unary = np.array([[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]])  # frame 1 prefers 1
    >>> move = np.array([[0.0, 0.6], [0.6, 0.0]])          # changing costs 0.6 each way
    >>> best_path(unary, np.stack([move, move]))[0].tolist()  # 1.2 to go there and back
    [0, 0, 0]
    >>> best_path(unary, np.stack([move, move]) / 2)[0].tolist()  # 0.6 < 1.0
    [0, 1, 0]
    """
    unary = np.asarray(unary, dtype=float)
    transition = np.asarray(transition, dtype=float)
    n, k = unary.shape
    if transition.shape != (max(n - 1, 0), k, k):
        raise ValueError(f"transition must be ({n - 1}, {k}, {k}), got {transition.shape}")
    if not (np.isfinite(unary).all() and np.isfinite(transition).all()):
        raise ValueError("costs must be finite")
    if n == 0:
        return np.zeros(0, dtype=int), 0.0
    back = np.empty((max(n - 1, 0), k), dtype=int)
    cost = unary[0].copy()
    cols = np.arange(k)
    for f in range(n - 1):  # K is tiny: one small vector step per frame
        total = cost[:, None] + transition[f]
        back[f] = np.argmin(total, axis=0)
        cost = total[back[f], cols] + unary[f + 1]
    path = np.empty(n, dtype=int)
    path[-1] = int(np.argmin(cost))
    for f in range(n - 2, -1, -1):
        path[f] = back[f, path[f + 1]]
    return path, float(cost[path[-1]])


def label_path(joints2d: np.ndarray, height_px: np.ndarray, linked: np.ndarray, *,
               link_cost: float = LINK_COST) -> dict[str, np.ndarray]:
    """Which frames' limb pairs to relabel so labels follow the limbs over the clip.

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, 2)
        The fitted joints, pixels (NaN in frames without a silhouette).
    height_px : numpy.ndarray, shape (F,)
        The body height per frame, pixels (NaN where unknown).
    linked : numpy.ndarray, shape (F,), bool
        Frame f's labels were carried from frame f - 1 (a warm start).
    link_cost : float
        Cost of changing labels across a link, body heights per joint.

    Returns
    -------
    dict
        ``{"arms": swap, "legs": swap}``, each (F,) bool: relabel that pair in that
        frame. Moving between frames costs the mean distance of the pair's joints,
        in body heights; frames without joints cost nothing either way.
    """
    j = np.asarray(joints2d, dtype=float)
    h = np.asarray(height_px, dtype=float)
    n = len(j)
    out = {}
    for name, ((jl, _), (jr, _)) in LIMB_PAIRS.items():
        both, other = jl + jr, jr + jl
        if n < 2:
            out[name] = np.zeros(n, dtype=bool)
            continue
        scale = np.nanmean(np.stack([h[:-1], h[1:]]), axis=0)
        same = np.linalg.norm(j[1:, both] - j[:-1, both], axis=-1).mean(-1) / scale
        swapped = np.linalg.norm(j[1:, other] - j[:-1, both], axis=-1).mean(-1) / scale
        known = np.isfinite(same) & np.isfinite(swapped)
        same, swapped = np.where(known, same, 0.0), np.where(known, swapped, 0.0)
        change = swapped + np.where(np.asarray(linked[1:], dtype=bool) & known, link_cost, 0.0)
        transition = np.empty((n - 1, 2, 2))
        transition[:, 0, 0] = transition[:, 1, 1] = same
        transition[:, 0, 1] = transition[:, 1, 0] = change
        unary = np.zeros((n, 2))
        unary[:, 1] = _SWAP_TIE
        path, _ = best_path(unary, transition)
        out[name] = path.astype(bool)
    return out


def relabel(arrays: dict[str, np.ndarray], swaps: dict[str, np.ndarray]) -> None:
    """Swap the limb pairs' labels in the frames ``swaps`` names, in place.

    ``arrays``: ``joints`` (F, 15, 2) and per-segment ``(F, 10)`` arrays (any other
    key); ``swaps``: :func:`label_path`'s result.
    """
    for name, ((jl, sl), (jr, sr)) in LIMB_PAIRS.items():
        f = np.flatnonzero(swaps[name])
        if not f.size:
            continue
        for key, a in arrays.items():
            x, y = (jl, jr) if key == "joints" else (sl, sr)
            a[f[:, None], x + y] = a[f[:, None], y + x]


#: Weight of an arm candidate's cost (J below the frame's best, units of S) against
#: the movement of its elbow and wrist between frames (body heights, mean of the two).
ARM_FIT_WEIGHT = 10.0
#: Cost per radian an arm candidate's elbow turns against the way the clip's elbows
#: bend (:func:`elbow_bend_signs`), beyond :data:`BEND_FREE` (chosen on the tuning
#: clips: 0.5, 2, 5, 20 and 100 gave +0.1, +0.3, +0.3, +0.3, +0.3 points).
ARM_BEND_WEIGHT = 5.0
#: A knee or elbow turned less than this either way says nothing of which way the
#: body faces, and an elbow may turn this far against the clip's bend for free.
BEND_FREE = np.deg2rad(10.0)
#: Spread from which the shoulders stand far enough apart in the image (a body turned
#: towards the camera) that an elbow's bend there no longer shows which way it faces.
BEND_SPREAD = 0.7
#: Fewest bent knees (legs x frames) to tell the way the clip's body faces.
BEND_SURE = 10


def turn(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Signed turn from image vectors ``a`` to ``b`` (..., 2) in pixels (y down):
    radians in (-pi, pi], counter-clockwise with y up (the fit's angle convention)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return np.angle(np.exp(1j * (np.arctan2(-b[..., 1], b[..., 0])
                                 - np.arctan2(-a[..., 1], a[..., 0]))))


def elbow_bend_signs(joints2d: np.ndarray, spread: np.ndarray) -> np.ndarray:
    """The way an elbow bends in the image per frame: +1 (counter-clockwise from upper
    to lower arm, y up), -1, or 0 (either way).

    A knee bends back and an elbow forward, so seen from the side the two turn
    opposite ways: the elbows' sign is the opposite of the median turn of the clip's
    knees bent more than :data:`BEND_FREE`. 0 where the spread is at least
    :data:`BEND_SPREAD` (a view near the front: the forearm bends towards or away from
    the camera), and everywhere when fewer than :data:`BEND_SURE` knees are bent.

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, 2)
        The fitted joints, pixels (NaN: no fit).
    spread : numpy.ndarray, shape (F,)
        The fitted spread per frame (NaN: no fit).

    Returns
    -------
    numpy.ndarray, shape (F,), float
    """
    j = np.asarray(joints2d, dtype=float)
    knees = np.concatenate([
        turn(j[:, JOINT_INDEX[f"{s}_knee"]] - j[:, JOINT_INDEX[f"{s}_hip"]],
             j[:, JOINT_INDEX[f"{s}_ankle"]] - j[:, JOINT_INDEX[f"{s}_knee"]])
        for s in "lr"])
    bent = knees[np.isfinite(knees) & (np.abs(knees) > BEND_FREE)]
    if len(bent) < BEND_SURE:
        return np.zeros(len(j))
    side = np.nan_to_num(np.asarray(spread, dtype=float), nan=1.0) < BEND_SPREAD
    return np.where(side, -np.sign(np.median(bent)), 0.0)


def arm_path(joints2d: np.ndarray, height_px: np.ndarray, candidates, *,
             fit_weight: float = ARM_FIT_WEIGHT, bend_sign: np.ndarray | None = None,
             bend_weight: float = ARM_BEND_WEIGHT) -> dict[str, np.ndarray]:
    """Each arm's placement per frame chosen over the clip among its candidates.

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, 2)
        The fitted joints, pixels (their elbows and wrists are each frame's first
        candidate).
    height_px : numpy.ndarray, shape (F,)
        Body height per frame, pixels.
    candidates : sequence of dict or None, length F
        Per frame :attr:`vidcap.video.fit.result.FramePose.arm_candidates` (None: the
        frame has only its fitted arms).
    fit_weight : float
        Cost per unit of S a candidate fits worse than the frame's best, against one
        body height of elbow and wrist movement between frames.
    bend_sign : numpy.ndarray, shape (F,), optional
        The way elbows bend per frame (:func:`elbow_bend_signs`; 0: either way). A
        candidate whose elbow turns the other way by more than :data:`BEND_FREE` costs
        ``bend_weight`` per radian beyond it (an arm inside the torso's outline fits
        bent either way; a real elbow bends one way only). None: no such cost.
    bend_weight : float

    Returns
    -------
    dict
        ``{"l": (elbows (F, 2), wrists (F, 2)), "r": ...}``: the chosen elbows and
        wrists (the fitted ones where nothing better was chosen).
    """
    j = np.asarray(joints2d, dtype=float)
    h = np.asarray(height_px, dtype=float)
    n = len(j)
    out = {}
    for s in ("l", "r"):
        ie, iw = JOINT_INDEX[f"{s}_elbow"], JOINT_INDEX[f"{s}_wrist"]
        k_max = max([len(c[s][2]) for c in candidates if c and s in c] or [1])
        ends = np.repeat(j[:, None, [ie, iw]], k_max, axis=1)  # (F, K, 2 joints, 2)
        unary = np.zeros((n, k_max))
        unary[:, 1:] = np.inf
        for f, c in enumerate(candidates):
            if c and s in c and np.isfinite(j[f, [ie, iw]]).all():
                e, w, cost = c[s]
                ends[f, :len(cost), 0], ends[f, :len(cost), 1] = e, w
                unary[f, :len(cost)] = fit_weight * cost
                if bend_sign is not None and bend_sign[f]:
                    bend = turn(np.asarray(e) - j[f, JOINT_INDEX[f"{s}_shoulder"]],
                                np.asarray(w) - np.asarray(e))
                    against = np.maximum(-bend_sign[f] * bend - BEND_FREE, 0.0)
                    unary[f, :len(cost)] += bend_weight * against
        big = 1e6  # a slot a frame does not have: never chosen
        unary = np.where(np.isfinite(unary), unary, big)
        scale = np.nan_to_num(np.nanmean(np.stack([h[:-1], h[1:]]), axis=0), nan=1.0)
        move = np.linalg.norm(ends[1:, None] - ends[:-1, :, None], axis=-1).mean(-1)
        move = np.nan_to_num(move / scale[:, None, None], nan=0.0)
        path, _ = best_path(unary, move) if n else (np.zeros(0, int), 0.0)
        pick = ends[np.arange(n), path]
        out[s] = (pick[:, 0], pick[:, 1])
    return out


__all__ = ["ARM_BEND_WEIGHT", "ARM_FIT_WEIGHT", "BEND_FREE", "LINK_COST", "arm_path",
           "best_path", "elbow_bend_signs", "label_path", "relabel", "turn"]
