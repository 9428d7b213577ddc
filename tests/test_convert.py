"""vidcap convert / batch / review end to end on the sample clips (synth branch)."""

import csv
import shutil

import numpy as np
import pytest

from tests.conftest import REPO, run_cli, write_timed_video
from vidcap.body import JOINT_INDEX
from vidcap.io.bvh import read_bvh
from vidcap.io.video import probe

WALK = REPO / "sample_videos" / "walk_side.mp4"
TRUTH = REPO / "sample_videos" / "walk_side_truth.npz"


@pytest.fixture(scope="module")
def converted(tmp_path_factory):
    if not WALK.exists():
        pytest.skip("sample_videos/ not present")
    d = tmp_path_factory.mktemp("convert")
    out, npz = d / "walk.bvh", d / "walk.npz"
    # the sample is a render of the seed's body (sample_videos/README): fitted with it
    r = run_cli("convert", WALK, "-o", out, "--save", npz, "--proportions", "seed")
    assert r.returncode == 0, r.stderr
    return out, npz, r


def test_convert_writes_a_bvh_readable_by_us_and_bvhio(converted):
    out, _, r = converted
    info = probe(WALK)
    m = read_bvh(out)
    assert m.n_frames == info.n_frames == 42
    assert m.fps == pytest.approx(info.fps, rel=1e-4)
    bvhio = pytest.importorskip("bvhio")
    c = bvhio.readAsBvh(str(out))
    assert c.FrameCount == info.n_frames
    assert c.FrameTime == pytest.approx(1.0 / info.fps, rel=1e-4)
    assert "frames at 25 fps" in r.stdout
    # a side view: the output says how to put the legs on the right hips
    assert "side view in" in r.stdout and '"type": "sides"' in r.stdout
    assert "walk_side.vidcap.json" in r.stdout


def test_converted_figure_is_upright_and_walks_the_right_way(converted):
    out, _, _ = converted
    pos = read_bvh(out).positions()
    i = JOINT_INDEX
    head, pelvis = pos[:, i["head_top"], 1], pos[:, i["pelvis"], 1]
    ankles = np.maximum(pos[:, i["l_ankle"], 1], pos[:, i["r_ankle"], 1])
    assert np.all(head > pelvis) and np.all(pelvis > ankles)
    # the clip walks to image right (truth), which is +X in our camera-aligned world
    truth = np.load(TRUTH)
    true_dir = np.sign(truth["joints2d"][-1, 0, 0] - truth["joints2d"][0, 0, 0])
    travel = pos[-1, i["pelvis"], 0] - pos[0, i["pelvis"], 0]
    assert true_dir > 0 and travel > 0.5  # metres over 1.7 s
    assert np.all(np.diff(pos[:, i["pelvis"], 0]) > -0.02)  # never walks backward


def test_saved_arrays(converted):
    _, npz, _ = converted
    with np.load(npz) as z:
        for k in ("masks", "joint_names", "joints2d", "joints3d", "proposed_signs", "signs",
                  "orientation", "proposed_orientation", "scores"):
            assert k in z.files, k
        F = z["masks"].shape[0]
        assert z["joints3d"].shape == (F, 15, 3) and z["signs"].shape == (F, 10)
        assert set(np.unique(z["signs"])) <= {-1, 1}
        # the ranked checks, most doubtful first
        assert len(z["check_frame"]) == len(z["check_segment"]) > 0
        assert np.all(np.diff(z["check_priority"]) <= 0)
        truth = np.load(TRUTH)
        assert np.mean(z["orientation"] == truth["orientation"]) > 0.9


def test_bad_annotations_fail_cleanly_and_leave_no_bvh(tmp_path):
    if not WALK.exists():
        pytest.skip("sample_videos/ not present")
    video = tmp_path / "clip.mp4"
    shutil.copy(WALK, video)
    (tmp_path / "clip.vidcap.json").write_text('{"version": 1, "events": [{"frame": 0, '
                                               '"type": "depth", "segment": "tail", '
                                               '"value": "away"}]}')
    out = tmp_path / "clip.bvh"
    r = run_cli("convert", video, "-o", out, "--no-cache")
    assert r.returncode == 2
    assert "clip.vidcap.json" in r.stderr and "unknown segment 'tail'" in r.stderr
    assert len([ln for ln in r.stderr.splitlines() if ln.startswith("vidcap: error")]) == 1
    assert not out.exists()


def test_annotation_beyond_the_clip_names_the_annotations_file(tmp_path):
    if not WALK.exists():
        pytest.skip("sample_videos/ not present")
    ann = tmp_path / "late.json"
    ann.write_text('{"version": 1, "events": [{"frame": 420, "type": "orientation", '
                   '"value": "left"}]}')
    out = tmp_path / "o.bvh"
    r = run_cli("convert", WALK, "-o", out, "--annotations", ann)
    assert r.returncode == 2 and "late.json" in r.stderr and "frame 420" in r.stderr
    assert not out.exists()



def test_frames_before_the_person_enters_and_after_leaving(tmp_path):
    """The first frames show only the background (the person enters later), a few in
    the middle too, and at the end the person walks out of the (cropped) picture:
    convert says which frames it left out, fills them, and the BVH has every frame."""
    if not WALK.exists():
        pytest.skip("sample_videos/ not present")
    from vidcap.io.video import read_frames, write_video

    width = 380  # of 480: the walker's last frames are cut off on the right
    frames = read_frames(WALK)
    n = len(frames)
    empty = np.median(frames, axis=0).astype(np.uint8)
    frames[:10] = empty
    frames[25:30] = empty
    video = tmp_path / "enters.mp4"
    write_video(video, list(np.ascontiguousarray(frames[:, :, :width])), probe(WALK).fps)
    out, npz = tmp_path / "enters.bvh", tmp_path / "enters.npz"
    r = run_cli("convert", video, "-o", out, "--no-cache", "--save", npz)
    assert r.returncode == 0, r.stderr
    assert f"no person in 15 of {n} frames (0-9, 25-29)" in r.stdout
    motion = read_bvh(out)
    assert motion.n_frames == n
    assert np.isfinite(motion.root_positions).all() and np.isfinite(motion.rotations).all()
    # left out: the frames where most of the true silhouette is beyond the crop
    truth = np.load(TRUTH)["masks"]
    visible = truth[:, :, :width].sum((1, 2)) / truth.sum((1, 2))
    outside = np.load(npz)["outside"]
    assert outside.any() and "mostly outside the picture" in r.stdout
    assert (visible[outside] < 0.8).all() and outside[visible < 0.5].all()


def test_a_moving_box_is_reported_as_a_poor_fit(tmp_path, converted):
    """Something that is not a person still converts, but the output says the body
    model does not fit it; a walking person's conversion says nothing of the kind."""
    from vidcap.io.video import write_video

    rng = np.random.default_rng(0)
    plate = rng.integers(60, 200, (240, 320, 3)).astype(np.uint8)
    frames = []
    for k in range(40):
        f = plate.copy()
        f[60:140, 20 + 6 * k:60 + 6 * k] = (30, 30, 200)  # a 40x80 box sliding right
        frames.append(f)
    video = tmp_path / "box.mp4"
    write_video(video, frames, 25.0)
    r = run_cli("convert", video, "-o", tmp_path / "box.bvh", "--no-cache")
    assert r.returncode == 0, r.stderr
    assert "fits the silhouettes poorly (median similarity 0." in r.stdout
    assert "fits the silhouettes poorly" not in converted[2].stdout

def test_annotations_override_the_proposals(tmp_path, converted):
    _, npz, _ = converted
    video = tmp_path / "clip.mp4"
    shutil.copy(WALK, video)
    with np.load(npz) as z:
        proposed = z["proposed_signs"]
    k = 0  # torso
    flip = int(-proposed[5, k])
    word = "toward" if flip > 0 else "away"
    ann = tmp_path / "a.json"
    ann.write_text('{"version": 1, "events": [{"frame": 5, "type": "depth", "segment": '
                   f'"torso", "value": "{word}"}}, {{"frame": 0, "type": "orientation", '
                   '"value": "right"}]}')
    out, save = tmp_path / "o.bvh", tmp_path / "o.npz"
    r = run_cli("convert", video, "-o", out, "--annotations", ann, "--save", save)
    assert r.returncode == 0, r.stderr
    with np.load(save) as z:
        assert z["signs"][5, k] == flip
        assert set(z["orientation"]) == {"right"}


def test_batch_three_files_one_corrupt(tmp_path):
    if not WALK.exists():
        pytest.skip("sample_videos/ not present")
    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(WALK, src / "a.mp4")
    shutil.copy(WALK, src / "b.mp4")
    (src / "c.mp4").write_bytes(np.random.default_rng(0).bytes(4000))
    outdir = tmp_path / "out"
    r = run_cli("batch", src, "-o", outdir, "--jobs", "2")
    assert r.returncode != 0
    assert sorted(p.name for p in outdir.glob("*.bvh")) == ["a.bvh", "b.bvh"]
    rows = list(csv.DictReader((outdir / "summary.csv").open()))
    status = {row["file"].split("/")[-1]: row for row in rows}
    assert status["a.mp4"]["status"] == "ok" and status["a.mp4"]["frames"] == "42"
    assert status["c.mp4"]["status"] == "failed" and "c.mp4" in status["c.mp4"]["message"]
    assert "failed" in r.stdout and "c.mp4" in r.stdout
    # re-running skips what is up to date, still reports the failure
    r2 = run_cli("batch", src / "*.mp4", "-o", outdir, "--jobs", "2")
    rows = {row["file"].split("/")[-1]: row["status"]
            for row in csv.DictReader((outdir / "summary.csv").open())}
    assert r2.returncode != 0 and rows == {"a.mp4": "skipped", "b.mp4": "skipped",
                                           "c.mp4": "failed"}


def test_review_frames_are_three_panels_wide(tmp_path, converted):
    _, npz, _ = converted
    out = tmp_path / "review.mp4"
    r = run_cli("review", WALK, "--from", npz, "-o", out, "--png", tmp_path / "png")
    assert r.returncode == 0, r.stderr
    info, src = probe(out), probe(WALK)
    assert info.width == 3 * src.width and info.height == src.height
    assert info.n_frames == src.n_frames
    import cv2

    img = cv2.imread(str(tmp_path / "png" / "review_00010.png"))
    w = src.width
    # the 3D panel shows a skeleton (not a blank image) and differs from the frame
    third = img[:, 2 * w:]
    assert (third < 100).any(axis=2).sum() > 200
    assert not np.array_equal(img[:, :w], third)


def test_review_refuses_results_of_another_video(tmp_path, converted):
    from vidcap.io.video import write_video

    _, npz, _ = converted
    other = tmp_path / "other.mp4"
    write_video(other, [np.zeros((48, 64, 3), np.uint8)] * 3, 25.0)
    r = run_cli("review", other, "--from", npz, "-o", tmp_path / "r.mp4")
    assert r.returncode == 2 and not (tmp_path / "r.mp4").exists()
    assert r.stderr.strip().splitlines()[-1] == (
        f"vidcap: error: {npz}: saved for a 480x360 video, but {other} is 64x48")


def test_second_run_uses_the_stage_cache(converted):
    from vidcap.video.pipeline import convert

    out, _, _ = converted
    cache = out.parent / ".vidcap-cache"
    files = sorted(p.name for p in cache.iterdir())
    assert {f.split("-")[0] for f in files} == {"plate", "silhouettes", "pose2d"}
    again = out.parent / "again.bvh"
    res = convert(WALK, again, progress=False, proportions="seed")
    assert sorted(p.name for p in cache.iterdir()) == files
    assert res.timings["pose2d"] < 0.5 and res.timings["plate"] < 0.5
    assert again.read_text() == out.read_text()


def test_convert_fits_long_clips_in_chunks_like_one_process(tmp_path):
    """A clip of two chunks' length: jobs=2 (workers started early, labels reconciled)
    and jobs=1 (the same chunks fitted one after another in this process) give the same
    2D fit to the bit, with the frame's cues too (a side view's arms were named the
    other way round from a chunk on, when one process fitted the clip in one pass); the
    same BVH frame count, one pose cache entry for both; --jobs 0 is refused."""
    from vidcap.synth import make_motion, synth_clip
    from vidcap.video.pipeline import convert

    video = tmp_path / "long.mp4"
    synth_clip(video, tmp_path / "truth.npz", make_motion("walk", n_frames=130), size=(320, 240),
               rng=np.random.default_rng(0), show_progress=False)
    two = convert(video, tmp_path / "a.bvh", cache_dir=tmp_path / "cache", progress=False,
                  jobs=2)
    one = convert(video, tmp_path / "b.bvh", cache_dir=None, progress=False, jobs=1)
    assert two.n_frames == one.n_frames == 130
    np.testing.assert_array_equal(one.image_joints2d, two.image_joints2d)
    cues = [convert(video, tmp_path / f"c{j}.bvh", cache_dir=None, progress=False, jobs=j,
                    cues="all") for j in (1, 2)]
    np.testing.assert_array_equal(cues[0].image_joints2d, cues[1].image_joints2d)
    assert not np.array_equal(cues[0].image_joints2d, one.image_joints2d)  # the cues read
    again = convert(video, tmp_path / "d.bvh", cache_dir=tmp_path / "cache", progress=False,
                    jobs=1)
    assert len(list((tmp_path / "cache").glob("pose2d-*.npz"))) == 1  # one plan, one entry
    assert again.timings["pose2d"] < 0.5
    assert read_bvh(tmp_path / "a.bvh").n_frames == 130
    r = run_cli("convert", video, "-o", tmp_path / "c.bvh", "--jobs", "0")
    assert r.returncode == 2 and "--jobs" in r.stderr


def test_convert_ensemble_in_chunks_like_one_process(tmp_path):
    """``--ensemble 2`` (each chunk fitted on the masks as given and eroded, joined per
    joint): jobs=2 and jobs=1 give the same 2D fit and BVH to the bit, another fit than
    one member's, in a pose cache entry of its own."""
    from vidcap.synth import make_motion, synth_clip
    from vidcap.video.pipeline import convert

    video, cache = tmp_path / "long.mp4", tmp_path / "cache"
    synth_clip(video, tmp_path / "truth.npz", make_motion("walk", n_frames=130),
               size=(320, 240), rng=np.random.default_rng(0), show_progress=False)
    runs = {(n, j): convert(video, tmp_path / f"e{n}j{j}.bvh", cache_dir=cache if j == 2 else None,
                            progress=False, jobs=j, ensemble=n)
            for n, j in ((2, 2), (2, 1), (1, 2))}
    np.testing.assert_array_equal(runs[2, 1].image_joints2d, runs[2, 2].image_joints2d)
    assert (tmp_path / "e2j1.bvh").read_text() == (tmp_path / "e2j2.bvh").read_text()
    assert not np.array_equal(runs[2, 2].image_joints2d, runs[1, 2].image_joints2d)
    assert np.isfinite(runs[2, 2].image_joints2d).all()
    assert len(list(cache.glob("pose2d-*.npz"))) == 2  # one entry each
    again = convert(video, tmp_path / "again.bvh", cache_dir=cache, progress=False, jobs=1,
                    ensemble=2)
    assert again.timings["pose2d"] < 0.5
    np.testing.assert_array_equal(again.image_joints2d, runs[2, 2].image_joints2d)


def test_view_side_on_a_real_side_view_walk(tmp_path, shared_data):
    """Weizmann's ido walks across the picture, seen from his right side. Told
    ``--view side``, every frame is a side view facing the walking direction (image
    right), and the wavering-view notice is not printed."""
    video = shared_data("video/ido_walk.avi")
    npz = tmp_path / "ido.npz"
    r = run_cli("convert", video, "-o", tmp_path / "ido.bvh", "--view", "side",
                "--save", npz, "--no-cache", "--jobs", "1")
    assert r.returncode == 0, r.stderr
    with np.load(npz) as z:
        assert set(z["orientation"]) == {"right"}
        np.testing.assert_allclose(z["yaw"], np.pi / 2)
    assert "--view side" not in r.stdout
    bad = run_cli("convert", video, "-o", tmp_path / "x.bvh", "--view", "sideways")
    assert bad.returncode == 2 and "invalid choice: 'sideways'" in bad.stderr
    assert not (tmp_path / "x.bvh").exists()


def test_variable_rate_video_gives_a_bvh_in_step_with_it(converted, tmp_path):
    """walk_side with 10 of its frames dropped (every other one of frames 10-29), the
    rest shown at their own times: the BVH is resampled at the camera's 25 fps over
    the clip's 1.64 s (42 frames, not 32 frames at the 19 fps average), and the
    pelvis walks as in the whole clip's BVH."""
    from vidcap.io.video import read_frames

    keep = [i for i in range(42) if not (10 <= i < 30 and i % 2)]
    video = tmp_path / "dropped.mp4"
    write_timed_video(video, read_frames(WALK)[keep], np.array(keep) / 25.0)
    out = tmp_path / "dropped.bvh"
    r = run_cli("convert", video, "-o", out, "--no-cache", "--jobs", "1")
    assert r.returncode == 0, r.stderr
    assert "variable frame rate (frames 40-80 ms apart)" in r.stdout
    m, whole = read_bvh(out), read_bvh(converted[0])
    assert m.n_frames == 42 and m.fps == pytest.approx(25.0)
    i = JOINT_INDEX["pelvis"]
    a, b = m.positions()[:, i, 0], whole.positions()[:, i, 0]
    assert np.abs((a - a[0]) - (b - b[0])).max() < 0.08  # metres, over a 1.1 m walk


def test_convert_with_a_camera_above(tmp_path):
    """``camera=(2.5, 3)`` (k ~ 0.35): the 2D fit draws the body warped (the image joints
    move, the neck lower under a larger head), the skeleton written keeps the body's own
    proportions, and the 3D stage reads un-warped joints (the motion is finite)."""
    from vidcap.body import JOINT_INDEX
    from vidcap.synth import make_motion, synth_clip
    from vidcap.video.pipeline import convert

    video = tmp_path / "walk.mp4"
    synth_clip(video, tmp_path / "truth.npz", make_motion("walk", n_frames=40),
               size=(320, 240), rng=np.random.default_rng(0), show_progress=False)
    runs = {cam: convert(video, tmp_path / f"{cam is None}.bvh", cache_dir=None,
                         progress=False, jobs=1, camera=cam) for cam in (None, (2.5, 3.0))}
    plain, high = runs[None], runs[2.5, 3.0]
    np.testing.assert_allclose(high.body.segment_lengths(), plain.body.segment_lengths())
    neck, top = JOINT_INDEX["neck"], JOINT_INDEX["head_top"]
    drop = {c: np.median(r.image_joints2d[:, neck, 1] - r.image_joints2d[:, top, 1])
            for c, r in (("plain", plain), ("high", high))}
    assert drop["high"] > 1.1 * drop["plain"]
    assert np.isfinite(high.motion.positions()).all()


def test_convert_reads_the_camera_from_the_scene(tmp_path):
    """``camera='auto'``: a walk rendered over a room whose verticals meet far below the
    frame (a camera looking down) is fitted with the body warped, as a given camera's is
    (the neck lower under a larger head), and the log says what the scene gave; a plain
    backdrop gives no perspective (the same fit as without a camera)."""
    from tests._synthframes import room_with_verticals
    from vidcap.body import JOINT_INDEX
    from vidcap.synth import make_motion, synth_clip
    from vidcap.video.pipeline import convert

    room = room_with_verticals(240, 320, 1200.0, np.random.default_rng(0))
    video = tmp_path / "walk.mp4"
    synth_clip(video, tmp_path / "truth.npz", make_motion("walk", n_frames=40), size=(320, 240),
               rng=np.random.default_rng(0), show_progress=False, background=room)
    logs, told = [], []
    runs = {cam: convert(video, tmp_path / f"{cam}.bvh", cache_dir=None, progress=False, jobs=1,
                         camera=cam, log=logs.append if cam == "auto" else told.append)
            for cam in (None, "auto")}
    said = [m for m in logs if m.startswith("camera perspective")]
    assert len(said) == 1 and "k = 0." in said[0], logs
    # without --camera the fit is the level one, and the user is told of the high camera
    assert sum(m.startswith("notice: the camera looks down") for m in told) == 1, told
    neck, top = JOINT_INDEX["neck"], JOINT_INDEX["head_top"]
    drop = {c: np.median(r.image_joints2d[:, neck, 1] - r.image_joints2d[:, top, 1])
            for c, r in runs.items()}
    assert drop["auto"] > 1.05 * drop[None]
    plain = tmp_path / "plain.mp4"
    synth_clip(plain, tmp_path / "truth2.npz", make_motion("walk", n_frames=40), size=(320, 240),
               rng=np.random.default_rng(0), show_progress=False)
    logs.clear()
    a = convert(plain, tmp_path / "a.bvh", cache_dir=None, progress=False, jobs=1,
                camera="auto", log=logs.append)
    told.clear()
    b = convert(plain, tmp_path / "b.bvh", cache_dir=None, progress=False, jobs=1,
                log=told.append)
    assert any(m.startswith("camera perspective") for m in logs)
    assert not any("the camera looks" in m for m in told), told
    np.testing.assert_array_equal(a.image_joints2d, b.image_joints2d)
