"""The plate's exposure gain by table lookup equals cv2.multiply, bit for bit."""

import cv2
import numpy as np
import pytest

from vidcap.video.gaintable import apply_gain, gain_table


@pytest.mark.parametrize("seed", range(5))
def test_lookup_equals_multiply(seed):
    rng = np.random.default_rng(seed)
    image = rng.integers(0, 256, (120, 160, 3), dtype=np.uint8)
    crop = image[7:101, 13:150]  # a strided view, as the edge band's box is
    for _ in range(40):
        gain = rng.uniform(0.3, 2.5, 3)
        want = cv2.multiply(crop, (*(float(v) for v in gain), 0.0))
        got = apply_gain(crop, gain)
        assert got.dtype == np.uint8 and got.shape == crop.shape
        assert np.array_equal(got, want)


def test_table_saturates_and_rounds():
    table = gain_table((2.0, 0.5, 1.0))
    assert table.shape == (256, 1, 3)
    assert table[200, 0, 0] == 255  # 400 saturates
    assert table[3, 0, 1] == 2  # 1.5 rounds to even, as OpenCV does
    assert table[5, 0, 1] == 2  # 2.5 too
    assert np.array_equal(table[:, 0, 2], np.arange(256))
