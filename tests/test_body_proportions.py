"""A subject's own proportions on the body model (issue 27): body_with_proportions,
widths, pickling, and the BVH skeleton following them."""

import pickle

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX, BodyModel, body_with_proportions


def test_seed_factors_give_the_seed_body():
    b = body_with_proportions(1.75)
    seed = BodyModel(height=1.75)
    np.testing.assert_allclose(b.segment_lengths(), seed.segment_lengths())
    np.testing.assert_allclose(b.segment_radii(), seed.segment_radii())


def test_longer_legs_keep_the_standing_height():
    b = body_with_proportions(1.6, {"legs": 1.15, "arms": 0.9, "shoulders": 1.2})
    seed = BodyModel(height=1.6)
    assert b.standing_height == pytest.approx(1.6)
    # every length and width scaled by one k so head + torso + legs = 1.6
    k = 1.6 / (seed.length("torso") + seed.length("head")
               + 1.15 * (seed.length("l_upper_leg") + seed.length("l_lower_leg")))
    assert b.length("r_lower_leg") == pytest.approx(1.15 * k * seed.length("r_lower_leg"))
    assert b.length("l_upper_arm") == pytest.approx(0.9 * k * seed.length("l_upper_arm"))
    assert b.radius("torso") == pytest.approx(1.2 * k * seed.radius("torso"))
    assert b.shoulder_half_width == pytest.approx(b.radius("torso"))
    assert b.radius("l_lower_leg") == pytest.approx(k * seed.radius("l_lower_leg"))


def test_a_group_factor_wins_over_its_alias():
    b = body_with_proportions(1.75, {"upper_legs": 1.2, "legs": 1.0}, keep_height=False)
    seed = BodyModel()
    assert b.length("l_upper_leg") == pytest.approx(1.2 * seed.length("l_upper_leg"))
    assert b.length("l_lower_leg") == pytest.approx(seed.length("l_lower_leg"))


@pytest.mark.parametrize("factors", [{"tail": 1.1}, {"legs": 0.0}, {"arms": float("nan")}])
def test_bad_factors_raise(factors):
    with pytest.raises(ValueError):
        body_with_proportions(1.75, factors)


def test_bad_widths_raise():
    with pytest.raises(ValueError, match="widths"):
        BodyModel(widths={"torso": -0.1})


def test_body_pickles_with_its_proportions():
    b = body_with_proportions(1.8, {"arms": 1.1, "leg_width": 1.3})
    c = pickle.loads(pickle.dumps(b))
    assert c == b
    np.testing.assert_allclose(c.segment_radii(), b.segment_radii())


def test_bvh_offsets_follow_the_subject(tmp_path):
    from vidcap.io.bvh import read_bvh, write_bvh
    from vidcap.video.motion import build_motion

    body = body_with_proportions(1.75, {"legs": 1.15, "arms": 0.9, "shoulders": 1.2})
    joints3d = np.repeat(body.rest_positions()[None], 3, axis=0)
    motion = build_motion(joints3d, 30.0, body=body, smooth_sigma=0.0).motion
    write_bvh(tmp_path / "m.bvh", motion)
    off = read_bvh(tmp_path / "m.bvh").skeleton.offsets
    bone = np.linalg.norm(off, axis=1)
    J = JOINT_INDEX
    assert bone[J["l_knee"]] == pytest.approx(body.length("l_upper_leg"), rel=1e-4)
    assert bone[J["r_wrist"]] == pytest.approx(body.length("r_lower_arm"), rel=1e-4)
    assert abs(off[J["l_shoulder"], 0]) == pytest.approx(body.shoulder_half_width, rel=1e-4)
    seed = BodyModel()
    assert bone[J["l_knee"]] > 1.05 * seed.length("l_upper_leg")
    assert bone[J["r_wrist"]] < 0.9 * seed.length("r_lower_arm")
