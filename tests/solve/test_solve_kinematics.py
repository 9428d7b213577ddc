"""The solve's parametrisation: forward kinematics, inverse, Jacobians, banded solve."""

from __future__ import annotations

import numpy as np

from vidcap.body import BodyModel, segment_vectors
from vidcap.kinematics import Motion
from vidcap.solve._banded import banded_cholesky_solve
from vidcap.solve.clip import make_problem
from vidcap.solve.gauss_newton import _HALF_BAND, _band, normal_equations
from vidcap.solve.residuals import linearise, residuals, sparse_jacobian
from vidcap.solve.skeleton import (
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
    return make_problem(j2, scale=170.0, fps=30.0, body=BODY, yaw=np.zeros(n), contact=contact,
                        prior_signs=rng.choice([-1, 1], (n, 10)),
                        hard_signs=rng.choice([-1, 0, 0, 1], (n, 10)))


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
    ab = _band(blocks)
    h_full = jac.T @ jac
    i, j = np.triu_indices(n * 24)
    inside = j - i <= _HALF_BAND
    np.testing.assert_allclose(ab[_HALF_BAND + i[inside] - j[inside], j[inside]],
                               h_full[i[inside], j[inside]], rtol=1e-9, atol=1e-6)
    assert np.abs(h_full[i[~inside], j[~inside]]).max() == 0.0


def test_banded_cholesky_solves():
    rng = np.random.default_rng(5)
    n, u = 40, 5
    a = np.zeros((n, n))
    for d in range(u + 1):
        v = rng.normal(size=n - d)
        a[np.arange(d, n), np.arange(n - d)] = v
        a[np.arange(n - d), np.arange(d, n)] = v
    a += np.eye(n) * (np.abs(a).sum(1).max() + 1)
    b = rng.normal(size=n)
    lb = np.array([[a[i, i - d] if i - d >= 0 else 0.0 for d in range(u + 1)] for i in range(n)])
    np.testing.assert_allclose(banded_cholesky_solve(lb, b), np.linalg.solve(a, b), atol=1e-10)
    assert banded_cholesky_solve(-np.abs(lb), b).size == 0  # not positive definite
