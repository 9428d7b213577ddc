"""Video input and output through PyAV (FFmpeg).

OpenCV is never used to read or write video here: OpenCV 4.13 and later abort the
whole Python process on some valid files (the uncompressed Weizmann AVI in
``../shared/data/video/``). Frames are ``(H, W, 3) uint8`` BGR, as OpenCV's image
functions expect them.

Every problem a user can cause (missing, empty, truncated, not a video, no video
stream) raises :class:`vidcap.errors.VideoError` naming the file.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from vidcap.errors import VideoError
from vidcap.fileio import atomic_path

#: The problem a :class:`~vidcap.errors.VideoError` names when a read yields no frame.
NO_FRAMES = "no decodable video frames"


@dataclass(frozen=True)
class VideoInfo:
    """What a video file holds.

    Attributes
    ----------
    path : str
    n_frames : int
        Number of decodable video frames.
    fps : float
        Average frame rate, frames per second.
    width, height : int
        Frame size in pixels, as shown (after ``rotation``).
    codec : str
        FFmpeg's name of the video codec.
    rotation : int
        Degrees counter-clockwise (0, 90, 180 or 270) by which the container's
        display matrix turns the stored frames to show them upright (phones store
        portrait video as landscape frames plus this); :func:`iter_frames` yields
        them turned.
    """

    path: str
    n_frames: int
    fps: float
    width: int
    height: int
    codec: str
    rotation: int = 0

    @property
    def duration(self) -> float:
        """Length in seconds."""
        return self.n_frames / self.fps


def _open(path: str | os.PathLike):
    import av

    p = Path(path)
    if not p.exists():
        raise VideoError("no such file", p)
    if p.is_dir():
        raise VideoError("is a folder, not a video file", p)
    if p.stat().st_size == 0:
        raise VideoError("the file is empty (0 bytes)", p)
    try:
        container = av.open(str(p), mode="r")
    except av.error.FFmpegError as exc:
        raise VideoError(f"not a readable video ({_ffmpeg_reason(exc)})", p) from None
    except (OSError, ValueError) as exc:
        raise VideoError(f"cannot open ({exc})", p) from None
    if not container.streams.video:
        kinds = sorted({s.type for s in container.streams}) or ["no streams"]
        container.close()
        raise VideoError(f"has no video stream (only {', '.join(kinds)})", p)
    if container.streams.video[0].codec_context is None:  # FFmpeg has no such decoder
        container.close()
        raise VideoError(f"cannot decode: codec {_fourcc(p)!r} not supported", p)
    return container


def _fourcc(path: Path) -> str:
    """The video codec's FourCC as the container names it (AVI ``strf``/``strh``, MP4
    and MOV ``stsd``), for the error when FFmpeg has no decoder (PyAV cannot say)."""
    with open(path, "rb") as fh:
        head = fh.read(1 << 20)
    i = head.find(b"strf")
    if i >= 0 and len(head) >= i + 28:
        tag = head[i + 24:i + 28]  # BITMAPINFOHEADER.biCompression
    elif (i := head.find(b"stsd")) >= 0 and len(head) >= i + 20:
        tag = head[i + 16:i + 20]  # the first sample entry's format
    else:
        return "unknown"
    return tag.decode("latin-1") if tag.isascii() and tag.strip(b"\0") else tag.hex()


def _ffmpeg_reason(exc) -> str:
    msg = getattr(exc, "strerror", None) or str(exc)
    return msg.split(":")[-1].strip() if msg else type(exc).__name__


def _fps(stream) -> float:
    rate = stream.average_rate or stream.guessed_rate or stream.base_rate
    return float(rate) if rate else 0.0


#: Frame rates a camera records at; outside them the header is not believed.
FPS_RANGE = (0.5, 1000.0)


def _sane_fps(fps: float) -> bool:
    return FPS_RANGE[0] <= fps <= FPS_RANGE[1]


def _rate_from_packets(container, stream, path) -> tuple[int, float]:
    """(frame count, frame rate) from the packets' timestamps, for an absurd header.

    Raises VideoError when the timestamps give no believable rate either.
    """
    pts = [p.pts for p in container.demux(stream) if p.size and p.pts is not None]
    header = _fps(stream)
    if len(pts) < 2:
        raise VideoError(f"frame rate {header:g} fps in the header, and no timestamps to"
                         " tell the real one", path)
    span = (max(pts) - min(pts)) * float(stream.time_base or 0)
    fps = (len(pts) - 1) / span if span > 0 else 0.0
    if not _sane_fps(fps):
        raise VideoError(f"frame rate {header:g} fps in the header and {fps:g} fps from the"
                         f" timestamps: outside {FPS_RANGE[0]:g}..{FPS_RANGE[1]:g} fps", path)
    return len(pts), fps


def probe(path: str | os.PathLike, *, count: bool = False) -> VideoInfo:
    """Read a video's metadata.

    Parameters
    ----------
    path : str or path-like
        Any file FFmpeg can read.
    count : bool
        Count the frames by decoding the whole file instead of trusting the
        container's frame count (slower; also proves the file decodes to the end).

    Returns
    -------
    VideoInfo

    Raises
    ------
    VideoError
        The file is missing, empty, not a video, has no video stream or has no
        decodable frame.
    """
    import av

    container = _open(path)
    try:
        stream = container.streams.video[0]
        n = int(stream.frames or 0)
        fps = _fps(stream)
        w, h = stream.codec_context.width, stream.codec_context.height
        codec = stream.codec_context.name
        turns = 0
        if count or n <= 0:
            n = 0
            try:
                for frame in container.decode(stream):
                    if n == 0:
                        turns = _quarter_turns(frame)
                        w, h = frame.width, frame.height  # what decodes, not the header
                    n += 1
            except av.error.FFmpegError as exc:
                if n == 0:
                    raise VideoError(f"no decodable frame ({_ffmpeg_reason(exc)})", path)\
                        from None
        else:
            try:  # the display matrix and the true size come with the decoded frames
                first = next(iter(container.decode(stream)), None)
            except av.error.FFmpegError:
                first = None  # reported by whatever decodes the file next
            if first is not None:
                turns, w, h = _quarter_turns(first), first.width, first.height
        if n <= 0:
            raise VideoError("the video stream has no frames", path)
        if not fps > 0:
            fps = 25.0
        if not _sane_fps(fps) or n > os.path.getsize(path):  # no frame takes under a byte
            container.seek(0)
            n, fps = _rate_from_packets(container, stream, path)
    finally:
        container.close()
    if turns % 2:
        w, h = h, w
    return VideoInfo(str(path), n, fps, int(w), int(h), codec, 90 * turns)


def frame_times(path: str | os.PathLike) -> np.ndarray | None:
    """Presentation time of every frame, from the container's timestamps.

    Only the packets are read, not decoded (a few ms for a minute of video).

    Parameters
    ----------
    path : str or path-like
        The video.

    Returns
    -------
    numpy.ndarray, shape (F,), or None
        Seconds from the first frame, increasing, in the order :func:`iter_frames`
        yields the frames; None where the container keeps no usable timestamps (a
        packet without one, or two frames at the same time).

    Raises
    ------
    VideoError
        The file cannot be opened or has no video stream.
    """
    import av

    container = _open(path)
    try:
        stream = container.streams.video[0]
        pts = []
        for packet in container.demux(stream):
            if packet.size == 0:  # the demuxer's end-of-stream flush packet
                continue
            if packet.pts is None:
                return None
            pts.append(int(packet.pts))
        tb = stream.time_base
    except av.error.FFmpegError:
        return None  # reported by whatever decodes the file next
    finally:
        container.close()
    if not pts or tb is None:
        return None
    t = np.sort(np.asarray(pts, dtype=np.int64))
    if len(t) > 1 and not (np.diff(t) > 0).all():
        return None
    return (t - t[0]) * float(tb)


def variable_rate(times, fps: float, *, tolerance: float = 0.5) -> bool:
    """Whether frames at ``times`` are not evenly spaced at ``fps``.

    True when some interval differs from ``1 / fps`` by more than ``tolerance``
    frame intervals, or the last frame is more than one interval away from where
    an even rate would put it (a slow drift).

    Parameters
    ----------
    times : array_like, shape (F,)
        Seconds (:func:`frame_times`).
    fps : float
        The nominal rate.
    tolerance : float
        Allowed deviation of one interval, in frame intervals.
    """
    t = np.asarray(times, dtype=float)
    if len(t) < 2 or not fps > 0:
        return False
    step = 1.0 / fps
    drift = abs((t[-1] - t[0]) - (len(t) - 1) * step)
    return bool(np.abs(np.diff(t) - step).max() > tolerance * step or drift > step)


def _quarter_turns(frame) -> int:
    """Quarter turns counter-clockwise (0-3) that show a decoded frame upright: its
    display matrix's rotation, rounded to a multiple of 90 degrees (flips and other
    angles are left alone; a PyAV without ``VideoFrame.rotation``: 0)."""
    try:
        return int(round(float(getattr(frame, "rotation", 0) or 0) / 90.0)) % 4
    except (TypeError, ValueError, OverflowError):  # a singular matrix (NaN)
        return 0


def iter_frames(
    path: str | os.PathLike, *, start: int = 0, stop: int | None = None, step: int = 1,
    only=None,
) -> Iterator[np.ndarray]:
    """Decode frames one at a time.

    Parameters
    ----------
    path : str or path-like
        The video.
    start, stop, step : int
        Which frames (0-based, ``stop`` exclusive), as in ``range``.
    only : collection of int, optional
        Of those, only these frame indices (the others are decoded, as they must
        be, but not converted to arrays: the colour conversion is most of a frame's
        cost).

    Yields
    ------
    numpy.ndarray, shape (H, W, 3), uint8
        BGR frames, upright: turned as the container's display matrix says (a phone's
        portrait video), so (H, W) is :func:`probe`'s ``(height, width)``.

    Raises
    ------
    VideoError
        On any decoding problem; frames already yielded stay valid. A file that
        yields no frame at all is an error too.
    """
    if start < 0 or step < 1:
        raise ValueError("start must be >= 0 and step >= 1")
    n = 0
    for i, frame, turns in _decoded(path, stop):
        if i < start or (i - start) % step or (only is not None and i not in only):
            continue
        n += 1
        img = _to_bgr(frame)
        yield _upright(img, turns)
    if n == 0 and (stop is None or stop > start):
        raise VideoError(NO_FRAMES, path)


def iter_thumbnails(
    path: str | os.PathLike, size: tuple[int, int], *, every: int = 1, only=(),
) -> Iterator[tuple[int, np.ndarray | None, np.ndarray | None]]:
    """Decode a video once for a look at every frame at low resolution and a few whole
    frames (the plate's samples and its evidence over time, :mod:`vidcap.video.timecover`).

    Parameters
    ----------
    path : str or path-like
        The video.
    size : (int, int)
        (width, height) of the thumbnails, as shown (after the display matrix's turn).
    every : int
        A thumbnail of every ``every``-th frame (0, every, 2 every, ...).
    only : collection of int
        Frame indices also yielded whole.

    Yields
    ------
    index : int
    thumbnail : numpy.ndarray, shape (height, width, 3), uint8, or None
        BGR, downscaled by area averaging (None for frames between the ``every``-th).
    frame : numpy.ndarray, shape (H, W, 3), uint8, or None
        The whole BGR frame for indices in ``only``, else None.

    Raises
    ------
    VideoError
        As :func:`iter_frames`.
    """
    if every < 1:
        raise ValueError("every must be >= 1")
    w, h = int(size[0]), int(size[1])
    n = 0
    for i, frame, turns in _decoded(path, None):
        n += 1
        thumb = img = None
        if i % every == 0:
            # (stored frames are turned after the scaling: a quarter turn swaps the sides)
            tw, th = (h, w) if turns % 2 else (w, h)
            thumb = _to_bgr(frame, width=tw, height=th, interpolation="AREA")
            thumb = _upright(thumb, turns)
        if i in only:
            img = _upright(_to_bgr(frame), turns)
        if thumb is not None or img is not None:
            yield i, thumb, img
    if n == 0:
        raise VideoError(NO_FRAMES, path)


def _upright(img: np.ndarray, turns: int) -> np.ndarray:
    """``img`` turned by ``turns`` quarter turns (the display matrix's), contiguous."""
    return np.ascontiguousarray(np.rot90(img, turns)) if turns else img


def _decoded(path, stop):
    """(index, PyAV frame, quarter turns) of each decoded frame before ``stop``; decoding
    errors as :class:`VideoError` (frames already yielded stay valid)."""
    import av

    container = _open(path)
    n = 0
    turns = None
    try:
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        for i, frame in enumerate(container.decode(stream)):
            if turns is None:
                turns = _quarter_turns(frame)
            if stop is not None and i >= stop:
                break
            n += 1
            yield i, frame, turns
    except av.error.FFmpegError as exc:
        raise VideoError(f"decoding failed after {n} frames ({_ffmpeg_reason(exc)})", path)\
            from None
    finally:
        container.close()


#: Whether this PyAV's ``VideoFrame.reformat`` takes ``threads`` (PyAV >= 17).
_REFORMAT_THREADS: bool | None = None


def _to_bgr(frame, **scale) -> np.ndarray:
    """One decoded frame as an (H, W, 3) uint8 BGR array, converted on this thread
    (``scale``: ``width``, ``height`` and ``interpolation`` of a downscaled copy).

    PyAV >= 17 converts on one thread per CPU by default. Each frame then waits for
    its slowest slice, and any other busy process (the 2D fit's workers) stalls
    it: on 2 CPUs with one other busy process the colour conversion of a 640x480
    H.264 clip took 3.6x as long as on one thread, which is also faster when
    nothing else runs (0.36 against 0.69 s for 300 frames). The pixels are the same.
    """
    global _REFORMAT_THREADS
    if _REFORMAT_THREADS is None:
        try:
            out = frame.to_ndarray(format="bgr24", threads=1, **scale)
        except TypeError:  # PyAV < 17: no threads argument, and one thread anyway
            _REFORMAT_THREADS = False
        else:
            _REFORMAT_THREADS = True
            return out
    if _REFORMAT_THREADS:
        return frame.to_ndarray(format="bgr24", threads=1, **scale)
    return frame.to_ndarray(format="bgr24", **scale)


def iter_frame_lists(
    path: str | os.PathLike, *, chunk_size: int = 64, start: int = 0, stop: int | None = None
) -> Iterator[list[np.ndarray]]:
    """Decode frames in lists of up to ``chunk_size`` consecutive (H, W, 3) uint8 BGR
    frames, so a long video never sits in memory whole (and no frame is copied)."""
    buf: list[np.ndarray] = []
    for frame in iter_frames(path, start=start, stop=stop):
        buf.append(frame)
        if len(buf) == chunk_size:
            yield buf
            buf = []
    if buf:
        yield buf


def iter_chunks(
    path: str | os.PathLike, *, chunk_size: int = 64, start: int = 0, stop: int | None = None
) -> Iterator[np.ndarray]:
    """Decode frames in chunks, so a long video never sits in memory whole.

    Yields
    ------
    numpy.ndarray, shape (n, H, W, 3), uint8
        Up to ``chunk_size`` consecutive BGR frames.
    """
    for frames in iter_frame_lists(path, chunk_size=chunk_size, start=start, stop=stop):
        yield np.stack(frames)


def read_frames(
    path: str | os.PathLike, *, start: int = 0, stop: int | None = None, step: int = 1
) -> np.ndarray:
    """Decode frames into one array, shape (F, H, W, 3) uint8 BGR."""
    return np.stack(list(iter_frames(path, start=start, stop=stop, step=step)))


class VideoWriter:
    """Write BGR frames to an H.264 MP4 (or any container FFmpeg knows), atomically.

    The file appears under its final name only when :meth:`close` succeeds (use it
    as a context manager); an exception inside the ``with`` block leaves nothing.

    Parameters
    ----------
    path : str or path-like
        Output file; H.264 (yuv420p) in the container its suffix names (``.mp4``,
        ``.mkv``, ``.mov``, ``.avi``).
    fps : float
        Frame rate.
    crf : int
        H.264 constant rate factor (lower is better quality; 18 is visually lossless).
    """

    def __init__(self, path: str | os.PathLike, fps: float, *, crf: int = 20):
        self.path = Path(path)
        self.fps = fps
        self.crf = crf
        self._ctx = atomic_path(self.path)
        self._tmp = None
        self._container = None
        self._stream = None
        self.n_frames = 0

    def __enter__(self):
        self._tmp = self._ctx.__enter__()
        return self

    def _start(self, h: int, w: int):
        import av

        if self._tmp is None:
            self.__enter__()
        self._container = av.open(str(self._tmp), mode="w", format=_format_for(self.path))
        rate = Fraction(self.fps).limit_denominator(1001)
        stream = self._container.add_stream("libx264", rate=rate)
        # yuv420p needs even sizes; pad by one pixel where needed.
        stream.width, stream.height = w + (w % 2), h + (h % 2)
        stream.pix_fmt = "yuv420p"
        stream.options = {"crf": str(self.crf), "preset": "veryfast"}
        self._stream = stream

    def write(self, frame: np.ndarray) -> None:
        """Append one (H, W, 3) uint8 BGR frame (or a stack (n, H, W, 3))."""
        import av

        frame = np.asarray(frame)
        if frame.ndim == 4:
            for f in frame:
                self.write(f)
            return
        if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise ValueError(f"frames must be (H, W, 3) uint8, got {frame.shape} {frame.dtype}")
        if self._stream is None:
            self._start(*frame.shape[:2])
        h, w = self._stream.height, self._stream.width
        if frame.shape[:2] != (h, w):
            if frame.shape[0] > h or frame.shape[1] > w:
                raise ValueError("all frames must have the size of the first")
            frame = np.pad(frame, ((0, h - frame.shape[0]), (0, w - frame.shape[1]), (0, 0)),
                           mode="edge")
        vf = av.VideoFrame.from_ndarray(np.ascontiguousarray(frame), format="bgr24")
        for packet in self._stream.encode(vf):
            self._container.mux(packet)
        self.n_frames += 1

    def close(self) -> None:
        """Flush the encoder and move the file into place."""
        if self._container is not None:
            for packet in self._stream.encode():
                self._container.mux(packet)
            self._container.close()
            self._container = None
        if self._tmp is not None:
            if self.n_frames == 0:
                raise ValueError(f"{self.path}: no frames were written")
            self._ctx.__exit__(None, None, None)
            self._tmp = None

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.close()
            return False
        if self._container is not None:
            try:
                self._container.close()
            except Exception:  # noqa: BLE001 - the original error matters more
                pass
            self._container = None
        self._ctx.__exit__(exc_type, exc, tb)
        self._tmp = None
        return False


def _format_for(path: Path) -> str | None:
    return {".mp4": "mp4", ".m4v": "mp4", ".mov": "mov", ".mkv": "matroska",
            ".avi": "avi"}.get(path.suffix.lower())


def write_video(path: str | os.PathLike, frames, fps: float, *, crf: int = 20) -> int:
    """Write an iterable of (H, W, 3) uint8 BGR frames to ``path``; return the count."""
    with VideoWriter(path, fps, crf=crf) as writer:
        for frame in frames:
            writer.write(frame)
    return writer.n_frames
