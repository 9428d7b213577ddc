"""``benchmarks/inplace_real.py``: a walker kept in place, known answers on a drawn
clip (issue 26's real bodies on the spot)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from inplace_real import MIN_FRAMES, walk_in_place  # noqa: E402


def _crossing(n=40, h=60, w=160, seed=0):
    """A textured wall, a red walker 10x30 px crossing it left to right at 3 px a frame
    with a leg that swings, and a dark shadow a few pixels right of the feet."""
    rng = np.random.default_rng(seed)
    wall = rng.integers(90, 111, (h, w, 3)).astype(np.uint8)
    frames = np.repeat(wall[None], n, axis=0).copy()
    frames += rng.integers(0, 3, frames.shape).astype(np.uint8)  # sensor noise
    masks = np.zeros((n, h, w), bool)
    for k in range(n):
        x = 10 + 3 * k
        masks[k, 15:45, x:x + 10] = True  # head and torso
        leg = x + 2 + (4 if k % 4 < 2 else -2)
        masks[k, 45:55, leg:leg + 4] = True
        frames[k, 52:55, x + 16:x + 30] = 40  # the shadow, apart from the feet
    frames[masks] = (30, 30, 200)
    return frames, masks, wall


def test_the_walker_stays_at_the_centre_and_the_truth_moves_with_it():
    frames, masks, wall = _crossing()
    out, truth, ignore = walk_in_place(frames, masks)
    assert len(out) >= MIN_FRAMES and truth.shape == out.shape[:3]
    torso_cols = [np.nonzero(t[20:40].any(axis=0))[0].mean() for t in truth]
    assert np.ptp(torso_cols) <= 1.0  # the torso does not travel
    assert abs(np.mean(torso_cols) - 80) <= 1.0  # at the frame's centre
    legs = [tuple(np.nonzero(t[50])[0]) for t in truth]
    assert len(set(legs)) > 1  # the leg still swings
    # the truth is exactly the red pixels pasted; the rest is wall again (noise only),
    # the walker and its shadow at their old places filled from other frames
    assert (np.all(out == (30, 30, 200), axis=-1) == truth).all()
    rest = ~truth
    assert np.abs(out.astype(int) - wall.astype(int))[rest].max() <= 3
    assert not ignore.any()


def test_a_clip_where_the_walker_never_clears_its_place_is_refused():
    frames, masks, _ = _crossing(n=8)
    masks[:] = masks[0]  # the same place in every frame: nothing to fill from
    try:
        walk_in_place(frames, masks)
    except ValueError as err:
        assert "consecutive frames" in str(err)
    else:
        raise AssertionError("a walker who never leaves must be refused")
