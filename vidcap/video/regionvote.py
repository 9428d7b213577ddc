"""The region vote: steps 2-6 of :mod:`vidcap.video.background` at low resolution.

Each sampled frame is segmented (:func:`skimage.segmentation.felzenszwalb`) and painted
with its regions' mean colours; per pixel, the region colour most samples share is the
first guess, and a region whose pixels agree with their guesses is background in that
frame (the seed's "regions that do not change"). Inside the motion footprint the
background round it, inpainted across, and the scene's colours in a ring round it
overturn a voted colour that is the person's (:func:`_footprint_plate`); static areas
the limbs sweep round are body parts that never moved (never seen uncovered).
:func:`region_vote` returns the per-sample background weights and those parts;
:func:`vidcap.video.background.estimate_background` turns them into the plate at full
resolution.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["region_vote", "work_hw"]

#: Take scene colours over a voted colour unlike every colour round the footprint
#: (:func:`_switch_to_scene_colours`). On: ``silhouettes_real.py --quick --no-mediapipe``
#: (session 27, against the same table of main 77e0cd9) mmskeleton_taichi (tuning: built
#: on it) 0.225 -> 0.815 median IoU against MediaPipe's masks, onebyone_room 233-445
#: (validation) 0.189 -> 0.746, the render 06_14 0-3 s front / room plate (validation)
#: 0.899 -> 0.919; no row of the 74 lower by more than 0.002.
SCENE_RING = True
#: The ring round the footprint, in working-size pixels.
RING_WIDTH = 6
#: Samples that must show a scene colour there (one is enough where the voted colour
#: is shared by many; 2 or 3.6 samples took taichi to 0.62 / 0.47, onebyone 0.65 / 0.31).
SCENE_MIN = 1


def work_hw(hw, work_size: int) -> tuple[int, int]:
    """(h, w), at least 2 each, of frames of size ``hw`` (h, w) downscaled to
    ``work_size`` pixels on the long side (never enlarged)."""
    hh, ww = int(hw[0]), int(hw[1])
    s = min(1.0, work_size / max(hh, ww))
    return max(2, round(hh * s)), max(2, round(ww * s))


def region_vote(frames, gains, *, work_size, segment_scale, min_region, progress,
                min_stability=0.5, min_support=0.15, cover=None):
    """Steps 2-6 of :mod:`vidcap.video.background` at low resolution.

    Parameters
    ----------
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The sampled frames.
    gains : numpy.ndarray, shape (K, 3)
        Their per-channel gains (the samples are divided by them).
    work_size : int
        Long side of the working resolution, pixels.
    segment_scale, min_region : float, int
        :func:`skimage.segmentation.felzenszwalb`'s ``scale`` and ``min_size``.
    progress : bool or None
        Show a progress bar over the samples.
    min_stability, min_support : float
        A region's least stability, a colour's least share of the samples.
    cover : numpy.ndarray, shape (h, w), optional
        The share of the clip's time each pixel moves
        (:func:`vidcap.video.timecover.motion_cover`), for the footprint's rings.

    Returns
    -------
    weights : numpy.ndarray, shape (K, h, w), float32
        Per sample and working pixel, 1 where the sample shows the background.
    holes : numpy.ndarray, shape (h, w), bool
        Body parts that never moved (never seen uncovered).
    """
    from skimage.segmentation import felzenszwalb

    from vidcap.fileio import progress as bar

    k, hh, ww = frames.shape[:3]
    h, w = work_hw((hh, ww), work_size)
    if cover is not None and cover.shape != (h, w):
        cover = cv2.resize(cover, (w, h), interpolation=cv2.INTER_NEAREST)
    small = np.stack([cv2.resize(f, (w, h), interpolation=cv2.INTER_AREA) for f in frames])
    small = small.astype(np.float32) / gains[:, None, None, :]
    labels = np.empty((k, h, w), np.int32)
    means = np.empty((k, h, w, 3), np.float32)
    offset = 0
    for t in bar(range(k), total=k, desc="background", unit="frame", enabled=progress):
        lab = felzenszwalb(np.clip(small[t], 0, 255).astype(np.uint8), scale=segment_scale,
                           sigma=0.5, min_size=min_region)
        flat = lab.ravel()
        cnt = np.bincount(flat).astype(np.float32)
        for c in range(3):
            means[t, ..., c] = (np.bincount(flat, small[t, ..., c].ravel()) / cnt)[lab]
        labels[t] = lab + offset
        offset += int(lab.max()) + 1
    n_regions = offset

    # Agreement threshold from the data: spread of region colours about their
    # temporal median, most of which is background most of the time.
    med = np.median(means, axis=0)
    resid = np.abs(means - med).max(axis=-1)
    sigma = 1.4826 * float(np.median(resid))
    tau = max(8.0, 4.0 * sigma)

    # agree[t, u, p]: samples t and u show the same region colour at p (max over
    # channels; channel planes keep the arithmetic element-wise and fast).
    planes = np.ascontiguousarray(np.moveaxis(means, -1, 0))  # (3, k, h, w)
    agree = np.empty((k, k, h, w), bool)
    for t in range(k):
        d = np.abs(planes[0] - planes[0, t])
        np.maximum(d, np.abs(planes[1] - planes[1, t]), out=d)
        np.maximum(d, np.abs(planes[2] - planes[2, t]), out=d)
        np.less(d, tau, out=agree[t])

    lab_flat = labels.ravel()
    reg_size = np.maximum(np.bincount(lab_flat, minlength=n_regions), 1).astype(np.float32)
    # support[t, p]: share of samples showing at p the region colour sample t shows.
    support = agree.sum(axis=1, dtype=np.float32) / k
    # Region stability (the seed's "regions that do not change"): how often, on
    # average over the region of sample t at p, its pixels show this colour. A
    # background region reaching beyond the person scores near 1 even where the
    # person covers it in most frames; a person's region scores the share of the
    # time it stays put, lowered by its moving parts.
    stability = (np.bincount(lab_flat, support.ravel(), minlength=n_regions)
                 / reg_size)[labels]  # (k, h, w)
    # A colour seen in too few samples is a mixture or a passer-by, however
    # stable its region: candidates need some support of their own.
    enough = support >= max(min_support, 2.5 / k)
    scored = np.where(enough, stability, stability - 2.0)
    best = scored.argmax(axis=0)
    level = np.take_along_axis(scored, best[None], 0)[0]
    same = np.take_along_axis(agree, best[None, None], 1)[:, 0]  # (k, h, w)
    weights = same & (level >= min_stability)[None]
    holes = _footprint_plate(small, means, med, tau, best, agree, weights, cover=cover,
                             voted_count=np.take_along_axis(support, best[None], 0)[0] * k)
    return weights.astype(np.float32), holes


def _footprint_plate(small, means, med, tau, best, agree, weights, *,
                     max_hole_share=0.6, min_evidence=0.25, min_support=0.15, cover=None,
                     voted_count=None):
    """Background inside the motion footprint, from the background around it.

    Updates ``weights`` (k, h, w) in place and returns the static body parts
    (h, w) bool, pixels never seen uncovered.

    The motion footprint is the union over samples of the pixels that differ from
    the temporal median. Inside it (and inside its holes) the per-pixel vote can
    pick the person's colour when the person covers a pixel in most frames. The
    background around the footprint, inpainted across it, is a spatial guess of
    what lies behind; at a footprint pixel whose voted colour is far from that
    guess while some sample is close to it, the samples showing that colour are
    taken instead.

    A person moving their limbs while the torso stays put (jumping jacks, waving)
    leaves the torso as a *hole* of the footprint: static pixels the frame border
    cannot reach through static pixels. A hole is a body part that never moved
    (never seen uncovered) when its colour is far from the guess and

    * it is not most of its footprint component (``max_hole_share`` of the filled
      component's area): a static object walked around on all sides is usually
      large next to the paths around it; and
    * the footprint around it shows the hole's own colour in some samples where
      its own background has another colour (``min_evidence`` of its ring
      pixels): the body part's outline changes while its colour stays (a hop,
      sleeves, a shifting hem), whereas around a patch of background or a static
      object the ring's background continues the patch's colour and passers-by
      rarely wear it.

    With ``cover`` ((h, w), the share of the clip's time each pixel moves:
    :mod:`vidcap.video.timecover`) the rings' cover is measured over time (at least
    :data:`vidcap.video.timecover.MIN_COVER`), not over the samples, so that which frames
    were drawn does not decide whether a hole is a body part. ``voted_count`` ((h, w)):
    how many samples show the voted colour (:data:`SCENE_RING`'s switch needs it; without
    it, the switch does not run).
    """
    k, h, w = small.shape[:3]
    box = np.ones((3, 3), np.uint8)
    blur = np.stack([cv2.GaussianBlur(x, (3, 3), 0) for x in small])
    dev = np.abs(blur - np.median(blur, axis=0)[None]).max(axis=-1)  # (k, h, w)
    # Pixel noise of the blurred samples (robust: most pixels are static in most
    # samples); region colours can flicker more than pixels, so not ``tau``.
    noise = 1.4826 * float(np.median(dev[:, ::2, ::2]))
    tau_region, tau = tau, max(8.0, 5.0 * noise)
    moving = (dev > tau).any(axis=0).astype(np.uint8)
    moving = cv2.morphologyEx(moving, cv2.MORPH_OPEN, box)
    out = np.zeros((h, w), bool)
    if not moving.any():
        return out
    # Holes are looked for with narrow gaps sealed (a hop's thin band above the
    # head, an arm's sweep, rarely close at low resolution).
    sealed = cv2.morphologyEx(moving, cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))
    n, lab = cv2.connectedComponents(1 - sealed, connectivity=4)
    border = np.unique(np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]]))
    hole_ids = np.setdiff1d(np.arange(1, n), border)
    is_hole = np.isin(lab, hole_ids)
    filled = (sealed > 0) | is_hole
    # Spatial guess: the voted plate outside the footprint, inpainted across it.
    voted = np.take_along_axis(means, best[None, ..., None], 0)[0]
    region = cv2.dilate(filled.astype(np.uint8), box)
    guess = cv2.inpaint(np.clip(voted, 0, 255).astype(np.uint8), region, 3,
                        cv2.INPAINT_TELEA).astype(np.float32)
    far = 3.0 * tau
    dist = np.abs(means - guess[None]).max(axis=-1)  # (k, h, w)
    near_t = dist.argmin(axis=0)
    near_d = np.take_along_axis(dist, near_t[None], 0)[0]
    voted_d = np.abs(voted - guess).max(axis=-1)
    # Switch when some sample is clearly nearer the guess than the voted colour.
    # and that colour has support of its own (not a passer-by's transient colour).
    alt = np.take_along_axis(agree, near_t[None, None], 1)[:, 0]  # (k, h, w)
    # (the region colours' own spread sets how far is clearly different)
    switch = (filled & (voted_d > 3.0 * max(tau, tau_region)) & (near_d <= 0.5 * voted_d)
              & (alt.sum(axis=0) >= max(min_support * k, 2.5)))
    if switch.any():
        weights[:, switch] = alt[:, switch]
    if SCENE_RING and voted_count is not None:
        # (only where the voted colour is one many samples share: a still person's,
        # not a pixel whose every sample differs, where a scene-like one is chance)
        _switch_to_scene_colours(means, voted, filled,
                                 filled & ~switch & (voted_count >= max(min_support * k, 2.5)),
                                 weights, far=3.0 * max(tau, tau_region),
                                 min_count=SCENE_MIN)
    if not len(hole_ids):
        return out
    _, comp = cv2.connectedComponents(filled.astype(np.uint8), connectivity=8)
    comp_area = np.bincount(comp.ravel())
    hole_area = np.bincount(lab.ravel(), minlength=n)
    # How often each pixel differs from its temporal median: around a body part
    # that never moved, the limbs and the hop cover the ring often; around a gap
    # left between a passer-by's sampled positions they cover it once or twice.
    if cover is None:
        cover = (dev > tau).mean(axis=0)
    else:
        from vidcap.video.timecover import MIN_COVER

        min_evidence = MIN_COVER
    unseen = voted_d > far
    moving_t = dev > tau  # (k, h, w): what moves in each sample
    moving_t = moving_t[moving_t.reshape(k, -1).sum(axis=1) > MIN_ACTIVE_PX]
    for i in hole_ids:
        hole = lab == i
        if hole_area[i] > max_hole_share * comp_area[np.bincount(comp[hole]).argmax()]:
            continue
        ring = cv2.dilate(hole.astype(np.uint8), box, iterations=2).astype(bool) & (
            sealed > 0)
        if ring.any() and cover[ring].mean() >= min_evidence and _attached(hole, moving_t, box):
            out |= hole & unseen
    if out.any():
        # Footprint pixels next to a static body part, far from the guess in every
        # sample, belong to it too (the head and shoulders above a hopping torso).
        cand = (filled & unseen & ~switch) | out
        nc, cl = cv2.connectedComponents(cand.astype(np.uint8), connectivity=8)
        keep = np.zeros(nc, bool)
        keep[np.unique(cl[out])] = True
        keep[0] = False
        out = keep[cl]
    weights[:, out] = 0
    return out


#: A hole of the motion footprint is a body part that never moved only if the moving
#: body touches it (within :data:`ATTACH_PX` pixels at the vote's working size) in at
#: least this share of the samples where something moves (more than
#: :data:`MIN_ACTIVE_PX` pixels): a still torso or leg is attached to the moving limbs
#: in every sample, while a piece of scene the person walks round (a table a dancer
#: crosses in front of: CMU 05_08 2.8-5.8 s front, now tuning, touched in 18 of 23
#: samples, the dancer 18-22 px away in the others) is left alone when the person is
#: elsewhere. On every other tuning render with such holes (jacks, arms, 02_06, 02_07,
#: 05_02, 05_20) the body part was touched in 23 of 23 samples, at most 3 px away.
MIN_ATTACHED = 0.9
ATTACH_PX = 3
MIN_ACTIVE_PX = 20


def _attached(hole: np.ndarray, moving: np.ndarray, box: np.ndarray) -> bool:
    """Whether the moving pixels of the samples ``moving`` (k', h, w) bool come within
    :data:`ATTACH_PX` of ``hole`` (h, w) in at least :data:`MIN_ATTACHED` of them (no
    sample: True, as before the test)."""
    if not len(moving):
        return True
    near = cv2.dilate(hole.astype(np.uint8), box, iterations=ATTACH_PX).astype(bool) & ~hole
    return bool(moving[:, near].any(axis=1).mean() >= MIN_ATTACHED)


def _scene_distance(ring_colours: np.ndarray, bin_width: int = 8):
    """A function giving, for colours (..., 3), the Chebyshev distance (grey levels, to
    ``bin_width``) to the nearest of ``ring_colours`` (N, 3): a distance transform of
    their occupancy grid in colour space, so any number of queries costs one lookup."""
    from scipy.ndimage import distance_transform_cdt

    n = 256 // bin_width
    cells = np.clip(ring_colours // bin_width, 0, n - 1).astype(np.intp)
    empty = np.ones((n, n, n), bool)
    empty[cells[:, 0], cells[:, 1], cells[:, 2]] = False
    grid = distance_transform_cdt(empty, metric="chessboard").astype(np.float32) * bin_width

    def distance(colours):
        c = np.clip(colours // bin_width, 0, n - 1).astype(np.intp)
        return grid[c[..., 0], c[..., 1], c[..., 2]]

    return distance


def _letterbox(means, dark: float = 16.0):
    """(h, w) bool: the rows and columns along the frame's edges that are dark in every
    sample (bars added to fit a frame shape: not part of the scene)."""
    dark_px = (means.max(axis=-1) < dark).all(axis=0)
    rows, cols = dark_px.all(axis=1), dark_px.all(axis=0)

    def edge_run(a):
        keep = np.zeros_like(a)
        for order in (slice(None), slice(None, None, -1)):
            run = np.logical_and.accumulate(a[order])
            keep[order] |= run
        return keep

    out = np.zeros(dark_px.shape, bool)
    out[edge_run(rows)] = True
    out[:, edge_run(cols)] = True
    return out


def _switch_to_scene_colours(means, voted, footprint, candidates, weights, *, far,
                             min_count):
    """Where the voted colour is unlike every colour of the scene round the footprint and
    enough samples show a colour like the scene's, take those samples (``weights``
    updated in place).

    The inpainted guess of :func:`_footprint_plate` is one colour per pixel, smeared
    across a large footprint (the floor's grey inpainted up a wall): a performer who
    stays in front of a textured wall in most samples kept their clothes in the plate
    (mmskeleton_taichi). The scene round the footprint, as a set of colours, does not
    smear: a black costume is far from every colour of a teal wall and a grey floor,
    and the wall seen between the performer's steps is near one of them.
    """
    if not candidates.any():
        return
    foot = footprint.astype(np.uint8)
    box = np.ones((3, 3), np.uint8)
    ring = ((cv2.dilate(foot, box, iterations=RING_WIDTH + 1) > 0)
            & ~(cv2.dilate(foot, box) > 0))
    ring &= ~_letterbox(means)
    if ring.sum() < 50:
        return
    scene_d = _scene_distance(np.clip(voted[ring], 0, 255))
    voted_d = scene_d(np.clip(voted, 0, 255))
    cand = candidates & (voted_d > far)
    if not cand.any():
        return
    ys, xs = np.nonzero(cand)
    # The samples that show a colour like the scene's; they need not agree with each
    # other (a textured wall's regions change their mean with the segmentation), only
    # be enough of them.
    like = scene_d(np.clip(means[:, ys, xs], 0, 255)) <= 0.5 * voted_d[ys, xs][None]
    hit = like.sum(axis=0) >= min_count
    if hit.any():
        weights[:, ys[hit], xs[hit]] = like[:, hit]
