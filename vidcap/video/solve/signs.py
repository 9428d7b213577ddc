"""Depth signs chosen by the solve, and their confidence: the cost of the other sign.

Every limb segment (and the head) can be reflected through the image plane without
moving its 2D projection: negate its world dZ, keep the joints above it. Given the
solved clip, each limb (upper and lower segment: 4 states, as
:mod:`vidcap.video.proposals`) and the head (2 states) take, per frame, the reflection
state minimising the clip's cost: the frame's own residuals (limits, sign prior,
hard signs: :func:`vidcap.video.solve.residuals.unary_from_joints`) plus the motion of the
limb's joints between consecutive frames (a reflection of a segment far out of the
image plane jumps). Min-sum dynamic programming over the frames chooses the states
and gives min-marginals: how much more the best clip costs with the other sign of
a segment in a frame, the proposal's confidence.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vidcap.body import SEGMENT_INDEX, SEGMENT_JOINTS, SEGMENT_NAMES
from vidcap.video.solve.residuals import Problem, unary_from_joints

#: Chains whose reflection states are chosen jointly: segments (proximal first).
CHAINS: tuple[tuple[str, ...], ...] = (
    ("head",), ("l_upper_arm", "l_lower_arm"), ("r_upper_arm", "r_lower_arm"),
    ("l_upper_leg", "l_lower_leg"), ("r_upper_leg", "r_lower_leg"),
)


@dataclass(frozen=True)
class SignSweep:
    """Result of :func:`sweep_signs`.

    Attributes
    ----------
    joints : (F, 15, 3) the clip with the chosen reflections applied, metres.
    flipped : (F, 10) bool, the segments reflected.
    confidence : (F, 10) the clip cost of the other sign minus the best cost (>= 0;
        inf for the torso, which is not reflected here).
    """

    joints: np.ndarray
    flipped: np.ndarray
    confidence: np.ndarray


def _states(n: int) -> np.ndarray:
    """(2**n, n) bool: which segments of an n-segment chain each state reflects."""
    return np.array([[(s >> (n - 1 - k)) & 1 for k in range(n)] for s in range(2 ** n)], bool)


def _reflect(joints, chain, state) -> np.ndarray:
    """``joints`` (F, 15, 3) with the chain's segments reflected where ``state`` (n,)."""
    out = joints.copy()
    for k, name in enumerate(chain):
        a, b = SEGMENT_JOINTS[SEGMENT_INDEX[name]]
        vec = joints[:, b] - joints[:, a]
        if state[k]:
            vec[:, 2] *= -1.0
        out[:, b] = out[:, a] + vec
    return out


#: Cost standing for "no such state" (the head's chain has 2 states of the 4).
_NONE = 1e30


def min_sum(unary, pair):
    """Min-sum over frames of C chains at once: unary (C, F, S), pair (C, F-1, S, S).

    Returns (best (C, F) states, min-marginals (C, F, S))."""
    C, F, S = unary.shape
    fwd = np.empty((C, F, S))
    bwd = np.zeros((C, F, S))
    back = np.zeros((C, F, S), int)
    fwd[:, 0] = unary[:, 0]
    cols = np.arange(S)
    chains = np.arange(C)[:, None]
    for f in range(1, F):  # over frames, all chains at once (S <= 4 states)
        tot = fwd[:, f - 1, :, None] + pair[:, f - 1]
        back[:, f] = np.argmin(tot, axis=1)
        fwd[:, f] = unary[:, f] + tot[chains, back[:, f], cols]
    for f in range(F - 2, -1, -1):
        bwd[:, f] = np.min(pair[:, f] + (unary[:, f + 1] + bwd[:, f + 1])[:, None, :], axis=2)
    best = np.empty((C, F), int)
    best[:, -1] = np.argmin(fwd[:, -1], axis=1)
    for f in range(F - 1, 0, -1):
        best[:, f - 1] = back[chains[:, 0], f, best[:, f]]
    return best, fwd + bwd


def sweep_signs(problem: Problem, joints, root, params, *, step_weight: float = 10.0
                ) -> SignSweep:
    """Reflection states of the solved clip minimising its cost (see module docstring).

    Parameters
    ----------
    problem : Problem
    joints : numpy.ndarray, shape (F, 15, 3)
        The solved joints.
    root : numpy.ndarray, shape (F, 3, 3)
        The torso's world rotations.
    params : numpy.ndarray, shape (F, 24)
    step_weight : float
        1 / metres: a limb joint moving ``d`` between frames costs
        ``0.5 (step_weight d)^2``.

    Returns
    -------
    SignSweep
    """
    F = joints.shape[0]
    out = joints.copy()
    flipped = np.zeros((F, len(SEGMENT_NAMES)), bool)
    conf = np.full((F, len(SEGMENT_NAMES)), np.inf)
    states = [_states(len(chain)) for chain in CHAINS]
    S = max(len(st) for st in states)
    variants = np.stack([_reflect(joints, chain, s)  # (V, F, 15, 3): every chain's states
                         for chain, st in zip(CHAINS, states, strict=True) for s in st])
    V = len(variants)
    res = unary_from_joints(problem, variants, np.broadcast_to(root, (V,) + root.shape),
                            np.broadcast_to(params, (V,) + params.shape))
    un_all = 0.5 * np.sum(res * res, -1)  # (V, F)
    un = np.full((len(CHAINS), F, S), _NONE)
    pair = np.full((len(CHAINS), max(F - 1, 0), S, S), _NONE)
    at = 0
    for c, (chain, st) in enumerate(zip(CHAINS, states, strict=True)):
        n = len(st)
        moved = sorted({int(SEGMENT_JOINTS[SEGMENT_INDEX[name], 1]) for name in chain})
        un[c, :, :n] = un_all[at:at + n].T
        pos = np.moveaxis(variants[at:at + n][:, :, moved], 0, 1)  # (F, n, m, 3)
        d = pos[1:, None] - pos[:-1, :, None]  # (F-1, n, n, m, 3)
        pair[c, :, :n, :n] = 0.5 * step_weight ** 2 * np.sum(d ** 2, axis=(-1, -2))
        at += n
    best, marg = min_sum(un, pair)
    for c, (chain, st) in enumerate(zip(CHAINS, states, strict=True)):
        n = len(st)
        sel = st[best[c]]
        lowest = marg[c, :, :n].min(axis=1)
        for k, name in enumerate(chain):
            seg = SEGMENT_INDEX[name]
            flipped[:, seg] = sel[:, k]
            other = st[:, k][None, :] != sel[:, k][:, None]  # (F, n)
            conf[:, seg] = np.where(other, marg[c, :, :n], np.inf).min(axis=1) - lowest
        for f_state in np.unique(best[c]):
            rows = best[c] == f_state
            out[rows] = _reflect(out[rows], chain, st[f_state])
    return SignSweep(out, flipped, conf)
