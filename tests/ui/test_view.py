"""``vidcap view``: offscreen screenshots compared with a small image cache (pyvista style).

Set ``VIDCAP_RESET_IMAGE_CACHE=1`` to rewrite the cached images after an intended change
(then look at them before committing).
"""

from __future__ import annotations

import csv
import os
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

pv = pytest.importorskip("pyvista")

from vidcap.ui import view as uiview  # noqa: E402

from vidcap.body import JOINT_NAMES, BodyModel  # noqa: E402
from vidcap.errors import InputFileError, UsageError  # noqa: E402
from vidcap.io.bvh import write_bvh  # noqa: E402
from vidcap.kinematics import Motion  # noqa: E402

CACHE = Path(__file__).parent / "image_cache"
SIZE = (240, 180)
#: pyvista's own tests fail above an error of 500 (``compare_images``, mean pixel difference
#: after a light blur); rendering differences between Mesa versions stay far below it.
THRESHOLD = 500.0


@pytest.fixture(autouse=True)
def _offscreen(monkeypatch):
    monkeypatch.setattr(pv, "OFF_SCREEN", True)


def _check(img: np.ndarray, name: str) -> None:
    cached = CACHE / f"{name}.png"
    if os.environ.get("VIDCAP_RESET_IMAGE_CACHE") or not cached.exists():
        if os.environ.get("CI") == "true" and not cached.exists():
            pytest.fail(f"{cached} is missing from the image cache")
        CACHE.mkdir(exist_ok=True)
        uiview._save_png(img, cached)
        return
    error = pv.compare_images(np.ascontiguousarray(img), cv2.imread(str(cached))[..., ::-1].copy())
    assert error < THRESHOLD, f"{name}: image error {error:.0f} >= {THRESHOLD} vs {cached}"


def sample_motion(n_frames: int = 4) -> Motion:
    """The body model's T-pose lowering its arms, bending the right knee and walking."""
    sk = BodyModel().skeleton()
    m = Motion.rest(sk, n_frames, fps=30.0)
    rot = m.rotations.copy()
    t = np.linspace(0, 1, n_frames)
    j = JOINT_NAMES.index
    rot[:, j("l_shoulder")] = Rotation.from_euler("z", (70 * t)[:, None], degrees=True).as_quat()
    rot[:, j("r_shoulder")] = Rotation.from_euler("z", (-40 * t)[:, None], degrees=True).as_quat()
    rot[:, j("r_elbow")] = Rotation.from_euler("y", (80 * t)[:, None], degrees=True).as_quat()
    rot[:, j("r_hip")] = Rotation.from_euler("x", (-30 * t)[:, None], degrees=True).as_quat()
    rot[:, j("r_knee")] = Rotation.from_euler("x", (60 * t)[:, None], degrees=True).as_quat()
    root = np.column_stack([0.1 * t, 0 * t, -0.5 * t])
    return Motion(sk, root, rot, 30.0)


@pytest.fixture
def sample_bvh(tmp_path) -> Path:
    path = tmp_path / "sample.bvh"
    write_bvh(path, sample_motion())
    return path


def test_bvh_screenshot_matches_cache(sample_bvh, tmp_path):
    out = tmp_path / "v.png"
    img = uiview.view(sample_bvh, screenshot=out, frame=3, window_size=SIZE)
    assert img.shape == (SIZE[1], SIZE[0], 3)
    assert out.is_file()
    _check(img, "bvh_frame3")


def test_frames_differ_and_skeleton_is_drawn(sample_bvh):
    scene = uiview.Scene(uiview.load_points(sample_bvh), window_size=SIZE, off_screen=True)
    try:
        a = scene.screenshot()
        scene.set_frame(3)
        b = scene.screenshot()
    finally:
        scene.plotter.close()
    bone = np.array(uiview.BONE_COLOUR) * 255
    near_bone = lambda im: (np.abs(im.astype(float) - bone).sum(axis=2) < 90).sum()  # noqa: E731
    assert near_bone(a) > 50 and near_bone(b) > 50  # the bones are on screen
    assert np.abs(a.astype(int) - b.astype(int)).sum(axis=2).astype(bool).mean() > 0.01


def test_motion_points_include_end_sites():
    m = sample_motion(2)
    pts = uiview.motion_points(m)
    assert pts.positions.shape == (2, 15 + len(m.skeleton.end_sites), 3)
    np.testing.assert_allclose(pts.positions[:, :15], m.positions())
    # every bone joins a joint to its child: its length is the rest offset's
    lengths = np.linalg.norm(pts.positions[0, pts.bones[:, 1]] - pts.positions[0, pts.bones[:, 0]],
                             axis=1)
    assert (lengths > 0.02).all()


def _write_c3d(path: Path, points_m: np.ndarray, labels, rate=100.0):
    ezc3d = pytest.importorskip("ezc3d")
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [rate]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = tuple(labels)
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    F, P, _ = points_m.shape
    data = np.ones((4, P, F))
    data[:3] = np.transpose(points_m * 1000.0, (2, 1, 0))
    c3d["data"]["points"] = data
    c3d.write(str(path))


def _zup(p):
    """Y-up body coordinates to a Z-up lab (x, -z, y)."""
    return np.stack([p[..., 0], -p[..., 2], p[..., 1]], axis=-1)


@pytest.fixture
def sample_c3d(tmp_path):
    rng = np.random.default_rng(3)
    joints = _zup(sample_motion(3).positions())  # (3, 15, 3)
    # two markers per joint, a few cm off the centre; one gap
    markers = np.concatenate([joints + rng.normal(0, 0.04, joints.shape) for _ in range(2)], 1)
    markers[1, 4] = np.nan
    labels = [f"M{i:02d}" for i in range(markers.shape[1])]
    path = tmp_path / "markers.c3d"
    _write_c3d(path, np.nan_to_num(markers), labels)
    centres = tmp_path / "centres.csv"
    with open(centres, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["frame", "time_s", "joint", "x_m", "y_m", "z_m"])
        for f in range(joints.shape[0]):
            for name, x in zip(JOINT_NAMES, joints[f], strict=True):
                w.writerow([f, f / 100.0, name, *x])
    return path, centres, joints


def test_c3d_reader_metres_and_gaps(sample_c3d):
    path, _, joints = sample_c3d
    pts = uiview.read_c3d_points(path)
    assert pts.positions.shape == (3, 30, 3) and pts.up == 2 and pts.fps == 100.0
    assert np.isnan(pts.positions[1, 4]).all()  # zeros written for the gap read back as NaN
    err = np.linalg.norm(pts.positions[0, :15] - joints[0], axis=1)
    assert 0.005 < np.median(err) < 0.2  # metres, markers a few cm off the centres


def test_centres_csv_and_bones(sample_c3d):
    _, centres, joints = sample_c3d
    pts = uiview.read_centres_csv(centres)
    assert pts.names == JOINT_NAMES
    np.testing.assert_allclose(pts.positions, joints)
    assert len(pts.bones) == 14 and pts.fps == pytest.approx(100.0)


def test_c3d_with_centres_screenshot_matches_cache(sample_c3d, tmp_path):
    path, centres, _ = sample_c3d
    img = uiview.view(path, screenshot=tmp_path / "c.png", centres=centres, frame=2,
                      window_size=SIZE)
    red = np.array(uiview.CENTRE_COLOUR) * 255
    assert ((np.abs(img.astype(float) - red).sum(axis=2) < 90).sum()) > 30
    _check(img, "c3d_centres_frame2")


def test_errors(tmp_path, sample_bvh):
    with pytest.raises(UsageError, match="frame 9"):
        uiview.view(sample_bvh, screenshot=tmp_path / "x.png", frame=9)
    with pytest.raises(UsageError, match=r"\.txt"):
        uiview.view(tmp_path / "notes.txt", screenshot=tmp_path / "x.png")
    with pytest.raises(InputFileError, match="missing.c3d"):
        uiview.view(tmp_path / "missing.c3d", screenshot=tmp_path / "x.png")
    bad = tmp_path / "bad.c3d"
    bad.write_bytes(b"not a c3d file at all" * 10)
    with pytest.raises(InputFileError, match="bad.c3d"):
        uiview.read_c3d_points(bad)
    badcsv = tmp_path / "c.csv"
    badcsv.write_text("a,b\n1,2\n")
    with pytest.raises(InputFileError, match="frame,time_s,joint"):
        uiview.read_centres_csv(badcsv)
    assert not (tmp_path / "x.png").exists()


def test_cli_view_screenshot(cli, sample_bvh, tmp_path):
    out = tmp_path / "cli.png"
    r = cli("view", sample_bvh, "--screenshot", out, "--frame", "-1", "--size", "240x180")
    assert r.returncode == 0, r.stderr
    assert out.is_file() and str(out) in r.stdout
    _check(cv2.imread(str(out))[..., ::-1], "bvh_frame3")
    r = cli("view", tmp_path / "nope.bvh", "--screenshot", out)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "nope.bvh" in r.stderr


def test_real_bvh_screenshot(shared_data, tmp_path):
    img = uiview.view(shared_data("motion/131_01.bvh"), screenshot=tmp_path / "r.png",
                      frame=0, window_size=SIZE)
    bone = np.array(uiview.BONE_COLOUR) * 255
    assert (np.abs(img.astype(float) - bone).sum(axis=2) < 90).sum() > 100


def test_missing_ui_extra_is_one_clear_line(monkeypatch):
    from vidcap.commands._ui import require

    monkeypatch.setitem(sys.modules, "trame", None)  # as if the extra were not installed
    with pytest.raises(UsageError, match=r"trame is not installed.*pip install 'vidcap\[ui\]'"):
        require("vidcap.ui.annotate", needs=("trame",))


def test_player_plays_in_real_time(sample_bvh):
    scene = uiview.Scene(uiview.load_points(sample_bvh), window_size=SIZE, off_screen=True)
    try:
        scene.add_player()
        scene.tick()
        assert scene.frame == 0  # not playing yet
        scene.toggle_play()
        t0 = scene._play_t0
        scene.tick(t0 + 2.0 / 30.0 + 1e-6)  # 30 fps clip: two frames later
        assert scene.frame == 2
        assert scene._slider.GetRepresentation().GetValue() == 2
        scene.tick(t0 + 5.0 / 30.0)  # wraps around the 4-frame clip
        assert scene.frame in (0, 1)
        scene.toggle_play()
        scene.tick(t0 + 10.0)
        assert scene.frame in (0, 1)
    finally:
        scene.plotter.close()


def test_cli_annotate_user_errors(cli, tmp_path):
    r = cli("annotate", tmp_path / "missing.mp4", "--no-browser")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "missing.mp4" in r.stderr
    r = cli("annotate", tmp_path / "missing.mp4", "--port", "70000")
    assert r.returncode == 2 and "--port" in r.stderr


@pytest.mark.parametrize("option", [("--camera", "2.5"), ("--camera", "1,2,95"),
                                    ("--cues", "skin"), ("--ensemble", "9")])
def test_cli_annotate_bad_fit_option(cli, tmp_path, option):
    # convert's fit options, checked before any work as convert checks them
    video = Path(__file__).resolve().parents[2] / "sample_videos" / "walk_side.mp4"
    r = cli("annotate", video, "--no-browser", "--cache-dir", tmp_path / "cache", *option)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and option[0] in r.stderr
    assert not (tmp_path / "cache").exists()


def test_cli_annotate_takes_converts_background(cli, tmp_path):
    # the plate convert was given, frames of the video here: a range past its end is
    # the same one-line error convert gives, so the option reached the pipeline
    video = Path(__file__).resolve().parents[2] / "sample_videos" / "walk_side.mp4"
    r = cli("annotate", video, "--no-browser", "--cache-dir", tmp_path / "cache",
            "--background", "900:")
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert "--background 900: holds no frame of the video" in r.stderr
