"""A person who held one pose for the whole clip (vidcap.video.heldpose)."""

import numpy as np

from vidcap.video.background import BackgroundModel


def _scene(seed=3):
    rng = np.random.default_rng(seed)
    plate = rng.integers(90, 110, (96, 128, 3)).astype(np.uint8)
    return plate, BackgroundModel.from_plate(plate, noise_sigma=2.0)


def test_samples_equal_to_the_plate_are_nearly_empty():
    from vidcap.video.heldpose import nearly_empty

    plate, model = _scene()
    frames = np.repeat(plate[None], 8, axis=0)
    assert nearly_empty(model, frames, np.ones((8, 3)))


def test_a_person_who_shows_in_the_samples_is_not_nearly_empty():
    from vidcap.video.heldpose import nearly_empty

    plate, model = _scene()
    frames = np.repeat(plate[None], 8, axis=0)
    frames[:, 20:90, 50:70] = (20, 20, 200)  # 11 % of the frame, unlike the plate
    assert not nearly_empty(model, frames, np.ones((8, 3)))
    frames[2:] = plate  # shown in two samples of eight: someone passing, not a held pose
    assert not nearly_empty(model, frames, np.ones((8, 3)))


def test_one_sample_of_a_person_settling_into_a_pose_keeps_the_gate_open():
    from vidcap.video.heldpose import MAX_SHOWN, nearly_empty

    plate, model = _scene()
    frames = np.repeat(plate[None], 8, axis=0)
    frames[:MAX_SHOWN, 20:90, 50:70] = (20, 20, 200)  # the first sample: still moving
    frames[MAX_SHOWN:, 60:64, 50:70] = (20, 20, 200)  # then a hand that sways (0.7 %)
    assert nearly_empty(model, frames, np.ones((8, 3)))
    frames[MAX_SHOWN, 20:90, 50:70] = (20, 20, 200)  # one more sample shows the body
    assert not nearly_empty(model, frames, np.ones((8, 3)))


def _detector(monkeypatch, box, at_rows):
    """A detector that finds ``box`` only when searching at ``at_rows`` rows, and a cut
    that is the box's middle third; returns the list of the heights searched."""
    import vidcap.video.personbox as pb

    searched = []

    def detect(frame, *, rows=480, **_):
        searched.append(rows)
        if rows != at_rows:
            return np.zeros((0, 4), np.int64), np.zeros(0)
        return np.array([box]), np.array([1.0])

    def cut(frame, b, *_, **__):
        x0, y0, x1, y1 = b
        out = np.zeros(frame.shape[:2], bool)
        out[y0:y1, x0 + (x1 - x0) // 3:x1 - (x1 - x0) // 3] = True
        return out

    monkeypatch.setattr(pb, "detect_people", detect)
    monkeypatch.setattr(pb, "cut_in_box", cut)
    return searched


def test_a_held_pose_is_searched_for_though_nothing_was_never_seen(monkeypatch):
    from vidcap.video import heldpose

    plate, model = _scene()
    frames = np.repeat(plate[None], 8, axis=0)  # the plate took the person in whole
    assert model.never_seen_fraction == 0.0  # personbox's own gate keeps it off
    searched = _detector(monkeypatch, (50, 10, 90, 90), at_rows=240)
    out = heldpose.absorbed_or_held(model, frames, np.ones((8, 3)))
    assert out.still_person is not None
    assert out.still_person[20:80, 65:75].all() and not out.still_person[:, :55].any()
    assert out.never_seen[20:80, 65:75].all()
    assert searched[:2] == [480, 240]  # the half height only when 480 found nobody
    monkeypatch.setattr(heldpose, "HELD_POSE", False)
    assert heldpose.absorbed_or_held(model, frames, np.ones((8, 3))) is model


def test_a_visible_person_keeps_the_detector_off(monkeypatch):
    from vidcap.video import heldpose

    # (as in frames of 240 rows and more: this test's 96 rows stand for them)
    monkeypatch.setattr(heldpose, "SMALL_FRAMES", False)
    plate, model = _scene()
    frames = np.repeat(plate[None], 8, axis=0)
    frames[:, 20:90, 50:70] = (20, 20, 200)
    searched = _detector(monkeypatch, (50, 10, 90, 90), at_rows=480)
    assert heldpose.absorbed_or_held(model, frames, np.ones((8, 3))) is model
    assert searched == []  # (the ordinary clip's cost: the samples' first pass only)


def test_in_a_small_frame_a_torso_under_a_waving_arm_is_searched_for(monkeypatch):
    """At Weizmann's size the plate's never-seen map misses a still torso, and an arm
    that waves keeps the samples' silhouettes from being nearly empty: with
    SMALL_FRAMES (off by default) the search runs anyway in frames under
    ENLARGE_BELOW rows, and finds the torso the plate took."""
    from vidcap.video import heldpose

    plate, model = _scene()
    plate[20:90, 60:72] = (20, 20, 200)  # the torso, taken into the plate
    model = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    frames = np.repeat(plate[None], 8, axis=0)
    for i in range(8):  # an arm, 8 % of the frame, that shows in every sample
        frames[i, 20:50, 30 + 2 * i:60] = (30, 160, 30)
    assert not heldpose.nearly_empty(model, frames, np.ones((8, 3)))
    _detector(monkeypatch, (50, 10, 90, 90), at_rows=480)
    monkeypatch.setattr(heldpose, "SMALL_FRAMES", False)
    assert heldpose.absorbed_or_held(model, frames, np.ones((8, 3))) is model
    monkeypatch.setattr(heldpose, "SMALL_FRAMES", True)
    out = heldpose.absorbed_or_held(model, frames, np.ones((8, 3)))
    assert out.still_person is not None and out.still_person[20:80, 65:75].all()


def test_in_a_small_frame_a_visible_person_stops_the_search_at_the_first_cut(monkeypatch):
    from vidcap.video import heldpose

    monkeypatch.setattr(heldpose, "SMALL_FRAMES", True)
    plate, model = _scene()
    frames = np.repeat(plate[None], 8, axis=0)
    frames[:, 10:90, 60:80] = (20, 20, 200)  # round the detector's cut
    searched = _detector(monkeypatch, (50, 10, 90, 90), at_rows=480)
    assert heldpose.absorbed_or_held(model, frames, np.ones((8, 3))) is model
    assert searched == [480]  # one look: the cut is in the silhouette
