"""Chunked fitting on worker processes (vidcap.video.fit.parallel)."""

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX, SEGMENT_INDEX
from vidcap.video.fit.parallel import (
    chunk_bounds,
    default_jobs,
    fit_sequence_chunked,
    reconcile_labels,
    swap_labels,
)
from vidcap.video.fit.pose2d import fit_sequence


@pytest.fixture(scope="module")
def walk_clip():
    """A 50-frame side-view walk: its colour frames and silhouettes."""
    from vidcap.synth import make_motion, render_clip

    motion = make_motion("walk", n_frames=50, rng=np.random.default_rng(0))
    frames, truth = render_clip(motion, size=(240, 180), yaw_deg=90.0, noise=0.0,
                                rng=np.random.default_rng(0))
    return frames, truth["masks"]


@pytest.fixture(scope="module")
def walk_masks(walk_clip):
    return walk_clip[1]


def test_chunk_bounds_tile_the_clip_aligned_with_overlap():
    b = chunk_bounds(300, 2)
    assert b == [(0, 0, 150), (140, 150, 300)]
    b = chunk_bounds(301, 4, overlap=10, align=10, min_chunk=60)
    assert [x[1] for x in b] == [0, 80, 160, 240]  # 301 / 4 rounded up to tens
    assert all(s == max(0, beg - 10) and s % 10 == 0 for s, beg, _ in b)
    assert b[-1][2] == 301 and all(b[k][2] == b[k + 1][1] for k in range(len(b) - 1))
    assert chunk_bounds(119, 8) == [(0, 0, 119)]  # shorter than two chunks: serial
    assert chunk_bounds(1000, 1) == [(0, 0, 1000)]
    assert 1 <= default_jobs() <= 8


def test_chunk_bounds_per_job_splits_further_down_to_min_chunk():
    b = chunk_bounds(300, 2, per_job=2)
    assert [x[1] for x in b] == [0, 80, 160, 240] and b[-1][2] == 300
    # no chunk shorter than min_chunk: 300 frames hold 5 of 60 at most
    assert len(chunk_bounds(300, 2, per_job=4)) == 5
    assert chunk_bounds(300, 1, per_job=2) == [(0, 0, 150), (140, 150, 300)]


def _arrays(rng, n=6):
    return {"joints2d": rng.normal(size=(n, 15, 2)) * 50,
            **{k: rng.normal(size=(n, 10)) for k in ("angles", "foreshortening", "scores",
                                                      "margins")},
            "spread": rng.random(n), "similarity": rng.random(n), "warm": np.ones(n, bool)}


def test_reconcile_finds_a_leg_swap_and_swap_labels_undoes_it():
    rng = np.random.default_rng(0)
    prev = _arrays(rng)
    cur = swap_labels(prev, {"arms": False, "legs": True})
    l_knee, r_knee = JOINT_INDEX["l_knee"], JOINT_INDEX["r_knee"]
    np.testing.assert_array_equal(cur["joints2d"][:, l_knee], prev["joints2d"][:, r_knee])
    a, b = SEGMENT_INDEX["l_lower_leg"], SEGMENT_INDEX["r_lower_leg"]
    np.testing.assert_array_equal(cur["angles"][:, a], prev["angles"][:, b])
    np.testing.assert_array_equal(cur["joints2d"][:, :9], prev["joints2d"][:, :9])  # arms kept
    cur["joints2d"] += rng.normal(size=cur["joints2d"].shape)  # a little disagreement
    swaps = reconcile_labels(prev, cur)
    assert swaps == {"arms": False, "legs": True}
    back = swap_labels(cur, swaps)
    assert np.abs(back["joints2d"] - prev["joints2d"]).max() < 10
    np.testing.assert_array_equal(back["angles"], prev["angles"])
    # NaN frames (no silhouette) do not decide anything
    cur2 = dict(cur, joints2d=cur["joints2d"].copy())
    cur2["joints2d"][0] = np.nan
    assert reconcile_labels(prev, cur2) == swaps


def test_the_settled_tail_names_the_chunk_where_the_overlap_would_not():
    """The later chunk's overlap frames are unsettled (here: its legs the other way round
    on most of them); the frames both chunks fitted past the earlier one's end agree
    when named as fitted, and decide."""
    rng = np.random.default_rng(1)
    prev = _arrays(rng, n=12)
    cur = {k: np.array(v, copy=True) for k, v in prev.items()}
    cur["joints2d"] += rng.normal(scale=0.1, size=cur["joints2d"].shape)
    head = swap_labels({k: v[:10] for k, v in cur.items()}, {"arms": False, "legs": True})
    cur["joints2d"][:10] = head["joints2d"]
    cur["joints2d"][:10] += rng.normal(scale=20.0, size=(10, 15, 2))  # unsettled
    assert reconcile_labels(prev, cur)["legs"]  # the overlap alone: the wrong way round
    assert reconcile_labels(prev, cur, tail=2) == {"arms": False, "legs": False}


def test_per_frame_chunks_equal_one_serial_pass(walk_masks):
    seen = []

    def progress(it, total):
        seen.append(total)
        for k in it:
            seen.append(k)
            yield k

    got = fit_sequence_chunked(walk_masks, jobs=2, tracked=False, min_chunk=20,
                               progress=progress)
    want = fit_sequence(walk_masks, tracked=False)
    for key, value in want.arrays().items():
        np.testing.assert_array_equal(got.arrays()[key], value, err_msg=key)
    assert seen[0] == len(walk_masks) and len(seen) == 1 + len(walk_masks)


def test_tracked_chunks_agree_with_serial_and_keep_labels(walk_masks, monkeypatch):
    from vidcap.video.fit import parallel

    serial = fit_sequence(walk_masks)
    got = fit_sequence_chunked(walk_masks, jobs=2, min_chunk=20)
    assert got.tracked and got.n_frames == serial.n_frames
    err = np.linalg.norm(got.joints2d - serial.joints2d, axis=-1)
    assert np.median(err) < 1.0  # px: the second chunk's track settles on the serial one
    # a chunk whose track began with the other labelling is relabelled to agree: make
    # every later chunk come back with both limb pairs swapped (workers are forked,
    # so they see the patched function) and the joined result must not change
    monkeypatch.setattr(parallel, "_fit_chunk", _swapped_chunk)
    again = fit_sequence_chunked(walk_masks, jobs=2, min_chunk=20)
    for key, value in got.arrays().items():
        np.testing.assert_array_equal(again.arrays()[key], value, err_msg=key)


def _swapped_chunk(masks, frames, skip, tracked, kw, stop=None):
    from vidcap.video.fit import parallel

    out = _REAL_FIT_CHUNK(masks, frames, skip, tracked, kw, stop)
    return parallel.swap_labels(out, {"arms": True, "legs": True}) if skip else out


def _real():
    from vidcap.video.fit import parallel

    return parallel._fit_chunk


_REAL_FIT_CHUNK = _real()


def test_chunks_on_one_process_with_cues_are_the_two_workers_fit_exactly(walk_clip,
                                                                          monkeypatch):
    """A fit planned in chunks (``jobs=2``) is the same, bit for bit, on one process
    (``workers=1``: the chunks fitted here one after another) as on two workers, with
    the cues, so ``vidcap convert``'s result does not depend on ``--jobs``. One plain
    serial pass differs (the second chunk's track starts fresh: a side view's arms),
    and so do chunks that each learn the colours from their own frames (the clip's
    model is learned once and handed to every chunk)."""
    from vidcap.video.fit import parallel

    frames, masks = walk_clip
    two = fit_sequence_chunked(masks, frames=frames, jobs=2, min_chunk=20)
    one = fit_sequence_chunked(masks, frames=frames, jobs=2, min_chunk=20, workers=1)
    for key, value in two.arrays().items():
        np.testing.assert_array_equal(one.arrays()[key], value, err_msg=key)

    def differ(pose):
        return int((np.abs(pose.joints2d - two.joints2d).max(axis=(1, 2)) > 1e-6).sum())

    assert differ(fit_sequence(masks, frames=frames)) > 0
    monkeypatch.setattr(parallel, "sequence_colours", lambda *a, **k: None)
    assert differ(fit_sequence_chunked(masks, frames=frames, jobs=2, min_chunk=20,
                                       workers=1)) > 0


def test_one_job_or_short_clip_is_the_serial_path(walk_masks):
    want = fit_sequence(walk_masks[:12])
    for jobs in (1, 4):
        got = fit_sequence_chunked(walk_masks[:12], jobs=jobs)
        np.testing.assert_array_equal(got.joints2d, want.joints2d)


def test_a_pool_started_ahead_gives_the_same_fit(walk_masks):
    from vidcap.video.fit.parallel import FitPool

    want = fit_sequence_chunked(walk_masks, jobs=2, min_chunk=20)
    with FitPool(2) as pool:
        for _ in range(2):  # reusable
            got = fit_sequence_chunked(walk_masks, min_chunk=20, pool=pool)
            np.testing.assert_array_equal(got.joints2d, want.joints2d)
            np.testing.assert_array_equal(got.similarity, want.similarity)
    with pytest.raises(RuntimeError):  # closed
        pool.executor.submit(int)


def test_a_streamed_fit_equals_the_chunked_fit_of_all_frames(walk_masks, monkeypatch):
    """Chunks sent as their frames arrive (StreamedFit.feed) give the fit of all frames
    at once, also when the clip turns out shorter than planned; the last chunk waits
    for finish()."""
    from vidcap.video.fit import parallel
    from vidcap.video.fit.parallel import FitPool, StreamedFit

    want = fit_sequence_chunked(walk_masks, jobs=2, min_chunk=20)
    sent = []
    submit = StreamedFit._submit

    def spy(self, chunk, masks, frames, bounds):
        sent.append((chunk, len(masks)))
        submit(self, chunk, masks, frames, bounds)

    monkeypatch.setattr(StreamedFit, "_submit", spy)
    with FitPool(2) as pool:
        stream = StreamedFit(pool, len(walk_masks), min_chunk=20)
        assert len(stream.bounds) == 2
        so_far = []
        for k in range(0, len(walk_masks), 7):  # frames arrive 7 at a time
            so_far.extend(walk_masks[k:k + 7])
            stream.feed(so_far)
        # the first chunk left as soon as its frames (and the tail it fits past its end
        # to name the next chunk's limbs by) were there, the last one waits
        first_end = stream.bounds[0][2] + parallel.TAIL
        assert sent == [(stream.bounds[0], 7 * -(-first_end // 7))]
        got = stream.finish(walk_masks)
        for key, value in want.arrays().items():
            np.testing.assert_array_equal(got.arrays()[key], value, err_msg=key)
        # planned for more frames than came: the chunks are planned again
        short = walk_masks[:45]
        stream = StreamedFit(pool, len(walk_masks), min_chunk=20)
        stream.feed(list(short))
        got = stream.finish(short)
        want_short = parallel.fit_sequence_chunked(short, jobs=2, min_chunk=20)
        np.testing.assert_array_equal(got.joints2d, want_short.joints2d)


def test_masks_as_a_stack_of_crops_fit_exactly_as_full_frames(walk_masks):
    """fit_sequence (and the chunked fit) on a MaskStack normalise each frame from its
    crop: every result equals the fit of the full (F, H, W) array."""
    from vidcap.video.fit.pose2d import fit_sequence
    from vidcap.video.fit.raster import normalise_mask
    from vidcap.video.masks import MaskStack

    m = walk_masks[:24].copy()
    m[5] = False  # an empty frame
    stack = MaskStack.from_masks(m)
    crop, origin = stack.crop(3)
    a, b = normalise_mask(m[3]), normalise_mask(crop, origin=origin)
    np.testing.assert_array_equal(a.mask, b.mask)
    np.testing.assert_array_equal(a.offset, b.offset)
    full = fit_sequence(m).arrays()
    cropped = fit_sequence(stack).arrays()
    for key, v in full.items():
        if isinstance(v, np.ndarray) and v.dtype.kind in "fb":
            np.testing.assert_array_equal(cropped[key], v, err_msg=key)


def _failing_chunk(masks, frames, skip, tracked, kw, stop=None):
    if skip:  # the second chunk
        raise ValueError("a bad chunk")
    return _REAL_FIT_CHUNK(masks, frames, skip, tracked, kw, stop)


def _dying_chunk(masks, frames, skip, tracked, kw, stop=None):
    import os

    if skip:
        os._exit(3)  # a worker killed mid-chunk (out of memory, a signal)
    return _REAL_FIT_CHUNK(masks, frames, skip, tracked, kw, stop)


def test_a_failing_or_dying_worker_is_an_error_not_a_hang(walk_masks, monkeypatch):
    import time

    from vidcap.video.fit import parallel

    monkeypatch.setattr(parallel, "_fit_chunk", _failing_chunk)
    with pytest.raises(ValueError, match="a bad chunk"):
        fit_sequence_chunked(walk_masks, jobs=2, min_chunk=20)
    monkeypatch.setattr(parallel, "_fit_chunk", _dying_chunk)
    t0 = time.perf_counter()
    with pytest.raises(RuntimeError, match="stopped"):
        fit_sequence_chunked(walk_masks, jobs=2, min_chunk=20)
    assert time.perf_counter() - t0 < 60
