"""Video I/O through PyAV: reading real files, writing H.264, and clear errors."""

from __future__ import annotations

import subprocess
import sys

import av
import cv2
import numpy as np
import pytest

from tests.conftest import write_timed_video
from vidcap.errors import VideoError
from vidcap.io.video import (
    VideoWriter,
    frame_times,
    iter_chunks,
    iter_frame_lists,
    iter_frames,
    iter_thumbnails,
    probe,
    read_frames,
    variable_rate,
    write_video,
)


def _frames(n=12, h=48, w=64, seed=0):
    rng = np.random.default_rng(seed)
    # Smooth content so H.264 reproduces it closely.
    base = rng.integers(40, 200, size=(1, 1, 3))
    y, x = np.mgrid[0:h, 0:w]
    out = []
    for i in range(n):
        img = np.empty((h, w, 3), np.uint8)
        img[...] = base
        img[..., 0] = (x * 3 + i * 5) % 256
        img[..., 1] = (y * 4) % 256
        out.append(img)
    return np.stack(out)


def test_write_then_read_round_trip(tmp_path):
    frames = _frames()
    out = tmp_path / "clip.mp4"
    assert write_video(out, frames, fps=25) == len(frames)
    info = probe(out)
    assert (info.n_frames, info.width, info.height) == (12, 64, 48)
    assert info.fps == pytest.approx(25)
    back = read_frames(out)
    assert back.shape == frames.shape and back.dtype == np.uint8
    assert np.abs(back.astype(int) - frames).mean() < 6  # lossy, but close


def test_frames_converted_on_one_thread_are_pyav_defaults_pixels(tmp_path):
    """iter_frames converts on one thread (PyAV >= 17 would use one per CPU): the
    pixels must be exactly PyAV's default conversion."""
    out = tmp_path / "c.mp4"
    write_video(out, _frames(n=6, h=96, w=128), fps=10)
    with av.open(str(out)) as c:
        ref = [f.to_ndarray(format="bgr24") for f in c.decode(video=0)]
    got = list(iter_frames(out))
    assert len(got) == len(ref) == 6
    for a, b in zip(got, ref, strict=True):
        np.testing.assert_array_equal(a, b)


def test_frame_conversion_without_the_threads_argument(monkeypatch):
    """PyAV < 17 has no ``threads`` argument: the conversion falls back to its default."""
    import vidcap.io.video as V

    class OldFrame:
        def to_ndarray(self, format):  # noqa: A002 - PyAV's name
            return np.full((2, 3, 3), 7 if format == "bgr24" else 0, np.uint8)

    monkeypatch.setattr(V, "_REFORMAT_THREADS", None)
    assert (V._to_bgr(OldFrame()) == 7).all()
    assert V._REFORMAT_THREADS is False
    assert (V._to_bgr(OldFrame()) == 7).all()


def _rotated_clip(path, degrees, n=4, h=48, w=64):
    """An H.264 clip whose display matrix turns its frames ``degrees`` counter-clockwise
    (what a phone writes for portrait video); a white block at the stored top left."""
    img = np.zeros((h, w, 3), np.uint8)
    img[:12, :20] = 255
    with av.open(str(path), "w") as out:
        s = out.add_stream("libx264", rate=10)
        s.width, s.height, s.pix_fmt = w, h, "yuv420p"
        s.set_display_rotation(degrees)
        for _ in range(n):
            for p in s.encode(av.VideoFrame.from_ndarray(img, format="bgr24")):
                out.mux(p)
        for p in s.encode():
            out.mux(p)
    return img


@pytest.mark.skipif(not hasattr(av.video.stream.VideoStream, "set_display_rotation"),
                    reason="this PyAV cannot write a display matrix")
@pytest.mark.parametrize("degrees", [90, -90, 180])
def test_frames_come_out_upright_as_the_display_matrix_says(tmp_path, degrees):
    path = tmp_path / "phone.mp4"
    stored = _rotated_clip(path, degrees)
    info = probe(path)
    assert info.rotation == degrees % 360
    upright = np.rot90(stored, degrees // 90)
    assert (info.height, info.width) == upright.shape[:2]
    frames = list(iter_frames(path))
    assert len(frames) == 4
    for f in frames:
        assert f.shape == upright.shape and f.flags.c_contiguous
        assert np.abs(f.astype(int) - upright).mean() < 8  # lossy, but the same picture
    if degrees == 180:  # the same shape as stored, but not the stored picture
        assert np.abs(frames[0].astype(int) - stored).mean() > 30
    # thumbnails (the plate's look at every frame) are upright at the asked (width, height)
    th, tw = upright.shape[0] // 4, upright.shape[1] // 4
    thumbs = [t for _, t, _ in iter_thumbnails(path, (tw, th))]
    small = cv2.resize(upright, (tw, th), interpolation=cv2.INTER_AREA)
    assert len(thumbs) == 4 and all(t.shape == (th, tw, 3) for t in thumbs)
    assert np.abs(thumbs[0].astype(int) - small).mean() < 12


def test_frame_times_of_even_and_uneven_videos(tmp_path):
    even = tmp_path / "even.mp4"
    write_video(even, _frames(12), 25.0)
    t = frame_times(even)
    np.testing.assert_allclose(t, np.arange(12) / 25.0, atol=1e-9)
    assert not variable_rate(t, probe(even).fps)
    # frames 4 and 6 dropped: shown at their own times, 80 ms after the one before
    keep = [0, 1, 2, 3, 5, 7, 8, 9, 10, 11]
    uneven = tmp_path / "uneven.mp4"
    write_timed_video(uneven, _frames(12)[keep], np.array(keep) / 25.0)
    t = frame_times(uneven)
    np.testing.assert_allclose(t, np.array(keep) / 25.0, atol=1e-6)
    assert len(t) == probe(uneven, count=True).n_frames == len(read_frames(uneven))
    assert variable_rate(t, probe(uneven).fps)
    # a slow drift is uneven too: 2 % slow over 100 frames is two frames late
    assert variable_rate(np.arange(100) * 1.02 / 25.0, 25.0)
    assert not variable_rate(np.arange(100) * 1.002 / 25.0, 25.0)


def test_chunks_cover_every_frame_in_order(tmp_path):
    frames = _frames(n=10)
    out = tmp_path / "c.mp4"
    write_video(out, frames, fps=10)
    chunks = list(iter_chunks(out, chunk_size=4))
    assert [len(c) for c in chunks] == [4, 4, 2]
    np.testing.assert_array_equal(np.concatenate(chunks), read_frames(out))
    lists = list(iter_frame_lists(out, chunk_size=4))
    assert [len(c) for c in lists] == [4, 4, 2]
    np.testing.assert_array_equal(np.stack(sum(lists, [])), read_frames(out))


def test_only_the_chosen_frames_are_returned(tmp_path):
    frames = _frames(n=10)
    out = tmp_path / "o.mp4"
    write_video(out, frames, fps=10)
    every = read_frames(out)
    got = list(iter_frames(out, only={7, 2, 5}))
    np.testing.assert_array_equal(np.stack(got), every[[2, 5, 7]])
    assert len(list(iter_frames(out, start=3, only={1, 2, 4}))) == 1  # both apply


def test_thumbnails_of_every_nth_frame_and_whole_chosen_frames(tmp_path):
    out = tmp_path / "t.mp4"
    write_video(out, _frames(n=10), fps=10)
    every = read_frames(out)
    got = list(iter_thumbnails(out, (8, 6), every=3, only={4, 6}))
    assert [i for i, _, _ in got] == [0, 3, 4, 6, 9]
    assert [t is None for _, t, _ in got] == [False, False, True, False, False]
    assert [f is None for _, _, f in got] == [True, True, False, False, True]
    np.testing.assert_array_equal(got[2][2], every[4])
    assert got[0][1].shape == (6, 8, 3)
    with pytest.raises(ValueError):
        next(iter_thumbnails(out, (8, 6), every=0))


def test_failed_write_leaves_no_file(tmp_path):
    out = tmp_path / "broken.mp4"
    with pytest.raises(RuntimeError), VideoWriter(out, 25) as w:
        w.write(_frames(2)[0])
        raise RuntimeError("boom")
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


def test_ido_walk_reads_in_a_subprocess_that_exits_normally(shared_data):
    # OpenCV >= 4.13 aborts the whole process on this file; PyAV must read it.
    path = shared_data("video/ido_walk.avi")
    code = (
        "from vidcap.io.video import read_frames, probe;"
        f"a = read_frames({str(path)!r}); i = probe({str(path)!r});"
        "print(a.shape, a.dtype, i.n_frames, i.fps)"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["(43,", "144,", "180,", "3)", "uint8", "43", "25.0"]


@pytest.fixture
def bad_videos(tmp_path):
    good = tmp_path / "good.mp4"
    write_video(good, _frames(30), fps=25)
    data = good.read_bytes()
    files = {}
    files["empty"] = tmp_path / "empty.mp4"
    files["empty"].write_bytes(b"")
    files["text"] = tmp_path / "notes.mp4"
    files["text"].write_text("this is not a video\n" * 20)
    files["truncated"] = tmp_path / "truncated.mp4"
    files["truncated"].write_bytes(data[: len(data) // 3])
    files["audio"] = tmp_path / "tone.m4a"
    with av.open(str(files["audio"]), "w") as c:
        s = c.add_stream("aac", rate=8000)
        t = np.arange(4096, dtype=np.float32) / 8000
        frame = av.AudioFrame.from_ndarray(
            np.sin(2 * np.pi * 440 * t)[None].astype(np.float32), format="fltp", layout="mono"
        )
        frame.sample_rate = 8000
        for p in s.encode(frame):
            c.mux(p)
        for p in s.encode():
            c.mux(p)
    files["missing"] = tmp_path / "nope.mp4"
    return files


@pytest.mark.parametrize("kind", ["empty", "text", "truncated", "audio", "missing"])
def test_bad_inputs_raise_video_error_naming_the_file(bad_videos, kind):
    path = bad_videos[kind]
    with pytest.raises(VideoError) as err:
        read_frames(path)
        probe(path, count=True)
    assert str(path) in str(err.value)


@pytest.mark.parametrize("kind", ["empty", "text", "truncated", "audio"])
def test_bad_inputs_give_one_line_cli_error_and_exit_2(bad_videos, kind, cli):
    path = bad_videos[kind]
    r = cli("info", "--count", path)
    assert r.returncode == 2, r.stdout + r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith(f"vidcap: error: {path}: ")
    assert "Traceback" not in r.stderr


def test_info_on_a_good_clip(tmp_path, cli):
    out = tmp_path / "ok.mp4"
    write_video(out, _frames(7), fps=12)
    r = cli("info", out)
    assert r.returncode == 0, r.stderr
    assert "7 frames" in r.stdout and "64x48" in r.stdout


def test_info_lists_every_file_and_reports_the_bad_ones(bad_videos, tmp_path, cli):
    good = tmp_path / "ok.mp4"
    write_video(good, _frames(7), fps=12)
    r = cli("info", bad_videos["text"], good, tmp_path / "missing.mp4")
    assert r.returncode == 2
    assert r.stdout.strip().splitlines() == [f"{good}: 7 frames, 12 fps, 64x48, h264, 0.58 s"]
    errors = r.stderr.strip().splitlines()
    assert [e.split(": ")[2] for e in errors] == [str(bad_videos["text"]),
                                                  str(tmp_path / "missing.mp4")]


def test_outputs_get_ordinary_file_permissions(tmp_path):
    import os

    from vidcap.fileio import write_text_atomic

    umask = os.umask(0o022)
    try:
        write_text_atomic(tmp_path / "a.txt", "x")
    finally:
        os.umask(umask)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o644
