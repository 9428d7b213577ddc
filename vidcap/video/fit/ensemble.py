"""The 2D fit as the median of fits on silhouettes changed by one pixel at the outline.

Why: the tracked fit turns on a few boundary pixels. On masks eroded or dilated by one
pixel its PCK moves by up to 10 points on a clip (RESULTS.md, "the fit's swing on small
mask changes"): the greedy search picks between poses a few pixels apart, and a track,
once formed, holds that pick for a stretch. Fits on several such masks take their wrong
turns at different frames and in different limbs, so each joint's median over them is
right wherever most of them are (bagging, with the outline's own uncertainty as the
resampling). The members are the masks as given, eroded and dilated by a 3x3 cross, and
then masks with a quarter of the pixels either side of the outline flipped, each frame's
draw seeded by its own pixels so that a chunked fit (:mod:`vidcap.video.fit.parallel`)
draws what a serial one does.

Every member is a whole :func:`~vidcap.video.fit.tracking.fit_sequence`; ``ensemble``
members cost that many fits. The frame's cues use one colour model for all members,
learned once from the masks as given.
"""

from __future__ import annotations

import warnings
import zlib

import cv2
import numpy as np

from vidcap.body import LIMB_PAIR_JOINTS, SEGMENT_NAMES
from vidcap.video.fit.cueframes import as_frame_crops
from vidcap.video.fit.result import Pose2D
from vidcap.video.fit.tracking import fit_sequence, sequence_colours
from vidcap.video.masks import MaskStack

#: The members' mask changes, in the order an ``ensemble`` of N takes the first N:
#: the masks as given first (the names of the limb pairs follow its fit).
MEMBERS = ("as_given", "erode", "dilate", "edge0", "edge1")

#: ``edgeN`` members: the share of the pixels on either side of the outline flipped.
EDGE_SHARE = 0.25

_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))

# each limb pair's joints and segments, (left, right)
_PAIR_JOINTS = tuple(LIMB_PAIR_JOINTS[p] for p in ("arms", "legs"))
_PAIR_SEGMENTS = tuple(
    ([SEGMENT_NAMES.index(f"l_{s}") for s in parts], [SEGMENT_NAMES.index(f"r_{s}") for s in parts])
    for parts in (("upper_arm", "lower_arm"), ("upper_leg", "lower_leg")))


def member_count(ensemble) -> int:
    """``ensemble`` as a number of members: a whole number (an ``int``, a NumPy integer
    or its text) from 1 to ``len(MEMBERS)``.

    Raises
    ------
    ValueError
        Otherwise (a bool, a fraction, text that is no whole number, out of range);
        the message names the value: ``ensemble must be a whole number from 1 to 5, got X``.
    """
    from operator import index

    try:
        n = int(ensemble) if isinstance(ensemble, str) else index(ensemble)
    except (TypeError, ValueError):
        n = None
    if n is None or isinstance(ensemble, bool) or not 1 <= n <= len(MEMBERS):
        raise ValueError(f"ensemble must be a whole number from 1 to {len(MEMBERS)}, "
                         f"got {ensemble}")
    return n


def changed_mask(mask: np.ndarray, how: str, share: float = EDGE_SHARE) -> np.ndarray:
    """One silhouette changed by one pixel at its outline.

    Parameters
    ----------
    mask : numpy.ndarray, shape (H, W), bool
    how : str
        One of :data:`MEMBERS`: ``'as_given'``; ``'erode'`` / ``'dilate'`` by a 3x3
        cross; ``'edgeN'``: ``share`` of the pixels the cross would erode or add flipped,
        drawn by a :class:`numpy.random.Generator` seeded by ``N`` and the silhouette's
        own pixels (the same frame gets the same draw wherever it is fitted, in a whole
        frame or in a crop).

    Returns
    -------
    numpy.ndarray, shape (H, W), bool
    """
    mask = np.asarray(mask, bool)
    if how == "as_given" or not mask.any():
        return mask
    m8 = mask.view(np.uint8)
    if how == "erode":
        return cv2.erode(m8, _CROSS).view(bool)
    if how == "dilate":
        return cv2.dilate(m8, _CROSS).view(bool)
    if not how.startswith("edge"):
        raise ValueError(f"unknown mask change {how!r}; expected one of {MEMBERS}")
    band = cv2.dilate(m8, _CROSS).view(bool) & ~cv2.erode(m8, _CROSS).view(bool)
    ys, xs = np.nonzero(band)
    # seeded by the silhouette's own shape, not where it lies in the array: a full frame,
    # a chunk's crop or a padded crop of the same frame get the same draw
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    tight = mask[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]
    seed = [int(how[4:]), *tight.shape, zlib.crc32(np.packbits(tight).tobytes())]
    flip = np.random.default_rng(seed).random(ys.size) < share
    out = mask.copy()
    out[ys[flip], xs[flip]] ^= True
    return out


def changed_masks(masks, how: str) -> MaskStack:
    """Every frame of ``masks`` (F, H, W) changed by :func:`changed_mask`, as a
    :class:`~vidcap.video.masks.MaskStack` (each frame's crop changed with a one-pixel
    margin: dilation may grow it by one pixel)."""
    shape = masks.frame_shape if isinstance(masks, MaskStack) else np.shape(masks)[1:]
    out = MaskStack(shape)
    h, w = shape
    for k in range(len(masks)):
        if isinstance(masks, MaskStack):
            crop, (y0, x0) = masks.crop(k)
        else:
            crop, (y0, x0) = np.asarray(masks[k], bool), (0, 0)
        if not crop.size or not crop.any():
            out.append(np.zeros(shape, bool), box=(0, 0, 0, 0))
            continue
        # a one-pixel frame round the crop (clipped at the image's border) for dilation
        a, b = max(y0 - 1, 0), min(y0 + crop.shape[0] + 1, h)
        c, d = max(x0 - 1, 0), min(x0 + crop.shape[1] + 1, w)
        padded = np.zeros((b - a, d - c), bool)
        padded[y0 - a:y0 - a + crop.shape[0], x0 - c:x0 - c + crop.shape[1]] = crop
        full = np.zeros(shape, bool)
        full[a:b, c:d] = changed_mask(padded, how)
        out.append(full)
    return out


def _aligned(pose: Pose2D, ref: np.ndarray) -> dict[str, np.ndarray]:
    """``pose``'s arrays with each limb pair's names swapped, per frame, where the
    swapped pair lies nearer ``ref`` (F, 15, 2) joints."""
    arrays = {k: np.array(v) for k, v in pose.arrays().items()
              if k in ("joints2d", "angles", "foreshortening", "scores", "margins")}
    j = arrays["joints2d"]
    for (a, b), (sa, sb) in zip(_PAIR_JOINTS, _PAIR_SEGMENTS, strict=True):
        both, crossed = list(a) + list(b), list(b) + list(a)
        kept = np.nansum(np.linalg.norm(j[:, both] - ref[:, both], axis=-1), axis=1)
        swapped = np.nansum(np.linalg.norm(j[:, crossed] - ref[:, both], axis=-1), axis=1)
        swap = swapped < kept
        j[np.ix_(swap, both)] = j[np.ix_(swap, crossed)]
        seg_both, seg_crossed = list(sa) + list(sb), list(sb) + list(sa)
        for key in ("angles", "foreshortening", "scores", "margins"):
            v = arrays[key]
            v[np.ix_(swap, seg_both)] = v[np.ix_(swap, seg_crossed)]
    return arrays


def combine(poses: list[Pose2D]) -> Pose2D:
    """The members' fits as one: each joint the median of the members' (limb pairs
    named as the first member names them, per frame).

    Parameters
    ----------
    poses : list of Pose2D
        Fits of the same clip; the first sets the limb pairs' names.

    Returns
    -------
    Pose2D
        ``joints2d`` (F, 15, 2) px: the per-joint median (NaN where every member has
        none). The per-segment and per-frame arrays (angles, foreshortening, scores,
        margins, similarity, warm) are those of the member whose joints lie nearest the
        median in that frame: a fit the image supports, not a blend of angles. The
        torso's ``spread`` and the ``model_height``, the two numbers per frame the 3D
        solve reads beside the joints, are the members' medians like the joints: the
        nearest member changes from frame to frame, and its spread jumped with it
        (onebyone_room's tuning visits, ``pose2d_real.py --ensemble 5``).
    """
    if len(poses) == 1:
        return poses[0]
    ref = poses[0].joints2d
    members = [_aligned(p, ref) for p in poses]
    joints = np.stack([m["joints2d"] for m in members])  # (M, F, 15, 2)
    with warnings.catch_warnings():  # frames without a silhouette: NaN in every member
        warnings.simplefilter("ignore", RuntimeWarning)
        median = np.nanmedian(joints, axis=0)
        off = np.nanmean(np.linalg.norm(joints - median, axis=-1), axis=-1)  # (M, F)
    nearest = np.argmin(np.nan_to_num(off, nan=np.inf), axis=0)
    frames = np.arange(len(ref))

    def pick(values: np.ndarray) -> np.ndarray:
        return values[nearest, frames]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        spread = np.nanmedian(np.stack([p.spread for p in poses]), axis=0)
        heights = None if poses[0].model_height is None else np.nanmedian(
            np.stack([p.model_height for p in poses]), axis=0)
    return Pose2D(poses[0].joint_names, median,
                  *(pick(np.stack([m[k] for m in members]))
                    for k in ("angles", "foreshortening", "scores", "margins")),
                  spread,
                  pick(np.stack([p.similarity for p in poses])),
                  pick(np.stack([p.warm for p in poses])), poses[0].tracked,
                  model_height=heights)


def fit_ensemble(masks, *, ensemble: int = 1, progress=None, frames=None,
                 cues: str = "all", colours=None, **kw) -> Pose2D:
    """:func:`~vidcap.video.fit.tracking.fit_sequence` on ``ensemble`` versions of the
    masks (:data:`MEMBERS`), joined by :func:`combine`.

    Parameters
    ----------
    masks : numpy.ndarray, shape (F, H, W), bool, or MaskStack
    ensemble : int
        Members, 1 to ``len(MEMBERS)``; 1 is ``fit_sequence`` itself.
    progress : callable, optional
        As ``fit_sequence``'s, called once for the clip's F frames: the members run one
        after another, and member i advances it over the i-th N-th of the frames
        (:func:`_shared_progress`).
    frames, cues, colours, **kw
        As ``fit_sequence``'s; with the frame's cues the colour model is learned once,
        from the masks as given, and shared by every member.

    Returns
    -------
    Pose2D

    Raises
    ------
    ValueError
        If ``ensemble`` is no whole number from 1 to ``len(MEMBERS)``
        (:func:`member_count`), or as ``fit_sequence``.
    """
    ensemble = member_count(ensemble)
    if ensemble == 1:
        return fit_sequence(masks, progress=progress, frames=frames, cues=cues,
                            colours=colours, **kw)
    if frames is not None:  # cut round the masks as given, once: a dilated crop may be a
        # pixel wider, and cue_image repeats a crop's border beyond it
        frames = as_frame_crops(frames, masks, height=kw.get("height", 80))
    if frames is not None and cues == "all" and colours is None:
        colours = sequence_colours(masks, frames, **kw)
    poses, bar = [], None if progress is None else iter(progress(range(len(masks)),
                                                                  total=len(masks)))
    for i, how in enumerate(MEMBERS[:ensemble]):
        member = masks if how == "as_given" else changed_masks(masks, how)
        poses.append(fit_sequence(member, progress=_shared_progress(bar, i, ensemble),
                                  frames=frames, cues=cues, colours=colours, **kw))
    for _ in bar or ():  # let the bar finish (a frame no member iterated: none)
        pass
    return combine(poses)


def _shared_progress(bar, i: int, n: int):
    """``fit_sequence``'s ``progress`` for member ``i`` of ``n``: its frames pass
    through unchanged, and those in the i-th n-th of the clip advance ``bar`` (an
    iterator over the clip's frames made by the caller's ``progress``): one bar over
    all members, each frame reported once, in order. None without a bar."""
    if bar is None:
        return None

    def wrap(frames, total):
        lo, hi = i * total // n, (i + 1) * total // n
        for k in frames:
            if lo <= k < hi:
                next(bar, None)
            yield k

    return wrap


__all__ = ["EDGE_SHARE", "MEMBERS", "changed_mask", "changed_masks", "combine", "fit_ensemble",
           "member_count"]
