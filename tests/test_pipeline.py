"""The 3D stage of the pipeline (lift_pose) and the stage cache, without video."""

import numpy as np
import pytest

from tests.posed import posed_clip
from vidcap.body import JOINT_INDEX, SEGMENT_INDEX
from vidcap.errors import VidcapError
from vidcap.video.annotations import Annotations
from vidcap.video.lift import swap_sides
from vidcap.video.masks import MaskStack, edges_reached, pixel_counts, touches_border
from vidcap.video.pipeline import (
    VIEWS,
    ConvertResult,
    StageCache,
    constrain_orientation,
    fill_gaps,
    lift_pose,
    partly_outside,
    person_track,
)
from vidcap.video.result import cut_notice


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


def test_constrain_orientation_keeps_the_facing_within_the_view():
    labels = np.array(["right", "front_right", "back_left", "left"])
    assert list(constrain_orientation(labels, "auto")) == list(labels)
    assert list(constrain_orientation(labels, "side")) == ["right", "right", "left", "left"]
    assert list(constrain_orientation(labels, "front")) == [
        "front_right", "front_right", "front_left", "front_left"]
    assert list(constrain_orientation(labels, "back")) == [
        "back_right", "back_right", "back_left", "back_left"]
    assert set(constrain_orientation(labels, "back_right")) == {"back_right"}
    with pytest.raises(ValueError, match="unknown view 'sideways'"):
        constrain_orientation(labels, "sideways")


def test_cli_view_choices_are_the_pipelines():
    from vidcap.commands.convert import VIEW_CHOICES

    assert set(VIEW_CHOICES) == set(VIEWS) and len(VIEW_CHOICES) == len(VIEWS)


def test_lift_pose_view_side_turns_a_three_quarter_reading_into_a_side_view():
    """A walk seen at 45 degrees reads as three-quarter; told ``side``, the lift puts
    the body at -/+90 degrees (facing still proposed); an orientation event of the
    user's still wins from its frame."""
    j2, _, _, fps = posed_clip(45.0, 40)
    auto = lift_pose(j2, fps=fps, image_sides=False)
    assert set(auto.proposed_orientation) == {"front_right"}
    side = lift_pose(j2, fps=fps, image_sides=False, view="side")
    assert set(side.orientation) == {"right"}
    np.testing.assert_allclose(side.yaw, np.pi / 2)
    # the facing comes from the proposal, not from the view
    mirrored = j2.copy()
    mirrored[..., 0] *= -1.0
    assert set(lift_pose(swap_sides(mirrored), fps=fps, image_sides=False,
                         view="side").orientation) == {"left"}
    ann = Annotations()
    ann.add_orientation(25, "back_right")
    told = lift_pose(j2, fps=fps, annotations=ann, image_sides=False, view="front")
    assert set(told.orientation[:25]) == {"front_right"}
    assert set(told.orientation[25:]) == {"back_right"}


def _result_with(proposed, view="auto"):
    """A ConvertResult holding only what :meth:`ConvertResult.notices` reads."""
    from types import SimpleNamespace

    n = len(proposed)
    return ConvertResult(
        video="v.mp4", fps=25.0, masks=np.zeros((n, 2, 2), bool), bbox=np.zeros((n, 4)),
        scores=np.zeros((n, 10)), similarity=np.full(n, 0.8),
        lifted=SimpleNamespace(proposed_orientation=np.asarray(proposed)), motion=None,
        jitter_before=0.0, jitter_after=0.0, image_joints2d=np.zeros((n, 15, 2)),
        view=view)


def test_a_wavering_view_is_reported_with_the_option_that_fixes_it():
    mixed = ["right"] * 19 + ["front_right"] * 24
    notes = _result_with(mixed).notices()
    assert any("side view in 19 frames" in m and "--view side" in m for m in notes)
    # told, or nearly all one sector (a turn through the side view takes a few frames)
    assert not any("--view" in m for m in _result_with(mixed, view="side").notices())
    few = ["right"] * 5 + ["front_right"] * 38
    assert not any("--view" in m for m in _result_with(few).notices())


def test_an_estimated_plate_with_many_empty_frames_or_a_poor_fit_suggests_a_photo():
    ok = _result_with(["right"] * 40)
    assert not any("--background" in m for m in ok.notices())
    empty = _result_with(["right"] * 40)
    empty.image_joints2d[:12] = np.nan  # 30 % of the frames without a person
    assert any("--background plate.png" in m for m in empty.notices())
    poor = _result_with(["right"] * 40)
    poor.similarity[:] = 0.36
    assert any("--background plate.png" in m for m in poor.notices())
    # a photo of the scene was given: nothing to suggest
    poor.plate_estimated = False
    assert not any("--background" in m for m in poor.notices())


def test_fill_gaps():
    j = np.arange(4 * 15 * 2, dtype=float).reshape(4, 15, 2)
    g = j.copy()
    g[1:3] = np.nan
    np.testing.assert_allclose(fill_gaps(g), j)
    with pytest.raises(VidcapError, match="no person"):
        fill_gaps(np.full((3, 15, 2), np.nan))



def test_frames_mostly_outside_the_picture_are_left_out():
    """A 20x40 'person' slides out at the right: the frames that touch the border
    with less than 70 % of the usual area are left out; a stack and an array agree."""
    masks = np.zeros((12, 60, 80), bool)
    for k in range(12):
        x = 10 + 6 * k
        masks[k, 10:50, x:x + 20] = True  # clipped by the frame from k = 9 on
    masks[3, 10:50, 10:14] = False  # gait: a thinner frame clear of the border counts
    stack = MaskStack.from_masks(masks)
    area = masks.sum((1, 2))
    for m in (masks, stack):
        assert (pixel_counts(m) == area).all()
        assert touches_border(m).tolist() == [False] * 9 + [True] * 3
        out = partly_outside(m)
        # k = 9, 10, 11 keep 16, 10, 4 of their 20 columns
        assert out.tolist() == [False] * 10 + [True] * 2
    track = person_track(np.array([[10 + 6 * k, 10, 30 + 6 * k, 50] for k in range(12)]),
                         masks, exclude=out)
    assert track[10] == track[11] == track[9]  # held from the last frame kept
    # the whole clip cut off (the feet below the frame, say): no reference, none left out
    cut = np.zeros((8, 60, 80), bool)
    cut[:, 30:, 30:50] = True
    assert not partly_outside(cut).any()


def test_a_person_cut_off_by_the_picture_is_told_which_edge_and_when():
    """Feet below the frame in 6 of 8 frames (a webcam's thighs-up shot): the notice names
    the bottom edge and the frames; a head above it in 1 of 8 (12.5 %, over CUT_SHARE) is
    named too; a person clear of every edge gets no notice, and frames without a fitted
    person are not counted."""
    masks = np.zeros((8, 60, 80), bool)
    masks[:, 20:58, 30:50] = True
    masks[2:, 58:] = masks[2:, 57:58]  # frames 2-7 reach the last row
    stack = MaskStack.from_masks(masks)
    seen = np.ones(8, bool)
    for m in (masks, stack):
        assert edges_reached(m)[:, 1].tolist() == [False] * 2 + [True] * 6
        assert not edges_reached(m)[:, [0, 2, 3]].any()
        note = cut_notice(m, seen)
        assert "bottom edge in 6 of 8 frames (2-7)" in note and "feet" in note
        assert "top" not in note and "the head" not in note
    assert cut_notice(masks[:2], seen[:2]) is None  # clear of every edge
    # frames without a fitted person do not count: 6 cut frames of 60 seen are 10 %
    few = np.concatenate([masks, np.repeat(masks[:1], 52, axis=0)])
    assert "6 of 60" in cut_notice(few, np.ones(60, bool))
    assert cut_notice(few, np.r_[np.zeros(8, bool), np.ones(52, bool)]) is None
    assert cut_notice(few, np.r_[np.ones(4, bool), np.zeros(4, bool), np.ones(52, bool)]) \
        is None  # 2 cut frames of 56 seen: under CUT_SHARE
    head = masks.copy()
    head[0, :21, 35:45] = True  # the head above the frame in frame 0 only
    note = cut_notice(head, seen)
    assert "bottom edge in 6 of 8 frames (2-7) and its top edge in 1 of 8 frames (0)" in note
    assert "cuts off the feet or legs and the head there" in note


def test_stage_cache_round_trip_and_damage(tmp_path):
    c = StageCache(tmp_path)
    assert c.load("pose2d", "k1") is None
    c.save("pose2d", "k1", a=np.arange(3))
    np.testing.assert_array_equal(c.load("pose2d", "k1")["a"], np.arange(3))
    assert c.load("pose2d", "k2") is None
    c.path("pose2d", "k1").write_bytes(b"garbage")
    assert c.load("pose2d", "k1") is None  # a damaged entry is recomputed, not an error
    assert StageCache(None).load("pose2d", "k1") is None


def test_run_says_when_more_than_one_person_is_in_view(tmp_path):
    from tests._synthframes import background, figure_mask
    from vidcap.io.video import write_video
    from vidcap.video.pipeline import run

    rng = np.random.default_rng(3)
    h, w, n = 240, 320, 24
    bg = background(h, w, rng)
    frames = []
    for i in range(n):
        # a walker crossing the frame and, from frame 12 on, a second one standing by
        m = figure_mask(h, w, 2 * np.pi * i / 12, cx=(0.25 + 0.3 * i / n) * w) > 0
        if i >= 12:
            m |= figure_mask(h, w, 0.0, cx=0.88 * w) > 0
        frames.append(np.where(m[..., None], np.uint8([40, 50, 160]), bg))
    video = tmp_path / "two.mp4"
    write_video(video, frames, 12.0)
    said = []
    run(video, progress=False, log=said.append)
    crowd = [m for m in said if "more than one person" in m]
    assert len(crowd) == 1, said
    count = int(crowd[0].split("blob in ")[1].split(" of ")[0])
    assert 8 <= count <= 12  # the frames with the second figure (its first few may be plate)
    said.clear()
    lone = tmp_path / "one.mp4"
    write_video(lone, frames[:12], 12.0)
    run(lone, progress=False, log=said.append)
    assert not any("more than one person" in m for m in said)


def test_lift_pose_reads_segments_at_the_model_height_of_each_frame():
    # The 2D fitter scales its model to each silhouette, which is a few per cent
    # shorter with the feet apart: every segment of those frames is drawn that much
    # shorter. Read at one scale for the clip that is depth in every segment; read at
    # the frame's model height (Pose2D.model_height) it is not.
    from vidcap.body import BodyModel
    from vidcap.video.pipeline import model_scales

    body = BodyModel()
    j2, j3, signs, fps = posed_clip(90.0, 60, scale=200.0)
    shrink = 0.975 + 0.025 * np.cos(np.arange(60) / 3.0)  # 0.95 .. 1.0
    top = j2[:, JOINT_INDEX["head_top"]][:, None]
    drawn = top + (j2 - top) * shrink[:, None, None]  # the model hangs from the head
    heights = 200.0 * body.height * shrink
    ann = Annotations()
    ann.add_orientation(0, "right")  # facing image right: the test is about depth
    # the per-segment lift: the scale's effect alone (the clip solve's pose prior, which
    # assumes the 2D fit's errors, takes back part of the one-scale reading's depth)
    exact = lift_pose(j2, fps=fps, annotations=ann, image_sides=False, method="segment")
    one = lift_pose(drawn, fps=fps, annotations=ann, image_sides=False, method="segment")
    per = lift_pose(drawn, fps=fps, annotations=ann, image_sides=False,
                    model_height=heights, method="segment")
    np.testing.assert_allclose(per.segment_scale, heights / body.height)
    e_exact, e_one, e_per = (_mpjpe(r.joints3d, j3) for r in (exact, one, per))
    assert e_per < e_exact + 0.005  # metres
    assert e_one > e_per + 0.02
    solved = [lift_pose(drawn, fps=fps, annotations=ann, image_sides=False, model_height=h)
              for h in (None, heights)]
    assert _mpjpe(solved[1].joints3d, j3) < _mpjpe(solved[0].joints3d, j3)  # the solve too
    # gaps (no fit) take their neighbours' scale; nothing usable: None (one scale)
    gappy = heights.copy()
    gappy[10:13] = np.nan
    s = model_scales(gappy, 60, body)
    between = np.interp(11, [9, 13], heights[[9, 13]])
    assert np.isfinite(s).all() and s[11] == pytest.approx(between / body.height)
    assert model_scales(np.full(60, np.nan), 60, body) is None
    with pytest.raises(ValueError, match="model_height"):
        model_scales(heights[:5], 60, body)


def test_a_sides_event_swaps_a_limb_pair_from_its_frame_on():
    # side view: nothing in the image tells the near leg from the far one; a 2D stage
    # that named them the other way round is put right by one sides event
    from vidcap.video.pipeline import swap_pairs

    j2, j3, signs, fps = posed_clip(90.0, 40)
    ann = Annotations()
    ann.add_orientation(0, "right")
    wrong = swap_pairs(j2, np.tile([False, True], (40, 1)))  # legs named the other way
    good = lift_pose(j2, fps=fps, annotations=ann, image_sides=False)
    bad = lift_pose(wrong, fps=fps, annotations=ann, image_sides=False)
    ann.add_sides(0, "legs", True)
    fixed = lift_pose(wrong, fps=fps, annotations=ann, image_sides=False)
    np.testing.assert_allclose(fixed.joints2d, good.joints2d)
    assert _mpjpe(fixed.joints3d, j3) < _mpjpe(good.joints3d, j3) + 1e-9
    assert _mpjpe(bad.joints3d, j3) > _mpjpe(good.joints3d, j3) + 0.02
    # from frame 20 on only
    late = Annotations()
    late.add_orientation(0, "right")
    late.add_sides(20, "legs", True)
    part = lift_pose(wrong, fps=fps, annotations=late, image_sides=False)
    np.testing.assert_allclose(part.joints2d[:20], wrong[:20])
    np.testing.assert_allclose(part.joints2d[20:], j2[20:])
    with pytest.raises(ValueError, match="swapped must be"):
        swap_pairs(j2, np.zeros((3, 2), bool))


def test_lift_pose_reports_how_much_longer_a_clamped_segment_was():
    from vidcap.body import BodyModel

    j2, j3, signs, fps = posed_clip(90.0, 10, scale=200.0)
    k = SEGMENT_INDEX["l_lower_arm"]
    length = BodyModel().segment_lengths()[k]
    elbow, wrist = j2[4, JOINT_INDEX["l_elbow"]], j2[4, JOINT_INDEX["l_wrist"]]
    far = elbow + (wrist - elbow) / np.linalg.norm(wrist - elbow) * 1.5 * length * 200.0
    ann = Annotations()
    ann.add_joint(4, "l_wrist", *far)  # the forearm drawn 1.5 times the model's length
    res = lift_pose(j2, fps=fps, annotations=ann, image_sides=False)
    assert res.clamped[4, k] and res.excess[4, k] == pytest.approx(0.5, abs=0.05)
    assert np.all(res.excess[np.arange(10) != 4] < 0.02)


def test_a_failure_while_the_fit_workers_start_ends_them_at_once(tmp_path):
    """A clip long enough for the fit's worker processes (which start before the
    silhouettes) and a plate of the wrong size: the error comes at once, no worker is
    left running and no output is written."""
    import multiprocessing
    import time

    import cv2

    from vidcap.io.video import write_video
    from vidcap.video.pipeline import convert

    rng = np.random.default_rng(0)
    frames = rng.integers(0, 255, size=(130, 48, 64, 3), dtype=np.uint8)
    video = tmp_path / "clip.mp4"
    write_video(video, frames, fps=25)
    plate = tmp_path / "plate.png"
    cv2.imwrite(str(plate), np.zeros((40, 40, 3), np.uint8))
    t0 = time.perf_counter()
    with pytest.raises(VidcapError, match="background is 40x40"):
        convert(video, tmp_path / "out.bvh", background=plate, cache_dir=None,
                progress=False, jobs=2)
    assert time.perf_counter() - t0 < 4.0  # (it used to wait 5 s for a stopped worker)
    assert not multiprocessing.active_children()
    assert not list(tmp_path.glob("*.bvh"))


def test_run_fits_the_default_human_body_once(tmp_path):
    """``run``'s default body is a real adult's (``proportions='human'``): the 2D fit is
    done once, with that body (the seed's never fitted first), its model height head top
    to ankles (the feet left out), and the motion's skeleton is that body's."""
    from vidcap.synth import make_motion, synth_clip
    from vidcap.video.fit.proportions import HUMAN, fit_keywords, human_proportions
    from vidcap.video.fit.tracking import fit_sequence
    from vidcap.video.pipeline import DEFAULT_PROPORTIONS, run

    assert DEFAULT_PROPORTIONS == "human"
    est = human_proportions()
    body = est.body(1.75)
    video = tmp_path / "walk.mp4"
    motion = make_motion("walk", body=body, n_frames=12)
    synth_clip(video, tmp_path / "t.npz", motion, body=body, foot=est.foot, size=(160, 120),
               rng=np.random.default_rng(0))
    said = []
    res = run(video, progress=False, jobs=1, log=said.append)
    assert "proportions" not in res.timings  # no second fit
    assert res.proportions.factors == HUMAN and any("body proportions" in m for m in said)
    direct = fit_sequence(res.masks, cues="outline", **fit_keywords(HUMAN))
    np.testing.assert_array_equal(res.similarity, direct.similarity)
    np.testing.assert_allclose(res.model_height, direct.model_height * (1 - est.foot))
    np.testing.assert_allclose(res.motion.skeleton.offsets, body.skeleton().offsets)
    seed = run(video, progress=False, jobs=1, proportions="seed")
    assert seed.proportions is None
    assert not np.array_equal(seed.similarity, res.similarity)


@pytest.mark.parametrize("factors, height", [
    ({"legs": 1.15, "arms": 1.05, "shoulders": 0.85, "arm_width": 0.8}, 1.92),  # tall, thin
    ({"legs": 0.9, "arms": 0.95, "shoulders": 1.2, "leg_width": 1.2}, 1.58),  # short, broad
])
def test_auto_proportions_reach_the_lift_and_the_bvh(tmp_path, monkeypatch, factors, height):
    """``proportions='auto'``: the estimate's body (its own bone lengths at the given
    height) is what the second 2D fit, the 3D lift and the motion's skeleton use, and
    the BVH written from it carries those lengths (the estimator is replaced by a known
    answer here; ``tests/fit/test_proportions.py`` checks the estimator itself)."""
    import vidcap.video.bodystage as bodystage
    from vidcap.body import SEGMENT_NAMES, SEGMENTS
    from vidcap.io.bvh import read_bvh, write_bvh
    from vidcap.synth import make_motion, synth_clip
    from vidcap.video.fit.proportions import ProportionEstimate
    from vidcap.video.pipeline import run

    est = ProportionEstimate(factors=factors, evidence=dict.fromkeys(factors, 30))
    body = est.body(height)
    seed_body = ProportionEstimate().body(height)
    video = tmp_path / "walk.mp4"
    motion = make_motion("walk", body=body, n_frames=10)
    synth_clip(video, tmp_path / "t.npz", motion, body=body, size=(160, 120),
               rng=np.random.default_rng(0))
    calls = []
    monkeypatch.setattr(bodystage, "estimate_proportions",
                        lambda masks, **kw: calls.append(len(masks)) or est)
    said = []
    res = run(video, progress=False, jobs=1, proportions="auto", height=height,
              log=said.append, cues="outline")
    assert calls == [10] and res.proportions is est
    assert any(est.summary() in m for m in said)
    np.testing.assert_allclose(res.body.segment_lengths(), body.segment_lengths())
    assert not np.allclose(body.segment_lengths(), seed_body.segment_lengths(), rtol=0.03)
    # the lift's bones are the body's (every frame, every segment)
    j3 = res.lifted.joints3d
    for name, seg in zip(SEGMENT_NAMES, SEGMENTS, strict=True):
        bone = np.linalg.norm(j3[:, JOINT_INDEX[seg.distal]] - j3[:, JOINT_INDEX[seg.proximal]],
                              axis=-1)
        np.testing.assert_allclose(bone, body.length(name), rtol=1e-3, err_msg=name)
    # the motion's skeleton, and the BVH's offsets read back, are the body's
    np.testing.assert_allclose(res.motion.skeleton.offsets, body.skeleton().offsets)
    write_bvh(tmp_path / "m.bvh", res.motion)
    back = read_bvh(tmp_path / "m.bvh").skeleton.offsets
    np.testing.assert_allclose(back, body.skeleton().offsets, atol=1e-5)
    knee = JOINT_INDEX["l_knee"]
    assert np.linalg.norm(back[knee]) == pytest.approx(body.length("l_upper_leg"), rel=1e-4)
