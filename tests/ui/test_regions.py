"""Regions in the annotate session and page: drawn, saved, silhouettes and fit redone.

The clip's silhouettes are the sample walk's true ones; its ``resegment`` applies the
user's regions to them exactly as the silhouette stage does
(:class:`vidcap.video.userregions.UserRegions`), so the expected masks are known.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from clips import SAMPLES, truth_clip
from vidcap.ui.session import AnnotateSession

from vidcap.video.masks import MaskStack
from vidcap.video.userregions import UserRegions


@pytest.fixture(scope="module")
def fitted():
    """The walk's true masks and a stand-in for the 2D fit on them (true joints)."""
    t = np.load(SAMPLES / "walk_side_truth.npz")
    masks = t["masks"]
    rows = masks.any(axis=2)
    height = (len(rows[0]) - rows[:, ::-1].argmax(axis=1)) - rows.argmax(axis=1)
    n = len(masks)
    pose = {"joints2d": t["joints2d"].astype(float), "scores": np.ones((n, 10)),
            "similarity": np.full(n, 0.8), "spread": np.full(n, np.nan),
            "model_height": height.astype(float)}
    return masks, pose


def _fake_refit(masks, pose, changed, *, progress=None, **_):
    """The refit (tested in tests/test_userregions.py) as a marker: the joints of the
    frames whose silhouette changed move 1 px right."""
    out = {k: np.array(v, copy=True) for k, v in pose.items()}
    out["joints2d"][changed, :, 0] += 1.0
    if progress is not None:
        progress(int(changed.sum()), int(changed.sum()))
    return out


@pytest.fixture(autouse=True)
def quick_refit(monkeypatch):
    import vidcap.video.refit

    monkeypatch.setattr(vidcap.video.refit, "refit_changed", _fake_refit)


@pytest.fixture
def clip(fitted):
    masks, pose = fitted
    calls = []

    def resegment(regions, on_masks):
        calls.append(regions)
        r = UserRegions(regions, masks.shape[1:])
        out = MaskStack(masks.shape[1:])
        for k, m in enumerate(masks):
            keep = r.keep(k)
            out.append(m if keep is None else m & keep)
            on_masks(k, out[k:])
        return out

    base = truth_clip("walk_side")
    c = replace(base, joints2d=pose["joints2d"], masks=MaskStack.from_masks(masks),
                fit_score=pose["similarity"], image_sides=True, spread=pose["spread"],
                model_height=pose["model_height"], resegment=resegment,
                pose={k: v.copy() for k, v in pose.items()})
    c.calls = calls
    return c


def _head_box(masks, frame):
    """A box over the top 30 rows of the person (head and neck) in ``frame``."""
    ys, xs = np.nonzero(masks[frame][:np.nonzero(masks[frame])[0].min() + 30])
    return (int(xs.min()) - 2, int(ys.min()) - 2, int(xs.max()) + 3, int(ys.max()) + 1)


def test_scene_region_saved_silhouettes_and_fit_redone(clip, fitted, tmp_path):
    masks, pose = fitted
    path = tmp_path / "a.json"
    s = AnnotateSession(clip, path)
    s.set_orientation(0, "right")
    box = _head_box(masks, 20)
    s.add_scene_region(20, box=box)
    assert json.loads(path.read_text())["events"][1] == {
        "frame": 20, "type": "scene_region", "box": list(box)}
    assert s.regions_stale and [r["type"] for r in s.region_items()] == ["scene_region"]
    lift_before = s.joints3d.copy()
    seen = []
    out = s.resegment(progress=lambda *a: seen.append(a))
    assert not s.regions_stale
    x0, y0, x1, y1 = box
    now = np.asarray(s.clip.masks)
    assert not now[:, y0:y1, x0:x1].any()
    changed = (now != masks).any(axis=(1, 2))
    assert out["changed"] == changed.sum() and 0 < changed.sum() < 20 and changed[20]
    assert {a[0] for a in seen} == {"silhouettes", "fit"}
    # the changed frames were refitted, no other
    moved = (s.clip.joints2d != pose["joints2d"]).any(axis=(1, 2))
    assert (moved == changed).all()
    assert not np.allclose(s.joints3d, lift_before)  # re-lifted with the new 2D pose
    assert s.frame_info(0)["orientation"] == "right"  # the other events still hold
    # deleting the region brings the first silhouettes back
    s.remove_region(20, "scene_region", s.region_items()[0]["key"])
    assert len(json.loads(path.read_text())["events"]) == 1
    s.resegment()
    assert (np.asarray(s.clip.masks) == masks).all()


def test_person_box_limits_its_frame(clip, fitted, tmp_path):
    masks, _ = fitted
    s = AnnotateSession(clip, tmp_path / "a.json")
    ys, xs = np.nonzero(masks[8])
    box = (int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.min()) + 60)
    s.add_person_box(8, box)
    s.resegment()
    m = s.clip.masks[8]
    assert m.any() and not m[box[3]:].any()
    assert (np.asarray(s.clip.masks[9]) == masks[9]).all()  # other frames untouched
    assert json.loads((tmp_path / "a.json").read_text())["events"] == [
        {"frame": 8, "type": "person_box", "box": list(box)}]


def test_drawn_boxes_are_clipped_and_ordered_bad_ones_refused(clip, tmp_path):
    s = AnnotateSession(clip, tmp_path / "a.json")
    s.add_scene_region(0, box=(500.4, 20.2, 300.6, -5))  # dragged up-left, past the edge
    assert s.region_items()[0]["box"] == [300, 0, 480, 21]
    with pytest.raises(ValueError, match="too small"):
        s.add_person_box(0, (10, 10, 11, 40))
    with pytest.raises(ValueError, match="no person_box"):
        s.remove_region(3, "person_box")


def test_an_edit_during_a_recompute_drops_its_result(clip, tmp_path):
    s = AnnotateSession(clip, tmp_path / "a.json")
    s.add_scene_region(0, box=(0, 0, 50, 50))
    inner = clip.resegment

    def resegment(regions, on_masks):
        s.add_scene_region(0, box=(60, 0, 100, 50))  # the user draws another meanwhile
        return inner(regions, on_masks)

    clip.resegment = resegment
    assert s.resegment() is None and s.regions_stale
    clip.resegment = inner
    assert s.resegment() is not None and len(clip.calls[-1].region_events()) == 2


def test_bad_region_in_the_file_is_a_load_error(clip, tmp_path):
    path = tmp_path / "a.json"
    text = json.dumps({"version": 1, "events": [
        {"frame": 0, "type": "scene_region", "box": [0, 0, 481, 10]}]})
    path.write_text(text)
    s = AnnotateSession(clip, path)
    assert "480x360" in s.load_error and str(path) in s.load_error
    assert path.read_text() == text


def test_page_draws_a_region_and_shows_the_new_silhouette(clip, fitted, tmp_path,
                                                           monkeypatch):
    pytest.importorskip("trame")
    pytest.importorskip("trame_pyvista")
    import pyvista as pv
    from vidcap.ui.annotate import AnnotateApp

    monkeypatch.setattr(pv, "OFF_SCREEN", True)
    masks, _ = fitted
    app = AnnotateApp(AnnotateSession(clip, tmp_path / "a.json"))
    try:
        st, k = app.state, app.display_scale
        st.frame = 20
        app._update_frame()
        area0, picture0 = st.sil_area, st.frame_src
        assert area0 == masks[20].sum()
        x0, y0, x1, y1 = _head_box(masks, 20)
        st.draw_mode = "scene_region"
        app.ctrl.trigger_fn("drag_start")(x1 * k, y1 * k)  # dragged from any corner
        app.ctrl.trigger_fn("drag_end")(x0 * k, y0 * k)
        assert [r["box"] for r in st.regions] == [[x0, y0, x1, y1]]
        assert st.sil_area < area0 and st.frame_src != picture0
        assert "frame(s) changed" in st.reseg_status
        # an outline drawn in the "outline" mode is a polygon
        st.draw_mode = "scene_area"
        app.ctrl.trigger_fn("drag_start")(10, 10)
        app.ctrl.trigger_fn("lasso_end")([[10, 10], [60, 12], [61, 40], [30, 50], [10, 40]])
        assert "polygon" in st.regions[-1] and len(st.regions) == 2
        app.ctrl.trigger_fn("delete_region")(st.regions[0]["id"])
        assert len(st.regions) == 1 and st.sil_area == area0
        st.show_sil = False
        app._update_frame()
        assert st.frame_src != picture0  # (the outline is still drawn)
    finally:
        app.plotter.close()
