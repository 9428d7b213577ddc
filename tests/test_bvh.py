"""BVH and ASF/AMC reading, BVH writing, forward kinematics."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from vidcap.body import BodyModel
from vidcap.errors import MotionFileError
from vidcap.io.asf import read_asf_amc
from vidcap.io.bvh import bvh_text, parse_bvh, read_bvh, write_bvh
from vidcap.kinematics import Motion


def _random_motion(n=40, seed=1):
    rng = np.random.default_rng(seed)
    sk = BodyModel(height=1.7).skeleton()
    # Smooth random rotations that pass through large angles (tests unwrapping).
    t = np.linspace(0, 1, n)[:, None, None]
    axes = rng.normal(size=(1, sk.n_joints, 3))
    rotvec = axes * (np.sin(2 * np.pi * t) * 1.5 + 3.5 * t)
    rot = Rotation.from_rotvec(rotvec.reshape(-1, 3)).as_quat().reshape(n, sk.n_joints, 4)
    root = np.cumsum(rng.normal(scale=0.02, size=(n, 3)), axis=0) + [0, 0.9, 0]
    return Motion(sk, root, rot, fps=30)


def test_write_read_round_trip_preserves_world_positions(tmp_path):
    m = _random_motion()
    write_bvh(tmp_path / "m.bvh", m)
    back = read_bvh(tmp_path / "m.bvh", units="m")
    assert back.skeleton.joint_names == m.skeleton.joint_names
    assert back.n_frames == m.n_frames and back.fps == pytest.approx(30, rel=1e-6)
    np.testing.assert_allclose(back.positions(), m.positions(), atol=1e-5)


def test_written_angles_are_unwrapped_without_360_jumps(tmp_path):
    m = _random_motion(n=200)
    text = bvh_text(m)
    data = np.array(text.split("Frame Time:")[1].split()[1:], float).reshape(200, -1)
    angles = data[:, 3:]
    assert np.abs(np.diff(angles, axis=0)).max() < 90


def test_written_header_follows_the_conventions(tmp_path):
    m = _random_motion(n=3)
    text = bvh_text(m)
    lines = [s.strip() for s in text.splitlines()]
    assert lines[1] == "ROOT pelvis"
    assert lines[3] == "OFFSET 0.000000 0.000000 0.000000"
    assert lines[4] == "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"
    assert lines.count("CHANNELS 3 Zrotation Xrotation Yrotation") == 14
    assert f"Frame Time: {1 / 30:.8f}" in lines
    ends = [lines[i + 2] for i, s in enumerate(lines) if s == "End Site"]
    assert len(ends) == 5 and all(e != "OFFSET 0.000000 0.000000 0.000000" for e in ends)


def test_rotation_channel_order_is_intrinsic_zxy():
    text = """HIERARCHY
ROOT a
{
 OFFSET 0 0 0
 CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
 JOINT b
 {
  OFFSET 0 1 0
  CHANNELS 3 Zrotation Xrotation Yrotation
  End Site
  {
   OFFSET 0 1 0
  }
 }
}
MOTION
Frames: 1
Frame Time: 0.1
0 0 0 90 0 0 0 0 0
"""
    m = parse_bvh(text, units=1.0)
    # Root rotated 90 degrees about Z: the child at +Y moves to -X.
    np.testing.assert_allclose(m.positions()[0, 1], [-1, 0, 0], atol=1e-12)


def _upright_checks(pos, ends, names, foot_names, head_name):
    allp = np.concatenate([pos[0], np.array([e[0] for e in ends.values()])])
    lowest = allp[:, 1].min()
    height = allp[:, 1].max() - lowest
    head = ends[head_name][0, 1] if head_name in ends else pos[0, names.index(head_name), 1]
    assert head == pytest.approx(allp[:, 1].max(), abs=0.05)  # the head is on top
    feet = [pos[0, names.index(f), 1] for f in foot_names]
    assert all(f - lowest < 0.1 for f in feet), feet
    return height


def test_cmu_bvh_reads_as_an_upright_figure(shared_data):
    m = read_bvh(shared_data("motion/131_01.bvh"))
    assert (m.n_frames, m.skeleton.n_joints) == (994, 31)
    assert m.fps == pytest.approx(120, rel=1e-4)
    names = m.skeleton.joint_names
    h = _upright_checks(m.positions(), m.end_site_positions(), names,
                        ["LeftToe", "RightToe"], "Head")
    # CMU's BVH conversion ends the head at the base of the crown, so the figure
    # measures ~1.39 m joint-to-joint for a subject whose legs say ~1.7 m.
    assert 1.3 < h < 2.0


def test_cmu_asf_amc_reads_as_an_upright_figure(shared_data):
    m = read_asf_amc(shared_data("motion/07.asf"), shared_data("motion/07_07.amc"))
    assert m.n_frames == 379
    names = m.skeleton.joint_names
    h = _upright_checks(m.positions(), m.end_site_positions(), names,
                        ["lfoot", "rfoot"], "head")
    assert 1.4 < h < 2.0
    # Subject 07's femur is 6.92462 units of 1/0.45 inch in the ASF.
    femur = np.linalg.norm(m.skeleton.offsets[names.index("ltibia")])
    assert femur == pytest.approx(6.92462 / 0.45 * 0.0254, rel=1e-6)


def test_asf_amc_and_bvh_walks_move_mostly_horizontally(shared_data):
    m = read_asf_amc(shared_data("motion/07.asf"), shared_data("motion/07_07.amc"))
    root = m.positions()[:, 0]
    travel = root[-1] - root[0]
    assert np.hypot(travel[0], travel[2]) > 1.0 and abs(travel[1]) < 0.1


@pytest.mark.parametrize(
    "text, problem",
    [
        ("hello", "not a BVH file"),
        ("HIERARCHY\nROOT a\n{\nOFFSET 0 0\n}\nMOTION\n", "malformed"),
        ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}\n"
         "MOTION\nFrames: 3\nFrame Time: 0.1\n0 0 0\n0 0 0\n", "truncated"),
        ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 1 Wrotation\n}\nMOTION\n", "bad channels"),
    ],
)
def test_malformed_bvh_raises_motion_file_error(tmp_path, text, problem):
    p = tmp_path / "bad.bvh"
    p.write_text(text)
    with pytest.raises(MotionFileError, match=problem) as err:
        read_bvh(p)
    assert str(p) in str(err.value)
