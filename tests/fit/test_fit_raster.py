"""Batched rasteriser: exact against a brute-force distance test; normalisation."""

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX, SEGMENT_NAMES
from vidcap.video.fit.raster import (
    draw_segments,
    image_angle,
    model_dimensions,
    normalise_mask,
    pose_joints,
    row_prefix_sums,
    segment_spans,
)


def _brute(p0, p1, r, shape, caps):
    ys, xs = np.mgrid[0 : shape[0], 0 : shape[1]].astype(float)
    v = p1 - p0
    vv = (v * v).sum(-1)[..., None, None]
    dx, dy = xs - p0[..., 0, None, None], ys - p0[..., 1, None, None]
    t = (dx * v[..., 0, None, None] + dy * v[..., 1, None, None]) / vv
    rr = r[None, :, None, None] ** 2 + 1e-9
    if caps:
        tc = np.clip(t, 0, 1)
        inside = (dx - tc * v[..., 0, None, None]) ** 2 + (dy - tc * v[..., 1, None, None]) ** 2
        inside = inside <= rr
    else:
        inside = (dx**2 + dy**2 - t**2 * vv <= rr) & (t >= -1e-9) & (t <= 1 + 1e-9)
    return inside.any(1)


@pytest.mark.parametrize("caps", [True, False])
def test_draw_matches_brute_force(caps):
    rng = np.random.default_rng(1)
    p0 = rng.uniform(5, 35, (40, 2, 2))
    p1 = p0 + rng.normal(0, 8, (40, 2, 2))
    p1[:5, 0, 1] = p0[:5, 0, 1]  # horizontal
    p1[5:10, 1, 0] = p0[5:10, 1, 0]  # vertical
    r = np.array([1.7, 3.2])
    got = draw_segments(p0, p1, r, (40, 40), caps=caps)
    assert got.shape == (40, 40, 40)
    assert np.array_equal(got, _brute(p0, p1, r, (40, 40), caps))
    # a window drawn at an origin is the same pixels
    win = draw_segments(p0, p1, r, (10, 15), origin=(12, 20), caps=caps)
    assert np.array_equal(win, got[:, 20:30, 12:27])


def test_spans_are_row_runs():
    # a horizontal 10 px bar of half-width 1 along y = 5: rows 4..6, columns 2..12
    f, l = segment_spans(np.array([[[2.0, 5.0]]]), np.array([[[12.0, 5.0]]]), np.array([1.0]),
                         np.arange(3, 8), caps=False)
    covered = (l >= f)[0, 0]
    assert covered.tolist() == [False, True, True, True, False]
    assert (f[0, 0, 1:4] == 2).all() and (l[0, 0, 1:4] == 12).all()
    # with round caps the ends reach one radius further on the axis row
    f, l = segment_spans(np.array([[[2.0, 5.0]]]), np.array([[[12.0, 5.0]]]), np.array([1.0]),
                         np.array([5]), caps=True)
    assert (f[0, 0, 0], l[0, 0, 0]) == (1, 13)


def test_rotated_bar_pixel_count():
    # area of a 40 x 6 bar at 30 degrees, counted from pixel centres: ~240 +- perimeter
    a = np.deg2rad(30.0)
    c = np.array([50.0, 50.0])
    d = 20 * np.array([np.cos(a), -np.sin(a)])
    m = draw_segments((c - d)[None, None], (c + d)[None, None], np.array([3.0]), (100, 100),
                      caps=False)[0]
    assert abs(m.sum() - 240) < 20


def test_pose_joints_lengths_and_angles():
    H = 175.0
    L, R, sh, hp = model_dimensions(H)
    angles = np.deg2rad([90, 95, 200, 250, 300, 330, 262, 270, 278, 270])
    fore = np.linspace(0.5, 1.0, 10)
    j = pose_joints(np.array([50.0, 100.0]), angles, fore, 0.0, L, sh, hp)
    for k, name in enumerate(SEGMENT_NAMES):
        from vidcap.body import SEGMENTS

        seg = SEGMENTS[k]
        v = j[JOINT_INDEX[seg.distal]] - j[JOINT_INDEX[seg.proximal]]
        assert np.hypot(*v) == pytest.approx(L[k] * fore[k])
        assert image_angle(v) == pytest.approx(angles[k]), name
    # spread 0: shoulders on the neck; spread 1: the body model's lateral offsets
    assert np.allclose(j[JOINT_INDEX["l_shoulder"]], j[JOINT_INDEX["neck"]])
    j1 = pose_joints(np.array([50.0, 100.0]), angles, fore, 1.0, L, sh, hp)
    assert j1[JOINT_INDEX["l_shoulder"], 0] < j1[JOINT_INDEX["neck"], 0]  # image left
    assert np.hypot(*(j1[JOINT_INDEX["l_hip"]] - j1[JOINT_INDEX["pelvis"]])) == pytest.approx(hp)
    # batched
    jb = pose_joints(np.zeros((4, 2)), np.repeat(angles[None], 4, 0), fore, np.ones(4), L, sh, hp)
    assert jb.shape == (4, 15, 2)


def test_normalise_round_trip():
    mask = np.zeros((480, 640), bool)
    mask[100:400, 300:360] = True
    n = normalise_mask(mask, height=60)
    assert n.bottom - n.top + 1 == 60
    assert n.mask.sum() == pytest.approx(60 * 12, rel=0.1)
    pts = np.array([[300.0, 100.0], [359.0, 399.0]])
    back = n.to_original(n.to_normalised(pts))
    assert np.allclose(back, pts)
    # corners of the silhouette land on its normalised corners (to half a pixel)
    ys, xs = np.nonzero(n.mask)
    assert np.allclose(n.to_normalised(pts), [[xs.min(), ys.min()], [xs.max(), ys.max()]],
                       atol=0.6)
    with pytest.raises(ValueError):
        normalise_mask(np.zeros((5, 5), bool))
    assert n.body is None and n.body_height == 60


def test_count_tables_equal_prefix_sums_of_the_mask():
    """The tables a normalised silhouette caches for the fitter: the row prefix sums of
    [ones, mask] and the silhouette's pixels above each row."""
    rng = np.random.default_rng(5)
    mask = np.zeros((200, 150), bool)
    mask[20:180, 40:110] = rng.random((160, 70)) < 0.6
    n = normalise_mask(mask, height=70)
    rows, prefix = n.count_tables
    np.testing.assert_array_equal(prefix, row_prefix_sums(np.stack([np.ones_like(n.mask),
                                                                    n.mask])))
    np.testing.assert_array_equal(rows, np.r_[0, np.cumsum(n.mask.sum(axis=1))])
    assert n.count_tables[1] is prefix  # computed once


def test_normalise_to_a_given_body_height():
    # a crouch: the 300 px silhouette of a 400 px tall body
    mask = np.zeros((480, 640), bool)
    mask[100:400, 300:360] = True
    n = normalise_mask(mask, height=80, body_height=400.0)
    assert n.body_height == 80 and n.bottom - n.top + 1 == 60
    assert n.scale == pytest.approx(0.2)
    pts = np.array([[300.0, 100.0], [359.0, 399.0]])
    assert np.allclose(n.to_original(n.to_normalised(pts)), pts)
    ys, xs = np.nonzero(n.mask)
    assert np.allclose(n.to_normalised(pts), [[xs.min(), ys.min()], [xs.max(), ys.max()]],
                       atol=0.6)
    with pytest.raises(ValueError, match="body_height"):
        normalise_mask(mask, body_height=0.0)


@pytest.mark.parametrize("caps", [True, False])
def test_span_counts_compiled_and_numpy_paths_equal_drawn_masks(caps, monkeypatch):
    """span_counts (numba kernel and numpy fallback) = weights summed under draw_segments;
    draw_segments' compiled and numpy paths draw the same pixels."""
    from vidcap.video.fit import raster

    assert raster._kernels() is not None  # numba is a dependency: the fast path must be live
    rng = np.random.default_rng(7)
    h, w = 40, 36
    for k in (1, 2, 5):
        b = 120
        p0 = rng.uniform(-8, 44, (b, k, 2))
        p1 = p0 + rng.normal(0, 12, (b, k, 2))
        p1[:4] = p0[:4]  # points
        p1[4:8, :, 0] = p0[4:8, :, 0]  # vertical
        p1[8:12, :, 1] = p0[8:12, :, 1]  # horizontal
        p0[12:16] = np.round(p0[12:16]) + 0.5  # ends on pixel borders
        radii = rng.uniform(0.3, 5.0, k)
        weights = rng.integers(0, 2, (3, 2, h, w)).astype(bool)
        cum = raster.row_prefix_sums(weights)
        table = rng.integers(0, 3, b)
        masks = raster.draw_segments(p0, p1, radii, (h, w), caps=caps)
        masks[:, :3] = masks[:, 31:] = False
        want = np.einsum("bhw,bchw->bc", masks.astype(int), weights[table].astype(int))
        fast = raster.span_counts(p0, p1, radii, cum, rows=(3, 31), table=table, caps=caps)
        window = raster.draw_segments(p0, p1, radii, (20, 17), origin=(9, 5), caps=caps)
        monkeypatch.setattr(raster, "_kernels", lambda: None)
        slow = raster.span_counts(p0, p1, radii, cum, rows=(3, 31), table=table, caps=caps)
        np.testing.assert_array_equal(raster.draw_segments(p0, p1, radii, (h, w), caps=caps)
                                      [:, 3:31], masks[:, 3:31])
        np.testing.assert_array_equal(
            raster.draw_segments(p0, p1, radii, (20, 17), origin=(9, 5), caps=caps), window)
        monkeypatch.undo()
        np.testing.assert_array_equal(fast, want)
        np.testing.assert_array_equal(slow, want)
        assert want.sum() > 0


def test_pose_joints_batch_equals_pose_joints_bit_for_bit(monkeypatch):
    """The compiled joint kernel gives exactly pose_joints' floats (and so does its fallback)."""
    from vidcap.video.fit import raster

    rng = np.random.default_rng(3)
    b = 50
    root = rng.uniform(0, 100, (b, 2))
    angles = rng.uniform(-7, 7, (b, 10))
    fore = rng.uniform(0.01, 1, (b, 10))
    spread = rng.uniform(0, 1, b)
    from vidcap.body import BodyModel

    kernels = raster._kernels
    # the seed's body (shoulders at the torso's top corners) and one whose shoulder
    # joints sit below them
    for body in (None, BodyModel(shoulder_drop=0.04)):
        monkeypatch.setattr(raster, "_kernels", kernels)
        lengths, _, lateral, hip = raster.model_dimensions(83.7, body)
        sh = raster.model_shoulder(lateral, 83.7, body)
        want = raster.pose_joints(root, angles, fore, spread, lengths, sh, hip)
        got = raster.pose_joints_batch(root, angles, fore, spread, lengths, sh, hip)
        assert got.shape == (b, 15, 2)
        np.testing.assert_array_equal(got, want)
        # the one-pose kernel (the fitter's current pose) takes cos/sin itself (libm):
        # the same joints up to the last bit where numpy's differ
        one = np.empty((1, 15, 2))
        for k in range(b):
            raster._kernels().pose_one(root[k], angles[k], fore[k], float(spread[k]), lengths,
                                       sh, float(hip), *raster._KERNEL_TABLES, one)
            np.testing.assert_allclose(one[0], want[k], rtol=0, atol=1e-9)
        monkeypatch.setattr(raster, "_kernels", lambda: None)
        np.testing.assert_array_equal(
            raster.pose_joints_batch(root, angles, fore, spread, lengths, sh, hip), want)


def test_shoulder_drop_moves_the_shoulders_down_the_torso():
    """A body whose shoulder joints sit ``shoulder_drop`` below the torso's top corners:
    in 2D both shoulders move that far (in pixels of the model's height) from the neck
    along the torso's axis, whatever the torso's angle and the spread; nothing else
    moves; in 3D the rest pose's shoulders are that much lower."""
    from vidcap.body import JOINT_INDEX, BodyModel
    from vidcap.video.fit import raster

    body, h = BodyModel(height=1.75, shoulder_drop=0.0385), 80.0
    lengths, _, lateral, hip = raster.model_dimensions(h, body)
    pair = raster.model_shoulder(lateral, h, body)
    assert pair[0] == pytest.approx(lateral) and pair[1] == pytest.approx(0.0385 / 1.75 * h)
    rng = np.random.default_rng(5)
    angles = rng.uniform(-3, 3, (20, 10))
    spread = rng.uniform(0, 1, 20)
    root = rng.uniform(0, 100, (20, 2))
    fore = np.ones((20, 10))
    flat = raster.pose_joints(root, angles, fore, spread, lengths, lateral, hip)
    low = raster.pose_joints_batch(root, angles, fore, spread, lengths, pair, hip)
    up = raster.direction(angles[:, 0])  # the torso's axis, pelvis -> neck
    for n in ("l_shoulder", "r_shoulder"):
        np.testing.assert_allclose(flat[:, JOINT_INDEX[n]] - low[:, JOINT_INDEX[n]],
                                   pair[1] * up, atol=1e-9)
    others = [JOINT_INDEX[n] for n in ("pelvis", "neck", "head_top", "l_hip", "r_knee")]
    np.testing.assert_array_equal(flat[:, others], low[:, others])
    rest = body.rest_positions()
    seed = BodyModel(height=1.75).rest_positions()
    assert seed[JOINT_INDEX["l_shoulder"], 1] - rest[JOINT_INDEX["l_shoulder"], 1] \
        == pytest.approx(0.0385)


def test_span_similarity_equals_counts_then_similarity(monkeypatch):
    """span_similarity (compiled, and numpy fallback) = similarity_from_counts of span_counts."""
    from vidcap.video.fit import raster
    from vidcap.video.fit.similarity import similarity_from_counts

    rng = np.random.default_rng(11)
    h, w, t, k, b = 40, 36, 3, 2, 90
    p0 = rng.uniform(-8, 44, (b, k, 2))
    p1 = p0 + rng.normal(0, 12, (b, k, 2))
    radii = rng.uniform(0.3, 5.0, (t, k))
    cum = raster.row_prefix_sums(rng.integers(0, 2, (t, 2, h, w)).astype(bool))
    table = rng.integers(0, t, b)
    m_base = rng.integers(0, 200, t)
    i_base = m_base // 2
    a = 300
    d = raster.span_counts(p0, p1, radii[table], cum, rows=(2, 35), table=table)
    want = similarity_from_counts(a, m_base[table] + d[:, 0], i_base[table] + d[:, 1])
    got = raster.span_similarity(p0, p1, radii, cum, a, m_base, i_base, rows=(2, 35),
                                 table=table)
    np.testing.assert_array_equal(got, want)
    assert np.ptp(want) > 0
    monkeypatch.setattr(raster, "_kernels", lambda: None)
    np.testing.assert_array_equal(
        raster.span_similarity(p0, p1, radii, cum, a, m_base, i_base, rows=(2, 35),
                               table=table), want)


@pytest.mark.parametrize("caps", [True, False])
def test_base_tables_compiled_and_numpy_paths_agree_with_drawn_model(caps, monkeypatch):
    """base_tables = row prefix sums of (not model) and (silhouette and not model)."""
    from vidcap.video.fit import raster

    rng = np.random.default_rng(5)
    h, w = 30, 27
    sil = rng.integers(0, 2, (h, w)).astype(bool)
    p0 = rng.uniform(-3, 30, (4, 2))
    p1 = p0 + rng.normal(0, 9, (4, 2))
    radii = rng.uniform(0.5, 4, 4)
    model = raster.draw_segments(p0[None], p1[None], radii, (h, w), caps=caps)[0]
    want = raster.row_prefix_sums(np.stack([~model, sil & ~model]))
    want[:, :4] = want[:, 25:] = 0
    for fallback in (False, True):
        if fallback:
            monkeypatch.setattr(raster, "_kernels", lambda: None)
        cum, m, i = raster.base_tables(p0, p1, radii, sil, rows=(4, 25), caps=caps)
        np.testing.assert_array_equal(cum[0], want)
        assert m == np.count_nonzero(model[4:25]) > 0
        assert i == np.count_nonzero((model & sil)[4:25])
        # the table only in the rows a search reaches; the counts still over all rows
        part, m2, i2 = raster.base_tables(p0, p1, radii, sil, rows=(4, 25), reach=(9, 17),
                                          sil_cum=raster.row_prefix_sums(sil), caps=caps)
        np.testing.assert_array_equal(part[0][:, 9:17], want[:, 9:17])
        assert not part[0][:, :9].any() and not part[0][:, 17:].any()
        assert (m2, i2) == (m, i)


def test_group_tables_leave_out_each_searched_pair():
    """group_tables: each table is the model without the searched segment (and child)."""
    from vidcap.video.fit import raster

    rng = np.random.default_rng(9)
    h, w = 25, 22
    masks = rng.random((10, h, w)) < 0.3
    sil = rng.random((h, w)) < 0.5
    segs, child = np.array([2, 3, 6]), np.array([3, 3, 7])
    got = raster.group_tables(masks, segs, child, sil)
    others = np.delete(masks, [2, 3], axis=0).any(axis=0)  # segment 2 with its child 3
    assert got[1][0] == np.count_nonzero(others)
    assert got[2][0] == np.count_nonzero(others & sil)
    row = 7  # its table counts, left of each column, the pixels outside that model
    np.testing.assert_array_equal(got[0][0, 0, row, 1:], np.cumsum(~others[row]))
    np.testing.assert_array_equal(got[0][0, 1, row, 1:], np.cumsum(~others[row] & sil[row]))


@pytest.mark.parametrize("caps", [False, True])
def test_group_span_tables_equal_group_tables_of_the_drawn_model(caps):
    """The span-counted group tables equal group_tables of the drawn segments, also
    with segments reaching past the image and limited table rows."""
    from vidcap.video.fit import raster

    rng = np.random.default_rng(11)
    h, w = 60, 45
    sil = rng.random((h, w)) < 0.5
    segs, child = np.array([2, 3, 6, 1, 9]), np.array([3, 3, 7, 1, 9])
    for _ in range(20):
        p0 = rng.uniform(-10, [w + 10, h + 10], (10, 2))
        p1 = p0 + rng.normal(0, 15, (10, 2))
        radii = rng.uniform(0.5, 6, 10)
        # each table's rows hold its pair (the tables' contract), with a random margin
        # that may reach past the image
        ys = np.stack([p0[:, 1], p1[:, 1]], 1)
        lo = np.minimum(ys[segs].min(1), ys[child].min(1)) - radii[[segs, child]].max(0)
        hi = np.maximum(ys[segs].max(1), ys[child].max(1)) + radii[[segs, child]].max(0)
        rows = np.stack([np.floor(lo) - 2 - rng.integers(0, 8, 5),
                         np.ceil(hi) + 3 + rng.integers(0, 8, 5)], 1).astype(np.int64)
        masks = raster.draw_segments(p0[:, None], p1[:, None], radii[:, None], (h, w),
                                     caps=caps)
        want = raster.group_tables(masks, segs, child, sil, rows=rows)
        got = raster.group_span_tables(p0, p1, radii, segs, child, sil, rows=rows, caps=caps)
        for g, x in zip(got, want, strict=True):
            np.testing.assert_array_equal(g, x)


def test_shift_overlaps_compiled_and_numpy_paths_agree(monkeypatch):
    from vidcap.video.fit import raster

    rng = np.random.default_rng(1)
    sil = rng.random((20, 15)) < 0.5
    model = rng.random((20, 15)) < 0.3
    got = raster.shift_overlaps(sil, model, 6)
    assert got[6] == np.count_nonzero(sil & model)  # no shift
    shifted = np.zeros_like(model)
    shifted[:, 2:] = model[:, :-2]  # the model moved right by 2 = t - n for t = 8
    assert got[8] == np.count_nonzero(sil & shifted)
    monkeypatch.setattr(raster, "_kernels", lambda: None)
    np.testing.assert_array_equal(raster.shift_overlaps(sil, model, 6), got)


def test_limb_and_pose_similarity_compiled_equal_numpy_paths(monkeypatch):
    """The fused end-point + similarity kernels give the numpy paths' floats exactly."""
    from vidcap.video.fit import raster

    rng = np.random.default_rng(8)
    h, w, b = 60, 50, 40
    cum = raster.row_prefix_sums(rng.integers(0, 2, (1, 2, h, w)).astype(bool))
    m_base, i_base = np.array([150]), np.array([90])
    a = 700
    # one limb segment (index 0 of K = 2) and its child
    vec = rng.normal(0, 10, (b, 2))
    start, old_end = np.array([25.0, 20.0]), np.array([27.0, 35.0])
    p0s, p1s = np.array([start, old_end]), np.array([old_end, [30.0, 48.0]])
    own = np.array([True, False])
    radii = np.array([[2.5, 2.0]])
    lengths, _, sh, hip = raster.model_dimensions(50.0)
    root = rng.uniform(20, 30, (b, 2))
    angles = rng.uniform(0, 7, (b, 10))
    fore = rng.uniform(0.2, 1, (b, 10))
    spread = rng.random(b)
    segs = np.array([0, 1, 6, 7])
    r4 = np.array([[3.0, 2.0, 2.5, 2.0]])

    def run():
        return (raster.limb_similarity(vec[:, 0], "angle", 12.5, start, old_end, p0s, p1s,
                                       own, radii, cum, a, m_base, i_base, rows=(0, h),
                                       caps=False),
                raster.limb_similarity(np.abs(vec[:, 1]) / 10, "ratio", np.array([3.0, 14.0]),
                                       start, old_end, p0s, p1s, own, radii, cum, a, m_base,
                                       i_base, rows=(0, h)),
                raster.pose_similarity(root, angles, fore, spread, lengths, sh, hip, segs, r4,
                                       cum, a, m_base, i_base, rows=(5, 55), caps=True))

    got = run()
    monkeypatch.setattr(raster, "_kernels", lambda: None)
    want = run()
    for g, x in zip(got, want, strict=True):
        np.testing.assert_array_equal(g, x)
        assert np.ptp(x) > 0


@pytest.mark.parametrize("form", ["angle", "ratio"])
def test_group_similarity_compiled_equals_numpy_path(form, monkeypatch):
    from vidcap.video.fit import raster

    rng = np.random.default_rng(12)
    h, w, n, b = 50, 40, 3, 7
    masks = rng.random((10, h, w)) < 0.2
    sil = rng.random((h, w)) < 0.5
    cum, m_base, i_base = raster.group_tables(masks, np.array([2, 3, 6]), np.array([3, 3, 7]),
                                              sil)
    own0 = rng.uniform(10, 30, (n, 2))
    own1 = own0 + rng.normal(0, 8, (n, 2))
    ch0, ch1 = own1.copy(), own1 + rng.normal(0, 8, (n, 2))
    leaf = np.array([False, True, False])
    radii = rng.uniform(1, 3, (n, 2))
    if form == "angle":
        values, scale = rng.uniform(0, 7, (n, b)), rng.uniform(5, 12, n)
    else:
        values, scale = rng.uniform(0.1, 1, (n, b)), rng.normal(0, 10, (n, 2))

    def run():
        return raster.group_similarity(values, form, scale, own0, own1, ch0, ch1, leaf, radii,
                                       cum, 900, m_base, i_base, caps=False)

    got = run()
    monkeypatch.setattr(raster, "_kernels", lambda: None)
    want = run()
    assert got.shape == (n, b) and np.ptp(want) > 0
    np.testing.assert_array_equal(got, want)


def test_group_tables_reach_rows_give_the_same_counts():
    """Tables filled only in the rows a search reaches: same counts, zeros elsewhere."""
    from vidcap.video.fit import raster

    rng = np.random.default_rng(10)
    h, w = 30, 20
    masks = rng.random((10, h, w)) < 0.3
    sil = rng.random((h, w)) < 0.5
    segs, child = np.array([2, 6]), np.array([3, 6])
    rows = np.array([[5, 17], [12, 40]])
    for (lo, hi), s, c in zip(rows, segs, child, strict=True):  # the pairs stay inside
        for k in {s, c}:
            masks[k, :lo] = masks[k, hi:] = False
    full = raster.group_tables(masks, segs, child, sil)
    got = raster.group_tables(masks, segs, child, sil, rows=rows)
    np.testing.assert_array_equal(got[1], full[1])
    np.testing.assert_array_equal(got[2], full[2])
    np.testing.assert_array_equal(got[0][0, :, 5:17], full[0][0, :, 5:17])
    assert not got[0][0, :, :5].any() and not got[0][0, :, 17:].any()
    np.testing.assert_array_equal(got[0][1, :, 12:], full[0][1, :, 12:])
