"""A camera's perspective on a standing body as one number k (vidcap.video.fit.perspective)."""

import numpy as np
import pytest

from vidcap.body import SEGMENT_INDEX, SEGMENTS
from vidcap.video.fit.perspective import perspective_factors, perspective_k, warp_height
from vidcap.video.fit.proportions import HUMAN


def _pinhole_rows(heights, camera_height, distance, pitch):
    """Image rows (focal 1, y down) of points at ``heights`` metres on a vertical line
    ``distance`` metres in front of a camera ``camera_height`` up, tilted down ``pitch``."""
    y = np.asarray(heights, float) - camera_height  # up from the lens
    depth = distance * np.cos(pitch) - y * np.sin(pitch)
    up = distance * np.sin(pitch) + y * np.cos(pitch)
    return -up / depth


@pytest.mark.parametrize("camera_height, distance, pitch_deg",
                         [(2.5, 3.0, 35.0), (3.2, 4.0, None), (0.4, 2.5, -10.0), (0.875, 3.0, 0.0)])
def test_k_maps_heights_as_a_pinhole_camera(camera_height, distance, pitch_deg):
    H = 1.75
    k = perspective_k(camera_height, distance, H, pitch_deg)
    pitch = (np.arctan2(camera_height - H / 2, distance) if pitch_deg is None
             else np.radians(pitch_deg))
    u = np.linspace(0.0, 1.0, 11)  # head top to soles
    rows = _pinhole_rows(H * (1 - u), camera_height, distance, pitch)
    seen = (rows - rows[0]) / (rows[-1] - rows[0])
    assert np.allclose(warp_height(u, k), seen, atol=1e-12)


def test_sign_of_k():
    assert perspective_k(2.5, 3.0) > 0.2  # above, looking down: the head is nearer
    assert perspective_k(0.3, 3.0) < -0.05  # low, looking up: the feet are nearer


def test_level_camera_at_mid_height_changes_nothing():
    assert perspective_k(0.875, 3.0, 1.75) == pytest.approx(0.0, abs=1e-12)
    assert perspective_factors(dict(HUMAN), 0.0) == dict(HUMAN)


def test_camera_that_cannot_see_the_subject_is_refused():
    with pytest.raises(ValueError):
        perspective_k(5.0, 1.0, 1.75, pitch_deg=-60.0)  # high up, looking at the sky
    with pytest.raises(ValueError):
        perspective_k(2.0, 0.0)


def test_warped_trunk_lands_where_the_camera_images_the_joints():
    """The warped body's joints, stacked head to soles, sit at the pinhole camera's rows."""
    k = perspective_k(2.5, 3.0, 1.75, pitch_deg=35.0)
    f = perspective_factors(dict(HUMAN), k)
    ratio = {g: SEGMENTS[SEGMENT_INDEX[s]].length_ratio
             for g, s in (("head", "head"), ("torso", "torso"), ("upper_legs", "l_upper_leg"),
                          ("lower_legs", "l_lower_leg"))}
    trunk = ("head", "torso", "upper_legs", "lower_legs")
    before = np.cumsum([HUMAN[g] * ratio[g] for g in trunk])
    after = np.cumsum([f[g] * ratio[g] for g in trunk])
    u = before / (before[-1] / HUMAN["above_feet"])  # shoulder, hips, knee, ankle
    v = after / (after[-1] / f["above_feet"])
    assert np.allclose(v, warp_height(u, k), atol=1e-12)
    assert f["head"] > HUMAN["head"] and f["lower_legs"] < HUMAN["lower_legs"]
    assert f["above_feet"] > HUMAN["above_feet"]  # the feet look shorter from above


def _pinhole_joints(k_geometry, heights, stature=1.75, px_per_unit=400.0):
    """(1, J, 2) image joints (rows down) of points at ``heights`` metres on a vertical
    line imaged by the pinhole camera ``k_geometry`` = (camera height, distance, pitch°)."""
    h, d, pitch = k_geometry
    rows = _pinhole_rows(heights, h, d, np.radians(pitch)) * px_per_unit
    joints = np.zeros((1, 15, 2))
    joints[0, :, 0] = 100.0
    joints[0, :, 1] = rows
    return joints


@pytest.mark.parametrize("geometry", [(2.5, 3.0, 35.0), (1.9, 3.1, 22.5), (0.4, 2.5, -10.0)])
def test_unwarp_gives_the_rows_of_a_camera_without_perspective(geometry):
    """A pinhole camera's rows of a standing body (head top at 0, then joints down to
    the ankles), un-warped with the camera's k: each joint's row from the head top is
    proportional to its depth below the head top, as scaled orthography draws it."""
    from vidcap.body import JOINT_INDEX
    from vidcap.video.fit.perspective import unwarp_joints

    H, above_feet = 1.75, 0.96
    k = perspective_k(*geometry[:2], H, geometry[2])
    heights = np.linspace(H, H * (1 - above_feet), 15)  # head top first, ankles last
    order = np.argsort([JOINT_INDEX["head_top"]] + [i for i in range(15)
                                                    if i != JOINT_INDEX["head_top"]])
    heights = heights[order]  # head_top gets the body's top, the others below it
    joints = _pinhole_joints(geometry, heights)
    top = joints[0, JOINT_INDEX["head_top"], 1]
    model_height = np.array([joints[0, :, 1].max() - top])  # head top to ankles
    flat, flat_height = unwarp_joints(joints, model_height, k, above_feet)
    depth_below_top = (H - heights) / (H * above_feet)
    rows = (flat[0, :, 1] - top) / flat_height[0]
    assert np.allclose(rows, depth_below_top, atol=1e-9)
    assert np.array_equal(flat[..., 0], joints[..., 0])  # columns kept


def test_warp_undoes_unwarp_and_k0_changes_nothing():
    from vidcap.video.fit.perspective import unwarp_joints, warp_joints

    rng = np.random.default_rng(3)
    joints = rng.uniform(0, 300, (5, 15, 2))
    height = rng.uniform(150, 250, 5)
    for k in (0.35, -0.1):
        flat, h = unwarp_joints(joints, height, k, 0.95)
        back, h_back = warp_joints(flat, h, k, 0.95)
        np.testing.assert_allclose(back, joints, rtol=0, atol=1e-9)
        np.testing.assert_allclose(h_back, height, rtol=1e-12)
    same, h0 = unwarp_joints(joints, height, 0.0, 0.95)
    np.testing.assert_array_equal(same, joints)
    np.testing.assert_array_equal(h0, height)
