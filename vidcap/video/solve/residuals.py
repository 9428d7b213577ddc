"""The residuals of the clip solve and their sparse Jacobian.

Per frame (the *unary* residuals, which depend on that frame's 24 parameters):

* projection: each joint's world (X, Y) against the fitted 2D joint read in metres
  (scaled orthography, seed 004 Eq. 2.1, at the frame's scale: weak perspective),
  times the joint's confidence over ``sigma_2d``;
* joint limits (:mod:`vidcap.video.solve.limits`): the excess over ``sigma_limit``;
* depth signs: a segment on the wrong side of the image plane, ``relu(-sign * dZ /
  length)``, over ``sigma_sign`` for a proposal (soft: the image may overrule it) and
  over ``sigma_hard`` beyond a margin for a user's annotation (hard);
* the torso's yaw against the orientation's, over ``sigma_yaw`` (per frame);
* the root's depth against 0, weakly (orthography cannot tell it; contact can);
* every segment's ``dZ / length`` against 0 over ``sigma_plane`` (the in-plane prior:
  where 2D noise leaves a segment's depth open, :func:`vidcap.video.solve.clip.plane_weight`);
* the pose prior learned from motion capture (:mod:`vidcap.video.solve.prior`): the
  head's and limbs' directions in the torso frame, whitened, times ``prior_weight``.

Across frames, linear in the joints: the second difference of every joint over
``sigma_acc`` (temporal smoothness), and the planted ankle's frame-to-frame motion
over ``sigma_contact`` (:mod:`vidcap.video.solve.contact`); in a clip with planted feet,
the pelvis' frame-to-frame motion across the torso's prior facing over
``sigma_heading`` (:func:`heading_rows`; people walk the way they face: the image shows
the pelvis' sideways motion, this gives its motion in depth, and the planted foot's
contact then ties the stance leg's depth, which the image leaves open, to it).

The Jacobian is built from 24 perturbed evaluations of the whole clip (one per
parameter column: the unary residuals and the joints of a frame depend on its own
parameters only), so it costs about 25 forward kinematics of the clip.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.sparse import coo_matrix

from vidcap.body import JOINT_INDEX, SEGMENT_JOINTS
from vidcap.video.solve.limits import (
    LIMITS,
    limit_angles,
    limit_excess,
    limit_jacobian,
    params_limit_angles,
)
from vidcap.video.solve.prior import (
    N_ROWS,
    feature_jacobian,
    features,
    load_prior,
    prior_residuals,
)
from vidcap.video.solve.skeleton import (
    N_PARAMS,
    PITCH,
    ROOT_POS,
    YAW,
    forward_kinematics,
    kinematics_jacobian,
)

_ANKLES = (JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"])
#: Margin (fraction of the length) a hard depth sign keeps from the image plane.
HARD_MARGIN = 0.03


#: :class:`Problem`'s fields that hold one entry per frame (the rest are the clip's).
PER_FRAME = ("target", "weight", "prior_signs", "hard_signs", "yaw", "yaw_weight", "contact")


@dataclass(frozen=True)
class Problem:
    """A clip to solve: targets, weights and priors (all per frame).

    Attributes
    ----------
    offsets : (15, 3) rest offsets, metres. lengths : (10,) segment lengths, metres.
    target : (F, 15, 2) joints' world (X, Y) from the image, metres.
    weight : (F, 15) confidence / sigma_2d, 1/m.
    prior_signs, hard_signs : (F, 10) in {-1, 0, +1} (0: none).
    yaw : (F,) radians; yaw_weight : (F,) 1/rad.
    contact : (F, 2) bool, planted left/right ankle.
    sign_weight, hard_weight, limit_weight, acc_weight, contact_weight, depth_weight,
    plane_weight, prior_weight, heading_weight : the inverse sigmas of the module
    docstring.
    """

    offsets: np.ndarray
    lengths: np.ndarray
    target: np.ndarray
    weight: np.ndarray
    prior_signs: np.ndarray
    hard_signs: np.ndarray
    yaw: np.ndarray
    yaw_weight: np.ndarray
    contact: np.ndarray
    sign_weight: float = 5.0
    hard_weight: float = 300.0
    limit_weight: float = 60.0
    acc_weight: float = 60.0
    contact_weight: float = 100.0
    depth_weight: float = 0.01
    plane_weight: float = 0.0
    prior_weight: float = 0.0
    heading_weight: float = 0.0

    @property
    def n_frames(self) -> int:
        """Frames F."""
        return self.target.shape[0]

    def frames(self, start: int, stop: int) -> Problem:
        """The same problem on frames ``start:stop``."""
        return replace(self, **{name: getattr(self, name)[start:stop] for name in PER_FRAME})


def segment_zeta(joints, lengths) -> np.ndarray:
    """dZ / length of every segment, (..., 10): > 0 distal joint nearer the camera."""
    dz = joints[..., SEGMENT_JOINTS[:, 1], 2] - joints[..., SEGMENT_JOINTS[:, 0], 2]
    return dz / lengths


def solved_signs(joints, lengths) -> np.ndarray:
    """The depth sign of every segment, (..., 10) int8: +1 where the distal joint is
    nearer the camera or level (:func:`segment_zeta` >= 0), else -1."""
    return np.where(segment_zeta(joints, lengths) < 0, -1, 1).astype(np.int8)


def sign_penalty(zeta, signs, *, margin: float = 0.0) -> np.ndarray:
    """relu(margin - sign * zeta) where a sign is given, 0 elsewhere, (..., 10)."""
    return np.where(signs != 0, np.maximum(margin - signs * zeta, 0.0), 0.0)


def unary(problem: Problem, params, frames=None):
    """Per-frame residuals (..., U) and joints (..., 15, 3) of poses ``params`` (..., 24).

    ``frames`` (...) indexes the problem's frames the poses belong to (default all,
    params (F, 24)).
    """
    joints, root, _ = forward_kinematics(params, problem.offsets)
    lim = limit_excess(params_limit_angles(params))
    return unary_from_joints(problem, joints, root, params, frames, excess=lim), joints


def unary_from_joints(problem: Problem, joints, root, params, frames=None, *,
                      excess=None) -> np.ndarray:
    """:func:`unary`'s residuals (..., U) of world ``joints`` (..., 15, 3) with the
    torso's rotation ``root`` (..., 3, 3); ``params`` (..., 24) give the yaw, pitch,
    roll and root depth; ``excess`` (..., 15) the joint limits' excess when known."""
    pb = problem
    idx = np.arange(pb.n_frames) if frames is None else frames
    proj = (joints[..., :2] - pb.target[idx]) * pb.weight[idx][..., None]
    lim = (limit_excess(limit_angles(joints, root, params[..., PITCH:PITCH + 2]))
           if excess is None else excess)
    zeta = segment_zeta(joints, pb.lengths)
    soft = sign_penalty(zeta, pb.prior_signs[idx]) * pb.sign_weight
    hard = sign_penalty(zeta, pb.hard_signs[idx], margin=HARD_MARGIN) * pb.hard_weight
    yaw = (params[..., YAW] - pb.yaw[idx]) * pb.yaw_weight[idx]
    depth = params[..., ROOT_POS.start + 2] * pb.depth_weight
    return np.concatenate([proj.reshape(proj.shape[:-2] + (-1,)), lim * pb.limit_weight,
                           soft, hard, yaw[..., None], depth[..., None],
                           zeta * pb.plane_weight, pose_prior(pb, joints, root)], axis=-1)


N_UNARY = 15 * 2 + len(LIMITS) + 10 + 10 + 2 + 10 + N_ROWS


def pose_prior(problem: Problem, joints, root) -> np.ndarray:
    """The pose prior's residuals (..., 32) (:func:`vidcap.video.solve.prior.prior_residuals`)
    times ``prior_weight``."""
    if not problem.prior_weight:
        return np.zeros(joints.shape[:-2] + (N_ROWS,))
    f = features(joints, root, problem.lengths)
    return problem.prior_weight * prior_residuals(f, *load_prior())


def contact_pairs(contact) -> tuple[np.ndarray, np.ndarray]:
    """Frames f (>= 1) and ankles (index into 15) planted at both f - 1 and f."""
    c = np.asarray(contact, bool)
    both = c[1:] & c[:-1]
    f, foot = np.nonzero(both)
    return f + 1, np.array(_ANKLES)[foot]


def heading_rows(problem: Problem) -> tuple[np.ndarray, np.ndarray]:
    """Frames f (>= 1) of the heading residual and the horizontal direction across the
    prior facing at each (n, 3) (yaw 0 faces +Z). None without a weight or without a
    planted foot (a clip that neither walks nor stands: jumping jacks), and none in
    frames whose prior yaw is a side label (exactly +-90 degrees: the facing known
    only to the 60-degree side sector, where the direction across it is not known)."""
    F = problem.n_frames
    if not problem.heading_weight or F < 2 or not problem.contact.any():
        return np.zeros(0, int), np.zeros((0, 3))
    f = np.arange(1, F)
    yaw = problem.yaw[f]
    keep = np.abs(np.cos(yaw)) > 1e-3
    f, yaw = f[keep], yaw[keep]
    return f, np.stack([np.cos(yaw), np.zeros_like(yaw), -np.sin(yaw)], axis=-1)


def temporal(problem: Problem, joints) -> np.ndarray:
    """Smoothness, contact and heading residuals of the clip's joints (F, 15, 3), flat."""
    acc = (joints[2:] - 2 * joints[1:-1] + joints[:-2]) * problem.acc_weight
    f, ank = contact_pairs(problem.contact)
    slide = (joints[f, ank] - joints[f - 1, ank]) * problem.contact_weight
    hf, across = heading_rows(problem)
    head = np.sum((joints[hf, 0] - joints[hf - 1, 0]) * across, -1) * problem.heading_weight
    return np.concatenate([acc.ravel(), slide.ravel(), head])


def residuals(problem: Problem, params) -> np.ndarray:
    """All residuals of the clip, flat: unary then temporal."""
    res, joints = unary(problem, params)
    return np.concatenate([res.ravel(), temporal(problem, joints)])


def cost(problem: Problem, params) -> float:
    """Half the sum of squared residuals."""
    r = residuals(problem, params)
    return 0.5 * float(r @ r)


@dataclass(frozen=True)
class Linearisation:
    """The clip's residuals and their Jacobian at a point, in blocks.

    Attributes
    ----------
    r : (R,) all residuals (:func:`residuals`' order).
    unary : (F, U, 24) d(unary residuals)/d(params) of each frame.
    joints : (F, 45, 24) d(joints)/d(params) of each frame (the temporal residuals'
        Jacobian is made of these).
    """

    r: np.ndarray
    unary: np.ndarray
    joints: np.ndarray


def linearise(problem: Problem, params, *, r=None, unary_rows: int | None = None
              ) -> Linearisation:
    """Residuals and Jacobian blocks at ``params`` (F, 24): the projection, sign, yaw
    and depth rows in closed form (:func:`vidcap.video.solve.skeleton.kinematics_jacobian`),
    the limit rows by finite differences of the swings
    (:func:`vidcap.video.solve.limits.limit_jacobian`).

    ``r`` (with ``unary_rows``, the unary rows per frame): :func:`residuals` at
    ``params`` when the caller has them (the LM's accepted step), not computed again:
    they are the same to the bit."""
    pb = problem
    p = np.asarray(params, dtype=float)
    F = p.shape[0]
    joints, root, jk = kinematics_jacobian(p, pb.offsets)  # jk (F, 15, 3, 24)
    excess, jlim = limit_jacobian(p)
    if r is None or unary_rows is None:
        res = unary_from_joints(pb, joints, root, p, excess=excess)
        r, unary_rows = np.concatenate([res.ravel(), temporal(pb, joints)]), res.shape[1]
    ju = np.zeros((F, unary_rows, N_PARAMS))
    # products written straight into ju's rows (one pass, no temporaries)
    np.multiply(jk[:, :, :2], pb.weight[:, :, None, None],
                out=ju[:, :30].reshape(F, 15, 2, N_PARAMS))
    n_lim = len(LIMITS)
    np.multiply(jlim, pb.limit_weight, out=ju[:, 30:30 + n_lim])
    dzeta = (jk[:, SEGMENT_JOINTS[:, 1], 2] - jk[:, SEGMENT_JOINTS[:, 0], 2]) \
        / pb.lengths[None, :, None]  # (F, 10, 24)
    zeta = segment_zeta(joints, pb.lengths)
    at = 30 + n_lim
    for signs, margin, w in ((pb.prior_signs, 0.0, pb.sign_weight),
                             (pb.hard_signs, HARD_MARGIN, pb.hard_weight)):
        active = (signs != 0) & (margin - signs * zeta > 0)
        ju[:, at:at + 10] = np.where(active[..., None], -w * signs[..., None] * dzeta, 0.0)
        at += 10
    ju[:, at, YAW] = pb.yaw_weight
    ju[:, at + 1, ROOT_POS.start + 2] = pb.depth_weight
    ju[:, at + 2:at + 12] = pb.plane_weight * dzeta
    if pb.prior_weight:
        _, jp = prior_residuals(features(joints, root, pb.lengths), *load_prior(),
                                jacobian=feature_jacobian(jk, root, pb.lengths),
                                out=ju[:, at + 12:])
        jp *= pb.prior_weight
    return Linearisation(r, ju, jk.reshape(F, 45, N_PARAMS))


def sparse_jacobian(problem: Problem, lin: Linearisation):
    """The Jacobian of :func:`residuals` as a CSR matrix (R, F * 24)."""
    pb = problem
    ju, jp = lin.unary, lin.joints
    F, U, _ = ju.shape
    col = (np.arange(F)[:, None] * N_PARAMS + np.arange(N_PARAMS)[None, :])  # (F, 24)
    rows = [np.broadcast_to((np.arange(F)[:, None] * U + np.arange(U))[..., None],
                            (F, U, N_PARAMS)).ravel()]
    cols = [np.broadcast_to(col[:, None, :], (F, U, N_PARAMS)).ravel()]
    data = [ju.ravel()]
    base = F * U
    if F > 2:
        n = F - 2
        row = base + (np.arange(n)[:, None] * 45 + np.arange(45))[..., None]
        for shift, coef in ((0, 1.0), (1, -2.0), (2, 1.0)):
            rows.append(np.broadcast_to(row, (n, 45, N_PARAMS)).ravel())
            cols.append(np.broadcast_to(col[shift:shift + n, None, :], (n, 45, N_PARAMS)).ravel())
            data.append((coef * pb.acc_weight * jp[shift:shift + n]).ravel())
        base += n * 45
    f, ank = contact_pairs(pb.contact)
    if f.size:
        n = f.size
        row = base + (np.arange(n)[:, None] * 3 + np.arange(3))[..., None]
        coord = 3 * ank[:, None] + np.arange(3)  # (n, 3) rows of jp
        for frames, coef in ((f, 1.0), (f - 1, -1.0)):
            block = jp[frames[:, None], coord]  # (n, 3, 24)
            rows.append(np.broadcast_to(row, (n, 3, N_PARAMS)).ravel())
            cols.append(np.broadcast_to(col[frames][:, None, :], (n, 3, N_PARAMS)).ravel())
            data.append((coef * pb.contact_weight * block).ravel())
        base += 3 * n
    hf, across = heading_rows(pb)
    if hf.size:
        n = hf.size
        row = base + np.arange(n)[:, None]
        for frames, coef in ((hf, 1.0), (hf - 1, -1.0)):
            block = np.einsum("nc,nci->ni", across, jp[frames, :3])  # the pelvis' rows
            rows.append(np.broadcast_to(row, (n, N_PARAMS)).ravel())
            cols.append(col[frames].ravel())
            data.append((coef * pb.heading_weight * block).ravel())
    return coo_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(lin.r.size, F * N_PARAMS)).tocsr()


def sparsity(problem: Problem):
    """The Jacobian's structure (``least_squares(jac_sparsity=...)``), CSR of ones."""
    F = problem.n_frames
    lin = Linearisation(np.zeros(residuals(problem, np.zeros((F, N_PARAMS))).size),
                        np.ones((F, N_UNARY, N_PARAMS)), np.ones((F, 45, N_PARAMS)))
    return sparse_jacobian(problem, lin)
