"""The exact quantile regression against HiGHS' linear programme (the fallback)."""

import numpy as np
import pytest

from vidcap.video.lift import _bspline_design, _quantile_lp
from vidcap.video.quantreg import quantile_fit


def _loss(b, y, beta, q):
    r = y - b @ beta
    return float(np.sum(np.where(r > 0, q * r, (q - 1.0) * r)))


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("q", [0.5, 0.9])
def test_quantile_fit_is_the_linear_programme_optimum(seed, q):
    rng = np.random.default_rng(seed)
    F = int(rng.integers(60, 600))
    n_pieces = max(1, (F - 1) // 91)
    inner = np.linspace(0.0, F - 1.0, n_pieces + 1)
    knots = np.r_[[inner[0]] * 2, inner, [inner[-1]] * 2]
    design = _bspline_design(np.arange(F, dtype=float), knots, 2).toarray()
    keep = rng.random(F) > 0.2
    t = np.arange(F) / F
    y = np.log(40.0 * (1.0 + 0.5 * np.sin(3.0 * t))) - np.abs(rng.normal(0.0, 0.1, F))
    b, y = design[keep], y[keep]
    beta = quantile_fit(b, y, q)
    assert beta is not None
    ref = _quantile_lp(b, y, q)  # HiGHS, the fallback
    assert _loss(b, y, beta, q) <= _loss(b, y, ref, q) + 1e-7
    np.testing.assert_allclose(design @ beta, design @ ref, atol=1e-6)
    # a vertex: m points fitted exactly, and the q-quantile's share of points above
    r = y - b @ beta
    assert np.sum(np.abs(r) < 1e-9) == b.shape[1]
    assert abs(np.mean(r > 0) - (1.0 - q)) <= b.shape[1] / len(y)


def test_quantile_fit_of_a_constant_is_the_sample_quantile():
    rng = np.random.default_rng(7)
    y = rng.normal(size=101)
    beta = quantile_fit(np.ones((101, 1)), y, 0.9)
    assert beta[0] == np.sort(y)[90]  # the 91st of 101: 10 above, 90 below


def test_quantile_fit_says_none_where_it_cannot_certify():
    y = np.r_[np.zeros(10), np.ones(10)]
    design = np.ones((20, 1))
    # at q = 0.5 every value in [0, 1] is optimal; the vertex has ties off the basis
    assert quantile_fit(design, y, 0.5) is None
    assert quantile_fit(np.zeros((5, 2)), np.ones(5), 0.5) is None  # rank 0
