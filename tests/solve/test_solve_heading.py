"""The heading residual: a walking body moves the way it faces (known answers)."""

from __future__ import annotations

import numpy as np

from vidcap.body import BodyModel, segment_vectors
from vidcap.video.solve.clip import FITTED_HEADING_WEIGHT, make_problem
from vidcap.video.solve.residuals import heading_rows, temporal

from .test_solve_clip import _clip, _solve

BODY = BodyModel()


def _pelvis_problem(yaw, contact=True, weight=400.0):
    n = len(yaw)
    return make_problem(np.full((n, 15, 2), 300.0), scale=170.0, fps=30.0, body=BODY,
                        yaw=yaw, contact=np.full((n, 2), contact), heading_weight=weight)


def test_a_pelvis_moving_the_way_it_faces_costs_nothing_and_sideways_costs_its_step():
    n = 6
    yaw = np.full(n, np.deg2rad(30.0))
    pb = _pelvis_problem(yaw)
    joints = np.zeros((n, 15, 3))
    facing = np.array([np.sin(yaw[0]), 0.0, np.cos(yaw[0])])
    across = np.array([np.cos(yaw[0]), 0.0, -np.sin(yaw[0])])
    joints[:, :] = (0.04 * np.arange(n))[:, None, None] * facing  # 1.2 m/s ahead
    head = temporal(pb, joints)[-(n - 1):]
    np.testing.assert_allclose(head, 0.0, atol=1e-12)
    joints[:, :] += (0.01 * np.arange(n))[:, None, None] * across  # 1 cm a frame sideways
    head = temporal(pb, joints)[-(n - 1):]
    np.testing.assert_allclose(head, 400.0 * 0.01)


def test_no_heading_rows_in_side_labelled_frames_without_contact_or_weight():
    yaw = np.deg2rad([30.0, 90.0, 30.0, -90.0, 45.0])
    f, across = heading_rows(_pelvis_problem(yaw))
    np.testing.assert_array_equal(f, [2, 4])  # frames 1 and 3 are side labels
    np.testing.assert_allclose(np.linalg.norm(across, axis=-1), 1.0)
    assert heading_rows(_pelvis_problem(yaw, contact=False))[0].size == 0  # jacks
    assert heading_rows(_pelvis_problem(yaw, weight=0.0))[0].size == 0


def test_the_heading_swings_the_stance_thigh_back_where_both_were_proposed_forward():
    # a walk at yaw 30 from 2D with 2 % noise; every frame's proposals put both thighs'
    # knees toward the camera (the thigh's two reflections look alike in the image):
    # walking the way the body faces, with a planted foot held still, turns them back
    t = _clip(yaw_deg=30.0)
    seg = segment_vectors(t["camera_joints"])[:, [6, 8]]  # the thighs
    out = np.abs(seg[..., 2] / np.linalg.norm(seg, axis=-1)) > 0.15
    prior = t["depth_signs"].copy()
    prior[:, [6, 8]] = 1
    right = {}
    for w in (0.0, FITTED_HEADING_WEIGHT):
        sol = _solve(t, 0.02, prior_signs=prior, heading_weight=w, sign_weight=1.0)
        right[w] = np.mean((sol.signs[:, [6, 8]] == t["depth_signs"][:, [6, 8]])[out])
    assert right[0.0] < 0.7  # measured 0.61
    assert right[FITTED_HEADING_WEIGHT] > 0.85  # measured 0.90
