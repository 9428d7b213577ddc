"""Each step of vidcap.mocap.skeleton.solve_joints on a tiny hand-built chain with known
centres: pelvis (root, 3 markers) -> thigh (ball hip, 3 markers) -> shank (hinge knee,
1, 2 or 3 markers) with an end joint."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from vidcap.mocap.c3d import MarkerData
from vidcap.mocap.frames import to_lab
from vidcap.mocap.markerset import parse_markerset
from vidcap.mocap.skeleton import (
    JointCentre,
    SolveOptions,
    child_samples,
    end_joint,
    fit_segment_centre,
    hinge_anchor,
    joint_tree,
    per_frame_centre,
    refine_symmetric,
    root_frames,
    root_joint,
    solve_joints,
)

HIP = np.array([0.1, -0.05, -0.08])  # in the pelvis frame
KNEE = np.array([0.0, -0.42, 0.0])  # in the thigh frame
PELVIS_MK = np.array([[0.12, 0.02, 0.05], [-0.12, 0.03, 0.04], [0.0, 0.05, -0.1]])
THIGH_MK = np.array([[0.07, -0.15, 0.02], [0.02, -0.3, 0.06], [-0.05, -0.25, 0.04]])
SHANK_MK = np.array([[0.06, -0.12, 0.03], [0.01, -0.3, 0.05], [-0.05, -0.2, 0.05]])
TOE = np.array([0.0, -0.4, 0.1])  # end point in the shank frame, a marker there too


def _chain(n_shank: int, frames: int = 240, noise: float = 0.0, seed: int = 3):
    """Markers (F, M, 3) of the chain, the marker set and the true lab centres."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 4 * np.pi, frames)
    r_pel = Rotation.from_rotvec(np.c_[0.2 * np.sin(t), 0.3 * np.sin(0.7 * t),
                                       0.1 * np.cos(1.3 * t)])
    o_pel = np.c_[0.3 * t, 0.01 * np.sin(t), 0.9 + 0.01 * np.cos(2 * t)]
    r_hip = Rotation.from_rotvec(np.c_[0.5 * np.sin(1.1 * t), 0.3 * np.cos(0.9 * t),
                                       0.4 * np.sin(0.6 * t + 1)])
    r_th = r_pel * r_hip
    hip = o_pel + r_pel.apply(HIP)
    r_sh = r_th * Rotation.from_rotvec(np.c_[0.6 + 0.6 * np.sin(1.7 * t), 0 * t, 0 * t])
    knee = hip + r_th.apply(KNEE)

    def lab(r, o, pts):
        return np.stack([o + r.apply(p) for p in pts], axis=1)

    shank = np.vstack([SHANK_MK[:n_shank], TOE[None]])
    pos = np.concatenate([lab(r_pel, o_pel, PELVIS_MK), lab(r_th, hip, THIGH_MK),
                          lab(r_sh, knee, shank)], axis=1)
    pos += rng.normal(scale=noise, size=pos.shape)
    sh = [f"S{k}" for k in range(n_shank)]
    labels = ("P0", "P1", "P2", "T0", "T1", "T2", *sh, "TOE")
    toml = f"""name = 'chain'
[segments.pelvis]
joint = 'pelvis'
markers = ['P0', 'P1', 'P2']
origin = ['l_hip']
[segments.l_upper_leg]
joint = 'l_hip'
parent = 'pelvis'
markers = ['T0', 'T1', 'T2']
[segments.l_lower_leg]
joint = 'l_knee'
parent = 'l_upper_leg'
markers = {sh!r}
end = {{ joint = 'l_toe', markers = ['TOE'] }}
"""
    data = MarkerData(labels, pos, 100.0, path="<chain>")
    truth = {"l_hip": hip, "l_knee": knee, "l_toe": knee + r_sh.apply(TOE),
             "knee_axis": r_th.apply([1.0, 0.0, 0.0])}
    return data, parse_markerset(toml), truth


def _steps(n_shank=3, noise=0.0):
    data, ms, truth = _chain(n_shank, noise=noise)
    return data, ms, truth, root_frames([data], ms.root)


def test_root_frames_are_rotations_that_carry_the_template_onto_the_markers():
    data, ms, _, (rf,) = _steps()
    assert rf.r.shape == (240, 3, 3) and rf.valid.all()
    np.testing.assert_allclose(np.einsum("fji,fjk->fik", rf.r, rf.r),
                               np.broadcast_to(np.eye(3), rf.r.shape), atol=1e-12)
    pred = rf.o[:, None] + np.einsum("fij,kj->fki", rf.r, rf.template)
    np.testing.assert_allclose(pred, data.positions[:, :3], atol=1e-12)


def test_child_samples_lie_on_spheres_about_the_hip_in_the_pelvis_frame():
    data, ms, truth, (rf,) = _steps()
    thigh = ms.segment("l_upper_leg")
    s = child_samples(thigh, [data], [rf])
    assert s.frames_used == 240 and len(s.sets) == 3
    hip_local = np.einsum("fji,fj->fi", rf.r, truth["l_hip"] - rf.o)
    np.testing.assert_allclose(hip_local, np.broadcast_to(hip_local[0], hip_local.shape),
                               atol=1e-12)
    for k, y in enumerate(s.sets):
        r = np.linalg.norm(y - hip_local[0], axis=1)
        np.testing.assert_allclose(r, np.linalg.norm(THIGH_MK[k]), atol=1e-12)
    # the fallback is the markers' centroid (no fallback list), in the parent's frame
    np.testing.assert_allclose(
        s.fallback_local, np.median(np.mean(np.stack(s.sets, 1), axis=1), axis=0), atol=1e-12)
    # a marker missing in some frames drops out of its own set only
    data.positions[:50, 3] = np.nan
    s2 = child_samples(thigh, [data], [rf])
    assert [len(y) for y in s2.sets] == [190, 240, 240] and s2.frames_used == 240


def test_hinge_anchor_is_the_parent_proximal_joint_for_a_long_bone_only():
    data, ms, truth, (rf,) = _steps()
    opts = SolveOptions()
    hip = fit_segment_centre(ms.segment("l_upper_leg"),
                             child_samples(ms.segment("l_upper_leg"), [data], [rf]),
                             hinge_anchor(ms.segment("l_upper_leg"), ms, data, rf, None, True),
                             None, opts)
    assert hinge_anchor(ms.segment("l_upper_leg"), ms, data, rf, None, True).point is None
    hip_lab = to_lab(rf.r, rf.o, hip.parent_local)
    tf = per_frame_centre(ms.segment("l_upper_leg"), data, rf, hip, 0)[1]
    shank = ms.segment("l_lower_leg")
    a = hinge_anchor(shank, ms, data, tf, hip_lab, True)
    assert "proximal joint" in a.what
    # the hip in the thigh's frame (constant: the hip is fixed in the thigh)
    np.testing.assert_allclose(a.point, np.einsum("fji,fj->fi", tf.r, hip_lab - tf.o)[0],
                               atol=1e-9)
    assert hinge_anchor(shank, ms, data, tf, hip_lab, False).point is None


def test_fit_segment_centre_recovers_the_hip_and_flags_a_still_joint():
    data, ms, truth, (rf,) = _steps()
    thigh = ms.segment("l_upper_leg")
    samples = child_samples(thigh, [data], [rf])
    fit = fit_segment_centre(thigh, samples, hinge_anchor(thigh, ms, data, rf, None, True),
                             None, SolveOptions())
    assert isinstance(fit, JointCentre) and not fit.report.flagged
    assert fit.report.kind == "sphere"
    np.testing.assert_allclose(to_lab(rf.r, rf.o, fit.parent_local), truth["l_hip"], atol=1e-9)
    # markers frozen in the parent frame: no centre, the fallback (their centroid) stands
    still = type(samples)(tuple(np.repeat(y[:1], len(y), 0) for y in samples.sets),
                          samples.fallback_local, samples.frames_used)
    fit2 = fit_segment_centre(thigh, still, hinge_anchor(thigh, ms, data, rf, None, True),
                              None, SolveOptions())
    assert fit2.report.flagged and fit2.report.method == "fallback"
    np.testing.assert_array_equal(fit2.parent_local, samples.fallback_local)


@pytest.mark.parametrize("n_shank", [1, 2, 3])
def test_knee_hinge_and_per_frame_centres_for_one_two_three_markers(n_shank):
    data, ms, truth, (rf,) = _steps(n_shank)
    opts = SolveOptions()
    thigh, shank = ms.segment("l_upper_leg"), ms.segment("l_lower_leg")
    hs = child_samples(thigh, [data], [rf])
    hip = refine_symmetric(thigh, [data], [rf], fit_segment_centre(
        thigh, hs, hinge_anchor(thigh, ms, data, rf, None, True), None, opts),
        hinge_anchor(thigh, ms, data, rf, None, True), hs, opts)
    assert hip.child_local is not None  # three thigh markers: SCoRE in both frames
    hip_lab, tf = per_frame_centre(thigh, data, rf, hip, 0)
    np.testing.assert_allclose(hip_lab, truth["l_hip"], atol=1e-7)
    ks = child_samples(shank, [data], [tf])
    anchor = hinge_anchor(shank, ms, data, tf, hip_lab, True)
    knee = fit_segment_centre(shank, ks, anchor, None, opts)
    knee = refine_symmetric(shank, [data], [tf], knee, anchor, ks, opts)
    assert knee.report.kind == "hinge" and "axis-rule" in knee.report.method
    assert (knee.own_frames is not None) == (n_shank >= 3)
    axis_lab = np.einsum("fij,j->fi", tf.r, knee.axis)
    np.testing.assert_allclose(np.abs(np.sum(axis_lab * truth["knee_axis"], 1)), 1, atol=1e-9)
    knee_lab, sf = per_frame_centre(shank, data, tf, knee, 0)
    # the hinge rule puts the centre on the axis nearest the hip: the knee itself here
    np.testing.assert_allclose(knee_lab, truth["l_knee"], atol=1e-6)
    assert sf.valid.all()
    v_end, rep = end_joint(shank, sf, data)
    assert rep.kind == "end"
    np.testing.assert_allclose(sf.o + np.einsum("fij,j->fi", sf.r, v_end), truth["l_toe"],
                               atol=1e-6)


def test_refine_symmetric_leaves_a_two_marker_child_alone():
    data, ms, truth, (rf,) = _steps(2)
    thigh, shank = ms.segment("l_upper_leg"), ms.segment("l_lower_leg")
    hs = child_samples(thigh, [data], [rf])
    hip = fit_segment_centre(thigh, hs, hinge_anchor(thigh, ms, data, rf, None, True), None,
                             SolveOptions())
    _, tf = per_frame_centre(thigh, data, rf, hip, 0)
    ks = child_samples(shank, [data], [tf])
    knee = fit_segment_centre(shank, ks, hinge_anchor(shank, ms, data, tf, None, True), None,
                              SolveOptions())
    assert refine_symmetric(shank, [data], [tf], knee, hinge_anchor(shank, ms, data, tf, None,
                            True), ks, SolveOptions()) is knee


def test_root_joint_tree_and_whole_solve_agree():
    data, ms, truth, (rf,) = _steps(noise=0.0)
    v, rep = root_joint(ms.root, rf, {"l_hip": HIP})
    np.testing.assert_allclose(v, HIP)
    assert rep.kind == "root" and "mean of l_hip" in rep.note
    v2, rep2 = root_joint(ms.root, rf, {})
    np.testing.assert_allclose(v2, rf.template.mean(axis=0))
    assert "centroid" in rep2.note
    names, parents, segs = joint_tree(ms)
    assert names == ["pelvis", "l_hip", "l_knee", "l_toe"] and parents == [-1, 0, 1, 2]
    assert segs == ["pelvis", "l_upper_leg", "l_lower_leg", "l_lower_leg"]
    sol = solve_joints(data, ms)
    for j in ("l_hip", "l_knee", "l_toe"):
        np.testing.assert_allclose(sol.position(j), truth[j], atol=1e-6)
