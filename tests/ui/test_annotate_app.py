"""The annotate page's server side without a browser: triggers, state and the saved file."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("trame")
pytest.importorskip("trame_pyvista")

from vidcap.ui.annotate import AnnotateApp  # noqa: E402
from vidcap.ui.session import AnnotateSession  # noqa: E402

from vidcap.body import JOINT_NAMES  # noqa: E402


@pytest.fixture
def app(walk_clip, tmp_path, monkeypatch):
    import pyvista as pv

    monkeypatch.setattr(pv, "OFF_SCREEN", True)
    a = AnnotateApp(AnnotateSession(walk_clip, tmp_path / "a.json"))
    yield a
    a.plotter.close()


def _call(app, name, *args):
    app.ctrl.trigger_fn(name)(*args)


def test_page_state_for_a_frame(app):
    st = app.state
    assert st.frame_src.startswith("data:image/jpeg;base64,")
    assert st.review_side_src.startswith("data:image/jpeg;base64,")
    assert len(st.segments) == 10 and len(st.joints_display) == 15
    assert st.n_inputs == 0 and st.load_error == ""
    # the picture is shown 640 px wide: joints are scaled by the same factor
    np.testing.assert_allclose(np.array(st.joints_display) / app.display_scale,
                               app.session.joints2d[0], atol=0.06)


def test_wide_videos_are_shown_shrunk_and_clicks_map_back(walk_clip, tmp_path, monkeypatch):
    """A 4K-wide clip is shown 1280 px wide (not 3840): the joints on the page and a
    click on one of them are in the shrunk picture's pixels, edits in the video's."""
    import dataclasses

    import pyvista as pv


    monkeypatch.setattr(pv, "OFF_SCREEN", True)
    w0, h0 = walk_clip.size
    k = 8  # 480 x 360 -> 3840 x 2880
    big = dataclasses.replace(
        walk_clip, joints2d=walk_clip.joints2d * k, size=(w0 * k, h0 * k),
        read_frame=lambda i: np.repeat(np.repeat(walk_clip.read_frame(i), k, 0), k, 1),
        masks=None)
    # frames may also come already shrunk (load_clip keeps them at the page's size)
    small = dataclasses.replace(big, read_frame=lambda i: np.repeat(np.repeat(
        walk_clip.read_frame(i), 2, 0), 2, 1))
    for clip in (big, small):
        _check_wide(clip, w0 * k, tmp_path)


def _check_wide(big, width, tmp_path):
    import base64

    import cv2
    from vidcap.ui.session import MAX_DISPLAY_WIDTH

    app = AnnotateApp(AnnotateSession(big, tmp_path / "a.json"))
    try:
        assert app.display_scale == MAX_DISPLAY_WIDTH / width
        jpeg = base64.b64decode(app.state.frame_src.split(",", 1)[1])
        shown = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
        assert shown.shape[1] == MAX_DISPLAY_WIDTH
        np.testing.assert_allclose(np.array(app.state.joints_display) / app.display_scale,
                                   big.joints2d[0], atol=0.5)
        x, y = app.state.joints_display[JOINT_NAMES.index("l_ankle")]
        _call(app, "drag_start", x, y)
        assert app.state.drag_joint == "l_ankle"
    finally:
        app.plotter.close()


def test_triggers_edit_and_save(app, tmp_path):
    st = app.state
    _call(app, "goto", 4)
    assert st.frame == 4
    _call(app, "set_orientation", "front_right")
    assert st.orientation == "front_right" and st.orientation_user and st.n_inputs == 1
    _call(app, "step", 1)
    assert st.frame == 5
    _call(app, "set_depth", "r_lower_leg", -1)
    seg = next(x for x in st.segments if x["name"] == "r_lower_leg")
    assert seg["sign"] == -1 and seg["user"]
    # a click on a joint without moving it is not an edit; a drag is
    x, y = st.joints_display[JOINT_NAMES.index("l_ankle")]
    _call(app, "drag_start", x, y)
    assert st.drag_joint == "l_ankle"
    _call(app, "drag_end", x + 0.5, y)
    assert st.n_inputs == 2 and st.drag_joint == ""
    _call(app, "drag_start", x + 1, y - 1)
    _call(app, "drag_end", x + 21, y - 1)
    assert st.n_inputs == 3 and "l_ankle" in st.user_joints
    _call(app, "drag_start", 1.0, 1.0)  # far from every joint: nothing is picked
    _call(app, "drag_end", 50.0, 50.0)
    assert st.n_inputs == 3
    _call(app, "clear_joint", "l_ankle")
    assert st.n_inputs == 2 and "l_ankle" not in st.user_joints
    events = json.loads((tmp_path / "a.json").read_text())["events"]
    assert [(e["frame"], e["type"]) for e in events] == [(4, "orientation"), (5, "depth")]
    _call(app, "set_depth", "tail", 1)  # refused, reported, nothing written
    assert "refused" in st.message and st.n_inputs == 2
    # the legs' left and right exchanged from this frame on, and back
    legs = [JOINT_NAMES.index(f"{s}_{j}") for s in "lr" for j in ("hip", "knee", "ankle")]
    shown = np.array(st.joints_display)
    _call(app, "flip_sides", "legs")
    assert st.sides_swapped == ["legs"] and st.n_inputs == 3
    np.testing.assert_allclose(np.array(st.joints_display)[legs], shown[legs[3:] + legs[:3]])
    _call(app, "flip_sides", "legs")
    assert st.sides_swapped == [] and st.n_inputs == 2  # flipped back: no event left
    np.testing.assert_allclose(np.array(st.joints_display), shown)


def test_keys_and_attention(app):
    st = app.state
    _call(app, "key", "next")
    _call(app, "key", "next")
    _call(app, "key", "prev")
    assert st.frame == 1
    _call(app, "key", "attention")
    first = app.session.flagged()
    assert st.frame in {it["frame"] for it in first} and st.message.startswith("frame ")
    _call(app, "goto", 10_000)
    assert st.frame == app.session.n_frames - 1


def test_frames_not_fitted_carry_a_filled_badge(tmp_path, monkeypatch):
    """A frame the pipeline did not fit (fit score 0: its pose is filled from the
    frames around) says so on the page, as the review video marks it FILLED."""
    import pyvista as pv

    from tests.ui.clips import truth_clip

    monkeypatch.setattr(pv, "OFF_SCREEN", True)
    clip = truth_clip("walk_side")
    clip.fit_score[[7, 8]] = 0.0
    a = AnnotateApp(AnnotateSession(clip, tmp_path / "a.json"))
    try:
        assert a.state.filled is False  # frame 0 was fitted
        a.state.frame = 7
        a._update_frame()
        assert a.state.filled is True
        a.state.frame = 9
        a._update_frame()
        assert a.state.filled is False
    finally:
        a.plotter.close()
