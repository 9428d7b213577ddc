"""The oracle helpers of ``benchmarks/solve_fitted.py --attribute`` (issue 33), known answers."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from vidcap.body import JOINT_INDEX, SEGMENT_NAMES, BodyModel
from vidcap.video.lifting import swap_pairs

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import solve_attribution as sa  # noqa: E402


def _joints2d(frames=6, seed=0):
    rest = BodyModel().rest_positions()
    rng = np.random.default_rng(seed)
    uv = np.c_[320 + 200 * rest[:, 0], 400 - 200 * rest[:, 1]]
    return uv[None] + rng.normal(0.0, 1.0, (frames, 15, 2))


def test_nearest_labeling_finds_the_planted_swaps():
    truth = _joints2d()
    planted = np.zeros((6, 2), bool)
    planted[1, 0] = planted[3, 1] = planted[4] = True
    named = swap_pairs(truth, planted) + 0.5  # a little off, same names
    assert np.array_equal(sa.nearest_labeling(named, truth), planted)
    # renamed by it, the joints sit on the truth's
    back = swap_pairs(named, sa.nearest_labeling(named, truth))
    assert np.allclose(back, truth + 0.5)


def test_true_2d_takes_the_fits_names():
    truth = _joints2d()
    planted = np.zeros((6, 2), bool)
    planted[2:5, 1] = True
    fitted = swap_pairs(truth, planted) + 2.0
    out = sa.true_2d_fit_names(fitted, truth)
    assert np.allclose(out, swap_pairs(truth, planted))


def test_true_signs_read_the_depth_of_each_segment():
    j = np.zeros((2, 15, 3))
    j[:, :, 1] = -np.arange(15)  # every joint below the previous: no depth so far
    j[0, JOINT_INDEX["l_elbow"], 2] = 0.2  # elbow toward the camera: upper arm +1
    j[1, JOINT_INDEX["r_knee"], 2] = -0.2  # knee away: upper leg -1, lower leg +1
    s = sa.true_signs(j)
    k = {n: i for i, n in enumerate(SEGMENT_NAMES)}
    assert s[0, k["l_upper_arm"]] == 1 and s[0, k["l_lower_arm"]] == -1
    assert s[1, k["r_upper_leg"]] == -1 and s[1, k["r_lower_leg"]] == 1


def test_settings_cover_each_oracle_alone_and_all_but_one():
    cols = dict(sa.settings())
    assert cols["stage"] == frozenset()
    for o in sa.ORACLES:
        assert cols[f"+{o}"] == {o}
    assert cols["all"] == set(sa.ORACLES) - {"front/back"}
    assert cols["all but names"] == {"2D", "signs", "yaw"}


def test_with_true_joints_takes_only_the_named_joints_under_the_fits_names():
    truth = _joints2d()
    planted = np.zeros((6, 2), bool)
    planted[1:3] = True  # the fit names both pairs the other way in frames 1-2
    fitted = swap_pairs(truth, planted) + 3.0
    out = sa.with_true_joints(fitted, truth, sa.JOINT_GROUPS["arms"])
    arms = [JOINT_INDEX[n] for n in sa.JOINT_GROUPS["arms"]]
    rest = [j for j in range(15) if j not in arms]
    assert np.allclose(out[:, arms], swap_pairs(truth, planted)[:, arms])
    assert np.allclose(out[:, rest], fitted[:, rest])


def test_bad_joint_weights_mark_the_planted_outliers_in_any_names():
    truth = _joints2d(frames=4)
    fitted = truth.copy()
    wrist, knee = JOINT_INDEX["l_wrist"], JOINT_INDEX["r_knee"]
    fitted[1, wrist] += [0.0, 30.0]  # 30 px of a 300-px body: 10 % off
    fitted[2, knee] += [12.0, 0.0]  # 4 %: under a 5 % threshold
    swapped = np.zeros((4, 2), bool)
    swapped[1, 0] = True  # the arms named the other way in that frame: still found
    named = swap_pairs(fitted, swapped)
    w = sa.bad_joint_weights(named, truth, np.full(4, 300.0), 0.05, weight=0.01)
    expect = np.ones((4, 15))
    expect[1, JOINT_INDEX["r_wrist"]] = 0.01  # where the renamed wrist now sits
    assert np.array_equal(w, expect)


def test_joint_settings_name_each_limb_group_and_each_threshold():
    cols = dict(sa.joint_settings())
    assert cols["stage"] == {}
    assert cols["+legs 2D"] == {"joints": sa.JOINT_GROUPS["legs"]}
    assert cols["+arms signs"] == {"sign_segments": sa.SEGMENT_GROUPS["arms"]}
    assert [k for k in cols if "dropped" in k] == ["2D > 5% dropped", "2D > 8% dropped"]
