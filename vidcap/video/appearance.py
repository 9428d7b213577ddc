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
   seen (not a guess), over the whole clip. **Sure background**: the seen plate
   in a window around the person (the motion footprint and the never-seen area,
   widened), outside them. A colour histogram of each (BGR quantised to
   :data:`BINS` levels per channel, smoothed) is the colour model.
2. **Uncertain area**: the never-seen area, the footprint, and plate pixels that
   look like the person (their colour is more likely under the person's model)
   and touch the footprint: a static body part the plate absorbed.
3. Per sample, in the uncertain area, the log-likelihood ratio person/background
   is smoothed over space (a box filter, the pairwise term of a graph cut done
   cheaply) and over time (neighbouring samples: a limb that is person in sample
   k is likely person in k +- 1); positive is person.
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

__all__ = ["appearance_plate", "colour_model", "log_ratio"]

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
    k, h, w = fg.shape
    n = fg.reshape(k, -1).sum(axis=1)
    ok = n >= 16
    if ok.sum() < 2:
        return False
    cx = (fg.sum(axis=1) * np.arange(w)).sum(axis=1)[ok] / n[ok]
    q25, q75 = np.percentile(cx, [25, 75])
    return bool(q75 - q25 <= MAX_TRAVEL * w)


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


def appearance_plate(model, frames: np.ndarray, gains: np.ndarray, *,
                     work_size: int = WORK_SIZE) -> object:
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

    Returns
    -------
    vidcap.video.background.BackgroundModel
        Unchanged when the person does not stay in place; else with the plate
        re-taken and ``never_seen`` / ``confidence`` updated in the uncertain area.
    """
    from vidcap.video.platemedian import robust_plate

    k, hh, ww = frames.shape[:3]
    if k < 4:
        return model
    s = min(1.0, work_size / max(hh, ww))
    h, w = max(2, round(hh * s)), max(2, round(ww * s))
    small = np.stack([cv2.resize(f, (w, h), interpolation=cv2.INTER_AREA) for f in frames])
    small = np.clip(small.astype(np.float32) / gains[:, None, None, :], 0, 255)
    plate = cv2.resize(model.plate, (w, h), interpolation=cv2.INTER_AREA).astype(np.float32)
    never = cv2.resize(model.never_seen.view(np.uint8), (w, h),
                       interpolation=cv2.INTER_NEAREST) > 0
    lit = np.zeros((h, w), bool)
    if model.self_lit is not None:
        lit = cv2.resize(model.self_lit.view(np.uint8), (w, h),
                         interpolation=cv2.INTER_NEAREST) > 0
    thr = float(model.threshold)
    d = np.abs(small - plate).sum(axis=-1)
    fg = np.stack([_person_blobs(x > thr) for x in d])
    # (and their outline: the glow's edge flickers with the exposure)
    fg[:, cv2.dilate(lit.view(np.uint8), np.ones((7, 7), np.uint8)) > 0] = False
    areas = fg.reshape(k, -1).sum(axis=1)
    foot = fg.sum(axis=0) >= 2
    med_area = float(np.median(areas))
    if med_area < 16 or not _in_place(fg):
        return model
    r = max(1, round(0.01 * max(h, w)))
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    never_wide = cv2.dilate(never.view(np.uint8), disk, iterations=2) > 0
    # 1. colour models. Sure person: differs from a plate that was seen, by a margin.
    sure = (d > 2 * thr) & fg & ~never_wide[None]
    sure &= np.stack([cv2.erode(x.view(np.uint8), np.ones((3, 3), np.uint8)) for x in sure]) > 0
    if sure.sum() < 50:
        return model
    # Colours never seen on the person are not impossible for it (a static part
    # may be another colour): a uniform share.
    px = small[sure]
    if never.any():
        # the never-seen area of the first plate is a static body part: what the
        # samples show there is the person too
        core_never = cv2.erode(never.view(np.uint8), disk) > 0
        if core_never.any():
            px = np.concatenate([px, small[:, core_never].reshape(-1, 3)])
    person_seen = colour_model(px)
    person_model = colour_model(px, uniform=PRIOR_UNSEEN)
    # 2. uncertain area: never seen, the footprint, and plate pixels unlike the
    # background around them that touch the footprint (a static part the plate
    # absorbed); grown while the ring around it finds more.
    seeds = foot | never
    absorbed = np.zeros((h, w), bool)
    ring_r = max(3, round(0.04 * max(h, w)))

    def ring_model(core):
        inner = cv2.dilate(core.view(np.uint8), disk, iterations=2) > 0
        outer = cv2.dilate(core.view(np.uint8), np.ones((2 * ring_r + 1,) * 2, np.uint8)) > 0
        ring = outer & ~inner & ~lit
        if ring.sum() < 50:
            return None
        px = small[:, ring][~fg[:, ring]]
        local = colour_model(px if len(px) >= 50 else plate[ring])
        # and the whole scene seen outside the person's area (colours the ring
        # misses: the background behind a raised arm may be another object)
        scene = ~(cv2.dilate(core.view(np.uint8), disk, iterations=3) > 0) & ~lit
        if scene.sum() < 50:
            return local
        return np.logaddexp(local, colour_model(plate[scene])) - np.log(2.0)

    bg_model = ring_model(seeds)
    if bg_model is None:
        return model
    for _ in range(GROW_STEPS):
        # (absorbed parts must have a colour seen on the moving person, and grow
        # by at most the ring's width a round)
        llr_plate = cv2.blur(log_ratio(plate, person_seen, bg_model), (3, 3))
        reach = cv2.dilate((seeds | absorbed).view(np.uint8),
                           np.ones((2 * ring_r + 1,) * 2, np.uint8)) > 0
        cand = (llr_plate > 0) & ~lit & reach
        n, lab = cv2.connectedComponents((cand | seeds).view(np.uint8), connectivity=8)
        keep = np.zeros(n, bool)
        keep[np.unique(lab[seeds])] = True
        keep[0] = False
        grown = cand & keep[lab] & ~foot
        if grown.sum() > MAX_SHARE * h * w or (grown == absorbed).all():
            break
        absorbed = grown
        bg_model = ring_model(seeds | absorbed)
        if bg_model is None:
            return model
    uncertain = cv2.dilate((never | absorbed).view(np.uint8), disk) > 0
    # 3. per-sample person by appearance, smoothed over space and time; where the
    # plate was seen, its own difference also counts.
    llr = log_ratio(small, person_model, bg_model)
    llr = _smooth(llr, 2 * r + 1)
    person = llr > 0
    # (a one-pixel margin: the outline at this resolution mixes person and scene)
    box3 = np.ones((3, 3), np.uint8)
    covered = np.stack([cv2.dilate(p.view(np.uint8), box3) for p in person & uncertain[None]])
    seen = (covered == 0) & uncertain[None]
    count = seen.sum(axis=0)
    ok = count >= max(MIN_SEEN, int(np.ceil(MIN_SEEN_SHARE * k)))
    # 4. plate re-taken at full resolution where uncertain
    up = np.stack([cv2.resize(x.view(np.uint8), (ww, hh), interpolation=cv2.INTER_NEAREST)
                   for x in seen])
    again = robust_plate(frames, gains, up)
    unc_full = cv2.resize(uncertain.view(np.uint8), (ww, hh),
                          interpolation=cv2.INTER_NEAREST) > 0
    ok_full = cv2.resize(ok.view(np.uint8), (ww, hh), interpolation=cv2.INTER_NEAREST) > 0
    new_never = unc_full & ~ok_full
    if model.self_lit is not None:
        new_never &= ~model.self_lit
    plate_new = model.plate.copy()
    take = unc_full & ok_full
    plate_new[take] = again[take]
    never_full = (model.never_seen & ~unc_full) | new_never
    if never_full.sum() < MIN_KEPT_NEVER * model.never_seen.sum():
        # Appearance alone un-flagged most of what no sample showed uncovered: the
        # person's colour model missed a static part (seen only on the limbs that
        # move, it does not know the shirt): not trusted.
        return model
    if never_full.any():
        # The pixels around were re-taken outside the person: the guess starts
        # right at the never-seen area's edge.
        fill = cv2.dilate(never_full.view(np.uint8), np.ones((3, 3), np.uint8))
        plate_new = cv2.inpaint(plate_new, fill, 5, cv2.INPAINT_TELEA)
    cnt_full = cv2.resize(count.astype(np.float32), (ww, hh), interpolation=cv2.INTER_NEAREST)
    conf = np.where(unc_full, cnt_full / k, model.confidence).astype(np.float32)
    return replace(model, plate=plate_new, never_seen=never_full, confidence=conf)
