"""The person's mirror image in a glossy floor, cut from the silhouette."""

from __future__ import annotations

import numpy as np

from vidcap.video import reflection
from vidcap.video.background import BackgroundModel
from vidcap.video.reflection import drop_reflection
from vidcap.video.silhouette import extract_silhouettes

H, W = 120, 80
TOP, FEET, LEFT, RIGHT = 20, 80, 30, 50  # the person: rows 20-79, columns 30-49


def _scene(rng, rho=0.35, legs=None):
    """A grey floor, a brown-suited person standing on it, and below the feet their
    mirror image: the floor's difference is ``rho`` times the mirrored body's."""
    plate = np.clip(rng.normal((150, 155, 170), 1.5, (H, W, 3)), 0, 255)
    frame = plate.copy()
    body = np.array((60.0, 70.0, 90.0))
    frame[TOP:FEET, LEFT:RIGHT] = body
    if legs is not None:  # lighter legs (rows 55-79), same hue as the body
        frame[55:FEET, LEFT:RIGHT] = legs
    n = 30  # rows of reflection below the feet
    for d in range(1, n + 1):
        src = frame[FEET - d, LEFT:RIGHT] - plate[FEET - d, LEFT:RIGHT]
        frame[FEET - 1 + d, LEFT:RIGHT] = plate[FEET - 1 + d, LEFT:RIGHT] + rho * src
    frame += rng.normal(0, 1.0, frame.shape)
    return plate.astype(np.uint8), np.clip(frame, 0, 255).astype(np.uint8)


def test_the_reflection_below_the_feet_is_cut_the_body_kept():
    plate, frame = _scene(np.random.default_rng(1))
    mask = np.zeros((H, W), np.uint8)
    mask[TOP:FEET + 30, LEFT:RIGHT] = 1  # the silhouette stage kept the reflection
    cut = drop_reflection(mask, frame, plate)
    assert cut > 0.9 * 30 * (RIGHT - LEFT)
    assert mask[TOP:FEET, LEFT:RIGHT].all()          # the body is whole
    assert mask[FEET + 1:FEET + 30].sum() < 0.05 * 30 * (RIGHT - LEFT)


def test_a_body_without_reflection_and_lighter_legs_are_kept():
    rng = np.random.default_rng(2)
    plate, frame = _scene(rng, rho=0.0)
    mask = np.zeros((H, W), np.uint8)
    mask[TOP:FEET, LEFT:RIGHT] = 1
    assert drop_reflection(mask, frame, plate) == 0
    # Legs a little lighter than the jacket (3/4 of its difference): not weak enough.
    plate, frame = _scene(rng, rho=0.0, legs=np.array((83.0, 91.0, 110.0)))
    mask[:] = 0
    mask[TOP:FEET, LEFT:RIGHT] = 1
    assert drop_reflection(mask, frame, plate) == 0


def test_legs_of_another_colour_under_a_strong_shirt_are_kept():
    """Jeans (blue-grey) under a red shirt: weaker against the wall than the shirt,
    but not the shirt's mirror image (another hue): kept (CDnet office)."""
    rng = np.random.default_rng(3)
    plate = np.clip(rng.normal((120, 135, 125), 1.5, (H, W, 3)), 0, 255)
    frame = plate.copy()
    frame[TOP:50, LEFT:RIGHT] = (40, 40, 200)        # red shirt (BGR)
    frame[50:FEET, LEFT:RIGHT] = (110, 85, 70)       # jeans
    frame = np.clip(frame + rng.normal(0, 1.0, frame.shape), 0, 255).astype(np.uint8)
    mask = np.zeros((H, W), np.uint8)
    mask[TOP:FEET, LEFT:RIGHT] = 1
    assert drop_reflection(mask, frame, plate.astype(np.uint8)) == 0
    assert mask[TOP:FEET, LEFT:RIGHT].all()


def test_extract_silhouettes_cuts_it_and_the_switch_keeps_it(monkeypatch):
    plate, frame = _scene(np.random.default_rng(4))
    truth = np.zeros((H, W), bool)
    truth[TOP:FEET, LEFT:RIGHT] = True
    bg = BackgroundModel.from_plate(plate, noise_sigma=1.5)
    got = extract_silhouettes(frame[None], bg).masks[0]
    iou = (got & truth).sum() / (got | truth).sum()
    assert iou > 0.95
    monkeypatch.setattr(reflection, "CUT_REFLECTIONS", False)
    kept = extract_silhouettes(frame[None], bg).masks[0]
    assert (kept & truth).sum() / (kept | truth).sum() < 0.8


def test_dark_legs_against_a_darker_floor_are_kept(monkeypatch):
    """Black trousers: against a white wall above the floor line, against a dark floor
    below it. Below the line the difference is weak and of the same direction, as a
    reflection's would be, but the colour is the trousers' own: kept
    (sports2d_walk_turn)."""
    rng = np.random.default_rng(5)
    plate = np.empty((H, W, 3))
    plate[:70] = (225, 228, 230)   # white wall
    plate[70:] = (55, 55, 60)      # dark floor
    plate = np.clip(plate + rng.normal(0, 1.5, plate.shape), 0, 255)
    frame = plate.copy()
    frame[TOP:FEET + 20, LEFT:RIGHT] = (20, 20, 22)   # black clothes down to the feet
    frame = np.clip(frame + rng.normal(0, 1.0, frame.shape), 0, 255).astype(np.uint8)
    mask = np.zeros((H, W), np.uint8)
    mask[TOP:FEET + 20, LEFT:RIGHT] = 1
    assert drop_reflection(mask, frame, plate.astype(np.uint8)) == 0
    monkeypatch.setattr(reflection, "OTHER_COLOUR", 0.0)  # without the colour test
    assert drop_reflection(mask.copy(), frame, plate.astype(np.uint8)) > 0


def test_a_reflection_running_onto_a_dark_band_is_cut_on_the_light_floor(monkeypatch):
    """A glossy light floor with a grey band across it 12 rows below the feet
    (sbi_caviar1): on the light floor the trousers' mirror image takes the floor's
    tint, on the band it shows nearly in the trousers' own colour. The whole run fails
    the colour test (12 of 30 rows of another colour than their mirror rows); its start
    passes it and is cut (:data:`reflection.SHORTEN_RUN`); without that nothing is."""
    rng = np.random.default_rng(6)
    band = slice(FEET + 12, FEET + 30)
    plate = np.clip(rng.normal((150, 155, 170), 1.5, (H, W, 3)), 0, 255)
    plate[band] = np.clip(rng.normal((110, 115, 125), 1.5, plate[band].shape), 0, 255)
    frame = plate.copy()
    body = np.array((60.0, 70.0, 90.0))
    frame[TOP:FEET, LEFT:RIGHT] = body
    for d in range(1, 13):  # the light floor: 0.35 of the body's difference
        row = FEET - 1 + d
        frame[row, LEFT:RIGHT] = plate[row, LEFT:RIGHT] + 0.35 * (body - plate[FEET - d,
                                                                           LEFT:RIGHT])
    frame[band, LEFT:RIGHT] = body + (5.0, 3.0, 2.0)  # the band: the trousers' colour
    frame = np.clip(frame + rng.normal(0, 1.0, frame.shape), 0, 255).astype(np.uint8)
    plate = plate.astype(np.uint8)
    mask = np.zeros((H, W), np.uint8)
    mask[TOP:FEET + 30, LEFT:RIGHT] = 1  # the silhouette stage kept the reflection
    monkeypatch.setattr(reflection, "SHORTEN_RUN", False)
    assert drop_reflection(mask.copy(), frame, plate) == 0
    monkeypatch.setattr(reflection, "SHORTEN_RUN", True)
    assert drop_reflection(mask, frame, plate) > 0
    assert mask[TOP:FEET, LEFT:RIGHT].all()  # the body is whole
    assert mask[FEET:FEET + 12].sum() < 0.05 * 12 * (RIGHT - LEFT)  # the light floor's cut


def test_a_reflection_strong_right_under_the_feet_is_cut_from_the_feet(monkeypatch):
    """A polished floor mirrors the feet strongly where they touch it (0.78-0.72 of the
    body's difference in the first four rows, above :data:`reflection.WEAK`), then
    weakly (0.35; sbi_caviar1 standing, cdnet_office_enter's desk). The run's first
    bins may be under :data:`reflection.START_WEAK`: the whole image is cut; without
    that the strong rows stay (a run starts only further down, if at all)."""
    rng = np.random.default_rng(7)
    plate = np.clip(rng.normal((150, 155, 170), 1.5, (H, W, 3)), 0, 255)
    frame = plate.copy()
    body = np.array((60.0, 70.0, 90.0))
    frame[TOP:FEET, LEFT:RIGHT] = body
    for d in range(1, 31):
        rho = (0.78, 0.76, 0.74, 0.72)[d - 1] if d <= 4 else 0.35
        row = FEET - 1 + d
        frame[row, LEFT:RIGHT] = plate[row, LEFT:RIGHT] + rho * (body - plate[FEET - d,
                                                                               LEFT:RIGHT])
    frame = np.clip(frame + rng.normal(0, 1.0, frame.shape), 0, 255).astype(np.uint8)
    plate = plate.astype(np.uint8)
    mask = np.zeros((H, W), np.uint8)
    mask[TOP:FEET + 30, LEFT:RIGHT] = 1
    monkeypatch.setattr(reflection, "START_WEAK", None)
    off = mask.copy()
    drop_reflection(off, frame, plate)
    assert off[FEET:FEET + 4, LEFT:RIGHT].all()  # the strong rows stay
    monkeypatch.setattr(reflection, "START_WEAK", 0.8)
    drop_reflection(mask, frame, plate)
    assert mask[TOP:FEET, LEFT:RIGHT].all()  # the body is whole
    assert mask[FEET:FEET + 30].sum() < 0.05 * 30 * (RIGHT - LEFT)
