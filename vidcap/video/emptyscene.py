"""The plate from frames where the scene is empty (issue 26, Build 1).

The plate's vote takes, per region, the colour the samples show most often. A person
who walks in and then stands still for most of the clip wins that vote: the plate
keeps them, and in the frames before they came (the scene empty) the wall they later
cover differs from the plate - a *ghost*: a false blob where nobody is, while the
standing person is absorbed.

A ghost tells itself from a person by its outline. Where a person is in the frame,
the outline of the difference blob runs along the person's edge: the frame has an
edge there, the plate (the scene behind) mostly has not. Where the plate holds the
person and the frame shows the empty scene, it is the other way round: the outline
is an edge of the plate, and the frame is smooth across it (the wall continues).
So, per sample and blob, along the blob's outline, the gradient the frame has beyond
the plate's is summed and compared with the gradient the plate has beyond the
frame's; a blob whose outline is mostly an edge of the plate is a ghost, the frame
shows the scene there, and the plate is re-taken in the blob from the samples that
show it as a ghost (their median, each scaled by its gain).

A person in view all along can look like a ghost for a moment (a plate that absorbed
part of someone who barely moves has edges of its own along their outline). The empty
scene does not: it comes before the person walked in or after they left. So a pixel is
re-taken only when the samples showing it as a ghost run from the clip's first or last
sample over at least :data:`MIN_EMPTY_S` (:func:`empty_stretch`), and when neither end
sample shows a ghost nothing else is looked at (~0.01 s; the whole pass ~0.3 s CPU on
24 samples of 640x480). The first sample lies up to a stride after the clip's start:
a ghost that lies apart from the person, with the person out of view or crossing the
frame's border (coming in, going out), may stretch from the clip's first (last) frame
instead (:data:`FROM_CLIP_ENDS`, :data:`GHOST_APART`, :data:`ENTERING`).
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from vidcap.video.maskbox import padded_box

__all__ = ["ghost_blobs", "plate_from_empty"]

#: A blob is a ghost when the frame's excess gradient along its outline is below this
#: share of the plate's excess. On cdnet_office_enter (tuning) the ghost of the man in
#: the empty samples scores 0.32-0.36, blobs of the man himself 0.69-2.7.
GHOST_RATIO = 0.5
#: Samples (at least) that must show the empty scene at a pixel, agreeing on it.
MIN_AGREE = 2
#: Shortest empty stretch, seconds: the samples that show the empty scene at a pixel
#: must run from the clip's first or last sample over at least this long (the person
#: came in or left; walking in or out takes longer). On the tuning clips: the true
#: ghosts of cdnet_office_enter run 4 s from the start; the false ones on
#: pose2sim_balance cam3 / cam4 (a person in view all along, 1.7 s) at most ~0.7 s.
MIN_EMPTY_S = 1.0
#: Frame rate taken for frames given as an array (no file to read it from).
ASSUMED_FPS = 30.0
#: Smallest blob considered, share of the frame.
MIN_BLOB = 2e-3


def _gradient(grey: np.ndarray) -> np.ndarray:
    """Gradient magnitude (H, W) float32 of a grey image (Sobel, 3x3)."""
    g = grey.astype(np.float32)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3)
    return cv2.magnitude(gx, gy)


def ghost_blobs(frame: np.ndarray, plate: np.ndarray, mask: np.ndarray, *,
                ratio: float = GHOST_RATIO, min_area: int | None = None) -> np.ndarray:
    """The blobs of ``mask`` whose outline is an edge of the plate, not of the frame.

    Parameters
    ----------
    frame : numpy.ndarray, shape (H, W, 3), uint8
        A frame, already scaled to the plate's exposure.
    plate : numpy.ndarray, shape (H, W, 3), uint8
    mask : numpy.ndarray, shape (H, W), bool or uint8
        Where the frame differs from the plate (a first-pass silhouette).
    ratio : float
        A blob is a ghost when, summed along its outline, the frame's gradient beyond
        the plate's is below ``ratio`` times the plate's gradient beyond the frame's.
    min_area : int, optional
        Smaller blobs are left out (default :data:`MIN_BLOB` of the frame, >= 16).

    Returns
    -------
    numpy.ndarray, shape (H, W), bool
        The ghost blobs (empty scene in the frame, something else in the plate).
    """
    h, w = mask.shape
    if min_area is None:
        min_area = max(16, int(MIN_BLOB * h * w))
    m = (np.asarray(mask) > 0).astype(np.uint8)
    out = np.zeros((h, w), bool)
    # Everything below happens within the blobs' bounding box and 3 pixels round it
    # (the outline band reaches 1 pixel out, its 3x3 gradients 2): the same values as
    # over the whole frame, in the area a person takes (most of the time at 1000x1000).
    box = padded_box(m, 3)
    if box is None:
        return out
    m = m[box]
    n, lab, st, _ = cv2.connectedComponentsWithStats(m, connectivity=8)
    if n < 2:
        return out
    gf = _gradient(cv2.cvtColor(frame[box], cv2.COLOR_BGR2GRAY))
    gp = _gradient(cv2.cvtColor(plate[box], cv2.COLOR_BGR2GRAY))
    k = np.ones((3, 3), np.uint8)
    outline = cv2.subtract(cv2.dilate(m, k), cv2.erode(m, k)) > 0
    # Per blob: the outline pixels nearest it (the band straddles the edge).
    near = cv2.dilate(lab.astype(np.float32), k).astype(np.int32)
    idx = near[outline]
    # Edges both have (the scene's own, where the outline runs along them) cancel:
    # only the edge the frame has and the plate lacks counts against the edge the
    # plate has and the frame lacks.
    d = gf[outline] - gp[outline]
    sf = np.bincount(idx, np.maximum(d, 0), minlength=n)
    sp = np.bincount(idx, np.maximum(-d, 0), minlength=n)
    ghost = (st[:, cv2.CC_STAT_AREA] >= min_area) & (sf < ratio * sp)
    ghost[0] = False
    if ghost.any():
        out[box] = ghost[lab]
    return out


#: Also measure an empty stretch from the clip's own first (last) frame, not only from
#: its first (last) sample, for ghosts apart from the person (:data:`GHOST_APART`):
#: the scene was empty from the moment the clip starts. The samples are
#: spread evenly, so the first lies up to a stride after the start; on sbi_candela
#: (tuning since) the sofa the man later sits on is empty in the first three samples
#: (0.5-1.4 s, a man walking in) and the last three (10.3-11.2 s of 11.7 s): 0.9 s
#: between samples, under :data:`MIN_EMPTY_S`, 1.4 s from the clip's ends: 0.770 /
#: 0.750 -> 0.889 / 0.854; every other row of ``silhouettes_real.py --quick``
#: unchanged (with :data:`GHOST_APART` and :data:`ENTERING`; without them the in-place
#: renders whose person is in view all along took false ghosts for an empty stretch).
FROM_CLIP_ENDS = True


#: A ghost may stretch to the clip's ends (:data:`FROM_CLIP_ENDS`) only when the
#: sample's other blobs (the person) are at least this share of the frame's long side
#: away from it. Where the scene is empty the person is elsewhere or out of view; a
#: person in view all along who moves a limb the plate held leaves a ghost beside
#: themselves: measured from the clip's ends for every ghost, the in-place render
#: 05_09 3/4 (validation) lost 0.37 median to such ghosts (0.913 -> 0.546);
#: sbi_candela's (tuning) lie 100+ pixels from the man walking in. (As the only test
#: for every stretch it lost cdnet_office_enter (tuning) its re-take, 0.901 -> 0.432:
#: exposure blobs beside the ghost in the empty samples.)
GHOST_APART = 0.05
#: ... and only when no other blob of the sample lies wholly inside the frame: the
#: person is out of view, coming in or going out (:func:`_apart`).
ENTERING = True


def _apart(ghost: np.ndarray, mask: np.ndarray, share: float) -> np.ndarray:
    """The blobs of ``ghost`` (H, W) bool at least ``share`` of the frame's long
    side from every pixel of ``mask`` (H, W, 0/1) that is not a ghost; none when a
    blob of ``mask`` that is not a ghost lies wholly inside the frame (with
    :data:`ENTERING`: a person in full view; one coming in or going out crosses the
    frame's border)."""
    other = (np.asarray(mask) > 0) & ~ghost
    if not other.any():
        return ghost
    h, w = ghost.shape
    if ENTERING:
        n, _, st, _ = cv2.connectedComponentsWithStats(other.view(np.uint8), connectivity=8)
        x0, y0 = st[1:, cv2.CC_STAT_LEFT], st[1:, cv2.CC_STAT_TOP]
        x1, y1 = x0 + st[1:, cv2.CC_STAT_WIDTH], y0 + st[1:, cv2.CC_STAT_HEIGHT]
        inside = (x0 > 0) & (y0 > 0) & (x1 < w) & (y1 < h)
        if (inside & (st[1:, cv2.CC_STAT_AREA] >= max(16, MIN_BLOB * h * w))).any():
            return np.zeros_like(ghost)
    dist = cv2.distanceTransform((~other).view(np.uint8), cv2.DIST_L2, 3)
    n, lab = cv2.connectedComponents(ghost.view(np.uint8), connectivity=8)
    nearest = np.full(n, np.inf, np.float32)
    np.minimum.at(nearest, lab[ghost], dist[ghost])
    keep = nearest >= share * max(h, w)
    keep[0] = False
    return keep[lab]


def empty_stretch(shown: np.ndarray, times: np.ndarray, min_span: float,
                  ends: tuple[float, float] | None = None, both: bool = False) -> np.ndarray:
    """Pixels whose empty-scene samples form a stretch at the clip's start or end.

    Parameters
    ----------
    shown : numpy.ndarray, shape (K, N), bool
        Per sample (in time order) and pixel: the sample shows the empty scene there.
    times : numpy.ndarray, shape (K,), float
        The samples' times, seconds.
    min_span : float
        Shortest stretch, seconds, from the first (last) sample to the last (first)
        sample of the stretch that shows the scene.
    ends : (float, float), optional
        The clip's first and last frame times, seconds: the stretch is measured from
        there instead of from the first (last) sample (:data:`FROM_CLIP_ENDS`).
    both : bool
        Also take a stretch from the start and one from the end together when their
        spans add up to ``min_span`` (:data:`BOTH_ENDS`).

    Returns
    -------
    numpy.ndarray, shape (N,), bool
        The stretch starts at the first sample or ends at the last one, runs over
        consecutive samples (one sample missing between two that show the scene is
        bridged: the ghost test misses a sample now and then) and spans ``min_span``
        (with ``both``: or the stretches at both ends do together).
    """
    k = shown.shape[0]
    out = np.zeros(shown.shape[1], bool)
    if k < 2:
        return out
    t0 = (times[0], times[-1]) if ends is None else ends
    spans = []
    for s, t, origin in ((shown, times, t0[0]), (shown[::-1], times[::-1], t0[1])):
        fill = s.copy()
        fill[1:-1] |= s[:-2] & s[2:]
        run = np.logical_and.accumulate(fill, axis=0) & s
        # The last sample of the stretch that shows the scene (run is False from the
        # first gap on, and True at 0 only where the end sample shows it).
        last = k - 1 - np.argmax(run[::-1], axis=0)
        span = np.where(run[0], np.abs(t[last] - origin), -np.inf)
        out |= span >= min_span
        spans.append(span)
    if both:
        out |= spans[0] + spans[1] >= min_span
    return out


def _nanmedian0(vals: np.ndarray) -> np.ndarray:
    """``numpy.nanmedian(vals, axis=0)`` of (K, N, 3) float32 whole numbers, each
    column with at least one number: the same values (the mean of two whole numbers
    below 2 ** 23 is exact) by one sort along the contiguous axis, several times
    faster than nanmedian's masked arrays."""
    srt = np.sort(np.ascontiguousarray(np.moveaxis(vals, 0, -1)), axis=-1)  # NaN last
    n = np.count_nonzero(~np.isnan(srt), axis=-1)[..., None]
    lo = np.take_along_axis(srt, (n - 1) // 2, axis=-1)[..., 0]
    hi = np.take_along_axis(srt, n // 2, axis=-1)[..., 0]
    return (lo + hi) / np.float32(2)


#: Where the clip's first and last samples agree (the same scene at both ends) and
#: their common colour is not the plate's (:data:`ENDS_OFF_PLATE`), the samples'
#: first-pass masks that the ghosts are found in compare at the plate's global
#: threshold, not at 3 x the noise map (:func:`_ends_agree_model`). The noise map is
#: measured against the first plate over the samples the vote took as scene; a person
#: who sat there in most of them and moved a little (sbi_candela, tuning: his legs on
#: the sofa, noise map 10-24 against a threshold of 15) inflates it, and the ghost of
#: the sitting man at the clip's ends loses most of its pixels: the legs stay in the
#: plate. Both ends showing the same thing says that what came between was someone
#: who came and went, not the sensor's noise. On since wt-sil6, with
#: :data:`ENDS_OFF_PLATE` and :data:`BOTH_ENDS`: sbi_candela 0.876 / 0.821 -> 0.885 /
#: 0.830, cdnet_office_enter 0.911 / 0.781 -> 0.909 / 0.781 (benchmarks/RESULTS.md).
#: (wt-sil4 tried it everywhere the ends agree, alone, with the even sampler: candela
#: 0.889 -> 0.934 but mmskeleton_taichi, validation, -0.0106; with convert's sampler
#: it finds the legs' ghost in samples 0-2 and 22-23 of 24, each end's stretch under
#: :data:`MIN_EMPTY_S`, and changes nothing alone.)
ENDS_AGREE = True
#: ... and only where the ends' common colour (their mean, each scaled by its gain)
#: differs from the plate by more than the threshold: pixels the plate took from the
#: middle of the clip. On sbi_candela 2,986 pixels instead of 36,340 (a third of the
#: frame, where the ends agree with the plate and nothing is to be found), with the
#: same figures.
ENDS_OFF_PLATE = True
#: An empty stretch may also be the stretch from the first sample and the one from the
#: last sample together (:func:`empty_stretch`'s ``both``): when both ends show the
#: same ghost, the person came and went, and the two spans add up to
#: :data:`MIN_EMPTY_S`. sbi_candela's legs: 0.63 s from the start, 0.47 s from the end
#: (samples at frames 9-29 and 330-344 of 350, 30 fps).
BOTH_ENDS = True


def _ends_agree_model(model, frames: np.ndarray, gains: np.ndarray):
    """``model`` with its noise map lowered to ``threshold / 3`` (so that 3 x the map is
    the global threshold) where the first and last of ``frames``, each scaled by its
    gain, differ by at most the threshold (L1 over the channels) and, with
    :data:`ENDS_OFF_PLATE`, their mean differs from the plate by more than it;
    ``model`` itself when nothing changes."""
    first = np.clip(frames[0] / gains[0], 0, 255)
    last = np.clip(frames[-1] / gains[-1], 0, 255)
    agree = np.abs(first - last).sum(axis=-1) <= model.threshold
    if ENDS_OFF_PLATE:
        agree &= np.abs((first + last) / 2 - model.plate).sum(axis=-1) > model.threshold
    cap = np.float32(model.threshold / 3.0)
    lower = agree & (model.noise_map > cap)
    if not lower.any():
        return model
    return replace(model, noise_map=np.where(lower, cap, model.noise_map).astype(np.float32))


def plate_from_empty(model, frames: np.ndarray, gains: np.ndarray, *,
                     ratio: float = GHOST_RATIO, times: np.ndarray | None = None,
                     ends: tuple[float, float] | None = None):
    """Re-take the plate where samples show the empty scene (see the module docstring).

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The samples the plate was estimated from.
    gains : numpy.ndarray, shape (K, 3)
        Their per-channel gains relative to the plate.
    ratio : float
        See :func:`ghost_blobs`.
    times : numpy.ndarray, shape (K,), optional
        The samples' times, seconds (default: ``model.sample_indices`` at
        :data:`ASSUMED_FPS`).
    ends : (float, float), optional
        The clip's first and last frame times, seconds; with :data:`FROM_CLIP_ENDS`,
        an empty stretch of ghosts apart from the person (:func:`_apart`) may also be
        measured from them (default: only from the first and last sample).

    Returns
    -------
    vidcap.video.background.BackgroundModel
        With the plate replaced in the ghosts (and those pixels no longer never seen);
        the same model when no sample shows a ghost.
    """
    from vidcap.video.platepass import _person_masks

    k = len(frames)
    if k < 3:
        return model
    found_by = _ends_agree_model(model, frames, gains) if ENDS_AGREE else model
    ghosts = np.zeros(frames.shape[:3], bool)
    # The ghosts apart from the sample's other blobs (:data:`GHOST_APART`): only they
    # may stretch to the clip's ends (:data:`FROM_CLIP_ENDS`).
    use_ends = FROM_CLIP_ENDS and ends is not None
    apart = np.zeros(frames.shape[:3], bool)
    # The samples scaled to the plate's exposure, only round each sample's blobs:
    # ghost_blobs reads no further, and only ghost pixels are read below.
    scaled = np.zeros(frames.shape, np.uint8)  # (zeroed lazily, unlike zeros_like)
    # The stretch runs from the first or the last sample: no ghost there, nothing to
    # do (and only those two samples' cost).
    for order in ((0, k - 1), range(1, k - 1)):
        order = list(order)
        masks = _person_masks(found_by, frames[order], gains[order])
        for t, m in zip(order, masks, strict=True):
            box = padded_box(m, 3)
            if box is None:
                continue
            scaled[t][box] = np.clip(frames[t][box] / gains[t], 0, 255).astype(np.uint8)
            ghosts[t] = ghost_blobs(scaled[t], model.plate, m, ratio=ratio)
            if use_ends and ghosts[t].any():
                apart[t] = _apart(ghosts[t], m, GHOST_APART)
        if model.self_lit is not None:
            ghosts[order] &= ~model.self_lit
            apart[order] &= ~model.self_lit
        if not (ghosts[0].any() or ghosts[-1].any()):
            return model
    if times is None:
        idx = model.sample_indices if len(model.sample_indices) == k else np.arange(k)
        times = np.asarray(idx, np.float64) / ASSUMED_FPS
    times = np.asarray(times, np.float64)

    def stretch(shown, sel):
        # From the first / last sample as before; from the clip's own first / last
        # frame when the ghosts lie apart from the person.
        out = empty_stretch(shown, times, MIN_EMPTY_S, both=BOTH_ENDS)
        if use_ends:
            out |= empty_stretch(shown & apart[:, sel], times, MIN_EMPTY_S, ends)
        return out

    count = ghosts.sum(axis=0, dtype=np.int16)
    redo = count >= MIN_AGREE
    if redo.any():
        # A first cut (the stretch of the ghosts holds wherever that of the agreeing
        # ones below does): the median is only taken where it may be needed.
        idx = np.flatnonzero(redo.ravel())
        redo.ravel()[idx[~stretch(ghosts[:, redo], redo)]] = False
    if not redo.any():
        return model
    # Median over the samples that show the scene there (NaN elsewhere).
    vals = scaled[:, redo].astype(np.float32)  # (K, N, 3)
    vals[~ghosts[:, redo]] = np.nan
    med = _nanmedian0(vals)
    # The empty scene is the same in every sample that shows it: at least
    # MIN_AGREE of them agree with their median (a person taken for a ghost in one
    # sample, in another pose in the next, does not).
    tmap = np.maximum(model.threshold, 3.0 * model.noise_map)[redo]
    near = np.abs(vals - med).sum(axis=-1) <= tmap  # (NaN compares False)
    ok = (near.sum(axis=0) >= MIN_AGREE) & stretch(near, redo)
    idx = np.flatnonzero(redo.ravel())
    redo.ravel()[idx[~ok]] = False
    if not redo.any():
        return model
    plate = model.plate.copy()
    plate[redo] = np.clip(med[ok], 0, 255).astype(np.uint8)
    conf = np.maximum(model.confidence, np.where(redo, count / k, 0)).astype(np.float32)
    return replace(model, plate=plate, never_seen=model.never_seen & ~redo, confidence=conf)
