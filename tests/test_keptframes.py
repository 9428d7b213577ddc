"""The colour kept round the person for the 3D stage's cues (vidcap.video.keptframes)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vidcap.video.keptframes import MARGIN_PX, KeptFrames

SAMPLES = Path(__file__).resolve().parents[1] / "sample_videos"


def test_frames_come_back_inside_the_box_and_its_margin_and_black_elsewhere():
    rng = np.random.default_rng(0)
    frames = rng.integers(0, 256, (3, 120, 160, 3), dtype=np.uint8)
    kept = KeptFrames()
    boxes = [(40, 80, 60, 90), (0, 0, 0, 0), (100, 120, 140, 160)]  # y0, y1, x0, x1
    for frame, box in zip(frames, boxes, strict=True):
        kept.append(frame, box)
    assert kept.complete(3) and not kept.complete(4)
    out = [f.copy() for f in kept.frames()]
    inside = np.zeros((120, 160), bool)
    m = MARGIN_PX  # 40 rows tall: the margin is the minimum
    inside[40 - m:80 + m, 60 - m:90 + m] = True
    np.testing.assert_array_equal(out[0][inside], frames[0][inside])
    assert not out[0][~inside].any()
    assert not out[1].any()  # no person, nothing kept (the buffer is cleared)
    inside[:] = False
    inside[100 - m:, 140 - m:] = True  # clipped at the frame's edges
    np.testing.assert_array_equal(out[2][inside], frames[2][inside])
    assert not out[2][~inside].any()


def test_covers_tells_whether_every_pixel_read_is_kept():
    kept = KeptFrames()
    frame = np.zeros((120, 160, 3), np.uint8)
    kept.append(frame, (40, 80, 60, 90))  # kept rows 24-95, columns 44-105
    kept.append(frame, (0, 0, 0, 0))  # nothing kept
    none = [np.inf, -np.inf, np.inf, -np.inf]  # a frame that reads no pixel
    assert kept.covers([[44, 105, 24, 95], none])
    assert not kept.covers([[44, 106, 24, 95], none])
    assert not kept.covers([[44, 105, 23, 95], none])
    assert not kept.covers([none, [50, 50, 50, 50]])  # frame 1 kept nothing
    assert not kept.covers([none, none, [50, 50, 50, 50]])  # a frame not kept at all
    assert kept.covers([none, none, none])


def _inside(frames, bounds):
    """``frames`` black outside each frame's ``bounds`` (x_min, x_max, y_min, y_max)."""
    out = np.zeros_like(frames)
    for k, (x0, x1, y0, y1) in enumerate(bounds.astype(int)):
        out[k, y0:y1 + 1, x0:x1 + 1] = frames[k, y0:y1 + 1, x0:x1 + 1]
    return out


def test_the_cues_read_nothing_outside_their_read_bounds():
    """frontback's and legorder's boxes of the pixels they read: frames black outside
    them give the cues what the whole frames give (and black frames do not)."""
    from vidcap.video.frontback import arm_visibility, read_bounds
    from vidcap.video.legorder import limb_edges, limb_radii, plan_lines
    from vidcap.video.legorder import read_bounds as limb_bounds

    truth = np.load(SAMPLES / "walk_side_truth.npz")  # arms over the torso, legs crossing
    joints = truth["joints2d"][:20].astype(float)
    shape = truth["masks"].shape[1:]
    frames = np.random.default_rng(0).integers(0, 256, (20, *shape, 3), dtype=np.uint8)
    arm = read_bounds(joints, shape)
    assert np.isfinite(arm).all()
    whole = arm_visibility(frames, joints)
    np.testing.assert_array_equal(arm_visibility(_inside(frames, arm), joints), whole)
    assert not np.array_equal(arm_visibility(np.zeros_like(frames), joints), whole,
                              equal_nan=True)
    radii = limb_radii(np.full(20, float(np.ptp(joints[0, :, 1]))))
    limbs = limb_bounds(plan_lines(joints, radii, shape))
    assert (limbs[:, 0] <= limbs[:, 1]).any()
    strength, count = limb_edges(frames, joints, radii)
    got = limb_edges(_inside(frames, limbs), joints, radii)
    np.testing.assert_array_equal(got[0], strength)
    np.testing.assert_array_equal(got[1], count)


def test_past_the_budget_everything_is_dropped():
    frame = np.full((100, 100, 3), 7, np.uint8)
    kept = KeptFrames(budget=3 * 100 * 100 * 3 - 1)
    for _ in range(3):
        kept.append(frame, (0, 100, 0, 100))
    assert kept.dropped and len(kept) == 0 and not kept.complete(3)
    kept.append(frame, (0, 100, 0, 100))
    assert len(kept) == 0


def test_a_frame_of_another_size_drops_what_was_kept():
    kept = KeptFrames()
    kept.append(np.zeros((100, 100, 3), np.uint8), (0, 50, 0, 50))
    kept.append(np.zeros((120, 100, 3), np.uint8), (0, 50, 0, 50))
    assert kept.dropped and not kept.complete(2)


def test_a_clip_whose_first_boxes_project_past_the_budget_is_not_kept_at_all():
    frame = np.full((100, 100, 3), 7, np.uint8)
    per_frame = 100 * 100 * 3
    kept = KeptFrames(budget=100 * per_frame, n_frames=101)
    for _ in range(9):
        kept.append(frame, (0, 100, 0, 100))
    assert not kept.dropped and len(kept) == 9  # too few frames to project from
    kept.append(frame, (0, 100, 0, 100))  # 10 of 101 frames: 101 x per_frame > budget
    assert kept.dropped and len(kept) == 0
    fits = KeptFrames(budget=100 * per_frame, n_frames=100)
    for _ in range(100):
        fits.append(frame, (0, 100, 0, 100))
    assert fits.complete(100)


def test_convert_reads_the_cues_from_the_kept_frames_as_from_a_second_decode(monkeypatch):
    """The 3D stage's colour cues from the silhouettes' kept frames equal those of
    decoding the video again (which a dropped keeper falls back to), and with them no
    second decode happens."""
    import vidcap.io.video as video_io
    import vidcap.video.keptframes as keptframes
    import vidcap.video.pipeline as pipeline

    cues, decodes = [], []
    real_cues, real_iter = pipeline.colour_cues, video_io.iter_frames

    def spy_cues(frames, *a, **k):
        out = real_cues(frames, *a, **k)
        cues.append(out)
        return out

    def spy_iter(*a, **k):
        decodes.append(a)
        return real_iter(*a, **k)

    monkeypatch.setattr(pipeline, "colour_cues", spy_cues)
    monkeypatch.setattr(video_io, "iter_frames", spy_iter)
    video = SAMPLES / "arms.mp4"
    kept = pipeline.run(video, progress=False, jobs=1)
    n_kept = len(decodes)
    monkeypatch.setattr(keptframes.KeptFrames.__init__, "__defaults__", (0, None))
    decoded = pipeline.run(video, progress=False, jobs=1)
    assert len(decodes) == 2 * n_kept + 1  # the second run decoded once more
    (near_a, limbs_a), (near_b, limbs_b) = cues
    arms = near_a[:, 0]  # the near side; the face (column 1) is searched in kept boxes too
    assert np.isfinite(arms).any() and np.abs(arms).max() > 0
    assert np.isfinite(near_a[:, 1]).any()
    np.testing.assert_array_equal(near_a, near_b)
    np.testing.assert_array_equal(limbs_a, limbs_b)
    np.testing.assert_array_equal(kept.lifted.joints3d, decoded.lifted.joints3d)
