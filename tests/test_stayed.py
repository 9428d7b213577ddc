"""The plate where a person came, stayed and went (vidcap.video.stayed)."""

from dataclasses import replace

import numpy as np

from vidcap.video import stayed
from vidcap.video.background import BackgroundModel, estimate_background
from vidcap.video.stayed import bracketed, retake_stayed

H, W, N, FPS = 96, 128, 150, 30.0
SPOT = (slice(30, 80), slice(54, 78))  # where the block stands
TABLE = (slice(45, 65), slice(60, 72))  # a dark table behind it, seen only when it is away


def _scene(rng):
    """A wall of smooth random shades with a dark table at TABLE (fixed over the clip)."""
    import cv2

    small = rng.integers(120, 200, (6, 8, 3)).astype(np.float32)
    base = cv2.resize(small, (W, H), interpolation=cv2.INTER_CUBIC)
    base[TABLE] = (30, 60, 90)
    return base


def _block(frame, x, rng):
    """A 50 x 24 block (a person) with its left edge at column ``x``, a dark-blue shirt
    with a little texture (it breathes: its shading changes from frame to frame)."""
    out = frame.copy()
    x0, x1 = max(0, int(round(x))), min(W, int(round(x)) + 24)
    if x1 > x0:
        out[30:80, x0:x1] = np.array([150, 40, 30]) + rng.normal(0, 3, (50, x1 - x0, 3))
    return out


def _clip(rng, path):
    """Frames (N, H, W, 3) uint8: the scene with sensor noise and the block at the
    columns ``path`` (N,) gives (NaN: out of view)."""
    base = _scene(rng)
    out = []
    for x in path:
        f = np.clip(base + rng.normal(0, 2, base.shape), 0, 255)
        out.append(f if np.isnan(x) else _block(f, x, rng))
    return np.clip(np.stack(out), 0, 255).astype(np.uint8), base


def _arriving():
    """Walks in from the left edge (frames 0-14), stands at SPOT (15-134: 80 % of the
    clip), walks out to the right (135-149)."""
    x = np.full(N, 54.0)
    x[:15] = np.linspace(-30, 54, 15)
    x[135:] = np.linspace(54, 140, 15)
    return x


def test_the_plate_under_a_block_that_came_stayed_and_went_is_the_scene():
    rng = np.random.default_rng(0)
    frames, base = _clip(rng, _arriving())
    bg = estimate_background(frames, rng=np.random.default_rng(0))
    err = np.abs(bg.plate[TABLE].astype(np.float32) - base[TABLE]).max(axis=-1)
    assert np.median(err) < 10 and (err < 20).mean() > 0.9
    assert not bg.never_seen[TABLE].any()
    # Without the pass the plate there is the block or a guess, not the scene.
    stayed.STAYED = False
    try:
        off = estimate_background(frames, rng=np.random.default_rng(0))
    finally:
        stayed.STAYED = True
    err = np.abs(off.plate[TABLE].astype(np.float32) - base[TABLE]).max(axis=-1)
    assert (err < 20).mean() < 0.5


def test_a_block_in_view_from_first_to_last_frame_is_not_bracketed():
    # The same block in place all along, swaying a few pixels (an in-place performer):
    # the ends show the block, not the scene; nothing is re-taken.
    rng = np.random.default_rng(1)
    frames, base = _clip(rng, 54 + 3 * np.sin(np.arange(N) / 5.0))
    plate = base.copy()
    plate[SPOT] = 120  # the plate's guess where the block always is
    model = replace(BackgroundModel.from_plate(plate.astype(np.uint8), noise_sigma=2.0),
                    sample_indices=np.arange(N), n_samples=N)
    out = retake_stayed(model, frames, np.ones((N, 3), np.float32), frames, step=1, fps=FPS)
    assert out is model


def test_bracketed_needs_the_stay_between_the_ends():
    # One pixel's colours over 40 frames: scene (50) at both ends, a person (200) in
    # between. Staying for 30 frames in one run: bracketed. The same person leaving it
    # every third frame of those 30 (a limb's passes) is not.
    n, end = 40, 5
    stay = np.full((n, 1, 1, 3), 50, np.uint8)
    stay[5:35] = 200
    passes = stay.copy()
    passes[5:35:3] = 50
    plate = np.full((1, 1, 3), 200, np.uint8)
    out = [bracketed(x, np.ones((n, 1, 1), bool), plate, 10.0, end, np.zeros((1, 1), bool))
           for x in (stay, passes)]
    assert out[0][0].all() and np.allclose(out[0][1], 50)
    assert not out[1][0].any()
    # Nor is a pixel whose plate already shows the scene, nor one whose ends show the
    # person (there at the first frame and at the last).
    scene_plate = np.full((1, 1, 3), 50, np.uint8)
    for p, x in ((scene_plate, stay), (plate, np.roll(stay, 10, 0))):
        assert not bracketed(x, np.ones((n, 1, 1), bool), p, 10.0, end,
                             np.zeros((1, 1), bool))[0].any()
