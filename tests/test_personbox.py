"""A person the plate absorbed, by detector box and grabCut (vidcap.video.personbox)."""

import numpy as np

from vidcap.video.background import BackgroundModel
from vidcap.video.personbox import absorbed_person, cut_in_box, detect_people


def test_nobody_detected_on_a_blank_frame():
    boxes, scores = detect_people(np.full((240, 320, 3), 128, np.uint8))
    assert boxes.shape == (0, 4) and scores.shape == (0,)


def test_the_cut_finds_the_figure_in_its_box():
    rng = np.random.default_rng(0)
    img = rng.integers(100, 140, (120, 160, 3)).astype(np.uint8)  # a grey textured wall
    truth = np.zeros((120, 160), bool)
    truth[30:110, 70:90] = True  # a red figure, centred in the box as a detector puts it
    img[truth] = (30, 30, 200)
    cut = cut_in_box(img, (50, 20, 110, 115))
    iou = (cut & truth).sum() / (cut | truth).sum()
    assert iou > 0.9
    assert not cut[:, :45].any()  # nothing outside the box


def test_a_plate_that_saw_everything_is_left_alone():
    frames = np.full((4, 64, 64, 3), 100, np.uint8)
    model = BackgroundModel.from_plate(frames[0], noise_sigma=2.0)
    assert absorbed_person(model, frames, np.ones((4, 3))) is model
