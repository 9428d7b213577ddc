"""The warm start carried forward (vidcap.video.fit.tracking.predicted_start): legs that
pass each other in a three-quarter view keep their hips."""

import dataclasses

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX, SEGMENT_INDEX
from vidcap.video.fit.result import FramePose
from vidcap.video.fit.tracking import PREDICTED_SEGMENTS, fit_sequence, predicted_start


def _pose(angles) -> FramePose:
    return FramePose(joints=np.zeros((15, 2)), angles=np.asarray(angles, dtype=float),
                     foreshortening=np.ones(10), scores=np.zeros(10), margins=np.zeros(10),
                     spread=0.5, crossed=False, similarity=0.9, warm=True, height_px=100.0)


def test_predicted_start_turns_the_legs_on_and_leaves_the_rest():
    before = _pose(np.full(10, 1.0))
    prev = _pose(np.full(10, 1.2))
    out = predicted_start(prev, before)
    legs = list(PREDICTED_SEGMENTS)
    assert sorted(legs) == sorted(SEGMENT_INDEX[f"{s}_{p}_leg"] for s in "lr"
                                  for p in ("upper", "lower"))
    np.testing.assert_allclose(out.angles[legs], 1.4)
    others = [k for k in range(10) if k not in legs]
    np.testing.assert_allclose(out.angles[others], 1.2)
    assert out.similarity == prev.similarity and out.spread == prev.spread
    np.testing.assert_allclose(prev.angles, 1.2)  # not changed in place


def test_predicted_start_wraps_and_passes_through_without_a_frame_before():
    prev = _pose(np.full(10, 0.05))
    out = predicted_start(prev, _pose(np.full(10, 2 * np.pi - 0.05)), segments=[7])
    assert out.angles[7] == pytest.approx(0.15)  # +0.1 across 0, not -2 pi
    assert predicted_start(prev, None) is prev
    back = predicted_start(prev, dataclasses.replace(prev, angles=np.full(10, 0.25)),
                           segments=[6])
    assert back.angles[6] == pytest.approx(2 * np.pi - 0.15)  # turning clockwise


def _hip_misses(joints, truth) -> int:
    """Frames x hips more than 5 % of the height from the truth, each leg pair matched
    to the truth in its better order per frame (as pose2d_accuracy.py does)."""
    legs = [JOINT_INDEX[f"{s}_{j}"] for s in "lr" for j in ("hip", "knee", "ankle")]
    height = np.linalg.norm(truth[:, JOINT_INDEX["head_top"]] - truth[:, JOINT_INDEX["pelvis"]],
                            axis=-1) * 175.0 / 77.0
    p, t = joints[:, legs], truth[:, legs]
    direct = np.linalg.norm(p - t, axis=-1)
    swapped = np.linalg.norm(p[:, [3, 4, 5, 0, 1, 2]] - t, axis=-1)
    err = np.where((swapped.sum(1) < direct.sum(1))[:, None], swapped, direct)
    return int((err[:, [0, 3]] > 0.05 * height[:, None]).sum())


@pytest.mark.parametrize("yaw", [45.0, 135.0])
def test_legs_passing_in_a_three_quarter_view_keep_their_hips(yaw):
    # the built-in walk seen three-quarter on: once a step the knees pass in the image
    # (the thighs cross), and a track started where each leg stood bounces the legs
    # back at the meeting, leaving each leg on the other hip for the rest of the step
    # (both hips 0.06-0.09 of the height off); carried forward it passes
    from vidcap.synth import make_motion, render_clip

    motion = make_motion("walk", n_frames=36)
    _, truth = render_clip(motion, size=(320, 240), yaw_deg=yaw, noise=0.0,
                           rng=np.random.default_rng(0))
    # the whole-arm track off in both: it moves the legs' crossing choice by the arms'
    # pixels (at yaw 45 it alone keeps the hips, 22 -> 2 frames off, without
    # prediction; at yaw 135 with prediction it loses them, 0 -> 24), which would
    # hide what prediction does; so does the search of both arms together (with it,
    # at yaw 45 the hips are off in 22 frames with prediction too)
    with_prediction = fit_sequence(truth["masks"], predict=True, crossing=False,
                                   arm_track=False, arm_pairs=False).joints2d
    without = fit_sequence(truth["masks"], predict=False, crossing=False,
                           arm_track=False, arm_pairs=False).joints2d
    assert _hip_misses(with_prediction, truth["joints2d"]) <= 2
    assert _hip_misses(without, truth["joints2d"]) >= 10
