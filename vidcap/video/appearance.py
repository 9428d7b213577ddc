"""The person by appearance where the plate is a guess (issue 26, Build 1-2).

A person who stays in place (jumping jacks, waving, turning on the spot) covers some
pixels in most or all sampled frames. There the vote of
:func:`vidcap.video.background.estimate_background` either keeps the person's colour
(the torso absorbed into the plate) or flags the pixels never seen and inpaints a
guess across a large area, which is wrong where the background is textured: the
silhouettes then take background between the limbs for person.

Temporal evidence cannot settle these pixels; appearance can. A person who covers
the same pixels in every frame still differs from the wall in colour. On the
sampled frames, at a reduced resolution:

1. **Sure person**: pixels that differ from the first plate where that plate was
   seen (not a guess), over the whole clip, and what the samples show inside the
   first plate's never-seen area (a static body part). **Background**: a ring
   round the person's area (round the convex hull of its largest part at first)
   in the samples where it is not foreground, mixed with the whole plate outside.
   A colour histogram of each (BGR quantised to :data:`BINS` levels per channel,
   smoothed) is the colour model.
2. **Uncertain area**: the never-seen area and plate pixels that look like the
   person (a colour seen on it, more likely under its model than under the
   background's) and touch what moved: a static body part the plate absorbed,
   grown a ring's width a round while the ring around it finds more. A grown part that
   lies beside what moved rather than between moving parts (:data:`MIN_BETWEEN`) is
   scene of the person's colours (a door frame, a curtain beside the arm's sweep) and
   is left out.
3. Per sample, in the uncertain area, the log-likelihood ratio person/background
   is smoothed over space (a box filter, the pairwise term of a graph cut done
   cheaply) and over time (neighbouring samples: a limb that is person in sample
   k is likely person in k +- 1); positive is person. In the first plate's
   never-seen area a mildly negative pixel whose colour no seen scene pixel nearby
   shows stays person (:func:`_keep_unlike`: a still head of a colour the scene
   has only far off).
4. The plate is re-taken, in the uncertain area, as the median of the samples in
   which the (dilated) person does not cover the pixel; pixels no sample shows
   uncovered are the honest never-seen map, inpainted from the background around
   them (a ring outside the person, so that the guess is not the person's colour).

Only clips in which the person stays in place are treated (the centroid of what
differs from the plate keeps its place across, see :func:`_in_place`): a walker's
plate saw everything.
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from vidcap.video.masks import centroid_columns
from vidcap.video.regionvote import work_hw

__all__ = ["appearance_plate", "between_moved", "colour_model", "log_ratio",
           "nearest_scene_distance",
           "person_scene_models", "small_samples"]

#: Quantisation levels per colour channel of the colour models.
BINS = 16
#: Long side, pixels, of the working resolution.
WORK_SIZE = 320
#: The person stays in place when the centroid of what differs from the plate keeps
#: within this share of the frame's width in the middle half of the samples.
MAX_TRAVEL = 0.05
#: Share of the person's colour model spread over every colour.
PRIOR_UNSEEN = 0.3
#: Rounds of growing the absorbed area; it may cover at most this share of the
#: frame (more has leaked into the scene).
GROW_STEPS, MAX_SHARE = 3, 0.15
#: The pass is refused when it leaves less than this share of the first never-seen
#: area never seen.
MIN_KEPT_NEVER = 0.5
#: A pixel needs this many samples (and this share) outside the person to be seen.
MIN_SEEN, MIN_SEEN_SHARE = 2, 0.1
#: An absorbed part lies between what moved (:func:`between_moved`): a grown
#: component with less than this share of its pixels between moving parts is scene
#: beside the person (a door frame, a curtain the arm passes; on the pose2sim
#: balance cameras 1 and 4 the grown parts were scene to 99 %, 4-11 % of them
#: between; the absorbed torso of the arms side render 26-100 %).
MIN_BETWEEN = 0.15
#: Inside the first plate's never-seen area, a sample's pixel the colour models call
#: scene by less than this (log ratio, smoothed) stays person when its colour matches
#: no seen plate pixel within the ring's width (L1 at most UNLIKE thresholds): a head
#: that never moves, whose skin is rare in the person's model and common in a brick
#: wall far off, is not the scene around it (:func:`_keep_unlike`). Chosen on the
#: tuning renders (benchmarks/silhouettes_real.py --quick --pck, median IoU and PCK of
#: the 2D fit, true masks in brackets): arms 3/4 0.909 -> 0.938, 61.9 -> 82.0 % (84.4),
#: arms front 0.923 -> 0.961, 82.0 -> 94.2 % (95.0), jacks 3/4 0.923 -> 0.930, 83.6 ->
#: 90.7 % (99.9), 02_06 0.913 -> 0.911, 34.5 -> 31.3 % (43.6). NEVER_KEEP alone (no
#: colour test) cost 02_06 0.045 (the floor beside the feet kept); UNLIKE 5: arms 3/4
#: 80.7 %, arms front 0.925; NEVER_KEEP 1: arms front 89.8 %, 02_06 0.887.
NEVER_KEEP, UNLIKE = 2.0, 3.0
#: The appearance pass's sure person lies this many of the frame's own pixels inside
#: what differed (at least one working pixel): the codec blends the outline's colours
#: over about two frame pixels, and a small frame (Weizmann's 180x144, worked at its
#: own size) kept the blend of dark jeans and a dark skirting board as the person's,
#: which then grew along the board and the table's foot (session 46, the room plate's
#: renders at 180x144). Frames over 426 pixels on the long side are worked at 320,
#: where one working pixel is 1.33 frame pixels or more: unchanged.
SURE_MARGIN_PX = 2
#: When the wider margin keeps less than this share of the one-pixel margin's sure
#: pixels, the person shows only thin limbs (arms waving over a body the plate
#: absorbed: 4-14 % kept on the arms and jacks renders at 180x144, 30-55 % where a
#: body shows) and the one-pixel margin is used.
MIN_MARGIN_KEPT = 0.25


def colour_model(pixels: np.ndarray, *, smooth: float = 1.0,
                 uniform: float = 0.0) -> np.ndarray:
    """Log-probability of each quantised colour, from sample pixels.

    Parameters
    ----------
    pixels : numpy.ndarray, shape (N, 3), uint8 or float
        BGR colours.
    smooth : float
        Gaussian smoothing of the histogram, bins (colours near those seen are
        likely too).
    uniform : float
        Share of the probability spread evenly over all colours.

    Returns
    -------
    numpy.ndarray, shape (BINS**3,), float32
        log P(colour bin), with a floor so that unseen colours are unlikely, not
        impossible.
    """
    q = _quantise(np.asarray(pixels).reshape(-1, 3))
    hist = np.bincount(q, minlength=BINS ** 3).astype(np.float32).reshape((BINS,) * 3)
    if smooth > 0:
        from scipy.ndimage import gaussian_filter

        hist = gaussian_filter(hist, smooth, mode="constant")
    hist = hist.ravel()
    total = max(float(hist.sum()), 1.0)
    p = (1 - uniform) * hist / total + uniform / hist.size
    return np.log(p + 1e-7).astype(np.float32)


def _quantise(x: np.ndarray) -> np.ndarray:
    q = np.clip(np.asarray(x, np.float32) * (BINS / 256.0), 0, BINS - 1).astype(np.int32)
    return (q[..., 0] * BINS + q[..., 1]) * BINS + q[..., 2]


def log_ratio(image: np.ndarray, person: np.ndarray, background: np.ndarray) -> np.ndarray:
    """log P(colour | person) - log P(colour | background) per pixel.

    Parameters
    ----------
    image : numpy.ndarray, shape (..., 3)
        BGR colours.
    person, background : numpy.ndarray, shape (BINS**3,)
        From :func:`colour_model`.

    Returns
    -------
    numpy.ndarray, shape (...), float32
    """
    q = _quantise(image)
    return (person - background)[q]


def _person_blobs(fg: np.ndarray) -> np.ndarray:
    """De-specked foreground, only blobs of at least a fifth of the largest."""
    fg = cv2.morphologyEx(fg.view(np.uint8), cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    n, lab, st, _ = cv2.connectedComponentsWithStats(fg, connectivity=8)
    if n <= 1:
        return fg > 0
    area = st[1:, cv2.CC_STAT_AREA]
    keep = np.concatenate([[False], area >= max(4, 0.2 * area.max())])
    return keep[lab]


def _in_place(fg: np.ndarray) -> bool:
    """Whether the person stays put: the centroid of each sample's foreground keeps
    its place across, the middle half of the samples within :data:`MAX_TRAVEL` of
    the frame's width (a walker's crosses the frame: 0.15-0.21 on the walks
    measured, in-place clips <= 0.005). The middle half, not the whole range: a few
    samples where a lamp's edge or a flicker pulls the centroid do not count."""
    cx = centroid_columns(fg)
    if len(cx) < 2:
        return False
    q25, q75 = np.percentile(cx, [25, 75])
    return bool(q75 - q25 <= MAX_TRAVEL * fg.shape[2])


def _hull(mask: np.ndarray) -> np.ndarray:
    """The mask with the convex hull of its largest 8-connected blob filled in."""
    n, lab, st, _ = cv2.connectedComponentsWithStats(mask.view(np.uint8), connectivity=8)
    if n <= 1:
        return mask
    big = lab == 1 + int(np.argmax(st[1:, cv2.CC_STAT_AREA]))
    pts = cv2.findNonZero(big.view(np.uint8))
    out = mask.view(np.uint8).copy()
    cv2.fillConvexPoly(out, cv2.convexHull(pts), 1)
    return out > 0


def between_moved(moved: np.ndarray) -> np.ndarray:
    """Pixels with ``moved`` on both sides, left and right in their row or above and
    below in their column.

    Parameters
    ----------
    moved : numpy.ndarray, shape (h, w), bool
        What differed from the plate (in a few samples).

    Returns
    -------
    numpy.ndarray, shape (h, w), bool
        True where a part the plate absorbed could lie: a still torso between swinging
        arms, a standing leg between the other leg and the moving trunk. (``moved``
        itself is between.)

    Examples
    --------
    >>> m = np.zeros((3, 5), bool); m[1, 0] = m[1, 4] = True
    >>> between_moved(m).astype(int)
    array([[0, 0, 0, 0, 0],
           [1, 1, 1, 1, 1],
           [0, 0, 0, 0, 0]])
    """
    m = np.asarray(moved, bool)
    left = np.logical_or.accumulate(m, axis=1)
    right = np.logical_or.accumulate(m[:, ::-1], axis=1)[:, ::-1]
    up = np.logical_or.accumulate(m, axis=0)
    down = np.logical_or.accumulate(m[::-1], axis=0)[::-1]
    return (left & right) | (up & down)


def _scene_beside(absorbed: np.ndarray, moved: np.ndarray) -> np.ndarray:
    """``absorbed`` without its connected parts that are not between what moved
    (less than :data:`MIN_BETWEEN` of their pixels :func:`between_moved`)."""
    n, lab = cv2.connectedComponents(absorbed.view(np.uint8), connectivity=8)
    if n <= 1:
        return absorbed
    inside = np.bincount(lab.ravel(), between_moved(moved).ravel(), minlength=n)
    size = np.bincount(lab.ravel(), minlength=n)
    keep = inside >= MIN_BETWEEN * np.maximum(size, 1)
    keep[0] = False
    return keep[lab]


def _smooth(llr: np.ndarray, size: int) -> np.ndarray:
    """Box filter over space per sample, then [1, 2, 1] / 4 over neighbouring samples."""
    sp = np.stack([cv2.blur(x, (size, size)) for x in llr])
    if len(sp) < 3:
        return sp
    out = 0.5 * sp
    out[1:] += 0.25 * sp[:-1]
    out[:-1] += 0.25 * sp[1:]
    out[0] += 0.25 * sp[0]
    out[-1] += 0.25 * sp[-1]
    return out


def small_samples(frames: np.ndarray, gains: np.ndarray,
                  work_size: int = WORK_SIZE) -> np.ndarray:
    """The samples at the plate passes' working resolution.

    The plate's passes (the appearance plate, the absorbed person, the colour models,
    the unseen flags) each work on the same small samples: the plate's orchestration
    (:func:`vidcap.video.background.estimate_background`) makes them once and hands
    them down (``small=``), ~0.1 s of CPU a pass at 1000x1000.

    Parameters
    ----------
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The samples.
    gains : numpy.ndarray, shape (K, 3)
        Their per-channel gains relative to the plate.
    work_size : int
        Long side of the working resolution, pixels.

    Returns
    -------
    numpy.ndarray, shape (K, h, w, 3), float32
        By area averaging, divided by the gains and clipped to 0-255; read only.
    """
    h, w = work_hw(frames.shape[1:3], work_size)
    small = np.stack([cv2.resize(f, (w, h), interpolation=cv2.INTER_AREA) for f in frames])
    small = np.clip(small.astype(np.float32) / gains[:, None, None, :], 0, 255)
    small.flags.writeable = False
    return small


class _Work:
    """The samples at the working resolution and what the first plate says there."""

    def __init__(self, model, frames, gains, work_size, small=None):
        k, hh, ww = frames.shape[:3]
        h, w = work_hw((hh, ww), work_size)
        self.k, self.h, self.w, self.full = k, h, w, (hh, ww)
        # (the orchestration's small samples when they are at this size)
        self.small = (small if small is not None and small.shape == (k, h, w, 3)
                      else small_samples(frames, gains, work_size))
        self.plate = cv2.resize(model.plate, (w, h),
                                interpolation=cv2.INTER_AREA).astype(np.float32)
        self.never = self.down(model.never_seen)
        self.lit = np.zeros((h, w), bool) if model.self_lit is None else self.down(
            model.self_lit)
        self.thr = float(model.threshold)
        # |small - plate| summed over the channels, added in the order NumPy's
        # sum(axis=-1) adds them (the same values; a 3-long axis reduces slowly)
        a = np.abs(self.small - self.plate)
        self.d = a[..., 0] + a[..., 1] + a[..., 2]
        fg = np.stack([_person_blobs(x > self.thr) for x in self.d])
        # (and the lamps' outline: the glow's edge flickers with the exposure)
        fg[:, cv2.dilate(self.lit.view(np.uint8), np.ones((7, 7), np.uint8)) > 0] = False
        self.fg = fg
        self.foot = fg.sum(axis=0) >= 2
        self.med_area = float(np.median(fg.reshape(k, -1).sum(axis=1)))
        self.r = max(1, round(0.01 * max(h, w)))
        self.disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE,
                                              (2 * self.r + 1, 2 * self.r + 1))
        self.ring_r = max(3, round(0.04 * max(h, w)))

    def down(self, mask):
        return cv2.resize(mask.view(np.uint8), (self.w, self.h),
                          interpolation=cv2.INTER_NEAREST) > 0

    def up(self, mask):
        return cv2.resize(mask.view(np.uint8), (self.full[1], self.full[0]),
                          interpolation=cv2.INTER_NEAREST)


def _eroded(masks: np.ndarray, radius: int) -> np.ndarray:
    """Each (h, w) mask of ``masks`` eroded by a square of half-width ``radius``."""
    box = np.ones((2 * radius + 1,) * 2, np.uint8)
    return np.stack([cv2.erode(x.view(np.uint8), box) for x in masks]) > 0


def _person_colours(wk: _Work, margin_px: int = 0) -> np.ndarray | None:
    """Colours sure to be the person, (N, 3): what differs by a margin from a plate
    that was seen, eroded, over all samples; and what the samples show inside the
    first plate's never-seen area (a static body part). ``margin_px``: erode by that
    many frame pixels where that is more than one working pixel and keeps at least
    :data:`MIN_MARGIN_KEPT` of what one keeps (0: one working pixel)."""
    never_wide = cv2.dilate(wk.never.view(np.uint8), wk.disk, iterations=2) > 0
    sure = (wk.d > 2 * wk.thr) & wk.fg & ~never_wide[None]
    radius = round(margin_px * wk.w / wk.full[1])  # the margin in working pixels
    narrow = _eroded(sure, 1)
    if radius > 1 and (deep := _eroded(sure, radius)).sum() >= MIN_MARGIN_KEPT * narrow.sum():
        narrow = deep
    sure = narrow
    if sure.sum() < 50:
        return None
    px = wk.small[sure]
    core = cv2.erode(wk.never.view(np.uint8), wk.disk) > 0
    if core.any():
        px = np.concatenate([px, wk.small[:, core].reshape(-1, 3)])
    return px


def _scene_model(wk: _Work, core: np.ndarray, hull: bool = False) -> np.ndarray | None:
    """The background's colour model: a ring around ``core`` in the samples where
    it is not foreground, mixed half and half with the whole plate outside it."""
    if hull:
        # The first model goes round the convex hull of the person's largest part:
        # a part the plate absorbed lies between what is known (a torso between the
        # back and the arms' sweep) and must not be taken for scene. (Later rounds
        # follow what was grown: on limbs spread wide the hull is mostly scene, and
        # a scene colour missing from the model lets the growth leak.)
        core = _hull(core)
    c8 = core.view(np.uint8)
    inner = cv2.dilate(c8, wk.disk, iterations=2) > 0
    outer = cv2.dilate(c8, np.ones((2 * wk.ring_r + 1,) * 2, np.uint8)) > 0
    ring = outer & ~inner & ~wk.lit
    if ring.sum() < 50:
        return None
    px = wk.small[:, ring][~wk.fg[:, ring]]
    local = colour_model(px if len(px) >= 50 else wk.plate[ring])
    # The whole scene outside the person's area: colours the ring misses (the
    # background behind a raised arm may be another object).
    scene = ~(cv2.dilate(c8, wk.disk, iterations=3) > 0) & ~wk.lit
    if scene.sum() < 50:
        return local
    return np.logaddexp(local, colour_model(wk.plate[scene])) - np.log(2.0)


def _grow_absorbed(wk: _Work, person_seen: np.ndarray):
    """Plate pixels that look like the person (a colour seen on it, unlike the
    background around) and touch what moved or was never seen: static parts the
    plate absorbed. Grown by at most the ring's width a round, :data:`GROW_STEPS`
    rounds, the background's model re-learnt round what was found. Returns
    ``(absorbed, background model)``, or None without a background model."""
    seeds = wk.foot | wk.never
    absorbed = np.zeros((wk.h, wk.w), bool)
    bg_model = _scene_model(wk, seeds, hull=True)
    if bg_model is None:
        return None
    grow = np.ones((2 * wk.ring_r + 1,) * 2, np.uint8)
    for _ in range(GROW_STEPS):
        llr_plate = cv2.blur(log_ratio(wk.plate, person_seen, bg_model), (3, 3))
        reach = cv2.dilate((seeds | absorbed).view(np.uint8), grow) > 0
        cand = (llr_plate > 0) & ~wk.lit & reach
        n, lab = cv2.connectedComponents((cand | seeds).view(np.uint8), connectivity=8)
        keep = np.zeros(n, bool)
        keep[np.unique(lab[seeds])] = True
        keep[0] = False
        grown = cand & keep[lab] & ~wk.foot
        if grown.sum() > MAX_SHARE * wk.h * wk.w or (grown == absorbed).all():
            break
        absorbed = grown
        bg_model = _scene_model(wk, seeds | absorbed)
        if bg_model is None:
            return None
    return absorbed, bg_model


def person_scene_models(model, frames: np.ndarray, gains: np.ndarray, *,
                        work_size: int = WORK_SIZE, small: np.ndarray | None = None):
    """The person's and the scene's colour models over the clip, for any clip.

    The person: what differs by a margin from the plate where it was seen, over all
    samples (and what the samples show in the never-seen area); the scene: a ring
    round the person's footprint where it is not foreground, mixed with the plate
    outside it (see :func:`_scene_model`).

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The samples the plate was estimated from.
    gains : numpy.ndarray, shape (K, 3)
    work_size : int
        Long side of the working resolution, pixels.
    small : numpy.ndarray, shape (K, h, w, 3), optional
        :func:`small_samples` of ``frames`` at ``work_size``, when the caller has them.

    Returns
    -------
    tuple of numpy.ndarray, each (BINS**3,), or None
        ``(person, scene)`` log-probabilities (the person's with a share
        :data:`PRIOR_UNSEEN` spread over every colour); None when the samples show
        too little of the person.
    """
    if len(frames) < 2:
        return None
    wk = _Work(model, frames, gains, work_size, small)
    px = _person_colours(wk)
    if px is None:
        # (a person who never leaves the never-seen area: what the samples show there)
        core = cv2.erode(wk.never.view(np.uint8), wk.disk) > 0
        if core.sum() < 50:
            return None
        px = wk.small[:, core].reshape(-1, 3)
    scene = _scene_model(wk, wk.foot | wk.never, hull=True)
    if scene is None:
        return None
    return colour_model(px, uniform=PRIOR_UNSEEN), scene


def appearance_plate(model, frames: np.ndarray, gains: np.ndarray, *,
                     work_size: int = WORK_SIZE, small: np.ndarray | None = None) -> object:
    """Re-take the plate where the person stays, deciding person by appearance.

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
        The plate so far (self-lit pixels found).
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The samples it was estimated from.
    gains : numpy.ndarray, shape (K, 3)
        Their per-channel gains relative to the plate.
    work_size : int
        Long side of the working resolution, pixels.
    small : numpy.ndarray, shape (K, h, w, 3), optional
        :func:`small_samples` of ``frames`` at ``work_size``, when the caller has them.

    Returns
    -------
    vidcap.video.background.BackgroundModel
        Unchanged when the person does not stay in place (or the pass is not
        trusted); else with the plate re-taken and ``never_seen`` / ``confidence``
        updated in the uncertain area.
    """
    if len(frames) < 4:
        return model
    wk = _Work(model, frames, gains, work_size, small)
    if wk.med_area < 16 or not _in_place(wk.fg):
        return model
    px = _person_colours(wk, SURE_MARGIN_PX)
    if px is None:
        return model
    got = _grow_absorbed(wk, colour_model(px))
    if got is None:
        return model
    absorbed, bg_model = got
    absorbed = _scene_beside(absorbed, wk.foot)
    uncertain = cv2.dilate((wk.never | absorbed).view(np.uint8), wk.disk) > 0
    # Per sample, person by appearance, smoothed over space and time. Colours never
    # seen on the person are not impossible for it: a uniform share.
    llr = log_ratio(wk.small, colour_model(px, uniform=PRIOR_UNSEEN), bg_model)
    # (A graph cut over space and the samples instead of the box filter measured mixed
    # on the tuning renders: jacks side 0.884 -> 0.855, jacks 3/4 0.902 -> 0.918, cam1
    # 0.362 -> 0.332; session 15, in git history.)
    person = _keep_unlike(wk, _smooth(llr, 2 * wk.r + 1))
    # (a one-pixel margin: the outline at this resolution mixes person and scene)
    box3 = np.ones((3, 3), np.uint8)
    covered = np.stack([cv2.dilate(p.view(np.uint8), box3) for p in person & uncertain[None]])
    seen = (covered == 0) & uncertain[None]
    return _retake(model, frames, gains, wk, uncertain, seen)


def nearest_scene_distance(colour, ys, xs, plate, scene, radius: int, step: int) -> np.ndarray:
    """Colour distance from each pixel's colour to the nearest seen scene pixel round it.

    Parameters
    ----------
    colour : numpy.ndarray, shape (N, 3)
        The colours to compare, in the plate's units.
    ys, xs : numpy.ndarray, shape (N,), int
        Where they are (working-resolution rows and columns).
    plate : numpy.ndarray, shape (H, W, 3)
        The scene's colours.
    scene : numpy.ndarray, shape (H, W), bool
        Where ``plate`` is the seen scene (only those pixels count).
    radius, step : int
        The disc searched round each pixel and the spacing of its offsets, pixels.

    Returns
    -------
    numpy.ndarray, shape (N,), float32
        The smallest L1 distance over the disc's scene pixels; inf where it has none.
    """
    best = np.full(len(ys), np.inf, np.float32)
    if not len(ys):
        return best
    dtype = np.result_type(colour, plate)
    # The plate padded by its edge pixels (what clipping the offsets to the frame read)
    # with the pixels that are not scene set to inf, one channel plane at a time: each
    # offset is then one gather per channel at a flat index, no clipping, no masking.
    pad = radius
    planes = [np.pad(np.where(scene, plate[..., c], np.inf).astype(dtype, copy=False), pad,
                     mode="edge").ravel() for c in range(3)]
    wp = scene.shape[1] + 2 * pad
    base = (np.asarray(ys, np.intp) + pad) * wp + (np.asarray(xs, np.intp) + pad)
    c0, c1, c2 = (np.ascontiguousarray(colour[:, c], dtype=dtype) for c in range(3))
    d = np.empty(len(ys), dtype)
    tmp = np.empty(len(ys), dtype)
    # a loop over the disc's offsets (tens), each vectorised over all N pixels
    for dy in range(-radius, radius + 1, step):
        for dx in range(-radius, radius + 1, step):
            if dx * dx + dy * dy > radius * radius:
                continue
            at = base + (dy * wp + dx)
            np.abs(np.subtract(c0, planes[0].take(at), out=d), out=d)
            d += np.abs(np.subtract(c1, planes[1].take(at), out=tmp), out=tmp)
            d += np.abs(np.subtract(c2, planes[2].take(at), out=tmp), out=tmp)
            np.minimum(best, d, out=best)  # (inf where the pixel is not scene)
    return best


def _keep_unlike(wk: _Work, llr: np.ndarray) -> np.ndarray:
    """Person per sample, (k, h, w) bool: ``llr > 0``; and, in the first plate's
    never-seen area, ``llr > -NEVER_KEEP`` where the sample's colour matches no seen
    plate pixel within the ring's width (L1 at most :data:`UNLIKE` thresholds): not a
    continuation of the scene around it."""
    person = llr > 0
    if NEVER_KEEP <= 0:
        return person
    ts, ys, xs = np.nonzero(~person & (llr > -NEVER_KEEP) & wk.never[None])
    if not len(ts):
        return person
    # A still pixel shows one colour in every sample: each pixel's colours are looked
    # at once (to 4 grey levels per channel; the cost stays the never-seen area's).
    q = (wk.small[ts, ys, xs] // 4).astype(np.int64)
    key = (((ys.astype(np.int64) * wk.w + xs) << 18) | (q[:, 0] << 12) | (q[:, 1] << 6)
           | q[:, 2])
    _, first, inv = np.unique(key, return_index=True, return_inverse=True)
    colour = wk.small[ts[first], ys[first], xs[first]]  # (U, 3)
    uy, ux = ys[first], xs[first]
    best = nearest_scene_distance(colour, uy, ux, wk.plate, ~(wk.never | wk.lit), wk.ring_r, 2)
    unlike = (best > UNLIKE * wk.thr)[inv.ravel()]
    person[ts[unlike], ys[unlike], xs[unlike]] = True
    return person


def _retake(model, frames, gains, wk: _Work, uncertain, seen):
    """The plate re-taken at full resolution where uncertain, from the samples that
    show it uncovered; the rest of the uncertain area is never seen, inpainted."""
    from vidcap.video.platemedian import robust_plate

    k = wk.k
    count = seen.sum(axis=0)
    ok = count >= max(MIN_SEEN, int(np.ceil(MIN_SEEN_SHARE * k)))
    again = robust_plate(frames, gains, np.stack([wk.up(x) for x in seen]))
    unc_full, ok_full = wk.up(uncertain) > 0, wk.up(ok) > 0
    new_never = unc_full & ~ok_full
    if model.self_lit is not None:
        new_never &= ~model.self_lit
    never_full = (model.never_seen & ~unc_full) | new_never
    if never_full.sum() < MIN_KEPT_NEVER * model.never_seen.sum():
        # Appearance alone un-flagged most of what no sample showed uncovered: the
        # person's colour model missed a static part: not trusted.
        return model
    plate = model.plate.copy()
    take = unc_full & ok_full
    plate[take] = again[take]
    if never_full.any():
        # The pixels around were re-taken outside the person: the guess starts
        # right at the never-seen area's edge.
        fill = cv2.dilate(never_full.view(np.uint8), np.ones((3, 3), np.uint8))
        plate = cv2.inpaint(plate, fill, 5, cv2.INPAINT_TELEA)
    hh, ww = wk.full
    cnt = cv2.resize(count.astype(np.float32), (ww, hh), interpolation=cv2.INTER_NEAREST)
    conf = np.where(unc_full, cnt / k, model.confidence).astype(np.float32)
    return replace(model, plate=plate, never_seen=never_full, confidence=conf)
