"""Bad inputs of the silhouette stage: one clear line each (issue 26)."""

from __future__ import annotations

import numpy as np
import pytest

from tests._synthframes import background, clip
from vidcap.video.background import BackgroundError, estimate_background
from vidcap.video.inputchecks import camera_shift


def test_too_few_frames_black_and_white():
    frames, _ = clip(3, 60, 80, rng=np.random.default_rng(1))
    with pytest.raises(BackgroundError, match="only 3 frames"):
        estimate_background(frames)
    with pytest.raises(BackgroundError, match="black"):
        estimate_background(np.zeros((10, 40, 50, 3), np.uint8))
    with pytest.raises(BackgroundError, match="white"):
        estimate_background(np.full((10, 40, 50, 3), 255, np.uint8))


def test_a_panning_camera_is_told_a_fixed_one_is_not():
    rng = np.random.default_rng(2)
    wide = background(120, 400, rng)
    pan = np.stack([wide[:, 8 * i:8 * i + 160] for i in range(12)])
    with pytest.raises(BackgroundError, match="camera moves"):
        estimate_background(pan)
    fixed, _ = clip(24, 120, 160, rng=rng, walk=True)
    shift, _changed = camera_shift(fixed[::2])
    assert shift < 1.0
    estimate_background(fixed)  # no error


def test_nobody_and_a_person_who_never_moves():
    still = background(60, 80, np.random.default_rng(3))
    with pytest.raises(BackgroundError, match="nothing moves"):
        estimate_background(np.repeat(still[None], 8, axis=0))
    statue = still.copy()
    statue[20:50, 30:45] = (40, 50, 160)  # someone standing perfectly still
    with pytest.raises(BackgroundError, match="never moves"):
        estimate_background(np.repeat(statue[None], 8, axis=0))


def test_plate_notice_only_when_much_is_never_seen():
    from vidcap.video.background import BackgroundModel
    from vidcap.video.inputchecks import plate_notice

    plate = background(60, 80, np.random.default_rng(4))
    model = BackgroundModel.from_plate(plate)
    assert plate_notice(model) is None
    never = np.zeros((60, 80), bool)
    never[10:40, 30:50] = True
    text = plate_notice(BackgroundModel(**{**model.__dict__, "never_seen": never}))
    assert "12.5%" in text and "--background" in text
