"""padded_box: a mask's bounding box widened and clipped to the frame."""

import numpy as np

from vidcap.video.maskbox import padded_box


def test_padded_box_widens_and_clips_to_the_frame():
    mask = np.zeros((20, 30), np.uint8)
    mask[5:8, 10:14] = 1
    assert padded_box(mask, 2) == (slice(3, 10), slice(8, 16))
    assert padded_box(mask, 1, 4) == (slice(4, 9), slice(6, 18))
    mask[0, 29] = 1  # a pixel in a corner: the box stops at the frame's edges
    assert padded_box(mask, 3) == (slice(0, 11), slice(7, 30))


def test_padded_box_of_an_empty_mask_is_none():
    assert padded_box(np.zeros((4, 5), np.uint8), 2) is None
