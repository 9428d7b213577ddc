"""Plate pixels that show the person although the scene was seen there (issue 26,
vidcap/video/absorbed.py)."""

from __future__ import annotations

import numpy as np

from vidcap.video.absorbed import flag_unseen, retake_absorbed
from vidcap.video.background import BackgroundModel

RED, BLUE = (40, 45, 190), (150, 60, 30)
GREY, LIGHT = (110, 120, 115), (150, 160, 150)


def _scene(h=120, w=160):
    xs = np.arange(w)
    out = np.zeros((h, w, 3), np.uint8)
    out[:] = np.where((xs // 8 % 2 == 0)[None, :, None], GREY, LIGHT)
    return out


def _stepping(n=20, seed=0):
    """A red torso swaying a few pixels; its blue leg stands at x 70-82 in all
    samples but every fifth, when it steps to x 90-102. Returns frames, the scene and
    the plate a majority vote gives (the leg where it stands most)."""
    rng = np.random.default_rng(seed)
    scene = _scene()
    frames = []
    for t in range(n):
        f = scene.copy()
        dx = int(round(4 * np.sin(2 * np.pi * t / 7)))
        f[30:70, 68 + dx:100 + dx] = RED
        x0 = 90 if t % 5 == 0 else 70
        f[70:110, x0:x0 + 12] = BLUE
        frames.append(np.clip(f + rng.normal(0, 2, f.shape), 0, 255).astype(np.uint8))
    plate = scene.copy()
    plate[70:110, 70:82] = BLUE
    return np.array(frames), scene, plate


def test_a_leg_the_plate_absorbed_is_retaken_from_the_samples_that_show_the_floor():
    frames, scene, plate = _stepping()
    model = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    again = retake_absorbed(model, frames, np.ones((len(frames), 3), np.float32))
    err = np.abs(again.plate.astype(int) - scene.astype(int)).sum(-1)
    assert np.median(err[72:108, 72:80]) < 12  # the floor, not the leg
    before = np.abs(plate.astype(int) - scene.astype(int)).sum(-1)
    outside = np.ones(err.shape, bool)
    outside[65:115, 60:110] = False
    assert (err[outside] == before[outside]).all()  # nothing else changes


def test_a_scene_the_colour_of_the_person_that_never_shows_otherwise_stays():
    """A blue block of the scene right beside where the leg steps (inside the motion
    footprint; every sample shows it) keeps its colour: no sample shows anything else
    there."""
    frames, scene, _ = _stepping()
    scene[70:110, 104:116] = BLUE
    frames[:, 70:110, 104:116] = BLUE
    model = BackgroundModel.from_plate(scene, noise_sigma=2.0)
    again = retake_absorbed(model, frames, np.ones((len(frames), 3), np.float32))
    assert (again.plate[70:110, 104:116] == BLUE).all()


def test_too_few_samples_leave_the_plate_alone():
    frames, _, plate = _stepping(n=3)
    model = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    assert retake_absorbed(model, frames, np.ones((3, 3), np.float32)) is model


def test_a_never_seen_flag_over_where_the_scene_shows_is_lifted_and_the_torso_kept():
    """The never-seen flag covers the torso (red in every sample) and spread beside it
    where the samples show the scene in all but a few: that part is re-taken and
    un-flagged, the torso stays flagged with its plate untouched."""
    from dataclasses import replace

    frames, scene, plate = _stepping()
    guess = plate.copy()
    guess[30:70, 60:110] = (128, 128, 128)  # an inpainted guess over the whole flag
    never = np.zeros(scene.shape[:2], bool)
    never[30:70, 60:110] = True  # the torso sways over x 64-104
    model = replace(BackgroundModel.from_plate(guess, noise_sigma=2.0), never_seen=never)
    again = retake_absorbed(model, frames, np.ones((len(frames), 3), np.float32))
    assert again.never_seen[32:68, 74:94].all()  # the torso: red in every sample
    assert (again.plate[32:68, 74:94] == 128).all()
    assert not again.never_seen[32:68, 60:62].any()  # beside it: the scene shows
    err = np.abs(again.plate.astype(int) - scene.astype(int)).sum(-1)
    assert np.median(err[32:68, 60:62]) < 12


WHITE, BLACK = (235, 235, 235), (20, 20, 22)
DARK, DARKER = (40, 60, 45), (24, 26, 24)


def _crossing(n=24, seed=1):
    """A runner (white top over black shorts over light legs) crossing a dark hedge
    from left to right, past a white post at x 78-81 (only where she runs: the scene
    shows no white elsewhere); the plate is the true scene.
    Returns frames and the scene."""
    rng = np.random.default_rng(seed)
    h, w = 120, 160
    xs = np.arange(w)
    scene = np.zeros((h, w, 3), np.uint8)
    scene[:] = np.where((xs // 6 % 2 == 0)[None, :, None], DARK, DARKER)
    scene[30:110, 78:82] = WHITE
    frames = []
    for t in range(n):
        f = scene.copy()
        x0 = int(round(-10 + t * 160 / n))
        sl = slice(max(0, x0), max(0, x0 + 16))
        f[30:62, sl] = WHITE
        f[62:76, sl] = BLACK
        f[76:110, sl] = (150, 170, 200)
        frames.append(np.clip(f + rng.normal(0, 2, f.shape), 0, 255).astype(np.uint8))
    return np.array(frames), scene


def test_a_post_the_person_passes_stays_the_scene_colour():
    """The post's white is the runner's top and her shorts are as dark as the hedge, so
    appearance alone would re-take the post from the samples where the shorts pass;
    but most samples show it white while the runner is elsewhere: it stays."""
    frames, scene = _crossing()
    model = BackgroundModel.from_plate(scene, noise_sigma=2.0)
    again = retake_absorbed(model, frames, np.ones((len(frames), 3), np.float32))
    assert (again.plate[30:110, 78:82] == WHITE).all()


def _dancer(n=24, seed=2, bar=False):
    """A red torso at x 60-90, y 30-80 in every sample, its shade turning (0.75-1.25 of
    its colour, as a body that turns on the spot, never the plate's), a blue arm
    swinging round its right side; the plate is the vote's: the torso (mid shade) where
    it always stands, never flagged. With ``bar``, a red bar of the scene (the torso's
    colour) at x 104-110 from y 0 to y 119, which the arm passes at y 40-56. Returns
    frames, the scene and that plate."""
    rng = np.random.default_rng(seed)
    scene = _scene()
    if bar:
        scene[:, 104:110] = RED
    frames = []
    for t in range(n):
        f = scene.copy()
        shade = (0.75, 0.85, 1.15, 1.25)[t % 4]
        f[30:80, 60:90] = np.clip(np.array(RED) * shade, 0, 255)
        y = 40 + int(round(8 * (0.5 + 0.5 * np.sin(2 * np.pi * t / 9))))
        f[y:y + 8, 90:118] = BLUE
        frames.append(np.clip(f + rng.normal(0, 2, f.shape), 0, 255).astype(np.uint8))
    plate = scene.copy()
    plate[30:80, 60:90] = RED
    return np.array(frames), scene, plate


def test_a_torso_no_sample_shows_uncovered_is_flagged_never_seen_and_inpainted():
    """The vote kept the torso's red where it always stands, and the torso's turning
    shade puts it in the motion footprint, so nobody flagged it: no sample shows a
    scene colour there, so it is never seen, its plate a guess from the scene round it
    (not the person's red: the silhouettes then see the torso)."""
    frames, scene, plate = _dancer()
    model = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    again = flag_unseen(model, frames, np.ones((len(frames), 3), np.float32))
    core = (slice(36, 74), slice(66, 84))
    assert again.never_seen[core].mean() > 0.9
    left = np.abs(again.plate[core].astype(int) - np.array(RED)).sum(-1)
    assert np.median(left) > 100  # no longer the torso's red
    assert not again.never_seen[:, :50].any()  # the scene beside stays seen


def test_a_scene_bar_of_the_persons_colour_reaching_out_of_the_footprint_stays_seen():
    """A bar of the scene in the torso's red, which the arm sweeps over at y 40-56 (so
    it lies in the motion footprint there, and every sample shows it red or the arm's
    blue, both the person's colours), continues above and below the footprint in the
    same colour: a scene object, not a body part; it stays seen, its plate untouched."""
    frames, scene, plate = _dancer(bar=True)
    model = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    again = flag_unseen(model, frames, np.ones((len(frames), 3), np.float32))
    assert not again.never_seen[:, 100:114].any()
    assert (again.plate[:, 104:110] == RED).all()


SKIN = (150, 170, 215)
TEAL = (150, 140, 40)


def _still_torso(n=24, seed=3, block=False):
    """A red torso at x 64-86, y 30-80 that never moves, its shade turning (0.93-1.07 of
    its colour: it differs from the plate in some samples, so it lies in the motion
    footprint), between two skin-coloured arms (6 wide, y 30-80) that swing out and in
    beside it: the person's colour model learns the arms' colour, not the torso's.
    With ``block``, a teal block of the scene at x 96-106, y 60-80, which the right
    arm's sweep reaches (in the motion footprint; every sample shows it teal or the
    arm's skin, both unlike the grey stripes round it). Returns frames, the scene and
    the plate the vote gives (the torso where it stands)."""
    rng = np.random.default_rng(seed)
    scene = _scene(240, 320)  # (the still test looks for the scene a ring's width out)
    if block:
        scene[60:80, 96:106] = TEAL
    frames = []
    for t in range(n):
        f = scene.copy()
        f[30:80, 64:86] = np.clip(np.array(RED) * (0.93, 0.97, 1.03, 1.07)[t % 4], 0, 255)
        dx = int(round(6 * (0.5 - 0.5 * np.cos(2 * np.pi * t / 8))))
        f[30:80, 56 - dx:62 - dx] = SKIN
        f[30:80, 88 + dx:94 + dx] = SKIN
        frames.append(np.clip(f + rng.normal(0, 2, f.shape), 0, 255).astype(np.uint8))
    plate = scene.copy()
    plate[30:80, 64:86] = RED
    return np.array(frames), scene, plate


def test_a_still_torso_between_the_arms_of_a_colour_the_person_model_lacks_is_flagged(
        monkeypatch):
    """Every sample shows the torso red, unlike the grey stripes round it, and the
    swinging arms on both sides: never seen, whatever the person's colour model (the
    arms' skin) says of red; its plate guessed from beyond what moved (the stripes, not
    the red). With FLAG_STILL off it stays the plate's."""
    import vidcap.video.absorbed as absorbed

    monkeypatch.setattr(absorbed, "FLAG_STILL", True)
    frames, scene, plate = _still_torso()
    model = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    gains = np.ones((len(frames), 3), np.float32)
    core = (slice(36, 74), slice(68, 82))
    again = flag_unseen(model, frames, gains)
    assert again.never_seen[core].mean() > 0.9
    assert not again.never_seen[:, :40].any() and not again.never_seen[:, 112:].any()
    assert not again.never_seen[90:].any()
    left = np.abs(again.plate[core].astype(int) - np.array(RED)).sum(-1)
    assert np.median(left) > 150  # the torso's red is gone from the plate
    monkeypatch.setattr(absorbed, "FLAG_STILL", False)
    assert flag_unseen(model, frames, gains).never_seen[core].mean() < 0.1


def test_a_still_scene_block_beside_the_arms_sweep_is_not_flagged(monkeypatch):
    """The teal block passes the still test's colour tests as the torso does (the
    plate's and every sample's colour unlike the stripes round it), but no sample has
    the person on both of its sides: scene beside what moved, not a body part between
    moving parts. It stays seen, its plate untouched; the torso is still flagged."""
    import vidcap.video.absorbed as absorbed

    monkeypatch.setattr(absorbed, "FLAG_STILL", True)
    frames, scene, plate = _still_torso(block=True)
    model = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    again = flag_unseen(model, frames, np.ones((len(frames), 3), np.float32))
    assert not again.never_seen[60:80, 96:106].any()
    assert (again.plate[62:78, 101:106] == TEAL).all()
    assert again.never_seen[36:74, 68:82].mean() > 0.9
    monkeypatch.setattr(absorbed, "STILL_BETWEEN", 0.0)  # without the test: flagged
    assert flag_unseen(model, frames, np.ones((len(frames), 3), np.float32)
                       ).never_seen[60:80, 96:106].mean() > 0.5


def test_the_still_test_waits_for_a_person_who_stays_in_one_place():
    """The foreground's centroid kept within STILL_TRAVEL of the frame's width over the
    whole clip: a dancer swaying on the spot stays; a man who walks in and then stands
    (a fifth of the width between the first and the last sample) does not, and neither
    does a clip with too little foreground to tell."""
    from vidcap.video.absorbed import STILL_TRAVEL, _stays

    k, h, w = 12, 40, 100
    sway = np.zeros((k, h, w), bool)
    for t in range(k):
        x = 45 + int(round(3 * np.sin(t)))
        sway[t, 10:30, x:x + 8] = True
    assert _stays(sway)
    walk_in = np.zeros((k, h, w), bool)
    for t in range(k):
        x = 70 - min(t, 4) * 5  # 70 -> 50, then stands
        walk_in[t, 10:30, x:x + 8] = True
    assert 20 > STILL_TRAVEL * w and not _stays(walk_in)
    assert not _stays(np.zeros((k, h, w), bool))
