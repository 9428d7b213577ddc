"""``vidcap pose2d`` end to end on a tiny rendered clip."""

import numpy as np

from vidcap.fit.pose2d import Pose2D


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


def test_pose2d_cli_without_masks_needs_silhouettes(tmp_path, cli):
    import importlib.util

    if importlib.util.find_spec("vidcap.silhouette") is not None:
        import pytest

        pytest.skip("silhouette extraction is available: covered by its own tests")
    video, _, _ = _clip(tmp_path)
    r = cli("pose2d", video, "-o", tmp_path / "o.npz")
    assert r.returncode == 2 and "--masks" in r.stderr
