"""Fixtures for the UI tests: the sample clip's truth as stage results."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from clips import truth_clip  # noqa: E402


@pytest.fixture(scope="session")
def walk_clip():
    """ClipData of sample_videos/walk_side.mp4 from its ground truth (frame 5 fits poorly)."""
    return truth_clip("walk_side")
