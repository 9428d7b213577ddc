"""The plate re-taken where it holds a colour that only passed by (vidcap.video.passedby)."""

from dataclasses import replace

import numpy as np

from vidcap.video import passedby
from vidcap.video.background import BackgroundModel
from vidcap.video.passedby import (
    moving_blobs,
    passed_by,
    plate_levels,
    retake_passed_by,
    whole_blob_frames,
)

H, W, N, FPS = 120, 160, 60, 30.0
BLOCK = (slice(40, 70), slice(90, 110))  # a brown chair
BROWN = (40, 70, 120)


def _scene(rng):
    """A grey floor with a brown block, and sensor noise: a function giving a frame."""
    base = np.full((H, W, 3), 100.0, np.float32)
    base[BLOCK] = BROWN
    return base, lambda: np.clip(base + rng.normal(0, 2, base.shape), 0, 255).astype(np.uint8)


def _walker(frame, x, top=30, height=70, width=30):
    """A person at column ``x``: a shirt of vertical folds (230 / 200, 4 px) that move
    with them, so that their inside changes from frame to frame as a real shirt's does."""
    out = frame.copy()
    x0 = int(round(x))
    cols = np.arange(x0, min(W, x0 + width))
    folds = np.where(((cols - x0) // 4) % 2 == 0, 230, 200).astype(np.uint8)
    out[top:top + height, cols] = folds[None, :, None]
    return out


def _model(plate):
    m = BackgroundModel.from_plate(plate.astype(np.uint8), noise_sigma=2.0)
    return replace(m, sample_indices=np.arange(N), n_samples=N,
                   noise_map=np.full((H, W), 4.0, np.float32))


def test_a_block_the_plate_gave_to_a_passer_by_is_taken_back():
    # A person walks slowly from x 30 to 95 in front of the brown block (covering it
    # from ~frame 27 on); the plate holds their shirt over the block, as the vote did on
    # sbi_hallmonitor. The frames before they came show the block still: it comes back.
    rng = np.random.default_rng(0)
    base, noisy = _scene(rng)
    frames = np.stack([_walker(noisy(), 30 + 65 * t / (N - 1)) for t in range(N)])
    wrong = base.copy()
    wrong[BLOCK] = 230
    model = _model(wrong)
    out = retake_passed_by(model, frames, np.ones((N, 3), np.float32), frames,
                           step=1, fps=FPS)
    err = np.abs(out.plate[BLOCK].astype(int) - np.array(BROWN)).max(axis=-1)
    assert (err <= 10).mean() > 0.9
    # Elsewhere the plate is left as it was.
    outside = np.ones((H, W), bool)
    outside[BLOCK] = False
    assert (out.plate[outside] == model.plate[outside]).mean() > 0.99


def test_a_person_who_came_and_stood_still_stays_out_of_the_plate():
    # A person walks in (frames 0-14), stands perfectly still over the block (15-49) and
    # walks on: the plate holds the block (seen before they came and after they left,
    # while nobody moved there) and keeps it, though the still person is what the
    # frames outside the moving blob show most.
    rng = np.random.default_rng(1)
    base, noisy = _scene(rng)
    xs = np.concatenate([np.linspace(20, 85, 15), np.full(35, 85.0), np.linspace(85, 130, 10)])
    frames = np.stack([_walker(noisy(), x) for x in xs])
    model = _model(base)
    out = retake_passed_by(model, frames, np.ones((N, 3), np.float32), frames,
                           step=1, fps=FPS)
    assert (out.plate[BLOCK] == model.plate[BLOCK]).all()


def test_the_moving_blob_is_the_walker_filled_not_where_they_were():
    rng = np.random.default_rng(2)
    _, noisy = _scene(rng)
    frames = np.stack([_walker(noisy(), 30 + 65 * t / (N - 1)) for t in range(N)])
    levels = plate_levels(frames, np.median(frames, axis=0).astype(np.uint8))
    blobs = moving_blobs(levels, 12.0, [3, 6, 12], 13)
    t = 30
    x0 = int(round(30 + 65 * t / (N - 1)))
    person = np.zeros((H, W), bool)
    person[30:100, x0:x0 + 30] = True
    assert (blobs[t] & person).sum() > 0.9 * person.sum()
    # not the trail: well left of where the walker is now (where they were 12 frames ago)
    assert not blobs[t][:, : x0 - 6].any()


def test_a_clip_shorter_than_twice_a_lag_still_finds_its_walker():
    # 7 frames, lags up to 6: the two-sided test has no frame for the lags of 4 and 6, the
    # one-sided ends still mark the walker (this raised a broadcast error before)
    rng = np.random.default_rng(3)
    _, noisy = _scene(rng)
    frames = np.stack([_walker(noisy(), 30 + 10 * t) for t in range(7)])
    levels = plate_levels(frames, np.median(frames, axis=0).astype(np.uint8))
    blobs = moving_blobs(levels, 12.0, [2, 4, 6], 13)
    assert blobs.shape == (7, H, W)
    person = np.zeros((H, W), bool)
    person[30:100, 60:90] = True  # frame 3
    assert (blobs[3] & person).sum() > 0.5 * person.sum()


def test_the_scene_is_what_the_quiet_ends_show_not_a_still_person():
    # Two pixels, 60 frames, the plate holds colour P at both.
    # A: the scene S for 10 frames, then a passer-by in P inside the moving blob for
    #    40, then S again: P only passed by, S comes back.
    # B: P while a person walks in front (inside the blob), then that person stands
    #    still in Q for 50 frames (outside the blob), then P while they leave: Q is what
    #    the frames outside the blob show most, but it is bracketed by the person's own
    #    coming and going; the plate stays.
    rng = np.random.default_rng(3)
    n = 60
    S, P, Q = (np.array(c, np.float32) for c in ((40, 70, 120), (230, 230, 230), (60, 60, 60)))
    vals = np.zeros((n, 1, 2, 3), np.float32)  # (uint8 below, as plate_levels gives)
    blobs = np.zeros((n, 1, 2), bool)
    vals[:, 0, 0] = S
    vals[10:50, 0, 0] = P
    blobs[10:50, 0, 0] = True
    vals[:, 0, 1] = Q
    vals[:5, 0, 1] = P
    vals[55:, 0, 1] = P
    blobs[:5, 0, 1] = blobs[55:, 0, 1] = True
    vals = np.clip(vals + rng.normal(0, 1, vals.shape), 0, 255).round().astype(np.uint8)
    plate = np.broadcast_to(P, (1, 2, 3)).astype(np.uint8)
    flag, scene = passed_by(vals, blobs, plate, 12.0, 3,
                            np.zeros((1, 2), bool))
    assert flag.tolist() == [[True, False]]
    assert np.abs(scene[0, 0] - S).max() < 3


def _dancer(frame, t):
    """A dancer who stands still for frames 0-24 (torso at x 60-90, the right arm
    waving) and then steps 12 px right and dances there (the shirt's folds scroll, both
    arms wave): the frames before the blob first covers her old torso show the torso."""
    out = frame.copy()
    x0 = 60 if t < 25 else 72
    cols = np.arange(x0, x0 + 30)
    folds = np.where(((cols - x0 + (0 if t < 25 else t)) // 4) % 2 == 0, 60, 30).astype(np.uint8)
    out[30:100, cols] = np.stack([folds, folds, folds + 140], -1)[None]
    y = 35 + int(12 * np.sin(t * 0.9))
    out[y:y + 6, x0 + 30:x0 + 50] = (60, 60, 200)
    if t >= 25:
        y = 35 + int(12 * np.cos(t * 0.9))
        out[y:y + 6, x0 - 22:x0] = (60, 60, 200)
    return out


def test_a_dancer_still_at_the_start_stays_out_of_the_plate(monkeypatch):
    # The plate holds the scene. Her old torso pixels show the torso outside the blob
    # (round the waving arm only) at the start and the scene inside the blob once she
    # dances beside it: without the whole-blob gate the pass takes the torso for the
    # scene (05_19 3/4 back); with it, the plate stays.
    rng = np.random.default_rng(4)
    base, noisy = _scene(rng)
    frames = np.stack([_dancer(noisy(), t) for t in range(N)])
    model = _model(base)
    ones = np.ones((N, 3), np.float32)
    monkeypatch.setattr(passedby, "MIN_HELD", 0.0)
    ungated = retake_passed_by(model, frames, ones, frames, step=1, fps=FPS)
    assert (ungated.plate[30:100, 60:72] != model.plate[30:100, 60:72]).any(-1).mean() > 0.1
    monkeypatch.undo()
    out = retake_passed_by(model, frames, ones, frames, step=1, fps=FPS)
    assert (out.plate == model.plate).all()


def test_whole_blob_frames_trust_a_blob_that_holds_what_differs():
    # Frame 0: the blob is the whole person; 1: the blob is an arm beside a still torso
    # that differs from the plate; 2: no blob, nothing differs; 3: no blob, a person-sized
    # block differs (someone standing perfectly still).
    plate = np.full((60, 80, 3), 100, np.uint8)
    levels = np.repeat(plate[None], 4, axis=0)
    blobs = np.zeros((4, 60, 80), bool)
    levels[0, 10:50, 20:40] = 200
    blobs[0, 9:51, 19:41] = True
    levels[1, 10:50, 20:40] = 200
    levels[1, 15:20, 40:55] = 200
    blobs[1, 14:21, 40:56] = True
    levels[3, 10:50, 20:40] = 200
    blobs[2:] = False
    assert whole_blob_frames(levels, blobs, plate, 12.0, 6).tolist() == [True, False, True, False]


def test_only_trusted_frames_give_the_scene():
    # One pixel: a still torso's colour Q outside the blob for 20 frames, then the plate's
    # colour P inside the blob: taken for a passer-by over the scene Q, unless those 20
    # frames are not trusted (the blob did not hold the person whole).
    rng = np.random.default_rng(5)
    n = 60
    vals = np.zeros((n, 1, 1, 3), np.float32)
    vals[:20] = (60, 60, 200)
    vals[20:] = (100, 100, 100)
    blobs = np.zeros((n, 1, 1), bool)
    blobs[20:] = True
    vals = np.clip(vals + rng.normal(0, 1, vals.shape), 0, 255).round().astype(np.uint8)
    plate = np.full((1, 1, 3), 100, np.uint8)
    left = np.zeros((1, 1), bool)
    assert passed_by(vals, blobs, plate, 12.0, 3, left)[0].all()
    trusted = np.arange(n) >= 20
    assert not passed_by(vals, blobs, plate, 12.0, 3, left, trusted)[0].any()
