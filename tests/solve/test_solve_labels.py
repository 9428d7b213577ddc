"""The solve's choice of which 2D leg and arm is the left one (issue 33), known answers."""

from __future__ import annotations

import numpy as np

from vidcap.body import JOINT_INDEX, BodyModel
from vidcap.video.solve.labels import exchange_limbs, relabel
from vidcap.video.solve.stage import held_labels

from .test_solve_clip import _clip, _rel_error, _solve

BODY = BodyModel()
_KNEES_ANKLES = [JOINT_INDEX[n] for n in ("l_knee", "l_ankle", "r_knee", "r_ankle")]
_SWAPPED = [JOINT_INDEX[n] for n in ("r_knee", "r_ankle", "l_knee", "l_ankle")]


def _plant_leg_swap(t, a, b):
    j2 = t["joints2d"].copy()
    j2[a:b, _KNEES_ANKLES] = t["joints2d"][a:b, _SWAPPED]
    return dict(t, joints2d=j2)


def test_a_planted_leg_swap_over_a_stretch_is_undone():
    t = _clip("walk", 45.0)
    bad = _plant_leg_swap(t, 20, 34)
    plain = _solve(bad)
    sol = _solve(bad, labels=True)
    assert sol.swapped[20:34, 1].mean() > 0.8
    assert sol.swapped[:18, 1].sum() + sol.swapped[36:, 1].sum() <= 2
    assert not sol.swapped[:, 0].any()  # the arms were right
    # two frames at the stretch's end, where the legs cross, may keep the planted names
    assert _rel_error(sol.joints3d, t["camera_joints"]) < 0.045  # right names throughout: 34 mm
    truth = t["camera_joints"][20:34]
    assert _rel_error(sol.joints3d[20:34], truth) < 0.7 * _rel_error(plain.joints3d[20:34], truth)


def test_right_names_are_kept():
    sol = _solve(_clip("walk", 45.0), labels=True)
    assert not sol.swapped.any()


def test_names_the_user_fixed_are_never_exchanged():
    t = _clip("walk", 45.0)
    bad = _plant_leg_swap(t, 20, 34)
    held = np.zeros((len(t["joints2d"]), 2), bool)
    held[15:40, 1] = True
    sol = _solve(bad, labels=True, held_labels=held)
    assert not sol.swapped[15:40, 1].any()


def test_held_labels_read_the_users_events():
    F = 6
    signs = np.zeros((F, 10), int)
    signs[1, 7] = 1  # l_lower_leg
    joints = np.full((F, 15, 2), np.nan)
    joints[2, JOINT_INDEX["r_wrist"]] = (3.0, 4.0)
    sides = np.zeros((F, 2), bool)
    sides[4:, 1] = True
    held = held_labels(signs, joints, sides)
    np.testing.assert_array_equal(held[:, 1], [0, 1, 0, 0, 1, 1])
    np.testing.assert_array_equal(held[:, 0], [0, 0, 1, 0, 0, 0])


def test_exchanging_the_limbs_twice_and_relabelling_twice_give_them_back():
    t = _clip("walk", 90.0, n=10)
    j = t["camera_joints"]
    np.testing.assert_allclose(exchange_limbs(exchange_limbs(j, "legs"), "legs"), j, atol=1e-12)
    # the exchanged limbs keep their bone lengths
    for a, b in (("l_hip", "l_knee"), ("r_knee", "r_ankle")):
        d0 = np.linalg.norm(j[:, JOINT_INDEX[a]] - j[:, JOINT_INDEX[b]], axis=-1)
        x = exchange_limbs(j, "legs")
        d1 = np.linalg.norm(x[:, JOINT_INDEX[a]] - x[:, JOINT_INDEX[b]], axis=-1)
        np.testing.assert_allclose(d0, d1, atol=1e-12)
    sol = _solve(t)
    from vidcap.video.solve.clip import make_problem

    pb = make_problem(t["joints2d"], scale=100.0, fps=30.0, body=BODY, yaw=0.0)
    sw = np.zeros((10, 2), bool)
    sw[3:6] = True
    back = relabel(relabel(pb, sw), sw)
    np.testing.assert_array_equal(back.target, pb.target)
    np.testing.assert_array_equal(back.contact, pb.contact)
    assert sol.swapped is not None and not sol.swapped.any()  # labels off: none
