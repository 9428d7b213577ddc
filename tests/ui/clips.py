"""Test-only stage results for the annotate page, made from a sample clip's ground truth.

The pipeline gives the page a :class:`vidcap.ui.session.ClipData`; these tests build one from
``sample_videos/<clip>_truth.npz`` instead (true 2D joints and silhouettes), so the page
and the session can be tested exactly, independently of the fitters' accuracy.
Nothing here is used by the library or the CLI.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from vidcap.ui.session import ClipData

from vidcap.io.video import read_frames

REPO = Path(__file__).resolve().parents[2]
SAMPLES = REPO / "sample_videos"


def truth_clip(name: str = "walk_side", *, poor_fit=(5,)) -> ClipData:
    """ClipData for ``sample_videos/<name>.mp4`` from its truth file (joints named by the
    body's true sides).

    ``poor_fit`` lists frames given a low fit score (to be flagged).
    """
    video = SAMPLES / f"{name}.mp4"
    t = np.load(SAMPLES / f"{name}_truth.npz")
    frames = read_frames(video)
    j2 = t["joints2d"].astype(float)
    fit = np.ones(len(j2))
    fit[list(poor_fit)] = 0.3
    return ClipData(video=video, fps=float(t["fps"]), read_frame=lambda i: frames[i],
                    joints2d=j2, masks=t["masks"], fit_score=fit, image_sides=False)
