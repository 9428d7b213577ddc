"""The 2D noise level, the noise-robust scale and the in-plane prior (issue 33)."""

from __future__ import annotations

import numpy as np

from vidcap.body import BodyModel
from vidcap.synth import make_motion, prepare_clip, truth_arrays
from vidcap.video.lift import estimate_scale
from vidcap.video.lifting import frame_scales
from vidcap.video.solve.clip import make_problem
from vidcap.video.solve.noise import noise_fraction, noise_sigma, robust_scale

BODY = BodyModel()


def _walk(yaw_deg=90.0, n=60):
    m = make_motion("walk", body=BODY, fps=30.0, n_frames=n, rng=np.random.default_rng(0))
    clip = prepare_clip(m, body=BODY, yaw_deg=yaw_deg, rng=np.random.default_rng(1))
    t = truth_arrays(clip, np.zeros((m.n_frames, 1, 1), bool))
    return t["joints2d"], float(np.linalg.norm(t["camera"][0, :3]))


def test_noise_sigma_reads_white_noise_and_not_the_motion():
    j2, s = _walk()
    assert noise_sigma(j2) < 0.003 * BODY.height * s  # the walk's own motion
    sigma = 0.02 * BODY.height * s
    noisy = j2 + np.random.default_rng(2).normal(0.0, sigma, j2.shape)
    assert abs(noise_sigma(noisy) / sigma - 1.0) < 0.1
    assert abs(noise_fraction(noisy, s, BODY) - 0.02) < 0.002
    assert noise_fraction(j2, s, BODY) == 0.0


def test_robust_scale_removes_the_noise_bias():
    j2, s = _walk()
    noisy = j2 + np.random.default_rng(2).normal(0.0, 0.02 * BODY.height * s, j2.shape)
    biased = estimate_scale(noisy, BODY)
    assert biased / s > 1.04  # the quantile of noisy heights: too large
    assert abs(robust_scale(noisy, BODY) / s - 1.0) < 0.4 * (biased / s - 1.0)
    assert robust_scale(j2, BODY) == estimate_scale(j2, BODY)  # no noise, no change
    assert abs(float(np.median(frame_scales(noisy, 30.0, BODY))) / s - 1.0) \
        < 0.4 * (biased / s - 1.0)


def test_the_in_plane_prior_and_contact_grow_with_the_noise():
    j2, s = _walk()
    rng = np.random.default_rng(3)
    pbs = [make_problem(j2 + rng.normal(0.0, f * BODY.height * s, j2.shape), scale=s,
                        fps=30.0, body=BODY, yaw=np.zeros(len(j2)), contact="off")
           for f in (0.0, 0.01, 0.04)]
    w = [pb.plane_weight for pb in pbs]
    assert w[0] == 0.0  # off on noise-free joints
    assert 0.0 < w[1] < w[2] < 3 * w[1]  # as the square root of the noise
    c = [pb.contact_weight for pb in pbs]
    assert c[0] == 100.0 and c[0] < c[1] < c[2]


def test_the_pose_prior_grows_with_the_noise_and_holds_a_floor_for_fitted_joints():
    from vidcap.video.solve.clip import FITTED_NOISE_FLOOR, PRIOR_WEIGHT

    j2, s = _walk()
    rng = np.random.default_rng(4)
    noisy = [j2 + rng.normal(0.0, f * BODY.height * s, j2.shape) for f in (0.0, 0.01, 0.04)]
    w = [make_problem(j, scale=s, fps=30.0, body=BODY, yaw=np.zeros(len(j2)),
                      contact="off").prior_weight for j in noisy]
    assert w[0] == 0.0 and 0.0 < w[1] < w[2] < 3 * w[1]  # the square root of the noise
    floored = make_problem(j2, scale=s, fps=30.0, body=BODY, yaw=np.zeros(len(j2)),
                           contact="off", noise_floor=FITTED_NOISE_FLOOR).prior_weight
    assert floored == PRIOR_WEIGHT * np.sqrt(FITTED_NOISE_FLOOR / 0.01)
