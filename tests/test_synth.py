"""The ground-truth renderer: motions, retargeting, camera, drawing, truth, CLI."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from vidcap.body import JOINT_INDEX, JOINT_NAMES, SEGMENT_INDEX, SEGMENT_NAMES, BodyModel
from vidcap.errors import MotionFileError, VidcapError
from vidcap.io.bvh import read_bvh
from vidcap.kinematics import Motion, Skeleton
from vidcap.synth import (
    JOINT_MAPS,
    body_yaw,
    depth_signs,
    detect_joint_map,
    make_camera,
    make_motion,
    project,
    render_body,
    render_clip,
    retarget,
    source_joint_positions,
)
from vidcap.video.motion import minimal_rotation

TRUTH_KEYS = {
    "joint_names", "masks", "joints2d", "joints3d", "depth_signs", "segment_names",
    "orientation", "yaw_deg", "camera", "view_dir", "fps",
}


def _angles_deg(a, b):
    cos = np.sum(a * b, -1) / np.linalg.norm(a, axis=-1) / np.linalg.norm(b, axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


def _seg_vectors(p):
    from vidcap.body import SEGMENT_JOINTS

    return p[:, SEGMENT_JOINTS[:, 1]] - p[:, SEGMENT_JOINTS[:, 0]]


@pytest.fixture(scope="module")
def walk_clip(tmp_path_factory):
    """One small CLI render shared by several tests."""
    from tests.conftest import run_cli

    d = tmp_path_factory.mktemp("synth")
    out, truth, bvh = d / "walk.mp4", d / "walk.npz", d / "walk.bvh"
    res = run_cli("synth", "--motion", "walk", "--frames", "12", "--yaw", "70",
                  "--size", "160x120", "-o", out, "--truth", truth, "--bvh", bvh,
                  "--noise", "3", "--lighting-drift", "0.1", "--seed", "3")
    assert res.returncode == 0, res.stderr
    return out, truth, bvh


def test_cli_writes_video_with_requested_frames_and_size(walk_clip):
    from vidcap.io.video import probe, read_frames

    out, truth, _ = walk_clip
    info = probe(out, count=True)
    assert (info.n_frames, info.width, info.height) == (12, 160, 120)
    frames = read_frames(out)
    assert frames.shape == (12, 120, 160, 3)
    t = np.load(truth)
    assert set(t.files) == TRUTH_KEYS
    assert t["masks"].shape == (12, 120, 160) and t["masks"].dtype == bool
    assert t["joints2d"].shape == (12, 15, 2) and t["joints3d"].shape == (12, 15, 3)
    assert t["depth_signs"].shape == (12, 10)
    assert set(np.unique(t["depth_signs"])) <= {-1, 1}
    assert list(t["joint_names"]) == list(JOINT_NAMES)
    assert list(t["segment_names"]) == list(SEGMENT_NAMES)
    assert t["orientation"].shape == (12,) and float(t["fps"]) == 30.0
    # the body is visible: inside the mask the video differs from the background
    # (clothes are far from the background colours), outside it does not change much
    m = t["masks"]
    assert 0.02 < m.mean() < 0.5
    diff = np.abs(frames.astype(float) - np.median(frames, axis=0)).sum(-1)
    assert diff[m].mean() > 3 * diff[~m].mean()


def test_truth_projection_and_masks(walk_clip):
    from scipy.ndimage import binary_dilation

    t = np.load(walk_clip[1])
    uv = project(t["camera"], t["joints3d"])
    np.testing.assert_allclose(t["joints2d"], uv, atol=0.5)
    # camera rows are orthogonal to the view direction and equally scaled
    A = t["camera"][:, :3]
    np.testing.assert_allclose(A @ t["view_dir"], 0.0, atol=1e-9)
    assert np.isclose(np.linalg.norm(A[0]), np.linalg.norm(A[1]))
    masks = binary_dilation(t["masks"], structure=np.ones((1, 5, 5), bool))  # 2 px
    ij = np.rint(uv).astype(int)
    F = len(ij)
    inside = masks[np.arange(F)[:, None], ij[..., 1].clip(0, 119), ij[..., 0].clip(0, 159)]
    in_image = (ij[..., 0] >= 0) & (ij[..., 0] < 160) & (ij[..., 1] >= 0) & (ij[..., 1] < 120)
    assert in_image.all()
    assert inside.all()


def test_depth_signs_agree_with_geometry(walk_clip):
    t = np.load(walk_clip[1])
    j, v = t["joints3d"], t["view_dir"]
    for k, name in enumerate(SEGMENT_NAMES):
        from vidcap.body import SEGMENTS

        s = SEGMENTS[k]
        prox = j[:, JOINT_INDEX[s.proximal]]
        dist = j[:, JOINT_INDEX[s.distal]]
        nearer = np.linalg.norm(dist - (-1e3 * v), axis=-1) < np.linalg.norm(
            prox - (-1e3 * v), axis=-1
        )  # distance to a far point on the camera side
        np.testing.assert_array_equal(t["depth_signs"][:, k] == 1, nearer, err_msg=name)


def _arm_forward_motion(body):
    """Rest pose with the left arm pointing straight forward (-Z)."""
    m = Motion.rest(body.skeleton(), 1)
    rot = m.rotations.copy()
    rot[0, JOINT_INDEX["l_shoulder"]] = minimal_rotation([-1, 0, 0], [0, 0, -1])
    return Motion(m.skeleton, m.root_positions, rot, 30.0)


@pytest.mark.parametrize("yaw, sign", [(0.0, 1), (180.0, -1), (40.0, 1), (-140.0, -1)])
def test_depth_sign_of_a_known_pose(yaw, sign):
    body = BodyModel()
    joints = _arm_forward_motion(body).positions()
    cam = make_camera(joints, size=(160, 120), yaw_deg=yaw)
    ds = depth_signs(joints, cam.view_dir)
    assert ds[0, SEGMENT_INDEX["l_upper_arm"]] == sign


@pytest.mark.parametrize(
    "yaw, label", [(0, "front"), (90, "right"), (-90, "left"), (180, "back"), (45, "front_right"),
                   (-135, "back_left")],
)
def test_yaw_and_orientation(yaw, label):
    from vidcap.body import orientation_from_yaw

    body = BodyModel()
    m = make_motion("walk", body=body, n_frames=20)
    j = m.positions()
    cam = make_camera(j, size=(160, 120), yaw_deg=yaw)
    y = np.rad2deg(body_yaw(j, cam.view_dir))
    d = (y - yaw + 180) % 360 - 180
    assert np.abs(d).max() < 8  # the walk's shoulder counter-rotation is +-4 degrees
    assert abs(np.mean(d)) < 1.0
    labels = orientation_from_yaw(np.deg2rad(y))
    assert all(lab.startswith(label) for lab in labels)
    # facing image-right means walking to the right for a forward walk
    if yaw == 90:
        u = cam.project(j[:, JOINT_INDEX["pelvis"]])[:, 0]
        assert u[-1] > u[0] + 20


def test_near_limb_occludes_far_limb():
    body = BodyModel()
    joints = body.rest_positions()[None]  # T-pose: arms along the view in a side view
    colours = {n: (128, 128, 128) for n in SEGMENT_NAMES}
    for seg in ("upper_arm", "lower_arm"):
        colours[f"l_{seg}"], colours[f"r_{seg}"] = (0, 255, 0), (255, 0, 0)
    colours["torso"] = (0, 0, 255)
    bg = np.zeros((120, 160, 3), np.uint8)
    for yaw, near in ((90, "r_upper_arm"), (-90, "l_upper_arm")):
        cam = make_camera(joints, size=(160, 120), yaw_deg=yaw)
        img, mask = render_body(joints[0], cam, body, bg, colours=colours)
        mid = 0.5 * (joints[0, JOINT_INDEX["l_shoulder"]] + joints[0, JOINT_INDEX["l_elbow"]])
        u, v = np.rint(cam.project(mid)).astype(int)
        px = img[v, u]
        assert mask[v, u]
        want = np.array(colours[near], float)
        assert np.argmax(px) == np.argmax(want) and px.max() > 3 * np.sort(px)[1], (yaw, px)


def test_procedural_motions_stand_on_the_floor():
    body = BodyModel(height=1.8)
    rng = np.random.default_rng(1)
    for name in ("walk", "jacks", "arms"):
        m = make_motion(name, body=body, n_frames=40, fps=25, rng=rng)
        assert m.skeleton.joint_names == JOINT_NAMES and m.n_frames == 40 and m.fps == 25
        p = m.positions()
        feet = p[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 1].min(1)
        assert feet.min() > -1e-9
        if name != "jacks":
            np.testing.assert_allclose(feet, 0.0, atol=1e-9)
        else:
            assert 0.02 < feet.max() < 0.15  # hops
        head = p[:, JOINT_INDEX["head_top"], 1]
        assert 1.7 < head.max() < 1.8 + 0.12  # jacks hop
    walk = make_motion("walk", body=body, n_frames=60, fps=30).positions()
    travel = np.linalg.norm(walk[-1, 0, [0, 2]] - walk[0, 0, [0, 2]])
    assert 2.0 < travel < 3.4  # 1.0-1.7 m/s for 2 s
    ank = walk[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]][..., [0, 2]]
    slide = np.linalg.norm(np.diff(ank, axis=0), axis=-1).min(axis=1)  # the planted foot
    assert slide.max() < 1e-3
    swing_height = walk[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 1].max()
    assert 0.1 < swing_height < 0.4
    jacks = make_motion("jacks", body=body, n_frames=60, fps=30).positions()
    assert np.ptp(jacks[:, 0, [0, 2]], axis=0).max() < 1e-9  # in place
    wr = jacks[:, JOINT_INDEX["l_wrist"], 1]
    assert wr.max() > jacks[:, JOINT_INDEX["head_top"], 1].max()  # hands overhead
    arms = make_motion("arms", body=body, n_frames=90, fps=30).positions()
    assert arms[:, JOINT_INDEX["l_wrist"], 1].max() > arms[:, JOINT_INDEX["neck"], 1].max()


def test_procedural_variation_is_seeded():
    a = make_motion("walk", n_frames=10, rng=np.random.default_rng(5)).positions()
    b = make_motion("walk", n_frames=10, rng=np.random.default_rng(5)).positions()
    c = make_motion("walk", n_frames=10, rng=np.random.default_rng(6)).positions()
    np.testing.assert_array_equal(a, b)
    assert np.abs(a - c).max() > 1e-3


def test_render_clip_in_memory_is_deterministic():
    m = make_motion("arms", n_frames=4)
    f1, t1 = render_clip(m, size=(96, 72), yaw_deg=30, rng=np.random.default_rng(2))
    f2, t2 = render_clip(m, size=(96, 72), yaw_deg=30, rng=np.random.default_rng(2))
    np.testing.assert_array_equal(f1, f2)
    np.testing.assert_array_equal(t1["masks"], t2["masks"])
    assert f1.shape == (4, 72, 96, 3)


def test_noise_and_lighting_drift():
    m = make_motion("jacks", n_frames=30)
    quiet, _ = render_clip(m, size=(64, 48), noise=0.0, rng=np.random.default_rng(0))
    noisy, _ = render_clip(m, size=(64, 48), noise=4.0, rng=np.random.default_rng(0))
    d = noisy.astype(float) - quiet.astype(float)
    assert 3.0 < d.std() < 5.0
    drift, truth = render_clip(m, size=(64, 48), noise=0.0, lighting_drift=0.2,
                               rng=np.random.default_rng(0))
    bg = ~truth["masks"].any(0)
    level = drift[:, bg].mean(axis=(1, 2))
    assert np.ptp(level) > 0.1 * level.mean()  # brightness changes by > 10 %
    assert np.abs(np.diff(level)).max() < 0.05 * level.mean()  # ...slowly


def test_background_image(tmp_path, cli):
    import cv2

    img = np.zeros((50, 80, 3), np.uint8)
    img[:] = (200, 200, 200)
    path = tmp_path / "bg.png"
    cv2.imwrite(str(path), img)
    frames, truth = render_clip(make_motion("walk", n_frames=2), size=(64, 48),
                                background=str(path), noise=0)
    np.testing.assert_array_equal(frames[0][~truth["masks"][0]], 200)
    bad = tmp_path / "bad.png"
    bad.write_text("not an image")
    res = cli("synth", "--frames", "2", "--size", "64x48", "--background", bad,
              "-o", tmp_path / "x.mp4", "--truth", tmp_path / "x.npz")
    assert res.returncode == 2 and "bad.png" in res.stderr
    assert not (tmp_path / "x.mp4").exists() and not (tmp_path / "x.npz").exists()


# --------------------------------------------------------------------------- retargeting
def _check_retarget(src, table_name, out):
    table = JOINT_MAPS[table_name]
    assert detect_joint_map(src.skeleton) == table_name
    ours = out.positions()
    theirs = source_joint_positions(src, table)
    ang = _angles_deg(_seg_vectors(ours), _seg_vectors(theirs))
    assert ang.max() < 2.0, dict(zip(SEGMENT_NAMES, ang.max(0).round(2), strict=True))
    feet = ours[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 1]
    assert abs(feet.min()) < 1e-9
    # the root travels like the source's, scaled by the leg-length ratio
    src_leg = np.median(np.linalg.norm(theirs[:, JOINT_INDEX["l_knee"]]
                                       - theirs[:, JOINT_INDEX["l_hip"]], axis=-1)
                        + np.linalg.norm(theirs[:, JOINT_INDEX["l_ankle"]]
                                         - theirs[:, JOINT_INDEX["l_knee"]], axis=-1))
    k = BodyModel().pelvis_height / src_leg
    d_src = theirs[-1, 0, [0, 2]] - theirs[0, 0, [0, 2]]
    d_our = ours[-1, 0, [0, 2]] - ours[0, 0, [0, 2]]
    np.testing.assert_allclose(d_our, k * d_src, atol=0.05 * np.linalg.norm(k * d_src))


def test_retarget_cmu_bvh(shared_data):
    src = read_bvh(shared_data("motion/131_01.bvh"))
    src = src.frames(0, 600)
    _check_retarget(src, "cmu_bvh", retarget(src, solid_torso=False))


def test_retarget_cmu_asf(shared_data):
    from vidcap.io.asf import read_asf_amc

    src = read_asf_amc(shared_data("motion/07.asf"), shared_data("motion/07_07.amc"))
    _check_retarget(src, "cmu_asf", retarget(src, solid_torso=False))


def _inside_torso(pos, body):
    """(F, 4) bool: elbows and wrists strictly inside the torso cylinder."""
    pel = pos[:, JOINT_INDEX["pelvis"]]
    axis = pos[:, JOINT_INDEX["neck"]] - pel
    length = np.linalg.norm(axis, axis=-1)
    axis /= length[:, None]
    out = []
    for name in ("l_elbow", "l_wrist", "r_elbow", "r_wrist"):
        d = pos[:, JOINT_INDEX[name]] - pel
        h = np.sum(d * axis, -1)
        rho = np.linalg.norm(d - h[:, None] * axis, axis=-1)
        out.append((h > 0) & (h < length) & (rho < body.radius("torso") - 1e-6))
    return np.stack(out, -1)


def test_retarget_keeps_the_arms_out_of_our_torso(shared_data):
    """131_01's performer rests a hand on the belly (source frames 250-280): on our
    wider torso the retargeted wrist went 2 cm inside it. The default retarget turns
    such an arm out to the surface; nothing else moves, and bones keep their lengths."""
    body = BodyModel()
    src = read_bvh(shared_data("motion/131_01.bvh")).frames(200, 330)
    exact = retarget(src, body, solid_torso=False).positions()
    solid = retarget(src, body).positions()
    hit = _inside_torso(exact, body)
    assert hit.sum() >= 10  # the case is real
    assert not _inside_torso(solid, body).any()
    arms = [JOINT_INDEX[n] for n in ("l_elbow", "l_wrist", "r_elbow", "r_wrist")]
    rest = [k for k in range(len(JOINT_NAMES)) if k not in arms]
    np.testing.assert_allclose(solid[:, rest], exact[:, rest], atol=1e-9)
    moved = np.linalg.norm(solid[:, arms] - exact[:, arms], axis=-1)
    assert moved[~hit.any(axis=1)].max() < 1e-9  # frames without contact are untouched
    assert 0.0 < moved.max() < 0.1  # a turn to the surface, not a new pose
    segs = _seg_vectors(solid)
    np.testing.assert_allclose(np.linalg.norm(segs, axis=-1),
                               np.linalg.norm(_seg_vectors(exact), axis=-1), atol=1e-9)


def test_retarget_humanik_names_like_cmu(shared_data, tmp_path):
    """The same 131_01 motion with its joints named as MotionBuilder's HumanIK (Mixamo,
    the widely shared CMU conversion, capture suits) names them: LeftArm for the
    shoulder, LeftUpLeg for the hip, the head's top at its End Site. It maps as
    'humanik' and retargets to the same poses as the CMU names."""
    import re

    text = shared_data("motion/131_01.bvh").read_text()
    renames = [("Shoulder", "Arm"), ("Collar", "Shoulder"), ("Elbow", "ForeArm"),
               ("Wrist", "Hand"), ("Hip", "UpLeg"), ("Knee", "Leg"), ("Ankle", "Foot"),
               ("Toe", "ToeBase")]
    for old, new in renames:  # in this order: Shoulder -> Arm before Collar -> Shoulder
        text = re.sub(rf"\b(Left|Right){old}\b", rf"\g<1>{new}", text)
    assert "JOINT LeftArm" in text and "JOINT LeftUpLeg" in text
    path = tmp_path / "humanik.bvh"
    path.write_text(text)
    src = read_bvh(path).frames(0, 240)
    assert detect_joint_map(src.skeleton) == "humanik"
    want = retarget(read_bvh(shared_data("motion/131_01.bvh")).frames(0, 240))
    np.testing.assert_allclose(retarget(src).positions(), want.positions(), atol=1e-9)


def test_retarget_our_own_skeleton_is_identity():
    body = BodyModel(height=1.6)
    m = make_motion("arms", body=body, n_frames=20, rng=np.random.default_rng(0))
    r = retarget(m, body)
    np.testing.assert_allclose(r.positions(), m.positions(), atol=1e-9)


def test_retarget_z_up_source():
    body = BodyModel()
    m = make_motion("walk", body=body, n_frames=15)
    zup = Rotation.from_euler("x", 90, degrees=True)  # Y up -> Z up
    p = m.positions()
    sk = m.skeleton
    rots = m.rotations.copy()
    rots[:, 0] = (zup * Rotation.from_quat(m.rotations[:, 0])).as_quat()  # turn the world
    zm = Motion(Skeleton(sk.joint_names, sk.parents, sk.offsets), zup.apply(m.root_positions),
                rots, 30)
    np.testing.assert_allclose(zm.positions(), zup.apply(p.reshape(-1, 3)).reshape(p.shape),
                               atol=1e-9)
    r = retarget(zm, body).positions()
    ang = _angles_deg(_seg_vectors(r), _seg_vectors(p))
    assert ang.max() < 1e-4  # degrees; arccos near 1 is only good to ~1e-6


def test_unmappable_motion(tmp_path, cli):
    bvh = tmp_path / "robot.bvh"
    bvh.write_text(
        "HIERARCHY\nROOT base\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition "
        "Zrotation Xrotation Yrotation\n JOINT arm\n {\n  OFFSET 0 1 0\n  CHANNELS 3 Zrotation "
        "Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 1 0\n  }\n }\n}\nMOTION\nFrames: 2\n"
        "Frame Time: 0.033333\n0 0 0 0 0 0 0 0 0\n0 0 0 0 0 0 0 0 0\n"
    )
    with pytest.raises(MotionFileError, match="robot.bvh.*cannot map"):
        make_motion(bvh)
    res = cli("synth", "--motion", bvh, "--size", "64x48", "-o", tmp_path / "r.mp4",
              "--truth", tmp_path / "r.npz")
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vidcap: error:") and "robot.bvh" in lines[0]
    assert not (tmp_path / "r.mp4").exists()


@pytest.mark.parametrize(
    "args, text",
    [(["--motion", "dance"], "dance"), (["--motion", "walk", "--range", "5"], "--range"),
     (["--motion", "walk", "--range", "100:120"], "no frames"),
     (["--motion", "walk", "--fps", "-3"], "--fps"),
     (["--size", "161x120"], "even"), (["--size", "big"], "WIDTHxHEIGHT"),
     (["--background", "no_such.png"], "no_such.png")],
)
def test_bad_options(tmp_path, cli, args, text):
    if "--size" not in args:
        args = [*args, "--size", "64x48"]
    res = cli("synth", *args, "--frames", "10", "-o", tmp_path / "x.mp4")
    assert res.returncode == 2, res.stderr
    assert text in res.stderr and len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "x.mp4").exists() and not (tmp_path / "x_truth.npz").exists()


def test_asf_needs_amc(shared_data):
    with pytest.raises(VidcapError, match="--amc"):
        make_motion(shared_data("motion/07.asf"))


def test_range_and_resample(shared_data):
    path = shared_data("motion/131_01.bvh")
    src = read_bvh(path)
    m = make_motion(path, frame_range=(100, 230), fps=30)
    assert m.fps == 30
    assert m.n_frames == int(np.floor(129 / src.fps * 30)) + 1  # 32 frames
    assert m.skeleton.joint_names == JOINT_NAMES


def test_bvh_output_reads_back_with_same_fk(walk_clip):
    _, truth, bvh = walk_clip
    t = np.load(truth)
    m = read_bvh(bvh, units="m")
    assert m.skeleton.joint_names == JOINT_NAMES
    np.testing.assert_allclose(m.positions(), t["joints3d"], atol=1e-5)


def test_cli_file_motion_with_bvh(tmp_path, cli, shared_data):
    asf, amc = shared_data("motion/07.asf"), shared_data("motion/07_07.amc")
    res = cli("synth", "--motion", asf, "--amc", amc, "--range", "0:40", "--fps", "30",
              "--yaw", "0", "--size", "96x72", "-o", tmp_path / "a.mp4",
              "--truth", tmp_path / "a.npz", "--bvh", tmp_path / "a.bvh")
    assert res.returncode == 0, res.stderr
    t = np.load(tmp_path / "a.npz")
    assert t["joints3d"].shape[0] == 10  # 40 frames at 120 Hz -> 0.325 s -> 10 frames at 30
    assert all(o.startswith("front") for o in t["orientation"])
    np.testing.assert_allclose(read_bvh(tmp_path / "a.bvh", units="m").positions(),
                               t["joints3d"], atol=1e-5)


def test_render_infers_the_body_from_the_motion():
    from vidcap.synth import prepare_clip

    for h in (1.5, 1.9):
        m = make_motion("walk", body=BodyModel(height=h), n_frames=2)
        assert np.isclose(prepare_clip(m, size=(64, 48)).body.height, h)


def test_sample_videos_match_their_truth():
    from pathlib import Path

    from vidcap.io.video import probe

    root = Path(__file__).resolve().parents[1] / "sample_videos"
    clips = sorted(root.glob("*.mp4"))
    assert len(clips) >= 2
    assert sum(p.stat().st_size for p in root.iterdir()) <= 2 * 1024 * 1024
    for clip in clips:
        t = np.load(clip.with_name(clip.stem + "_truth.npz"))
        info = probe(clip, count=True)
        assert t["masks"].shape == (info.n_frames, info.height, info.width)
        assert np.isclose(float(t["fps"]), info.fps)
        np.testing.assert_allclose(project(t["camera"], t["joints3d"]), t["joints2d"], atol=0.5)


def test_a_body_with_feet_stands_on_soles_below_its_ankles():
    """``foot``: a standing body seen from the side gets feet whose soles are
    ``foot`` x the stature below the ankles and which point the way it faces (toes
    three times as far ahead of the ankle as the heel is behind it, within a pixel);
    nothing else changes, and ``foot=0`` (the default) draws none."""
    from vidcap.synth.camera import make_camera
    from vidcap.synth.render import render_body
    from vidcap.video.fit.proportions import human_proportions

    est = human_proportions()
    body = est.body(1.75)  # head top to ankles: 1.75 less the feet
    joints = body.rest_positions()
    cam = make_camera(joints[None], size=(200, 240), yaw_deg=90, height=1.75,
                      radius=body.radius("torso"))
    bg = np.zeros((240, 200, 3), np.uint8)
    _, bare = render_body(joints, cam, body, bg)
    _, shod = render_body(joints, cam, body, bg, foot=est.foot)
    ankle = cam.project(joints)[JOINT_INDEX["l_ankle"]]
    foot_px = est.foot * 1.75 * cam.pixels_per_metre  # 7 px
    assert np.flatnonzero(bare.any(1)).max() <= ankle[1] + 0.5
    assert abs(np.flatnonzero(shod.any(1)).max() + 1 - (ankle[1] + foot_px)) <= 1.0
    assert not (bare & ~shod).any()  # the feet add pixels, remove none
    sole = np.flatnonzero(shod[int(ankle[1] + foot_px) - 2])
    ahead, behind = sole.max() + 1 - ankle[0], ankle[0] - sole.min()
    assert ahead > 2 * behind > 0  # yaw 90 faces image right
    assert abs((ahead + behind) / cam.pixels_per_metre / 1.75 - 0.145) < 0.01


def test_synth_cli_human_body_has_feet(tmp_path, cli):
    """``vidcap synth --proportions human``: a real adult's body, its silhouette
    reaching below the ankles by the feet (the seed's ends at them)."""
    lows = {}
    for name in ("seed", "human"):
        out = tmp_path / f"{name}.mp4"
        res = cli("synth", "--frames", "2", "--size", "160x120", "--proportions", name,
                  "--noise", "0", "-o", out)
        assert res.returncode == 0, res.stderr
        t = np.load(tmp_path / f"{name}_truth.npz")
        ankles = t["joints2d"][0, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 1].max()
        height = np.ptp(t["joints2d"][0, :, 1])
        lows[name] = (np.flatnonzero(t["masks"][0].any(1)).max() + 1 - ankles) / height
    assert lows["seed"] < 0.02 < 0.03 < lows["human"]
