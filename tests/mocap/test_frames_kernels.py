"""The compiled kernels of the marker path (vidcap.mocap._frames_kernels,
_jointfit_kernels) against the numpy paths they replace: Kabsch poses with gaps, weights
and degenerate point sets, the three-point templates, frame changes, medians, the
per-marker fit statistics, and the whole solve on a small synthetic chain."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from vidcap.mocap import _sphere_moments, jointfit
from vidcap.mocap import frames as fr
from vidcap.mocap.skeleton import solve_joints

sys.path.insert(0, str(Path(__file__).parent))
from test_skeleton_steps import _chain  # noqa: E402


def _numpy_only(monkeypatch):
    """Every compiled kernel of the marker path off: the numpy reference paths."""
    monkeypatch.setattr(fr, "_kernels", lambda: None)
    monkeypatch.setattr(_sphere_moments, "_kernels", lambda: None)
    monkeypatch.setattr(jointfit, "_kernels", lambda: None)


def _poses(rng, tmpl, frames=300, noise=1e-3):
    rot = Rotation.random(frames, random_state=rng).as_matrix()
    pts = np.einsum("fij,kj->fki", rot, tmpl) + rng.normal(size=(frames, 1, 3))
    return pts + rng.normal(scale=noise, size=pts.shape)


def _same(a, b, atol):
    assert (np.isfinite(a) == np.isfinite(b)).all()
    np.testing.assert_allclose(a[np.isfinite(a)], b[np.isfinite(b)], rtol=0, atol=atol)


def test_compiled_rotation_fit_matches_the_svd_path(monkeypatch):
    """Horn's quaternion sweeps give Kabsch's SVD rotations and singular values, and
    kabsch() gives the same poses through either backend, gaps and weights included."""
    kern = fr._kernels()
    assert kern is not None  # numba is a dependency: the fast path must be live
    rng = np.random.default_rng(11)
    h = rng.normal(size=(500, 3, 3))
    h[3] = np.outer([1.0, 2, 3], [3.0, 1, 0]) + np.outer([0.0, 1, 0], [1.0, 0, 2])  # rank 2
    r_np, s_np = fr._rotations_numpy(h.copy())
    r_k, s_k = kern.rotations_from_cross(h.copy())
    np.testing.assert_allclose(r_k, r_np, atol=1e-12)
    np.testing.assert_allclose(s_k, s_np, rtol=1e-9, atol=1e-7)
    np.testing.assert_allclose(np.linalg.det(r_k), 1.0, atol=1e-12)
    tmpl = rng.normal(size=(4, 3)) * 0.1
    pts = _poses(rng, tmpl, 200)
    pts[5, 1] = np.nan
    pts[6, :2] = np.nan  # two points left: no pose
    w = np.array([1.0, 2.0, 0.5, 1.0])
    fast = fr.kabsch(tmpl, pts, w)
    monkeypatch.setattr(fr, "_kernels", lambda: None)
    slow = fr.kabsch(tmpl, pts, w)
    for a, b in zip(fast, slow, strict=True):
        _same(a, b, 1e-12)
    assert np.isnan(fast[0][6]).all() and np.isfinite(fast[0][5]).all()


@pytest.mark.parametrize("case", ["tetra", "planar3", "collinear", "nearly_collinear",
                                  "weights_fk", "mirror"])
def test_fused_kabsch_equals_the_numpy_path(case, monkeypatch):
    """The fused kernel (Newton on Horn's quartic, the sweeps where that is
    ill-determined, the rank test from G's invariants) against the batched numpy path:
    same poses, same frames without one."""
    rng = np.random.default_rng(7)
    tmpl = rng.normal(size=(5, 3)) * 0.1
    weights = None
    if case == "planar3":
        tmpl = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.0, 0.05, 0]])
    elif case == "collinear":
        tmpl = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.2, 0, 0]])
    elif case == "nearly_collinear":  # s2/s1 from 2.5e-8 to 2.5e-6 over the frames
        tmpl = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.2, 1.7e-4, 0]])
    pts = _poses(rng, tmpl, 400, noise=0.0 if "collinear" in case else 1e-3)
    if case == "nearly_collinear":  # the rank test's 1e-6 and its undecided band crossed
        bent = np.zeros((400, 3, 3))
        bent[:, 2, 1] = 1.8e-4 * np.logspace(-1, 1, 400)
        rot = Rotation.random(400, random_state=rng).as_matrix()
        pts = np.einsum("fij,fkj->fki", rot, tmpl * [1, 0, 0] + bent) + 1.0
    if case == "weights_fk":
        weights = rng.uniform(0.1, 2.0, size=pts.shape[:2])
        weights[::7, 0] = 0.0
        weights[::11, 1] = np.nan
        pts[::13, 2] = np.nan
    if case == "mirror":  # mirrored points: Horn's top eigenvalues 2 (s₂ - s₃) apart, with
        # s₂/s₁ = 0.5 and s₃ 2e-5 below s₂: the Jacobi sweeps take over
        tmpl = np.diag([0.1, 0.1 * np.sqrt(0.5), 0.1 * np.sqrt(0.49999)])
        tmpl = np.concatenate([tmpl, -tmpl])
        pts = _poses(rng, tmpl, 400, noise=1e-7) * np.array([1.0, 1.0, -1.0])
        kern = fr._kernels()
        state = kern.kabsch_frames(tmpl, pts, np.ones(pts.shape[:2]), fr._EPS)[2]
        assert (state == kern.POSE | kern.SWEEP_ROTATION).all()
    fast = fr.kabsch(tmpl, pts, weights)
    sweeps = fr._kabsch_numpy(tmpl, pts, weights)  # batched numpy, Jacobi rotations
    monkeypatch.setattr(fr, "_kernels", lambda: None)
    slow = fr.kabsch(tmpl, pts, weights)  # batched numpy, SVD rotations
    # Ill-determined rotations (about a near-line; mirrored with s₂ ≈ s₃) differ between
    # any two methods: the SVD and the sweeps by 3e-10 and 1.4e-9 here.
    tol = {"nearly_collinear": 1e-9, "mirror": 1e-8}.get(case, 1e-11)
    for a, b, c in zip(fast, slow, sweeps, strict=True):
        _same(a, b, tol)
        _same(a, c, 1e-9 if case == "mirror" else tol)
    if case == "collinear":
        assert np.isnan(fast[0]).all()
    elif case == "nearly_collinear":
        valid = np.isfinite(fast[0]).all(axis=(1, 2))
        assert not valid[:250].any() and valid[-50:].all()  # s2/s1 = 1e-6 at ~318
    else:
        assert np.isfinite(fast[0]).all(axis=(1, 2)).sum() > 0


def test_newton_path_gives_way_where_horn_eigenvalues_meet():
    """A reflected square-ish point set puts Horn's two top eigenvalues together: the
    fast path declines (the sweeps decide), a plain rotation it takes."""
    kern = fr._kernels()
    a = np.empty((4, 4))
    rot = np.empty((1, 3, 3))
    s = np.diag([1.0, 1.0, -1.0])  # λ = 1 + 1 - 1 twice: two eigenvalues equal
    assert not kern._rotation_newton(s, 3.0, a, rot, 0)
    r0 = Rotation.from_rotvec([0.3, -0.2, 0.5]).as_matrix()
    s = np.diag([3.0, 2.0, 1.0]) @ r0.T  # h = Σ t xᵀ for x = r0 t
    assert kern._rotation_newton(s, 6.0, a, rot, 0)
    np.testing.assert_allclose(rot[0], r0, atol=1e-13)


def test_three_point_template_equals_the_numpy_path(monkeypatch):
    rng = np.random.default_rng(3)
    tmpl = rng.normal(size=(4, 3)) * 0.1
    pts = _poses(rng, tmpl, 301)
    pts[:20, 0] = np.nan  # the first point missing: no three-point frame, Kabsch fills
    pts[30:40, 3] = np.nan
    pts[50, 2] = pts[50, 0] + 2 * (pts[50, 1] - pts[50, 0])  # collinear first three
    fast = fr.frames_from_points(pts)
    monkeypatch.setattr(fr, "_kernels", lambda: None)
    slow = fr.frames_from_points(pts)
    _same(fast.template, slow.template, 1e-15)
    _same(fast.r, slow.r, 1e-12)
    _same(fast.o, slow.o, 1e-12)
    assert fast.valid[:20].all()  # three of four points present
    none = fr.frames_from_points(np.full((5, 3, 3), np.nan))
    assert np.isnan(none.template).all() and not none.valid.any()


@pytest.mark.parametrize("n_shank", [1, 2, 3])
def test_whole_solve_equals_the_numpy_reference(n_shank, monkeypatch):
    """The solve with every kernel against the plain numpy paths, noisy chain with gaps:
    the same centres, frames and reports to 1e-9."""
    data, ms, _ = _chain(n_shank, noise=5e-4)
    data.positions[10:20, 4] = np.nan
    data.positions[100:103, 1] = np.nan
    fast = solve_joints(data, ms)
    _numpy_only(monkeypatch)
    slow = solve_joints(data, ms)
    np.testing.assert_allclose(fast.positions, slow.positions, rtol=0, atol=1e-9)
    _same(fast.rotations, slow.rotations, 1e-9)
    for a, b in zip(fast.reports, slow.reports, strict=True):
        assert (a.joint, a.kind, a.method, a.flagged) == (b.joint, b.kind, b.method, b.flagged)
        np.testing.assert_allclose(a.center_local_m, b.center_local_m, rtol=0, atol=1e-9)
        np.testing.assert_allclose([a.rms_residual_m, a.cap_angle_deg],
                                   [b.rms_residual_m, b.cap_angle_deg], rtol=1e-9)


def test_frame_changes_and_medians_equal_the_numpy_path(monkeypatch):
    rng = np.random.default_rng(5)
    r = Rotation.random(50, random_state=rng).as_matrix()
    o = rng.normal(size=(50, 3))
    x = rng.normal(size=(50, 4, 3))
    x[3, 1] = np.nan
    y = rng.normal(size=(41, 3))
    y[::4, 2] = np.nan
    v = np.array([0.1, -0.2, 0.3])
    fast = fr.to_local(r, o, x), fr.to_lab(r, o, v), fr.nanmedian_rows(y)
    monkeypatch.setattr(fr, "_kernels", lambda: None)
    slow = fr.to_local(r, o, x), fr.to_lab(r, o, v), fr.nanmedian_rows(y)
    for a, b in zip(fast, slow, strict=True):
        _same(a, b, 1e-15)
    np.testing.assert_array_equal(fast[2], slow[2])  # order statistics: exact
    assert np.isnan(fr.nanmedian_rows(np.full((3, 3), np.nan))).all()


@pytest.mark.parametrize("hinge", [False, True])
def test_marker_statistics_equal_the_numpy_path(hinge, monkeypatch):
    """Residual, cap angle, weakest direction and pooled spread of markers on spheres
    (circles for a hinge) about a centre: compiled and numpy agree to rounding."""
    rng = np.random.default_rng(9)
    centre = np.array([0.01, -0.02, 0.03])
    normal = np.array([0.0, 0.6, 0.8]) if hinge else None
    sets = []
    for radius, n in [(0.2, 500), (0.3, 321), (0.25, 2)]:
        d = rng.normal(size=(n, 3))
        if hinge:
            d -= np.outer(d @ normal, normal)
        d = d / np.linalg.norm(d, axis=1, keepdims=True) * np.linspace(0.2, 1, n)[:, None]
        sets.append(centre + radius * d + rng.normal(scale=1e-3, size=(n, 3)))
    radii = np.array([0.2, 0.3, 0.25])
    fast = (jointfit.cap_and_residual(sets, centre, radii, normal),
            jointfit.weak_axis(sets, centre, 1e-3), jointfit.pooled_covariance(sets))
    monkeypatch.setattr(jointfit, "_kernels", lambda: None)
    slow = (jointfit.cap_and_residual(sets, centre, radii, normal),
            jointfit.weak_axis(sets, centre, 1e-3), jointfit.pooled_covariance(sets))
    np.testing.assert_allclose(fast[0], slow[0], rtol=1e-12)
    np.testing.assert_allclose(abs(fast[1][0] @ slow[1][0]), 1.0, atol=1e-12)
    np.testing.assert_allclose(fast[1][1], slow[1][1], rtol=1e-10)
    np.testing.assert_allclose(fast[2], slow[2], rtol=1e-12, atol=1e-18)
