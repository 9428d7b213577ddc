"""The camera's perspective read from the scene's verticals (vidcap.video.vanishing)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from vidcap.video.fit.perspective import warp_height
from vidcap.video.vanishing import (
    ScenePerspective,
    camera_notice,
    k_from_vanishing_point,
    line_segments,
    person_axes,
    scene_k,
    scene_k_for,
    scene_perspective,
    vanishing_families,
)

H, W = 480, 640
TOP, BOTTOM = 100, 400  # the person's head top and soles, rows


def _plate(vertical_vp, floor_vp=None, rng=None):
    """A light plate with dark lines toward ``vertical_vp`` (x, y) from the top half, and
    (a distractor) floor boards toward ``floor_vp`` in the bottom half, more of them."""
    rng = np.random.default_rng(0) if rng is None else rng
    img = np.full((H, W, 3), 200, np.uint8)
    for x in np.linspace(40, W - 40, 9):
        start = np.array([x, 20.0])
        d = np.subtract(vertical_vp, start)
        end = start + d / np.linalg.norm(d) * 200
        cv2.line(img, tuple(np.int32(start)), tuple(np.int32(end)), (60, 60, 60), 2)
    if floor_vp is not None:
        for x in np.linspace(-200, W + 200, 25):
            start = np.array([x, H - 1.0])
            d = np.subtract(floor_vp, start)
            end = start + d / np.linalg.norm(d) * 150
            cv2.line(img, tuple(np.int32(start)), tuple(np.int32(end)), (90, 90, 90), 2)
    noise = rng.normal(0, 3, img.shape)
    return np.clip(img + noise, 0, 255).astype(np.uint8)


def _person_masks(vertical_vp, xs=(150, 330, 480)):
    """A tapering body from (x, TOP) toward the vertical vanishing point down to row
    BOTTOM, one frame per x."""
    masks = []
    for x in xs:
        m = np.zeros((H, W), np.uint8)
        top = np.array([x, TOP], float)
        d = np.subtract(vertical_vp, top)
        bottom = top + d * (BOTTOM - TOP) / d[1]
        left, right = np.array([-18.0, 0.0]), np.array([18.0, 0.0])
        poly = np.array([top + left, top + right, bottom + right * 0.7, bottom + left * 0.7])
        cv2.fillConvexPoly(m, np.int32(np.round(poly)), 1)
        masks.append(m.astype(bool))
    return np.stack(masks)


def _true_k(vertical_vp):
    s = (vertical_vp[1] - TOP) / (BOTTOM - TOP)
    return 1.0 / (s - 1.0)


def test_k_from_vanishing_point_inverts_the_warp():
    # g(u) of perspective.py sends u -> inf to (1 + k) / k body heights below the head
    for k in (0.1, 0.35, 0.8, -0.2):
        s = float(warp_height(1e9, k))
        point = np.array([100.0, 50.0 + s * 300.0, 1.0])
        got = k_from_vanishing_point(point, np.array([[100.0, 50.0]]), np.array([[100.0, 350.0]]))
        assert got[0] == pytest.approx(k, rel=1e-6)
    # parallel verticals (a point at infinity): a level camera
    assert k_from_vanishing_point(np.array([0.0, 1.0, 0.0]), np.array([[0.0, 0.0]]),
                                  np.array([[0.0, 10.0]]))[0] == 0.0


def test_a_high_camera_is_found_past_a_floor_of_boards():
    vp = (330.0, 1500.0)  # verticals meet far below: a camera looking down
    plate = _plate(vp, floor_vp=(330.0, -300.0))
    families = vanishing_families(line_segments(plate), H)
    assert len(families) >= 2  # the boards and the verticals
    found = scene_perspective(plate, _person_masks(vp))
    assert found.k == pytest.approx(_true_k(vp), abs=0.03)
    assert found.vanishing_point[1] == pytest.approx(vp[1], rel=0.1)
    assert "k = 0.2" in found.reason


def test_parallel_verticals_give_no_perspective():
    vp = (330.0, 1e7)  # a level camera: the verticals stay parallel
    found = scene_perspective(_plate(vp), _person_masks(vp))
    assert found.k == 0.0 and "level camera" in found.reason


def test_no_lines_or_no_person_give_zero_with_a_reason():
    plain = np.full((H, W, 3), 128, np.uint8)
    masks = _person_masks((330.0, 1500.0))
    found = scene_perspective(plain, masks)
    assert found.k == 0.0 and "no family of vertical lines" in found.reason
    nobody = scene_perspective(_plate((330.0, 1500.0)), np.zeros((3, H, W), bool))
    assert nobody.k == 0.0 and "no standing person" in nobody.reason
    lines = []
    assert scene_k(plain, masks, lines.append) == 0.0 and lines[0].startswith("camera perspective")


def test_lines_the_person_does_not_stand_along_are_not_the_verticals():
    # only the boards (meeting above the person, away from the person's axis): no k
    vp = (330.0, 1500.0)
    img = _plate(vp, floor_vp=(330.0, -300.0))
    img[:240] = 200  # the verticals wiped out
    found = scene_perspective(img, _person_masks(vp, xs=(120, 520)))
    assert found.k == 0.0 and "no family of lines is the person's vertical" in found.reason


def test_person_axes_reads_the_tallest_frames():
    vp = (330.0, 1500.0)
    masks = _person_masks(vp)
    short = np.zeros((1, H, W), bool)
    short[0, 300:400, 100:140] = True  # a crouch: left out
    top, bottom = person_axes(np.concatenate([masks, short]))
    assert len(top) == 3
    assert np.allclose(top[:, 1], TOP, atol=1) and np.allclose(bottom[:, 1], BOTTOM, atol=1)


def test_a_high_camera_is_told_to_a_user_who_described_none():
    vp = (330.0, 1500.0)  # k 0.27: a camera looking down
    plate, masks = _plate(vp), _person_masks(vp)
    said = []
    assert scene_k_for(None, 0.0, plate, masks, said.append) == 0.0  # told, not applied
    assert len(said) == 1 and said[0].startswith("notice: the camera looks down on")
    assert "--camera auto" in said[0] and "k = 0.2" in said[0]
    said.clear()  # a camera the user described, or a level one: nothing to tell
    assert scene_k_for((2.5, 3.0), 0.31, plate, masks, said.append) == 0.31
    level = (330.0, 1e7)
    assert scene_k_for(None, 0.0, _plate(level), _person_masks(level), said.append) == 0.0
    assert said == []
    assert scene_k_for("auto", 0.0, plate, masks, said.append) == pytest.approx(_true_k(vp),
                                                                               abs=0.03)
    below = ScenePerspective(-0.2, None, 5, 2.0, "")
    assert "looks up at" in camera_notice(below) and "low" in camera_notice(below)
    assert camera_notice(ScenePerspective(0.07, None, 5, 2.0, "")) is None
