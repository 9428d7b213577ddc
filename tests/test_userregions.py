"""The user's regions (scene_region, person_box) in the silhouette stage, its cache key,
and the refit of the frames they change."""

import json
import shutil

import numpy as np
import pytest

from tests._synthframes import background
from tests.conftest import REPO
from vidcap.video.annotations import Annotations
from vidcap.video.background import BackgroundModel
from vidcap.video.masks import MaskStack
from vidcap.video.refit import changed_frames, refit_changed, refit_windows
from vidcap.video.silhouette import extract_silhouettes
from vidcap.video.userregions import UserRegions, region_cache_part

WALK = REPO / "sample_videos" / "walk_side.mp4"


def _lamp_clip(n=10):
    """A person (a bobbing block) with a static bright lamp *larger* than them, apart:
    frames (n, 120, 160, 3), the true masks, the lamp's box."""
    rng = np.random.default_rng(3)
    plate = background(120, 160, rng)
    frames, truth = [], []
    for k in range(n):
        f = plate.copy()
        m = np.zeros((120, 160), bool)
        m[30 + k % 3:90 + k % 3, 30 + 2 * k:44 + 2 * k] = True  # the person, walking right
        f[m] = (30, 200, 30)
        f[20:110, 100:150] = (250, 250, 250)  # the lamp: in no plate, in every frame
        frames.append(f)
        truth.append(m)
    return np.stack(frames), np.stack(truth), plate, (100, 20, 150, 110)


def test_scene_region_removes_a_static_block_and_the_person_is_chosen():
    frames, truth, plate, lamp = _lamp_clip()
    bg = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    auto = extract_silhouettes(frames, bg)
    assert np.asarray(auto.masks)[:, 20:110, 100:150].any()  # the lamp taken as the person
    ann = Annotations()
    ann.add_scene_region(3, box=lamp)
    sil = extract_silhouettes(frames, bg, regions=UserRegions(ann, plate.shape[:2]))
    got = np.asarray(sil.masks)
    assert not got[:, 20:110, 100:150].any()  # in no frame
    assert ((got != truth).sum(axis=(1, 2)) <= 4).all()  # (the median rounds 4 corners)
    assert (sil.n_other_blobs == 0).all()  # nor counted as another person


def test_scene_polygon_and_half_resolution_work():
    frames, truth, plate, (x0, y0, x1, y1) = _lamp_clip(4)
    frames = np.repeat(np.repeat(frames, 4, axis=1), 4, axis=2)  # 480x640: worked at half
    truth = np.repeat(np.repeat(truth, 4, axis=1), 4, axis=2)
    plate = np.repeat(np.repeat(plate, 4, axis=0), 4, axis=1)
    ann = Annotations()
    # the lamp as a drawn outline (a polygon a little larger than the lamp)
    ann.add_scene_region(0, polygon=[(4 * x0 - 3, 4 * y0 - 3), (4 * x1 + 3, 4 * y0 - 3),
                                     (4 * x1 + 3, 4 * y1 + 3), (4 * x0 - 3, 4 * y1 + 3)])
    sil = extract_silhouettes(frames, BackgroundModel.from_plate(plate, noise_sigma=2.0),
                              regions=UserRegions(ann, plate.shape[:2]))
    got = np.asarray(sil.masks)
    assert not got[:, 4 * y0:4 * y1, 4 * x0:4 * x1].any()
    inter = (got & truth).sum(axis=(1, 2))
    union = (got | truth).sum(axis=(1, 2))
    assert (inter / union).min() > 0.95


def test_person_box_picks_the_other_blob_from_its_frame_on():
    """Two walkers: the first frame's larger one (A) is followed; a person box around
    B at frame 4 makes B the person from frame 4 on, and nothing outside the box is
    kept in frame 4."""
    rng = np.random.default_rng(16)
    plate = background(120, 200, rng)
    frames = []
    for k in range(10):
        f = plate.copy()
        f[20:84, 30 + 2 * k:45 + 2 * k] = (30, 200, 30)  # A, walking right
        f[40:100, 140 - 2 * k:154 - 2 * k] = (200, 30, 30)  # B, smaller, walking left
        frames.append(f)
    frames = np.stack(frames)
    bg = BackgroundModel.from_plate(plate, noise_sigma=2.0)
    auto = extract_silhouettes(frames, bg)
    assert (auto.bbox[:, 0] < 100).all()  # A throughout
    ann = Annotations()
    ann.add_person_box(4, (120, 30, 160, 110))
    sil = extract_silhouettes(frames, bg, regions=UserRegions(ann, plate.shape[:2]))
    x0 = sil.bbox[:, 0]
    assert (x0[:4] < 100).all() and (x0[4:] > 100).all()
    assert [int(v) for v in sil.bbox[4]] == [132, 40, 146, 100]
    assert not np.asarray(sil.masks[4])[:, :120].any()


def test_keep_masks_at_work_scale_cover_any_allowed_pixel():
    ann = Annotations()
    ann.add_scene_region(0, box=(0, 0, 5, 8))  # odd edge: work pixel 2 is half allowed
    r = UserRegions(ann, (8, 8))
    work, full = r.keep_masks(0, (4, 4))
    assert work.dtype == np.uint8 and set(np.unique(work)) == {0, 255}
    assert (work[:, :2] == 0).all() and (work[:, 2:] == 255).all()
    assert full[:, 5:].all() and not full[:, :5].any()
    assert r.keep_masks(0, (4, 4))[0] is work  # the scene mask is made once
    assert UserRegions(Annotations(), (8, 8)).keep_masks(0, None) is None
    assert not UserRegions(Annotations(), (8, 8))


def test_cache_part_only_regions():
    a = Annotations()
    a.add_orientation(0, "left")
    a.add_depth(3, "head", "toward")
    assert region_cache_part(a) == [] and region_cache_part(None) == []
    a.add_person_box(2, (1, 2, 3, 4))
    assert region_cache_part(a) == [{"frame": 2, "type": "person_box", "box": [1, 2, 3, 4]}]
    b = Annotations()
    b.add_scene_region(7, box=(1, 2, 3, 4))
    c = Annotations()
    c.add_scene_region(0, box=(1, 2, 3, 4))  # drawn on another frame: the same pixels
    assert region_cache_part(b) == region_cache_part(c) != region_cache_part(a)


@pytest.fixture(scope="module")
def walk_copy(tmp_path_factory):
    if not WALK.exists():
        pytest.skip("sample_videos/ not present")
    d = tmp_path_factory.mktemp("walk")
    shutil.copy(WALK, d / "clip.mp4")
    return d / "clip.mp4"


def _head_half(bbox):
    x0, y0, x1, y1 = (int(v) for v in bbox)
    return x0, y0, x1, (y0 + y1) // 2


def test_silhouette_cache_is_keyed_by_regions_only(walk_copy, tmp_path):
    from vidcap.video.pipeline import silhouettes_only

    cache = tmp_path / "cache"  # its own: the entries counted are this test's only
    entries = lambda: sorted(p.name for p in cache.glob("silhouettes-*.npz"))  # noqa: E731
    a = Annotations()
    plain = silhouettes_only(walk_copy, a, cache_dir=cache)
    first = entries()
    assert len(first) == 1
    a.add_orientation(0, "left")
    a.add_depth(3, "head", "toward")
    a.add_joint(4, "l_wrist", 10, 20)
    silhouettes_only(walk_copy, a, cache_dir=cache)
    assert entries() == first  # other events: the same entry
    # a box over the person's upper body in frames 0-2 (where the walk starts)
    x0, y0, x1, _ = (int(v) for v in plain.bbox[1])
    a.add_scene_region(1, box=_head_half(plain.bbox[1]))
    calls = []
    cut = silhouettes_only(walk_copy, a, cache_dir=cache,
                           on_masks=lambda start, m: calls.append((start, len(m))))
    assert len(entries()) == 2 and calls and calls[0][0] == 0
    old, new = np.asarray(plain.masks), np.asarray(cut.masks)
    x0, y0, x1, y1 = _head_half(plain.bbox[1])
    assert not new[:, y0:y1, x0:x1].any()
    assert old[1, y0:y1, x0:x1].any()
    assert changed_frames(plain.masks, cut.masks)[1]
    again = silhouettes_only(walk_copy, a, cache_dir=cache, on_masks=lambda *_: calls.append(0))
    assert len(entries()) == 2 and calls[-1] != 0  # a cache hit: no chunk extracted
    assert not changed_frames(cut.masks, again.masks).any()


def test_convert_honours_the_region_and_reuses_its_silhouettes(walk_copy, tmp_path):
    """The whole pipeline (as ``vidcap convert``) with a region over the person's upper
    body: the silhouettes come from the cache entry made for that region (drawn on another
    frame: the same pixels, the same entry), and hold none of its pixels."""
    from vidcap.video import pipeline

    cache = tmp_path / "cache"  # its own, filled here: no other test's entries needed
    plain = pipeline.silhouettes_only(walk_copy, Annotations(), cache_dir=cache)
    drawn = Annotations()
    drawn.add_scene_region(1, box=_head_half(plain.bbox[1]))
    pipeline.silhouettes_only(walk_copy, drawn, cache_dir=cache)
    before = sorted(cache.glob("silhouettes-*.npz"))
    a = Annotations()
    a.add_scene_region(0, box=_head_half(plain.bbox[1]))
    a.add_orientation(0, "right")
    res = pipeline.run(walk_copy, annotations=a, cache_dir=cache, jobs=1)
    assert sorted(cache.glob("silhouettes-*.npz")) == before and len(before) == 2
    x0, y0, x1, y1 = _head_half(plain.bbox[1])
    assert not np.asarray(res.masks)[:, y0:y1, x0:x1].any()
    assert np.isfinite(res.image_joints2d[1]).all()


def test_region_beyond_the_frame_is_one_line_naming_the_file(walk_copy, tmp_path, capsys):
    from vidcap.cli import main

    ann = walk_copy.with_name("clip.vidcap.json")
    ann.write_text(json.dumps({"version": 1, "events": [
        {"frame": 0, "type": "scene_region", "box": [400, 0, 481, 50]}]}))
    out = tmp_path / "o.bvh"
    try:
        code = main(["convert", str(walk_copy), "-o", str(out), "--no-cache"])
    finally:
        ann.unlink()
    err = capsys.readouterr().err
    assert code == 2, err
    lines = [ln for ln in err.splitlines() if ln.startswith("vidcap: error:")]
    assert len(lines) == 1
    assert "clip.vidcap.json" in lines[0] and "480x360" in lines[0]
    assert "Traceback" not in err and not out.exists()


def test_changed_frames_and_windows():
    a = MaskStack.from_masks(np.zeros((6, 8, 8), bool))
    m = np.zeros((6, 8, 8), bool)
    m[2, 1:3, 1:3] = True
    m[4, 0, 0] = True
    b = MaskStack.from_masks(m)
    assert changed_frames(a, b).tolist() == [False, False, True, False, True, False]
    assert changed_frames(b, b).tolist() == [False] * 6
    assert changed_frames(a, b[:5]).all()
    ch = np.zeros(100, bool)
    ch[[3, 4, 47, 52, 95]] = True
    assert refit_windows(ch) == [(0, 0, 15), (30, 40, 63), (80, 90, 100)]


def test_refit_changed_frames_only():
    """Cut the truth silhouettes of frames 21-22 in half: the fit changes there, stays
    exactly the same outside the refit window, and is what a fresh fit gives."""
    from vidcap.video.fit.tracking import fit_sequence

    if not WALK.exists():
        pytest.skip("sample_videos/ not present")
    masks = np.load(WALK.with_name("walk_side_truth.npz"))["masks"]
    old_stack = MaskStack.from_masks(masks)
    old = {k: np.asarray(v) for k, v in fit_sequence(old_stack).arrays().items()}
    cut = masks.copy()
    cut[21:23, 200:] = False  # the lower half gone
    new_stack = MaskStack.from_masks(cut)
    changed = changed_frames(old_stack, new_stack)
    assert changed.tolist() == [k in (21, 22) for k in range(len(masks))]
    seen = []
    new = refit_changed(new_stack, old, changed, progress=lambda d, t: seen.append((d, t)),
                        whole_share=1.0)
    (start, begin, end), = refit_windows(changed)
    assert (begin, end) == (20, 33) and seen[-1] == (end - start,) * 2
    outside = np.r_[0:begin, end:len(masks)]
    for k in ("joints2d", "similarity", "spread", "model_height", "scores"):
        assert np.array_equal(new[k][outside], old[k][outside], equal_nan=True), k
    legs = new["joints2d"][21, 9:15]  # hips, knees, ankles: drawn within the cut mask
    assert np.nanmax(legs[:, 1]) < np.nanmax(old["joints2d"][21, 9:15, 1])


def test_refit_changed_keeps_the_fits_body():
    """A fit made with a real adult's body (``vidcap convert``'s default) is refitted with
    the same body: the refit window is ``fit_sequence`` with that body, its model height
    head top to ankles (the feet left out), as the pipeline keeps it."""
    from vidcap.video.fit.proportions import HUMAN, fit_keywords
    from vidcap.video.fit.tracking import fit_sequence

    if not WALK.exists():
        pytest.skip("sample_videos/ not present")
    masks = np.load(WALK.with_name("walk_side_truth.npz"))["masks"][:30]
    kw = fit_keywords(HUMAN)
    old = {k: np.asarray(v) for k, v in fit_sequence(masks, **kw).arrays().items()}
    cut = masks.copy()
    cut[12, 200:] = False
    changed = np.arange(len(masks)) == 12
    new = refit_changed(MaskStack.from_masks(cut), old, changed, whole_share=1.0, fit_kw=kw)
    (start, begin, end), = refit_windows(changed)
    direct = fit_sequence(cut[start:end], **kw)
    np.testing.assert_array_equal(new["similarity"][begin:end],
                                  direct.similarity[begin - start:])
    np.testing.assert_allclose(new["model_height"][begin:end],
                               direct.model_height[begin - start:] * (1 - kw["foot"]))
