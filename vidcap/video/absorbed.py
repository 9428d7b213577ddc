"""Plate pixels that show the person although the scene was seen there (issue 26).

A person who stays near one spot (stepping in place, bending, twisting) covers some
pixels in most sampled frames but not all: a leg stands on the same floorboards in
four samples of five. The plate's vote keeps the majority, the person's colour; the
silhouettes then miss the leg where it stands (no difference from the plate) and take
the floor for person where it left (a difference). The pixel was seen, so it is not
flagged never seen and :mod:`vidcap.video.appearance` (which handles what is never
seen, and only for a person who keeps still) leaves it.

Appearance settles it per pixel, over the whole clip: where the plate's colour is the
person's (the clip's colour models, :func:`vidcap.video.appearance.person_scene_models`)
and some samples show the pixel in a colour of the scene, those samples are the
background there; the plate is re-taken from them. Only inside the motion footprint
(what differs from the plate in some samples, grown a little): elsewhere the vote saw
the scene in most samples. Pixels flagged never seen are re-taken, and un-flagged, when
a third of the samples show the scene there (the flag spread from a static torso into
the arms' sweep).

The other way round (:func:`flag_unseen`): a candidate that no sample shows in a colour of
the scene was never seen uncovered (a dancer's back, a leg held in place while the limbs
sweep round it): it is flagged never seen and its plate inpainted, so that the silhouettes
see the person there. Without asking the colour models (:data:`FLAG_STILL`): for a person
who stays in one place, footprint pixels between the person's whose plate and every sample
are unlike the seen scene round them (a still torso the colour of a floor elsewhere in the
frame), their plate guessed from beyond the footprint.
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from vidcap.video.masks import centroid_columns

__all__ = ["flag_unseen", "retake_absorbed"]

#: The plate's colour must be this much more likely under the person's model (log
#: ratio, after a 3x3 mean) to be re-taken; a sample this much more likely under the
#: scene's shows the background there. One such sample is enough: both tests must
#: hold. Chosen on the tuning renders 131_01 0-3 s side and 14_19 10-13 s 3/4 (median
#: IoU 0.836 / 0.721 without the step; margin 1 and two samples: 0.913 / 0.810;
#: margin 0.25 and one sample: 0.964 / 0.935; margin 0 cost pose2sim cam1 0.33 ->
#: 0.32 against MediaPipe's masks, 0.25 lifts it to 0.34).
MARGIN = 0.25
#: A pixel flagged never seen is re-taken (and un-flagged) when this share of the
#: samples shows it in the scene's colours: the flag reaches beyond a body part that
#: never moved into where the limbs sweep (jacks side: 6.5 % of the frame flagged, 4.2
#: % in truth). Chosen on the tuning renders: jacks side 0.884 -> 0.892, 3/4 0.902 ->
#: 0.915, arms 3/4 0.890 -> 0.901, the never-seen share nearer the truth on each; jacks
#: front and arms side 0.981 / 0.980 -> 0.977 (a sixth of the samples: 0.974; half:
#: 14_19 3/4 0.942 -> 0.935).
NEVER_SHARE = 1 / 3
#: The footprint is grown by this share of the working frame's long side.
REACH = 0.02
#: Candidates (the plate's colour the person's, in the footprint) that no sample shows
#: in a scene colour are never seen: flagged so, their plate inpainted from round them
#: (:func:`flag_unseen`, run by :func:`vidcap.video.background.estimate_background` after
#: the empty-scene and person-box passes, whose ghost and steady tests need the plate's
#: own edges: run before them it cost cdnet_office_enter 0.901 -> 0.407). A dancer's back
#: or a standing leg covers the same pixels in every sample while the limbs make the
#: footprint round them; the vote keeps the person's colour there and, the pixel being
#: in the footprint, nobody flagged it. The plate's colour must be FLAG_MARGIN more likely
#: under the person's model (without its uniform share) than the scene's, and no seen
#: scene pixel within FLAG_RADIUS ring widths may have it (within FLAG_UNLIKE
#: thresholds, L1). Chosen on the tuning rows (benchmarks/silhouettes_real.py --quick,
#: median IoU): off -> on, 05_18 side 0.788 -> 0.952, 05_12 3/4 back 0.854 -> 0.975,
#: 05_09 3/4 0.913 -> 0.972; FLAG_MARGIN 0.25 / 1 / 2: pose2sim cam3 (vs MediaPipe's
#: masks; off 0.805) 0.731 / 0.753 / 0.803, cam4 (off 0.786) 0.748 / 0.768 / 0.786,
#: 05_18 0.935 / 0.947 / 0.952; FLAG_RADIUS 1 / 2 / 3: 14_19 10-13 s 3/4 0.948 / 0.962
#: / 0.945; without the unlike test a chrome table foot the legs step round was flagged
#: (14_19 3/4 0.948 -> 0.920).
FLAG_UNSEEN, FLAG_MARGIN, FLAG_UNLIKE, FLAG_RADIUS = True, 2.0, 3.0, 2.0
#: Also flag never seen the footprint pixels whose plate colour and every sample's colour
#: are unlike the seen scene round them (FLAG_UNLIKE thresholds within STILL_RADIUS ring
#: widths, three times as far for a pixel with none so near; :func:`_still_unlike`),
#: without asking the person's colour model: a person who barely moves shows the
#: differences from the plate mostly where the plate holds the person and the sample the
#: scene, and a torso that never left its pixels is rarely among the sure person pixels,
#: so its colour is unlikely under that model although no sample shows the scene there.
#: Off on its own it did not generalise (wt-still2; silhouettes_real.py --quick --pck;
#: benchmarks/HISTORY.md, Silhouettes):
#: 06_10 4-7 s side 0.837 -> 0.955, 05_13 0.905 -> 0.956, but 02_04 0.967 -> 0.893, 05_05
#: 0.874 -> 0.797, 05_10 0.956 -> 0.894, cdnet_office_enter 0.901 -> 0.788, sbi_candela
#: 0.889 -> 0.809, pose2sim cam4 0.786 -> 0.579: scene objects of their own colour inside
#: the footprint (a table foot, a door, a lamp post) pass the same colour tests. On since
#: two gates (issue-26 silval2 helper), chosen on the tuning rows:
#:
#: * STILL_BETWEEN: a flagged pixel lies between the person's pixels (left and right in
#:   its row, or above and below in its column; :func:`vidcap.video.appearance.
#:   between_moved`) in at least this share of the samples: a torso between the arms,
#:   head and legs, not a table foot beside the legs' sweep. Flagged pixels whose truth
#:   covers >= half / < a tenth of the samples, without -> with the gate at 0.7: 05_05
#:   side 1327 / 72 -> 1241 / 0 (the chrome table foot), 05_12 1551 / 73 -> 1055 / 0,
#:   02_07 11-14 s front 2604 / 271 -> 333 / 0, 14_19 3/4 66 / 123 -> 0 / 0, arms front
#:   13 / 269 -> 0 / 0, jacks 3/4 129 / 325 -> 0 / 0 (05_13, 06_10: all good, kept);
#:   0.5 kept 40 bad pixels of jacks 3/4 and 4 of arms front.
#: * STILL_TRAVEL: only when the person stays in one place over the whole clip (the
#:   centroid of each sample's foreground within this share of the frame's width): the
#:   rows it helps travel 0.04-0.06 (05_05, 05_13, 06_10 4-7 s), those it cost 0.116
#:   (05_12 0.975 -> 0.967), 0.156 (pose2sim cam4 vs MediaPipe's masks 0.786 -> 0.762),
#:   0.20 and 0.51 (cdnet_office_enter 0.901 -> 0.858, sbi_candela 0.889 -> 0.834: a man
#:   who walks in and stands or sits).
#:
#: The flagged pixels' plate is guessed from beyond the motion footprint
#: (:func:`_guess_beyond`): 05_05 0.874 -> 0.903 (0.874 from their own edge, which
#: carries in the unflagged rest of the torso), 06_10 0.955 -> 0.965, 05_13 0.956 -> 0.963.
#: Full table, off -> on (one run each, silhouettes_real.py --quick --pck --no-mediapipe):
#: tuning 06_10 4-7 s 0.837 -> 0.965, 05_13 0.905 -> 0.963, 05_05 0.874 -> 0.903;
#: validation 05_07 0.902 -> 0.976, 06_12 150 deg 0.922 -> 0.964, 06_10 2-5 s 0.923 ->
#: 0.937, 06_10 5-8 s 0.932 -> 0.943, but 05_10 0.956 -> 0.931, 06_14 0.944 -> 0.923,
#: mmskeleton_clean_jerk (vs MediaPipe's masks) 0.333 -> 0.322; the rest within 0.006.
FLAG_STILL, STILL_RADIUS, STILL_BETWEEN, STILL_TRAVEL = True, 1.0, 0.7, 0.1
#: A plate pixel is the scene, not the person, when at least this share of the samples
#: shows it in the plate's colour while the sample's person (what differs from the
#: plate) keeps at least :data:`AWAY` of the working frame's long side from its column:
#: the person is elsewhere, so what the pixel shows is what stands behind. A runner crossing the
#: frame passes a white fence post in 2-3 samples of 24 (her white top made the post's
#: colour the person's, her dark shorts the scene's: the post was re-taken dark and cut
#: her in two in 4 frames of 33, sports2d_run p10 IoU 0.42 against MediaPipe's). Away
#: from the person, the post's pixels showed the plate's colour in >= 12 samples of 24
#: (all of them >= 6); on the tuning renders 131_01 0-3 s side and 14_19 10-13 s 3/4
#: (a person in place) 0.7 % and 0.4 % of the re-taken pixels had >= 6 such samples.
CONFIRMED_SHARE, AWAY = 0.25, 0.05


def retake_absorbed(model, frames: np.ndarray, gains: np.ndarray, *,
                    work_size: int = 320, small: np.ndarray | None = None) -> object:
    """Re-take the plate where it shows the person although the scene was seen.

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
        The plate so far.
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The samples it was estimated from.
    gains : numpy.ndarray, shape (K, 3)
        Their per-channel gains relative to the plate.
    work_size : int
        Long side, pixels, of the working resolution of the colour decisions.
    small : numpy.ndarray, shape (K, h, w, 3), optional
        :func:`vidcap.video.appearance.small_samples` of ``frames`` at ``work_size``.

    Returns
    -------
    vidcap.video.background.BackgroundModel
        With ``plate`` (and ``confidence``) re-taken where absorbed; unchanged when
        the clip's colour models cannot be learnt or nothing is absorbed.
    """
    from vidcap.video.platemedian import robust_plate

    k = len(frames)
    ev = _evidence(model, frames, gains, work_size, small=small)
    if ev is None:
        return model
    wk, cand, llr = ev["wk"], ev["cand"], ev["llr"]
    seen = (llr < -MARGIN) & cand[None]
    count = seen.sum(axis=0)
    ok = cand & (count >= np.where(wk.never, max(1, int(np.ceil(NEVER_SHARE * k))), 1))
    if not ok.any():
        return model
    seen &= ok[None]
    take = wk.up(ok) > 0
    # (the medians only inside the box of what is re-taken: the footprint is small
    # next to a large frame)
    x, y, w, h = cv2.boundingRect(take.view(np.uint8))
    box = (slice(y, y + h), slice(x, x + w))
    masks = np.stack([wk.up(m)[box] for m in seen])
    again = robust_plate(np.ascontiguousarray(frames[:, box[0], box[1]]), gains, masks)
    far = np.abs(again.astype(np.int16) - model.plate[box].astype(np.int16)).sum(axis=-1)
    take[box] &= far > model.threshold
    if not take.any():
        return model
    plate = model.plate.copy()
    plate[box][take[box]] = again[take[box]]
    hh, ww = wk.full
    cnt = cv2.resize(count.astype(np.float32), (ww, hh), interpolation=cv2.INTER_NEAREST)
    conf = np.where(take, cnt / k, model.confidence).astype(np.float32)
    return replace(model, plate=plate, confidence=conf, never_seen=model.never_seen & ~take)


def _evidence(model, frames, gains, work_size, still=False, small=None):
    """What :func:`retake_absorbed` and :func:`flag_unseen` decide on, as a dict: the
    samples at the working resolution (``wk``), the person's colours (``px``), the
    scene's model (``scene``), the footprint grown by :data:`REACH` (``foot``), the
    candidates (``cand``: in it, the plate's colour the person's, or never seen) and
    the per-sample log ratio person / scene (``llr``, (k, h, w)); None when the clip's
    colour models cannot be learnt or nothing is a candidate (with ``still``, unless the
    still test will run: :data:`FLAG_STILL`, a person who stays in one place)."""
    from vidcap.video.appearance import (
        PRIOR_UNSEEN,
        _person_colours,
        _scene_model,
        _Work,
        colour_model,
        log_ratio,
    )

    if len(frames) < 4:
        return None
    wk = _Work(model, frames, gains, work_size, small)
    if wk.med_area < 16:
        return None
    px = _person_colours(wk)
    if px is None:
        # (a person who never leaves the never-seen area: what the samples show there,
        # as person_scene_models does)
        core = cv2.erode(wk.never.view(np.uint8), wk.disk) > 0
        if core.sum() >= 50:
            px = wk.small[:, core].reshape(-1, 3)
    scene = _scene_model(wk, wk.foot | wk.never)
    if px is None or scene is None:
        return None
    person = colour_model(px, uniform=PRIOR_UNSEEN)
    reach = max(1, round(REACH * max(wk.h, wk.w)))
    foot = cv2.dilate(wk.foot.view(np.uint8),
                      np.ones((2 * reach + 1,) * 2, np.uint8)) > 0
    llr_plate = cv2.blur(log_ratio(wk.plate, person, scene), (3, 3))
    # (never-seen pixels whatever their plate: it is an inpainted guess)
    cand = ((foot & (llr_plate > MARGIN) & ~_seen_without_person(wk)) | wk.never) & ~wk.lit
    if not cand.any() and not (still and FLAG_STILL and _stays(wk.fg)):
        return None
    llr = np.stack([cv2.blur(x, (3, 3)) for x in log_ratio(wk.small, person, scene)])
    return {"wk": wk, "px": px, "scene": scene, "foot": foot, "cand": cand, "llr": llr}


def flag_unseen(model, frames: np.ndarray, gains: np.ndarray, *,
                work_size: int = 320, small: np.ndarray | None = None) -> object:
    """Flag never seen the plate pixels that show the person and that no sample shows
    uncovered (see :data:`FLAG_UNSEEN`).

    Candidates as :func:`retake_absorbed`'s (in the motion footprint, the plate's colour
    the person's) that no sample shows in a colour of the scene, whose plate colour is
    one seen on the person (the person's model without its uniform share, by
    :data:`FLAG_MARGIN`) and unlike the seen scene round them (:func:`_unlike_scene`):
    a dancer's back or a standing leg that covers the same pixels in every sample while
    the limbs make the footprint round it. Run after the passes that use the samples'
    evidence of the empty scene (:mod:`vidcap.video.emptyscene`,
    :mod:`vidcap.video.personbox`), which need the plate's edges there.

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
        The plate so far.
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The samples it was estimated from.
    gains : numpy.ndarray, shape (K, 3)
        Their per-channel gains relative to the plate.
    work_size : int
        Long side, pixels, of the working resolution of the colour decisions.
    small : numpy.ndarray, shape (K, h, w, 3), optional
        :func:`vidcap.video.appearance.small_samples` of ``frames`` at ``work_size``.

    Returns
    -------
    vidcap.video.background.BackgroundModel
        With those pixels flagged ``never_seen``, their plate inpainted from round them
        and their confidence 0; unchanged when there are none.
    """
    from vidcap.video.appearance import colour_model, log_ratio

    # (the still test needs no candidate of the colour models)
    ev = _evidence(model, frames, gains, work_size, still=True, small=small)
    if ev is None:
        return model
    wk, cand = ev["wk"], ev["cand"]
    # (the person's model without its uniform share: a colour seen on the person, not
    # merely one the scene round it lacks)
    strict = cv2.blur(log_ratio(wk.plate, colour_model(ev["px"]), ev["scene"]), (3, 3))
    unseen = (cand & ~wk.never & ~(ev["llr"] < -MARGIN).any(axis=0)
              & (strict > FLAG_MARGIN))
    unseen &= _unlike_scene(wk, unseen, ~ev["foot"])
    still = _still_unlike(wk, ev["foot"]) if FLAG_STILL and _stays(wk.fg) else None
    if still is not None:
        unseen = unseen | still
    model = _flag_unseen(model, wk, unseen)
    if still is not None and still.any():
        model = replace(model, plate=_guess_beyond(model.plate, wk, still, ev["foot"]))
    return model


def _still_unlike(wk, foot: np.ndarray) -> np.ndarray:
    """(h, w) bool: footprint pixels (``foot``) whose plate colour and every sample's
    colour are unlike the seen scene round them (:data:`FLAG_STILL`): a body part that
    never left its pixels, whatever the person's colour model says of it; only pixels
    between the person's in :data:`STILL_BETWEEN` of the samples (not scene beside
    what moved).

    The plate's colour is tested first (one colour a pixel); only what passes has its
    samples tested."""
    from vidcap.video.appearance import between_moved, nearest_scene_distance

    pool = foot & ~wk.never & ~wk.lit & ~_seen_without_person(wk)
    if STILL_BETWEEN > 0:
        inside = np.zeros(pool.shape, np.float32)
        for f in wk.fg:
            inside += between_moved(f)
        pool &= inside >= STILL_BETWEEN * wk.k
    out = np.zeros(pool.shape, bool)
    ys, xs = np.nonzero(pool)
    if not len(ys):
        return out
    scene = ~foot & ~wk.never & ~wk.lit
    r = int(round(STILL_RADIUS * wk.ring_r))
    far = FLAG_UNLIKE * wk.thr

    # A pixel deeper in the footprint than r from the seen scene is compared three times
    # as far; none in that reach says nothing (the wall behind a body that bends and
    # rises: it is left as it is).
    reach = np.full(len(ys), r)
    d = nearest_scene_distance(wk.plate[ys, xs], ys, xs, wk.plate, scene, r, max(2, r // 6))
    deep = ~np.isfinite(d)
    reach[deep] = 3 * r
    d[deep] = nearest_scene_distance(wk.plate[ys[deep], xs[deep]], ys[deep], xs[deep],
                                     wk.plate, scene, 3 * r, max(2, r // 2))
    unlike = np.isfinite(d) & (d > far)
    ys, xs, reach = ys[unlike], xs[unlike], reach[unlike]
    if not len(ys):
        return out
    # Each sample's colour against the same sample's scene round the pixel (not the
    # plate's: a white wall the exposure drives into saturation differs from the plate
    # in every bright sample, and from its own surroundings in none).
    seen = np.zeros(len(ys), bool)
    for t in range(wk.k):
        for rr in np.unique(reach):
            left = ~seen & (reach == rr)
            if left.any():
                seen[left] = nearest_scene_distance(
                    wk.small[t, ys[left], xs[left]], ys[left], xs[left], wk.small[t],
                    scene & ~wk.fg[t], int(rr), max(2, int(rr) // 6)) <= far
    out[ys[~seen], xs[~seen]] = True
    # (a body part is an area the ring's width across: specks and slivers along the
    # footprint's edge, where the plate was inpainted, are not)
    n, lab, st, _ = cv2.connectedComponentsWithStats(out.view(np.uint8), connectivity=8)
    keep = np.concatenate([[False], st[1:, cv2.CC_STAT_AREA] >= wk.ring_r ** 2])
    return keep[lab]


def _stays(fg: np.ndarray) -> bool:
    """Whether the person stays in one place over the whole clip: the centroid of every
    sample's foreground ``fg`` (k, h, w) within :data:`STILL_TRAVEL` of the frame's width
    (samples with under 16 foreground pixels left out)."""
    cx = centroid_columns(fg)
    if len(cx) < 2:
        return False
    return bool(np.ptp(cx) <= STILL_TRAVEL * fg.shape[2])


def _seen_without_person(wk) -> np.ndarray:
    """(h, w) bool: pixels whose plate colour :data:`CONFIRMED_SHARE` of the samples show
    while their person (``wk.fg``) is :data:`AWAY` from them: the scene, confirmed.

    Away in columns: no part of the sample's foreground lies within AWAY of the pixel's
    column. (Not away from the foreground itself: a part the plate absorbed, a leg below
    the torso, is not foreground and would confirm its own colour.)"""
    r = max(1, round(AWAY * max(wk.h, wk.w)))
    cols = wk.fg.any(axis=1).view(np.uint8)  # (k, w)
    near = cv2.dilate(cols, np.ones((1, 2 * r + 1), np.uint8)) > 0
    count = ((wk.d < wk.thr) & ~near[:, None, :]).sum(axis=0)
    return count >= max(2, int(np.ceil(CONFIRMED_SHARE * wk.k)))


def _flag_unseen(model, wk, unseen: np.ndarray):
    """``model`` with ``unseen`` (work resolution, (h, w) bool) flagged never seen, its
    plate inpainted from a ring round it (the plate's person colour there is no guess of
    what stands behind), confidence 0."""
    if not unseen.any():
        return model
    full = wk.up(unseen) > 0
    if model.self_lit is not None:
        full &= ~model.self_lit
    ring = cv2.dilate(full.view(np.uint8), _ring_box(wk))
    plate = cv2.inpaint(model.plate, ring, 5, cv2.INPAINT_TELEA)
    conf = np.where(full, 0.0, model.confidence).astype(np.float32)
    return replace(model, plate=plate, never_seen=model.never_seen | full, confidence=conf)


def _ring_box(wk) -> np.ndarray:
    r = int(np.ceil(wk.full[0] / wk.h)) + 1
    return np.ones((2 * r + 1, 2 * r + 1), np.uint8)


def _guess_beyond(plate: np.ndarray, wk, parts: np.ndarray, foot: np.ndarray) -> np.ndarray:
    """``plate`` with ``parts`` (work resolution, (h, w) bool) and a ring round them
    inpainted from beyond the footprint ``foot`` (work resolution) rather than from
    their own edge: next to a body part that never left its pixels, the plate often
    holds more of it (a torso's far side, unflagged), whose colour an inpaint from the
    edge would carry in."""
    ring = cv2.dilate((wk.up(parts) > 0).view(np.uint8), _ring_box(wk))
    wide = ring | wk.up(foot)
    x, y, w, h = cv2.boundingRect(wide)
    pad = 8
    y0, x0 = max(0, y - pad), max(0, x - pad)
    y1, x1 = min(wide.shape[0], y + h + pad), min(wide.shape[1], x + w + pad)
    guess = cv2.inpaint(np.ascontiguousarray(plate[y0:y1, x0:x1]),
                        np.ascontiguousarray(wide[y0:y1, x0:x1]), 5, cv2.INPAINT_TELEA)
    out = plate.copy()
    sub = ring[y0:y1, x0:x1] > 0
    out[y0:y1, x0:x1][sub] = guess[sub]
    return out


def _unlike_scene(wk, pixels: np.ndarray, scene: np.ndarray) -> np.ndarray:
    """(h, w) bool: the ``pixels`` whose plate colour no ``scene`` pixel within the ring's
    width shows (L1 over the channels above :data:`FLAG_UNLIKE` thresholds): not the
    continuation of a scene object that reaches out of the footprint (a table's chrome
    foot the legs step round)."""
    from vidcap.video.appearance import nearest_scene_distance

    ys, xs = np.nonzero(pixels)
    out = np.zeros(pixels.shape, bool)
    if not len(ys):
        return out
    colour = wk.plate[ys, xs]
    scene = scene & ~wk.lit
    r = int(round(FLAG_RADIUS * wk.ring_r))
    best = nearest_scene_distance(colour, ys, xs, wk.plate, scene, r, max(2, r // 6))
    out[ys, xs] = best > FLAG_UNLIKE * wk.thr
    return out
