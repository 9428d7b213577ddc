"""AnnotateSession: edits re-lift at once, autosave atomically, malformed files are kept."""

from __future__ import annotations

import json

import numpy as np
import pytest
from vidcap.ui.session import AnnotateSession, backup_path

from vidcap.body import JOINT_INDEX, SEGMENT_INDEX, SEGMENT_JOINTS
from vidcap.video.annotations import Annotations


def _events(path):
    return json.loads(path.read_text())["events"]


def test_fresh_session_writes_nothing(walk_clip, tmp_path):
    path = tmp_path / "a.json"
    s = AnnotateSession(walk_clip, path)
    assert s.n_user_inputs == 0 and s.load_error is None
    assert not path.exists()
    assert s.joints3d.shape == (walk_clip.n_frames, 15, 3)
    info = s.frame_info(0)
    assert len(info["segments"]) == 10 and info["orientation"] == "right"


def test_depth_edit_relifts_from_that_frame_on_and_saves(walk_clip, tmp_path):
    path = tmp_path / "a.json"
    s = AnnotateSession(walk_clip, path, lift="segment")  # Eq. 2.2 exactly
    k = SEGMENT_INDEX["l_lower_arm"]
    a, b = SEGMENT_JOINTS[k]
    before = s.joints3d.copy()
    old_sign = s.signs[:, k].copy()
    ms = s.set_depth(10, "l_lower_arm", -int(old_sign[10]))
    assert ms > 0
    # carried forward until the segment next passes through the image plane (after
    # that the proposals decide again)
    passes = np.flatnonzero(s._near_plane[11:, k])
    stop = 11 + int(passes[0]) if passes.size else walk_clip.n_frames
    assert stop > 12 and (s.signs[10:stop, k] == -old_sign[10]).all()
    dz_old = before[10, b, 2] - before[10, a, 2]
    dz_new = s.joints3d[10, b, 2] - s.joints3d[10, a, 2]
    # Eq. 2.2: the same depth magnitude, the other sign (unless the segment is in the plane)
    assert dz_new == pytest.approx(-dz_old, abs=1e-9)
    # the image-plane coordinates are untouched
    np.testing.assert_allclose(s.joints3d[10, :, :2], before[10, :, :2], atol=1e-12)
    assert _events(path) == [{"frame": 10, "type": "depth", "segment": "l_lower_arm",
                              "value": "away" if old_sign[10] > 0 else "toward"}]
    assert s.n_user_inputs == 1
    assert Annotations.load(path, walk_clip.n_frames).n_user_inputs == 1


def test_flip_then_reopen_restores_state(walk_clip, tmp_path):
    path = tmp_path / "a.json"
    s = AnnotateSession(walk_clip, path)
    s.flip_depth(3, "r_lower_leg")
    s.set_orientation(20, "front_right")
    s.set_joint(7, "l_wrist", 100.5, 200.25)
    s2 = AnnotateSession(walk_clip, path)
    assert s2.n_user_inputs == 3
    np.testing.assert_array_equal(s2.signs, s.signs)
    np.testing.assert_allclose(s2.joints3d, s.joints3d)
    assert s2.orientation[19] == "right" and s2.orientation[20] == "front_right"
    np.testing.assert_allclose(s2.joints2d[7, JOINT_INDEX["l_wrist"]], [100.5, 200.25])
    # the joint fix holds at its frame only
    np.testing.assert_allclose(s2.joints2d[8], walk_clip.joints2d[8])
    assert s2.frame_info(7)["user_joints"] == ["l_wrist"]


@pytest.mark.parametrize("lift, tol", [("segment", 0.05), ("solve", 0.35)])
def test_joint_fix_moves_the_3d_joint(walk_clip, tmp_path, lift, tol):
    # the solve weighs the fixed joint against its neighbours in time and the bones
    s = AnnotateSession(walk_clip, tmp_path / "a.json", lift=lift)
    j = JOINT_INDEX["r_wrist"]
    before = s.joints3d[12, j].copy()
    u, v = walk_clip.joints2d[12, j] + [12.0, -8.0]
    s.set_joint(12, "r_wrist", u, v)
    moved = s.joints3d[12, j] - before
    assert moved[0] == pytest.approx(12.0 / s.scale, rel=tol)
    assert moved[1] == pytest.approx(8.0 / s.scale, rel=tol)  # image y down, Y up
    s.clear_joint(12, "r_wrist")
    np.testing.assert_allclose(s.joints3d[12, j], before)
    assert s.n_user_inputs == 0


def test_nearest_joint_pick(walk_clip, tmp_path):
    s = AnnotateSession(walk_clip, tmp_path / "a.json")
    u, v = walk_clip.joints2d[4, JOINT_INDEX["head_top"]]
    assert s.nearest_joint(4, u + 2, v - 1, radius=6) == "head_top"
    assert s.nearest_joint(4, u + 200, v, radius=6) is None


def test_attention_list_and_cycling(walk_clip, tmp_path):
    s = AnnotateSession(walk_clip, tmp_path / "a.json")
    items = s.flagged()
    assert any(it["frame"] == 5 and it["segment"] == "" for it in items)  # poor fit flagged
    seen = []
    for _ in range(len(items)):
        it = s.next_attention(-1)
        seen.append((it["frame"], it["segment"]))
    assert len(set(seen)) == len(items)  # every item once before cycling
    # a user sign removes that segment's doubt at that frame
    depth_items = [it for it in items if it["segment"]]
    if depth_items:
        it = depth_items[0]
        s.set_depth(it["frame"], it["segment"], 1)
        assert all((x["frame"], x["segment"]) != (it["frame"], it["segment"])
                   for x in s.flagged())



def test_frames_not_fitted_are_flagged_as_filled(tmp_path):
    """A fit score of 0 marks a frame the pipeline did not fit (filled from its
    neighbours); the list says so rather than calling it a poor fit."""
    from tests.ui.clips import truth_clip

    clip = truth_clip("walk_side", poor_fit=(5,))
    clip.fit_score[[7, 8]] = 0.0
    items = [it for it in AnnotateSession(clip, tmp_path / "a.json").flagged()
             if not it["segment"]]
    reasons = {it["frame"]: it["reason"] for it in items}
    assert reasons[5] == "2D fit poor (0.30)"
    # one item for the run of frames 7-8, at its first frame, before the poor fits
    assert reasons[7].startswith("frames 7-8 not fitted") and 8 not in reasons
    assert [it["frame"] for it in items][:2] == [7, 5]

def test_malformed_file_is_kept_and_backed_up(walk_clip, tmp_path):
    path = tmp_path / "a.json"
    text = '{"version": 1, "events": [{"frame": 2, "type": "depth", "segment": "tail"}'
    path.write_text(text)
    s = AnnotateSession(walk_clip, path)
    assert s.load_error and "a.json" in s.load_error
    assert s.backup == tmp_path / "a.json.bak"
    assert s.backup.read_text() == text and path.read_text() == text
    s.save()  # nothing to save: the user's file must not become an empty one
    assert path.read_text() == text
    # a second start keeps the first backup and makes another
    s2 = AnnotateSession(walk_clip, path)
    assert s2.backup == tmp_path / "a.json.bak1"
    # the first real edit writes the new file; the backup stays
    s2.set_depth(0, "torso", 1)
    assert _events(path) == [{"frame": 0, "type": "depth", "segment": "torso",
                              "value": "toward"}]
    assert s.backup.read_text() == text


def test_backup_path_is_free(tmp_path):
    p = tmp_path / "x.json"
    assert backup_path(p).name == "x.json.bak"
    (tmp_path / "x.json.bak").write_text("")
    assert backup_path(p).name == "x.json.bak1"


def test_bad_edits_are_refused(walk_clip, tmp_path):
    s = AnnotateSession(walk_clip, tmp_path / "a.json")
    with pytest.raises(ValueError):
        s.set_depth(walk_clip.n_frames, "torso", 1)
    with pytest.raises(ValueError):
        s.set_orientation(0, "upside_down")
    with pytest.raises(ValueError):
        s.set_joint(0, "tail", 1, 2)
    assert s.n_user_inputs == 0 and not (tmp_path / "a.json").exists()


def test_deferred_refresh_matches_full_edit(walk_clip, tmp_path):
    full = AnnotateSession(walk_clip, tmp_path / "full.json")
    lazy = AnnotateSession(walk_clip, tmp_path / "lazy.json", defer_refresh=True)
    for s in (full, lazy):
        s.set_depth(8, "r_upper_leg", -1)
        s.set_orientation(15, "front_right")
    k = SEGMENT_INDEX["r_upper_leg"]
    held = lazy.user_signs[:, k] != 0  # from 8 until the segment next passes the image plane
    assert lazy.stale and held[8] and (lazy.signs[held, k] == -1).all()
    assert (tmp_path / "lazy.json").read_text() == (tmp_path / "full.json").read_text()
    assert lazy.refresh() and not lazy.stale
    np.testing.assert_array_equal(lazy.signs, full.signs)
    np.testing.assert_allclose(lazy.joints3d, full.joints3d)


def test_refresh_dropped_when_an_edit_comes_in(walk_clip, tmp_path):
    s = AnnotateSession(walk_clip, tmp_path / "a.json", defer_refresh=True)
    s.set_depth(3, "torso", 1)
    real = s._lift_pose

    def lift_then_edit(annotations):
        out = real(annotations)
        s._lift_pose = real
        s.set_depth(4, "head", -1)  # the user clicks again while the worker runs
        return out

    s._lift_pose = lift_then_edit
    assert s.refresh() is False and s.stale
    assert s.refresh() is True and not s.stale
    assert s.signs[4, SEGMENT_INDEX["head"]] == -1


def test_frames_without_a_fit_are_filled_and_drawn(walk_clip, tmp_path):
    from dataclasses import replace

    from vidcap.ui import render

    j2 = walk_clip.joints2d.copy()
    j2[[0, 1, 20]] = np.nan
    clip = replace(walk_clip, joints2d=j2)
    s = AnnotateSession(clip, tmp_path / "a.json")
    assert np.isfinite(s.joints3d).all() and np.isfinite(s.joints2d).all()
    # frame 20 is interpolated between its neighbours (vidcap.video.pipeline.fill_gaps)
    np.testing.assert_allclose(s.joints2d[20], (j2[19] + j2[21]) / 2)
    nan_pose = np.full((15, 2), np.nan)
    img = render.draw_model(clip.read_frame(20), nan_pose, s.signs[20])
    np.testing.assert_array_equal(img, clip.read_frame(20))  # nothing to draw, no crash


@pytest.mark.parametrize("lift, atol", [("segment", 1e-9), ("solve", 0.03)])
def test_quick_relift_agrees_with_the_full_stage_for_user_signs(walk_clip, tmp_path, lift,
                                                                 atol):
    """Before the worker's refresh, a user's sign already shows (and the rest agrees with
    the last full result, so the page does not jump when the refresh lands; the solve's
    local re-solve of the edited frames is within a few cm of the whole clip's)."""
    lazy = AnnotateSession(walk_clip, tmp_path / "a.json", defer_refresh=True, lift=lift)
    lazy.set_depth(6, "l_upper_arm", -1)
    quick = lazy.joints3d.copy()
    k = SEGMENT_INDEX["l_upper_arm"]
    assert lazy.signs[6, k] == -1
    lazy.refresh()
    assert lazy.signs[6, k] == -1
    np.testing.assert_allclose(quick[6], lazy.joints3d[6], atol=atol)


def test_solve_depth_edit_is_hard_and_local(walk_clip, tmp_path):
    """With the clip solve, a deferred depth edit re-solves only the frames it reaches:
    the user's sign holds there (the distal joint on that side of the image plane) and
    frames far from the edit keep their pose."""
    s = AnnotateSession(walk_clip, tmp_path / "a.json", defer_refresh=True)
    k = SEGMENT_INDEX["l_lower_leg"]
    a, b = SEGMENT_JOINTS[k]
    before = s.joints3d.copy()
    want = -int(s.signs[20, k])
    s.set_depth(20, "l_lower_leg", want)
    held = np.flatnonzero(s.user_signs[:, k] != 0)
    assert held[0] == 20
    dz = s.joints3d[held, b, 2] - s.joints3d[held, a, 2]
    assert (np.sign(dz) == want).all()
    np.testing.assert_array_equal(s.joints3d[:5], before[:5])


def test_sides_edit_swaps_the_legs_from_that_frame_on(walk_clip, tmp_path):
    path = tmp_path / "a.json"
    s = AnnotateSession(walk_clip, path, defer_refresh=True)
    before = s.joints2d.copy()
    s.flip_sides(12, "legs")
    left = [JOINT_INDEX[f"l_{j}"] for j in ("hip", "knee", "ankle")]
    right = [JOINT_INDEX[f"r_{j}"] for j in ("hip", "knee", "ankle")]
    np.testing.assert_allclose(s.joints2d[:12], before[:12])
    np.testing.assert_allclose(s.joints2d[12:, left], before[12:, right])
    np.testing.assert_allclose(s.joints2d[12:, right], before[12:, left])
    assert not s.stale  # the full stage ran: the proposals follow the renamed legs
    assert s.frame_info(12)["sides_swapped"] == ["legs"]
    assert s.frame_info(11)["sides_swapped"] == []
    assert _events(path) == [{"frame": 12, "type": "sides", "pair": "legs",
                              "value": "swapped"}]
    s.flip_sides(30, "legs")  # and back from frame 30
    np.testing.assert_allclose(s.joints2d[30:], before[30:])
    with pytest.raises(ValueError, match="limb pair"):
        s.set_sides(3, "feet", True)
