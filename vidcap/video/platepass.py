"""Second looks at a plate estimated from the video (issue 26, Build 1 and 3).

:func:`vidcap.video.background.estimate_background` votes, per pixel, for the colour the
scene shows most stably. Two things real clips need are added here, on the same
sampled frames:

* **Self-lit pixels** (a lamp, a screen, a window) keep their level while the
  camera's exposure drifts; compared with a plate scaled by the frame's gain they
  would differ in every frame without ever moving and be taken for a person. They
  are found (:func:`vidcap.video.stillparts.self_lit`), their plate is the median as
  recorded, and the silhouette stage compares them unscaled.
* **Pixels the plate took from the person although the scene was seen there**
  (:mod:`vidcap.video.absorbed`: a leg that stands on the same floorboards in most
  samples), after the appearance pass, re-taken from the samples that show the scene's
  colours there.
* **Plate, person, plate again.** The silhouettes of the samples are extracted with
  the first plate; each pixel's plate is then re-taken from the samples in which
  it lies outside the (dilated) person. A pixel the vote or the never-seen
  inpainting got wrong while it was in fact uncovered in several samples (the gap
  between legs apart, the floor between the feet) gets its real background back
  and stops being flagged never seen. Only the never-seen area and a ring around
  it (where the plate was inpainted) are re-taken: elsewhere the vote saw it.
* **A guessed colour no sample shows** (:func:`_retake_modes`, :data:`MODE_RETAKE`): in
  the same area, a plate colour that none of the samples shows there gives way to the
  colour most samples show, when the others show the person passing (many colours,
  not a second steady one) and the samples showing it lie outside the person. The
  ghosts beside a person who sways over the same spot (pose2sim cam3's window and
  mats: the vote's mix of his colours, the first-pass person swallowing the ghost so
  that the pass above never saw the scene there).
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from vidcap.video.maskbox import padded_box

__all__ = ["refine_plate"]

#: Samples (share, at least 3) outside the person a pixel needs to be re-taken.
MIN_SEEN_SHARE = 0.2
#: Dilation of the first-pass person, share of the frame's height (its blurred
#: outline, a shadow at the feet).
PERSON_MARGIN = 0.02
#: Re-take the guessed area's plate from the colour its samples show most often
#: (:func:`_retake_modes`).
MODE_RETAKE = True
#: Share of the samples the most shown colour needs (:func:`_retake_modes`).
MODE_SHARE = 0.5
#: A self-lit pixel's sample is the lamp's noise unless it is this many times further
#: from the plate than the samples' median distance (plus as many thresholds): a
#: person in front of the lamp (:func:`_with_self_lit`).
LIT_OUTLIER = 3.0


def refine_plate(model, frames: np.ndarray, gains: np.ndarray, small_hw, *,
                 still_parts: bool = False, colour_models: bool = False,
                 small: np.ndarray | None = None) -> object:
    """Self-lit pixels, the appearance pass, absorbed pixels re-taken, then one plate ->
    person -> plate pass (then, when asked, the still parts of the person by appearance).

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
        The first estimate.
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The samples it was estimated from.
    gains : numpy.ndarray, shape (K, 3)
        Their per-channel gains relative to the plate.
    small_hw : (int, int)
        The low working resolution of the estimate.
    still_parts : bool
        Also look for parts of the person that never move (:mod:`vidcap.video.stillparts`).
        Off by default: on a side-view jumping-jacks render it lifts the median IoU
        from 0.06 to 0.53, but on a walker with empty stretches it took background for
        still parts (see benchmarks/RESULTS.md, Silhouettes).
    colour_models : bool
        Learn the clip's person and scene colours for the silhouettes' graph cut
        (:func:`vidcap.video.graphcut.clip_colours`); on when the cut runs
        (``--graph-cut``).
    small : numpy.ndarray, shape (K, h, w, 3), optional
        :func:`vidcap.video.appearance.small_samples` of ``frames``, which the colour
        passes share (made here when not given).

    Returns
    -------
    vidcap.video.background.BackgroundModel
    """
    from vidcap.video.absorbed import retake_absorbed
    from vidcap.video.appearance import appearance_plate, small_samples

    model = _with_self_lit(model, frames, gains, small_hw)
    if small is None:
        small = small_samples(frames, gains)
    model = appearance_plate(model, frames, gains, small=small)
    model = retake_absorbed(model, frames, gains, small=small)
    model = _second_pass(model, frames, gains)
    if MODE_RETAKE:
        model = _retake_modes(model, frames, gains)
    if still_parts:
        model = _with_still_parts(model, frames, gains, small_hw)
    if not colour_models:
        return model
    from vidcap.video.graphcut import clip_colours

    return replace(model, colours=clip_colours(model, frames, gains, small))


def _with_still_parts(model, frames, gains, small_hw):
    """Static parts of the person found by appearance (:mod:`vidcap.video.stillparts`):
    flagged never seen, their plate inpainted from around them, kept as
    ``still_person``."""
    from vidcap.video.stillparts import still_parts

    k, hh, ww = frames.shape[:3]
    h, w = small_hw
    small = np.stack([cv2.resize(f, (w, h), interpolation=cv2.INTER_AREA) for f in frames])
    small = np.clip(small / gains[:, None, None, :], 0, 255).astype(np.uint8)
    plate_s = cv2.resize(model.plate, (w, h), interpolation=cv2.INTER_AREA)
    exclude = None
    if model.self_lit is not None:
        exclude = cv2.resize(model.self_lit.view(np.uint8), (w, h),
                             interpolation=cv2.INTER_NEAREST) > 0
    still = still_parts(small, plate_s, model.threshold, exclude=exclude)
    if not still.any():
        return model
    full = cv2.resize(still.view(np.uint8), (ww, hh), interpolation=cv2.INTER_NEAREST)
    r = int(np.ceil(hh / h)) + 1
    ring = cv2.dilate(full, np.ones((2 * r + 1, 2 * r + 1), np.uint8))
    plate = cv2.inpaint(model.plate, ring, 5, cv2.INPAINT_TELEA)
    full = full > 0
    conf = np.where(full, 0.0, model.confidence).astype(np.float32)
    return replace(model, plate=plate, never_seen=model.never_seen | full, confidence=conf,
                   still_person=full, person_plate=model.plate)


def _with_self_lit(model, frames, gains, small_hw):
    from vidcap.video.platemedian import masked_median as _masked_median
    from vidcap.video.stillparts import self_lit

    k, hh, ww = frames.shape[:3]
    h, w = small_hw
    raw = np.stack([cv2.resize(f, (w, h), interpolation=cv2.INTER_AREA) for f in frames])
    lit = self_lit(raw.astype(np.float32), gains, float(np.mean(model.noise_sigma)))
    if not lit.any():
        return model
    lit = cv2.resize(lit.view(np.uint8), (ww, hh), interpolation=cv2.INTER_NEAREST) > 0
    plate = model.plate.copy()
    samples = frames[:, lit]  # (K, N, 3)
    plate[lit] = _masked_median(samples[:, :, None], None)[:, 0]
    # A lit wall's glow is part lamp, part scene: it follows the exposure in part.
    # Its spread about the unscaled plate is its noise (the per-pixel threshold).
    resid = np.abs(samples.astype(np.float32) - plate[lit].astype(np.float32)).sum(axis=-1)
    # ... but not a sample where someone stands in front of it: their distance from the
    # lamp is no noise of the lamp's, and as a threshold it hid them there (06_07)
    usual = resid <= LIT_OUTLIER * np.median(resid, axis=0) + LIT_OUTLIER * model.threshold
    resid = np.where(usual, resid, 0.0)
    noise_map = model.noise_map.copy()
    noise_map[lit] = np.maximum(noise_map[lit], resid.max(axis=0) / 2.0)
    never = model.never_seen & ~lit  # a lamp is scene, seen in every frame
    return replace(model, plate=plate, self_lit=lit, never_seen=never, noise_map=noise_map)


def _person_masks(model, frames, gains) -> np.ndarray:
    """The samples' person with the first plate, (K, H, W) uint8 0/1: pixels beyond
    the per-pixel threshold (self-lit ones compared unscaled), de-specked, in blobs
    of at least 0.2 % of the frame, holes filled. (A lean version of the silhouette
    stage: the dilation that follows covers its rough outline.)"""
    k, hh, ww = frames.shape[:3]
    tmap = np.maximum(model.threshold, 3.0 * model.noise_map).astype(np.float32)
    min_area = max(16, int(2e-3 * hh * ww))
    out = np.zeros((k, hh, ww), np.uint8)
    plate = model.plate.astype(np.float32)
    lit = model.self_lit
    ones = np.ones((1, 3), np.float32)
    for t in range(k):
        # cv2 multiplies by the gains in float32 too (the same values as plate *
        # gains[t]), 3x faster than numpy's broadcast over the channels
        ref = cv2.multiply(plate, tuple(float(g) for g in gains[t]) + (0.0,))
        if lit is not None:
            ref[lit] = plate[lit]
        # |frame - ref| summed over the channels: the same float32 values as numpy's
        # abs(...).sum(axis=-1) (a + b + c in that order) at half its time, which
        # reduces a length-3 axis slowly (this runs 3-4 times per plate).
        l1 = cv2.transform(cv2.absdiff(frames[t].astype(np.float32), ref), ones)
        fg = cv2.medianBlur((l1 > tmap).view(np.uint8), 3)
        contours, _ = cv2.findContours(fg, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        big = [c for c in contours if cv2.contourArea(c) >= min_area]
        if big:
            cv2.drawContours(out[t], big, -1, 1, cv2.FILLED)
    return out


def dilate_in_box(mask: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """``cv2.dilate(mask, kernel)`` computed in the bounding box of the mask's pixels
    and the kernel's reach round it: the same values (nothing else is reached) at the
    cost of the person's area, not the frame's, with a large kernel on a large frame.

    Parameters
    ----------
    mask : numpy.ndarray, shape (H, W), uint8
    kernel : numpy.ndarray, shape (2 * ry + 1, 2 * rx + 1), uint8
        A structuring element centred on its middle.

    Returns
    -------
    numpy.ndarray, shape (H, W), uint8
    """
    out = np.zeros_like(mask)
    box = padded_box(mask, kernel.shape[0] // 2, kernel.shape[1] // 2)
    if box is not None:
        out[box] = cv2.dilate(mask[box], kernel)
    return out


def _min_seen(k: int) -> int:
    """The fewest of ``k`` samples that count as showing something: :data:`MIN_SEEN_SHARE`
    of them, at least 3."""
    return max(3, int(np.ceil(MIN_SEEN_SHARE * k)))


def _guessed_area(model) -> np.ndarray:
    """Where the first plate is a guess, (H, W) bool: the never-seen area and the ring
    it was inpainted from, 3 % of the frame's height wide (elsewhere the vote saw the
    background)."""
    r = max(3, int(round(0.03 * model.never_seen.shape[0])))
    return cv2.dilate(model.never_seen.view(np.uint8),
                      np.ones((2 * r + 1, 2 * r + 1), np.uint8)) > 0


def _second_pass(model, frames, gains):
    from vidcap.video.platemedian import robust_plate as _robust_plate

    k, hh, ww = frames.shape[:3]
    if k < 4 or not model.never_seen.any():
        return model
    guessed = _guessed_area(model)
    masks = _person_masks(model, frames, gains)
    if not masks.any():
        return model
    r = max(1, int(round(PERSON_MARGIN * hh)))
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    # Nothing changes outside the guessed area: the rest runs in its bounding box (the
    # masks dilated in that box and r pixels round it, all the dilation reads), the
    # same values as over the whole frame in a fraction of the time.
    x, y, bw, bh = cv2.boundingRect(guessed.view(np.uint8))
    y0, x0 = max(0, y - r), max(0, x - r)
    wide = (slice(y0, min(hh, y + bh + r)), slice(x0, min(ww, x + bw + r)))
    box = (slice(y, y + bh), slice(x, x + bw))
    inner = (slice(y - y0, y - y0 + bh), slice(x - x0, x - x0 + bw))
    covered = np.stack([dilate_in_box(m[wide], kernel)[inner] for m in masks])
    seen = (covered == 0).astype(np.uint8)
    count = np.zeros((hh, ww), np.int32)
    count[box] = seen.sum(axis=0, dtype=np.int32)
    enough = count[box] >= _min_seen(k)
    again = _robust_plate(frames[:, box[0], box[1]], gains, seen)
    far = np.abs(again.astype(np.int16) - model.plate[box].astype(np.int16)).sum(axis=-1)
    redo = np.zeros((hh, ww), bool)
    redo[box] = enough & (far > model.threshold) & guessed[box]
    if model.self_lit is not None:
        redo &= ~model.self_lit
    if not redo.any():
        return model
    plate = model.plate.copy()
    plate[box][redo[box]] = again[redo[box]]
    conf = np.maximum(model.confidence, np.where(redo, count / k, 0)).astype(np.float32)
    return replace(model, plate=plate, never_seen=model.never_seen & ~redo, confidence=conf)


def _close_to(sub: np.ndarray, i: int, tmap: np.ndarray) -> np.ndarray:
    """(K, N) bool: the samples ``sub`` (K, N, 3) int16 within ``tmap`` (N,) of sample
    ``i``'s colour in L1 (summed over the channel planes: the same integers as the
    (K, N, 3) differences summed, without their temporaries)."""
    d = np.abs(sub[..., 0] - sub[i, :, 0])
    d += np.abs(sub[..., 1] - sub[i, :, 1])
    d += np.abs(sub[..., 2] - sub[i, :, 2])
    return d <= tmap


def _retake_modes(model, frames, gains):
    """The guessed area (never seen and the ring round it, as :func:`_second_pass`)
    re-taken where no sample shows the plate's colour and most samples show one colour:
    the median of the samples within the threshold of it. A plate colour no sample
    shows is a guess (inpainted, or the vote's mix of the person's colours: a ghost
    beside a person who sways over the same spot), while the scene seen in most samples
    is what the pixel is."""
    from vidcap.video.platemedian import masked_median, normalised_u8

    k, hh, ww = frames.shape[:3]
    if k < 4 or not model.never_seen.any():
        return model
    guessed = _guessed_area(model)
    if model.self_lit is not None:
        guessed &= ~model.self_lit
    ys, xs = np.nonzero(guessed)
    tmap = np.maximum(model.threshold, 3.0 * model.noise_map[ys, xs]).astype(np.float32)
    # (K, N, 3) the guessed pixels' samples at the plate's exposure
    sub = normalised_u8(frames[:, ys, xs][:, None], gains)[:, 0].astype(np.int16)
    plate = model.plate[ys, xs].astype(np.int16)
    unshown = ~(np.abs(sub - plate).sum(-1) <= tmap).any(axis=0)
    sub, tmap, plate = sub[:, unshown], tmap[unshown], plate[unshown]
    ys, xs = ys[unshown], xs[unshown]
    need = max(3, int(np.ceil(MODE_SHARE * k)))
    if len(ys) == 0:
        return model
    best = np.zeros(len(ys), np.int32)
    best_i = np.zeros(len(ys), np.intp)
    for i in range(k):
        support = _close_to(sub, i, tmap).sum(axis=0)
        better = support > best
        best[better] = support[better]
        best_i[better] = i
    # ... and other samples show something else: a colour every sample shows never
    # changed, and the vote's verdict (a person who never moved) stands.
    keep = (best >= need) & (k - best >= _min_seen(k))
    if not keep.any():
        return model
    sub, tmap, plate = sub[:, keep], tmap[keep], plate[keep]
    ys, xs, best_i = ys[keep], xs[keep], best_i[keep]
    colour = sub[best_i, np.arange(len(ys))]
    near = np.abs(sub - colour).sum(-1) <= tmap
    # The other samples must not agree on a second colour: two steady colours (the
    # scene, and a part of the person who holds still over it for a while) are not
    # told apart by how often each is shown; the person passing shows many colours.
    second = np.zeros(len(ys), np.int32)
    for i in range(k):
        support = (_close_to(sub, i, tmap) & ~near).sum(axis=0)
        second = np.maximum(second, np.where(near[i], 0, support))
    again = masked_median(sub.astype(np.uint8)[:, None], ~near[:, None])[0]
    far = ((np.abs(again.astype(np.int16) - plate).sum(-1) > tmap)
           & (second < _min_seen(k)))
    if not far.any():
        return model
    ys, xs, again, near = ys[far], xs[far], again[far], near[:, far]
    out = model.plate.copy()
    out[ys, xs] = again
    # Plate, person, plate: with the new colours the samples that show them must show
    # them outside the person (a person who stands on the pixel throughout would show
    # his own colour in most samples, inside his blob).
    inside = _person_masks(replace(model, plate=out), frames, gains)[:, ys, xs] > 0
    apart = (near & ~inside).sum(axis=0) > (near & inside).sum(axis=0)
    if not apart.any():
        return model
    out[ys[~apart], xs[~apart]] = model.plate[ys[~apart], xs[~apart]]
    ys, xs, near = ys[apart], xs[apart], near[:, apart]
    redo = np.zeros((hh, ww), bool)
    redo[ys, xs] = True
    conf = model.confidence.copy()
    conf[ys, xs] = np.maximum(conf[ys, xs], near.mean(axis=0))
    return replace(model, plate=out, never_seen=model.never_seen & ~redo, confidence=conf)
