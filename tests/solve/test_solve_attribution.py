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
