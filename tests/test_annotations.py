"""Annotation files: round trip, carrying forward, strict validation, safe saving."""

import json

import numpy as np
import pytest

from vidcap.body import SEGMENT_INDEX
from vidcap.errors import AnnotationError
from vidcap.video.annotations import Annotations, default_path


def _sample():
    a = Annotations()
    a.add_orientation(0, "right")
    a.add_orientation(30, "back_right")
    a.add_depth(5, "l_lower_arm", "toward")
    a.add_depth(12, "l_lower_arm", -1)
    a.add_depth(20, "l_lower_arm", "auto")
    a.add_depth(3, "torso", +1)
    a.add_joint(7, "l_wrist", 12.5, 40.0)
    a.add_sides(0, "legs", True)
    a.add_sides(25, "legs", False)
    return a


def test_round_trip(tmp_path):
    a = _sample()
    p = tmp_path / "clip.vidcap.json"
    a.save(p)
    b = Annotations.load(p, n_frames=50)
    assert a == b and b.n_user_inputs == 9
    assert json.loads(p.read_text())["version"] == 1


def test_resolve_carries_forward():
    signs, orient, joints = _sample().resolve(40)
    k = SEGMENT_INDEX["l_lower_arm"]
    assert signs[:5, k].tolist() == [0] * 5
    assert set(signs[5:12, k]) == {1} and set(signs[12:20, k]) == {-1}
    assert set(signs[20:, k]) == {0}
    assert set(signs[3:, SEGMENT_INDEX["torso"]]) == {1}
    assert orient[0] == "right" and orient[29] == "right" and orient[30] == "back_right"
    assert np.isfinite(joints).sum() == 2 and tuple(joints[7, 5]) == (12.5, 40.0)
    sides = _sample().sides(40)  # (F, 2): arms, legs
    assert sides.shape == (40, 2) and not sides[:, 0].any()
    assert sides[:25, 1].all() and not sides[25:, 1].any()


def test_depth_event_ends_where_the_segment_next_enters_the_image_plane():
    a = Annotations()
    a.add_depth(2, "head", "away")
    near = np.zeros((12, 10), bool)
    near[6:8, SEGMENT_INDEX["head"]] = True
    signs, _, _ = a.resolve(12, near_plane=near)
    assert signs[:, SEGMENT_INDEX["head"]].tolist() == [0, 0, -1, -1, -1, -1] + [0] * 6


@pytest.mark.parametrize(
    "doc, message",
    [
        ("[1, 2]", "top level must be an object"),
        ('{"version": 2, "events": []}', "'version' must be 1"),
        ('{"version": 1}', "'events' must be a list"),
        ('{"version": 1, "events": [{"frame": 0, "type": "depth", "segment": "l_foot",'
         ' "value": "toward"}]}', "events[0]: unknown segment 'l_foot'"),
        ('{"version": 1, "events": [{"frame": 99, "type": "orientation", "value": "left"}]}',
         "events[0]: frame 99 is out of range"),
        ('{"version": 1, "events": [{"frame": -1, "type": "orientation", "value": "left"}]}',
         "'frame' must be a non-negative integer"),
        ('{"version": 1, "events": [{"frame": 1, "type": "orientation", "value": "up"}]}',
         "orientation 'up' is not one of"),
        ('{"version": 1, "events": [{"frame": 1, "type": "depth", "segment": "head",'
         ' "value": 1}]}', "depth value 1 is not toward, away or auto"),
        ('{"version": 1, "events": [{"frame": 1, "type": "joint", "joint": "nose",'
         ' "u": 1, "v": 2}]}', "unknown joint 'nose'"),
        ('{"version": 1, "events": [{"frame": 1, "type": "joint", "joint": "neck",'
         ' "u": "a", "v": 2}]}', "'u' and 'v' must be finite numbers"),
        ('{"version": 1, "events": [{"frame": 1, "type": "sides", "pair": "hands",'
         ' "value": "swapped"}]}', "unknown limb pair 'hands'"),
        ('{"version": 1, "events": [{"frame": 1, "type": "sides", "pair": "legs",'
         ' "value": true}]}', "sides value True is not swapped or as_fitted"),
        ('{"version": 1, "events": [{"frame": 1, "type": "spin"}]}', "'type' must be one of"),
        ('{"version": 1, "events": [{"frame": 1, "type": "orientation"}]}', "lacks ['value']"),
        ('{"version": 1, "events": [{"frame": 1, "type": "orientation", "value": "left",'
         ' "x": 1}]}', "unknown key(s) ['x']"),
        ('{"version": 1, "events": [{"frame": 1, "type": "orientation", "value": "left"},'
         ' {"frame": 1, "type": "orientation", "value": "right"}]}', "events[1]: a second"),
        ('{"version": 1, "events": [', "not valid JSON (line 1"),
        ('{"version": 1, "events": [{"frame": 0, "type": "scene_region"}]}',
         "events[0]: scene_region: needs one of 'box'"),
        ('{"version": 1, "events": [{"frame": 0, "type": "scene_region", "box": [0, 0, 5, 5],'
         ' "polygon": [[0, 0], [1, 0], [0, 1]]}]}', "needs one of 'box'"),
        ('{"version": 1, "events": [{"frame": 0, "type": "scene_region", "box": [0, 0, 5]}]}',
         "'box' must be four integers [x0, y0, x1, y1]"),
        ('{"version": 1, "events": [{"frame": 0, "type": "person_box", "box": [0, 0, 5.5,'
         ' 9]}]}', "events[0]: person_box: 'box' must be four integers"),
        ('{"version": 1, "events": [{"frame": 0, "type": "person_box", "box": [9, 0, 5, 9]}]}',
         "box [9, 0, 5, 9] is empty: it needs x0 < x1 and y0 < y1"),
        ('{"version": 1, "events": [{"frame": 0, "type": "person_box", "box": [-1, 0, 5, 9]}]}',
         "must lie within 0.."),
        ('{"version": 1, "events": [{"frame": 0, "type": "person_box"}]}', "lacks ['box']"),
        ('{"version": 1, "events": [{"frame": 0, "type": "scene_region", "polygon":'
         ' [[0, 0], [1, 0]]}]}', "'polygon' must be 3 to"),
        ('{"version": 1, "events": [{"frame": 0, "type": "scene_region", "polygon":'
         ' [[0, 0], [1, 0], [1, "a"]]}]}', "'polygon' points must be pixels"),
        ('{"version": 1, "events": [{"frame": 0, "type": "person_box", "box": [0, 0, 5, 9],'
         ' "polygon": 1}]}', "unknown key(s) ['polygon']"),
        ('{"version": 1, "events": [{"frame": 3, "type": "person_box", "box": [0, 0, 5, 9]},'
         ' {"frame": 3, "type": "person_box", "box": [1, 0, 5, 9]}]}', "events[1]: a second"),
    ],
)
def test_malformed_files_give_one_line_errors(tmp_path, doc, message):
    p = tmp_path / "bad.json"
    p.write_text(doc)
    with pytest.raises(AnnotationError) as info:
        Annotations.load(p, n_frames=50)
    text = str(info.value)
    assert message in text and str(p) in text and "\n" not in text


def test_regions_round_trip_apart_from_the_other_events_and_fit_the_frame(tmp_path):
    a = _sample()
    key = a.add_scene_region(4, box=(400, 0, 480, 120))
    a.add_scene_region(9, polygon=[(10, 300), (60.5, 290), (40, 350)])
    a.add_person_box(25, (120, 40, 260, 355))
    p = tmp_path / "r.json"
    a.save(p)
    b = Annotations.load(p, n_frames=50, frame_size=(480, 360))
    assert a == b and b.n_user_inputs == 12
    assert [e.type for e in b.region_events()] == ["scene_region", "scene_region",
                                                   "person_box"]
    signs, orient, joints = b.resolve(40)  # regions change none of the 3D stage's inputs
    ref = _sample().resolve(40)
    assert (signs == ref[0]).all() and (orient == ref[1]).all()
    assert np.array_equal(joints, ref[2], equal_nan=True)
    with pytest.raises(AnnotationError) as info:
        Annotations.load(p, frame_size=(479, 360))
    text = str(info.value)
    assert str(p) in text and "scene_region at frame 4" in text and "479x360" in text
    assert "\n" not in text
    assert b.remove(4, "scene_region", key) and len(b.region_events()) == 2


def test_missing_file(tmp_path):
    with pytest.raises(AnnotationError, match="no such annotations file"):
        Annotations.load(tmp_path / "none.json")


def test_failed_save_keeps_the_users_file(tmp_path, monkeypatch):
    p = tmp_path / "a.json"
    _sample().save(p)
    before = p.read_text()
    a = _sample()
    a.add_depth(1, "head", "away")
    import vidcap.video.annotations as mod

    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(mod.json, "dumps", boom)
    with pytest.raises(OSError):
        a.save(p)
    assert p.read_text() == before
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.json"]


def test_api_rejects_bad_values():
    a = Annotations()
    with pytest.raises(ValueError):
        a.add_depth(0, "l_foot", 1)
    with pytest.raises(ValueError):
        a.add_depth(0, "head", 2)
    with pytest.raises(ValueError):
        a.add_orientation(-1, "left")
    with pytest.raises(ValueError):
        a.add_joint(0, "neck", np.nan, 1)
    with pytest.raises(ValueError, match="limb pair"):
        a.add_sides(0, "feet", True)
    with pytest.raises(ValueError, match="True or False"):
        a.add_sides(0, "legs", "yes")
    with pytest.raises(ValueError, match="a box or a polygon"):
        a.add_scene_region(0)
    with pytest.raises(ValueError, match="empty"):
        a.add_person_box(0, (5, 5, 5, 9))
    a.add_depth(4, "head", 1)
    a.add_depth(4, "head", -1)  # replaces
    assert a.n_user_inputs == 1 and a.remove(4, "depth", "head") and len(a) == 0


def test_default_path():
    assert default_path("/x/walk.mp4").name == "walk.vidcap.json"


def test_plane_passages_end_a_depth_event_that_never_leaves_the_near_plane_zone():
    from vidcap.video.pipeline import plane_passages

    F, k = 20, SEGMENT_INDEX["l_lower_leg"]
    zeta = np.full((F, 10), 0.5)
    zeta[:, k] = 0.1 * np.abs(np.cos(np.linspace(0.0, np.pi, F)))  # crosses the plane once
    passes = plane_passages(zeta)
    starts = np.flatnonzero(np.diff(np.r_[0, passes[:, k].astype(int)]) == 1)
    assert len(starts) == 1 and 8 <= starts[0] <= 11  # one passage (a run of equal minima)
    assert not passes[:, SEGMENT_INDEX["head"]].any()  # never below the near-plane bound
    a = Annotations()
    a.add_depth(1, "l_lower_leg", "toward")
    signs, _, _ = a.resolve(F, near_plane=passes)
    held = np.flatnonzero(signs[:, k])
    assert held[0] == 1 and held[-1] == np.flatnonzero(passes[:, k])[0] - 1
    # the old rule (zone entry) holds the event across the sign change
    signs_old, _, _ = a.resolve(F, near_plane=zeta < 0.15)
    assert (signs_old[1:, k] == 1).all()
