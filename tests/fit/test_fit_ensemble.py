"""The 2D fit as the median of fits on masks changed at the outline (fit.ensemble)."""

import numpy as np
import pytest

from vidcap.body import JOINT_NAMES, LIMB_PAIR_JOINTS, SEGMENT_NAMES
from vidcap.video.fit.ensemble import changed_mask, changed_masks, combine, fit_ensemble
from vidcap.video.fit.result import Pose2D
from vidcap.video.masks import MaskStack


def _disc(h=60, w=80, cy=30, cx=40, r=15):
    yy, xx = np.mgrid[:h, :w]
    return (yy - cy) ** 2 + (xx - cx) ** 2 <= r * r


def test_each_change_moves_only_the_outline():
    mask = _disc()
    eroded, dilated = changed_mask(mask, "erode"), changed_mask(mask, "dilate")
    assert (eroded <= mask).all() and (mask <= dilated).all()
    assert eroded.sum() < mask.sum() < dilated.sum()
    edge = changed_mask(mask, "edge0")
    changed = edge ^ mask
    assert changed.any()
    assert not (changed & ~dilated).any() and not (changed & eroded).any()
    # about a quarter of the band either side of the outline is flipped
    share = changed.sum() / (dilated & ~eroded).sum()
    assert 0.15 < share < 0.35
    assert not (changed_mask(mask, "edge1") == edge).all()
    with pytest.raises(ValueError, match="unknown mask change"):
        changed_mask(mask, "blur")


def test_a_frame_gets_the_same_draw_wherever_it_is_fitted():
    # a chunked fit sees a frame at another index of another stack: same draw
    a, b = _disc(cx=30), _disc(cx=50)
    first = changed_masks(MaskStack.from_masks([a, b]), "edge0")
    alone = changed_masks(MaskStack.from_masks([b]), "edge0")
    assert np.array_equal(first[1], alone[0])
    assert np.array_equal(first[0], changed_mask(a, "edge0"))
    # a dilated crop at the image's border grows into the frame, not past it
    corner = np.zeros((20, 20), bool)
    corner[:5, :5] = True
    grown = changed_masks(MaskStack.from_masks([corner]), "dilate")[0]
    assert np.array_equal(grown, changed_mask(corner, "dilate"))


def _pose(joints: np.ndarray, tag: float) -> Pose2D:
    f = len(joints)
    seg = np.tile(np.arange(10.0), (f, 1)) + tag
    return Pose2D(JOINT_NAMES, joints, seg, seg, seg, seg, np.full(f, tag),
                  np.full(f, tag), np.zeros(f, bool), True, model_height=np.full(f, 100 + tag))


def test_the_median_outvotes_one_member_and_follows_the_first_members_names():
    rng = np.random.default_rng(0)
    truth = rng.uniform(0, 100, (6, 15, 2))
    a, b, c = truth.copy(), truth.copy(), truth.copy()
    c[2, JOINT_NAMES.index("l_wrist")] += 40.0  # one member's arm off in one frame
    legs = LIMB_PAIR_JOINTS["legs"]
    b[:, legs[0] + legs[1]] = truth[:, legs[1] + legs[0]]  # another names the legs the other way
    out = combine([_pose(a, 0.0), _pose(b, 1.0), _pose(c, 2.0)])
    assert np.allclose(out.joints2d, truth)
    # per-frame arrays come from the member nearest the median: never the one 40 px off
    assert out.similarity[2] != 2.0
    # but the spread and the model's height the solve reads are the members' medians
    assert np.allclose(out.spread, 1.0) and np.allclose(out.model_height, 101.0)
    # the renamed member's leg segments were swapped back with its joints
    seg = [SEGMENT_NAMES.index(n) for n in ("l_upper_leg", "r_upper_leg")]
    picked_b = out.similarity == 1.0
    if picked_b.any():
        assert np.allclose(out.angles[picked_b][:, seg], np.array(seg)[::-1] + 1.0)
    # a frame no member fitted stays NaN
    a[4] = b[4] = c[4] = np.nan
    out = combine([_pose(a, 0.0), _pose(b, 1.0), _pose(c, 2.0)])
    assert np.isnan(out.joints2d[4]).all() and np.isfinite(out.joints2d[3]).all()


def test_one_member_is_the_plain_fit_and_the_count_is_checked():
    from vidcap.synth import make_motion, render_clip
    from vidcap.video.fit.tracking import fit_sequence

    motion = make_motion("walk", n_frames=6)
    _, truth = render_clip(motion, size=(160, 120), noise=0.0, rng=np.random.default_rng(0))
    masks = truth["masks"]
    plain = fit_sequence(masks, cues="outline")
    assert np.array_equal(fit_ensemble(masks, cues="outline").joints2d, plain.joints2d,
                          equal_nan=True)
    three = fit_ensemble(masks, cues="outline", ensemble=3)
    assert three.joints2d.shape == plain.joints2d.shape
    assert np.isfinite(three.joints2d).all()
    for bad in (0, 6):
        with pytest.raises(ValueError, match="ensemble must be"):
            fit_ensemble(masks, ensemble=bad)


def test_one_progress_bar_counts_every_frame_once_over_all_members():
    from vidcap.synth import make_motion, render_clip

    motion = make_motion("walk", n_frames=7)
    _, truth = render_clip(motion, size=(160, 120), noise=0.0, rng=np.random.default_rng(0))
    calls, seen = [], []

    def progress(it, total):
        calls.append(total)
        for k in it:
            seen.append(k)
            yield k

    fit_ensemble(truth["masks"], cues="outline", ensemble=3, progress=progress)
    assert calls == [7] and seen == list(range(7))
