"""The plate from samples that show the empty scene (vidcap.video.emptyscene)."""

import numpy as np

from vidcap.video import emptyscene
from vidcap.video.background import BackgroundModel
from vidcap.video.emptyscene import empty_stretch, ghost_blobs, plate_from_empty


def _wall(rng, h=96, w=128):
    """A smooth wall (a gentle gradient) with sensor noise, uint8 BGR."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    base = np.stack([90 + 0.3 * x, 110 + 0.2 * y, 130 + 0.1 * (x + y)], axis=-1)
    return lambda: np.clip(base + rng.normal(0, 2, base.shape), 0, 255).astype(np.uint8)


def _block(img, colour=(30, 40, 200)):
    out = img.copy()
    out[30:80, 50:70] = colour
    return out


def test_ghost_blobs_tell_the_plate_edge_from_the_frame_edge():
    rng = np.random.default_rng(0)
    wall = _wall(rng)
    mask = np.zeros((96, 128), bool)
    mask[30:80, 50:70] = True
    # The plate holds the block, the frame shows the wall: a ghost.
    assert ghost_blobs(wall(), _block(wall()), mask).sum() == mask.sum()
    # The frame holds the block, the plate is the wall: a person, not a ghost.
    assert not ghost_blobs(_block(wall()), wall(), mask).any()


def test_an_empty_stretch_gives_the_plate_the_still_block_took():
    # A plate that kept a block standing still; 6 empty samples (2.5 s), then 18 with
    # the block: the empty ones give the wall back.
    rng = np.random.default_rng(1)
    wall = _wall(rng)
    model = BackgroundModel.from_plate(_block(wall()), noise_sigma=2.0)
    frames = np.stack([wall() for _ in range(6)] + [_block(wall()) for _ in range(18)])
    times = 0.5 * np.arange(24)
    clean = wall().astype(np.int16)[35:75, 53:67]
    got = plate_from_empty(model, frames, np.ones((24, 3)), times=times)
    assert np.abs(got.plate[35:75, 53:67].astype(np.int16) - clean).sum(axis=-1).mean() < 15
    # Without the empty stretch nothing changes.
    same = plate_from_empty(model, frames[6:], np.ones((18, 3)), times=times[6:])
    assert same is model
    # Nor when the same 6 samples span less than a second (0.1 s apart; a person in
    # view all along can look like a ghost for a moment) ...
    assert plate_from_empty(model, frames, np.ones((24, 3)), times=0.1 * np.arange(24)) is model
    # ... or lie in the middle of the clip (not where the person came in or left).
    mid = np.concatenate([frames[6:15], frames[:6], frames[15:]])
    assert plate_from_empty(model, mid, np.ones((24, 3)), times=times) is model


def test_empty_stretch_runs_from_an_end_of_the_clip():
    shown = np.array([[1, 1, 0, 0, 0],
                      [0, 1, 0, 1, 0],
                      [1, 1, 0, 1, 1],
                      [0, 0, 1, 0, 1],
                      [0, 0, 1, 0, 1]], bool)
    t = np.arange(5.0)
    # Column 0: samples 0 and 2 (one missed between, bridged): 2 s from the start.
    # 1: 0-2. 2: 3-4 at the end, 1 s. 3: samples 1-2, at neither end. 4: 2-4 at the
    # end, 2 s.
    assert empty_stretch(shown, t, 2.0).tolist() == [True, True, False, False, True]
    assert empty_stretch(shown, t, 1.0).tolist() == [True, True, True, False, True]
    assert not empty_stretch(shown[:1], t[:1], 0.0).any()


def test_empty_stretch_counts_from_the_clip_start_not_the_first_sample():
    # Three samples 0.45 s apart show the scene, the first 0.5 s into the clip: 0.9 s
    # between samples (under a second), 1.4 s from the clip's first frame. The same
    # at the end: the last sample 0.5 s before the clip's last frame.
    t = np.array([0.5, 0.95, 1.4, 1.85, 2.3, 2.75, 3.2])
    start = np.array([1, 1, 1, 0, 0, 0, 0], bool)[:, None]
    end = start[::-1]
    for shown in (start, end):
        assert not empty_stretch(shown, t, 1.0).any()
        assert empty_stretch(shown, t, 1.0, ends=(0.0, 3.7)).all()
        assert not empty_stretch(shown, t, 1.5, ends=(0.0, 3.7)).any()
    # Nothing shown at an end: no stretch, whatever the clip's length.
    mid = np.array([0, 1, 1, 1, 1, 0, 0], bool)[:, None]
    assert not empty_stretch(mid, t, 0.5, ends=(0.0, 3.7)).any()


def test_the_plate_is_retaken_when_the_clip_starts_empty_before_the_first_sample(
        monkeypatch):
    # Three empty samples 0.45 s apart, the first 0.5 s into the clip, then the block
    # stands still: 0.9 s between the empty samples, 1.4 s from the clip's first frame.
    monkeypatch.setattr(emptyscene, "FROM_CLIP_ENDS", True)
    rng = np.random.default_rng(2)
    wall = _wall(rng)
    model = BackgroundModel.from_plate(_block(wall()), noise_sigma=2.0)
    frames = np.stack([wall() for _ in range(3)] + [_block(wall()) for _ in range(9)])
    times = 0.5 + 0.45 * np.arange(12)
    assert plate_from_empty(model, frames, np.ones((12, 3)), times=times) is model
    got = plate_from_empty(model, frames, np.ones((12, 3)), times=times,
                           ends=(0.0, times[-1] + 0.5))
    clean = wall().astype(np.int16)[35:75, 53:67]
    assert np.abs(got.plate[35:75, 53:67].astype(np.int16) - clean).sum(axis=-1).mean() < 15
    assert not got.never_seen.any()

    # Off (the default), the stretch counts from the first sample: 0.9 s, too short.
    monkeypatch.setattr(emptyscene, "FROM_CLIP_ENDS", False)
    assert plate_from_empty(model, frames, np.ones((12, 3)), times=times,
                            ends=(0.0, times[-1] + 0.5)) is model


def test_a_ghost_stretches_to_the_clip_ends_only_with_the_person_away_or_coming_in():
    h, w = 100, 200
    ghost = np.zeros((h, w), bool)
    ghost[40:60, 20:40] = True
    mask = ghost.astype(np.uint8)
    # Nobody else in the sample: the ghost stands.
    assert (emptyscene._apart(ghost, mask, 0.05) == ghost).all()
    # The person coming in across the right border, far off: it stands.
    entering = mask.copy()
    entering[30:90, 170:200] = 1
    assert (emptyscene._apart(ghost, entering, 0.05) == ghost).all()
    # ... but not within 5 % of the long side (10 px) of it.
    close = mask.copy()
    close[30:90, 45:200] = 1
    assert not emptyscene._apart(ghost, close, 0.05).any()
    # A person wholly in view, however far: no ghost may stretch to the ends.
    inside = mask.copy()
    inside[30:90, 150:180] = 1
    assert not emptyscene._apart(ghost, inside, 0.05).any()


def test_a_low_contrast_ghost_under_an_inflated_noise_map_is_found_where_the_ends_agree(
        monkeypatch):
    """A person who sat still in most samples (a block 12 grey levels a channel off the
    wall, L1 36) inflated the noise map there (3 x 20 = 60 hides the block); the clip's
    first and last samples both show the wall. Where the ends agree the ghost is found
    at the global threshold and the plate re-taken; without it nothing changes."""
    from dataclasses import replace

    monkeypatch.setattr(emptyscene, "ENDS_AGREE", True)
    rng = np.random.default_rng(5)
    wall = _wall(rng)
    near = lambda: np.clip(wall().astype(np.int16) + 12, 0, 255).astype(np.uint8)  # noqa: E731
    block = np.zeros((96, 128), bool)
    block[30:80, 50:70] = True

    def sat(img):
        out = img.copy()
        out[block] = near()[block]
        return out

    model = BackgroundModel.from_plate(sat(wall()), noise_sigma=2.0)
    assert 12 < model.threshold < 36
    noise = model.noise_map.copy()
    noise[block] = 20.0
    model = replace(model, noise_map=noise)
    frames = np.stack([wall() for _ in range(4)] + [sat(wall()) for _ in range(16)]
                      + [wall() for _ in range(4)])
    times = 0.5 * np.arange(24)
    gains = np.ones((24, 3))
    got = plate_from_empty(model, frames, gains, times=times)
    clean = wall().astype(np.int16)
    err = np.abs(got.plate.astype(np.int16) - clean).sum(axis=-1)[35:75, 53:67]
    assert err.mean() < 12
    monkeypatch.setattr(emptyscene, "ENDS_AGREE", False)
    assert plate_from_empty(model, frames, gains, times=times) is model


def test_the_noise_map_is_lowered_only_where_the_ends_agree(monkeypatch):
    monkeypatch.setattr(emptyscene, "ENDS_OFF_PLATE", False)
    rng = np.random.default_rng(6)
    wall = _wall(rng)
    model = BackgroundModel.from_plate(wall(), noise_sigma=2.0)
    from dataclasses import replace

    model = replace(model, noise_map=np.full((96, 128), 30.0, np.float32))
    frames = np.stack([wall(), wall(), _block(wall())])  # the last ends with the block
    got = emptyscene._ends_agree_model(model, frames, np.ones((3, 3)))
    cap = np.float32(model.threshold / 3.0)
    assert (got.noise_map[30:80, 50:70] == 30.0).all()
    outside = np.ones((96, 128), bool)
    outside[30:80, 50:70] = False
    # (two noisy looks at the wall agree within the threshold nearly everywhere)
    assert np.isclose(got.noise_map[outside], cap).mean() > 0.95
    assert np.isin(got.noise_map, [cap, 30.0]).all()


def test_the_noise_map_is_lowered_only_where_the_ends_agree_on_another_colour_than_the_plate(
        monkeypatch):
    """With :data:`emptyscene.ENDS_OFF_PLATE`: where both ends show the wall and the plate
    holds the block (someone came and went) the map is lowered; where the ends show what
    the plate holds, nothing is to be found and it stays."""
    from dataclasses import replace

    monkeypatch.setattr(emptyscene, "ENDS_OFF_PLATE", True)
    rng = np.random.default_rng(7)
    wall = _wall(rng)
    model = BackgroundModel.from_plate(_block(wall()), noise_sigma=2.0)
    model = replace(model, noise_map=np.full((96, 128), 30.0, np.float32))
    frames = np.stack([wall(), _block(wall()), wall()])
    got = emptyscene._ends_agree_model(model, frames, np.ones((3, 3)))
    cap = np.float32(model.threshold / 3.0)
    # (two noisy looks at the wall agree within the threshold nearly everywhere)
    assert np.isclose(got.noise_map[30:80, 50:70], cap).mean() > 0.95
    outside = np.ones((96, 128), bool)
    outside[30:80, 50:70] = False
    assert (got.noise_map[outside] == 30.0).mean() > 0.99


def test_empty_stretches_at_both_ends_add_up():
    # Scene shown in samples 0-1 (0.6 s from the first sample) and 9-10 (0.5 s to the
    # last): neither alone spans 1 s, together they do (someone came and went).
    t = np.array([0.0, 0.6, 1.2, 1.8, 2.4, 3.0, 3.6, 4.2, 4.8, 5.5, 6.0])
    both = np.zeros(11, bool)
    both[[0, 1, 9, 10]] = True
    start = np.zeros(11, bool)
    start[[0, 1]] = True
    shown = np.stack([both, start, both], axis=1)
    assert not empty_stretch(shown, t, 1.0).any()
    assert empty_stretch(shown, t, 1.0, both=True).tolist() == [True, False, True]
    assert not empty_stretch(shown, t, 1.2, both=True).any()


def test_a_block_that_came_and_went_is_retaken_from_both_ends(monkeypatch):
    """Two empty samples at each end, 0.6 s apart (0.6 s a stretch, under the second
    :data:`emptyscene.MIN_EMPTY_S` asks for), the block standing still between: with
    :data:`emptyscene.BOTH_ENDS` the plate gets the wall back, without it not."""
    monkeypatch.setattr(emptyscene, "FROM_CLIP_ENDS", False)
    rng = np.random.default_rng(8)
    wall = _wall(rng)
    model = BackgroundModel.from_plate(_block(wall()), noise_sigma=2.0)
    frames = np.stack([wall() for _ in range(2)] + [_block(wall()) for _ in range(8)]
                      + [wall() for _ in range(2)])
    times = 0.6 * np.arange(12)
    gains = np.ones((12, 3))
    monkeypatch.setattr(emptyscene, "BOTH_ENDS", False)
    assert plate_from_empty(model, frames, gains, times=times) is model
    monkeypatch.setattr(emptyscene, "BOTH_ENDS", True)
    got = plate_from_empty(model, frames, gains, times=times)
    clean = wall().astype(np.int16)[35:75, 53:67]
    assert np.abs(got.plate[35:75, 53:67].astype(np.int16) - clean).sum(axis=-1).mean() < 15
