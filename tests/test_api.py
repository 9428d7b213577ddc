"""The Python API (vidcap.convert, vidcap.joints) against the CLI it mirrors."""

from __future__ import annotations

import numpy as np
import pytest

import vidcap
from tests.conftest import REPO, run_cli
from vidcap.body import JOINT_NAMES
from vidcap.errors import C3DError, UsageError, VideoError
from vidcap.io.bvh import read_bvh
from vidcap.io.gltf import read_gltf

WALK = REPO / "sample_videos" / "walk_side.mp4"


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    """walk_side by the API, and by the CLI with --save (no cache: two real runs)."""
    d = tmp_path_factory.mktemp("api")
    r = run_cli("convert", WALK, "-o", d / "cli.bvh", "--save", d / "cli.npz", "--no-cache",
                "--quiet")
    assert r.returncode == 0, r.stderr
    return vidcap.convert(WALK), d


@pytest.mark.slow
def test_convert_gives_the_clis_motion(walk):
    m, d = walk
    saved = np.load(d / "cli.npz")
    F = saved["joints3d"].shape[0]
    assert m.joints3d.shape == (F, 15, 3) and m.joint_names == JOINT_NAMES
    np.testing.assert_allclose(m.joints3d, saved["bvh_joints3d"], atol=1e-9)
    np.testing.assert_allclose(m.frame_times, saved["frame_times"])
    assert m.fps == pytest.approx(float(saved["fps"]))
    assert isinstance(m.notices, list)
    # the joints stand on the floor and are about the subject's height tall
    assert m.joints3d[..., 1].max() - m.joints3d[..., 1].min() == pytest.approx(1.75, abs=0.2)


@pytest.mark.slow
def test_saved_files_match_the_clis(walk, tmp_path):
    m, d = walk
    assert m.save(tmp_path / "a.bvh") == [tmp_path / "a.bvh"]
    ours, cli = read_bvh(tmp_path / "a.bvh"), read_bvh(d / "cli.bvh")
    np.testing.assert_allclose(ours.positions(), cli.positions(), atol=1e-5)
    files = m.save(tmp_path / "a.gltf", rig="humanik")
    assert files == [tmp_path / "a.gltf", tmp_path / "a.bin"]
    g = read_gltf(files[0])
    assert g.joint_names[0] == "Hips" and len(g.times) == m.joints3d.shape[0]
    m.save(tmp_path / "a.npz")
    np.testing.assert_array_equal(np.load(tmp_path / "a.npz")["bvh_joints3d"], m.joints3d)
    with pytest.raises(UsageError, match="unknown rig"):
        m.save(tmp_path / "b.bvh", rig="unreal")
    assert not (tmp_path / "b.bvh").exists()


def test_convert_raises_the_clis_errors(tmp_path):
    with pytest.raises(VideoError):
        vidcap.convert(tmp_path / "missing.mp4")
    for kw, match in (({"height": -1.0}, "--height"), ({"jobs": 0}, "--jobs"),
                      ({"view": "sideways"}, "unknown view"), ({"ensemble": 6}, "--ensemble"),
                      ({"ensemble": 2.5}, "--ensemble"), ({"camera": (2.0, 0.0)}, "--camera"),
                      ({"camera": "2.5"}, "--camera")):
        with pytest.raises(UsageError, match=match):
            vidcap.convert(WALK, **kw)


def test_joints_gives_the_clis_centres(shared_data, tmp_path):
    c3d = shared_data("c3d/07_01.c3d")
    r = run_cli("joints", c3d, "--centres", tmp_path / "c.csv", timeout=180)
    assert r.returncode == 0, r.stderr
    j = vidcap.joints(c3d)
    F, J = j.centres.shape[:2]
    assert j.centres.shape == (316, J, 3) and "l_knee" in j.joint_names
    rows = np.genfromtxt(tmp_path / "c.csv", delimiter=",", skip_header=1,
                         usecols=(3, 4, 5)).reshape(F, J, 3)
    np.testing.assert_allclose(rows, j.centres, atol=1e-6)
    files = j.save(tmp_path / "j.glb")
    g = read_gltf(files[0])
    assert set(j.joint_names) <= set(g.joint_names) and len(g.times) == F
    with pytest.raises(C3DError):
        vidcap.joints(tmp_path / "c.csv")
