"""The clip solve's pose prior (vidcap.video.solve.prior) with known answers."""

from __future__ import annotations

import numpy as np

from vidcap.body import BodyModel
from vidcap.video.solve.prior import (
    N_FEATURES,
    feature_jacobian,
    features,
    fit_prior,
    load_prior,
    prior_residuals,
)
from vidcap.video.solve.skeleton import forward_kinematics, kinematics_jacobian

BODY = BodyModel()


def _poses(n, seed, spread=0.5):
    rng = np.random.default_rng(seed)
    p = rng.normal(0.0, spread, (n, 24))
    p[:, :3] = rng.normal(0.0, 1.0, (n, 3))
    return p


def test_features_are_unit_directions_in_the_torso_frame():
    p = _poses(5, 1)
    joints, root, _ = forward_kinematics(p, BODY.rest_offsets())
    f = features(joints, root, BODY.segment_lengths()).reshape(5, 9, 3)
    np.testing.assert_allclose(np.linalg.norm(f, axis=-1), 1.0, atol=1e-12)
    q = p.copy()
    q[:, :6] = 0.0  # the torso turned back to the rest frame: same features
    j0, r0, _ = forward_kinematics(q, BODY.rest_offsets())
    np.testing.assert_allclose(features(j0, r0, BODY.segment_lengths()).reshape(5, 9, 3), f,
                               atol=1e-12)
    rest, rroot, _ = forward_kinematics(np.zeros((1, 24)), BODY.rest_offsets())
    fr = features(rest, rroot, BODY.segment_lengths()).reshape(9, 3)
    np.testing.assert_allclose(fr[0], [0.0, 1.0, 0.0], atol=1e-12)  # head up
    np.testing.assert_allclose(fr[1], [-1.0, 0.0, 0.0], atol=1e-12)  # left arm out (T-pose)


def test_prior_jacobian_matches_finite_differences():
    p = _poses(4, 2)
    off, lengths = BODY.rest_offsets(), BODY.segment_lengths()
    joints, root, jk = kinematics_jacobian(p, off)
    table = load_prior()
    r0, jac = prior_residuals(features(joints, root, lengths), *table,
                              jacobian=feature_jacobian(jk, root, lengths))
    h = 1e-7
    for i in range(24):
        q = p.copy()
        q[:, i] += h
        j1, rt1, _ = forward_kinematics(q, off)
        num = (prior_residuals(features(j1, rt1, lengths), *table) - r0) / h
        np.testing.assert_allclose(jac[..., i], num, atol=1e-4 * max(1.0, np.abs(num).max()))


def test_fit_prior_recovers_a_gaussian_and_scores_typical_poses_lower():
    rng = np.random.default_rng(0)
    mean = rng.normal(0.0, 0.3, N_FEATURES)
    x = mean + rng.normal(0.0, 0.2, (4000, N_FEATURES))
    means, factors, consts = fit_prior(x, k=1, floor=0.0)
    np.testing.assert_allclose(means[0], mean, atol=0.02)
    prec = factors[0].T @ factors[0]
    np.testing.assert_allclose(np.diag(prec), 25.0, rtol=0.1)  # 1 / 0.2^2
    near = prior_residuals(mean[None], means, factors, consts)
    far = prior_residuals(mean[None] + 0.6, means, factors, consts)
    assert np.sum(near ** 2) < 0.01 * np.sum(far ** 2)


def test_mixture_picks_the_nearest_component():
    rng = np.random.default_rng(1)
    x = rng.normal(0.0, 0.3, (4000, N_FEATURES))
    x[:, 0] = np.repeat([-1.0, 1.0], 2000) + rng.normal(0.0, 0.1, 4000)  # two modes
    means, factors, consts = fit_prior(x, k=2, floor=0.0, seed=1, restarts=8)
    assert np.allclose(np.sort(means[:, 0]), [-1.0, 1.0], atol=0.05)
    probe = np.zeros((2, N_FEATURES))
    probe[:, 0] = (-1.0, 1.0)
    r = prior_residuals(probe, means, factors, consts)
    assert np.abs(r[:, :3]).max() < 1.0  # each at its own component's mean
    single = fit_prior(x, k=1, floor=0.0)
    assert np.sum(r ** 2) < np.sum(prior_residuals(probe, *single) ** 2)


def test_shipped_table_names_its_training_trials():
    from vidcap.video.solve.prior import TABLE

    with np.load(TABLE) as t:
        trials = [str(s) for s in t["trials"]]
    assert trials and not any(s[:3] in ("007", "013", "016", "131") for s in trials)
