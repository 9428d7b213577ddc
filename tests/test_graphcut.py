"""The graph cut over the silhouette's uncertain band (issue 26, vidcap/video/graphcut.py)."""

from __future__ import annotations

import numpy as np
import pytest

from vidcap.video.appearance import colour_model
from vidcap.video.graphcut import CutParams, cut_frame

RED = (40, 45, 190)
GREENS = ((60, 140, 70), (40, 100, 50))


def _scene(h=80, w=100, seed=0):
    """A textured background of two greens (checks of 4 pixels) with noise."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[:h, :w]
    check = ((yy // 4 + xx // 4) % 2 == 0)[..., None]
    img = np.where(check, GREENS[0], GREENS[1]).astype(np.float32)
    return np.clip(img + rng.normal(0, 2, img.shape), 0, 255)


def _models(scene, rng):
    person = np.clip(rng.normal(RED, 4, (400, 3)), 0, 255)
    return np.stack([colour_model(person, uniform=0.3), colour_model(scene.reshape(-1, 3))])


def _l1(frame, plate):
    return np.clip(np.abs(frame.astype(np.float32) - plate).sum(-1), 0, 255).astype(np.uint8)


def test_a_block_the_plate_absorbed_is_recovered_by_the_cut():
    rng = np.random.default_rng(1)
    scene = _scene()
    frame = scene.copy()
    body = np.zeros(scene.shape[:2], bool)
    body[20:60, 40:60] = True                      # a torso that never moved
    arm = np.zeros_like(body)
    arm[30:34, 60:85] = True                       # an arm that did
    frame[body | arm] = RED
    frame = np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8)
    # The plate absorbed the torso (its colour there) and flagged it never seen.
    plate = scene.copy()
    plate[body] = RED
    never = body.copy()
    tmap = np.full(body.shape, 30, np.uint8)
    l1 = _l1(frame, plate)
    fg = np.where(l1 > tmap, 255, 0).astype(np.uint8)
    assert (fg[body] > 0).mean() < 0.05            # the threshold misses the torso
    cp = CutParams.make(_models(scene, rng), never)
    out = cut_frame(frame, l1, tmap, fg, np.ones(3), cp) > 0
    truth = body | arm
    assert (out & truth).sum() / (out | truth).sum() > 0.95


def test_a_frame_whose_scene_has_the_persons_colour_keeps_the_plain_foreground(
        monkeypatch):
    """The same absorbed torso, but a strip of the scene round the person is the
    person's red (a wall the colour of skin): the colour models no longer tell scene
    from person there, so the frame keeps the thresholded foreground (SCENE_KEPT_MIN);
    without the gate the cut would decide it, and the trace says why."""
    import vidcap.video.graphcut as gc

    rng = np.random.default_rng(1)
    scene = _scene()
    scene[46:58, 66:95] = RED                      # red scene, seen in every frame
    frame = scene.copy()
    body = np.zeros(scene.shape[:2], bool)
    body[20:60, 40:60] = True
    arm = np.zeros_like(body)
    arm[30:34, 60:85] = True
    frame[body | arm] = RED
    frame = np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8)
    plate = scene.copy()
    plate[body] = RED
    tmap = np.full(body.shape, 30, np.uint8)
    l1 = _l1(frame, plate)
    fg = np.where(l1 > tmap, 255, 0).astype(np.uint8)
    models = _models(_scene(), rng)
    monkeypatch.setattr(gc, "TRACE", [])
    out = cut_frame(frame, l1, tmap, fg, np.ones(3), CutParams.make(models, body.copy()))
    np.testing.assert_array_equal(out, fg)
    kept = gc.TRACE[0][1]
    assert 0.5 < kept < gc.SCENE_KEPT_MIN           # the red strip: person by colour
    monkeypatch.setattr(gc, "SCENE_KEPT_MIN", 0.0)
    out = cut_frame(frame, l1, tmap, fg, np.ones(3), CutParams.make(models, body.copy()))
    assert (out[body] > 0).mean() > 0.9            # the cut ran: the torso filled in


def test_the_cut_does_not_spread_onto_a_textured_background_of_another_colour():
    rng = np.random.default_rng(2)
    scene = _scene(seed=3)
    frame = scene.copy()
    body = np.zeros(scene.shape[:2], bool)
    body[20:60, 40:60] = True
    frame[body] = RED
    frame = np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8)
    # A wrong guess in a wide never-seen area round the person (inpainted grey):
    # the threshold takes the whole area for foreground.
    never = np.zeros_like(body)
    never[10:70, 25:75] = True
    plate = scene.copy()
    plate[never] = (128, 128, 128)
    tmap = np.full(body.shape, 30, np.uint8)
    l1 = _l1(frame, plate)
    fg = np.where(l1 > tmap, 255, 0).astype(np.uint8)
    assert (fg[never & ~body] > 0).mean() > 0.9
    cp = CutParams.make(_models(scene, rng), never)
    out = cut_frame(frame, l1, tmap, fg, np.ones(3), cp) > 0
    assert (out & ~body).sum() < 0.03 * body.sum()
    assert (out & body).sum() > 0.97 * body.sum()


def test_an_empty_foreground_is_returned_unchanged():
    scene = _scene().astype(np.uint8)
    fg = np.zeros(scene.shape[:2], np.uint8)
    cp = CutParams.make(np.zeros((2, 4096), np.float32), fg > 0)
    out = cut_frame(scene, fg, fg + 30, fg, np.ones(3), cp)
    assert not out.any() and cp.prev is None


def test_the_plate_stage_learns_the_colours_and_the_cut_helps_an_in_place_clip():
    from tests.test_appearance import _in_place, _iou
    from vidcap.video.background import estimate_background
    from vidcap.video.silhouette import extract_silhouettes

    frames, masks = _in_place()
    bg = estimate_background(frames, rng=np.random.default_rng(0), colour_models=True)
    assert bg.colours is not None and bg.colours.shape == (2, 16 ** 3)
    red = (np.array(RED) * 16 // 256) @ (256, 16, 1)
    assert bg.colours[0, red] > bg.colours[1, red] + 2    # the torso's red is the person's
    plain = _iou(extract_silhouettes(frames, bg, progress=False).masks, masks)
    cut = _iou(extract_silhouettes(frames, bg, graph_cut=True, progress=False).masks, masks)
    # (the plate's retake of absorbed pixels, vidcap/video/absorbed.py, lifted the plain
    # worst frame 0.64 -> 0.76: the cut's margin there is 0.04 now)
    assert np.median(cut) >= np.median(plain) and cut.min() > plain.min() + 0.03


def test_the_cut_without_colour_models_is_refused_not_skipped():
    """A plate estimated without the colour models cannot feed the cut: asking for it
    says so instead of silently returning the plain silhouettes."""
    from tests.test_appearance import _in_place
    from vidcap.video.background import estimate_background
    from vidcap.video.silhouette import extract_silhouettes

    frames, _ = _in_place()
    bg = estimate_background(frames, rng=np.random.default_rng(0))
    assert bg.colours is None
    with pytest.raises(ValueError, match="colour_models=True"):
        extract_silhouettes(frames, bg, graph_cut=True, progress=False)


def test_the_stage_cache_keeps_the_colour_models_and_the_cut_is_used(tmp_path):
    """The pipeline's plate and silhouette stages with ``graph_cut``: the plate entry
    keeps the colour models (its own key: the plain entry stays), the silhouettes are
    the cut's (the torso the plate absorbed is recovered), and a second call reads
    both stages from the cache."""
    from tests.test_appearance import _in_place, _iou
    from vidcap.io.video import write_video
    from vidcap.video.annotations import Annotations
    from vidcap.video.pipeline import silhouettes_only

    frames, masks = _in_place()
    video = tmp_path / "still.mkv"
    write_video(video, frames, 25, crf=12)
    cache = tmp_path / "cache"
    said = []
    plain = silhouettes_only(video, Annotations(), cache_dir=cache, graph_cut=False)
    cut = silhouettes_only(video, Annotations(), cache_dir=cache, graph_cut=True,
                           log=said.append)
    assert not any("skipped" in m for m in said), said
    plates = sorted(cache.glob("plate-*.npz"))
    assert len(plates) == 2 and len(list(cache.glob("silhouettes-*.npz"))) == 2
    with_colours = [p for p in plates if "colours" in np.load(p).files]
    assert len(with_colours) == 1 and np.load(with_colours[0])["colours"].shape == (2, 4096)
    iou_plain, iou_cut = _iou(plain.masks[:], masks), _iou(cut.masks[:], masks)
    assert np.median(iou_cut) >= np.median(iou_plain) and iou_cut.min() > iou_plain.min()
    said.clear()
    again = silhouettes_only(video, Annotations(), cache_dir=cache, graph_cut=True,
                             log=said.append)
    assert not any("estimating" in m for m in said)
    np.testing.assert_array_equal(again.masks[:], cut.masks[:])


def test_convert_with_graph_cut_runs_the_cut_and_without_it_does_not(tmp_path, monkeypatch):
    """``run(graph_cut=True)`` (``vidcap convert --graph-cut``) asks the silhouette stage
    for the cut on a plate with colour models; ``graph_cut=False`` does not; a given
    plate falls back to the plain threshold with a notice."""
    import cv2

    from tests._synthframes import background, figure_mask
    from vidcap.io.video import write_video
    from vidcap.video import pipeline, silhouette

    rng = np.random.default_rng(3)
    h, w, n = 120, 160, 16
    bg = background(h, w, rng)
    frames = [np.where((figure_mask(h, w, 2 * np.pi * i / 12, cx=(0.3 + 0.4 * i / n) * w)
                        > 0)[..., None], np.uint8([40, 50, 160]), bg) for i in range(n)]
    video = tmp_path / "walk.mp4"
    write_video(video, frames, 12.0)
    asked = []
    real = silhouette.extract_silhouettes

    class Seen(Exception):
        pass

    def spy(source, plate, **kw):  # the stage's call, then stop (the fit is not under test)
        cut = real(source, plate, **kw)
        asked.append((kw.get("graph_cut", False), getattr(plate, "colours", None) is not None,
                      cut.masks[:].sum()))
        raise Seen

    monkeypatch.setattr(silhouette, "extract_silhouettes", spy)
    for flag in (True, False):
        with pytest.raises(Seen):
            pipeline.run(video, progress=False, graph_cut=flag, jobs=1)
    assert [a[:2] for a in asked] == [(True, True), (False, False)]
    assert asked[0][2] > 0.5 * asked[1][2]  # (the cut keeps the walker)
    plate = tmp_path / "plate.png"
    cv2.imwrite(str(plate), bg)
    said = []
    with pytest.raises(Seen):
        pipeline.run(video, progress=False, graph_cut=True, jobs=1, background=plate,
                     log=said.append)
    assert asked[-1][:2] == (False, False) and any("graph cut" in m for m in said)


def test_convert_command_flag_and_default_agree_with_the_pipeline():
    import argparse

    from vidcap.commands import convert as convert_cmd
    from vidcap.video import pipeline

    assert convert_cmd.DEFAULT_GRAPH_CUT == pipeline.DEFAULT_GRAPH_CUT
    ap = argparse.ArgumentParser()
    convert_cmd.add_arguments(ap)
    assert ap.parse_args(["v.mp4", "-o", "o.bvh", "--graph-cut"]).graph_cut is True
    assert ap.parse_args(["v.mp4", "-o", "o.bvh", "--no-graph-cut"]).graph_cut is False
    assert ap.parse_args(["v.mp4", "-o", "o.bvh"]).graph_cut is None  # the pipeline's default


def test_lost_share_counts_the_seen_part_of_the_plain_blob_the_cut_leaves_out():
    import cv2

    from vidcap.video.graphcut import _lost_share

    fg = np.zeros((40, 40), np.uint8)
    fg[10:20, 10:20] = 255
    plain = max(cv2.findContours(fg, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)[0],
                key=cv2.contourArea)
    cut = fg[5:35, 5:35].copy()                     # a crop at (5, 5)
    cut[5 + 4:5 + 5] = 0                            # the row y = 14 cut away ...
    never = np.zeros(cut.shape, bool)
    # ... leaving rows 15-19 (50 px) as the largest blob: rows 10-14 (50 of 100) lost
    assert _lost_share(plain, cut, never, (5, 5)) == pytest.approx(0.5)
    never[5:10] = True                              # rows 10-14 never seen: not counted
    assert _lost_share(plain, cut, never, (5, 5)) == pytest.approx(0.0)


def test_a_cut_that_breaks_the_person_in_two_keeps_the_plain_frame(monkeypatch):
    """A waist the scene's colour that differs from the plate by nothing (a shadow
    test's pixels): the cut takes it for the scene and splits the person; the larger
    half keeps under LOST_MAX of the plain blob, so the frame stays as thresholded."""
    import vidcap.video.graphcut as gc

    rng = np.random.default_rng(4)
    scene = _scene()
    frame = scene.copy()
    fgm = np.zeros(scene.shape[:2], bool)
    fgm[10:30, 40:60] = True                        # chest
    fgm[34:56, 40:60] = True                        # legs
    waist = np.zeros_like(fgm)
    waist[30:34, 48:52] = True                      # a narrow waist (in the band)
    frame[fgm] = RED
    frame[waist] = GREENS[0]
    frame = np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8)
    l1 = np.where(fgm, 200, 0).astype(np.uint8)     # the waist: no difference
    tmap = np.full(fgm.shape, 30, np.uint8)
    fg = np.where(fgm | waist, 255, 0).astype(np.uint8)
    never = np.zeros_like(fgm)
    models = _models(scene, rng)
    out = cut_frame(frame, l1, tmap, fg, np.ones(3), CutParams.make(models, never))
    np.testing.assert_array_equal(out, fg)
    monkeypatch.setattr(gc, "LOST_MAX", 1.0)        # without the guards: cut in two
    monkeypatch.setattr(gc, "KEEP_PIECES", False)
    out = cut_frame(frame, l1, tmap, fg, np.ones(3), CutParams.make(models, never))
    assert not out[waist].any() and out[fgm].mean() > 250


def test_an_interrupt_inside_a_compiled_kernel_comes_out_as_keyboard_interrupt():
    """Python reports a Ctrl-C handled while numba boxes a kernel's results as a
    SystemError caused by the KeyboardInterrupt; the cut raises the interrupt itself
    (vidcap.interrupt's exit 130), and other errors as they are."""
    from vidcap.video.graphcut import _compiled

    def interrupted():
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError("returned a result with an exception set") from exc

    def broken():
        raise SystemError("something else")

    with pytest.raises(KeyboardInterrupt):
        _compiled(interrupted)
    with pytest.raises(SystemError, match="something else"):
        _compiled(broken)
    assert _compiled(lambda a, b: a + b, 2, 3) == 5


def _head_on_a_neck():
    """A body (40 x 20) with a head (8 x 8) on a neck (2 rows x 4 columns) the colour of
    the scene that differs from the plate by nothing: (frame, l1, fg, body, neck, head)."""
    rng = np.random.default_rng(5)
    scene = _scene()
    frame = scene.copy()
    body = np.zeros(scene.shape[:2], bool)
    body[30:70, 40:60] = True
    head = np.zeros_like(body)
    head[20:28, 46:54] = True
    neck = np.zeros_like(body)
    neck[28:30, 48:52] = True
    frame[body | head] = RED
    frame[neck] = GREENS[0]
    frame = np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8)
    l1 = np.where(body | head, 200, 0).astype(np.uint8)
    fg = np.where(body | head | neck, 255, 0).astype(np.uint8)
    return frame, l1, fg, body, neck, head, _models(scene, rng)


def test_a_head_the_cut_splits_off_at_its_neck_is_reattached(monkeypatch):
    """The cut drops a neck the scene's colour (under LOST_MAX of the blob: the guard
    does not see it) and the head would be a blob of its own, which the silhouette
    stage leaves out; keep_pieces gives the neck back."""
    import cv2

    import vidcap.video.graphcut as gc

    frame, l1, fg, body, neck, head, models = _head_on_a_neck()
    tmap = np.full(fg.shape, 30, np.uint8)
    never = np.zeros(fg.shape, bool)
    monkeypatch.setattr(gc, "KEEP_PIECES", False)
    out = cut_frame(frame, l1, tmap, fg, np.ones(3), CutParams.make(models, never))
    assert not out[neck].any() and out[head].all()  # split off
    monkeypatch.setattr(gc, "KEEP_PIECES", True)
    out = cut_frame(frame, l1, tmap, fg, np.ones(3), CutParams.make(models, never))
    assert out[neck].all() and out[head].all() and out[body].all()
    assert cv2.connectedComponents(out, connectivity=8)[0] == 2  # one blob


def test_keep_pieces_gives_back_the_plain_pixels_near_a_split_off_piece_only():
    import cv2

    from vidcap.video.graphcut import keep_pieces

    plain = np.zeros((60, 60), np.uint8)
    plain[20:50, 20:40] = 255                        # body, 600 px
    plain[10:18, 26:34] = 255                        # head, 64 px
    plain[18:20, 28:32] = 255                        # neck
    plain[45:50, 40:52] = 255                        # a halo on the body's side
    blob = max(cv2.findContours(plain, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)[0],
               key=cv2.contourArea)
    cut = plain.copy()
    cut[18:20] = 0                                   # the neck dropped
    cut[45:50, 40:52] = 0                            # the halo trimmed (rightly)
    out = keep_pieces(cut.copy(), plain, blob, 3)
    assert (out[18:20, 28:32] == 255).all()          # the neck is back
    assert not out[45:50, 40:52].any()               # the body's trim is kept
    np.testing.assert_array_equal(out[:17], plain[:17])
    # a piece under PIECE_MIN of the blob (a one-pixel speck) is not a head: left alone
    speck = plain.copy()
    speck[10:18, 26:34] = 0
    speck[17, 30] = 255
    blob = max(cv2.findContours(speck, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)[0],
               key=cv2.contourArea)
    cut = speck.copy()
    cut[18:20] = 0
    np.testing.assert_array_equal(keep_pieces(cut.copy(), speck, blob, 3), cut)


def test_the_cuts_blobs_in_the_plain_person_stay_the_person_when_the_cut_widens_a_gap():
    """Torso and legs, two blobs a row apart, are joined as one person in the plain
    foreground (JOIN_GAP); the cut trims each by two rows and the gap grows past the
    join: the torso still counts, because it lies in the plain foreground's person."""
    from types import SimpleNamespace

    import cv2

    from vidcap.video.silhouette import _person_parts

    p = SimpleNamespace(fx=1.0, fy=1.0, min_area=16)
    plain = np.zeros((100, 60), np.uint8)
    plain[10:40, 20:40] = 255                        # torso
    plain[41:81, 20:40] = 255                        # legs, one row below
    cut = plain.copy()
    cut[38:43] = 0                                   # both trimmed: a 5-row gap
    contours, _ = cv2.findContours(cut, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    areas = np.array([cv2.contourArea(c) for c in contours])
    _, alone = _person_parts(contours, areas, None, cut, p)
    assert len(alone) == 1                           # the cut alone: legs only
    _, parts = _person_parts(contours, areas, None, cut, p, plain)
    assert sorted(parts) == [0, 1]
    # a blob of the cut's outside the plain person (a false blob nearby) is not taken
    cut[90:98, 20:40] = 255
    contours, _ = cv2.findContours(cut, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    areas = np.array([cv2.contourArea(c) for c in contours])
    _, parts = _person_parts(contours, areas, None, cut, p, plain)
    far = next(i for i, c in enumerate(contours) if c[:, 0, 1].min() >= 90)
    assert len(parts) == 2 and far not in parts
