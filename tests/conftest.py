"""Shared fixtures: where the real data is, and how to run the CLI."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"


def _need_shared(path: Path) -> Path:
    if path.exists():
        return path
    if os.environ.get("CI") == "true":
        pytest.fail(f"{path} is missing; CI must have ../shared/data beside the clone")
    pytest.skip(f"{path} is not here (../shared/data is only beside the project's own clones)")


@pytest.fixture
def shared_data():
    """Return a function mapping a path under ``../shared/data`` to an existing Path.

    Skips the test when the data is absent, except under ``CI=true`` where it fails.
    """
    return lambda rel: _need_shared(SHARED_DATA / rel)


def run_cli(
    *args: str, cwd: Path | None = None, timeout: float = 600
) -> subprocess.CompletedProcess:
    """Run ``python -m vidcap ARGS`` in a subprocess and capture its output."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")
    return subprocess.run(
        [sys.executable, "-m", "vidcap", *map(str, args)],
        cwd=cwd or REPO, env=env, capture_output=True, text=True, timeout=timeout,
    )


@pytest.fixture
def cli():
    """The :func:`run_cli` helper as a fixture."""
    return run_cli


def write_timed_video(path: Path, frames, times_s) -> None:
    """Write BGR frames to an H.264 MP4 shown at the given times (seconds): a
    variable-rate video, as phones record or as a dropped frame leaves one."""
    from fractions import Fraction

    import av
    import numpy as np

    ms = Fraction(1, 1000)
    with av.open(str(path), "w") as out:
        stream = out.add_stream("libx264", rate=30)
        stream.height, stream.width = frames[0].shape[:2]
        stream.pix_fmt = "yuv420p"
        stream.codec_context.time_base = ms
        for img, t in zip(frames, times_s, strict=True):
            vf = av.VideoFrame.from_ndarray(np.ascontiguousarray(img), format="bgr24")
            vf.pts, vf.time_base = int(round(t * 1000)), ms
            for packet in stream.encode(vf):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
