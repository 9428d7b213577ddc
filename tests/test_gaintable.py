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


def test_gained_plate_crops_equal_the_lookup_of_each_crop():
    """Crops inside the last one computed are cut from it; others computed anew; the
    bytes always those of apply_gain on the crop (and the plate itself without a gain)."""
    from vidcap.video.gaintable import GainedPlate

    rng = np.random.default_rng(4)
    plate = rng.integers(0, 256, (60, 50, 3), dtype=np.uint8)
    g = (1.07, 0.93, 1.21)
    gp = GainedPlate(plate, g)
    for box in [(5, 50, 3, 40), (10, 30, 3, 20), (5, 50, 3, 40), (0, 60, 0, 50),
                (40, 60, 30, 50), (2, 9, 45, 50)]:
        y0, y1, x0, x1 = box
        assert np.array_equal(gp.crop(*box), apply_gain(plate[y0:y1, x0:x1], g)), box
    plain = GainedPlate(plate, None)
    assert np.shares_memory(plain.crop(3, 9, 4, 8), plate)
    assert np.array_equal(plain.crop(3, 9, 4, 8), plate[3:9, 4:8])
