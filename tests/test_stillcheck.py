"""vidcap.video.stillcheck: the warning for silhouettes nearly empty because nothing moved."""

from __future__ import annotations

import numpy as np

from tests.test_pipeline import _result_with
from vidcap.video.stillcheck import still_warning


def _boxes(rng, n, x, y, w, h, jitter):
    d = rng.integers(-jitter, jitter + 1, size=(n, 2))
    return np.column_stack([x + d[:, 0], y + d[:, 1], x + w + d[:, 0], y + h + d[:, 1]])


def test_a_small_blob_that_stays_in_one_spot_is_warned_of():
    rng = np.random.default_rng(0)
    speck = _boxes(rng, 60, 300, 200, 20, 24, 2)  # 5 % of 480 high, one spot
    msg = still_warning(speck, (480, 640))
    assert msg is not None and msg.startswith("warning:") and "--background" in msg
    assert "\n" not in msg
    assert "median 5 %" in msg


def test_a_person_who_fills_the_height_or_walks_is_not():
    rng = np.random.default_rng(1)
    standing = _boxes(rng, 60, 280, 60, 80, 360, 3)  # 75 % of the height, in place
    assert still_warning(standing, (480, 640)) is None
    # small (far away) but walking across: the boxes cover a band of the frame
    walk = np.column_stack([np.arange(0, 600, 10), np.full(60, 300),
                            np.arange(0, 600, 10) + 15, np.full(60, 340)])
    assert still_warning(walk, (480, 640)) is None
    # no person at all (-1 boxes): told by the frames-without-a-person notice instead
    assert still_warning(np.full((10, 4), -1), (480, 640)) is None


def test_the_union_of_the_boxes_counts_overlaps_once():
    # two overlapping 10x10 boxes on a 100x100 frame: 10*10 + 10*10 - 5*5 pixels
    b = np.array([[0, 0, 10, 10], [5, 5, 15, 15]] * 3)
    # heights 10 % and cover 1.75 %: warned, and the cover is printed as measured
    assert "1.8 % of the frame" in still_warning(b, (100, 100))


def test_convert_puts_the_warning_first_and_only_with_an_estimated_plate():
    res = _result_with(["right"] * 20)
    res.masks = np.zeros((20, 480, 640), bool)
    res.bbox = np.tile([300, 200, 320, 224], (20, 1))
    notes = res.notices()
    assert notes[0].startswith("warning: the silhouettes are nearly empty")
    assert sum("--background plate.png" in m for m in notes) == 1
    res.plate_estimated = False
    assert not any("nearly empty" in m for m in res.notices())
