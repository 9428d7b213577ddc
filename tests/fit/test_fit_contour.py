"""Contour analysis: scan lines, line fits, elbow corner (Alg. 3-4), knee crossing (Alg. 5)."""

import numpy as np
import pytest

from vidcap.video.fit.contour import (
    arm_angles,
    elbow_corner,
    fit_angle,
    knees_crossed,
    leg_curves,
    limb_curve,
    row_runs,
)
from vidcap.video.fit.raster import draw_segments


def test_row_runs():
    m = np.array([[0, 1, 1, 0, 1], [0, 0, 0, 0, 0], [1, 1, 1, 1, 1]], bool)
    rows, starts, ends = row_runs(m)
    assert rows.tolist() == [0, 0, 2]
    assert starts.tolist() == [1, 4, 0]
    assert ends.tolist() == [2, 4, 4]


@pytest.mark.parametrize(
    "pattern, crossed",
    [
        ([1, 1, 0, 0, 0], True),  # one line, then two to the end: Figure 3.7
        ([0, 0, 0, 0], False),  # two lines from the start
        ([1, 1, 1, 1], False),  # never separates
        ([1, 0, 0, 1, 0], False),  # merges again after separating
        ([], False),
    ],
)
def test_knees_crossed(pattern, crossed):
    assert knees_crossed(np.array(pattern, bool)) is crossed


def test_fit_angle_orientation():
    t = np.linspace(0, 10, 11)
    a = np.deg2rad(240.0)  # down-left in the image (y up convention)
    pts = np.stack([np.cos(a) * t, -np.sin(a) * t], 1)
    assert fit_angle(pts) == pytest.approx(a)
    assert fit_angle(pts[::-1]) == pytest.approx(a - np.pi)


def _polyline(start, angles_deg, lengths, step=1.0):
    pts = [np.asarray(start, float)]
    for a, n in zip(np.deg2rad(angles_deg), lengths, strict=True):
        d = np.array([np.cos(a), -np.sin(a)]) * step
        for _ in range(int(n / step)):
            pts.append(pts[-1] + d)
    return np.array(pts)


def test_elbow_corner_on_polyline():
    pts = _polyline((0, 0), [200, 260], [20, 25])
    k = elbow_corner(pts)
    assert abs(k - 20) <= 1
    lower, upper, corner = arm_angles(pts)
    assert np.rad2deg(upper) == pytest.approx(200, abs=1.5)
    assert np.rad2deg(lower) == pytest.approx(260, abs=1.5)
    straight = _polyline((0, 0), [250], [40])
    assert elbow_corner(straight) == -1
    lo, up, c = arm_angles(straight)
    assert c == -1 and lo == up == pytest.approx(np.deg2rad(250))
    assert elbow_corner(pts[:6]) == -1  # too short for a corner 4 points from both ends


def test_bent_arm_silhouette_split_at_elbow_within_2px():
    shoulder = np.array([60.0, 30.0])
    a_up, a_lo = np.deg2rad(205.0), np.deg2rad(265.0)
    elbow = shoulder + 40 * np.array([np.cos(a_up), -np.sin(a_up)])
    wrist = elbow + 45 * np.array([np.cos(a_lo), -np.sin(a_lo)])
    m = draw_segments(np.array([[shoulder, elbow]]), np.array([[elbow, wrist]]),
                      np.array([3.0, 3.0]), (100, 100), caps=False)[0]
    ys, xs = np.nonzero(m)
    curve = limb_curve(np.stack([xs, ys], 1), shoulder)
    lower, upper, corner = arm_angles(curve)
    assert corner >= 0
    assert np.hypot(*(curve[corner] - elbow)) <= 2.0
    assert abs(np.rad2deg(upper - a_up)) < 3 and abs(np.rad2deg(lower - a_lo)) < 3


def test_leg_curves_merge_flags():
    m = np.zeros((20, 30), bool)
    m[0:5, 10:16] = True  # one merged run at the top
    m[5:20, 5:10] = True  # then two legs
    m[5:20, 18:23] = True
    left, right, merged = leg_curves(m, 0, 19, radius=2.5)
    assert merged.tolist() == [True] * 5 + [False] * 15
    assert left[-1, 0] == pytest.approx(7.0) and right[-1, 0] == pytest.approx(20.0)
    assert knees_crossed(merged)
