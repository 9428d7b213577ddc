"""A rendered walk for the tests that need a video to convert (cache, interrupts)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def synth_walk(folder: Path, n_frames: int, size: tuple[int, int], seed: int) -> Path:
    """``folder/walk.mp4``: the built-in walk rendered at ``size``, ``n_frames`` long."""
    from vidcap.synth import make_motion, synth_clip

    video = folder / "walk.mp4"
    synth_clip(video, folder / "truth.npz", make_motion("walk", n_frames=n_frames), size=size,
               rng=np.random.default_rng(seed), show_progress=False)
    return video
