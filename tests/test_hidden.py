"""Joints the image cannot show, from the 3D clip solve (:mod:`vidcap.video.hidden`)."""

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX as J
from vidcap.video.hidden import (
    HIDDEN_CHOICES,
    REHANG_SPREAD,
    arm_residual,
    check_hidden,
    exchange_forearms,
    fill_hidden,
    hidden_arms,
    hidden_joints,
    rehang_arms,
    reproject,
    solve_hidden,
    solve_in_image,
)

ARM = {s: [J[f"{s}_shoulder"], J[f"{s}_elbow"], J[f"{s}_wrist"]] for s in "lr"}
LEGS = [J[f"{s}_{p}"] for s in "lr" for p in ("hip", "knee", "ankle")]
HIPS = [J["l_hip"], J["r_hip"]]
LOWER_LEGS = [J[f"{s}_{p}"] for s in "lr" for p in ("knee", "ankle")]


def _walk(n=30, yaw_deg=90.0):
    """A side view of the built-in walk: joints3d (F, 15, 3) in the camera's frame (X
    right, Y up) and their scaled orthographic image (F, 15, 2), 200 px/m."""
    from vidcap.synth import make_motion

    j = make_motion("walk", n_frames=n).positions()
    a = np.deg2rad(yaw_deg)  # turn the walk (along -Z) to cross the picture
    rot = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])
    j3 = j @ rot.T
    uv = np.stack([320.0 + 200.0 * j3[..., 0], 420.0 - 200.0 * j3[..., 1]], axis=-1)
    return j3, uv


def test_reproject_draws_the_3d_joints_where_the_camera_sees_them():
    j3, uv = _walk(8)
    # any scale and offset of the 3D (metres, another origin): the axis joints say which
    got = reproject(0.5 * j3 + np.array([3.0, -1.0, 7.0]), uv)
    np.testing.assert_allclose(got, uv, atol=1e-9)


def test_hidden_arms_are_the_arms_drawn_inside_the_torso():
    _, uv = _walk(1)
    pose = uv[0].copy()
    shoulder = pose[J["l_shoulder"]]
    pose[J["l_elbow"]] = shoulder + [0.0, 40.0]  # hanging along the torso
    pose[J["l_wrist"]] = shoulder + [0.0, 90.0]
    pose[J["r_elbow"]] = pose[J["r_shoulder"]] + [60.0, -20.0]  # raised out to the side
    pose[J["r_wrist"]] = pose[J["r_shoulder"]] + [120.0, -40.0]
    assert hidden_arms(pose[None]).tolist() == [[True, False]]
    assert not hidden_arms(np.full((1, 15, 2), np.nan)).any()


def _front_pose(n=5):
    """A front view of the model's T-pose with its left forearm folded across the
    torso (elbow forward and in): joints3d (F, 15, 3) and their image (F, 15, 2)."""
    from vidcap.body import BodyModel

    j = BodyModel().rest_positions()
    j[J["l_elbow"]] = j[J["l_shoulder"]] + [0.08, -0.2, -0.12]
    j[J["l_wrist"]] = j[J["l_elbow"]] + [0.22, 0.05, -0.2]
    j3 = np.repeat(j[None], n, axis=0) + np.linspace(0.0, 0.2, n)[:, None, None] * [1, 0, 0]
    uv = np.stack([320.0 + 200.0 * j3[..., 0], 420.0 - 200.0 * j3[..., 1]], axis=-1)
    return j3, uv


def test_fill_hidden_takes_hidden_arms_shoulders_and_hips_from_the_3d_and_keeps_the_rest():
    j3, uv = _front_pose()
    fit = uv.copy()
    # the 2D fit's left arm hung down along the torso (the frame shows nothing of the
    # forearm across it); its right arm, out to the side, is what the image shows
    fit[:, J["l_elbow"]] = fit[:, J["l_shoulder"]] + [15.0, 45.0]
    fit[:, J["l_wrist"]] = fit[:, J["l_shoulder"]] + [25.0, 110.0]
    fit[:, J["l_shoulder"]] += [4.0, 2.0]
    fit[:, J["r_wrist"]] += [0.0, 6.0]  # a visible arm fitted a little off: kept
    fit[:, LEGS] += 3.0  # legs fitted a little off: knees and ankles kept, hips solved
    assert hidden_arms(fit).tolist() == [[True, False]] * len(fit)
    # the solve names arms by the body's sides: exchanged, they are matched back
    named = j3[:, [0, 1, 2, 6, 7, 8, 3, 4, 5, 9, 10, 11, 12, 13, 14]]
    out = fill_hidden(fit, named)
    np.testing.assert_allclose(out[:, ARM["l"]], uv[:, ARM["l"]], atol=1e-6)
    np.testing.assert_allclose(out[:, J["r_shoulder"]], uv[:, J["r_shoulder"]], atol=1e-6)
    np.testing.assert_array_equal(out[:, ARM["r"][1:]], fit[:, ARM["r"][1:]])
    np.testing.assert_array_equal(out[:, LOWER_LEGS], fit[:, LOWER_LEGS])
    np.testing.assert_allclose(out[:, HIPS], uv[:, HIPS], atol=1e-6)
    np.testing.assert_array_equal(out[:, :3], fit[:, :3])


def test_fill_hidden_matches_the_solves_legs_to_the_fits_before_taking_its_hips():
    """The solve names legs by the body's sides, the fit by the image's: each frame's
    hips come from the solve's leg nearer the fit's leg of that name. A walk turned 30
    degrees from facing the camera (hips ~30 px apart), its fitted hips 6 px off and the
    solve's legs named the other way round in every other frame: the hips land on the
    true ones, the knees and ankles stay."""
    j3, uv = _walk(6, yaw_deg=30.0)
    assert np.linalg.norm(uv[:, J["l_hip"]] - uv[:, J["r_hip"]], axis=-1).min() > 20.0
    fit = uv.copy()
    fit[:, HIPS] += [6.0, -4.0]
    named = j3.copy()
    left, right = [J[f"l_{p}"] for p in ("hip", "knee", "ankle")], \
        [J[f"r_{p}"] for p in ("hip", "knee", "ankle")]
    named[::2][:, left + right] = j3[::2][:, right + left]
    out = fill_hidden(fit, named)
    np.testing.assert_allclose(out[:, HIPS], uv[:, HIPS], atol=1e-6)
    np.testing.assert_array_equal(out[:, LOWER_LEGS], fit[:, LOWER_LEGS])


def test_hidden_joints_name_each_elbow_and_wrist_inside_the_torso():
    _, uv = _walk(1)
    pose = uv[0].copy()
    sh = pose[J["l_shoulder"]]
    pose[J["l_elbow"]] = sh + [0.0, 40.0]  # elbow inside, the forearm out in front
    pose[J["l_wrist"]] = sh + [90.0, 40.0]
    pose[J["r_elbow"]] = pose[J["r_shoulder"]] + [60.0, -20.0]  # raised out in the open
    pose[J["r_wrist"]] = pose[J["r_shoulder"]] + [120.0, -40.0]
    assert hidden_joints(pose[None]).tolist() == [[[True, False], [False, False]]]
    assert hidden_arms(pose[None]).tolist() == [[True, False]]


def test_fill_hidden_keeps_a_wrist_the_image_shows_and_takes_what_the_torso_hides():
    """An arm whose elbow is inside the torso's outline but whose wrist stands out in
    front of it: the wrist stays where the fit put it (the image shows it), the
    elbow comes from the solve; a wrist inside the outline takes its elbow along."""
    j3, uv = _front_pose()
    fit = uv.copy()
    sh = fit[:, J["l_shoulder"]]
    fit[:, J["l_elbow"]] = sh + [15.0, 45.0]  # inside the torso's outline
    fit[:, J["l_wrist"]] = sh + [-90.0, 60.0]  # out beside the torso
    fit[:, J["r_elbow"]] = fit[:, J["r_shoulder"]] + [50.0, 10.0]  # out beside the torso
    fit[:, J["r_wrist"]] = fit[:, J["r_shoulder"]] + [-40.0, 60.0]  # inside it
    hid = hidden_joints(fit)
    assert hid[:, 0].tolist() == [[True, False]] * len(fit)
    assert hid[:, 1].tolist() == [[False, True]] * len(fit)
    out = fill_hidden(fit, j3)
    np.testing.assert_allclose(out[:, J["l_elbow"]], uv[:, J["l_elbow"]], atol=1e-6)
    np.testing.assert_array_equal(out[:, J["l_wrist"]], fit[:, J["l_wrist"]])
    np.testing.assert_allclose(out[:, ARM["r"][1:]], uv[:, ARM["r"][1:]], atol=1e-6)


def test_fill_hidden_leaves_frames_without_a_fit_empty():
    j3, uv = _front_pose(3)
    fit = uv.copy()
    fit[1] = np.nan
    out = fill_hidden(fit, j3)
    assert np.isnan(out[1]).all() and np.isfinite(out[[0, 2]]).all()


def test_solve_in_image_names_the_solves_limbs_as_the_fit_does():
    """The exact 3D of a turned walk with both limb pairs named the other way round in
    every third frame: drawn in the image, every joint lands on the fit's own."""
    j3, uv = _walk(9, yaw_deg=30.0)
    named = j3.copy()
    order = [0, 1, 2, 6, 7, 8, 3, 4, 5, 12, 13, 14, 9, 10, 11]
    named[::3] = j3[::3][:, order]
    np.testing.assert_allclose(solve_in_image(uv, named), uv, atol=1e-6)


def test_solve_hidden_keeps_a_consistent_pose_and_the_legs():
    """The walk's exact 2D is a pose the solve can take: the arms and hips it puts back
    stay within 2 % of the height of where they were, and the knees and ankles are the
    fit's."""
    _, uv = _walk(30)
    out = solve_hidden(uv, fps=30.0, frame_size=(640, 480))
    height = 200.0 * 1.75
    for joints in (ARM["l"] + ARM["r"], HIPS):
        assert np.median(np.linalg.norm(out[:, joints] - uv[:, joints], axis=-1)) < 0.02 * height
    np.testing.assert_array_equal(out[:, LOWER_LEGS], uv[:, LOWER_LEGS])


FOREARMS = {s: [J[f"{s}_elbow"], J[f"{s}_wrist"]] for s in "lr"}


def test_exchange_forearms_hangs_each_forearm_from_the_other_shoulder_in_those_frames():
    _, uv = _walk(4)
    out = exchange_forearms(uv, np.array([False, True, False, True]))
    np.testing.assert_array_equal(out[[0, 2]], uv[[0, 2]])
    np.testing.assert_array_equal(out[[1, 3]][:, FOREARMS["l"]], uv[[1, 3]][:, FOREARMS["r"]])
    np.testing.assert_array_equal(out[[1, 3]][:, FOREARMS["r"]], uv[[1, 3]][:, FOREARMS["l"]])
    np.testing.assert_array_equal(out[:, ARM["l"][0]], uv[:, ARM["l"][0]])  # shoulders stay


def test_arm_residual_is_zero_for_the_solves_own_pose_and_grows_with_a_wrong_hanging():
    j3, uv = _walk(6, yaw_deg=115.0)  # the shoulders apart in the image
    assert np.abs(arm_residual(j3, uv)).max() < 1e-9
    wrong = exchange_forearms(uv, np.ones(6, bool))
    assert (arm_residual(j3, wrong) > 0.05).all()  # body heights


def test_rehang_arms_hangs_a_planted_run_of_exchanged_forearms_back():
    """A turned walk (spread 0.4) whose forearms hang from the wrong shoulders in frames
    10-19 (the arms' identities swapped inside the torso): a solve that knows the body
    (here the true 3D, whatever it is given) fits the other hanging better there, and
    only there."""
    j3, uv = _walk(30, yaw_deg=115.0)
    planted = np.zeros(30, bool)
    planted[10:20] = True
    fit = exchange_forearms(uv, planted)
    calls = []

    def solve(j2):
        calls.append(j2)
        return j3

    out2, out3 = rehang_arms(fit, j3, solve, np.full(30, 0.4))
    np.testing.assert_allclose(out2, uv, atol=1e-9)
    assert out3 is j3 and len(calls) == 2  # the exchanged clip, then the mixed one
    # nearly edge-on (spread below REHANG_SPREAD) the shoulders coincide: left alone
    same2, same3 = rehang_arms(fit, j3, solve, np.full(30, REHANG_SPREAD - 0.1))
    assert same2 is fit and same3 is j3 and len(calls) == 2


def test_solve_hidden_hangs_the_forearms_back_with_the_real_solve():
    """The same planted run through the clip solve itself (``rehang=True``): the frames'
    elbows and wrists come back within 3 % of the height of their own shoulders' arms;
    without it (the default) they stay more than 5 % off."""
    _, uv = _walk(30, yaw_deg=115.0)
    planted = np.zeros(30, bool)
    planted[10:20] = True
    fit = exchange_forearms(uv, planted)
    height = 200.0 * 1.75
    spread = np.full(30, 0.4)
    plain = solve_hidden(fit, fps=30.0, frame_size=(640, 480), spread=spread)  # the default
    out = solve_hidden(fit, fps=30.0, frame_size=(640, 480), spread=spread, rehang=True)
    ends = FOREARMS["l"] + FOREARMS["r"]
    err = np.linalg.norm(out[planted][:, ends] - uv[planted][:, ends], axis=-1)
    assert np.median(err) < 0.03 * height
    assert np.median(np.linalg.norm(plain[planted][:, ends] - uv[planted][:, ends],
                                    axis=-1)) > 0.05 * height


def test_hidden_choices_are_checked_and_spelled_alike_in_the_commands():
    from vidcap.commands import convert as convert_cmd
    from vidcap.errors import UsageError
    from vidcap.video import hidden

    assert convert_cmd.HIDDEN_CHOICES == HIDDEN_CHOICES
    assert convert_cmd.POSE2D_HIDDEN == hidden.DEFAULT_HIDDEN == "fit"
    assert convert_cmd.CONVERT_HIDDEN == hidden.CONVERT_HIDDEN == "solve"
    for ok in HIDDEN_CHOICES:
        check_hidden(ok)
    with pytest.raises(UsageError, match="--hidden 'guess'"):
        check_hidden("guess")


def test_convert_and_pose2d_refuse_an_unknown_hidden_before_any_work(tmp_path, cli):
    from vidcap.errors import UsageError
    from vidcap.video import pipeline

    with pytest.raises(UsageError, match="--hidden"):
        pipeline.run(tmp_path / "nothing.mp4", hidden="guess")
    for command in (("pose2d", "-o", tmp_path / "p.npz"), ("convert", "-o", tmp_path / "o.bvh")):
        r = cli(command[0], tmp_path / "nothing.mp4", *command[1:], "--hidden", "guess")
        assert r.returncode == 2 and "--hidden" in r.stderr


def test_run_with_hidden_solve_changes_only_the_arms_shoulders_and_hips_of_its_2d(tmp_path):
    """``pipeline.run(hidden='solve')`` (``vidcap convert``'s default): the same fit, the
    same 3D, and in both 2D outputs only the shoulders, arms and hips may differ; with
    the per-segment lift nothing changes."""
    from vidcap.synth import make_motion, synth_clip
    from vidcap.video.pipeline import run

    video = tmp_path / "walk.mp4"
    synth_clip(video, tmp_path / "t.npz", make_motion("walk", n_frames=12), size=(160, 120),
               rng=np.random.default_rng(0))
    kw = {"progress": False, "jobs": 1, "cache_dir": tmp_path / "cache", "proportions": "seed"}
    fit, solved = run(video, hidden="fit", **kw), run(video, hidden="solve", **kw)
    np.testing.assert_array_equal(fit.lifted.joints3d, solved.lifted.joints3d)
    arms = ARM["l"] + ARM["r"]
    rest = [k for k in range(15) if k not in arms + HIPS]
    for a, b in ((fit.image_joints2d, solved.image_joints2d),
                 (fit.lifted.joints2d, solved.lifted.joints2d)):
        np.testing.assert_array_equal(a[:, rest], b[:, rest])
        assert not np.array_equal(a[:, arms], b[:, arms])
    seg = [run(video, hidden=h, lift="segment", **kw).image_joints2d for h in HIDDEN_CHOICES]
    np.testing.assert_array_equal(*seg)
