"""The clip solve on synthetic clips with known answers (issue 33)."""

from __future__ import annotations

import numpy as np
import pytest

from vidcap.body import BodyModel, segment_vectors
from vidcap.io.bvh import write_bvh
from vidcap.synth import make_motion, prepare_clip, truth_arrays
from vidcap.video.lift import estimate_scale
from vidcap.video.solve import solve_clip
from vidcap.video.solve.limits import limit_angles, limit_excess
from vidcap.video.solve.skeleton import params_to_motion, root_rotation

BODY = BodyModel()


def _clip(motion="walk", yaw_deg=45.0, n=60):
    m = make_motion(motion, body=BODY, fps=30.0, n_frames=n, rng=np.random.default_rng(0))
    clip = prepare_clip(m, body=BODY, yaw_deg=yaw_deg, rng=np.random.default_rng(1))
    t = truth_arrays(clip, np.zeros((m.n_frames, 1, 1), bool))
    cam = t["camera"]
    s = np.linalg.norm(cam[0, :3])
    rot = np.stack([cam[0, :3] / s, -cam[1, :3] / s, -t["view_dir"]])
    t["camera_joints"] = t["joints3d"] @ rot.T
    return t


def _solve(t, noise=0.0, *, true_scale=False, **kw):
    j2 = t["joints2d"]
    s = np.linalg.norm(t["camera"][0, :3]) if true_scale else estimate_scale(j2, BODY)
    if noise:
        j2 = j2 + np.random.default_rng(7).normal(0.0, noise * BODY.height * s, j2.shape)
    kw.setdefault("prior_signs", t["depth_signs"])
    return solve_clip(j2, scale=s, fps=30.0, body=BODY, yaw=np.deg2rad(t["yaw_deg"]), **kw)


def _rel_error(a, b):
    return np.linalg.norm((a - a[:, :1]) - (b - b[:, :1]), axis=-1).mean()


def test_true_2d_gives_the_true_pose():
    t = _clip()
    sol = _solve(t, true_scale=True)  # the per-segment lift is exact here; the solve's
    assert _rel_error(sol.joints3d, t["camera_joints"]) < 0.02  # smoothing costs < 2 cm
    lengths = np.linalg.norm(segment_vectors(sol.joints3d), axis=-1)
    np.testing.assert_allclose(lengths, np.broadcast_to(BODY.segment_lengths(), lengths.shape),
                               atol=1e-9)


def _out_of_plane(t, k, lo=0.4, hi=1.0):
    seg = segment_vectors(t["camera_joints"])[:, k]
    zeta = seg[:, 2] / np.linalg.norm(seg, axis=-1)
    return (np.abs(zeta) > lo) & (np.abs(zeta) < hi)


def test_a_planted_sign_flip_is_corrected_by_its_neighbours():
    t = _clip()
    k = 7  # l_lower_leg
    ok = _out_of_plane(t, k)
    f = int(np.flatnonzero(ok[1:-1] & ok[:-2] & ok[2:])[len(ok) // 4] + 1)
    prior = t["depth_signs"].copy()
    prior[f, k] *= -1
    sol = _solve(t, prior_signs=prior)
    assert sol.signs[f, k] == t["depth_signs"][f, k]
    # and the solve says the proposal's sign there was cheap to give up
    assert np.isfinite(sol.confidence[f, k])


def test_a_hard_user_depth_sign_is_never_overruled():
    t = _clip()
    k = 2  # l_upper_arm
    ok = _out_of_plane(t, k, 0.2, 0.7)
    frames = np.flatnonzero(ok)[:6]
    hard = np.zeros_like(t["depth_signs"])
    hard[frames, k] = -t["depth_signs"][frames, k]  # against the image's best reading
    sol = _solve(t, hard_signs=hard)
    np.testing.assert_array_equal(sol.signs[frames, k], hard[frames, k])


def test_joint_limits_hold_on_every_solved_frame():
    t = _clip("walk", 45.0)
    sol = _solve(t, noise=0.02)
    p = sol.params
    root = root_rotation(p[:, 3], p[:, 4], p[:, 5])
    excess = limit_excess(limit_angles(sol.joints3d, root, p[:, 4:6]))
    assert np.rad2deg(excess).max() < 2.0


def test_bvh_of_the_solve_reads_back_to_its_joints(tmp_path):
    bvhio = pytest.importorskip("bvhio")
    t = _clip(n=20)
    sol = _solve(t, noise=0.01)
    m = params_to_motion(sol.params, BODY, 30.0)
    path = tmp_path / "solve.bvh"
    write_bvh(path, m)
    root = bvhio.readAsHierarchy(str(path))
    names = m.skeleton.joint_names
    theirs = np.empty((m.n_frames, len(names), 3))
    for f in range(m.n_frames):
        root.loadPose(f)
        pos = {j.Name: np.array(list(j.PositionWorld), float) for j, _, _ in root.layout()}
        theirs[f] = [pos[n] for n in names]
    assert np.abs(theirs - sol.joints3d).max() < 1e-3


@pytest.mark.parametrize("motion, yaw", [("walk", 90.0), ("walk", 45.0), ("jacks", 20.0)])
def test_contact_marks_feet_that_stand_still(motion, yaw):
    t = _clip(motion, yaw)
    contact = _solve(t).contact
    if motion == "walk":
        assert contact.any(axis=1).mean() > 0.6
    ankles = t["camera_joints"][:, [11, 14]]
    speed = np.linalg.norm(np.gradient(ankles, axis=0), axis=-1) * 30.0  # m/s, true
    if contact.any():
        assert np.mean(speed[contact] < 0.3) > 0.8  # the ends of a stance move a little


def test_a_run_of_frames_left_in_a_wrong_pose_is_repaired():
    from vidcap.video.solve.clip import make_problem
    from vidcap.video.solve.repair import frame_costs, repair_outliers
    from vidcap.video.solve.skeleton import params_from_joints

    t = _clip()
    s = np.linalg.norm(t["camera"][0, :3])
    yaw = np.deg2rad(t["yaw_deg"])
    pb = make_problem(t["joints2d"], scale=s, fps=30.0, body=BODY, yaw=yaw,
                      prior_signs=t["depth_signs"], contact="off")
    good = params_from_joints(t["camera_joints"], yaw)
    good[:, :2] = pb.target[:, 0]
    good[:, 2] = 0.0
    bad = good.copy()
    bad[30:34, 6:] = -good[30:34, 6:] + 1.0  # every limb swung far off for 4 frames
    assert frame_costs(pb, bad)[30:34].min() > 20 * np.median(frame_costs(pb, good))
    fixed, n = repair_outliers(pb, bad)
    assert n >= 1
    assert np.abs(fixed[30:34] - good[30:34]).max() < 0.1
    np.testing.assert_array_equal(fixed[:20], bad[:20])  # away from the run: untouched
