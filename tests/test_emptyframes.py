"""The plate from frames named as the empty scene, ``--background START:END``
(vidcap.video.emptyframes)."""

from __future__ import annotations

import numpy as np
import pytest

from tests._synthframes import background
from vidcap.errors import InputFileError
from vidcap.io.video import write_video
from vidcap.video.background import load_plate
from vidcap.video.emptyframes import empty_plate, frame_range, given_plate_identity


def test_frame_ranges_and_what_is_no_range(tmp_path):
    assert frame_range("0:80") == (0, 80)
    assert frame_range(":80") == (0, 80)
    assert frame_range("400:") == (400, None)
    assert frame_range(" 3 : 9 ") == (3, 9)
    assert frame_range("plate.png") is None
    assert frame_range("1:2:3") is None and frame_range("-1:4") is None
    odd = tmp_path / "1:2"  # a file of that name is the image, not frames
    odd.write_bytes(b"x")
    assert frame_range(odd) is None


def _arrives_and_stays(tmp_path, n_empty=8, n_stay=16):
    """A textured scene, empty for ``n_empty`` frames; then a block (the person) that
    stands in one place to the end, swaying by a pixel: no frame after the first
    ``n_empty`` shows the scene behind it."""
    rng = np.random.default_rng(5)
    scene = background(96, 128, rng)
    frames, masks = [], []
    for i in range(n_empty + n_stay):
        f = scene.copy()
        m = np.zeros((96, 128), bool)
        if i >= n_empty:
            x = 50 + (i % 2)
            m[20:90, x:x + 24] = True
            f[m] = (30, 40, 200)
        frames.append(f)
        masks.append(m)
    video = tmp_path / "stays.mkv"
    write_video(video, frames, 25, crf=10)
    return video, scene, np.array(masks)


def test_the_plate_is_the_scene_the_named_frames_show(tmp_path):
    video, scene, _ = _arrives_and_stays(tmp_path)
    model = load_plate("0:8", video)  # as convert and silhouettes read --background
    assert model.plate.shape == scene.shape and not model.never_seen.any()
    err = np.abs(model.plate.astype(int) - scene.astype(int))
    assert np.median(err) <= 3  # H.264 at crf 10
    assert np.median(err[20:90, 50:75]) <= 3  # where the person stands later
    # the later frames are the person: a plate from them holds the block
    later = empty_plate(video, 8, None)
    assert np.median(np.abs(later[20:90, 52:72].astype(int) - (30, 40, 200))) <= 12


def test_the_person_who_stays_is_found_against_that_plate(tmp_path, cli):
    video, _, truth = _arrives_and_stays(tmp_path)
    out = tmp_path / "m.npz"
    r = cli("silhouettes", video, "-o", out, "--background", ":8")
    assert r.returncode == 0, r.stderr
    with np.load(out) as z:
        got = z["masks"][8:]
    iou = (got & truth[8:]).sum((1, 2)) / (got | truth[8:]).sum((1, 2))
    assert np.median(iou) > 0.9


def test_frames_outside_the_video_are_one_clear_error(tmp_path, cli):
    video, _, _ = _arrives_and_stays(tmp_path)
    with pytest.raises(InputFileError, match="holds no frame of the video, which has 24"):
        empty_plate(video, 30, 40)
    with pytest.raises(InputFileError, match="names no frame: END must be after START"):
        empty_plate(video, 5, 5)
    out = tmp_path / "m.npz"
    r = cli("silhouettes", video, "-o", out, "--background", "30:40")
    assert r.returncode == 2 and not out.exists()
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "stays.mkv" in lines[0] and "30:40" in lines[0]
    assert "Traceback" not in r.stderr


def test_the_stage_cache_tells_ranges_and_images_apart(tmp_path):
    video_id = {"path": "/v.mp4", "size": 1, "mtime_ns": 2}
    a = given_plate_identity("0:8", video_id)
    assert a != given_plate_identity("0:9", video_id)
    assert a != given_plate_identity("0:8", {**video_id, "size": 3})
    img = tmp_path / "plate.png"
    img.write_bytes(b"png")
    assert given_plate_identity(img, video_id)[0]["path"] == str(img.resolve())


def test_large_frames_take_fewer_samples(tmp_path, monkeypatch):
    import vidcap.io.video as vio
    import vidcap.video.emptyframes as ef

    video, scene, _ = _arrives_and_stays(tmp_path)
    asked = []
    real = vio.iter_frames

    def counting(path, **kw):
        asked.append(len(kw["only"]))
        return real(path, **kw)

    monkeypatch.setattr(vio, "iter_frames", counting)
    ef.empty_plate(video, 0, 8)
    monkeypatch.setattr(ef, "MAX_BYTES", 96 * 128 * 3 * 2)  # room for two frames: five
    plate = ef.empty_plate(video, 0, 8)
    assert asked == [8, ef.MIN_SAMPLES]
    assert np.median(np.abs(plate.astype(int) - scene.astype(int))) <= 3


def test_a_range_across_a_frame_size_change_is_one_clear_error(tmp_path):
    from tests.hostile.test_video import _ts_clip

    a, b, joined = tmp_path / "a.ts", tmp_path / "b.ts", tmp_path / "joined.ts"
    _ts_clip(a, 160, 120, 12, 0)
    _ts_clip(b, 200, 150, 12, 1)
    joined.write_bytes(a.read_bytes() + b.read_bytes())
    assert empty_plate(joined, 0, 10).shape == (120, 160, 3)  # before the join: fine
    with pytest.raises(InputFileError, match="the frame size changes within --background 0:"):
        empty_plate(joined, 0, None)
