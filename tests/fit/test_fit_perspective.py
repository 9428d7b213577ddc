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
