"""The 3D stage of the pipeline (lift_pose) and the stage cache, without video."""

import numpy as np
import pytest

from tests.posed import posed_clip
from vidcap.annotations import Annotations
from vidcap.body import JOINT_INDEX, SEGMENT_INDEX
from vidcap.errors import VidcapError
from vidcap.lift import swap_sides
from vidcap.pipeline import StageCache, fill_gaps, lift_pose


def _mpjpe(a, b):
    return np.linalg.norm((a - a[:, :1]) - (b - b[:, :1]), axis=-1).mean()


def test_lift_pose_assigns_true_sides_from_image_sides():
    j2, j3, signs, fps = posed_clip(30.0, 60)  # facing the camera, turned right
    image_named = swap_sides(j2)  # what the 2D fitter reports: l_* = the image's left
    ann = Annotations()
    ann.add_orientation(0, "front_right")
    res = lift_pose(image_named, fps=fps, annotations=ann, image_sides=True)
    np.testing.assert_allclose(res.joints2d, j2)
    assert _mpjpe(res.joints3d, j3) < 0.06 * 1.75
    # orientation was the user's; the proposal is still reported
    assert set(res.orientation) == {"front_right"} and res.proposed_orientation.shape == (60,)


def test_lift_pose_applies_user_signs_and_joints():
    j2, j3, signs, fps = posed_clip(45.0, 30)
    k = SEGMENT_INDEX["r_lower_leg"]
    free = lift_pose(j2, fps=fps, image_sides=False)
    ann = Annotations()
    ann.add_depth(3, "r_lower_leg", int(-free.proposed_signs[3, k]))
    ann.add_joint(7, "l_wrist", 11.0, 22.0)
    res = lift_pose(j2, fps=fps, annotations=ann, image_sides=False)
    assert res.signs[3, k] == -free.proposed_signs[3, k]
    np.testing.assert_array_equal(res.proposed_signs, free.proposed_signs)
    np.testing.assert_allclose(res.joints2d[7, JOINT_INDEX["l_wrist"]], [11.0, 22.0])


def test_fill_gaps():
    j = np.arange(4 * 15 * 2, dtype=float).reshape(4, 15, 2)
    g = j.copy()
    g[1:3] = np.nan
    np.testing.assert_allclose(fill_gaps(g), j)
    with pytest.raises(VidcapError, match="no person"):
        fill_gaps(np.full((3, 15, 2), np.nan))


def test_stage_cache_round_trip_and_damage(tmp_path):
    c = StageCache(tmp_path)
    assert c.load("pose2d", "k1") is None
    c.save("pose2d", "k1", a=np.arange(3))
    np.testing.assert_array_equal(c.load("pose2d", "k1")["a"], np.arange(3))
    assert c.load("pose2d", "k2") is None
    c.path("pose2d", "k1").write_bytes(b"garbage")
    assert c.load("pose2d", "k1") is None  # a damaged entry is recomputed, not an error
    assert StageCache(None).load("pose2d", "k1") is None
