"""The person by appearance where the plate is a guess (issue 26, vidcap/video/appearance.py)."""

from __future__ import annotations

import numpy as np

from tests._synthframes import clip
from vidcap.video.appearance import appearance_plate, colour_model, log_ratio
from vidcap.video.background import estimate_background
from vidcap.video.silhouette import extract_silhouettes

RED, SKIN = (40, 45, 190), (120, 160, 215)


def _iou(a, b):
    a, b = np.asarray(a, bool), np.asarray(b, bool)
    return (a & b).sum((1, 2)) / np.maximum((a | b).sum((1, 2)), 1)


def test_colour_models_tell_person_from_scene_and_allow_unseen_colours():
    rng = np.random.default_rng(0)
    person = np.clip(rng.normal(RED, 4, (500, 3)), 0, 255)
    scene = np.clip(rng.normal((120, 130, 125), 4, (500, 3)), 0, 255)
    p, b = colour_model(person, uniform=0.3), colour_model(scene)
    llr = log_ratio(np.array([RED, (120, 130, 125), (200, 30, 30)], np.float32), p, b)
    assert llr[0] > 3 and llr[1] < -3
    assert llr[2] > 0  # a colour neither model saw: unlike the scene, so person


def _in_place(n=30, h=120, w=160, seed=1, drift=0.0):
    """A static red torso with skin arms sweeping round it, over a striped scene;
    ``drift``: the exposure goes from 1 - drift to 1 + drift over the clip."""
    rng = np.random.default_rng(seed)
    xs = np.arange(w)
    scene = np.zeros((h, w, 3), np.float32)
    scene[:] = np.where((xs // 8 % 2 == 0)[None, :, None], (110, 120, 115), (150, 160, 150))
    frames, masks = [], []
    for t in range(n):
        f, m = scene.copy(), np.zeros((h, w), bool)
        m[40:90, 70:90] = True                      # the torso never moves
        f[m] = RED
        a = np.deg2rad(-60 + 120 * (0.5 + 0.5 * np.sin(2 * np.pi * t / 10)))
        for side in (-1, 1):                        # arms from the shoulders
            for s in np.linspace(0, 35, 60):
                x = int(80 + side * (10 + s * np.cos(a)))
                y = int(45 - s * np.sin(a))
                arm = np.zeros((h, w), bool)
                arm[max(0, y - 2):y + 3, max(0, x - 2):x + 3] = True
                f[arm & ~m] = RED if s < 15 else SKIN
                m |= arm
        gain = 1 - drift + 2 * drift * t / max(n - 1, 1)
        frames.append(np.clip(f * gain + rng.normal(0, 2, f.shape), 0, 255))
        masks.append(m)
    return np.array(frames, np.uint8), np.array(masks)


def test_a_torso_the_plate_absorbed_is_found_by_appearance(monkeypatch):
    frames, masks = _in_place()
    always = masks.all(axis=0)
    # Without the pass the plate keeps the torso (the arms alone differ from it).
    import vidcap.video.appearance as appearance

    with monkeypatch.context() as m:
        m.setattr(appearance, "appearance_plate", lambda model, *a, **k: model)
        plain = estimate_background(frames, n_samples=20)
    assert plain.never_seen[always].mean() < 0.1
    before = np.median(_iou(extract_silhouettes(frames, plain).masks, masks))
    bg = estimate_background(frames, n_samples=20)
    # Most of the torso is flagged never seen; little else is.
    assert bg.never_seen[always].mean() > 0.7
    assert (bg.never_seen & ~always).mean() < 0.01
    # The plate where the arms sweep is the scene.
    swept = masks.any(axis=0) & ~always & ~masks[0]
    err = np.abs(bg.plate.astype(int) - frames[0].astype(int)).sum(-1)
    assert np.median(err[swept]) < 20
    after = np.median(_iou(extract_silhouettes(frames, bg).masks, masks))
    assert before < 0.3 and after > 0.7


def test_a_walker_keeps_a_plate_that_saw_everything():
    rng = np.random.default_rng(2)
    frames, masks = clip(30, 120, 160, rng=rng, walk=True)
    bg = estimate_background(frames, n_samples=16)
    from vidcap.video.background import _frame_gains, sample_frames

    smp, _ = sample_frames(frames, n_samples=16)
    again = appearance_plate(bg, smp, _frame_gains(smp))
    assert again.never_seen.mean() <= bg.never_seen.mean() + 0.005
    sil = extract_silhouettes(frames, again)
    assert np.median(_iou(sil.masks, masks)) > 0.9


def test_the_absorbed_torso_is_found_under_exposure_drift():
    frames, masks = _in_place(drift=0.2)
    bg = estimate_background(frames, n_samples=20)
    always = masks.all(axis=0)
    assert bg.never_seen[always].mean() > 0.7
    assert (bg.never_seen & ~always).mean() < 0.01
    assert np.median(_iou(extract_silhouettes(frames, bg).masks, masks)) > 0.7


def test_a_static_block_beside_the_person_stays_scene(monkeypatch):
    """A still object of the person's colour beside the arms' sweep (a red door frame
    on pose2sim cam4) touches what moved and looks like the person, but lies beside
    it, not between moving parts: the plate keeps it and no silhouette takes it."""
    import vidcap.video.appearance as appearance

    frames, masks = _in_place()
    block = np.zeros(masks.shape[1:], bool)
    block[40:80, 128:138] = True  # right of the sweep (arms reach x <= 125)
    rng = np.random.default_rng(5)
    frames[:, block] = np.clip(np.array(RED) + rng.normal(0, 2, (len(frames), block.sum(), 3)),
                               0, 255).astype(np.uint8)
    always = masks.all(axis=0)

    def run():
        bg = estimate_background(frames, n_samples=20)
        sil = np.asarray(extract_silhouettes(frames, bg).masks, bool)
        return bg, sil[:, block].mean()

    with monkeypatch.context() as m:  # without the gate the block is taken for person
        m.setattr(appearance, "MIN_BETWEEN", 0.0)
        bg0, share0 = run()
    assert bg0.never_seen[block].mean() > 0.4 and share0 > 0.05  # (0.55, 0.11)
    bg, share = run()
    assert bg.never_seen[block].mean() < 0.02 and share < 0.01
    assert bg.never_seen[always].mean() > 0.7  # the absorbed torso is still found
    assert np.median(_iou(extract_silhouettes(frames, bg).masks, masks)) > 0.7


def test_between_moved_has_moved_parts_on_both_sides():
    from vidcap.video.appearance import between_moved

    m = np.zeros((7, 7), bool)
    m[3, 1] = m[3, 5] = True   # left and right of (3, 3)
    m[0, 6] = True             # alone in its row and column
    out = between_moved(m)
    assert out[3, 1:6].all() and not out[3, 0] and not out[3, 6]
    assert out[0, 6] and not out[0, 5] and not out[1, 6]


def test_a_still_part_unlike_the_scene_around_stays_person_when_colours_are_unsure(
        monkeypatch):
    """Inside the first plate's never-seen area, a sample's pixel the colour models
    call scene only by a little (a head whose skin is rare in the person's model and
    common in a brick wall far away) stays person when no seen plate pixel nearby has
    its colour; one that continues the scene around it does not."""
    from types import SimpleNamespace

    import vidcap.video.appearance as appearance

    monkeypatch.setattr(appearance, "NEVER_KEEP", 2.0)
    h, w, k = 40, 60, 3
    plate = np.zeros((h, w, 3), np.float32)
    plate[:, :30] = (120, 120, 120)
    plate[:, 30:] = (60, 140, 60)
    never = np.zeros((h, w), bool)
    never[10:30, 20:42] = True
    small = np.repeat(plate[None], k, axis=0)
    small[:, 10:30, 20:28] = SKIN              # like nothing around: person
    small[:, 10:30, 34:42] = (60, 140, 60)     # the green scene continued: scene
    llr = np.full((k, h, w), -1.0, np.float32)
    llr[:, 10:20, 20:28] = -3.0                # clearly scene by colour: scene
    llr[:, :, :5] = 1.0                        # outside: llr > 0 alone decides
    wk = SimpleNamespace(small=small, plate=plate, never=never,
                         lit=np.zeros((h, w), bool), ring_r=8, thr=12.0, h=h, w=w)
    person = appearance._keep_unlike(wk, llr)
    assert person[:, 20:30, 20:28].all()
    assert not person[:, 10:20, 20:28].any()
    assert not person[:, 10:30, 34:42].any()
    assert person[:, :, :5].all() and not person[:, :, 5:20].any()
    monkeypatch.setattr(appearance, "NEVER_KEEP", 0.0)
    assert not appearance._keep_unlike(wk, llr)[:, 10:30, 20:42].any()


def test_small_samples_are_the_resize_divide_and_clip_they_stand_for():
    """The passes' work images: area resize to the working size, divided by the gains,
    clipped, read only; a pass given them works on them, one given another size's
    makes its own."""
    import cv2

    from vidcap.video.appearance import _Work, small_samples
    from vidcap.video.background import BackgroundModel

    rng = np.random.default_rng(8)
    frames = rng.integers(0, 256, (4, 40, 30, 3), dtype=np.uint8)
    gains = rng.uniform(0.9, 1.1, (4, 3)).astype(np.float32)
    a = small_samples(frames, gains, 20)
    want = np.clip(np.stack([cv2.resize(f, (15, 20), interpolation=cv2.INTER_AREA)
                             for f in frames]).astype(np.float32)
                   / gains[:, None, None, :], 0, 255)
    assert np.array_equal(a, want) and not a.flags.writeable
    model = BackgroundModel.from_plate(np.full((40, 30, 3), 128, np.uint8), noise_sigma=1.0)
    assert _Work(model, frames, gains, 20, a).small is a
    other = _Work(model, frames, gains, 10, a).small
    assert other.shape == (4, 10, 8, 3) and other is not a


def test_the_plate_makes_the_small_samples_once(monkeypatch):
    """Every colour pass of one plate (appearance, absorbed, colour models, unseen
    flags) works on the one set of small samples the orchestration made."""
    from tests._synthframes import clip
    from vidcap.video import appearance
    from vidcap.video.background import estimate_background

    made = []
    real = appearance.small_samples

    def counted(*args, **kw):
        made.append(1)
        return real(*args, **kw)

    monkeypatch.setattr(appearance, "small_samples", counted)
    frames, _ = clip(30, 90, 120, rng=np.random.default_rng(9), walk=False)
    estimate_background(frames, n_samples=12, colour_models=True)
    assert len(made) == 1


def _fake_work(fg, colours, size=(60, 80), full=(60, 80)):
    """A :class:`vidcap.video.appearance._Work` stand-in: samples ``colours`` (K, h, w,
    3), what differed ``fg`` (K, h, w), a grey plate, nothing never seen."""
    import types

    import cv2

    h, w = size
    return types.SimpleNamespace(
        never=np.zeros((h, w), bool), disk=cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3)),
        d=np.where(fg, 100.0, 0.0), thr=10.0, fg=fg, small=colours.astype(np.float32),
        w=w, h=h, full=full)


def test_the_sure_person_keeps_two_frame_pixels_from_the_outline():
    """At a frame's own size (a 180x144 clip is worked at 180x144) the person's sure
    colours come from two pixels inside what differed, where the codec's blend of the
    outline with the scene (a dark skirting board beside dark jeans) is gone; a frame
    worked at half its size keeps its one working pixel (two frame pixels)."""
    from vidcap.video.appearance import _person_colours

    fg = np.zeros((3, 60, 80), bool)
    fg[:, 10:30, 20:40] = True                       # a 20x20 torso
    colours = np.zeros((3, 60, 80, 3))
    colours[fg] = RED
    inner = np.zeros_like(fg)
    inner[:, 12:28, 22:38] = True
    colours[fg & ~inner] = (35, 45, 70)              # its 2 px outline blended with the board
    board = np.all(_person_colours(_fake_work(fg, colours), 2) == (35, 45, 70), axis=1)
    assert len(board) == 3 * 16 * 16 and not board.any()
    one = _person_colours(_fake_work(fg, colours), 0)
    assert len(one) == 3 * 18 * 18 and np.all(one == (35, 45, 70), axis=1).sum() == 3 * 68
    # worked at half the frame's size: one working pixel is two frame pixels already
    half = _person_colours(_fake_work(fg, colours, full=(120, 160)), 2)
    assert len(half) == 3 * 18 * 18


def test_a_person_shown_by_thin_limbs_keeps_the_one_pixel_margin():
    """Arms waving over a body the plate absorbed: a two-pixel margin would erase the
    4-px-wide arms, so the one-pixel margin's colours are used."""
    from vidcap.video.appearance import _person_colours

    fg = np.zeros((3, 60, 80), bool)
    fg[:, 10:14, 5:75] = True                        # a 4-px arm across the frame
    colours = np.zeros((3, 60, 80, 3))
    colours[fg] = SKIN
    got = _person_colours(_fake_work(fg, colours), 2)
    assert got is not None and len(got) == 3 * 2 * 68   # the 3x3 erosion's 2 rows
