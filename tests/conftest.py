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
