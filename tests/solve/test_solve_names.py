"""The 3D stage re-naming limbs where the 2D fit's names jump (issue 33), known answers."""

from __future__ import annotations

import numpy as np

from vidcap.body import JOINT_INDEX, BodyModel
from vidcap.video.lift import estimate_scale
from vidcap.video.lifting import apply_user_view, consistent_names, lift_pose
from vidcap.video.solve.labels import consistent_labels, exchange_distal, second_order_labels

from .test_solve_clip import _clip

BODY = BodyModel()
_LEGS = [JOINT_INDEX[n] for n in ("l_knee", "l_ankle", "r_knee", "r_ankle")]
_HIPS = [JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]]


def _walk(yaw=45.0):
    t = _clip("walk", yaw)
    unit = 0.01 * BODY.height * estimate_scale(t["joints2d"], BODY)  # px per 1 % of height
    return t["joints2d"], unit


def _plant(j2, a, b, col=1):
    sw = np.zeros((len(j2), 2), bool)
    sw[a:b, col] = True
    return exchange_distal(j2, sw), sw


def test_exchange_distal_moves_knees_and_ankles_only():
    j2, _ = _walk()
    out, _ = _plant(j2, 3, 5)
    assert np.array_equal(out[3, JOINT_INDEX["l_knee"]], j2[3, JOINT_INDEX["r_knee"]])
    assert np.array_equal(out[4, JOINT_INDEX["r_ankle"]], j2[4, JOINT_INDEX["l_ankle"]])
    assert np.array_equal(out[:, _HIPS], j2[:, _HIPS])
    assert np.array_equal(out[:3], j2[:3]) and np.array_equal(out[5:], j2[5:])


def test_smooth_names_are_kept():
    j2, unit = _walk()
    assert not consistent_labels(j2, unit).any()


def test_a_planted_leg_jump_over_a_stretch_is_undone():
    j2, unit = _walk()
    bad, planted = _plant(j2, 20, 34)
    assert np.array_equal(consistent_labels(bad, unit), planted)
    arms_bad, arms_planted = _plant(j2, 10, 18, col=0)
    assert np.array_equal(consistent_labels(arms_bad, unit), arms_planted)


def test_held_frames_keep_their_names():
    j2, unit = _walk()
    bad, planted = _plant(j2, 20, 34)
    held = np.zeros_like(planted)
    held[25, 1] = True  # the user named the legs in one frame of the stretch
    got = consistent_labels(bad, unit, held=held)
    assert not got[25, 1]
    assert not got[:, 0].any()


def test_one_misfit_frame_does_not_rename_the_frames_after_it():
    j2, unit = _walk()
    bad = j2.copy()
    bad[30, JOINT_INDEX["l_knee"]] += 40 * unit  # one knee 40 % of the height off
    got = consistent_labels(bad, unit)
    assert got[:, 1].sum() <= 1  # at most that frame


def test_second_order_labels_on_two_frames_take_the_cheaper_unary():
    unary = np.array([[[0.0, 1.0], [2.0, 0.5]]])
    x = np.zeros((1, 2, 2, 1, 2))
    assert np.array_equal(second_order_labels(unary, x, 1.0), [[0, 1]])


def test_edge_on_torso_keeps_the_fits_names():
    j2, unit = _walk()
    bad, planted = _plant(j2, 20, 34)
    rho = np.full(len(j2), 0.8)
    assert np.array_equal(consistent_names(bad, rho, unit), planted)
    rho[:] = 0.1  # a pure side view: names are a coin toss there
    assert not consistent_names(bad, rho, unit).any()


def test_apply_user_view_exchanges_before_the_users_sides():
    j2, _ = _walk()
    F = len(j2)
    orient = np.full(F, "front_right")
    nan = np.full_like(j2, np.nan)
    names = np.zeros((F, 2), bool)
    names[5:9, 1] = True
    sides = np.zeros((F, 2), bool)
    sides[7:12, 1] = True  # the user swaps the legs as shown: both apply in 7-8
    _, _, plain = apply_user_view(j2, orient, np.ones(F), np.full(F, ""), nan,
                                  image_sides=False)
    _, _, got = apply_user_view(j2, orient, np.ones(F), np.full(F, ""), nan,
                                image_sides=False, names_swapped=names, user_sides=sides)
    knee_l, knee_r = JOINT_INDEX["l_knee"], JOINT_INDEX["r_knee"]
    assert np.array_equal(got[5, knee_l], plain[5, knee_r])  # the stage's exchange
    assert np.array_equal(got[10, knee_l], plain[10, knee_r])  # the user's (whole leg)
    assert np.array_equal(got[7, knee_l], plain[7, knee_l])  # both: as named


def test_lift_pose_undoes_a_planted_jump_and_reports_it(monkeypatch):
    import vidcap.video.lifting as lifting

    j2, _ = _walk()
    off = lift_pose(_plant(j2, 20, 34)[0], fps=30.0, body=BODY, image_sides=False)
    assert off.names_swapped is None  # off by default (CONSISTENT_NAMES)
    monkeypatch.setattr(lifting, "CONSISTENT_NAMES", True)
    bad, planted = _plant(j2, 20, 34)
    res = lift_pose(bad, fps=30.0, body=BODY, image_sides=False)
    assert np.array_equal(res.names_swapped, planted)
    np.testing.assert_allclose(res.joints2d[:, _LEGS], j2[:, _LEGS])
    seg = lift_pose(bad, fps=30.0, body=BODY, image_sides=False, method="segment")
    assert seg.names_swapped is None  # the seed's lift keeps the fit's names
