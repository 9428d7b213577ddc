"""Hostile videos: an unknown codec FourCC and an absurd header frame rate in the real
Weizmann AVI get one line naming the file (exit 2), not a traceback or a MemoryError."""

from __future__ import annotations

import struct

import pytest

from tests.hostile.mutate import digest, first_error, listing, outcome, run_capped


def avi_set(data: bytes, field: str, value) -> bytes:
    """A copy of an AVI with its first video stream's codec FourCC or rate rewritten."""
    out = bytearray(data)
    strh, strf = data.find(b"strh"), data.find(b"strf")
    if field == "fourcc":
        out[strh + 12:strh + 16] = value  # strh.fccHandler
        out[strf + 24:strf + 28] = value  # BITMAPINFOHEADER.biCompression
    elif field == "rate":
        struct.pack_into("<II", out, strh + 28, 1, value)  # dwScale, dwRate
    return bytes(out)


@pytest.fixture
def avi(shared_data):
    return shared_data("video/ido_walk.avi").read_bytes()


def _run(tmp_path, bad, *args):
    before, files = digest([bad]), listing(tmp_path)
    run = run_capped([*args], cwd=tmp_path, timeout=120)
    return run, outcome(run, name=str(bad), inputs_before=before, inputs_after=digest([bad]),
                        files_before=files, files_after=listing(tmp_path))


@pytest.mark.parametrize("command", ["info", "convert"])
def test_unknown_codec_is_named(avi, tmp_path, command):
    bad = tmp_path / "zz.avi"
    bad.write_bytes(avi_set(avi, "fourcc", b"ZZZZ"))
    args = ["info", bad] if command == "info" else ["convert", bad, "-o", tmp_path / "o.bvh",
                                                    "--no-cache"]
    run, got = _run(tmp_path, bad, *args)
    assert got == "clean error", run.stderr[-800:]
    assert "cannot decode: codec 'ZZZZ' not supported" in first_error(run)


def test_absurd_frame_rate_is_refused_not_allocated(avi, tmp_path):
    bad = tmp_path / "fast.avi"
    bad.write_bytes(avi_set(avi, "rate", 1_000_000_000))
    run, got = _run(tmp_path, bad, "convert", bad, "-o", tmp_path / "o.bvh", "--no-cache")
    assert got == "clean error", run.stderr[-800:]
    assert "frame rate" in first_error(run)


def test_rate_from_the_packets_when_the_header_is_absurd(tmp_path, monkeypatch):
    """A container whose header rate is absurd but whose timestamps are not: the rate
    and the count come from the packets."""
    import av
    import numpy as np

    from vidcap.io import video

    path = tmp_path / "v.mkv"
    with av.open(str(path), "w") as out:
        s = out.add_stream("mpeg4", rate=10)
        s.width, s.height, s.pix_fmt = 64, 48, "yuv420p"
        for i in range(20):
            f = av.VideoFrame.from_ndarray(np.full((48, 64, 3), i * 10, np.uint8), "rgb24")
            for p in s.encode(f):
                out.mux(p)
        for p in s.encode():
            out.mux(p)
    real = video._fps
    monkeypatch.setattr(video, "_fps", lambda st: 1e9)  # what a corrupt header would say
    info = video.probe(path)
    monkeypatch.setattr(video, "_fps", real)
    assert info.n_frames == 20
    assert info.fps == pytest.approx(10.0, rel=0.01)


def _ts_clip(path, width, height, frames, seed):
    """A short MPEG-TS H.264 clip: a block crossing a grey, noisy scene."""
    import av
    import numpy as np

    rng = np.random.default_rng(seed)
    with av.open(str(path), "w", format="mpegts") as out:
        stream = out.add_stream("libx264", rate=25)
        stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
        for i in range(frames):
            img = np.full((height, width, 3), 120, np.uint8)
            img[height // 4:3 * height // 4, 10 + 3 * i:30 + 3 * i] = (200, 40, 40)
            img = img + rng.integers(0, 5, img.shape, dtype=np.uint8)
            out.mux(stream.encode(av.VideoFrame.from_ndarray(img, format="rgb24")))
        out.mux(stream.encode())


def test_frame_size_change_mid_stream_is_named(tmp_path):
    """Two MPEG-TS streams of different sizes joined byte for byte decode as one video whose
    frames change size at the join: `convert` names the file and the frame, exit 2."""
    a, b, bad = tmp_path / "a.ts", tmp_path / "b.ts", tmp_path / "joined.ts"
    _ts_clip(a, 160, 120, 30, 0)
    _ts_clip(b, 200, 150, 30, 1)
    bad.write_bytes(a.read_bytes() + b.read_bytes())
    a.unlink()
    b.unlink()
    run, got = _run(tmp_path, bad, "convert", bad, "-o", tmp_path / "o.bvh", "--no-cache")
    assert got == "clean error", run.stderr[-800:]
    line = first_error(run)
    assert "joined.ts" in line and "frame size changes mid-stream" in line, line
