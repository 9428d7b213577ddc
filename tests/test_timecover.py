"""The plate's motion evidence over every frame (vidcap.video.timecover)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from tests._synthframes import background, figure_mask
from vidcap.video import timecover
from vidcap.video.background import _frame_gains, estimate_background, sample_frames
from vidcap.video.regionvote import region_vote
from vidcap.video.timecover import motion_cover, thumbnail_step


def _still_jacks(n=90, burst=(0, 45), h=120, w=160, seed=4):
    """A figure that does jumping jacks in frames ``burst`` and stands still (arms down)
    the rest of the clip: its torso never leaves its pixels, the limbs sweep round it
    for half the clip. Frames (n, h, w, 3) uint8, true masks (n, h, w) bool."""
    rng = np.random.default_rng(seed)
    bg = background(h, w, rng).astype(np.float32)
    colour = np.array([40, 50, 160], np.float32)
    frames = np.empty((n, h, w, 3), np.uint8)
    masks = np.empty((n, h, w), bool)
    a, b = burst
    for i in range(n):
        phase = 2 * np.pi * (i - a) / (b - a) if a <= i < b else 0.0
        m = figure_mask(h, w, phase) > 0
        img = np.where(m[..., None], colour, bg) + rng.normal(0, 2, (h, w, 3))
        frames[i] = np.clip(img, 0, 255).astype(np.uint8)
        masks[i] = m
    return frames, masks


def test_motion_cover_is_the_share_of_time_a_pixel_moves():
    rng = np.random.default_rng(0)
    bg = background(48, 64, rng).astype(np.float32)
    frames = np.empty((100, 48, 64, 3), np.uint8)
    for i in range(100):
        img = bg.copy()
        if i < 20:  # a block over the left part for a fifth of the clip
            img[10:30, 5:25] = (20, 200, 40)
        if i % 2:  # a block that blinks every other frame
            img[10:30, 40:60] = (230, 30, 30)
        frames[i] = np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8)
    cover = motion_cover(frames)
    assert cover.shape == (48, 64) and cover.dtype == np.float32
    assert abs(np.median(cover[13:27, 8:22]) - 0.2) < 0.02
    # (differs from its median half the time, the median itself a toss-up between the two)
    assert np.median(cover[13:27, 43:57]) >= 0.45
    still = np.ones((48, 64), bool)
    still[7:33, 2:28] = still[7:33, 37:63] = False
    assert cover[still].max() <= 0.02


def test_thumbnail_step_caps_the_thumbnails():
    assert thumbnail_step(90) == 1
    assert thumbnail_step(timecover.MAX_THUMBS) == 1
    assert thumbnail_step(timecover.MAX_THUMBS + 1) == 2
    assert -(-5000 // thumbnail_step(5000)) <= timecover.MAX_THUMBS


def test_a_still_torso_is_a_hole_of_the_footprint_whatever_frames_are_drawn():
    """The limbs sweep round a torso that never moves for half the clip: over time its
    ring is covered often enough, whichever 24 frames are sampled; counted over the
    samples alone, the same test passes for some draws and fails for others."""
    frames, masks = _still_jacks()
    core = masks.all(axis=0)
    core_small = cv2.resize(core.view(np.uint8), (160, 120), interpolation=cv2.INTER_AREA) > 0
    cover = motion_cover(frames)
    with_time, with_samples = [], []
    for seed in range(6):
        smp, _ = sample_frames(frames, n_samples=24, rng=np.random.default_rng(seed))
        for cov, out in ((cover, with_time), (None, with_samples)):
            _, holes = region_vote(smp, _frame_gains(smp), work_size=160, segment_scale=60.0,
                                   min_region=12, progress=False, cover=cov)
            out.append(holes[core_small].mean())
    assert min(with_time) > 0.9
    assert min(with_samples) < 0.5 < max(with_samples)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_still_torso_is_flagged_never_seen_for_every_draw(seed):
    frames, masks = _still_jacks()
    core = masks.all(axis=0)
    bg = estimate_background(frames, n_samples=24, rng=np.random.default_rng(seed))
    assert bg.never_seen[core].mean() > 0.9
    # (and not the scene: the flag stays near the figure)
    assert bg.never_seen[~masks.any(axis=0)].mean() < 0.02


def test_a_walker_seen_in_every_frame_leaves_no_static_body_part():
    """A person crossing the frame covers each pixel of the path for a moment: over
    every frame the path is continuous, no hole, nothing flagged never seen."""
    rng = np.random.default_rng(31)
    h, w, n = 120, 160, 90
    bg = background(h, w, rng).astype(np.float32)
    frames = np.empty((n, h, w, 3), np.uint8)
    for i in range(n):
        m = figure_mask(h, w, 2 * np.pi * i / 15, cx=(0.1 + 0.8 * i / (n - 1)) * w) > 0
        img = np.where(m[..., None], np.array([40, 50, 160], np.float32), bg)
        frames[i] = np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8)
    for seed in range(3):
        got = estimate_background(frames, n_samples=24, rng=np.random.default_rng(seed))
        assert got.never_seen_fraction < 0.005


def test_a_video_file_gives_the_same_samples_and_thumbnails(tmp_path):
    """The file path decodes once for samples and thumbnails: the samples are the frames
    sample_frames picks, the thumbnails every frame at the working size."""
    from vidcap.io.video import probe, read_frames, write_video
    from vidcap.video.background import _sample_indices, _samples_and_thumbnails

    frames, _ = _still_jacks(n=40)
    video = tmp_path / "c.mp4"
    write_video(video, frames, 30.0)
    info = probe(video)
    got, idx, thumbs = _samples_and_thumbnails(video, 12, np.random.default_rng(2), info,
                                               (30, 40))
    assert (idx == _sample_indices(40, 12, np.random.default_rng(2))).all()
    decoded = read_frames(video)
    assert (got == decoded[idx]).all()
    assert thumbs.shape == (40, 30, 40, 3)
    small = np.stack([cv2.resize(f, (40, 30), interpolation=cv2.INTER_AREA) for f in decoded])
    assert np.median(np.abs(thumbs.astype(int) - small)) <= 2
