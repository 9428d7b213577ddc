"""Eq. 3.1-3.3 similarity on hand-computed examples."""

import numpy as np
import pytest

from vidcap.video.fit.similarity import similarity, similarity_from_counts


def test_hand_computed_5x5():
    sil = np.zeros((5, 5), bool)
    sil[1:4, 1:4] = True  # 9 pixels
    model = np.zeros((5, 5), bool)
    model[2:5, 2:4] = True  # 6 pixels, 4 of them inside the silhouette
    # union = 9 + 6 - 4 = 11; p = (9 - 4) / 11 = 5/11; n = (6 - 4) / 11 = 2/11
    expected = np.exp(-5 / 11 - 2 / 11) * (1 - 5 / 11)
    assert similarity(sil, model) == pytest.approx(expected, rel=1e-12)
    assert float(similarity(sil, model)) == pytest.approx(0.2887, abs=1e-4)


def test_batch_shapes_and_extremes():
    sil = np.zeros((5, 5), bool)
    sil[1:4, 1:4] = True
    batch = np.stack([sil, np.zeros_like(sil), ~sil])
    s = similarity(sil, batch)
    assert s.shape == (3,)
    assert s[0] == 1.0  # perfect cover
    assert s[1] == 0.0  # p = 1: nothing covered
    # the complement: union 25, p = 9/25, n = 16/25
    assert s[2] == pytest.approx(np.exp(-1.0) * (1 - 9 / 25))
    # missing silhouette costs more than the same amount of overreach (the 1 - p factor)
    assert similarity_from_counts(10, 8, 8) < similarity_from_counts(8, 10, 8)


def test_shape_mismatch_raises():
    with pytest.raises(ValueError):
        similarity(np.zeros((5, 5), bool), np.zeros((2, 4, 5), bool))


def test_scalar_counts_equal_the_array_path_bit_for_bit():
    """The fitter scores one model at a time with Python ints: the same S as numpy's."""
    rng = np.random.default_rng(4)
    a = rng.integers(0, 5000, 2000)
    m = rng.integers(0, 5000, 2000)
    i = (rng.random(2000) * np.minimum(a, m)).astype(np.int64)
    vector = similarity_from_counts(a, m, i)
    scalar = [similarity_from_counts(int(x), int(y), int(z))
              for x, y, z in zip(a, m, i, strict=True)]
    assert all(type(s) is float for s in scalar)
    np.testing.assert_array_equal(np.array(scalar), vector)
    assert similarity_from_counts(0, 0, 0) == 1.0
