"""Background plate estimation (seed 004 section 3.1.2)."""

from __future__ import annotations

import numpy as np
import pytest

from tests._synthframes import background, clip
from vidcap.errors import InputFileError
from vidcap.video.background import (
    BackgroundError,
    BackgroundModel,
    estimate_background,
    load_plate,
    sample_frames,
)


def _plate_error(plate, truth):
    return np.abs(plate.astype(int) - truth.astype(int)).sum(-1)


@pytest.mark.parametrize("method", ["felzenszwalb", "median"])
def test_plate_of_a_walker_matches_the_true_background(method):
    frames, masks = clip(40, 120, 160, rng=np.random.default_rng(3), walk=True)
    truth = background(120, 160, np.random.default_rng(3))
    bg = estimate_background(frames, method=method, n_samples=20)
    err = _plate_error(bg.plate, truth)
    # camera noise sigma 2 per channel: L1 error of a clean mean stays well below 15
    assert np.median(err) < 6
    assert (err > 30).mean() < 0.01
    assert bg.plate.shape == (120, 160, 3) and bg.plate.dtype == np.uint8
    assert bg.confidence.shape == (120, 160)
    assert 0 <= bg.confidence.min() and bg.confidence.max() <= 1
    # the measured noise is near the true sigma (2 grey levels per channel)
    assert 1.0 < float(np.mean(bg.noise_sigma)) < 3.5
    assert 12 <= bg.threshold < 60


def test_pixel_covered_in_most_frames_gets_background_where_uncovered():
    """A block covering one spot in 70% of frames: the median takes the block's
    colour, the region method the background's (the jumping-jacks case)."""
    rng = np.random.default_rng(5)
    h, w, n = 96, 128, 30
    truth = background(h, w, rng)
    frames = np.repeat(truth[None], n, axis=0).astype(np.float32)
    for i in range(n):
        if i % 10 < 7:  # covered 70% of the time, by a block that wobbles
            x = 50 + (i % 3)
            frames[i, 30:70, x:x + 24] = (40, 40, 170)
        # a small walker elsewhere so the scene is not static
        frames[i, 75:90, 4 * i % 120:4 * i % 120 + 6] = (200, 200, 30)
    frames = np.clip(frames + rng.normal(0, 2, frames.shape), 0, 255).astype(np.uint8)
    spot = (slice(35, 65), slice(55, 72))
    med = estimate_background(frames, method="median", n_samples=n)
    fz = estimate_background(frames, method="felzenszwalb", n_samples=n)
    assert np.median(_plate_error(med.plate[spot], truth[spot])) > 100
    assert np.median(_plate_error(fz.plate[spot], truth[spot])) < 10
    assert fz.confidence[spot].mean() < 0.5 < fz.confidence[5:25, 5:25].mean()


def test_never_uncovered_pixels_are_flagged():
    rng = np.random.default_rng(6)
    h, w, n = 96, 128, 24
    truth = background(h, w, rng)
    frames = np.repeat(truth[None], n, axis=0).copy()
    for i in range(n):
        # something always covering the middle, never twice the same colour (a
        # person turning on the spot), and a walker so the scene is not static
        frames[i, 30:70, 50:74] = rng.integers(0, 256, 3)
        frames[i, 75:90, 4 * i % 120:4 * i % 120 + 6] = (200, 200, 30)
    bg = estimate_background(frames, n_samples=n)
    assert bg.never_seen[40:60, 55:70].mean() > 0.9
    assert 0 < bg.never_seen_fraction < 0.2
    assert not bg.never_seen[:20].any()


def test_lighting_drift_is_normalised():
    frames, _ = clip(30, 96, 128, rng=np.random.default_rng(7), walk=True, drift=0.25)
    bg = estimate_background(frames, n_samples=15)
    truth = background(96, 128, np.random.default_rng(7))
    # the plate is at the samples' median light (gain ~1), not smeared
    assert np.median(_plate_error(bg.plate, truth)) < 10


def test_static_scene_is_a_clear_error():
    rng = np.random.default_rng(8)
    truth = background(64, 80, rng)
    frames = np.clip(truth[None] + rng.normal(0, 2, (10, 64, 80, 3)), 0, 255).astype(np.uint8)
    for method in ("felzenszwalb", "median"):
        with pytest.raises(BackgroundError, match="nothing moves"):
            estimate_background(frames, method=method)


def test_one_frame_and_no_frame_are_clear_errors():
    one = np.zeros((1, 32, 32, 3), np.uint8)
    with pytest.raises(BackgroundError, match="one frame"):
        estimate_background(one)
    with pytest.raises(BackgroundError, match="no frames"):
        estimate_background(np.zeros((0, 32, 32, 3), np.uint8))


def test_sampling_is_spread_and_seeded():
    frames = np.arange(100, dtype=np.uint8)[:, None, None, None] * np.ones((1, 2, 2, 3), np.uint8)
    s, idx = sample_frames(frames, n_samples=10)
    assert len(idx) == 10 and idx.min() < 10 and idx.max() >= 90
    assert (s[:, 0, 0, 0] == idx).all()
    a = sample_frames(frames, n_samples=10, rng=np.random.default_rng(1))[1]
    b = sample_frames(frames, n_samples=10, rng=np.random.default_rng(1))[1]
    assert (a == b).all()


def test_given_plate(tmp_path):
    import cv2

    img = background(40, 50, np.random.default_rng(9))
    cv2.imwrite(str(tmp_path / "p.png"), img)
    bg = load_plate(tmp_path / "p.png")
    assert (bg.plate == img).all() and bg.method == "given"
    assert not np.isfinite(bg.threshold)
    (tmp_path / "bad.png").write_text("not an image")
    with pytest.raises(InputFileError, match="bad.png"):
        load_plate(tmp_path / "bad.png")
    with pytest.raises(InputFileError, match="missing.png"):
        load_plate(tmp_path / "missing.png")
    with pytest.raises(ValueError):
        BackgroundModel.from_plate(np.zeros((4, 4), np.uint8))


def test_sparse_walker_gaps_are_not_static_body_parts():
    """A walker sampled only 12 times leaves static background enclosed between
    its positions (holes of the motion footprint); their ring is covered once or
    twice, not often, so they are background, not a body part that never moved."""
    frames, _ = clip(12, 120, 160, rng=np.random.default_rng(31), walk=True)
    truth = background(120, 160, np.random.default_rng(31))
    bg = estimate_background(frames, n_samples=12)
    assert bg.never_seen_fraction < 0.01
    assert np.median(_plate_error(bg.plate, truth)) < 8


def test_static_torso_is_flagged_never_seen_and_inpainted():
    """Jumping jacks in place: the torso never moves; the median keeps it in the
    plate, the footprint-hole step flags it and inpaints background there."""
    frames, masks = clip(30, 120, 160, rng=np.random.default_rng(4))
    truth = background(120, 160, np.random.default_rng(4))
    always = masks.all(axis=0)
    fz = estimate_background(frames, n_samples=15)
    med = estimate_background(frames, method="median", n_samples=15)
    assert fz.never_seen[always].mean() > 0.5
    assert fz.confidence[always].mean() < 0.3
    # the inpainted plate is nearer the true background than the body's colours
    err_fz = np.median(_plate_error(fz.plate[always], truth[always]))
    err_med = np.median(_plate_error(med.plate[always], truth[always]))
    assert err_fz < 0.5 * err_med


def test_masked_median_equals_a_partition_for_every_sample_count():
    """The few-sample path (a sorting network of min / max) and the partition give
    the same per-pixel median of the included samples, for 1-12 samples."""
    from vidcap.video.background import _masked_median

    rng = np.random.default_rng(3)
    for k in range(1, 13):
        x = rng.integers(0, 256, (k, 9, 11, 3), dtype=np.uint8)
        excl = rng.random((k, 9, 11)) < 0.3
        excl[:, 0, 0] = True  # a pixel with no sample included
        for e in (None, excl):
            got = _masked_median(x, e)
            for yy in range(9):
                for xx in range(11):
                    keep = np.ones(k, bool) if e is None else ~e[:, yy, xx]
                    if not keep.any():
                        continue
                    s = np.sort(x[keep, yy, xx], axis=0)
                    # the included samples' middle rank (the lower one for an even count)
                    assert (got[yy, xx] == s[(keep.sum() - 1) // 2]).all(), (k, yy, xx)


def test_a_video_file_is_probed_once_and_its_rate_times_the_empty_scene(tmp_path, monkeypatch):
    """The samples' positions and the empty-scene pass's times come from one probe of the
    file; the times are the sample indices at the file's own frame rate."""
    import vidcap.io.video as video
    import vidcap.video.emptyscene as emptyscene

    frames, _ = clip(30, 96, 128, rng=np.random.default_rng(4), walk=True)
    path = tmp_path / "walk.mp4"
    video.write_video(path, list(frames), 12.0)
    probes, seen = [], {}
    probe, plate_from_empty = video.probe, emptyscene.plate_from_empty
    monkeypatch.setattr(video, "probe", lambda *a, **k: probes.append(1) or probe(*a, **k))

    def spy(model, smp, gains, *, times, **kw):
        seen["times"] = times
        return plate_from_empty(model, smp, gains, times=times, **kw)

    monkeypatch.setattr(emptyscene, "plate_from_empty", spy)
    bg = estimate_background(path, n_samples=10, empty_scene=True)
    assert len(probes) == 1
    np.testing.assert_allclose(seen["times"], bg.sample_indices / 12.0)


def test_the_colours_are_learned_again_once_an_absorbed_person_is_found(monkeypatch):
    from dataclasses import replace

    import vidcap.video.graphcut as graphcut
    import vidcap.video.heldpose as heldpose

    frames, _ = clip(12, 60, 80, rng=np.random.default_rng(5), walk=True)
    learned = []

    def colours(model, *_):
        learned.append(model.still_person is not None)
        return np.full((2, 4), len(learned), np.float32)

    def found(model, *_, **__):
        return replace(model, still_person=np.ones(model.plate.shape[:2], bool))

    monkeypatch.setattr(graphcut, "clip_colours", colours)
    monkeypatch.setattr(heldpose, "absorbed_or_held", found)
    bg = estimate_background(frames, n_samples=8, colour_models=True, person_box=True)
    # learned on the plate stage's model, then again on the model with the person
    assert learned == [False, True] and bg.colours[0, 0] == 2
    monkeypatch.setattr(heldpose, "absorbed_or_held", lambda model, *_, **__: model)
    learned.clear()
    estimate_background(frames, n_samples=8, colour_models=True, person_box=True)
    assert learned == [False]  # nobody absorbed: no second look


def _performer_before_a_textured_wall(rng, n=40, h=120, w=160):
    """A dark-clad performer swaying over the middle of a mottled wall (regions whose
    means change with the segmentation), a floor band and black letterbox bars: frames
    (F, H, W, 3) uint8, masks (F, H, W) bool and the empty scene (H, W, 3) uint8."""
    import cv2

    from tests._synthframes import figure_mask

    wall = np.zeros((h, w, 3), np.float32)
    wall[:] = (150, 140, 40)
    blot = cv2.resize(rng.uniform(0, 1, (h // 2, w // 2)).astype(np.float32), (w, h),
                      interpolation=cv2.INTER_CUBIC)
    wall *= (0.55 + 0.45 * blot)[..., None]
    wall += rng.normal(0, 5, wall.shape)
    wall[90:108] = (190, 190, 195)
    wall[:10] = 0
    wall[108:] = 0
    frames = np.empty((n, h, w, 3), np.float32)
    masks = np.empty((n, h, w), bool)
    for i in range(n):
        ph = 2 * np.pi * i / n
        m = cv2.dilate(figure_mask(h, w, 0.6 + 0.6 * np.sin(3 * ph), cx=w / 2 + 20 * np.sin(ph)),
                       np.ones((9, 9), np.uint8)).astype(bool)
        frames[i] = wall
        frames[i][m] = (10, 4, 3)
        masks[i] = m
    frames = np.clip(frames + rng.normal(0, 2, frames.shape), 0, 255).astype(np.uint8)
    return frames, masks, np.clip(wall, 0, 255).astype(np.uint8)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_performer_before_a_textured_wall_leaves_the_plate(seed, monkeypatch):
    """Pixels the performer covers in 50-85 % of the samples: the scene round the
    footprint, as a set of colours, tells the costume from the wall seen between the
    steps (without it the costume stays in the plate over a sixth of them)."""
    import vidcap.video.regionvote as rv

    frames, masks, truth = _performer_before_a_textured_wall(np.random.default_rng(seed))
    cover = masks.mean(axis=0)
    spot = (cover > 0.5) & (cover < 0.85)
    assert spot.sum() > 1000

    def wrong(on):
        monkeypatch.setattr(rv, "SCENE_RING", on)
        plate = estimate_background(frames, n_samples=24).plate
        return (_plate_error(plate, truth)[spot] > 100).mean()

    assert wrong(True) < 0.05
    assert wrong(False) > 0.1


def test_letterbox_bars_are_found_only_at_the_edges():
    from vidcap.video.regionvote import _letterbox

    means = np.full((3, 20, 30, 3), 120.0, np.float32)
    means[:, :3] = 2.0  # a bar on top
    means[:, -2:] = 5.0  # and at the bottom
    means[:, 10] = 1.0  # a dark row inside the picture is scene
    box = _letterbox(means)
    assert box[:3].all() and box[-2:].all() and not box[3:-2].any()
    means[1, 0, 7] = 90.0  # a bar is dark in every sample, and runs from the edge
    box = _letterbox(means)
    assert box[-2:].all() and not box[:-2].any()


def test_l1_adds_the_channels_as_numpys_reduction_does():
    """The finish's L1 residual (three additions) equals ``np.abs(r).sum(axis=-1)`` to
    the bit, whatever the layout."""
    from vidcap.video.background import _l1

    rng = np.random.default_rng(5)
    for shape in [(24, 50, 40, 3), (3, 7, 5, 3), (100, 3)]:
        r = (rng.integers(0, 256, shape).astype(np.float32)
             - rng.uniform(0, 255, shape).astype(np.float32) * np.float32(1.0371))
        assert np.array_equal(_l1(r), np.abs(r).sum(axis=-1))
        strided = r[::2, ..., :] if r.ndim == 4 else r
        assert np.array_equal(_l1(strided), np.abs(strided).sum(axis=-1))


def _around_a_block(block_colour, near_share, n=60, h=120, w=160, seed=7):
    """A static block (rows 50-70, columns 70-90) and a red ring of varying width round
    it (a body's moving parts) in ``near_share`` of the frames; in the others the red
    mass stands at the frame's left edge, away from the block. Frames (n, h, w, 3) uint8
    and the block's pixels (h, w) bool."""
    rng = np.random.default_rng(seed)
    bg = background(h, w, rng).astype(np.float32)
    block = np.zeros((h, w), bool)
    block[50:70, 70:90] = True
    bg[block] = block_colour
    yy, xx = np.mgrid[:h, :w]
    r = np.hypot(yy - 59.5, xx - 79.5)
    red = np.array([40, 40, 200], np.float32)
    frames = np.empty((n, h, w, 3), np.uint8)
    for i in range(n):
        if i % 10 < 10 * near_share:
            person = (r >= 14) & (r < 18 + 8 * rng.random())
        else:
            person = (np.abs(yy - 60) < 25) & (np.abs(xx - 12 - 3 * rng.random()) < 8)
        img = np.where(person[..., None], red, bg) + rng.normal(0, 2, (h, w, 3))
        frames[i] = np.clip(img, 0, 255).astype(np.uint8)
    return frames, block


def test_a_static_object_the_person_leaves_is_not_a_body_part():
    """A block of scene the person moves round in 40 % of the frames and leaves for the
    frame's edge in the rest is a hole of the motion footprint, its ring covered often
    and its colour unlike the scene inpainted round it: what marks a body part that never
    moved, but for one thing: the moving body does not touch it in every sample
    (``regionvote.MIN_ATTACHED``). It stays in the plate as the scene it is; a block of
    the person's colour touched by the moving ring in every frame is flagged."""
    frames, block = _around_a_block((200, 120, 40), near_share=0.4)
    bg = estimate_background(frames, n_samples=24, rng=np.random.default_rng(0))
    assert bg.never_seen[block].mean() < 0.1
    assert np.median(_plate_error(bg.plate[block], np.array([200, 120, 40]))) < 15
    frames, block = _around_a_block((40, 40, 200), near_share=1.0)
    bg = estimate_background(frames, n_samples=24, rng=np.random.default_rng(0))
    assert bg.never_seen[block].mean() > 0.9
