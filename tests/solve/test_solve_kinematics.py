"""The solve's parametrisation: forward kinematics, inverse, Jacobians, banded solve."""

from __future__ import annotations

import numpy as np
import pytest

from vidcap.body import BodyModel, segment_vectors
from vidcap.kinematics import Motion
from vidcap.video.solve.blocksolve import solve_block_banded
from vidcap.video.solve.clip import make_problem
from vidcap.video.solve.gauss_newton import normal_equations
from vidcap.video.solve.limits import (
    limit_angles,
    limit_excess,
    limit_jacobian,
    params_limit_angles,
)
from vidcap.video.solve.residuals import linearise, residuals, sparse_jacobian
from vidcap.video.solve.skeleton import (
    forward_kinematics,
    kinematics_jacobian,
    local_quaternions,
    params_from_joints,
    params_to_motion,
)

BODY = BodyModel(height=1.7)


def _poses(n, seed=0, spread=0.5):
    return np.random.default_rng(seed).normal(0.0, spread, (n, 24))


def test_fk_is_the_bvh_motion_and_keeps_bone_lengths():
    p = _poses(6)
    joints, _, _ = forward_kinematics(p, BODY.rest_offsets())
    m = Motion(BODY.skeleton(), p[:, :3], local_quaternions(p, BODY), 30.0)
    np.testing.assert_allclose(m.positions(), joints, atol=1e-12)
    np.testing.assert_allclose(params_to_motion(p, BODY, 30.0).positions(), joints, atol=1e-12)
    lengths = np.linalg.norm(segment_vectors(joints), axis=-1)
    np.testing.assert_allclose(lengths, np.broadcast_to(BODY.segment_lengths(), lengths.shape),
                               atol=1e-12)


def test_params_from_joints_inverts_fk():
    p = _poses(6, seed=1, spread=0.4)
    joints, _, _ = forward_kinematics(p, BODY.rest_offsets())
    back = params_from_joints(joints, p[:, 3])
    np.testing.assert_allclose(back, p, atol=1e-9)


def test_kinematics_jacobian_matches_finite_differences():
    p = _poses(3, seed=2, spread=0.7)
    off = BODY.rest_offsets()
    joints, _, jac = kinematics_jacobian(p, off)
    h = 1e-6
    for i in range(24):
        q = p.copy()
        q[:, i] += h
        num = (forward_kinematics(q, off)[0] - joints) / h
        np.testing.assert_allclose(jac[..., i], num, atol=2e-5)


def _problem(n, seed=3):
    rng = np.random.default_rng(seed)
    j2 = rng.normal(320.0, 60.0, (n, 15, 2))
    contact = np.zeros((n, 2), bool)
    contact[2:7, 0] = True
    yaw = np.linspace(-0.4, 0.9, n)
    yaw[n // 2] = np.pi / 2  # a side label: no heading row there
    return make_problem(j2, scale=170.0, fps=30.0, body=BODY, yaw=yaw, contact=contact,
                        prior_signs=rng.choice([-1, 1], (n, 10)),
                        hard_signs=rng.choice([-1, 0, 0, 1], (n, 10)), heading_weight=400.0)


def test_residual_jacobian_and_normal_equations():
    n = 9
    pb = _problem(n)
    p = _poses(n, seed=4, spread=0.6)
    lin = linearise(pb, p)
    r0 = residuals(pb, p)
    np.testing.assert_allclose(lin.r, r0)
    jac = sparse_jacobian(pb, lin).toarray()
    num = np.empty_like(jac)
    h = 1e-7
    for i in range(n * 24):
        q = p.ravel().copy()
        q[i] += h
        num[:, i] = (residuals(pb, q.reshape(n, 24)) - r0) / h
    np.testing.assert_allclose(jac, num, atol=5e-3 * np.abs(num).max())
    blocks, grad = normal_equations(pb, lin)
    np.testing.assert_allclose(grad.ravel(), jac.T @ lin.r, rtol=1e-9, atol=1e-6)
    h_full = jac.T @ jac
    np.testing.assert_allclose(_dense(blocks), h_full, rtol=1e-9, atol=1e-6)


def test_limit_angles_from_parameters_are_those_of_the_joints():
    p = _poses(40, seed=6, spread=1.2)  # many poses beyond the limits
    joints, root, _ = forward_kinematics(p, BODY.rest_offsets())
    from_joints = limit_angles(joints, root, p[:, 4:6])
    np.testing.assert_allclose(params_limit_angles(p), from_joints, atol=1e-12)
    excess, jac = limit_jacobian(p)
    np.testing.assert_allclose(excess, limit_excess(from_joints), atol=1e-12)
    assert (excess > 0).any(axis=0).all()  # every limit is exceeded somewhere
    h = 1e-7
    for i in range(24):
        q = p.copy()
        q[:, i] += h
        num = (limit_excess(params_limit_angles(q)) - excess) / h
        np.testing.assert_allclose(jac[:, :, i], num, atol=1e-4)


def _dense(blocks):
    """The symmetric matrix (F P, F P) of blocks (3, F, P, P)."""
    _, F, P, _ = blocks.shape
    h = np.zeros((F * P, F * P))
    for d in range(3):
        for f in range(F - d):
            h[f * P:(f + 1) * P, (f + d) * P:(f + d + 1) * P] = blocks[d, f]
            if d:
                h[(f + d) * P:(f + d + 1) * P, f * P:(f + 1) * P] = blocks[d, f].T
    return h


@pytest.mark.parametrize("n_frames", [1, 6, 7])
def test_block_banded_solve(n_frames):
    rng = np.random.default_rng(5)
    P = 4
    blocks = rng.normal(size=(3, n_frames, P, P))
    blocks[0] = blocks[0] @ np.swapaxes(blocks[0], 1, 2) + 20.0 * np.eye(P)
    blocks[1, -1:] = 0.0
    blocks[2, -2:] = 0.0
    rhs = rng.normal(size=(n_frames, P))
    x = solve_block_banded(blocks, rhs)
    np.testing.assert_allclose(x.ravel(), np.linalg.solve(_dense(blocks), rhs.ravel()),
                               atol=1e-10)
    assert solve_block_banded(-blocks, rhs) is None  # not positive definite
