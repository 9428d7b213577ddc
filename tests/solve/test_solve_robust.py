"""The clip solve's Cauchy re-weighting of the 2D joints (issue 33), known answers."""

from __future__ import annotations

import numpy as np

from vidcap.body import JOINT_INDEX, BodyModel
from vidcap.video.solve.clip import make_problem, robust_weights

from .test_solve_clip import _clip, _solve

BODY = BodyModel()
ANKLE = JOINT_INDEX["l_ankle"]


def _outlier(t, a=20, b=30, px=(60.0, -40.0)):
    j2 = t["joints2d"].copy()
    j2[a:b, ANKLE] += px  # the fit put the ankle far off for a stretch
    return dict(t, joints2d=j2)


def _errors(sol, t):
    a = sol.joints3d - sol.joints3d[:, :1]
    b = t["camera_joints"] - t["camera_joints"][:, :1]
    e = np.linalg.norm(a - b, axis=-1)[20:30]
    return e[:, ANKLE].mean(), e.mean()


def test_an_outlier_joint_is_followed_less():
    t = _clip("walk", 45.0)
    bad = _outlier(t)
    # as the 3D stage solves fitted joints: the pose prior holds where the image is doubted
    plain = _errors(_solve(bad, contact="off", noise_floor=0.06), t)
    robust = _errors(_solve(bad, contact="off", noise_floor=0.06, robust=1.5), t)
    assert robust[0] < 0.85 * plain[0]  # 0.38 -> 0.29 m
    assert robust[1] < plain[1]


def test_the_users_joints_keep_their_weight():
    t = _clip("walk", 45.0, n=10)
    pb = make_problem(t["joints2d"], scale=100.0, fps=30.0, body=BODY, yaw=0.0)
    joints = np.zeros((10, 15, 3))
    joints[..., :2] = pb.target
    joints[:, ANKLE, 0] += 0.2  # 0.2 m off: ~11 sigmas
    kept = np.zeros((10, 15), bool)
    kept[5:, ANKLE] = True
    w = robust_weights(pb, joints, 1.5, kept=kept).weight
    np.testing.assert_allclose(w[5:, ANKLE], pb.weight[5:, ANKLE])
    assert (w[:5, ANKLE] < 0.2 * pb.weight[:5, ANKLE]).all()
    others = np.ones((10, 15), bool)
    others[:, ANKLE] = False
    np.testing.assert_allclose(w[others], pb.weight[others])  # fitted exactly: unchanged
