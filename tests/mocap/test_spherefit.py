"""Tests for vidcap.mocap.spherefit: exact recovery, degenerate motion, NaN handling,
incremental and multi-marker fits, the noise correction, and equivariance properties."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vidcap.errors import FitError, VidcapError
from vidcap.mocap import _sphere_moments
from vidcap.mocap import spherefit as sf
from vidcap.mocap.spherefit import (
    IncrementalGDK,
    SphereFit,
    crlb,
    estimate_noise_trace,
    gdke,
    lls,
    mgdk,
    mle,
    ugdk,
)


def unit(rng, n, d):
    u = rng.normal(size=(n, d))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def cap(rng, n, half_angle, radius=1.0, center=(0.0, 0.0, 0.0)):
    """Points uniform on a spherical cap about +z of the given half-angle (radians)."""
    z = rng.uniform(np.cos(half_angle), 1.0, n)
    ph = rng.uniform(0, 2 * np.pi, n)
    s = np.sqrt(1 - z * z)
    return np.asarray(center) + radius * np.stack([s * np.cos(ph), s * np.sin(ph), z], axis=1)


def random_rotation(rng, d):
    q, r = np.linalg.qr(rng.normal(size=(d, d)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def circle_points(rng, n, d, center, radius, arc=2 * np.pi):
    """Noise-free points on a circle in a random 2-plane of R^d; returns points, plane basis."""
    basis = random_rotation(rng, d)[:, :2]
    t = rng.uniform(0, arc, n)
    pts = center + radius * (np.cos(t)[:, None] * basis[:, 0] + np.sin(t)[:, None] * basis[:, 1])
    return pts, basis


# ------------------------------------------------------------------ exact recovery
@pytest.mark.parametrize("d", [2, 3, 4])
def test_noise_free_spheres_recovered(d):
    rng = np.random.default_rng(d)
    center = rng.normal(size=d) * 3
    radius = 0.7
    pts = center + radius * unit(rng, 60, d)
    for fit in (gdke(pts), ugdk(pts, 0.0), lls(pts), mle(pts, x0=np.append(center + 0.1, 1.0))):
        assert fit.kind == "sphere"
        np.testing.assert_allclose(fit.center, center, rtol=0, atol=1e-9 * np.abs(center).max())
        assert fit.radius == pytest.approx(radius, rel=1e-9)
        assert fit.n == 60 and fit.dropped == 0


@pytest.mark.parametrize("d", [3, 4])
def test_noise_free_circles_recovered_with_normal(d):
    rng = np.random.default_rng(10 + d)
    center = rng.normal(size=d)
    pts, basis = circle_points(rng, 40, d, center, 2.5, arc=2.0)  # a 115° arc
    fit = gdke(pts)
    assert fit.kind == "circle"
    np.testing.assert_allclose(fit.center, center, atol=1e-9 * 2.5)
    assert fit.radius == pytest.approx(2.5, rel=1e-9)
    # the normal is a unit vector orthogonal to the plane of motion
    assert np.linalg.norm(fit.normal) == pytest.approx(1.0)
    np.testing.assert_allclose(basis.T @ fit.normal, 0.0, atol=1e-9)
    if d == 3:
        expected = np.cross(basis[:, 0], basis[:, 1])
        assert abs(fit.normal @ expected) == pytest.approx(1.0, abs=1e-12)


def test_noisy_hinge_is_circle_and_sphere_cap_is_sphere():
    rng = np.random.default_rng(3)
    pts, basis = circle_points(rng, 500, 3, np.zeros(3), 1.0, arc=np.pi)
    hinge = pts + rng.normal(scale=0.005, size=pts.shape)
    fit = gdke(hinge)
    assert fit.kind == "circle"
    assert abs(fit.normal @ np.cross(basis[:, 0], basis[:, 1])) > 0.999
    assert np.linalg.norm(fit.center) < 0.01
    # a 15° cap of a sphere is still a sphere at the default threshold
    assert gdke(cap(rng, 500, np.radians(15))).kind == "sphere"


def test_still_points():
    pts = np.tile([0.3, -1.0, 2.0], (25, 1))
    fit = gdke(pts)
    assert fit.kind == "still"
    assert np.isnan(fit.center).all() and np.isnan(fit.radius)
    # with an explicit tolerance, sub-millimetre jitter is still
    jitter = pts + np.random.default_rng(0).normal(scale=1e-4, size=pts.shape)
    assert gdke(jitter, still_tol=1e-3).kind == "still"
    assert gdke(jitter).kind != "still"


@pytest.mark.parametrize("n", [300, 5 * sf._CHUNK_ROWS])  # batched and one-pass chunked paths
def test_far_from_origin(n):
    rng = np.random.default_rng(7)
    radius = 0.25
    center = np.array([1e4, -0.7e4, 0.3e4]) * radius
    pts = cap(rng, n, np.radians(60), radius, center)
    fit = gdke(pts)
    assert np.linalg.norm(fit.center - center) <= 1e-6 * radius
    assert fit.radius == pytest.approx(radius, rel=1e-6)
    inc = IncrementalGDK(3)
    inc.add(pts)
    assert np.linalg.norm(inc.fit().center - center) <= 1e-6 * radius


def test_chunked_path_matches_batched_path():
    rng = np.random.default_rng(8)
    pts = cap(rng, 5 * sf._CHUNK_ROWS + 17, np.radians(70), 0.4, (0.1, 0.2, 0.3))
    pts += rng.normal(scale=0.01, size=pts.shape)
    a = gdke(pts)  # chunked
    b = gdke(pts[None])  # batched path with a leading axis of 1
    np.testing.assert_allclose(a.center, b.center[0], rtol=1e-10)
    assert a.radius == pytest.approx(b.radius[0], rel=1e-10)
    pts[[5, 9000, 30000]] = np.nan
    c = gdke(pts)
    assert c.dropped == 3 and c.n == len(pts) - 3
    d = gdke(pts[~np.isnan(pts).any(axis=1)])
    np.testing.assert_allclose(c.center, d.center, rtol=1e-12)


def test_compiled_kernels_match_numpy_paths(monkeypatch):
    """The numba D = 3 kernels (single one-pass and stacks) equal the pure-numpy paths."""
    assert sf._kernels() is not None  # numba is a dependency: the fast path must be live
    rng = np.random.default_rng(81)
    big = cap(rng, 5 * sf._CHUNK_ROWS + 17, np.radians(50), 0.3, (2e3, -1e3, 5e2))
    big += rng.normal(scale=0.003, size=big.shape)
    big[[0, 4000, 40000]] = np.nan  # first row is the provisional centre of both paths
    stack = cap(rng, 60 * 80, np.radians(100)).reshape(60, 80, 3) + rng.normal(size=(60, 1, 3))
    stack[7, [0, 11]] = np.nan
    stack[9, 3:] = np.nan  # too few rows left: NaN fit with errors='nan'
    fast = gdke(big), gdke(stack, errors="nan")
    monkeypatch.setattr(_sphere_moments, "_kernels", lambda: None)
    slow = gdke(big), gdke(stack, errors="nan")
    for a, b in zip(fast, slow, strict=True):
        np.testing.assert_allclose(a.center, b.center, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(a.radius, b.radius, rtol=1e-9)
        np.testing.assert_array_equal(a.kind, b.kind)
        np.testing.assert_array_equal(a.n, b.n)
        np.testing.assert_array_equal(a.dropped, b.dropped)
    assert fast[0].dropped == 3 and fast[1].kind[9] == "still"


def test_closed_form_eigenvalues_match_lapack():
    rng = np.random.default_rng(82)
    a = rng.normal(size=(500, 3, 3))
    mats = [a @ np.swapaxes(a, -1, -2)]  # generic SPD
    u = np.linalg.qr(rng.normal(size=(200, 3, 3)))[0]
    # (eigenvalues, tolerance / |A|): isolated eigenvalues to rounding, a repeated pair to
    # ~sqrt(eps) (documented in _eigvalsh3), in which case the isolated one stays exact
    cases = [([1.0, 1.0, 1.0], 1e-12), ([0.0, 0.0, 2.0], 1e-7), ([0.0, 1.0, 1.0], 1e-7),
             ([1e-9, 0.5, 1.0], 1e-12), ([0.0, 0.0, 0.0], 0.0), ([1e-4, 0.3, 0.31], 1e-12)]
    tols = [1e-12]
    for w, tol in cases:
        mats.append(np.einsum("kij,j,klj->kil", u, np.asarray(w), u))
        tols.append(tol)
    for m, tol in zip(mats, tols, strict=True):
        m = 0.5 * (m + np.swapaxes(m, -1, -2))
        ref = np.linalg.eigvalsh(m)
        got = sf._eigvalsh3(m)
        scale = np.abs(ref).max(axis=-1, keepdims=True) + 1e-300
        assert np.all(np.abs(got - ref) <= max(tol, 1e-12) * scale)
        assert np.all(np.diff(got, axis=-1) >= 0)
    circ = sf._eigvalsh3(mats[3])  # circle-like: the isolated smallest is exact
    assert np.all(np.abs(circ[:, 0] - np.linalg.eigvalsh(mats[3])[:, 0]) <= 1e-14)


# ------------------------------------------------------------------ stacks, NaN, errors
def test_stack_equals_loop():
    rng = np.random.default_rng(4)
    centers = rng.normal(size=(4, 5, 3))
    pts = centers[..., None, :] + cap(rng, 4 * 5 * 50, np.radians(90)).reshape(4, 5, 50, 3)
    pts += rng.normal(scale=0.01, size=pts.shape)
    fit = gdke(pts)
    assert fit.center.shape == (4, 5, 3) and fit.radius.shape == (4, 5)
    assert fit.kind.shape == (4, 5) and fit.n.shape == (4, 5)
    for i in range(4):
        for j in range(5):
            one = gdke(pts[i, j])
            np.testing.assert_allclose(fit.center[i, j], one.center, rtol=1e-12)
            assert fit.radius[i, j] == pytest.approx(one.radius, rel=1e-12)
            assert fit.kind[i, j] == one.kind


def test_nan_rows_dropped_and_counted_in_stacks():
    rng = np.random.default_rng(5)
    pts = cap(rng, 2 * 40, np.radians(120)).reshape(2, 40, 3) + [[[0, 0, 0]], [[1, 2, 3]]]
    holey = pts.copy()
    holey[0, [0, 7]] = np.nan  # includes the first row (the provisional centre)
    holey[1, 3, 1] = np.nan
    fit = gdke(holey)
    assert list(fit.n) == [38, 39] and list(fit.dropped) == [2, 1]
    np.testing.assert_allclose(fit.center[0], gdke(np.delete(pts[0], [0, 7], 0)).center, atol=1e-12)
    np.testing.assert_allclose(fit.center[1], [1, 2, 3], atol=1e-9)


def test_too_few_points_and_inf_raise():
    pts = np.full((6, 3), np.nan)
    pts[:3] = np.eye(3)
    with pytest.raises(FitError, match="at least 4 usable points, got 3"):
        gdke(pts)
    with pytest.raises(VidcapError):
        lls(pts)
    bad = np.random.default_rng(0).normal(size=(10, 3))
    bad[2, 0] = np.inf
    with pytest.raises(FitError, match="non-finite"):
        gdke(bad)
    # errors='nan' returns a NaN fit for the short set in a stack
    stack = np.stack([np.random.default_rng(1).normal(size=(6, 3)), pts])
    fit = gdke(stack, errors="nan")
    assert fit.kind[1] == "still" and np.isnan(fit.center[1]).all()
    assert np.isfinite(fit.center[0]).all()


def test_sphere_fit_is_frozen():
    fit = gdke(np.random.default_rng(0).normal(size=(10, 3)))
    assert isinstance(fit, SphereFit)
    with pytest.raises(AttributeError):
        fit.radius = 1.0


# ------------------------------------------------------------------ incremental
def test_incremental_equals_gdke():
    rng = np.random.default_rng(6)
    pts = cap(rng, 1000, np.radians(50), 0.3, (5.0, -2.0, 1.0))
    pts += rng.normal(scale=0.003, size=pts.shape)
    pts[[10, 500]] = np.nan
    ref = gdke(pts)
    inc = IncrementalGDK(3)
    for row in pts[:100]:
        inc.add(row)  # one sample at a time
    for chunk in np.array_split(pts[100:], 13):
        inc.add(chunk)
    fit = inc.fit()
    assert inc.n == ref.n == 998 and fit.dropped == 2
    assert np.linalg.norm(fit.center - ref.center) <= 1e-9 * np.linalg.norm(ref.center)
    assert fit.radius == pytest.approx(ref.radius, rel=1e-9)
    assert np.linalg.norm(inc.fit(1e-5).center - ugdk(pts, 1e-5).center) <= 1e-9 * 5.5


# ------------------------------------------------------------------ UGDK, noise, bound
def test_ugdk_removes_gdke_bias_on_a_cap():
    # 60° cap, σ/r = 5 %: GDKE's bias does not shrink with N; UGDK's error does.
    rng = np.random.default_rng(11)
    sigma, trials, n = 0.05, 40, 2000
    pts = cap(rng, trials * n, np.radians(60)).reshape(trials, n, 3)
    pts += rng.normal(scale=sigma, size=pts.shape)
    g = gdke(pts).center
    u = ugdk(pts, sigma**2).center
    bound = np.sqrt(np.trace(crlb(np.zeros(3), 1.0, pts[0], sigma)[:3, :3]))
    g_err = np.linalg.norm(g, axis=1)
    u_err = np.linalg.norm(u, axis=1)
    assert np.mean(g_err) > 5 * bound  # biased far beyond the bound
    assert np.sqrt(np.mean(u_err**2)) < 1.5 * bound  # near the bound (40 trials: ±11 %)


def test_ugdk_refine_steps_to_the_geometric_fit():
    rng = np.random.default_rng(14)
    # σ/r = 10 %, 60° cap, N = 100: the closed form is ~1.4x the bound, one step ~1.1x
    sigma, trials, n = 0.1, 300, 100
    pts = cap(rng, trials * n, np.radians(60)).reshape(trials, n, 3)
    pts += rng.normal(scale=sigma, size=pts.shape)
    plain = np.linalg.norm(ugdk(pts, sigma**2).center, axis=-1)
    one = np.linalg.norm(ugdk(pts, sigma**2, refine=1).center, axis=-1)
    # RMS ratio ~0.79 measured; 300 trials give a few % Monte Carlo error on each RMS
    assert np.sqrt(np.mean(one**2)) < 0.9 * np.sqrt(np.mean(plain**2))
    # iterated steps converge to the Levenberg-Marquardt fit, NaN rows ignored
    few = pts[:4].copy()
    few[1, [0, 3]] = np.nan
    fit = ugdk(few, sigma**2, refine=8)
    for k in range(4):
        x = few[k][~np.isnan(few[k]).any(axis=1)]
        ref = mle(x)  # stops at scipy's ftol, so compare the geometric cost, not 1e-9 digits

        def cost(c, r, x=x):
            return np.sum((np.linalg.norm(x - c, axis=1) - r) ** 2)

        assert cost(fit.center[k], fit.radius[k]) <= cost(ref.center, ref.radius) * (1 + 1e-9)
        assert np.linalg.norm(fit.center[k] - ref.center) < 1e-4
    assert list(fit.n) == [100, 98, 100, 100]
    # circles (hinges) are returned unrefined
    t = rng.uniform(0, 2 * np.pi, 80)
    hinge = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], axis=1) + [0.5, 0.0, 1.0]
    a, b = ugdk(hinge, 1e-8), ugdk(hinge, 1e-8, refine=1)
    assert b.kind == "circle"
    np.testing.assert_array_equal(a.center, b.center)


def test_ugdk_accepts_matrix_noise():
    rng = np.random.default_rng(12)
    pts = cap(rng, 400, np.radians(90))
    cov = np.diag([1e-4, 4e-4, 2e-4])
    a = ugdk(pts, cov)
    b = ugdk(pts, 2e-4)
    assert not np.allclose(a.center, b.center)
    with pytest.raises(FitError):
        ugdk(pts, np.eye(2))


def test_estimate_noise_trace():
    rng = np.random.default_rng(13)
    sigma = 0.02
    pts = cap(rng, 4 * 3000, np.radians(90)).reshape(4, 3000, 3)
    pts += rng.normal(scale=sigma, size=pts.shape)
    tr = estimate_noise_trace(pts)
    assert tr.shape == (4,)
    # standard error of a variance from 3000 samples is ≈ 2.6 %
    np.testing.assert_allclose(tr, 3 * sigma**2, rtol=0.12)


def test_crlb_full_circle_closed_form():
    # N equally spaced points on a circle: J = σ⁻² diag(N/2, N/2, N), so var(c_x) = 2σ²/N
    n, sigma = 64, 0.1
    t = 2 * np.pi * np.arange(n) / n
    pts = np.stack([np.cos(t), np.sin(t)], axis=1) * 3
    bound = crlb([0.0, 0.0], 3.0, pts, sigma)
    np.testing.assert_allclose(bound, np.diag([2, 2, 1]) * sigma**2 / n, atol=1e-15)


def test_mle_recovers_from_a_poor_start():
    rng = np.random.default_rng(14)
    pts = cap(rng, 200, np.radians(120), 2.0, (1.0, 1.0, 1.0))
    fit = mle(pts, x0=[0.0, 0.0, 0.0, 0.5])
    np.testing.assert_allclose(fit.center, [1, 1, 1], atol=1e-8)


# ------------------------------------------------------------------ MGDK
def test_mgdk_exact_and_input_forms_agree():
    rng = np.random.default_rng(15)
    center = np.array([0.2, -0.1, 0.4])
    sets = [cap(rng, n, np.radians(80), r, center) for n, r in ((50, 0.4), (30, 0.1), (70, 0.25))]
    fit = mgdk(sets)
    np.testing.assert_allclose(fit.center, center, atol=1e-12)
    np.testing.assert_allclose(fit.radius, [0.4, 0.1, 0.25], rtol=1e-10)
    assert fit.n == 150
    padded = np.full((3, 70, 3), np.nan)
    for i, s in enumerate(sets):
        padded[i, : len(s)] = s
    fit2 = mgdk(padded)
    np.testing.assert_allclose(fit2.center, fit.center, atol=1e-12)
    assert fit2.dropped == 60


def test_mgdk_beats_every_single_marker_when_one_is_near_the_centre():
    # two markers on one segment: far (r = 0.3) and near (r = 0.06) the joint centre,
    # σ = 2 mm, 90° cap, 100 samples each; 150 seeded trials.
    rng = np.random.default_rng(16)
    trials, n, sigma = 150, 100, 0.002
    far = cap(rng, trials * n, np.radians(90), 0.3).reshape(trials, n, 3)
    near = cap(rng, trials * n, np.radians(90), 0.06).reshape(trials, n, 3)
    far += rng.normal(scale=sigma, size=far.shape)
    near += rng.normal(scale=sigma, size=near.shape)
    e_far = np.linalg.norm(ugdk(far, sigma**2).center, axis=1)
    e_near = np.linalg.norm(ugdk(near, sigma**2).center, axis=1)
    for weighting in ("samples", "radius"):
        e_m = np.array([np.linalg.norm(mgdk([far[i], near[i]], sigma**2, weighting=weighting)
                                       .center) for i in range(trials)])
        best_single = min(np.mean(e_far**2), np.mean(e_near**2))
        # paired comparison on the same data: the mean squared error must be lower,
        # and per trial the combined fit must win more often than it loses
        assert np.mean(e_m**2) < best_single
        assert np.mean(e_m < e_far) > 0.5
    e_r = np.array([np.linalg.norm(mgdk([far[i], near[i]], sigma**2, weighting="radius").center)
                    for i in range(trials)])
    assert np.mean(e_r**2) < 0.8 * min(np.mean(e_far**2), np.mean(e_near**2))


# ------------------------------------------------------------------ properties
def _noisy_cap(seed, n=80):
    rng = np.random.default_rng(seed)
    pts = cap(rng, n, np.radians(rng.uniform(40, 180)), rng.uniform(0.2, 3.0))
    return pts + rng.normal(scale=0.02, size=pts.shape)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    shift=st.lists(st.floats(-1e3, 1e3), min_size=3, max_size=3),
    scale=st.floats(1e-3, 1e3),
    quat=st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(
        lambda q: np.linalg.norm(q) > 0.1
    ),
)
def test_center_equivariance(seed, shift, scale, quat):
    pts = _noisy_cap(seed)
    q = np.asarray(quat) / np.linalg.norm(quat)
    w, x, y, z = q
    rot = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    t = np.asarray(shift)
    base = gdke(pts)
    moved = gdke(scale * pts @ rot.T + t)
    expect = scale * rot @ base.center + t
    # tolerance: rounding of coordinates of size |t| + scale·|x|, amplified by cond(C)
    tol = 1e-10 * base.condition * (np.abs(t).max() + scale * (1 + np.abs(pts).max()))
    assert np.linalg.norm(moved.center - expect) <= tol
    assert moved.radius == pytest.approx(scale * base.radius, rel=1e-8)
    assert moved.kind == base.kind
    # the same holds for the noise-corrected fit when Σ scales with the data
    u0 = ugdk(pts, 4e-4)
    u1 = ugdk(scale * pts @ rot.T + t, 4e-4 * scale**2)
    assert np.linalg.norm(u1.center - (scale * rot @ u0.center + t)) <= tol * 10
