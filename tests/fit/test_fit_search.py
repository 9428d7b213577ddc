"""The coarse-to-fine interval search (Algorithms 1 and 6)."""

import numpy as np
import pytest

from vidcap.video.fit.search import interval_search


@pytest.mark.parametrize("optimum", [47.3, 45.0, 100.0, 134.2])
def test_finds_optimum_of_unimodal_score_in_batches(optimum):
    calls = []

    def score(v):
        calls.append(len(v))
        return -np.abs(v - optimum) ** 1.5

    res = interval_search(score, 45.0, 135.0, divisions=8, min_step=1.0)
    # the final step is (90 / 8) * (2 / 8)^k < 1 degree
    assert abs(res.value - optimum) <= 0.5
    assert res.iterations == len(calls)  # one score call (one batch) per iteration
    assert all(n <= 9 for n in calls) and calls[0] == 9
    assert res.evaluations == sum(calls)


def test_stays_within_limits_and_warm_start():
    res = interval_search(lambda v: v, 240.0, 300.0, divisions=8, min_step=1.0)
    assert res.value == pytest.approx(300.0)
    warm = interval_search(lambda v: -(v - 262.0) ** 2, 240.0, 300.0, divisions=8, min_step=1.0,
                           start=265.0, interval=8.0)
    cold = interval_search(lambda v: -(v - 262.0) ** 2, 240.0, 300.0, divisions=8, min_step=1.0)
    assert abs(warm.value - 262.0) <= 0.5
    assert warm.evaluations < cold.evaluations


def test_foreshortening_search_prefers_full_length_on_ties():
    # a flat score (the limb hidden inside the torso): Algorithm 6 cannot tell
    res = interval_search(lambda v: np.ones_like(v), 0.05, 1.0, divisions=5, min_step=0.05,
                          prefer=1.0)
    assert res.value == pytest.approx(1.0)


def test_periodic_wraps_and_margin():
    two_pi = 2 * np.pi
    target = 0.05  # just past 0: candidates must wrap around 2 pi

    def score(v):
        d = np.angle(np.exp(1j * (v - target)))
        return np.exp(-d**2 / 0.1) + 0.5 * np.exp(-np.angle(np.exp(1j * (v - np.pi))) ** 2 / 0.1)

    res = interval_search(score, 0.0, two_pi, divisions=8, min_step=np.deg2rad(1),
                          start=6.0, interval=1.0, periodic=two_pi)
    assert abs(np.angle(np.exp(1j * (res.value - target)))) < np.deg2rad(1)
    assert 0 <= res.value < two_pi
    full = interval_search(score, 0.0, two_pi, divisions=8, min_step=np.deg2rad(1),
                           periodic=two_pi)
    # the second mode at pi scores ~0.5: the margin reports the gap to it
    assert full.margin == pytest.approx(0.5, abs=0.05)


def test_bad_interval():
    with pytest.raises(ValueError):
        interval_search(lambda v: v, 1.0, 1.0, min_step=0.1)


@pytest.mark.parametrize("periodic", [None, 2 * np.pi])
def test_compiled_bookkeeping_equals_numpy_fallback(periodic, monkeypatch):
    """interval_search gives the same values, scores and runner-up with the compiled
    helpers as with the numpy code (bit for bit), including wrapped warm starts."""
    from vidcap.video.fit import search

    assert search._kernels() is not None
    rng = np.random.default_rng(2)
    table = rng.normal(size=4096)

    def score(v):  # rough and with exact ties, as silhouette counts are
        return np.round(table[(np.abs(v) * 97).astype(int) % 4096], 1)

    lo, hi = (0.0, 2 * np.pi) if periodic else (1.0, 4.0)
    cases = [dict(), dict(start=6.1 if periodic else 3.9, interval=0.7),
             dict(start=0.2, interval=3.0, prefer=0.1), dict(prefer=2.0)]
    got = [search.interval_search(score, lo, hi, min_step=0.01, periodic=periodic, **c)
           for c in cases]
    monkeypatch.setattr(search, "_kernels", lambda: None)
    want = [search.interval_search(score, lo, hi, min_step=0.01, periodic=periodic, **c)
            for c in cases]
    assert got == want
    assert len({r.value for r in want}) > 1


@pytest.mark.parametrize("periodic", [None, 2 * np.pi])
def test_many_compiled_bookkeeping_equals_numpy_fallback(periodic, monkeypatch):
    """interval_search_many: compiled helpers and numpy code give the same arrays."""
    from vidcap.video.fit import search

    rng = np.random.default_rng(4)
    table = rng.normal(size=4096)

    def score(v):  # (N, B) -> (N, B), rough, with exact ties
        return np.round(table[(np.abs(v) * 97).astype(int) % 4096], 1) + np.arange(len(v))[:, None]

    lo = np.array([0.0, 1.0, 2.0, 0.5])
    hi = lo + (2 * np.pi if periodic else np.array([1.0, 3.0, 0.5, 2.0]))
    cases = [dict(), dict(start=lo + 0.3, interval=0.5),
             dict(start=hi - 0.1, interval=0.4, prefer=np.array([np.nan, 1.5, np.nan, 1.0]))]
    got = [search.interval_search_many(score, lo, hi, min_step=0.01, periodic=periodic, **c)
           for c in cases]
    monkeypatch.setattr(search, "_kernels", lambda: None)
    want = [search.interval_search_many(score, lo, hi, min_step=0.01, periodic=periodic, **c)
            for c in cases]
    for g, w in zip(got, want, strict=True):
        for a, b in zip(g[:3], w[:3], strict=True):
            np.testing.assert_array_equal(a, b)
        assert g[3] == w[3]
    assert not np.array_equal(want[0][0], want[1][0])
