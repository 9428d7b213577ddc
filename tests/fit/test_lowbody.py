"""The scale of a body seated for seconds (vidcap.video.fit.lowbody)."""

from __future__ import annotations

import numpy as np
import pytest

from vidcap.synth import make_motion, render_clip
from vidcap.video.fit.lowbody import FACTORS, GAIN, _peak, window_factor
from vidcap.video.fit.pose2d import fit_sequence


def _scores(peak: float, n: int, top: float = 0.9) -> np.ndarray:
    """S of ``n`` sample frames at :data:`FACTORS`, peaking at ``peak``."""
    f = np.asarray(FACTORS)
    return np.tile(top - 2.0 * (f - peak) ** 2, (n, 1))


def test_peak_between_the_probed_factors():
    f = np.asarray(FACTORS)
    assert _peak(f, -(f - 1.27) ** 2) == pytest.approx(1.27, abs=1e-9)
    assert _peak(f, -(f - 0.8) ** 2) == FACTORS[0]  # at an end: the end itself


def test_window_factor_reads_a_seated_sample_and_leaves_a_standing_one():
    assert window_factor(_scores(1.27, 6)) == pytest.approx(1.27, abs=1e-6)
    assert window_factor(_scores(1.0, 6)) is None
    # larger by less than GAIN: not called larger
    near = _scores(1.0, 6)
    near[:, 1] = near[:, 0] + 0.5 * GAIN
    assert window_factor(near) is None
    # two frames of six call it larger: under the share
    one = _scores(1.0, 6)
    one[:2] = _scores(1.3, 2)
    assert window_factor(one) is None
    two = _scores(1.0, 6)
    two[:3] = _scores(1.3, 3)
    assert window_factor(two) == pytest.approx(1.3, abs=1e-6)


def _render(name: str, yaw: float, frames: int):
    motion = make_motion(name, n_frames=frames, rng=np.random.default_rng(3))
    video, truth = render_clip(motion, yaw_deg=yaw, size=(320, 240), noise=0.0,
                               rng=np.random.default_rng(0))
    stature = 1.75 * np.linalg.norm(truth["camera"][0, :3])  # px, the camera's scale
    return video, truth["masks"], truth["joints2d"], stature


def _pck(joints, truth, stature) -> float:
    d = np.linalg.norm(joints - truth, axis=-1)
    flip = joints.copy()  # image-side names: match each pair either way
    for a, b in ((3, 6), (4, 7), (5, 8), (9, 12), (10, 13), (11, 14)):
        flip[:, [a, b]] = flip[:, [b, a]]
    d = np.minimum(d, np.linalg.norm(flip - truth, axis=-1))
    return float(np.mean(d / stature <= 0.05))


def test_a_seated_body_is_fitted_at_its_standing_height():
    _, masks, truth, stature = _render("sit", 45.0, 30)
    plain = fit_sequence(masks, cues="outline")  # off by default
    probed = fit_sequence(masks, cues="outline", low_body=True)
    # the silhouettes' height is ~0.8 of the standing height; the probe finds it
    assert np.nanmedian(plain.model_height) / stature < 0.85
    assert abs(np.nanmedian(probed.model_height) / stature - 1.0) < 0.06
    assert _pck(probed.joints2d, truth, stature) > _pck(plain.joints2d, truth, stature) + 0.15


def test_a_standing_body_costs_nothing():
    _, masks, _, _ = _render("jacks", 0.0, 20)
    plain = fit_sequence(masks, cues="outline")
    probed = fit_sequence(masks, cues="outline", low_body=True)
    np.testing.assert_array_equal(probed.joints2d, plain.joints2d)


def test_pose2d_seated_option(tmp_path, cli):
    from vidcap.synth import synth_clip

    video, truth = tmp_path / "sit.mp4", tmp_path / "sit_truth.npz"
    synth_clip(video, truth, make_motion("sit", n_frames=24, rng=np.random.default_rng(3)),
               size=(320, 240), yaw_deg=45.0, rng=np.random.default_rng(0),
               show_progress=False)
    with np.load(truth) as t:
        stature = 1.75 * np.linalg.norm(t["camera"][0, :3])
    ratio = {}
    for flag in ((), ("--seated",)):
        out = tmp_path / f"pose{len(flag)}.npz"
        r = cli("pose2d", video, "--masks", truth, "-o", out, "--proportions", "seed",
                "--cues", "outline", *flag)
        assert r.returncode == 0, r.stderr
        with np.load(out) as p:
            ratio[flag] = np.nanmedian(p["model_height"]) / stature
    assert ratio[()] < 0.85 and ratio[("--seated",)] > 0.92


def test_the_stage_cache_keys_the_seated_fit_apart():
    from vidcap.video.pipeline import _pose_key

    plain = _pose_key("sil", [(0, 30)], "outline", {})
    assert _pose_key("sil", [(0, 30)], "outline", {"low_body": True}) != plain
    assert _pose_key("sil", [(0, 30)], "outline", {"low_body": False}) == plain
