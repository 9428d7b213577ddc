"""The body model: seed 004 tables, tree, T-pose, orientation labels."""

from __future__ import annotations

import numpy as np
import pytest

from vidcap import body
from vidcap.body import BodyModel


def test_joint_names_match_the_design_conventions():
    assert body.JOINT_NAMES == (
        "pelvis", "neck", "head_top", "l_shoulder", "l_elbow", "l_wrist", "r_shoulder",
        "r_elbow", "r_wrist", "l_hip", "l_knee", "l_ankle", "r_hip", "r_knee", "r_ankle",
    )
    assert len(body.SEGMENTS) == 10
    assert body.DOF == 23


def test_table_3_1_lengths_sum_to_the_height():
    b = BodyModel(height=1.80)
    standing = b.length("head") + b.length("torso") + b.length("l_upper_leg") \
        + b.length("l_lower_leg")
    assert standing == pytest.approx(1.80)
    assert b.length("l_lower_arm") == pytest.approx(1.80 * 35 / 175)
    assert b.radius("torso") == pytest.approx(0.5 * 1.80 * 40 / 175)


def test_rest_pose_is_a_t_pose_with_feet_on_the_floor():
    b = BodyModel()
    p = b.rest_positions()
    J = body.JOINT_INDEX
    assert p[:, 1].min() == pytest.approx(0.0)
    assert p[J["head_top"], 1] == pytest.approx(1.75)
    # Arms horizontal, left arm toward -X (the body faces -Z), right toward +X.
    for side, sign in (("l", -1), ("r", 1)):
        arm = p[[J[f"{side}_shoulder"], J[f"{side}_elbow"], J[f"{side}_wrist"]]]
        assert np.ptp(arm[:, 1]) == pytest.approx(0.0)
        assert np.all(np.sign(np.diff(arm[:, 0])) == sign)
    # Segment lengths measured on the posed skeleton equal the model's lengths.
    seg = np.linalg.norm(body.segment_vectors(p), axis=-1)
    np.testing.assert_allclose(seg, b.segment_lengths())


def test_per_subject_lengths_override_the_ratios():
    b = BodyModel(height=1.6, lengths={"l_upper_arm": 0.31})
    assert b.length("l_upper_arm") == 0.31
    assert b.length("r_upper_arm") == pytest.approx(1.6 * 25 / 175)
    with pytest.raises(ValueError, match="unknown segment"):
        BodyModel(lengths={"tail": 0.3})
    with pytest.raises(ValueError, match="positive"):
        BodyModel(height=-1)


def test_skeleton_has_no_zero_length_bones_or_end_sites():
    sk = BodyModel().skeleton()
    assert np.all(np.linalg.norm(sk.offsets[1:], axis=1) > 0.05)
    leaves = [n for j, n in enumerate(sk.joint_names) if not sk.children(j)]
    assert sorted(leaves) == sorted(sk.end_sites)
    assert all(np.linalg.norm(v) > 0.01 for v in sk.end_sites.values())


@pytest.mark.parametrize(
    "yaw_deg, label",
    [(90, "right"), (-90, "left"), (100, "right"), (20, "front_right"), (-20, "front_left"),
     (150, "back_right"), (-150, "back_left"), (180, "back_right"), (0, "front_right")],
)
def test_orientation_labels_from_yaw(yaw_deg, label):
    assert body.orientation_from_yaw(np.deg2rad(yaw_deg)) == label
    assert label in body.ORIENTATIONS


def test_joint_limits_cover_every_segment_and_knees_fold_backward():
    assert set(body.IMAGE_ANGLE_LIMITS_DEG) == set(body.SEGMENT_NAMES)
    assert body.IMAGE_ANGLE_LIMITS_DEG["torso"] == (45.0, 135.0)  # Table 3.3 waist
    assert body.IMAGE_ANGLE_LIMITS_DEG["l_upper_leg"] == (240.0, 300.0)  # Table 3.3 hip
    assert body.FLEXION_DIRECTION["l_knee"][2] > 0  # backward = +Z (the body faces -Z)
    assert body.FLEXION_DIRECTION["l_elbow"][2] < 0
