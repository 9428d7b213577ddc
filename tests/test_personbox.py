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


def test_a_box_round_no_person_cuts_nothing():
    """A detector's box round a lit strip of wall with a speck in it: whatever grabCut
    makes of the speck fills far less of the box than a person (a fifth or more), so
    the cut is empty; the figure of the test above fills its box enough to stay."""
    rng = np.random.default_rng(1)
    img = rng.integers(100, 140, (120, 160, 3)).astype(np.uint8)
    img[40:43, 78:81] = (30, 30, 200)  # 9 px of red in a 60x95 box
    assert not cut_in_box(img, (50, 20, 110, 115)).any()
    img[30:110, 70:90] = (30, 30, 200)
    assert cut_in_box(img, (50, 20, 110, 115)).sum() > 0.2 * 60 * 95


def test_a_plate_that_saw_everything_is_left_alone():
    frames = np.full((4, 64, 64, 3), 100, np.uint8)
    model = BackgroundModel.from_plate(frames[0], noise_sigma=2.0)
    assert absorbed_person(model, frames, np.ones((4, 3))) is model


def test_where_the_still_person_stood_first_the_later_samples_give_the_plate():
    from vidcap.video.personbox import _uncovered_plate

    rng = np.random.default_rng(2)
    wall = lambda: rng.integers(99, 102, (60, 80, 3)).astype(np.uint8)  # noqa: E731
    a = np.zeros((60, 80), bool)
    a[10:50, 10:25] = True  # where the person stands in samples 0-2
    b = np.zeros((60, 80), bool)
    b[10:50, 50:65] = True  # and in samples 3-5
    frames = np.stack([wall() for _ in range(6)])
    cuts = np.stack([a, a, a, b, b, b])
    frames[cuts] = (20, 20, 180)
    plate0 = frames[0].copy()  # the vote kept the person at A
    model = BackgroundModel.from_plate(plate0, noise_sigma=2.0)
    plate, seen = _uncovered_plate(model, frames, np.ones((6, 3)), cuts)
    assert seen[15:45, 12:23].all()  # A is seen uncovered in samples 3-5
    assert np.abs(plate[15:45, 12:23].astype(int) - 100).max() <= 6  # the wall
    assert not seen[:, 40:].any()  # B shows the plate's wall already: nothing to re-take


def _absorbed_scene(monkeypatch, boxes):
    """8 samples equal to the plate (so the first-pass silhouette is empty: the person,
    if any, is absorbed), a plate that left a patch never seen, and a detector that
    returns ``boxes[i]`` on sample i; returns the samples, the model and the list the
    cuts are logged to (a cut is the box's middle third)."""
    from dataclasses import replace

    import vidcap.video.personbox as pb

    rng = np.random.default_rng(3)
    plate = rng.integers(90, 110, (96, 128, 3)).astype(np.uint8)
    frames = np.repeat(plate[None], 8, axis=0)
    never = np.zeros((96, 128), bool)
    never[40:60, 50:70] = True  # 3 % of the frame never seen: the detector runs
    model = replace(BackgroundModel.from_plate(plate, noise_sigma=2.0), never_seen=never)
    lookup = {frames[i].ctypes.data: b for i, b in enumerate(boxes)}
    cuts = []

    def detect(frame, **_):
        b = lookup[frame.ctypes.data]
        return np.array([b]), np.array([1.0])

    def cut(frame, box, *_, **__):
        x0, y0, x1, y1 = box
        out = np.zeros(frame.shape[:2], bool)
        out[y0:y1, x0 + (x1 - x0) // 3:x1 - (x1 - x0) // 3] = True
        cuts.append(tuple(box))
        return out

    monkeypatch.setattr(pb, "detect_people", detect)
    monkeypatch.setattr(pb, "cut_in_box", cut)
    return frames, model, cuts


def test_a_person_whose_boxes_move_is_cut_once(monkeypatch):
    from vidcap.video.personbox import BOXES_MOVE, find_absorbed

    # A person crossing the frame: each box 30 px right of the last (IoU 0.2).
    boxes = [(5 + 30 * i, 10, 45 + 30 * i, 90) for i in range(8)]
    frames, model, cuts = _absorbed_scene(monkeypatch, boxes)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert reason == BOXES_MOVE and out is model
    assert cuts == [boxes[0]]  # only the first sample was cut (to tell absorbed)


def test_a_person_whose_boxes_stay_is_cut_in_every_sample(monkeypatch):
    from vidcap.video.personbox import ABSORBED, find_absorbed

    # A still person: the detector's box jitters by a pixel or two (IoU > 0.9).
    boxes = [(50 + i % 2, 10, 90 + i % 2, 90 + i % 3) for i in range(8)]
    frames, model, cuts = _absorbed_scene(monkeypatch, boxes)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert len(cuts) == 8  # the cuts decide
    assert reason == ABSORBED and out.still_person is not None
    assert out.still_person[20:80, 65:75].all() and not out.still_person[:, :55].any()


def test_a_find_not_seen_again_is_given_up(monkeypatch):
    from vidcap.video.personbox import GIVE_UP, NOT_AGAIN, find_absorbed

    # One find in sample 0 (the detector's false alarm), nothing after it but a
    # box in the last sample, which is never looked at.
    boxes = [(50, 10, 90, 90)] + [(0, 0, 0, 0)] * 6 + [(50, 10, 90, 90)]
    frames, model, cuts = _absorbed_scene(monkeypatch, boxes)
    import vidcap.video.personbox as pb

    looked, detect = [], pb.detect_people

    def counting(frame, **kw):
        looked.append(1)
        b, s = detect(frame, **kw)
        keep = b[:, 2] > b[:, 0]
        return b[keep], s[keep]

    monkeypatch.setattr(pb, "detect_people", counting)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert reason == NOT_AGAIN and out is model
    assert len(looked) == GIVE_UP + 1 and cuts == [boxes[0]]


def test_the_enclosing_box_is_the_whole_person_not_a_part():
    from vidcap.video.personbox import enclosing_box

    whole, legs, other = (40, 10, 100, 90), (55, 50, 85, 90), (0, 0, 120, 40)
    boxes = np.array([whole, legs, other])
    # The legs score best; the whole body holds them; the larger box elsewhere
    # (holding a third of the legs' box) is not the person.
    assert tuple(enclosing_box(boxes, np.array([0.8, 1.2, 0.9]))) == whole
    assert tuple(enclosing_box(boxes[1:], np.array([1.2, 0.9]))) == legs
    assert tuple(enclosing_box(boxes[:1], np.array([0.6]))) == whole


def test_a_still_person_whose_best_box_swaps_for_a_part_is_absorbed(monkeypatch):
    import vidcap.video.personbox as pb
    from vidcap.video.personbox import ABSORBED, find_absorbed

    # The detector finds the whole person and the legs alone in every sample, the
    # legs scoring best in every other one (05_04 front): the person never moved.
    whole, legs = (40, 10, 100, 90), (55, 50, 85, 90)
    frames, model, cuts = _absorbed_scene(monkeypatch, [whole] * 8)

    def detect(frame, **_):
        i = next(k for k in range(8) if frames[k].ctypes.data == frame.ctypes.data)
        return np.array([whole, legs]), np.array([1.0, 1.5 if i % 2 else 0.5])

    monkeypatch.setattr(pb, "detect_people", detect)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert reason == ABSORBED and set(cuts) == {whole}
    assert out.still_person[15:85, 62:78].all()


def _moving_cuts(monkeypatch, frames, shift_legs: bool):
    """A cut per sample i: a torso swinging 6 px a sample over legs that stay (or
    that swing with it, ``shift_legs``); the detector's box the same throughout."""
    import vidcap.video.personbox as pb

    def cut(frame, box, *_, **__):
        i = next(k for k in range(len(frames)) if frames[k].ctypes.data == frame.ctypes.data)
        dx = 6 * (i % 4)
        out = np.zeros(frame.shape[:2], bool)
        out[12:50, 52 + dx:76 + dx] = True  # head and torso
        lx = dx if shift_legs else 0
        out[50:90, 58 + lx:72 + lx] = True  # the legs
        return out

    monkeypatch.setattr(pb, "cut_in_box", cut)


def test_legs_held_under_a_swinging_torso_are_absorbed(monkeypatch):
    import vidcap.video.personbox as pb
    from vidcap.video.personbox import ABSORBED, CUTS_MOVE, find_absorbed

    monkeypatch.setattr(pb, "IN_PLACE", False)  # the default: such cuts move
    monkeypatch.setattr(pb, "STILL_CORE", False)  # (its own test is below)
    frames, model, _ = _absorbed_scene(monkeypatch, [(40, 10, 100, 90)] * 8)
    _moving_cuts(monkeypatch, frames, shift_legs=False)
    assert find_absorbed(model, frames, np.ones((8, 3)))[1] == CUTS_MOVE
    monkeypatch.setattr(pb, "IN_PLACE", True)
    frames, model, _ = _absorbed_scene(monkeypatch, [(40, 10, 100, 90)] * 8)
    _moving_cuts(monkeypatch, frames, shift_legs=False)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert reason == ABSORBED
    assert out.still_person[52:88, 59:71].all()  # the legs, in every cut
    assert not out.still_person[:, :50].any() and not out.still_person[:, 95:].any()


def test_a_person_rocking_on_their_legs_is_left_to_the_plate(monkeypatch):
    import vidcap.video.personbox as pb
    from vidcap.video.personbox import CUTS_MOVE, find_absorbed

    monkeypatch.setattr(pb, "IN_PLACE", True)
    monkeypatch.setattr(pb, "STILL_CORE", False)  # (its own test is below)
    frames, model, _ = _absorbed_scene(monkeypatch, [(40, 10, 100, 90)] * 8)
    _moving_cuts(monkeypatch, frames, shift_legs=True)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert reason == CUTS_MOVE and out is model


def test_a_part_found_inside_the_first_box_is_the_whole_person_again(monkeypatch):
    from vidcap.video.personbox import ABSORBED, find_absorbed

    # The whole person in the first sample, then only a head and a raised arm
    # (a dancer whose legs the plate holds): no box moved.
    whole, head = (40, 10, 100, 90), (55, 10, 85, 45)
    frames, model, cuts = _absorbed_scene(monkeypatch, [whole] + [head] * 7)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert reason == ABSORBED and set(cuts) == {whole}


def test_a_first_find_of_part_of_a_visible_blob_does_not_decide(monkeypatch):
    import vidcap.video.platepass as pp
    from vidcap.video.personbox import ABSORBED, find_absorbed

    # Sample 0: the first-pass silhouette shows a tall blob and the detector boxes
    # only its top (covered: the person would count as visible); every later sample
    # shows nothing where the whole person is boxed (absorbed).
    whole, head = (40, 10, 100, 90), (55, 10, 85, 40)
    frames, model, cuts = _absorbed_scene(monkeypatch, [head] + [whole] * 7)
    blob = np.zeros(frames.shape[1:3], np.uint8)
    blob[5:92, 45:95] = 1

    def person_masks(_model, fr, _gains):
        first = fr[:1].ctypes.data == frames[0].ctypes.data
        return np.stack([blob if first and len(fr) == 1 else np.zeros_like(blob)] * len(fr))

    monkeypatch.setattr(pp, "_person_masks", person_masks)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert reason == ABSORBED and cuts[0] == head and set(cuts[1:]) == {whole}


def test_a_person_in_a_small_frame_is_searched_for_enlarged(monkeypatch):
    """A walk rendered toward the camera at Weizmann's size (180x144, the body ~79 px
    tall, under the detector's 128-row window): found in some frames once the frame is
    enlarged to the searched height, in none at its own size."""
    import vidcap.video.personbox as pb
    from vidcap import synth

    rng = np.random.default_rng(0)
    frames, truth = synth.render_clip(synth.make_motion("walk", n_frames=30, rng=rng), rng=rng,
                                      yaw_deg=0, size=(180, 144), pixels_per_metre=45.0,
                                      noise=2.0)
    picks = range(0, 30, 3)

    def found_boxes():
        out = []
        for k in picks:
            boxes, _ = detect_people(frames[k])
            out += [(k, b) for b in boxes]
        return out

    enlarged = found_boxes()
    assert len({k for k, _ in enlarged}) >= 2
    for k, (x0, y0, x1, y1) in enlarged:  # round the figure, not elsewhere
        ys, xs = np.nonzero(truth["masks"][k])
        assert x0 <= xs.mean() <= x1 and y0 <= ys.mean() <= y1
    monkeypatch.setattr(pb, "ENLARGE_BELOW", 0)  # searched at the frame's own size
    assert found_boxes() == []


def test_a_side_on_person_is_found_by_the_second_detector():
    """A walk seen side-on at Weizmann's size: the default detector (trained on people
    facing or leaving the camera) finds nobody; the Daimler detector, trained on
    pedestrians crossing a street, boxes the figure in every look, and nothing on a
    blank frame."""
    from vidcap import synth

    rng = np.random.default_rng(0)
    frames, truth = synth.render_clip(synth.make_motion("walk", n_frames=30, rng=rng), rng=rng,
                                      yaw_deg=90, size=(180, 144), pixels_per_metre=45.0,
                                      noise=2.0)
    for k in range(0, 30, 3):
        assert len(detect_people(frames[k])[0]) == 0
        boxes, scores = detect_people(frames[k], detector="daimler")
        ys, xs = np.nonzero(truth["masks"][k])
        assert any(x0 <= xs.mean() <= x1 and y0 <= ys.mean() <= y1
                   for x0, y0, x1, y1 in boxes)
    boxes, _ = detect_people(np.full((144, 180, 3), 128, np.uint8), detector="daimler")
    assert boxes.shape == (0, 4)


def test_the_second_detector_searches_only_where_the_first_found_nobody(monkeypatch):
    import vidcap.video.personbox as pb
    from vidcap.video.personbox import ABSORBED, NOBODY, find_absorbed

    # A still person only the Daimler detector sees.
    boxes = [(50 + i % 2, 10, 90 + i % 2, 90 + i % 3) for i in range(8)]
    frames, model, cuts = _absorbed_scene(monkeypatch, boxes)
    asked, detect = [], pb.detect_people

    def only_daimler(frame, detector="default", **kw):
        asked.append(detector)
        if detector == "default":
            return np.zeros((0, 4), np.int64), np.zeros(0)
        return detect(frame, **kw)

    monkeypatch.setattr(pb, "detect_people", only_daimler)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert reason == ABSORBED and out.still_person is not None
    assert asked[:pb.GIVE_UP] == ["default"] * pb.GIVE_UP and asked[pb.GIVE_UP] == "daimler"
    monkeypatch.setattr(pb, "SECOND_DETECTOR", False)
    assert find_absorbed(model, frames, np.ones((8, 3)))[1] == NOBODY

    # Where the default detector finds the person, the second one never runs.
    asked.clear()
    monkeypatch.setattr(pb, "SECOND_DETECTOR", True)
    monkeypatch.setattr(pb, "detect_people", lambda frame, detector="default", **kw: (
        asked.append(detector) or detect(frame, **kw)))
    assert find_absorbed(model, frames, np.ones((8, 3)))[1] == ABSORBED
    assert set(asked) == {"default"}


def _swinging_legs(monkeypatch, frames):
    """A cut per sample i: a head and torso that stay over legs that swing 8 px a
    sample (a walk or jumping jacks on the spot, as the detector's grabCut sees it)."""
    import vidcap.video.personbox as pb

    def cut(frame, box, *_, **__):
        i = next(k for k in range(len(frames)) if frames[k].ctypes.data == frame.ctypes.data)
        dx = 8 * (i % 4) - 12
        out = np.zeros(frame.shape[:2], bool)
        out[12:50, 56:72] = True  # head and torso, the same in every sample
        out[50:90, 60 + dx:68 + dx] = True  # a swinging leg
        return out

    monkeypatch.setattr(pb, "cut_in_box", cut)


def test_a_still_torso_over_swinging_legs_is_absorbed(monkeypatch):
    import vidcap.video.personbox as pb
    from vidcap.video.personbox import ABSORBED, CUTS_MOVE, find_absorbed

    monkeypatch.setattr(pb, "STILL_CORE", False)
    frames, model, _ = _absorbed_scene(monkeypatch, [(40, 10, 100, 90)] * 8)
    _swinging_legs(monkeypatch, frames)
    assert find_absorbed(model, frames, np.ones((8, 3)))[1] == CUTS_MOVE
    monkeypatch.setattr(pb, "STILL_CORE", True)
    frames, model, _ = _absorbed_scene(monkeypatch, [(40, 10, 100, 90)] * 8)
    _swinging_legs(monkeypatch, frames)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert reason == ABSORBED
    assert out.still_person[14:48, 58:70].all()  # the torso, in every cut
    # a leg's place is the person in at most a quarter of the cuts: left to the plate
    assert not out.still_person[52:88, :56].any() and not out.still_person[:, 76:].any()


def test_cuts_that_share_too_little_are_a_person_moving_about(monkeypatch):
    import vidcap.video.personbox as pb
    from vidcap.video.personbox import CUTS_MOVE, find_absorbed

    monkeypatch.setattr(pb, "STILL_CORE", True)
    frames, model, _ = _absorbed_scene(monkeypatch, [(40, 10, 100, 90)] * 8)

    def cut(frame, box, *_, **__):  # the whole body 10 px further each sample
        i = next(k for k in range(len(frames)) if frames[k].ctypes.data == frame.ctypes.data)
        out = np.zeros(frame.shape[:2], bool)
        out[12:90, 40 + 10 * (i % 4):56 + 10 * (i % 4)] = True
        return out

    monkeypatch.setattr(pb, "cut_in_box", cut)
    out, reason = find_absorbed(model, frames, np.ones((8, 3)))
    assert reason == CUTS_MOVE and out is model


def test_scene_colours_swept_into_the_cuts_are_not_the_person():
    """A red torso the plate absorbed, blue legs that swing (the first-pass
    silhouette shows them) and a grey stand behind them, of the wall's grey: the
    cuts hold all three; the person's colours keep the torso and drop the stand."""
    from vidcap.video.personbox import _person_coloured
    from vidcap.video.platepass import _person_masks

    rng = np.random.default_rng(4)
    plate = rng.integers(95, 106, (96, 128, 3)).astype(np.uint8)  # a grey wall
    plate[12:50, 56:72] = (40, 40, 190)  # the absorbed torso
    plate[40:90, 76:90] = rng.integers(110, 121, (50, 14, 3))  # the stand, a lighter grey
    frames, cuts = [], []
    for i in range(6):
        frame = plate.copy()
        x = 56 + 4 * (i % 3)
        frame[50:90, x:x + 8] = (170, 60, 30)  # a blue leg, where the plate shows wall
        cut = np.zeros((96, 128), bool)
        cut[12:90, 56:90] = True  # grabCut swept the stand in with the person
        frames.append(frame)
        cuts.append(cut)
    model = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    frames, gains = np.stack(frames), np.ones((6, 3))
    seen = _person_masks(model, frames, gains) > 0  # the first pass: the legs
    assert seen[:, 50:90, 56:68].any() and not seen[:, :50].any()
    kept = _person_coloured(model, frames, gains, np.stack(cuts), seen)
    assert kept[16:46, 60:68].all()  # the torso: a colour the wall round it lacks
    assert kept[44:86, 79:87].mean() < 0.05  # the stand: the scene's colours
