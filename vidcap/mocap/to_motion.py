"""A solved marker skeleton as a :class:`vidcap.kinematics.Motion` (BVH-ready)."""

from __future__ import annotations

import numpy as np

from vidcap.mocap.frames import _EPS, unit
from vidcap.mocap.solution import JointSolution


def lab_to_yup(up) -> np.ndarray:
    """Rotation taking lab coordinates to Y-up coordinates (3, 3).

    The lab's ``up`` becomes +Y; the lab axis most perpendicular to it (X first)
    becomes +X. For the usual Z-up C3D lab: (x, y, z) -> (x, z, -y).
    """
    y = unit(np.asarray(up, dtype=float))
    cand = np.eye(3)[np.argsort(np.abs(np.eye(3) @ y), kind="stable")[0]]
    x = unit(cand - (cand @ y) * y)
    z = np.cross(x, y)
    return np.stack([x, y, z])


def _project_so3(m: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(m)
    d = np.sign(np.linalg.det(u @ vt)) or 1.0
    return u @ np.diag([1.0, 1.0, d]) @ vt


def _align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest rotation taking unit a to unit b (3, 3)."""
    from scipy.spatial.transform import Rotation

    v = np.cross(a, b)
    s, c = np.linalg.norm(v), float(a @ b)
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        perp = np.eye(3)[int(np.argmin(np.abs(a)))]
        return Rotation.from_rotvec(np.pi * unit(np.cross(a, perp))).as_matrix()
    return Rotation.from_rotvec(v / s * np.arctan2(s, c)).as_matrix()


def _two_vector_frame(primary, secondary) -> np.ndarray:
    e1 = unit(primary)
    e2 = unit(secondary - (secondary @ e1) * e1)
    return np.stack([e1, e2, np.cross(e1, e2)], axis=1)


def _fill_nearest(valid: np.ndarray) -> np.ndarray:
    """Index of the nearest valid frame for every frame (F,); -1 when none is valid."""
    idx = np.flatnonzero(valid)
    if idx.size == 0:
        return np.full(valid.shape, -1)
    f = np.arange(valid.size)
    pos = np.clip(np.searchsorted(idx, f), 1, max(idx.size - 1, 1))
    if idx.size == 1:
        return np.full(valid.shape, idx[0])
    left, right = idx[pos - 1], idx[pos]
    return np.where(np.abs(f - left) <= np.abs(right - f), left, right)


def _segment_alignments(sol: JointSolution, valid: np.ndarray) -> dict[str, np.ndarray]:
    """Per segment, the constant rotation (3, 3; columns = rest x, y, z in the segment's
    local coordinates) that makes the rest pose a T-pose (see :func:`solution_to_motion`)."""
    ms = sol.markerset
    sidx = {n: i for i, n in enumerate(sol.segment_names)}
    lp = sol.local_points
    align: dict[str, np.ndarray] = {}
    up_lab = np.asarray(sol.up, dtype=float)
    for spec in ms.segments:
        i = sidx[spec.name]
        pts = lp[spec.name]
        base = pts[spec.joint]
        rest = np.asarray(spec.rest, dtype=float)
        side = None
        if len(spec.side) == 2 and all(j in pts for j in spec.side):
            side = pts[spec.side[1]] - pts[spec.side[0]]
        tip = pts[spec.tip] - base if spec.tip in pts else None
        if spec.parent is None:
            up_loc = unit(np.median(
                np.einsum("fij,i->fj", sol.rotations[valid[:, i], i], up_lab), axis=0))
            if side is None:
                side = np.eye(3)[int(np.argmin(np.abs(up_loc)))]
            e = _two_vector_frame(side, up_loc)  # local images of rest +X, +Y
            align[spec.name] = e  # columns: rest x, y, z in local coordinates
        elif side is not None and tip is not None:
            e = _two_vector_frame(tip, side)
            f = _two_vector_frame(rest, np.array([1.0, 0.0, 0.0]))
            align[spec.name] = e @ f.T
        else:
            p = sidx[spec.parent]
            both = valid[:, i] & valid[:, p]
            if both.any():
                rel = np.einsum("fji,fjk->fik", sol.rotations[both, p], sol.rotations[both, i])
                q = _project_so3(rel.mean(axis=0))
            else:
                q = np.eye(3)
            a_p = align[spec.parent]
            if tip is not None and np.isfinite(tip).all() and np.linalg.norm(tip) > _EPS:
                m = a_p.T @ q @ unit(tip)
                t = _align(rest, m)
            else:
                t = np.eye(3)
            align[spec.name] = q.T @ a_p @ t
    return align


def solution_to_motion(sol: JointSolution):
    """The marker-derived skeleton as a :class:`vidcap.kinematics.Motion`.

    Bones join the joint centres (constant lengths: the fitted centres are constant
    in their segments' frames, so each bone is the median distance over frames);
    each joint's rotation is its segment's frame times a constant alignment chosen so
    that the rest pose is a T-pose (Y up, -Z forward, left arm toward -X, metres),
    with zero twist at the trial's mean pose. Frames where a segment's frame is
    unknown hold the nearest known frame's rotation.

    Parameters
    ----------
    sol : JointSolution

    Returns
    -------
    Motion
        Joints named as in ``sol.joint_names``; root at the root joint.
    """
    from scipy.spatial.transform import Rotation

    from vidcap.kinematics import Motion, Skeleton

    ms = sol.markerset
    g = lab_to_yup(sol.up)
    F, S = sol.rotations.shape[:2]
    sidx = {n: i for i, n in enumerate(sol.segment_names)}
    valid = np.isfinite(sol.rotations).all(axis=(2, 3))  # (F, S)
    # fill unknown segment frames from the nearest known frame
    rots = sol.rotations.copy()
    for s in range(S):
        near = _fill_nearest(valid[:, s])
        rots[:, s] = np.eye(3) if near[0] < 0 else rots[near, s]
    lp = sol.local_points
    align = _segment_alignments(sol, valid)
    # skeleton offsets
    names = sol.joint_names
    J = len(names)
    offsets = np.zeros((J, 3))
    seg_of_joint = {s.joint: s.name for s in ms.segments}
    for j, name in enumerate(names):
        p = sol.joint_parents[j]
        if p < 0:
            continue
        pseg = seg_of_joint[names[p]]
        pts = lp[pseg]
        offsets[j] = align[pseg].T @ (pts[name] - pts[names[p]])
    offsets = np.where(np.isfinite(offsets), offsets, 0.0)
    # world rotations per joint, then local
    world = np.empty((F, J, 3, 3))
    for j, name in enumerate(names):
        seg = sol.joint_segment[j]
        if name in seg_of_joint:
            world[:, j] = np.einsum("ij,fjk,kl->fil", g, rots[:, sidx[seg]], align[seg])
        else:  # end joints take their parent's rotation (local identity)
            world[:, j] = world[:, sol.joint_parents[j]]
    local = world.copy()
    for j in range(1, J):
        p = sol.joint_parents[j]
        local[:, j] = np.einsum("fji,fjk->fik", world[:, p], world[:, j])
    quat = Rotation.from_matrix(local.reshape(-1, 3, 3)).as_quat().reshape(F, J, 4)
    root = np.einsum("ij,fj->fi", g, sol.positions[:, 0])
    near = _fill_nearest(np.isfinite(root).all(axis=1))
    root = np.zeros_like(root) if near[0] < 0 else root[near]
    ends = {}
    for j, name in enumerate(names):
        if j not in sol.joint_parents:
            length = np.linalg.norm(offsets[j])
            d = unit(offsets[j]) if length > _EPS else np.array([0.0, 1.0, 0.0])
            ends[name] = d * max(0.25 * length, 0.02)
    # depth-first joint order, as a BVH file lists them
    parents = sol.joint_parents
    perm: list[int] = []
    stack = [0]
    while stack:
        j = stack.pop()
        perm.append(j)
        stack.extend(reversed([k for k in range(J) if parents[k] == j]))
    inv = {old: new for new, old in enumerate(perm)}
    skel = Skeleton(tuple(names[j] for j in perm),
                    tuple(-1 if parents[j] < 0 else inv[parents[j]] for j in perm),
                    offsets[perm], ends)
    return Motion(skel, root, quat[:, perm], sol.fps)
