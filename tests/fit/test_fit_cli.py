"""``vidcap pose2d`` end to end on a tiny rendered clip."""

import numpy as np
import pytest

from vidcap.video.fit.pose2d import Pose2D


def _clip(tmp_path):
    from vidcap.synth import make_motion, synth_clip

    video, truth = tmp_path / "clip.mp4", tmp_path / "truth.npz"
    motion = make_motion("walk", n_frames=4)
    synth_clip(video, truth, motion, size=(160, 120), rng=np.random.default_rng(0))
    masks = tmp_path / "masks.npz"
    d = np.load(truth)
    np.savez(masks, masks=d["masks"])
    return video, masks, d


def test_pose2d_cli_writes_npz(tmp_path, cli):
    video, masks, truth = _clip(tmp_path)
    out = tmp_path / "pose2d.npz"
    r = cli("pose2d", video, "--masks", masks, "-o", out)
    assert r.returncode == 0, r.stderr
    pose = Pose2D.load(out)
    assert pose.joints2d.shape == (4, 15, 2)
    assert pose.tracked
    hpx = np.ptp(truth["joints2d"][0, :, 1])
    err = np.linalg.norm(pose.joints2d - truth["joints2d"], axis=-1)
    # pelvis and head (no left/right ambiguity) within a few percent of the height
    assert np.median(err[:, :3]) < 0.05 * hpx
    r = cli("pose2d", video, "--masks", masks, "-o", out, "--per-frame")
    assert r.returncode == 0 and not Pose2D.load(out).tracked


def test_pose2d_cli_errors(tmp_path, cli):
    video, masks, _ = _clip(tmp_path)
    bad = tmp_path / "bad.npz"
    np.savez(bad, other=np.zeros(3))
    r = cli("pose2d", video, "--masks", bad, "-o", tmp_path / "o.npz")
    assert r.returncode == 2 and "bad.npz" in r.stderr and "masks" in r.stderr
    small = tmp_path / "small.npz"
    np.savez(small, masks=np.ones((4, 10, 10), bool))
    r = cli("pose2d", video, "--masks", small, "-o", tmp_path / "o.npz")
    assert r.returncode == 2 and "small.npz" in r.stderr
    assert not (tmp_path / "o.npz").exists()


def test_pose2d_cli_without_masks_extracts_silhouettes(tmp_path, cli):
    """Without --masks the silhouettes come from the video (as ``vidcap silhouettes``)."""
    from vidcap.synth import make_motion, synth_clip

    video, truth = tmp_path / "walk.mp4", tmp_path / "truth.npz"
    synth_clip(video, truth, make_motion("walk", n_frames=30), size=(160, 120),
               rng=np.random.default_rng(1))
    out = tmp_path / "pose2d.npz"
    r = cli("pose2d", video, "-o", out)
    assert r.returncode == 0, r.stderr
    pose = Pose2D.load(out)
    d = np.load(truth)
    assert pose.joints2d.shape == (30, 15, 2)
    found = np.isfinite(pose.joints2d).all(axis=(1, 2))
    assert found.mean() > 0.8  # a silhouette was extracted in (nearly) every frame
    hpx = np.ptp(d["joints2d"][0, :, 1])
    err = np.linalg.norm(pose.joints2d[found] - d["joints2d"][found], axis=-1)
    assert np.median(err[:, :3]) < 0.08 * hpx  # pelvis, neck, head top


def test_pose2d_cli_cues_option(tmp_path, cli):
    video, masks, _ = _clip(tmp_path)
    out = tmp_path / "pose2d.npz"
    for cues in ("outline", "all"):
        r = cli("pose2d", video, "--masks", masks, "-o", out, "--cues", cues)
        assert r.returncode == 0, r.stderr
        assert Pose2D.load(out).joints2d.shape == (4, 15, 2)
    out.unlink()
    r = cli("pose2d", video, "--masks", masks, "-o", out, "--cues", "colour")
    assert r.returncode == 2 and not out.exists()
    assert r.stderr.strip().count("\n") == 0  # one line, no usage text, no traceback
    assert r.stderr.startswith("vidcap: error:") and "--cues 'colour'" in r.stderr
    assert "all" in r.stderr and "outline" in r.stderr


def test_convert_cli_bad_cues_is_a_one_line_error(tmp_path, cli):
    video, _, _ = _clip(tmp_path)
    r = cli("convert", video, "-o", tmp_path / "o.bvh", "--cues", "skin")
    assert r.returncode == 2 and not (tmp_path / "o.bvh").exists()
    assert r.stderr.strip().count("\n") == 0 and "--cues 'skin'" in r.stderr


def test_cues_default_and_pose_cache_key(monkeypatch):
    from vidcap.commands import convert as convert_cmd
    from vidcap.video import pipeline

    assert convert_cmd.DEFAULT_CUES == pipeline.DEFAULT_CUES
    assert convert_cmd.DEFAULT_PROPORTIONS == pipeline.DEFAULT_PROPORTIONS
    # a fit with another body is not read back as the seed's; the seed's keeps its key
    from vidcap.video.fit.proportions import HUMAN, fit_keywords

    seed_key = pipeline._pose_key("sil", [(0, 0, 100)], "outline")
    assert pipeline._pose_key("sil", [(0, 0, 100)], "outline", {}) == seed_key
    assert pipeline._pose_key("sil", [(0, 0, 100)], "outline", fit_keywords(HUMAN)) != seed_key
    # a body whose shoulder joints alone sit elsewhere is another fit
    dropped = {**HUMAN, "shoulder_drop": 0.03}
    assert pipeline._pose_key("sil", [(0, 0, 100)], "outline", fit_keywords(dropped)) \
        != pipeline._pose_key("sil", [(0, 0, 100)], "outline", fit_keywords(HUMAN))
    keys = {cues: pipeline._pose_key("sil", [(0, 0, 100)], cues) for cues in ("all", "outline")}
    assert keys["all"] != keys["outline"]  # a fit with cues is not read back as one without
    # nor is a cache written by an older fit read back as the new fit's
    monkeypatch.setattr(pipeline, "_POSE_VERSION", pipeline._POSE_VERSION - 1)
    assert pipeline._pose_key("sil", [(0, 0, 100)], "outline") != seed_key
    with pytest.raises(ValueError, match="cues"):
        pipeline.run("nothing.mp4", cues="skin")


def test_pose2d_cli_human_proportions(tmp_path, cli):
    """``--proportions human``: the fit uses a real adult's proportions, written as
    fractions of the stature (the upper arm, from the shoulder joint 0.022 below the
    top of the shoulder, longer than the seed's, the lower arm shorter; head top to
    ankles 0.961 of it: the feet below)."""
    video, masks, _ = _clip(tmp_path)
    out = tmp_path / "pose2d.npz"
    r = cli("pose2d", video, "--masks", masks, "-o", out, "--proportions", "human")
    assert r.returncode == 0, r.stderr
    assert "body proportions" in r.stdout
    d = np.load(out)
    from vidcap.body import SEGMENT_INDEX

    lengths = d["body_lengths"]
    assert lengths[SEGMENT_INDEX["l_upper_arm"]] == pytest.approx(0.166, abs=1e-3)
    assert float(d["body_shoulder_drop"]) == pytest.approx(0.022, abs=1e-4)
    assert lengths[SEGMENT_INDEX["l_lower_arm"]] == pytest.approx(0.145, abs=1e-3)
    legs = lengths[SEGMENT_INDEX["l_upper_leg"]] + lengths[SEGMENT_INDEX["l_lower_leg"]]
    assert legs + lengths[SEGMENT_INDEX["torso"]] + lengths[SEGMENT_INDEX["head"]] \
        == pytest.approx(0.961, abs=1e-3)
    assert np.isfinite(Pose2D.load(out).joints2d).all()


def test_pose2d_cli_hidden_solve_changes_only_arms_shoulders_and_hips(tmp_path, cli):
    """``--hidden solve`` takes the shoulders, the hips and the hidden arms from the clip
    solve (vidcap.video.hidden.fill_hidden); the head, neck, pelvis, knees and ankles stay
    as fitted."""
    from vidcap.body import JOINT_INDEX as J

    video, masks, _ = _clip(tmp_path)
    fit, solved = tmp_path / "fit.npz", tmp_path / "solved.npz"
    assert cli("pose2d", video, "--masks", masks, "-o", fit).returncode == 0
    r = cli("pose2d", video, "--masks", masks, "-o", solved, "--hidden", "solve")
    assert r.returncode == 0, r.stderr
    a, b = Pose2D.load(fit).joints2d, Pose2D.load(solved).joints2d
    arms = [J[f"{s}_{p}"] for s in "lr" for p in ("shoulder", "elbow", "wrist")]
    hips = [J["l_hip"], J["r_hip"]]
    rest = [k for k in range(15) if k not in arms + hips]
    np.testing.assert_array_equal(a[:, rest], b[:, rest])
    assert np.isfinite(b).all() and not np.array_equal(a[:, arms], b[:, arms])
    assert not np.array_equal(a[:, hips], b[:, hips])


def test_pose2d_cli_without_masks_gives_the_plates_notice(tmp_path, cli):
    """A person who stands still over part of the frame: ``vidcap pose2d`` (computing the
    silhouettes itself) prints the plate's notice as ``vidcap silhouettes`` does."""
    from tests._synthframes import clip
    from vidcap.io.video import write_video

    frames, _ = clip(40, 96, 128, rng=np.random.default_rng(7), walk=False, noise=1.0)
    video = tmp_path / "still.mkv"
    write_video(video, frames, 25, crf=12)
    shown = cli("silhouettes", video, "-o", tmp_path / "m.npz")
    fitted = cli("pose2d", video, "-o", tmp_path / "p.npz")
    assert shown.returncode == 0 and fitted.returncode == 0, fitted.stderr
    notice = [line for line in shown.stderr.splitlines()
              if line.startswith("notice: the background")]
    assert notice, shown.stderr
    assert notice[0] in fitted.stderr.splitlines()


def test_pose2d_cli_ensemble_option(tmp_path, cli):
    """``--ensemble 1`` is the one fit of the default, to the bit; ``--ensemble 3`` (the
    median of fits on the masks as given, eroded and dilated) moves joints but stays as
    near the truth."""
    video, masks, truth = _clip(tmp_path)
    poses = {}
    for n in (None, "1", "3"):
        out = tmp_path / f"pose{n}.npz"
        r = cli("pose2d", video, "--masks", masks, "-o", out,
                *(() if n is None else ("--ensemble", n)))
        assert r.returncode == 0, r.stderr
        poses[n] = Pose2D.load(out).joints2d
    np.testing.assert_array_equal(poses["1"], poses[None])
    assert poses["3"].shape == (4, 15, 2) and np.isfinite(poses["3"]).all()
    assert not np.array_equal(poses["3"], poses["1"])
    hpx = np.ptp(truth["joints2d"][0, :, 1])
    err = {n: np.linalg.norm(poses[n] - truth["joints2d"], axis=-1) for n in ("1", "3")}
    assert np.median(err["3"][:, :3]) < 0.05 * hpx  # pelvis, neck, head top
    assert np.mean(err["3"]) < np.mean(err["1"]) + 0.02 * hpx


@pytest.mark.parametrize("command,bad", [("pose2d", "0"), ("pose2d", "6"), ("pose2d", "2.5"),
                                         ("convert", "x")])
def test_bad_ensemble_is_a_one_line_error(tmp_path, cli, command, bad):
    video, masks, _ = _clip(tmp_path)
    out = tmp_path / ("o.npz" if command == "pose2d" else "o.bvh")
    extra = ("--masks", masks) if command == "pose2d" else ()
    r = cli(command, video, *extra, "-o", out, "--ensemble", bad)
    assert r.returncode == 2 and not out.exists()
    assert r.stderr.strip().count("\n") == 0  # one line, no usage text, no traceback
    assert r.stderr.startswith("vidcap: error: --ensemble") and f"got {bad}" in r.stderr
    assert "1 to 5" in r.stderr


def test_ensemble_option_checks_and_pose_cache_key():
    """The option's values; a fit of several members has a cache key of its own, one
    member keeps the key of the fit before the option (for every body)."""
    from vidcap.api import check_ensemble_option
    from vidcap.commands import convert as convert_cmd
    from vidcap.errors import UsageError
    from vidcap.video import pipeline
    from vidcap.video.fit.ensemble import MEMBERS
    from vidcap.video.fitbody import fit_keywords_for

    assert convert_cmd.ENSEMBLE_MAX == len(MEMBERS)
    assert [check_ensemble_option(v) for v in (1, "2", " 5 ", np.int64(3))] == [1, 2, 5, 3]
    for bad in (0, 6, "2.5", 2.0, "", None, True):
        with pytest.raises(UsageError, match="--ensemble"):
            check_ensemble_option(bad)
    chunks = [(0, 0, 70), (60, 70, 140)]
    for proportions in ("seed", "human"):
        one = fit_keywords_for(proportions)
        assert fit_keywords_for(proportions, 1) == one and "ensemble" not in one
        for cues in ("outline", "all"):
            key = pipeline._pose_key("sil", chunks, cues, one)
            assert pipeline._pose_key("sil", chunks, cues, {**one, "ensemble": 1}) == key
            keys = {pipeline._pose_key("sil", chunks, cues, fit_keywords_for(proportions, n))
                    for n in (2, 3, 5)}
            assert len(keys) == 3 and key not in keys
    # the seed's body, one fit: the key of before the option, {} or None
    assert pipeline._pose_key("sil", chunks, "outline", {"ensemble": 1}) == \
        pipeline._pose_key("sil", chunks, "outline")
    # 'auto' replaces its first fit by one with the estimate: only that one is an ensemble
    assert fit_keywords_for("auto", 3) == {}
    # a camera's perspective: the known bodies warped (a key of their own), the seed's
    # body without one keeps the key of before; the estimated one is fitted as measured
    assert fit_keywords_for("seed", 1, 0.0) == {}
    assert "body" in fit_keywords_for("seed", 1, 0.3)
    assert fit_keywords_for("human", 1, 0.3) != fit_keywords_for("human")
    assert fit_keywords_for("auto", 1, 0.3) == {}
    with pytest.raises(ValueError, match="ensemble"):
        pipeline.run("nothing.mp4", ensemble=6)


def test_pose2d_hidden_solve_reads_the_height_to_the_ankles(tmp_path, monkeypatch):
    """With a body that has feet (``--proportions human``, the default) the 3D solve is
    given the model's height without them, as ``vidcap convert`` gives it (the fitted
    model is drawn head top to soles)."""
    import vidcap.video.hidden as hidden
    from vidcap.cli import main
    from vidcap.video.fit.proportions import fit_keywords, human_proportions

    video, masks, _ = _clip(tmp_path)
    seen = {}

    def spy(joints2d, **kw):
        seen["model_height"] = kw["model_height"]
        return joints2d

    monkeypatch.setattr(hidden, "solve_hidden", spy)
    out = tmp_path / "solved.npz"
    assert main(["pose2d", str(video), "--masks", str(masks), "-o", str(out),
                 "--hidden", "solve"]) == 0
    foot = fit_keywords(human_proportions().factors)["foot"]
    assert 0.0 < foot < 0.1
    fitted = Pose2D.load(out).model_height
    np.testing.assert_allclose(seen["model_height"], fitted * (1.0 - foot))


@pytest.mark.parametrize("command,bad,says", [
    ("pose2d", "2,abc", "HEIGHT,DISTANCE"), ("pose2d", "1,2,3,4", "HEIGHT,DISTANCE"),
    ("convert", "2,0", "positive"), ("convert", "5,1,-60", "not in front"),
    ("convert", "2,3,95", "89 degrees"), ("pose2d", "1.75,0.01", "too near"),
    ("convert", "above", "or auto")])
def test_bad_camera_is_a_one_line_error(tmp_path, cli, command, bad, says):
    video, masks, _ = _clip(tmp_path)
    out = tmp_path / ("o.npz" if command == "pose2d" else "o.bvh")
    extra = ("--masks", masks) if command == "pose2d" else ()
    r = cli(command, video, *extra, "-o", out, "--camera", bad)
    assert r.returncode == 2 and not out.exists()
    assert r.stderr.strip().count("\n") == 0, r.stderr  # one line, no traceback
    assert r.stderr.startswith("vidcap: error: --camera") and says in r.stderr


def test_pose2d_camera_draws_the_head_larger(tmp_path, cli):
    """``--camera 2.5,3`` (a camera above, looking down: k ~ 0.35) fits a body whose
    head is drawn larger and legs shorter: the joints move; with ``--hidden solve`` the
    solve reads them un-warped and its joints come back warped, finite."""
    video, masks, _ = _clip(tmp_path)
    poses = {}
    for name, extra in (("plain", ()), ("cam", ("--camera", "2.5,3")),
                        ("cam_solve", ("--camera", "2.5,3", "--hidden", "solve"))):
        out = tmp_path / f"{name}.npz"
        r = cli("pose2d", video, "--masks", masks, "-o", out, *extra)
        assert r.returncode == 0, r.stderr
        poses[name] = Pose2D.load(out)
    from vidcap.body import JOINT_INDEX

    def head_share(p):  # neck's depth below the head top over the ankles' depth
        j = p.joints2d
        ankle = j[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 1].mean(1)
        top = j[:, JOINT_INDEX["head_top"], 1]
        return np.median((j[:, JOINT_INDEX["neck"], 1] - top) / (ankle - top))

    assert head_share(poses["cam"]) > 1.1 * head_share(poses["plain"])
    assert np.isfinite(poses["cam_solve"].joints2d).all()


def test_pose2d_auto_proportions_with_a_camera_hands_on_the_unwarped_body(tmp_path, cli):
    """``--proportions auto --camera``: the body is measured on the image (a camera
    above draws the head larger and the legs shorter), so the lengths written are the
    measurement un-warped for the camera, as ``vidcap convert`` hands them to the 3D;
    without a camera they are the measurement itself."""
    from vidcap.video.fit.perspective import camera_perspective
    from vidcap.video.fit.proportions import estimate_proportions
    from vidcap.video.fitbody import unwarped_estimate

    video, masks, _ = _clip(tmp_path)
    lengths = {}
    for name, extra in (("plain", ()), ("cam", ("--camera", "2.5,3"))):
        out = tmp_path / f"{name}.npz"
        r = cli("pose2d", video, "--masks", masks, "-o", out, "--proportions", "auto",
                *extra)
        assert r.returncode == 0, r.stderr
        lengths[name] = np.load(out)["body_lengths"]
    measured = estimate_proportions(np.load(masks)["masks"])
    assert lengths["plain"] == pytest.approx(measured.body(1.0).segment_lengths())
    k = camera_perspective((2.5, 3.0), 1.75)
    flat = unwarped_estimate(measured, k).body(1.0).segment_lengths()
    assert lengths["cam"] == pytest.approx(flat)
    assert not np.allclose(lengths["cam"], lengths["plain"], rtol=1e-3)


def test_pose2d_camera_auto_reads_the_room(tmp_path, cli):
    """``--camera auto`` with masks given: the plate is estimated from the video for its
    verticals (meeting far below: a camera looking down), stderr says what k they give,
    and the body is drawn warped (the neck lower under a larger head) as with a given
    camera."""
    from tests._synthframes import room_with_verticals
    from vidcap.body import JOINT_INDEX
    from vidcap.synth import make_motion, synth_clip

    video, truth = tmp_path / "clip.mp4", tmp_path / "truth.npz"
    room = room_with_verticals(240, 320, 1200.0, np.random.default_rng(0))
    synth_clip(video, truth, make_motion("walk", n_frames=20), size=(320, 240),
               rng=np.random.default_rng(0), background=room)
    masks = tmp_path / "masks.npz"
    np.savez(masks, masks=np.load(truth)["masks"])
    drops = {}
    for name, extra in (("plain", ()), ("auto", ("--camera", "auto"))):
        out = tmp_path / f"{name}.npz"
        r = cli("pose2d", video, "--masks", masks, "-o", out, *extra)
        assert r.returncode == 0, r.stderr
        assert ("camera perspective" in r.stderr) == (name == "auto")
        j = np.load(out)["joints2d"]
        drops[name] = np.median(j[:, JOINT_INDEX["neck"], 1] - j[:, JOINT_INDEX["head_top"], 1])
    assert "k = 0." in r.stderr
    assert drops["auto"] > 1.05 * drops["plain"]
