"""vidcap.video.steadyscene: never-seen pixels re-taken from a second steady state."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from vidcap.video import steadyscene
from vidcap.video.background import BackgroundModel
from vidcap.video.steadyscene import retake_steady, steady_runs

GREY, RED, BLUE = (120, 120, 120), (40, 40, 200), (200, 60, 40)


def test_steady_runs_are_the_unbroken_agreeing_stretch_round_each_sample():
    c = np.array([[0], [1], [2], [90], [91], [90], [0]], np.float32)[:, :, None] * [1, 1, 1]
    start, stop = steady_runs(c.astype(np.float32), tau=10.0)
    assert start[:, 0].tolist() == [0, 0, 0, 3, 3, 3, 6]
    assert stop[:, 0].tolist() == [2, 2, 2, 5, 5, 5, 6]  # the last 0 is cut off by the 90s


def _clip(rng, k=12):
    """K samples 12x12: columns 0-3 a person who stands, then steps aside (the wall
    shows from sample 6 on); 4-7 a person there throughout; 8-11 two poses of the
    person (red, then blue). All never seen, the plate a grey guess."""
    frames = np.empty((k, 12, 12, 3), np.float32)
    frames[:] = GREY
    frames[:6, :, 0:4] = RED
    frames[:, :, 4:8] = RED
    frames[:6, :, 8:12] = RED
    frames[6:, :, 8:12] = BLUE
    frames += rng.normal(0, 1.5, frames.shape)
    frames = np.clip(frames, 0, 255).astype(np.uint8)
    guess = np.full((12, 12, 3), (112, 126, 118), np.uint8)  # inpainted: near the wall
    model = BackgroundModel.from_plate(guess, noise_sigma=1.5)
    return frames, replace(model, never_seen=np.ones((12, 12), bool))


def test_the_scene_seen_after_a_still_person_steps_aside_is_taken_back(monkeypatch):
    monkeypatch.setattr(steadyscene, "STEADY_SCENE", True)
    rng = np.random.default_rng(0)
    frames, model = _clip(rng)
    times = np.arange(len(frames)) * 0.5
    out = retake_steady(model, frames, np.ones((len(frames), 3), np.float32), times)
    # stood, then left: the wall, no longer never seen, confidence its share of samples
    assert not out.never_seen[:, 0:4].any()
    assert np.abs(out.plate[:, 0:4].astype(int) - GREY).max() <= 3
    assert np.allclose(out.confidence[:, 0:4], 0.5)
    # never left, or two poses of the person, neither near the guess: still never seen
    assert out.never_seen[:, 4:12].all()
    assert (out.plate[:, 4:12] == model.plate[:, 4:12]).all()


def test_short_stretches_and_the_switch_leave_the_plate(monkeypatch):
    rng = np.random.default_rng(1)
    frames, model = _clip(rng)
    ones = np.ones((len(frames), 3), np.float32)
    # off (the default): the same object back
    monkeypatch.setattr(steadyscene, "STEADY_SCENE", False)
    assert retake_steady(model, frames, ones, np.arange(12) * 0.5) is model
    monkeypatch.setattr(steadyscene, "STEADY_SCENE", True)
    # the wall's six samples within 0.5 s: not a steady state (MIN_SECONDS)
    assert retake_steady(model, frames, ones, np.arange(12) * 0.05) is model


def _passer_by(rng, k=12):
    """K samples 12x12 with a seen plate. Columns 0-3: the scene (grey) steady for the
    first eight samples, then someone passing (another colour each sample); the plate a
    blend of them that no two consecutive samples show. Columns 4-7: someone came and
    stood (red, steady in samples 2-9) with the scene only at the clip's ends, the plate
    the scene. Columns 8-11: as 0-3 but the plate confident (a pass put it there)."""
    frames = np.empty((k, 12, 12, 3), np.float32)
    frames[:] = GREY
    passing = rng.uniform(0, 255, size=(k - 8, 3))
    frames[8:, :, 0:4] = passing[:, None, None, :]
    frames[8:, :, 8:12] = passing[:, None, None, :]
    frames[1:11, :, 4:8] = RED
    frames[1, :, 4:8] = BLUE  # (coming in)
    frames[10, :, 4:8] = BLUE  # (going out)
    frames += rng.normal(0, 1.5, frames.shape)
    frames = np.clip(frames, 0, 255).astype(np.uint8)
    plate = np.full((12, 12, 3), GREY, np.uint8)
    plate[:, 0:4] = plate[:, 8:12] = (190, 200, 215)  # the vote's blend
    model = BackgroundModel.from_plate(plate, noise_sigma=1.5)
    conf = np.full((12, 12), 0.2, np.float32)
    conf[:, 8:12] = 0.9
    return frames, replace(model, confidence=conf)


def test_a_plate_colour_no_steady_stretch_shows_gives_way_to_the_scene_that_stayed(
        monkeypatch):
    monkeypatch.setattr(steadyscene, "UNSTEADY_PLATE", True)
    monkeypatch.setattr(steadyscene, "STEADY_SCENE", False)
    rng = np.random.default_rng(2)
    frames, model = _passer_by(rng)
    out = retake_steady(model, frames, np.ones((len(frames), 3), np.float32),
                        np.arange(len(frames)) * 0.5)
    assert np.abs(out.plate[:, 0:4].astype(int) - GREY).max() <= 3
    assert np.allclose(out.confidence[:, 0:4], 8 / 12)
    # the person who came and stood is not the scene; a confident plate is kept
    assert (out.plate[:, 4:12] == model.plate[:, 4:12]).all()
    monkeypatch.setattr(steadyscene, "UNSTEADY_PLATE", False)
    assert retake_steady(model, frames, np.ones((len(frames), 3), np.float32),
                         np.arange(len(frames)) * 0.5) is model


def test_a_steady_colour_the_clip_models_call_the_person_is_not_taken(monkeypatch):
    from vidcap.video.appearance import colour_model

    monkeypatch.setattr(steadyscene, "UNSTEADY_PLATE", True)
    rng = np.random.default_rng(3)
    frames, model = _passer_by(rng)
    grey = np.tile(np.asarray(GREY, np.float32), (200, 1))
    red = np.tile(np.asarray(RED, np.float32), (200, 1))
    ones, times = np.ones((len(frames), 3), np.float32), np.arange(len(frames)) * 0.5
    # grey the scene's colour: taken as before
    scene_grey = replace(model, colours=np.stack([colour_model(red, uniform=0.1),
                                                  colour_model(grey, uniform=0.1)]))
    out = retake_steady(scene_grey, frames, ones, times)
    assert np.abs(out.plate[:, 0:4].astype(int) - GREY).max() <= 3
    # grey the person's (a sleeve that stayed): the plate kept
    person_grey = replace(model, colours=np.stack([colour_model(grey, uniform=0.1),
                                                   colour_model(red, uniform=0.1)]))
    assert retake_steady(person_grey, frames, ones, times) is person_grey
