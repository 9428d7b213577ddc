"""MaskStack: silhouettes stored as bit-packed bounding-box crops, read as full frames."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from vidcap.fileio import savez_atomic
from vidcap.video.masks import MaskStack, frames_with_pixels


def _masks(seed=0):
    rng = np.random.default_rng(seed)
    m = np.zeros((6, 31, 43), bool)
    m[1, 3:12, 5:18] = rng.random((9, 13)) > 0.4  # a ragged blob
    m[2, 30, 42] = True  # one pixel in the last row and column
    m[3] = True  # everything
    m[5, 0, 0:9] = True  # a row crossing a byte boundary of the packed bits
    return m  # frames 0 and 4 empty


def test_frames_read_back_exactly():
    m = _masks()
    st = MaskStack.from_masks(m)
    assert st.shape == m.shape and len(st) == 6 and st.dtype == bool
    np.testing.assert_array_equal(np.asarray(st), m)
    for k in range(-6, 6):
        np.testing.assert_array_equal(st[k], m[k])
    np.testing.assert_array_equal(np.asarray(st[1:5:2]), m[1:5:2])
    np.testing.assert_array_equal(st[1, 3:12, 5:18], m[1, 3:12, 5:18])
    np.testing.assert_array_equal(st[2:4, 30], m[2:4, 30])
    np.testing.assert_array_equal(frames_with_pixels(st), m.any(axis=(1, 2)))
    np.testing.assert_array_equal(frames_with_pixels(m), m.any(axis=(1, 2)))
    # the rest of the array interface works on the full array
    np.testing.assert_array_equal(st.sum((1, 2)), m.sum((1, 2)))
    np.testing.assert_array_equal(st & m[::-1], m & m[::-1])
    with pytest.raises(IndexError):
        st[6]
    with pytest.raises(AttributeError):
        st.no_such_attribute  # noqa: B018


def test_only_the_box_is_kept_and_a_given_box_is_used():
    m = np.zeros((3, 480, 640), bool)
    m[:, 100:300, 200:260] = True
    st = MaskStack.from_masks(m)
    assert st.nbytes < m.nbytes / 50
    assert st.boxes.tolist() == [[100, 300, 200, 260]] * 3
    loose = MaskStack(m.shape[1:])
    loose.append(m[0], (90, 310, 190, 270))  # a box with a margin holds the same mask
    np.testing.assert_array_equal(loose[0], m[0])
    with pytest.raises(ValueError, match="mask in a stack"):
        loose.append(np.zeros((5, 5), bool))


def test_stored_arrays_pickle_extend_and_npz_round_trip(tmp_path):
    m = _masks(1)
    st = MaskStack.from_masks(m[:3])
    st.extend(MaskStack.from_masks(m[3:]))
    np.testing.assert_array_equal(np.asarray(st), m)
    back = MaskStack.from_arrays(**st.to_arrays())
    np.testing.assert_array_equal(np.asarray(back), m)
    np.testing.assert_array_equal(np.asarray(pickle.loads(pickle.dumps(st))), m)
    arrays = st.to_arrays()
    arrays["mask_sizes"] = arrays["mask_sizes"][:-1]
    with pytest.raises(ValueError, match="do not agree"):
        MaskStack.from_arrays(**arrays)
    # written into an .npz frame by frame, read back as an ordinary array
    savez_atomic(tmp_path / "m.npz", masks=st, other=np.arange(4))
    with np.load(tmp_path / "m.npz") as z:
        assert z["masks"].dtype == bool
        np.testing.assert_array_equal(z["masks"], m)
        np.testing.assert_array_equal(z["other"], np.arange(4))
    assert MaskStack.from_masks([], shape=(4, 5)).shape == (0, 4, 5)


def test_masks_read_from_an_npz_frame_by_frame(tmp_path):
    from vidcap.video.masks import read_npz_masks

    m = _masks(2)
    np.savez_compressed(tmp_path / "a.npz", masks=m, other=np.arange(3))
    np.testing.assert_array_equal(np.asarray(read_npz_masks(tmp_path / "a.npz")), m)
    # 0/1 integers and Fortran order read as the same masks
    np.savez(tmp_path / "b.npz", masks=np.asfortranarray(m.astype(np.uint8)))
    np.testing.assert_array_equal(np.asarray(read_npz_masks(tmp_path / "b.npz")), m)
    with pytest.raises(KeyError):
        read_npz_masks(tmp_path / "a.npz", key="nope")
    np.savez(tmp_path / "c.npz", masks=m[0])
    with pytest.raises(ValueError, match="frames, height, width"):
        read_npz_masks(tmp_path / "c.npz")
