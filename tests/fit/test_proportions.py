"""The subject's own proportions from a clip (issue 27): known answers on renders of
bodies scaled away from the seed's ratios."""

import numpy as np
import pytest

from vidcap.body import SEGMENT_INDEX, body_with_proportions
from vidcap.video.fit.lengthprofile import length_profiles
from vidcap.video.fit.proportions import (
    ProportionEstimate,
    estimate_proportions,
    sample_windows,
)
from vidcap.video.fit.raster import draw_pose, model_dimensions, pose_joints

SCALED = {"legs": 1.15, "arms": 0.9, "shoulders": 1.2}


def test_length_profile_measures_clear_limbs():
    """Arms bent up beside the head and legs apart, drawn with the subject's
    proportions; a seed-proportioned model in the same pose (its ratios stretched to the
    subject's joints) reads each limb segment's own length from the outline."""
    from vidcap.body import BodyModel

    true, seed = body_with_proportions(1.0, SCALED), BodyModel(height=1.0)
    h = 200.0
    L, R, sh, hip = model_dimensions(h, true)
    angles = np.deg2rad([90, 90, 180, 90, 0, 90, 250, 265, 290, 275]).astype(float)
    joints = pose_joints(np.array([170.0, 160.0]), angles, np.ones(10), 1.0, L, sh, hip)
    mask = draw_pose(joints, R, (320, 340), caps=False)
    fore = true.segment_lengths() / seed.segment_lengths()
    spread = true.shoulder_half_width / seed.shoulder_half_width
    lengths, _ = length_profiles(mask, joints, angles, fore, spread, h)
    for seg in ("l_upper_arm", "l_lower_arm", "r_upper_arm", "r_lower_arm", "l_lower_leg",
                "r_lower_leg"):
        assert lengths[SEGMENT_INDEX[seg]] == pytest.approx(true.length(seg), rel=0.04), seg
    assert np.isnan(lengths[:2]).all()  # torso and head are not profiled


def test_sample_windows_avoid_empty_frames():
    masks = np.zeros((200, 20, 20), bool)
    masks[:, 5:15, 8:12] = True
    masks[95:105] = False  # a gap
    wins = sample_windows(masks, window=30, windows=3)
    assert len(wins) == 3
    for w in wins:
        assert masks[w].any(axis=(1, 2)).all() and w.stop - w.start == 30
    assert sample_windows(np.zeros((5, 8, 8), bool)) == []


def test_seed_estimate_reports_the_seed():
    est = ProportionEstimate()
    assert "(+0%)" in est.summary()
    assert est.body(1.75) == body_with_proportions(1.75)


@pytest.mark.parametrize("factors", [SCALED, {}])
def test_legs_and_shoulders_recovered_within_5_percent(factors):
    """A side-view walk of a body with known proportions: the legs' share of the
    height and the shoulders' breadth come back within 5 %."""
    from vidcap.synth import make_motion, render_clip

    truth = ProportionEstimate(factors=factors)
    body = truth.body(1.75)
    motion = make_motion("walk", body=body, n_frames=30)
    _, t = render_clip(motion, body=body, yaw_deg=90, size=(320, 240), noise=0.0,
                       rng=np.random.default_rng(0))
    est = estimate_proportions(t["masks"], searched=("legs", "shoulders"),
                               steps=((0.05, 4),))
    got, want = est.ratios(), truth.ratios()
    for group in ("upper_legs", "lower_legs", "torso", "shoulders"):
        assert got[group] == pytest.approx(want[group], rel=0.05), group
    assert np.isfinite(est.similarity).all()
