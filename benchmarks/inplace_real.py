"""Real bodies walking in place: a real clip's walker moved back to one spot in every
frame (``silhouettes_real.py`` rows "... in place (real body)").

Why: the independent checks run on Weizmann action clips, most of them in place (jumping
jacks, waving, bending, jumping on the spot): a torso that never leaves its pixels, at
180x144. The project may not use those clips, and its in-place evidence so far was
renders of its own cylinder bodies. A real walker with the dataset's own masks, shifted
each frame so that the torso stays where it is, is a real body (clothes, blur, noise,
the camera's colours) in a real scene whose torso never uncovers the wall behind it,
with exact truth: the shifted mask.

How, per frame k: the walker, with the blobs of change from the clip's median frame that
touch it (a shadow), is filled, pixel by pixel, from the nearest frame that shows that
pixel clear (real pixels of the same camera, so noise and light stay real); then the walker's masked
pixels are pasted with the torso's smoothed column moved to the frame's centre. What is
not real: the walker's legs still swing as in a walk, the pasted body casts no shadow at
its new place, and a border pixel the dataset's mask leaves out stays behind (hidden in
the filled hole). Clips shorter than :data:`MIN_FRAMES` are played forwards and back.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Frames of an in-place clip at least (Weizmann's in-place clips: 2-4 s at 25 fps).
MIN_FRAMES = 80
#: Frames over which the torso's column is averaged: what remains after subtracting
#: the average is the walker's own sway.
SMOOTH_FRAMES = 15
#: Pixels round the dataset's mask also filled from another frame.
MARGIN_PX = 3
#: Blobs of change this near the walker (body heights) are the walker's: a low sun's
#: shadow of the legs is a streak that starts up to a third of the height from the feet.
NEAR = 0.4
#: Change from the clip's median frame (max over channels, 0-255) taken as the walker's
#: (or its shadow's) where it touches the mask.
CHANGE = 20


def _torso_column(mask: np.ndarray) -> float:
    """The mean column of the torso (the rows from 15 to 50 % of the body's height
    down) of one mask (H, W) bool that holds the walker."""
    ys, xs = np.nonzero(mask)
    top, height = ys.min(), np.ptp(ys) + 1
    torso = (ys >= top + 0.15 * height) & (ys <= top + 0.5 * height)
    return float(xs[torso].mean() if torso.any() else xs.mean())


def _shift_columns(a: np.ndarray, dx: int) -> np.ndarray:
    """``a`` (H, W, ...) moved ``dx`` columns right, the uncovered columns zero."""
    out = np.zeros_like(a)
    if dx >= 0:
        out[:, dx:] = a[:, :a.shape[1] - dx]
    else:
        out[:, :dx] = a[:, -dx:]
    return out


def _usable(masks: np.ndarray) -> np.ndarray:
    """(F,) bool: frames whose walker is whole (not cut by the left or right edge, at
    least 0.8 of the median height)."""
    width = masks.shape[2]
    seen = masks.any(axis=(1, 2))
    heights = np.array([np.ptp(np.nonzero(m.any(axis=1))[0]) + 1 if s else 0
                        for m, s in zip(masks, seen, strict=True)])
    cols = masks.any(axis=1)
    inside = ~cols[:, :2].any(1) & ~cols[:, width - 2:].any(1)
    return seen & inside & (heights >= 0.8 * np.median(heights[seen]))


def _walker_holes(frames: np.ndarray, masks: np.ndarray) -> np.ndarray:
    """(F, H, W) bool: per frame, the walker's mask widened by :data:`MARGIN_PX` and every
    blob of change from the clip's median frame within :data:`NEAR` of it (a shadow, a
    bag, a border pixel the mask leaves out)."""
    import cv2

    median = np.median(frames[:: max(1, len(frames) // 60)], axis=0).astype(np.int16)
    grow = np.ones((2 * MARGIN_PX + 1,) * 2, np.uint8)
    out = np.zeros(masks.shape, bool)
    for k, (frame, mask) in enumerate(zip(frames, masks, strict=True)):
        if not mask.any():
            continue
        change = (np.abs(frame.astype(np.int16) - median).max(axis=2) > CHANGE).astype(np.uint8)
        body = cv2.dilate(mask.astype(np.uint8), grow)
        reach = int(NEAR * np.ptp(np.nonzero(mask.any(axis=1))[0]))
        near = cv2.dilate(mask.astype(np.uint8), np.ones((2 * reach + 1,) * 2, np.uint8))
        _, labels = cv2.connectedComponents(cv2.dilate(change, np.ones((3, 3), np.uint8)))
        touching = np.unique(labels[(near > 0) & (labels > 0)])
        out[k] = (body > 0) | np.isin(labels, touching[touching > 0])
    return out


def _fill_sources(holes: np.ndarray, k: int):
    """The pixels of frame ``k``'s hole (a tuple of row and column indices) and, per
    pixel, the nearest frame in time whose hole leaves it clear (or None when some
    pixel is clear in no frame)."""
    n = len(holes)
    at = np.nonzero(holes[k])
    distance = np.where(holes[:, at[0], at[1]], n + 1, np.abs(np.arange(n) - k)[:, None])
    nearest = distance.argmin(axis=0)
    if (distance[nearest, np.arange(len(nearest))] > n).any():
        return at, None
    return at, nearest


def _longest_run(ok: np.ndarray) -> tuple[int, int]:
    best, start = (0, 0), None
    for i, v in enumerate(np.append(ok, False)):
        if v and start is None:
            start = i
        elif not v and start is not None:
            best = max(best, (start, i), key=lambda r: r[1] - r[0])
            start = None
    return best


def walk_in_place(frames: np.ndarray, masks: np.ndarray, ignore: np.ndarray | None = None):
    """The walker of a real clip kept in place.

    Parameters
    ----------
    frames : numpy.ndarray, shape (F, H, W, 3), uint8
        The clip, one walker crossing a fixed camera's view.
    masks : numpy.ndarray, shape (F, H, W), bool
        The dataset's masks of the walker.
    ignore : numpy.ndarray, shape (F, H, W), bool, optional
        Pixels the dataset leaves unscored (the walker's blurred border).

    Returns
    -------
    frames, truth, ignore : numpy.ndarray
        The in-place clip (F', H, W, 3) uint8, its masks and unscored pixels (F', H, W)
        bool, F' >= :data:`MIN_FRAMES` (played forwards and back when the walk is
        shorter).

    Raises
    ------
    ValueError
        Fewer than 10 consecutive frames show the whole walker with a hole that other
        frames fill.
    """
    n, h, w = masks.shape
    ignore = np.zeros_like(masks) if ignore is None else ignore
    seen = masks.any(axis=(1, 2))
    torso = np.full(n, np.nan)
    for k in np.flatnonzero(seen):
        torso[k] = _torso_column(masks[k])
    holes = _walker_holes(frames, masks)
    ok = _usable(masks)
    filled = np.zeros(n, bool)
    for k in np.flatnonzero(ok):
        filled[k] = _fill_sources(holes, k)[1] is not None
    start, stop = _longest_run(ok & filled)
    if stop - start < 10:
        raise ValueError(f"only {stop - start} consecutive frames show the whole walker "
                         "with every pixel of their hole clear in another frame")
    idx = np.arange(start, stop)
    pad = SMOOTH_FRAMES // 2
    track = np.pad(torso[idx], pad, mode="reflect", reflect_type="odd")  # keeps a trend
    smooth = np.convolve(track, np.ones(SMOOTH_FRAMES) / SMOOTH_FRAMES, mode="valid")
    out_f, out_t, out_i = [], [], []
    for k, centre in zip(idx, smooth, strict=True):
        frame = frames[k].copy()
        at, source = _fill_sources(holes, k)
        frame[at] = frames[source, at[0], at[1]]
        dx = int(round(w / 2 - centre))
        body = _shift_columns(masks[k], dx)
        edge = _shift_columns(ignore[k] & ~masks[k], dx)  # the blurred border comes along
        paste = body | edge
        frame[paste] = _shift_columns(frames[k], dx)[paste]
        out_f.append(frame)
        out_t.append(body)
        out_i.append(edge)
    forwards = list(range(len(out_f)))
    order = forwards[:]
    while len(order) < MIN_FRAMES:  # forwards and back
        order += forwards[-2::-1] if order[-1] == forwards[-1] else forwards[1:]
    order = order[:max(MIN_FRAMES, len(out_f))]
    return (np.stack(out_f)[order], np.stack(out_t)[order], np.stack(out_i)[order])


def inplace_clip(video: Path, masks: np.ndarray, ignore: np.ndarray | None,
                 out_dir: Path):
    """:func:`walk_in_place` of a clip, the video written to ``out_dir`` (H.264 crf 18,
    the clip's frame rate) and reused.

    Returns
    -------
    (pathlib.Path, numpy.ndarray, numpy.ndarray)
        The in-place video, its truth and its unscored pixels, (F', H, W) bool.
    """
    from vidcap.io.video import probe, read_frames, write_video

    out = out_dir / f"{video.stem}_in_place.mp4"
    truth_file = out.with_suffix(".truth.npz")
    if out.exists() and truth_file.exists():
        with np.load(truth_file) as z:
            return out, z["masks"], z["ignore"]
    frames, truth, unscored = walk_in_place(read_frames(video)[:len(masks)], masks, ignore)
    write_video(out, iter(frames), probe(video).fps, crf=18)
    np.savez_compressed(truth_file, masks=truth, ignore=unscored)
    return out, truth, unscored
