"""Silhouette extraction (seed 004 section 3.1.3) and normalisation (section 4.2)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from tests._synthframes import background, clip
from vidcap.video.background import BackgroundModel, estimate_background
from vidcap.video.silhouette import NoPersonError, extract_silhouettes, is_monochrome


def _iou(a, b):
    return (a & b).sum((1, 2)) / np.maximum((a | b).sum((1, 2)), 1)


@pytest.fixture(scope="module")
def walker():
    return clip(40, 120, 160, rng=np.random.default_rng(11), walk=True)


def test_walker_silhouettes_match_truth(walker):
    frames, masks = walker
    bg = estimate_background(frames, n_samples=20)
    sil = extract_silhouettes(frames, bg)
    iou = _iou(sil.masks, masks)
    assert np.median(iou) > 0.9 and iou.min() > 0.7
    assert sil.masks.shape == masks.shape and sil.masks.dtype == bool
    assert sil.found.all() and (sil.n_other_blobs == 0).all()
    # bbox: x0, y0, x1, y1 with exclusive ends, and heights from it
    for m, (x0, y0, x1, y1) in zip(sil.masks, sil.bbox, strict=True):
        ys, xs = np.nonzero(m)
        assert (x0, y0, x1, y1) == (xs.min(), ys.min(), xs.max() + 1, ys.max() + 1)
    assert (sil.heights == sil.bbox[:, 3] - sil.bbox[:, 1]).all()
    assert (sil.areas == sil.masks.sum((1, 2))).all()


def test_lighting_drift_and_chunks(walker):
    frames, masks = clip(40, 120, 160, rng=np.random.default_rng(12), walk=True, drift=0.25)
    bg = estimate_background(frames, n_samples=20)
    sil = extract_silhouettes(frames, bg, chunk_size=7)
    assert np.median(_iou(sil.masks, masks)) > 0.9
    # the measured gains follow the drift (0.75 -> 1.25 about the median light)
    assert sil.gains[-1].mean() / sil.gains[0].mean() == pytest.approx(1.25 / 0.75, rel=0.05)


def test_threshold_override_and_shadows():
    rng = np.random.default_rng(13)
    plate = background(80, 100, rng)
    frame = plate.copy()
    frame[20:60, 40:55] = (30, 200, 30)                                # a person
    frame[60:70, 55:90] = (plate[60:70, 55:90] * 0.7).astype(np.uint8)  # its shadow
    bg = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    sil = extract_silhouettes(frame[None], bg)
    assert sil.masks[0, 20:60, 40:55].mean() > 0.98  # a 3x3 median rounds corners
    assert not sil.masks[0, 62:68, 60:88].any()                       # shadow dropped
    keep = extract_silhouettes(frame[None], bg, shadows=False)
    assert keep.masks[0, 62:68, 60:88].mean() > 0.9
    # an absurd threshold finds nobody
    with pytest.raises(NoPersonError):
        extract_silhouettes(frame[None], bg, threshold=700)
    assert extract_silhouettes(frame[None], bg, threshold=700, require_person=False).found[0] \
        == np.False_



def test_soft_shade_on_a_lit_wall_is_dropped_dark_clothes_are_kept():
    """A body darkens a bright wall around it by a few per cent with the wall's colour
    kept but a little chroma noise (real walk past a white wall: 3-24 % darker); that shade
    is not the person. Dark grey clothes of the wall's hue (60 % darker) are."""
    rng = np.random.default_rng(17)
    plate = np.clip(rng.normal((200, 205, 210), 1.5, (90, 120, 3)), 0, 255).astype(np.uint8)
    frame = plate.astype(np.float32)
    frame[10:80, 50:70] = plate[10:80, 50:70] * 0.4         # dark clothes, the wall's hue
    halo = np.zeros((90, 120), bool)
    halo[5:85, 35:85] = True
    halo[10:80, 50:70] = False
    frame[halo] = plate[halo] * 0.95 + rng.normal(0, 2.0, (halo.sum(), 3))  # the shade
    frame = np.clip(frame, 0, 255).astype(np.uint8)
    bg = BackgroundModel.from_plate(plate, noise_sigma=1.5)
    sil = extract_silhouettes(frame[None], bg)
    assert sil.masks[0, 12:78, 52:68].mean() > 0.98
    assert sil.masks[0][halo].mean() < 0.15
    assert extract_silhouettes(frame[None], bg, shadows=False).masks[0][halo].mean() > 0.8


def test_grey_video_keeps_a_person_darker_than_the_background():
    """In grey video every pixel has the plate's (absent) colour, so the shadow test
    would cut out a person 5-40 % darker than the background; it is off there."""
    rng = np.random.default_rng(14)
    plate = cv2.cvtColor(cv2.cvtColor(background(80, 100, rng), cv2.COLOR_BGR2GRAY),
                         cv2.COLOR_GRAY2BGR)
    frame = plate.copy()
    frame[20:60, 40:55] = (plate[20:60, 40:55] * 0.75).astype(np.uint8)  # grey clothes
    assert is_monochrome(frame[None]) and not is_monochrome(background(80, 100, rng)[None])
    bg = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    sil = extract_silhouettes(frame[None], bg)
    assert sil.masks[0, 22:58, 42:53].mean() > 0.98
    # the same darkening in a colour video is a shadow (the test above), and still dropped
    colour = background(80, 100, rng)
    shade = colour.copy()
    shade[20:60, 40:55] = (colour[20:60, 40:55] * 0.75).astype(np.uint8)
    shade[10:70, 70:85] = (30, 200, 30)  # a person, so there is a blob to keep
    colour_bg = BackgroundModel.from_plate(colour, noise_sigma=2.0)
    sil = extract_silhouettes(shade[None], colour_bg)
    assert sil.masks[0, 22:58, 42:53].mean() < 0.1
    # ... also when the video opens on black frames (a fade-in): the plate decides
    black = np.zeros_like(colour)
    sil = extract_silhouettes(np.stack([black] * 8 + [shade]), colour_bg,
                              require_person=False)
    assert sil.masks[8, 22:58, 42:53].mean() < 0.1


def test_frame_with_only_noise_specks_has_no_person():
    """Specks above the threshold that the 3x3 median removes leave an empty frame
    (the person has not entered yet): no person found, no error."""
    rng = np.random.default_rng(15)
    plate = background(80, 100, rng)
    frames = np.stack([plate] * 3)
    frames[0, 10, 10] = 255 - plate[10, 10]  # isolated single pixels
    frames[0, 50, 70] = 255 - plate[50, 70]
    frames[2, 20:60, 40:55] = (30, 200, 30)  # then the person
    sil = extract_silhouettes(frames, BackgroundModel.from_plate(plate, noise_sigma=2.0))
    assert sil.foreground_fraction[0] > 0  # the specks were above the threshold
    assert sil.found.tolist() == [False, False, True] and not sil.masks[0].any()

def test_holes_filled_largest_blob_kept_others_reported():
    plate = np.full((100, 120, 3), 128, np.uint8)
    frame = plate.copy()
    frame[10:90, 20:50] = 20           # the person ...
    frame[40:50, 30:40] = 128          # ... with a hole (same colour as the background)
    frame[30:70, 80:100] = 230         # another, smaller person
    frame[5, 5] = 0                    # a speck
    bg = BackgroundModel.from_plate(plate, noise_sigma=1.0)
    sil = extract_silhouettes(frame[None], bg)
    assert sil.masks[0, 11:89, 21:49].all()
    assert not sil.masks[0, 30:70, 80:100].any() and not sil.masks[0, 5, 5]
    assert sil.n_other_blobs[0] == 1 and sil.max_people == 2
    f, x0, y0, x1, y1, _area = sil.others[0]
    assert (f, x0, y0, x1, y1) == (0, 80, 30, 100, 70)



def test_the_person_is_followed_not_the_largest_blob():
    """Two figures of about the same size: the one taken in the first frame is kept
    while their areas trade places every frame; one twice as large takes over."""
    rng = np.random.default_rng(16)
    plate = background(160, 200, rng)
    frames, a_boxes = [], []
    for k in range(12):
        f = plate.copy()
        ha, hb = (62, 58) if k % 2 == 0 else (58, 62)  # the larger one alternates
        if k >= 9:
            hb = 2 * ha + 10  # B comes much closer (taller, same width x 2)
        f[20:20 + ha, 30 + 2 * k:45 + 2 * k] = (30, 200, 30)  # A, walking right
        f[150 - hb:150, 140 - 2 * k:155 - 2 * k + (15 if k >= 9 else 0)] = (200, 30, 30)
        frames.append(f)
        a_boxes.append((30 + 2 * k, 20, 45 + 2 * k, 20 + ha))
    sil = extract_silhouettes(np.stack(frames), BackgroundModel.from_plate(plate,
                                                                           noise_sigma=2.0))
    on_a = [abs(int(sil.bbox[k, 0]) - a_boxes[k][0]) <= 2 for k in range(12)]
    assert on_a == [True] * 9 + [False] * 3
    assert (sil.n_other_blobs == 1).all()  # the other figure is still reported

def test_given_plate_measures_its_own_threshold():
    rng = np.random.default_rng(14)
    plate = background(80, 100, rng)
    frames = np.clip(plate[None] + rng.normal(0, 3, (5, 80, 100, 3)), 0, 255).astype(np.uint8)
    frames[:, 20:60, 40:55] = (30, 200, 30)
    sil = extract_silhouettes(frames, BackgroundModel.from_plate(plate))
    assert 12 <= sil.threshold < 60
    assert _iou(sil.masks, np.broadcast_to(
        np.pad(np.ones((40, 15), bool), ((20, 20), (40, 45))), sil.masks.shape)).min() > 0.95


def test_size_mismatch_is_an_error():
    bg = BackgroundModel.from_plate(np.zeros((10, 10, 3), np.uint8), noise_sigma=1)
    with pytest.raises(Exception, match="10x10"):
        extract_silhouettes(np.zeros((2, 12, 10, 3), np.uint8), bg)


def test_half_resolution_work_scale_keeps_the_outline():
    """At work_scale 2 the outline is refined at full resolution: the masks agree
    with the full-resolution ones and with the truth to within a few edge pixels."""
    frames, masks = clip(12, 240, 320, rng=np.random.default_rng(31), walk=True)
    bg = estimate_background(frames, n_samples=12)
    full = extract_silhouettes(frames, bg, work_scale=1)
    half = extract_silhouettes(frames, bg, work_scale=2)
    assert half.masks.shape == masks.shape
    iou_half = (half.masks & masks).sum((1, 2)) / (half.masks | masks).sum((1, 2))
    iou_full = (full.masks & masks).sum((1, 2)) / (full.masks | masks).sum((1, 2))
    assert np.median(iou_half) > 0.95
    assert np.median(iou_half) > np.median(iou_full) - 0.02
    assert np.abs(half.bbox - full.bbox).max() <= 2
    assert (half.found == full.found).all()


def test_blurred_outline_is_decided_by_the_persons_own_contrast():
    """A soft edge (antialiasing, codec blur) is a band of mixtures: the noise
    threshold alone keeps mixtures with a few per cent of person (a fat mask);
    the contrast test keeps the pixels at least ``edge_fraction`` person."""
    rng = np.random.default_rng(5)
    h, w = 120, 160
    plate = np.full((h, w, 3), (150, 170, 140), np.uint8)
    yy, xx = np.mgrid[:h, :w]
    cover = ((np.abs(xx - 80) < 18) & (np.abs(yy - 60) < 40)).astype(np.float32)
    # Gaussian blur of the hard edge: coverage falls from 1 to 0 over ~6 px.
    soft = cv2.GaussianBlur(cover, (0, 0), 1.5)
    person = np.array([40, 40, 200], np.float32)
    frames = []
    for _ in range(4):
        f = soft[..., None] * person + (1 - soft[..., None]) * plate
        f += rng.normal(0, 2.0, f.shape)
        frames.append(np.clip(np.round(f), 0, 255).astype(np.uint8))
    frames = np.stack(frames)
    bg = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    half = (soft >= 0.5)[None].repeat(len(frames), 0)
    plain = extract_silhouettes(frames, bg, edge_band=0)
    ours = extract_silhouettes(frames, bg, edge_fraction=0.5)
    # The plain test keeps faint mixtures: wider than the half-coverage outline.
    assert (plain.areas > 1.1 * half.sum((1, 2))).all()
    assert np.median(_iou(ours.masks, half)) > 0.97
    assert np.median(_iou(ours.masks, half)) > np.median(_iou(plain.masks, half)) + 0.05
    # A lower share keeps more of the band, never less than the half test.
    low = extract_silhouettes(frames, bg, edge_fraction=0.2)
    assert (low.areas >= ours.areas).all() and (low.areas <= plain.areas).all()


def test_a_person_cut_in_two_by_a_plate_error_stays_whole():
    """A band of the person the plate absorbed (a leg's colour where it stands most)
    splits torso and legs into two blobs of similar size: both are the person (a gap
    under a twentieth of the height), also when the previous frame's box covers only
    the legs; a blob further away is not."""
    from vidcap.video.silhouette import _params_for, silhouette_frame

    plate = np.full((200, 160, 3), 128, np.uint8)
    frame = plate.copy()
    frame[10:90, 60:90] = (30, 30, 200)    # torso, 80 rows
    frame[90:93, 60:90] = 128              # the absorbed band: a 3-pixel gap
    frame[93:180, 64:86] = (200, 60, 30)   # legs
    frame[60:100, 120:135] = (30, 200, 30)  # something else, 34 px away
    bg = BackgroundModel.from_plate(plate, noise_sigma=1.0)
    p = _params_for(bg, frame[None], None, 3.0, True, None, 0.2, None)
    for prev in (None, np.array([64, 93, 86, 180])):
        r, _ = silhouette_frame(frame, p, prev)
        assert r.mask[12:88, 62:88].all() and r.mask[95:178, 66:84].all()
        assert not r.mask[60:100, 120:135].any()
        assert len(r.others) == 1


def test_a_frame_noisier_than_the_plate_raises_its_own_threshold(monkeypatch):
    """A stretch of heavier noise (compression, a darker scene) than the plate's samples
    saw: the frame's own difference sets its floor, so the specks do not join the
    person; the plate's threshold alone takes a band of them round the body."""
    import vidcap.video.silhouette as sil_mod

    rng = np.random.default_rng(7)
    plate = background(120, 160, rng)
    truth = np.zeros((120, 160), bool)
    truth[20:100, 60:90] = True

    def frame(sigma):
        f = plate.astype(np.float32) + rng.normal(0, sigma, plate.shape)
        f[truth] = (40, 180, 60)
        return np.clip(f, 0, 255).astype(np.uint8)

    frames = np.stack([frame(1.0), frame(9.0)])
    bg = BackgroundModel.from_plate(plate, noise_sigma=1.0)

    def ious():
        masks = extract_silhouettes(frames, bg).masks
        return [float((m & truth).sum() / (m | truth).sum()) for m in masks]

    clean, noisy = ious()
    assert clean > 0.97 and noisy > 0.9
    monkeypatch.setattr(sil_mod, "FRAME_RAISE", None)
    clean_off, noisy_off = ious()
    assert clean_off == pytest.approx(clean)  # a clean frame is left as it was
    assert noisy_off < noisy - 0.1


def _board_scene(seed, board):
    """A person (truth rows 50-109, columns 20-39) and a whiteboard (rows 10-59,
    columns 90-149) whose plate is ``board`` (a level or an array); the exposure drops
    to 0.8 but the board keeps its level: frame 0, and frame 1 with something darker in
    front of the board. Returns frames (2, H, W, 3), the plate's model, the truth."""
    rng = np.random.default_rng(seed)
    plate = background(120, 160, rng)
    plate[10:60, 90:150] = board
    truth = np.zeros((120, 160), bool)
    truth[50:110, 20:40] = True
    f = plate.astype(np.float32) * 0.8 + rng.normal(0, 1.0, plate.shape)
    f[10:60, 90:150] = np.minimum(plate[10:60, 90:150], 250) + rng.normal(0, 1.0,
                                                                           (50, 60, 3))
    f[truth] = (40, 60, 160)
    frame = np.clip(f, 0, 255).astype(np.uint8)
    board_dark = frame.copy()
    board_dark[15:45, 100:120] = (40, 60, 160)
    return np.stack([frame, board_dark]), BackgroundModel.from_plate(plate, noise_sigma=1.0), truth


def _ious(masks, truth):
    return [float((m & truth).sum() / (m | truth).sum()) for m in masks]


def test_a_clipped_highlight_that_keeps_its_level_is_not_the_person(monkeypatch):
    """The exposure drops to 0.8 but a whiteboard at the clip level (plate 255) stays
    at 250: scaled by the frame's gain the plate says 204 there. Compared one-sided
    (only darker counts at clipped plate channels), the board is scene and the person
    is found; compared both ways the board, larger than the person, is taken."""
    import vidcap.video.silhouette as sil_mod

    frames, bg, truth = _board_scene(21, 255)
    sil = extract_silhouettes(frames, bg)
    assert min(_ious(sil.masks, truth)) > 0.95
    assert sil.n_other_blobs[1] == 1  # the dark patch on the board still differs
    monkeypatch.setattr(sil_mod, "SATURATED", None)
    monkeypatch.setattr(sil_mod, "HIGHLIGHT", None)
    assert max(_ious(extract_silhouettes(frames, bg).masks, truth)) < 0.3


def test_a_highlight_under_the_clip_level_that_keeps_its_level_is_not_the_person(
        monkeypatch):
    """A whiteboard at 243-247 in the plate (highlights, not clipped): the exposure
    drops to 0.8 and the board keeps its level, ~45 levels a channel above the scaled
    plate. Between the plate and the scaled plate (:data:`HIGHLIGHT`) it is scene, and
    the person is found; something darker in front of it still differs; compared
    both ways (off) the board, larger than the person, is taken."""
    import vidcap.video.silhouette as sil_mod

    board = np.random.default_rng(0).integers(243, 248, (50, 60, 3))
    frames, bg, truth = _board_scene(22, board)
    assert (bg.plate[10:60, 90:150] < sil_mod.SATURATED).all()
    sil = extract_silhouettes(frames, bg)
    assert min(_ious(sil.masks, truth)) > 0.95
    assert sil.n_other_blobs[1] == 1
    monkeypatch.setattr(sil_mod, "HIGHLIGHT", None)
    assert max(_ious(extract_silhouettes(frames, bg).masks, truth)) < 0.3
