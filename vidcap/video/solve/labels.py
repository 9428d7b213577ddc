"""Which 2D limb is the body's left one, chosen by the clip solve (issue 33).

The 2D fit names the legs (and arms) by tracking them, and loses them where they
cross: for stretches of frames its left knee and ankle are the body's right ones. The
solve then bends the body to fit the wrong names. Here each limb pair takes, per
frame, one of two labelings, as named or with the pair's left and right distal joints
(knee and ankle; elbow and wrist: the hips and shoulders come with the torso)
exchanged. Both are solved over the clip (the swapped one from the named solution with
the two limbs' 3D segments exchanged), scored per frame by the solve's own cost
(projection, joint limits, pose prior, signs, smoothness within the labeling), and
chosen over the clip by min-sum dynamic programming (:func:`vidcap.video.solve.signs.min_sum`)
with the motion of the pair's joints between consecutive frames as the cost of a
transition: a change of names is cheap where the limbs cross, where the two
labelings' limbs are close, and dear elsewhere.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from vidcap.body import JOINT_INDEX
from vidcap.video.solve.gauss_newton import levenberg_marquardt
from vidcap.video.solve.repair import frame_costs
from vidcap.video.solve.residuals import Problem
from vidcap.video.solve.signs import min_sum
from vidcap.video.solve.skeleton import forward_kinematics, params_from_joints

#: The pairs (columns of the (F, 2) swap arrays, as :data:`vidcap.video.annotations.PAIRS`):
#: (proximal joints (left, right), distal joints (left, right)).
PAIRS = ("arms", "legs")
_JOINTS = {"arms": ("shoulder", ("elbow", "wrist")), "legs": ("hip", ("knee", "ankle"))}
#: Segments (body.SEGMENT_NAMES order) of each pair: left upper, left lower, right ...
_SEGMENTS = {"arms": (2, 3, 4, 5), "legs": (6, 7, 8, 9)}
#: 1 / metres: a transition costs 0.5 (STEP_WEIGHT d)^2 for the pair's joints moving d
#: between frames (summed over them).
STEP_WEIGHT = 10.0
#: Levenberg-Marquardt iterations of each swapped labeling's solve.
LABEL_ITER = 8
#: Cost of a frame with a pair's names exchanged, over its own: ties keep the names.
SWAP_BIAS = 1.0
_NONE = 1e30


def _distal(pair):
    prox, dist = _JOINTS[pair]
    left = [JOINT_INDEX[f"l_{j}"] for j in dist]
    right = [JOINT_INDEX[f"r_{j}"] for j in dist]
    return left, right, JOINT_INDEX[f"l_{prox}"], JOINT_INDEX[f"r_{prox}"]


def relabel(problem: Problem, swapped) -> Problem:
    """``problem`` with each pair's left and right distal 2D joints (targets, weights),
    proposed depth signs and (legs) foot contacts exchanged where ``swapped`` (F, 2)."""
    sw = np.asarray(swapped, bool)
    target, weight = problem.target.copy(), problem.weight.copy()
    prior = problem.prior_signs.copy()
    contact = problem.contact.copy()
    for col, pair in enumerate(PAIRS):
        rows = np.flatnonzero(sw[:, col])
        if not rows.size:
            continue
        left, right, _, _ = _distal(pair)
        a, b = left + right, right + left
        target[np.ix_(rows, a)] = problem.target[np.ix_(rows, b)]
        weight[np.ix_(rows, a)] = problem.weight[np.ix_(rows, b)]
        ls, rs = _SEGMENTS[pair][:2], _SEGMENTS[pair][2:]
        prior[np.ix_(rows, ls + rs)] = problem.prior_signs[np.ix_(rows, rs + ls)]
        if pair == "legs":
            contact[rows] = problem.contact[rows][:, ::-1]
    return replace(problem, target=target, weight=weight, prior_signs=prior, contact=contact)


def exchange_limbs(joints, pair: str) -> np.ndarray:
    """``joints`` (F, 15, 3) with the pair's two limbs' 3D segments exchanged: each
    limb hangs from its own hip (shoulder) with the other's segment vectors, so its
    2D shows where the other's did (exactly so in a side view)."""
    left, right, lp, rp = _distal(pair)
    out = np.array(joints, dtype=float)
    for dst, src, dp, sp in ((left, right, lp, rp), (right, left, rp, lp)):
        prev_d, prev_s = dp, sp
        for d, s in zip(dst, src, strict=True):
            out[:, d] = out[:, prev_d] + (joints[:, s] - joints[:, prev_s])
            prev_d, prev_s = d, s
    return out


#: :func:`consistent_labels`: weight of a pair's named 2D joints' second difference over
#: frames (in units of 1 % of the height): a frame costs 0.5 NAME_ACC_WEIGHT sum_p
#: min(|a_p|^2, NAME_ACC_CAP^2) over the pair's four distal joints p. The cap (10 % of the
#: height) makes a single misfit frame cost the same under either naming, so it cannot
#: pull the names of the frames after it; a jump of the 2D fit from one leg to the other
#: (20-30 % of the height) still costs the most a frame can. Chosen on the tuning renders
#: (``benchmarks/solve_fitted.py --front``, on a first variant: whole limbs exchanged in the
#: body-side names, no side hold): weights 0.003 / 0.02 / 1 (no cap) gave 82.5 / 90.4 /
#: 65.6 mm, caps 5 / 10 / 20 / none 68.0 / 65.6 / 65.6 / 65.6 mm; as kept, 67.1 mm.
NAME_ACC_WEIGHT = 1.0
NAME_ACC_CAP = 10.0
#: :func:`consistent_labels`: cost of a frame whose pair is exchanged against the 2D
#: fit's names (ties keep them; 0.1 and 1 gave the same on the tuning renders).
NAME_BIAS = 1.0


def second_order_labels(unary, x, weight: float, cap: float = np.inf) -> np.ndarray:
    """Labelings minimising a unary cost plus a second-difference cost over frames.

    Parameters
    ----------
    unary : numpy.ndarray, shape (C, F, 2)
        Cost of each chain's labeling 0 (as named) and 1 (exchanged) per frame.
    x : numpy.ndarray, shape (C, F, 2, P, 2)
        Each chain's P points under labeling 0 and 1.
    weight, cap : float
        A frame f costs ``0.5 weight sum_p min(|a_p|^2, cap^2)``, ``a_p`` the second
        difference of point p at f under the labelings of f-1, f, f+1.

    Returns
    -------
    numpy.ndarray of int, shape (C, F)
        0 or 1 per chain and frame (min-sum over the state pairs (s_{f-1}, s_f)).
    """
    C, F = unary.shape[:2]
    if F < 3:
        return np.argmin(unary, axis=2)
    a_, b_ = np.array([0, 0, 1, 1]), np.array([0, 1, 0, 1])  # state k: (s_k, s_k+1)
    un = unary[:, 1:][:, :, b_].copy()
    un[:, 0] += unary[:, 0][:, a_]
    pair = np.full((C, F - 2, 4, 4), _NONE)
    for s in range(4):
        for t in range(4):
            if b_[s] == a_[t]:  # consecutive states share their frame
                acc = x[:, 2:, b_[t]] - 2 * x[:, 1:-1, a_[t]] + x[:, :-2, a_[s]]
                a2 = np.minimum(np.sum(acc ** 2, axis=-1), cap ** 2)
                pair[:, :, s, t] = 0.5 * weight * np.sum(a2, axis=-1)
    best, _ = min_sum(un, pair)
    return np.concatenate([a_[best[:, :1]], b_[best]], axis=1)


def consistent_labels(joints2d, unit, *, held=None, weight: float = NAME_ACC_WEIGHT,
                      cap: float = NAME_ACC_CAP, bias: float = NAME_BIAS,
                      prior=None) -> np.ndarray:
    """Where each limb pair's distal 2D joints are best exchanged so that every named
    joint moves smoothly through the clip.

    The 2D fit names the legs (arms) by tracking them and loses them for stretches of
    frames: its left knee and ankle jump onto the right leg and back. Each named joint
    then accelerates hard twice; exchanging the pair over the stretch removes both.
    Which naming is right where nothing jumps is left to the fit (``bias``).

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Named 2D joints (the fit's own names or the body's sides), pixels.
    unit : float or array_like, shape (F,)
        Pixels per unit of :data:`NAME_ACC_CAP` (1 % of the height).
    held : array_like of bool, shape (F, 2), optional
        (Frame, pair: arms, legs) kept as named.
    weight, cap, bias : float
        :data:`NAME_ACC_WEIGHT`, :data:`NAME_ACC_CAP`, :data:`NAME_BIAS`.
    prior : array_like, shape (F, 2), optional
        (Frame, pair) extra cost of exchanging (negative: of keeping the names), replacing
        ``bias`` where finite (NaN: ``bias``): another cue's evidence for the names.

    Returns
    -------
    numpy.ndarray of bool, shape (F, 2)
        Frames whose arms' (column 0), legs' (1) distal joints are to be exchanged
        (:func:`exchange_distal`).
    """
    j = np.asarray(joints2d, float)
    F = len(j)
    u = np.broadcast_to(np.asarray(unit, float), (F,))[:, None, None, None]
    x, unary = [], np.zeros((len(PAIRS), F, 2))
    for c, pair in enumerate(PAIRS):
        left, right, _, _ = _distal(pair)
        x.append(np.stack([j[:, left + right], j[:, right + left]], 1) / u)
        unary[c, :, 1] = bias
        if prior is not None:
            pc = np.asarray(prior, float)[:, c]
            has = np.isfinite(pc)
            unary[c, has, 1] = np.maximum(pc[has], 0.0)
            unary[c, has, 0] = np.maximum(-pc[has], 0.0)
        if held is not None:
            unary[c, np.asarray(held, bool)[:, c], 1] = _NONE
    return second_order_labels(unary, np.stack(x), weight, cap).T.astype(bool)


def exchange_distal(joints2d, swapped) -> np.ndarray:
    """A copy of ``joints2d`` (F, 15, D) with each pair's left and right distal joints
    (elbow and wrist; knee and ankle) exchanged where ``swapped`` (F, 2); the shoulders
    and hips stay (they are the torso's)."""
    out = np.array(joints2d, dtype=float)
    sw = np.asarray(swapped, bool)
    for c, pair in enumerate(PAIRS):
        rows = np.flatnonzero(sw[:, c])
        left, right, _, _ = _distal(pair)
        out[np.ix_(rows, left + right)] = np.asarray(joints2d, float)[np.ix_(rows, right + left)]
    return out


def choose_labels(problem: Problem, params, *, held=None, fixed=None,
                  step_weight: float = STEP_WEIGHT, max_iter: int = LABEL_ITER,
                  bias: float = SWAP_BIAS):
    """Each pair's labeling per frame (see the module docstring).

    Parameters
    ----------
    problem : Problem
        As named.
    params : numpy.ndarray, shape (F, 24)
        The clip solved as named.
    held : array_like of bool, shape (F, 2), optional
        (Frame, pair) whose names are the user's (a sides event, a placed joint, a
        depth event on the pair): kept as named.
    fixed : array_like of bool, shape (F,), optional
        Frames held by the solve (a local re-solve's edges): kept as named.

    Returns
    -------
    swapped : numpy.ndarray of bool, shape (F, 2)
    params : numpy.ndarray, shape (F, 24)
        The named solution, the swapped one's poses where a pair was swapped (both
        pairs swapped in a frame: the arms' solution with the legs' limbs exchanged).
    """
    # the named labeling gets as many iterations as the swapped ones: the swapped
    # starts are exact in a side view, so a less converged named solution would lose
    # every tie
    p = levenberg_marquardt(problem, params, max_iter=max_iter, fixed=fixed).params
    F = len(p)
    keep = np.zeros((F, len(PAIRS)), bool) if held is None else np.array(held, bool)
    if fixed is not None:
        keep |= np.asarray(fixed, bool)[:, None]
    joints, _, _ = forward_kinematics(p, problem.offsets)
    base = frame_costs(problem, p)
    unary = np.full((len(PAIRS), F, 2), _NONE)
    pair_cost = np.zeros((len(PAIRS), max(F - 1, 0), 2, 2))
    alt = []
    for c, pair in enumerate(PAIRS):
        swapped = np.zeros((F, len(PAIRS)), bool)
        swapped[:, c] = True
        pb = relabel(problem, swapped)
        q0 = params_from_joints(exchange_limbs(joints, pair), p[:, 3])
        q0[:, :3] = p[:, :3]
        q = levenberg_marquardt(pb, q0, max_iter=max_iter, fixed=fixed).params
        alt.append(q)
        unary[c, :, 0] = base
        unary[c, :, 1] = np.where(keep[:, c], _NONE, frame_costs(pb, q) + bias)
        left, right, _, _ = _distal(pair)
        qj, _, _ = forward_kinematics(q, problem.offsets)
        pos = np.stack([joints[:, left + right], qj[:, left + right]], axis=1)  # (F, 2, 4, 3)
        d = pos[1:, None] - pos[:-1, :, None]  # (F-1, 2, 2, 4, 3)
        pair_cost[c] = 0.5 * step_weight ** 2 * np.sum(d ** 2, axis=(-1, -2))
    best, _ = min_sum(unary, pair_cost)
    swapped = best.T.astype(bool)  # (F, 2)
    out = p.copy()
    for c in range(len(PAIRS)):
        out[swapped[:, c]] = alt[c][swapped[:, c]]
    both = swapped.all(axis=1)
    if both.any():  # the arms' solution with the legs exchanged too
        j_both, _, _ = forward_kinematics(alt[0][both], problem.offsets)
        q = params_from_joints(exchange_limbs(j_both, "legs"), alt[0][both, 3])
        q[:, :3] = alt[0][both, :3]
        out[both] = q
    return swapped, out
