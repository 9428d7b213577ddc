"""A video's silhouettes kept small: each frame's bounding box, bit-packed.

A full (F, H, W) bool stack costs one byte per pixel and frame: 2 GB a minute of
1080p at 30 fps. The person covers a small box of the frame, so
:class:`MaskStack` keeps only that box of each frame, eight pixels to a byte
(typically 50-100x smaller), and hands out full frames one at a time. It stands in
for the (F, H, W) array wherever frames are read one by one (``len``, ``stack[k]``,
slices, ``shape``); ``numpy.asarray(stack)``, numpy operators and the other array
methods build the whole array, for short clips (tests, benchmarks, scripts).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np


class MaskStack(Sequence):
    """Silhouettes (F, H, W) bool, stored as each frame's bounding-box crop.

    Parameters
    ----------
    shape : (int, int)
        Frame height and width, pixels.
    boxes : numpy.ndarray, shape (F, 4), int
        ``y0, y1, x0, x1`` of each frame's crop (empty, ``y0 == y1``, for a frame
        without any pixel set).
    bits : list of numpy.ndarray
        Each crop, ``numpy.packbits(crop, axis=-1)``, shape (y1 - y0, ceil((x1 - x0) / 8)).
    """

    dtype = np.dtype(bool)
    ndim = 3

    def __init__(self, shape, boxes=None, bits=None):
        self.frame_shape = (int(shape[0]), int(shape[1]))
        # one (y0, y1, x0, x1) tuple per frame: appending a frame is O(1)
        self._boxes = ([] if boxes is None
                       else [tuple(int(v) for v in b) for b in np.reshape(boxes, (-1, 4))])
        self._boxes_array = None  # ``boxes``, built when asked for
        self.bits = [] if bits is None else list(bits)
        if len(self.bits) != len(self._boxes):
            raise ValueError(f"{len(self._boxes)} boxes but {len(self.bits)} crops")

    # -- building -----------------------------------------------------------------
    @classmethod
    def from_masks(cls, masks: Iterable[np.ndarray], shape=None) -> MaskStack:
        """A stack of full-frame masks, each (H, W) (``shape``: for no masks at all)."""
        out = None if shape is None else cls(shape)
        for m in masks:
            m = np.asarray(m, dtype=bool)
            if out is None:
                out = cls(m.shape)
            out.append(m)
        if out is None:
            raise ValueError("no masks and no frame shape")
        return out

    def append(self, mask: np.ndarray, box=None) -> None:
        """Add one frame's full (H, W) mask; ``box`` (``y0, y1, x0, x1``), when known,
        must hold every set pixel (it saves finding it)."""
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != self.frame_shape:
            raise ValueError(f"a {mask.shape} mask in a stack of {self.frame_shape} frames")
        if box is None:
            rows = np.flatnonzero(mask.any(axis=1))
            if rows.size:
                cols = np.flatnonzero(mask[rows[0]:rows[-1] + 1].any(axis=0))
                box = (rows[0], rows[-1] + 1, cols[0], cols[-1] + 1)
            else:
                box = (0, 0, 0, 0)
        y0, y1, x0, x1 = (int(v) for v in box)
        self._boxes.append((y0, y1, x0, x1))
        self._boxes_array = None
        self.bits.append(np.packbits(mask[y0:y1, x0:x1], axis=-1))

    def extend(self, other: MaskStack) -> None:
        """Append every frame of another stack of the same frame size."""
        if other.frame_shape != self.frame_shape:
            raise ValueError(f"{other.frame_shape} frames added to {self.frame_shape} ones")
        self._boxes.extend(other._boxes)
        self._boxes_array = None
        self.bits.extend(other.bits)

    # -- reading --------------------------------------------------------------------
    @property
    def boxes(self) -> np.ndarray:
        """(F, 4) int64: ``y0, y1, x0, x1`` of each frame's crop."""
        if self._boxes_array is None or len(self._boxes_array) != len(self._boxes):
            self._boxes_array = np.array(self._boxes, np.int64).reshape(-1, 4)
        return self._boxes_array

    @property
    def shape(self) -> tuple[int, int, int]:
        return (len(self._boxes), *self.frame_shape)

    @property
    def nbytes(self) -> int:
        """Bytes held by the crops (what the full stack would take: ``numpy.prod(shape)``)."""
        return int(sum(b.nbytes for b in self.bits) + 32 * len(self._boxes))

    def __len__(self) -> int:
        return len(self._boxes)

    def crop(self, k: int) -> tuple[np.ndarray, tuple[int, int]]:
        """Frame ``k``'s crop (h, w) bool and its top-left corner ``(y0, x0)``."""
        y0, y1, x0, x1 = self._boxes[k]
        crop = np.unpackbits(self.bits[k], axis=-1, count=x1 - x0).view(bool)
        return crop.reshape(y1 - y0, x1 - x0), (y0, x0)

    def __getitem__(self, key):
        if isinstance(key, tuple) and key:  # (frames, rows, columns): only those frames
            first, rest = key[0], key[1:]
            if isinstance(first, (int, np.integer)):
                return self[first][rest]
            if isinstance(first, slice):
                return np.asarray(self[first])[(slice(None), *rest)]
            return np.asarray(self)[key]
        if isinstance(key, slice):
            idx = range(len(self))[key]
            out = MaskStack(self.frame_shape)
            out._boxes = self._boxes[key]
            out.bits = [self.bits[i] for i in idx]
            return out
        if isinstance(key, (int, np.integer)):
            k = int(key)
            if not -len(self) <= k < len(self):
                raise IndexError(f"frame {k} of a stack of {len(self)}")
            out = np.zeros(self.frame_shape, bool)
            self._paste(k % len(self), out)
            return out
        raise TypeError(f"MaskStack indices are frames or slices, not {type(key).__name__}")

    def __getattr__(self, name):
        # the rest of numpy's array interface (``.sum``, ``.mean``, ``.astype`` ...)
        # works on the full array, built for the call: fine for short clips only
        if name.startswith("_") or not hasattr(np.ndarray, name):
            raise AttributeError(f"'MaskStack' object has no attribute '{name}'")
        return getattr(np.asarray(self), name)

    def any_per_frame(self) -> np.ndarray:
        """(F,) bool: which frames have any pixel set."""
        b = self.boxes
        return (b[:, 1] > b[:, 0]) & (b[:, 3] > b[:, 2]) & np.array(
            [bool(x.any()) for x in self.bits], bool)

    def __array__(self, dtype=None, copy=None):
        out = np.zeros(self.shape, bool)
        for k in range(len(self)):
            self._paste(k, out[k])
        return out if dtype is None else out.astype(dtype, copy=False)

    def _paste(self, k: int, frame: np.ndarray) -> None:
        """Set frame ``k``'s pixels in ``frame`` (H, W), which is all False."""
        crop, (y0, x0) = self.crop(k)
        frame[y0:y0 + crop.shape[0], x0:x0 + crop.shape[1]] = crop

    # -- storing ----------------------------------------------------------------------
    def to_arrays(self) -> dict[str, np.ndarray]:
        """The stack as four flat arrays (for an ``.npz``): see :meth:`from_arrays`."""
        sizes = np.array([b.size for b in self.bits], np.int64)
        flat = (np.concatenate([b.reshape(-1) for b in self.bits]) if self.bits
                else np.zeros(0, np.uint8))
        return {"mask_shape": np.array(self.frame_shape, np.int64),
                "mask_boxes": self.boxes.copy(), "mask_bits": flat, "mask_sizes": sizes}

    @classmethod
    def from_arrays(cls, mask_shape, mask_boxes, mask_bits, mask_sizes) -> MaskStack:
        """Inverse of :meth:`to_arrays`."""
        boxes = np.asarray(mask_boxes, np.int64).reshape(-1, 4)
        sizes = np.asarray(mask_sizes, np.int64)
        flat = np.asarray(mask_bits, np.uint8)
        if len(sizes) != len(boxes) or sizes.sum() != flat.size:
            raise ValueError("mask arrays do not agree")
        ends = np.cumsum(sizes)
        bits = []
        for (y0, y1, x0, x1), a, b in zip(boxes, ends - sizes, ends, strict=True):
            bits.append(flat[a:b].reshape(y1 - y0, (x1 - x0 + 7) // 8))
        return cls(tuple(np.asarray(mask_shape).tolist()), boxes, bits)


def read_npz_masks(path, key: str = "masks") -> MaskStack:
    """Read an (F, H, W) array of an ``.npz`` file as a :class:`MaskStack`, one frame
    at a time (the whole array is never in memory); nonzero is set.

    Raises
    ------
    KeyError
        The file has no array ``key``.
    ValueError
        The array is not 3-D, or is not a plain numeric array.
    OSError, zipfile.BadZipFile
        The file cannot be read.
    """
    import zipfile

    from numpy.lib import format as npy

    with zipfile.ZipFile(path) as zf:
        name = f"{key}.npy"
        if name not in zf.namelist():
            raise KeyError(key)
        with zf.open(name) as fh:
            version = npy.read_magic(fh)
            shape, fortran, dtype = (npy.read_array_header_1_0(fh) if version == (1, 0)
                                     else npy.read_array_header_2_0(fh))
            if len(shape) != 3:
                raise ValueError(f"'{key}' must be (frames, height, width), got {shape}")
            if dtype.kind not in "biuf" or dtype.hasobject:
                raise ValueError(f"'{key}' holds {dtype}, not numbers")
            out = MaskStack(shape[1:])
            if fortran:  # frames are not contiguous in the file: read it whole
                with np.load(path, allow_pickle=False) as z:
                    for frame in z[key]:
                        out.append(frame != 0)
                return out
            size = shape[1] * shape[2]
            for k in range(shape[0]):
                buf = fh.read(size * dtype.itemsize)
                if len(buf) != size * dtype.itemsize:
                    raise ValueError(f"'{key}' ends after {k} of its {shape[0]} frames")
                out.append(np.frombuffer(buf, dtype).reshape(shape[1:]) != 0)
    return out


def mask_frames(masks) -> Sequence:
    """``masks`` as something read frame by frame: a :class:`MaskStack` stays one, a
    list of frames stays a list, anything else becomes a bool array (F, H, W)."""
    if isinstance(masks, (MaskStack, list)):
        return masks
    return np.asarray(masks, dtype=bool)


def pixel_counts(masks) -> np.ndarray:
    """(F,) int64: set pixels per frame of a stack or an (F, H, W) array."""
    if isinstance(masks, MaskStack):
        return np.array([int(np.bitwise_count(b).sum()) for b in masks.bits], np.int64)
    return np.asarray(masks, dtype=bool).reshape(len(masks), -1).sum(axis=1)


def edges_reached(masks) -> np.ndarray:
    """Which of the picture's edges each frame's mask reaches.

    Parameters
    ----------
    masks : MaskStack or numpy.ndarray, shape (F, H, W) bool

    Returns
    -------
    numpy.ndarray of bool, shape (F, 4)
        The mask has a pixel on the first row, the last row, the first column, the last
        column (top, bottom, left, right); all False for an empty frame.
    """
    if isinstance(masks, MaskStack):
        b = masks.boxes
        h, w = masks.frame_shape
        full = (b[:, 1] > b[:, 0]) & (b[:, 3] > b[:, 2])
        return full[:, None] & np.stack(
            [b[:, 0] == 0, b[:, 1] == h, b[:, 2] == 0, b[:, 3] == w], axis=1)
    m = np.asarray(masks, dtype=bool)
    return np.stack([m[:, 0].any(-1), m[:, -1].any(-1), m[:, :, 0].any(-1),
                     m[:, :, -1].any(-1)], axis=1)


def touches_border(masks) -> np.ndarray:
    """(F,) bool: frames whose mask reaches the first or last row or column."""
    return edges_reached(masks).any(axis=1)


def frames_with_pixels(masks) -> np.ndarray:
    """(F,) bool: which frames of a stack, an (F, H, W) array or a sequence of (H, W)
    masks have any pixel set (a sequence frame by frame: not stacked into one array)."""
    if isinstance(masks, MaskStack):
        return masks.any_per_frame()
    if not isinstance(masks, np.ndarray):
        return np.array([bool(np.asarray(m).any()) for m in masks], bool)
    return np.asarray(masks, dtype=bool).reshape(len(masks), -1).any(axis=1)


def centroid_columns(fg: np.ndarray, min_pixels: int = 16) -> np.ndarray:
    """Column of each sample's foreground centroid, pixels.

    Parameters
    ----------
    fg : (K, H, W) bool
        Foreground of K samples.
    min_pixels : int
        Samples with fewer foreground pixels are left out (their centroid is noise).

    Returns
    -------
    (M,) float
        The centroid's column of the M <= K samples kept, in sample order.
    """
    k, _, w = fg.shape
    n = fg.reshape(k, -1).sum(axis=1)
    ok = n >= min_pixels
    return (fg.sum(axis=1) * np.arange(w)).sum(axis=1)[ok] / n[ok]


__all__ = ["MaskStack", "centroid_columns", "edges_reached", "frames_with_pixels", "mask_frames",
           "pixel_counts", "read_npz_masks", "touches_border"]
