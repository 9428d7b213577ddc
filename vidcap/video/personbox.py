"""A person the plate absorbed, found by a person detector and cut out by appearance
(issue 26, Build 1 and 2).

A person who stands nearly still for the whole clip is never uncovered: the plate's
vote keeps them, and the difference from the plate shows only what moves (a hand, the
page of a book). OpenCV's built-in HOG people detector (Dalal and Triggs 2005, no
model file to download) still sees them in the frames. Only when the plate left part
of the frame never seen (a guess), the detector runs on up to :data:`N_DETECT` of the
plate's samples and the person is cut out of its best box by appearance
(``cv2.grabCut`` initialised from the box: outside is scene, the box's central column
probably person). The first detection decides: when the first-pass silhouette covers
:data:`MAX_COVER` or more of the cut, the person is visible and nothing is done
(cost: one detection and one cut). Otherwise, with the cuts of every detected sample:

* where the person was cut in some samples and a third of them show the pixel
  uncovered with another colour than the plate, the plate is re-taken from those
  (the person stood elsewhere for a while);
* the pixels cut as the person in half of them or more, and never uncovered, are the
  person's still parts: the model's ``still_person`` (with ``person_plate``, the plate
  before, their own colour), flagged never seen and inpainted from around them, as
  :mod:`vidcap.video.stillparts` does; the silhouette stage counts them as the person
  in every frame where they still look as they did;
* pixels outside the person that every sample agrees on but the plate does not are
  re-taken as the samples' median (a plate guess beside the person).
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

__all__ = ["absorbed_person", "detect_people"]

#: Detections scoring below this (the SVM margin) are dropped.
MIN_SCORE = 0.5
#: The first-pass silhouette covering less than this share of the person cut in the
#: detector's box means the person is absorbed. On the tuning clips: 0.32-0.34 where
#: the man stands still all along (cdnet_office_stand), 0.81-0.99 where he walked in
#: and the plate is right (cdnet_office_enter).
MAX_COVER = 0.6
#: Samples the detector runs on (evenly spread over the plate's samples).
N_DETECT = 8
#: The detector runs only when the plate left at least this share of the frame never
#: seen (a guess): a person absorbed for the whole clip leaves some.
MIN_NEVER_SEEN = 0.005
#: The detector gives up when it found nobody in this many samples (a person it does
#: not see: bent over, a render's mannequin; each look costs ~0.14 s CPU at 640x480).
GIVE_UP = 4
#: Long side, pixels, of the crop the person is cut in (larger crops are cut shrunk:
#: cv2.grabCut's time grows with the pixels; 1088x1920 lab views took ~2 s a cut).
CUT_SIZE = 320
#: Median IoU of the cuts of consecutive detected samples a still person reaches
#: (cdnet_office_stand, tuning: 0.94, 0.99, 0.98, 0.89, 0.17 where he steps aside,
#: 0.86, 0.65; median 0.89).
STILL_IOU = 0.8
#: Share of the cut samples a pixel must be the person in.
MIN_AGREE = 0.5

_HOG = None


def _hog():
    global _HOG
    if _HOG is None:
        _HOG = cv2.HOGDescriptor()
        _HOG.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    return _HOG


def detect_people(frame: np.ndarray, *, min_score: float = MIN_SCORE
                  ) -> tuple[np.ndarray, np.ndarray]:
    """People in one frame by OpenCV's HOG detector.

    The frame is padded below by a quarter of its height (a person cut off by the
    frame's lower edge still fits the detector's window) and shrunk to at most 480
    rows (the window is 128 rows: larger frames only cost time).

    Parameters
    ----------
    frame : numpy.ndarray, shape (H, W, 3), uint8
    min_score : float
        Smallest SVM score kept.

    Returns
    -------
    boxes : numpy.ndarray, shape (N, 4), int
        ``x0, y0, x1, y1`` in the frame's pixels (clipped to it), x1, y1 exclusive.
    scores : numpy.ndarray, shape (N,), float
    """
    h, w = frame.shape[:2]
    s = min(1.0, 480.0 / h)
    img = frame if s == 1.0 else cv2.resize(frame, (max(1, int(w * s)), max(1, int(h * s))),
                                            interpolation=cv2.INTER_AREA)
    img = cv2.copyMakeBorder(img, 0, img.shape[0] // 4, 0, 0, cv2.BORDER_REPLICATE)
    if img.shape[0] < 128 or img.shape[1] < 64:
        return np.zeros((0, 4), np.int64), np.zeros(0)
    rects, weights = _hog().detectMultiScale(img, winStride=(8, 8), padding=(16, 16),
                                             scale=1.05)
    if len(rects) == 0:
        return np.zeros((0, 4), np.int64), np.zeros(0)
    rects = np.asarray(rects, np.float64) / s
    scores = np.ravel(weights).astype(np.float64)
    boxes = np.column_stack([rects[:, 0], rects[:, 1], rects[:, 0] + rects[:, 2],
                             rects[:, 1] + rects[:, 3]])
    boxes = np.round(boxes).astype(np.int64)
    boxes[:, [0, 2]] = np.clip(boxes[:, [0, 2]], 0, w)
    boxes[:, [1, 3]] = np.clip(boxes[:, [1, 3]], 0, h)
    keep = (scores >= min_score) & (boxes[:, 2] > boxes[:, 0]) & (boxes[:, 3] > boxes[:, 1])
    return boxes[keep], scores[keep]


def cut_in_box(frame: np.ndarray, box, sure: np.ndarray | None = None, *,
               iterations: int = 4) -> np.ndarray:
    """The person inside ``box`` by ``cv2.grabCut``.

    Parameters
    ----------
    frame : numpy.ndarray, shape (H, W, 3), uint8
    box : sequence of 4 int
        ``x0, y0, x1, y1`` (a detector's box, with a margin round the body).
    sure : numpy.ndarray, shape (H, W), bool, optional
        Pixels known to be the person (a first-pass silhouette).
    iterations : int

    Returns
    -------
    numpy.ndarray, shape (H, W), bool
        The person (False outside the box).
    """
    h, w = frame.shape[:2]
    x0, y0, x1, y1 = (int(v) for v in box)
    bw, bh = x1 - x0, y1 - y0
    # A crop with a margin of scene round the box (grabCut learns the scene there).
    mx, my = max(4, bw // 4), max(4, bh // 8)
    cx0, cy0, cx1, cy1 = max(0, x0 - mx), max(0, y0 - my), min(w, x1 + mx), min(h, y1 + my)
    crop = np.ascontiguousarray(frame[cy0:cy1, cx0:cx1])
    m = np.full(crop.shape[:2], cv2.GC_BGD, np.uint8)
    m[y0 - cy0:y1 - cy0, x0 - cx0:x1 - cx0] = cv2.GC_PR_BGD
    # The detector centres the body: its middle third of the width, below the head
    # room, is probably the person.
    m[y0 - cy0 + bh // 8:y1 - cy0, x0 - cx0 + bw // 3:x1 - cx0 - bw // 3] = cv2.GC_PR_FGD
    if sure is not None:
        s = sure[cy0:cy1, cx0:cx1]
        m[s & (m != cv2.GC_BGD)] = cv2.GC_FGD
    if not ((m == cv2.GC_BGD).any() and np.isin(m, (cv2.GC_FGD, cv2.GC_PR_FGD)).any()):
        return np.zeros((h, w), bool)
    ch, cw = crop.shape[:2]
    s = min(1.0, CUT_SIZE / max(ch, cw))
    if s < 1.0:  # a large person: cut at CUT_SIZE (the time grows with the pixels)
        size = (max(1, round(cw * s)), max(1, round(ch * s)))
        crop = cv2.resize(crop, size, interpolation=cv2.INTER_AREA)
        m = cv2.resize(m, size, interpolation=cv2.INTER_NEAREST)
    bgd, fgd = np.zeros((1, 65), np.float64), np.zeros((1, 65), np.float64)
    cv2.setRNGSeed(0)  # grabCut seeds its colour models by k-means: the same cut every run
    cv2.grabCut(crop, m, None, bgd, fgd, iterations, cv2.GC_INIT_WITH_MASK)
    fg = ((m == cv2.GC_FGD) | (m == cv2.GC_PR_FGD)).view(np.uint8)
    if s < 1.0:
        fg = cv2.resize(fg, (cw, ch), interpolation=cv2.INTER_NEAREST)
    out = np.zeros((h, w), bool)
    out[cy0:cy1, cx0:cx1] = fg > 0
    return out


def absorbed_person(model, frames: np.ndarray, gains: np.ndarray, *,
                    n_detect: int = N_DETECT, max_cover: float = MAX_COVER):
    """The still parts of a person the plate absorbed (see the module docstring).

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The plate's samples.
    gains : numpy.ndarray, shape (K, 3)
    n_detect : int
        Samples the detector runs on.
    max_cover : float
        A detection counts as absorbed when the first-pass silhouette covers less
        than this share of the person cut in its box.

    Returns
    -------
    vidcap.video.background.BackgroundModel
        With ``still_person`` / ``person_plate`` set and the plate inpainted there;
        the same model when no absorbed person is found.
    """
    from vidcap.video.platepass import _person_masks

    k, hh, ww = frames.shape[:3]
    if k < 2:
        return model
    pick = np.unique(np.linspace(0, k - 1, min(n_detect, k)).round().astype(int))
    if model.never_seen_fraction < MIN_NEVER_SEEN:
        return model  # the plate saw the whole scene: nobody absorbed (and no cost)
    cuts, where, absorbed = [], [], 0
    for i, t in enumerate(pick):
        if i >= GIVE_UP and not cuts:
            return model  # the detector does not see this person (and no more cost)
        boxes, scores = detect_people(frames[t])
        if not len(boxes):
            continue
        b = boxes[int(np.argmax(scores))]
        cut = cut_in_box(frames[t], b)
        if not cut.any():
            continue
        if absorbed == 0:
            cover = (_person_masks(model, frames[t:t + 1], gains[t:t + 1])[0] > 0)[cut].mean()
            if cover >= max_cover:
                # The person shows in the silhouette: nothing absorbed (and cheap).
                return model
            absorbed += 1
        cuts.append(cut)
        where.append(t)
        if len(cuts) == 3 and max(_iou(cuts[0], cuts[1]), _iou(cuts[1], cuts[2])) < STILL_IOU:
            return model  # the first three cuts say the person moves (and no more cost)
    if len(cuts) < 2:
        return model
    cuts = np.stack(cuts)
    inter = (cuts[1:] & cuts[:-1]).sum(axis=(1, 2))
    union = np.maximum((cuts[1:] | cuts[:-1]).sum(axis=(1, 2)), 1)
    if np.median(inter / union) < STILL_IOU:
        return model  # the person moves: the plate sees round them, nothing to add
    plate, seen = _uncovered_plate(model, frames[where], gains[where], cuts)
    still = (cuts.mean(axis=0) >= MIN_AGREE) & ~seen
    if model.self_lit is not None:
        still &= ~model.self_lit
    if not still.any():
        return model
    full = still.view(np.uint8)
    ring = cv2.dilate(full, np.ones((5, 5), np.uint8))
    if STEADY:
        plate = _steady_scene(model, frames, gains, ring > 0, plate)
    plate = cv2.inpaint(plate, ring, 5, cv2.INPAINT_TELEA)
    conf = np.where(still, 0.0, model.confidence).astype(np.float32)
    return replace(model, plate=plate, never_seen=(model.never_seen & ~seen) | still,
                   confidence=conf, still_person=still, person_plate=model.plate)


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    return float((a & b).sum() / max(1, (a | b).sum()))


#: Share of the cut samples (and at least 2) a pixel the person covered must be seen
#: uncovered in to be re-taken from them (a cut that misses a leg in one sample must
#: not put the leg in the plate).
MIN_UNCOVERED = 0.34


def _uncovered_plate(model, frames, gains, cuts):
    """The plate re-taken, where the person was cut in some samples, from the samples
    that show the pixel outside the (dilated) person; returns the plate and where it
    was re-taken, (H, W) bool."""
    from vidcap.video.platemedian import robust_plate

    k = cuts.shape[0]
    r = max(1, int(round(0.02 * cuts.shape[1])))
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    covered = np.stack([cv2.dilate(c.view(np.uint8), kernel) for c in cuts]) > 0
    outside = ~covered
    need = max(2, int(np.ceil(MIN_UNCOVERED * k)))
    seen = covered.any(axis=0) & (outside.sum(axis=0) >= need)
    plate = model.plate.copy()
    if seen.any():
        again = robust_plate(frames, gains, outside.view(np.uint8))
        # Only where the uncovered samples show something else than the plate: the
        # same colour means they show the person too (a cut that missed a leg).
        tmap = np.maximum(model.threshold, 3.0 * model.noise_map)
        seen &= np.abs(again.astype(np.float32) - plate).sum(axis=-1) > tmap
        plate[seen] = again[seen]
    return plate, seen


#: Re-take the plate where every sample agrees on a colour the plate lacks (see
#: :func:`_steady_scene`).
STEADY = True
#: Share of the samples that must agree with their median. cdnet_office_stand (tuning):
#: a plate guess at the desk beside the man is steady in 21 of 24 samples (his hand
#: passes); 0.9 left it, 0.75 re-takes it (0.809 -> 0.823 median IoU).
STEADY_SHARE = 0.75


def _steady_scene(model, frames, gains, person, plate):
    """The plate re-taken where the samples agree with their own median in nearly
    every sample but not with the plate, outside ``person``: once the still person is
    known, what stays put and differs from the plate is scene the vote got wrong (an
    inpainting guess next to the person), not the person."""
    # Sample by sample (K of them, never pixel by pixel): the same float64 division
    # and float32 values as one array expression, without its (K, H, W, 3) float64
    # temporaries (1.2 GB and most of this pass's time on a 1080x1920 clip).
    scaled = np.empty(frames.shape, np.float32)
    for k in range(len(frames)):
        scaled[k] = np.clip(frames[k] / gains[k], 0, 255)
    med = np.median(scaled, axis=0)
    tmap = np.maximum(model.threshold, 3.0 * model.noise_map)
    agree_n = np.zeros(frames.shape[1:3], np.int32)
    for k in range(len(frames)):
        agree_n += np.abs(scaled[k] - med).sum(axis=-1) <= tmap
    agree = agree_n / len(frames) >= STEADY_SHARE
    far = np.abs(med - plate.astype(np.float32)).sum(axis=-1) > tmap
    redo = agree & far & ~person
    if model.self_lit is not None:
        redo &= ~model.self_lit
    plate = plate.copy()
    plate[redo] = np.clip(med[redo], 0, 255).astype(np.uint8)
    return plate
