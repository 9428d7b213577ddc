"""The annotate page with a camera's perspective (``vidcap annotate --camera``): it lifts
what ``vidcap convert --camera`` lifts, and shows the joints where the frame has them."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from vidcap.ui.session import AnnotateSession

from vidcap.body import JOINT_INDEX
from vidcap.video.annotations import Annotations
from vidcap.video.fit.perspective import unwarp_points, warp_joints
from vidcap.video.flatview import flat_view

K, ABOVE_FEET = 0.3, 0.96  # a camera well above the subject; a real adult's ankles


def _heights(joints2d):
    """Head top to the lower ankle, pixels, per frame."""
    ankles = joints2d[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 1].max(axis=1)
    return ankles - joints2d[:, JOINT_INDEX["head_top"], 1]


@pytest.fixture(scope="module")
def camera_clips(walk_clip):
    """The sample walk's truth as a level camera sees it, and as a high camera would."""
    flat = walk_clip.joints2d
    height = _heights(flat)
    image, image_height = warp_joints(flat, height, K, ABOVE_FEET)
    level = dataclasses.replace(walk_clip, model_height=height)
    high = dataclasses.replace(walk_clip, joints2d=image, model_height=image_height,
                               perspective=(K, ABOVE_FEET))
    return level, high


def test_the_warp_moves_the_joints_by_pixels(camera_clips):
    level, high = camera_clips
    shift = np.abs(high.joints2d[..., 1] - level.joints2d[..., 1])
    assert np.nanmax(shift) > 8.0  # the test would not see a page that ignored it


def test_a_high_camera_lifts_as_the_level_one_and_shows_the_frame(camera_clips, tmp_path):
    level, high = camera_clips
    a = AnnotateSession(high, tmp_path / "high.json")
    b = AnnotateSession(level, tmp_path / "level.json")
    np.testing.assert_allclose(a.joints3d, b.joints3d, atol=1e-4)  # 0.1 mm: (u, v) kept to 0.01 px
    np.testing.assert_array_equal(a.signs, b.signs)
    # what the page lifted before --camera reached it: the warped joints as if level
    ignored = AnnotateSession(dataclasses.replace(high, perspective=(0.0, 1.0)),
                              tmp_path / "ignored.json")
    off = np.linalg.norm((ignored.joints3d - ignored.joints3d[:, :1])
                         - (b.joints3d - b.joints3d[:, :1]), axis=-1)
    assert off.max() > 0.03  # metres: a difference the tolerance above could not hide
    # the page draws the joints on the high camera's frame, not the un-warped ones
    assert np.nanmax(np.abs(a.joints2d - high.joints2d)) < 1e-6
    assert np.nanmax(np.abs(a.joints2d - b.joints2d)) > 8.0


@pytest.mark.parametrize("lift", ["solve", "segment"])
def test_a_joint_placed_on_the_frame_is_unwarped_as_the_fit_is(camera_clips, tmp_path, lift):
    level, high = camera_clips
    f, name = 12, "l_wrist"
    u, v = np.round(high.joints2d[f, JOINT_INDEX[name]] + (6.0, 14.0), 2)  # as the page keeps
    flat_uv = unwarp_points(np.array([[[u, v]]]), high.joints2d[f:f + 1],
                            high.model_height[f:f + 1], K, ABOVE_FEET)[0, 0]
    assert abs(flat_uv[1] - v) > 1.0
    a = AnnotateSession(high, tmp_path / "high.json", lift=lift)
    b = AnnotateSession(level, tmp_path / "level.json", lift=lift)
    a.set_joint(f, name, float(u), float(v))
    b.set_joint(f, name, float(flat_uv[0]), float(flat_uv[1]))
    np.testing.assert_allclose(a.joints3d, b.joints3d, atol=1e-4)  # 0.1 mm: (u, v) kept to 0.01 px
    # shown where the user put it
    np.testing.assert_allclose(a.joints2d[f, JOINT_INDEX[name]], (u, v), atol=1e-6)
    # and the full 3D stage (the reopened file) agrees with the quick one
    again = AnnotateSession(high, tmp_path / "high.json", lift=lift)
    np.testing.assert_allclose(again.joints3d, a.joints3d, atol=1e-6)


def test_flat_view_moves_joint_events_only(camera_clips):
    _, high = camera_clips
    ann = Annotations()
    ann.add_joint(3, "r_knee", *map(float, high.joints2d[3, JOINT_INDEX["r_knee"]]))
    ann.add_joint(10_000, "r_knee", 50.0, 60.0)  # beyond the clip: kept as placed
    ann.add_depth(3, "l_lower_arm", 1)
    flat2d, _, events = flat_view(high.joints2d, high.model_height, ann, high.perspective)
    _, _, joints = events.resolve(4)
    # a joint placed on the fitted joint goes where the fitted joint goes
    np.testing.assert_allclose(joints[3, JOINT_INDEX["r_knee"]],
                               flat2d[3, JOINT_INDEX["r_knee"]], atol=1e-9)
    kept = [e for e in events.events if e.frame == 10_000]
    assert kept[0].value == (50.0, 60.0)
    assert [e.type for e in events.events] == [e.type for e in ann.events]
    # a level camera changes nothing, to the object
    assert flat_view(high.joints2d, high.model_height, ann)[2] is ann


def test_load_clip_with_converts_camera_lifts_what_convert_lifts(tmp_path):
    from pathlib import Path

    from vidcap.ui.session import load_clip

    from vidcap.video import pipeline
    from vidcap.video.fit.perspective import camera_perspective

    video = Path(__file__).resolve().parents[2] / "sample_videos" / "walk_side.mp4"
    camera = (2.5, 3.0)
    clip = load_clip(video, cache_dir=tmp_path, camera=camera)
    assert clip.perspective[0] == pytest.approx(camera_perspective(camera, 1.75))
    session = AnnotateSession(clip, tmp_path / "a.json")
    res = pipeline.run(video, cache_dir=tmp_path, camera=camera)
    np.testing.assert_allclose(session.joints3d, res.lifted.joints3d, atol=1e-9)
    assert res.perspective == clip.perspective
