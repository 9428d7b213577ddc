"""A person the plate absorbed, found by a person detector and cut out by appearance
(issue 26, Build 1 and 2).

A person who stands nearly still for the whole clip is never uncovered: the plate's
vote keeps them, and the difference from the plate shows only what moves (a hand, the
page of a book). OpenCV's built-in HOG people detector (Dalal and Triggs 2005, no
model file to download) still sees them in the frames; where it sees nobody in any
sample (a person seen side-on: it was trained on people facing or leaving the camera),
the search runs once more with OpenCV's other built-in HOG detector, trained on
pedestrians of the Daimler benchmark (Munder and Gavrila 2006), who are mostly seen
side-on as they cross a street (:data:`SECOND_DETECTOR`). Only when the plate left part
of the frame never seen (a guess), the detector runs on up to :data:`N_DETECT` of the
plate's samples and the person is cut out of its best box (the largest detection
holding the best-scoring one, :func:`enclosing_box`: the detector also fires on the
legs alone) by appearance
(``cv2.grabCut`` initialised from the box: outside is scene, the box's central column
probably person). The first detection decides: when the first-pass silhouette covers
:data:`MAX_COVER` or more of the cut, the person is visible and nothing is done
(cost: one detection and one cut), unless the cut is a small part of the
silhouette's blob it lies in (:data:`MIN_PART`: the detector boxed a head and a
raised arm), when the next sample decides. Before any other sample is cut, the
detector's boxes must show a person who stays put (the first three overlap
:data:`BOX_STILL`; a later box round a part of the first, :func:`_whole_of`, counts
as the first) and find them again within :data:`GIVE_UP` samples; the cuts must stay
(:data:`STILL_IOU`), or, with :data:`IN_PLACE` (off), change only above the legs (a
person bending or waving on legs that never move, :func:`_moves_in_place`), or, with
:data:`STILL_CORE` (on), share a core the first-pass silhouette does not show (limbs
that swing on a torso that stays: a walk or jumping jacks on the spot,
:func:`_still_core`), of which only the pixels of the person's colours are taken
(:func:`_person_coloured`: a cut also sweeps in scene behind the legs);
:func:`find_absorbed` says which test decided. Otherwise, with the cuts of every detected sample:

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

from vidcap.video.maskbox import padded_box

__all__ = ["absorbed_person", "detect_people", "enclosing_box", "find_absorbed"]

#: Detections scoring below this (the SVM margin) are dropped.
MIN_SCORE = 0.5
#: Frames with fewer rows than this are enlarged to the searched height (``rows``): the
#: detector's window is 128 rows (a person about 100 px tall), and a person in a
#: 180x144 clip (Weizmann's) is 70-90 px tall: never found at the frame's own size.
ENLARGE_BELOW = 240
#: A cut filling less of the detector's box than this is no person. People fill 0.19-0.28
#: of their boxes (the 180x144 renders' front, three-quarter and held poses); the box the
#: enlarged search put round the PETS render's lamp and a lit strip of wall cut 0-8 pixels
#: of its 6,200 (0.001), which the still-parts path then took for the person (0.24 -> 0).
MIN_FILL = 0.05
#: The first-pass silhouette covering less than this share of the person cut in the
#: detector's box means the person is absorbed. On the tuning clips: 0.32-0.34 where
#: the man stands still all along (cdnet_office_stand), 0.81-0.99 where he walked in
#: and the plate is right (cdnet_office_enter).
MAX_COVER = 0.6
#: Samples the detector runs on (evenly spread over the plate's samples).
N_DETECT = 8
#: The detector runs only when the plate left at least this share of the frame never
#: seen (a guess): a person absorbed for the whole clip leaves some. 0.005 missed the
#: dancer of 05_04 front (tuning since), absorbed whole, who left 0.0048.
MIN_NEVER_SEEN = 0.004
#: The detector gives up when it found nobody in this many samples (a person it does
#: not see: bent over, a render's mannequin; each look costs ~0.14 s CPU at 640x480),
#: or nobody again in this many samples after its first find (a still person is
#: found again: 8 of 8 samples on the two tuning clips where one is absorbed,
#: cdnet_office_stand and pose2sim_balance cam1).
GIVE_UP = 4
#: Long side, pixels, of the crop the person is cut in (larger crops are cut shrunk:
#: cv2.grabCut's time grows with the pixels; 1088x1920 lab views took ~2 s a cut).
CUT_SIZE = 320
#: Median IoU of the cuts of consecutive detected samples a still person reaches
#: (cdnet_office_stand, tuning: 0.94, 0.99, 0.98, 0.89, 0.17 where he steps aside,
#: 0.86, 0.65; median 0.89).
STILL_IOU = 0.8
#: With :data:`IN_PLACE`, the first three cuts overlapping less than this (IoU, each
#: with the next; else :data:`STILL_IOU`) show a person who moves about: nothing is cut
#: further. Between it and :data:`STILL_IOU`
#: the cuts of a person who bends or waves on legs that never move (02_07 4-7 s side,
#: a dancer's legs in the plate: 0.38, 0.42, then 0.63-0.82) go on to
#: :func:`_moves_in_place`.
MOVE_IOU = 0.35
#: Cuts of a person moving in place needed before their still parts are added (a
#: held pose swaying over the PETS plate, which the plate sees round, gave 2 with
#: the first-pass silhouette covering 0.60 and 0.64 of them).
MIN_IN_PLACE = 3
#: Take the still legs of a person who bends or waves (:func:`_moves_in_place`).
#: Off: built on 02_07 4-7 s side (0.522 -> 0.983 median IoU), it took the table's
#: stand behind the legs for the person on the first validation render it reached
#: (06_11 6-9 s front, 0.953 -> 0.877) and changed no other row of 120
#: (``silhouettes_real.py --in-place``).
IN_PLACE = False
#: Share of the cut samples a pixel must be the person in.
MIN_AGREE = 0.5
#: Search again with the Daimler detector where the default one found nobody in any
#: sample (:data:`NOBODY`). Chosen on the renders of ``silhouettes_real.py --small``
#: and without it, one sitting (session 43): at 180x144 the tuning rows' mean median
#: IoU 0.770 -> 0.792 (arms side 0.590 -> 0.866, held 131_01 side 0.000 -> 0.728:
#: both seen side-on, where the default detector found nobody); no validation row moved
#: (the second search ran on eight of them and stopped at one of the tests below).
SECOND_DETECTOR = True
#: The Daimler detector's searched height, rows: its window is 96 rows (a person
#: about 72 px tall); every frame is scaled to it (a 180x144 clip's people, 70-90 px
#: tall, fit the window without the default detector's enlargement to 480 rows).
DAIMLER_ROWS = 240
#: The Daimler detector's smallest SVM score kept (its finds round the renders'
#: side-on people scored 1.6-2.6).
DAIMLER_MIN_SCORE = 1.0

_HOG = {}


def _hog(detector: str = "default"):
    """OpenCV's built-in HOG people detector: ``'default'`` (INRIA, 64x128 window) or
    ``'daimler'`` (48x96), made once."""
    if detector not in _HOG:
        if detector == "daimler":
            hog = cv2.HOGDescriptor((48, 96), (16, 16), (8, 8), (8, 8), 9)
            hog.setSVMDetector(cv2.HOGDescriptor_getDaimlerPeopleDetector())
        elif detector == "default":
            hog = cv2.HOGDescriptor()
            hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
        else:
            raise ValueError(f"unknown detector {detector!r}; expected 'default' or "
                             "'daimler'")
        _HOG[detector] = hog
    return _HOG[detector]


def detect_people(frame: np.ndarray, *, min_score: float | None = None, rows: int = 480,
                  detector: str = "default") -> tuple[np.ndarray, np.ndarray]:
    """People in one frame by one of OpenCV's HOG detectors.

    The frame is padded below by a quarter of its height (a person cut off by the
    frame's lower edge still fits the detector's window). With the ``'default'``
    detector it is shrunk to at most ``rows`` rows (the window is 128 rows: larger
    frames only cost time), and a frame under :data:`ENLARGE_BELOW` rows is enlarged
    to ``rows`` rows (its people are too small for the window); the ``'daimler'``
    detector searches every frame scaled to :data:`DAIMLER_ROWS` rows.

    Parameters
    ----------
    frame : numpy.ndarray, shape (H, W, 3), uint8
    min_score : float, optional
        Smallest SVM score kept (default :data:`MIN_SCORE`, or
        :data:`DAIMLER_MIN_SCORE` for the Daimler detector).
    rows : int
        The frame's height, at most, as searched by the default detector.
    detector : {'default', 'daimler'}
        OpenCV's people detector trained on INRIA's people (mostly facing or leaving
        the camera), or on Daimler's pedestrians (mostly side-on).

    Returns
    -------
    boxes : numpy.ndarray, shape (N, 4), int
        ``x0, y0, x1, y1`` in the frame's pixels (clipped to it), x1, y1 exclusive.
    scores : numpy.ndarray, shape (N,), float
    """
    hog = _hog(detector)
    daimler = detector == "daimler"
    if min_score is None:
        min_score = DAIMLER_MIN_SCORE if daimler else MIN_SCORE
    h, w = frame.shape[:2]
    if daimler:
        s = DAIMLER_ROWS / h
    else:
        s = rows / h if h < ENLARGE_BELOW else min(1.0, rows / h)
    img = frame if s == 1.0 else cv2.resize(frame, (max(1, int(w * s)), max(1, int(h * s))),
                                            interpolation=cv2.INTER_AREA if s < 1.0
                                            else cv2.INTER_LINEAR)
    img = cv2.copyMakeBorder(img, 0, img.shape[0] // 4, 0, 0, cv2.BORDER_REPLICATE)
    win_w, win_h = hog.winSize
    if img.shape[0] < win_h or img.shape[1] < win_w:
        return np.zeros((0, 4), np.int64), np.zeros(0)
    # (the smaller window's stride and padding halved with it)
    step, pad = ((4, 4), (8, 8)) if daimler else ((8, 8), (16, 16))
    rects, weights = hog.detectMultiScale(img, winStride=step, padding=pad, scale=1.05)
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
        The person (False outside the box); all False when the cut fills less than
        :data:`MIN_FILL` of the box.
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
    if np.count_nonzero(fg) < MIN_FILL * bw * bh:
        return out  # a few pixels: the detector boxed no person
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
    return find_absorbed(model, frames, gains, n_detect=n_detect, max_cover=max_cover)[0]


#: Why :func:`find_absorbed` left the plate alone, or ``ABSORBED`` when it did not.
(SAW_ALL, NOBODY, NOT_AGAIN, TOO_FEW, VISIBLE, BOXES_MOVE, CUTS_MOVE, NOTHING_STILL,
 ABSORBED) = (
    "the plate saw the whole scene", "nobody detected", "the first find not seen again",
    "fewer than 2 cuts", "the person is visible", "the detector's boxes move",
    "the cuts move", "nothing still to add", "absorbed")


def find_absorbed(model, frames: np.ndarray, gains: np.ndarray, *,
                  n_detect: int = N_DETECT, max_cover: float = MAX_COVER,
                  unseen_gate: bool = True, rows: tuple[int, ...] = (480,)):
    """:func:`absorbed_person` and why it decided so.

    The cheap tests come first: the detector's boxes of the first three samples
    with a detection must stay put (:data:`BOX_STILL`) before any sample but the
    first is cut by ``cv2.grabCut`` (the first cut tells an absorbed person from a
    visible one), and the detector must find someone again within :data:`GIVE_UP`
    samples of its first find.

    ``unseen_gate`` False runs the detector whatever the plate left never seen (a
    person who held one pose, :mod:`vidcap.video.heldpose`); ``rows``: the heights the
    detector searches each sample at (:func:`detect_people`), the next only when the
    one before found nobody. When the default detector found nobody (:data:`NOBODY`),
    the same search runs with the Daimler detector (:data:`SECOND_DETECTOR`).

    Returns
    -------
    model : vidcap.video.background.BackgroundModel
        As :func:`absorbed_person`.
    reason : str
        :data:`ABSORBED` when the model changed, else why not (:data:`SAW_ALL`,
        :data:`NOBODY`, :data:`NOT_AGAIN`, :data:`TOO_FEW`, :data:`VISIBLE`,
        :data:`BOXES_MOVE`, :data:`CUTS_MOVE`, :data:`NOTHING_STILL`).
    """
    k = frames.shape[0]
    if k < 2 or (unseen_gate and model.never_seen_fraction < MIN_NEVER_SEEN):
        return model, SAW_ALL  # the plate saw the whole scene: nobody absorbed (no cost)
    got = _search(model, frames, gains, n_detect, max_cover, rows, "default")
    if got[1] == NOBODY and SECOND_DETECTOR:
        # (a person the default detector does not see, often side-on: every test of
        # the search applies to the second detector's finds as to the first's)
        got = _search(model, frames, gains, n_detect, max_cover, rows, "daimler")
    return got


def _search(model, frames, gains, n_detect: int, max_cover: float, rows, detector: str):
    """:func:`find_absorbed`'s search of the samples with one ``detector``
    (:func:`detect_people`'s)."""
    from vidcap.video.platepass import _person_masks

    k = frames.shape[0]
    pick = np.unique(np.linspace(0, k - 1, min(n_detect, k)).round().astype(int))
    cuts, where, boxes, pending, first = [], [], [], [], 0
    for i, t in enumerate(pick):
        if i >= GIVE_UP and not cuts:
            return model, NOBODY  # the detector does not see this person (no more cost)
        if len(boxes) == 1 and i - first > GIVE_UP:
            # A person absorbed for the whole clip stands in every sample, where the
            # detector sees them again: its first find was not such a person.
            return model, NOT_AGAIN
        found, scores = _detect(frames[t], rows, detector)
        if not len(found):
            continue
        b = enclosing_box(found, scores)
        if not cuts:
            cut = cut_in_box(frames[t], b)
            if not cut.any():
                continue
            seen = _person_masks(model, frames[t:t + 1], gains[t:t + 1])[0] > 0
            if seen[cut].mean() >= max_cover:
                if _part_of_blob(cut, seen):
                    continue  # the detector boxed a part (a head and arm): not telling
                return model, VISIBLE  # the person shows in the silhouette (and cheap)
            cuts.append(cut)
            where.append(t)
            boxes.append(b)
            first = i
            continue
        b = _whole_of(b, boxes[0])
        boxes.append(b)
        pending.append((t, b))
        if len(boxes) < 3:
            continue  # the cuts wait for the boxes' verdict
        if len(boxes) == 3 and _boxes_move(boxes):
            return model, BOXES_MOVE  # (and no cut but the first)
        if _cut_pending(frames, pending, cuts, where):
            return model, CUTS_MOVE  # the first three cuts say the person moves
        pending = []
    if _cut_pending(frames, pending, cuts, where):
        return model, CUTS_MOVE
    if len(cuts) < 2:
        return model, TOO_FEW
    cuts = np.stack(cuts)
    if np.median(_consecutive_ious(cuts)) >= STILL_IOU:
        return _add_still(model, frames, gains, cuts, where)
    if IN_PLACE and _moves_in_place(model, frames, gains, cuts, where, max_cover):
        return _add_still(model, frames, gains, cuts, where)
    if STILL_CORE and len(cuts) >= MIN_IN_PLACE:
        seen = _person_masks(model, frames[where], gains[where]) > 0
        if _still_core(cuts, seen, max_cover):
            only = _person_coloured(model, frames[where], gains[where], cuts, seen)
            return _add_still(model, frames, gains, cuts, where, only=only)
    return model, CUTS_MOVE  # the plate sees round them, nothing to add


#: Take the still core of a person whose limbs move on a body that stays put (a walk
#: or jumping jacks on the spot): :func:`_still_core`.
STILL_CORE = True
#: The still core must be at least this share of the median cut.
CORE_SHARE = 0.4


def _still_core(cuts, seen, max_cover) -> bool:
    """Whether cuts (N, H, W) bool that change from sample to sample (limbs that
    swing) share a core the first-pass silhouettes ``seen`` (N, H, W) bool do not show
    (a torso and head that never leave their pixels): the pixels in :data:`MIN_AGREE`
    of the cuts at least :data:`CORE_SHARE` of the median cut, and ``seen`` covering
    under ``max_cover`` of them (:func:`_shown_under`)."""
    core = cuts.mean(axis=0) >= MIN_AGREE
    if core.sum() < CORE_SHARE * np.median(cuts.sum(axis=(1, 2))):
        return False
    return _shown_under(seen, core, max_cover)


def _shown_under(seen, core, max_cover) -> bool:
    """Whether the first-pass silhouettes ``seen`` (N, H, W) bool cover under
    ``max_cover`` of ``core`` (H, W) bool, by the median over the samples."""
    return bool(np.median(seen[:, core].mean(axis=1)) < max_cover)


def _moves_in_place(model, frames, gains, cuts, where, max_cover) -> bool:
    """Whether cuts that change from sample to sample (an upper body bending or
    waving) still show a person the plate holds in part (legs that never move): at
    least :data:`MIN_IN_PLACE` cuts, their lower halves overlapping as a still
    person's do (:data:`STILL_IOU`, each with the next, by the median; 02_07 4-7 s
    side 0.84, a person rocking on bending knees, 06_10 2-5 s 3/4, 0.70), the
    first-pass silhouette covering under
    ``max_cover`` of the pixels most of them share by the median (a person rocking
    on their feet shows there: the plate sees round them)."""
    from vidcap.video.platepass import _person_masks

    if len(cuts) < MIN_IN_PLACE:
        return False
    rows = np.nonzero(cuts.any(axis=(0, 2)))[0]
    legs = cuts[:, (rows[0] + rows[-1]) // 2:]  # the lower half of what was cut
    if np.median(_consecutive_ious(legs)) < STILL_IOU:
        return False  # the legs move too: a person rocking, stepping or turning
    core = cuts.mean(axis=0) >= MIN_AGREE  # what _add_still would take
    if not core.any():
        return False
    return _shown_under(_person_masks(model, frames[where], gains[where]) > 0, core,
                        max_cover)


def _person_coloured(model, frames, gains, cuts, seen) -> np.ndarray:
    """(H, W) bool: the plate's pixels inside the cuts (N, H, W) bool whose colour the
    person's visible parts (the first-pass silhouettes ``seen`` (N, H, W) bool inside
    the cuts, in ``frames`` (N, H, W, 3) uint8 with ``gains`` (N, 3)) explain better
    than the scene round the cuts does: a cut that swept in a table's stand behind
    swinging legs keeps the legs' and the torso's colours, not the stand's."""
    from vidcap.video.appearance import colour_model, log_ratio

    union = cuts.any(axis=0)
    seen = seen & cuts
    if seen.sum() < MIN_COLOUR_PIXELS:
        return union  # too little of the person shows to learn their colours
    shown = frames.astype(np.float32) / gains[:, None, None, :]
    r = max(2, int(round(0.05 * frames.shape[1])))
    ring = cv2.dilate(union.view(np.uint8), np.ones((2 * r + 1,) * 2, np.uint8)) > 0
    ring &= ~union
    # (the person's colours with a share spread evenly over all colours: a torso whose
    # shirt no visible part shares is kept where the scene round it has no such colour)
    person = colour_model(shown[seen], uniform=UNSEEN_SHARE)
    llr = log_ratio(model.plate, person, colour_model(model.plate[ring]))
    # (averaged over 3x3 pixels: the thin strokes of scene a pixel's colour lets
    # through, a stand's legs, go with the scene beside them, while a head whose face
    # alone the scene could explain stays with its hair; an opening instead dropped
    # ido_walk in place's head: 0.90 -> 0.82 median IoU at 180x144)
    llr = cv2.blur(llr.astype(np.float32), (3, 3))
    return union & (llr > 0)


#: Share of the person's colour model spread over every colour (parts never shown).
UNSEEN_SHARE = 0.5
#: Pixels of the person's visible parts needed to learn their colours.
MIN_COLOUR_PIXELS = 50


def _detect(frame, rows, detector: str = "default"):
    """:func:`detect_people` at each height of ``rows`` in turn, up to the first that
    finds someone (the Daimler ``detector`` at its own height, once)."""
    if detector != "default":
        return detect_people(frame, detector=detector)
    for r in rows:
        found, scores = detect_people(frame, rows=r)
        if len(found):
            break
    return found, scores


#: A first cut covering less than this share of the first-pass silhouette's blobs it
#: lies in is a part of the person (the detector's box round a head and a raised arm
#: of a dancer whose legs the plate holds) and does not decide that the person is
#: visible.
MIN_PART = 0.5


def _part_of_blob(cut: np.ndarray, seen: np.ndarray) -> bool:
    """Whether ``cut`` (H, W) bool is under :data:`MIN_PART` of the blobs of ``seen``
    (H, W) bool (8-connected) it touches."""
    _, labels = cv2.connectedComponents(seen.view(np.uint8), connectivity=8)
    touched = np.unique(labels[cut & seen])
    touched = touched[touched > 0]
    if not len(touched):
        return False
    blob = np.isin(labels, touched).sum()
    return bool(cut.sum() < MIN_PART * blob)


def _cut_pending(frames, pending, cuts, where) -> bool:
    """Cut the samples in ``pending`` ((t, box) pairs) into ``cuts`` / ``where`` (empty
    cuts skipped); True when the third cut says the person moves."""
    for t, b in pending:
        cut = cut_in_box(frames[t], b)
        if not cut.any():
            continue
        cuts.append(cut)
        where.append(t)
        # (without an in-place path, why cut on)
        least = MOVE_IOU if IN_PLACE or STILL_CORE else STILL_IOU
        if len(cuts) == 3 and max(_iou(cuts[0], cuts[1]), _iou(cuts[1], cuts[2])) < least:
            return True
    return False


def _add_still(model, frames, gains, cuts, where, only=None):
    """The model with the still person of ``cuts`` (N, H, W) bool, cut in the samples
    ``where`` (and within ``only``, (H, W) bool, when given), and the plate re-taken
    round them; ``(model, reason)``."""
    plate, seen = _uncovered_plate(model, frames[where], gains[where], cuts)
    still = (cuts.mean(axis=0) >= MIN_AGREE) & ~seen
    if only is not None:
        still &= only
    if model.self_lit is not None:
        still &= ~model.self_lit
    if not still.any():
        return model, NOTHING_STILL
    full = still.view(np.uint8)
    ring = cv2.dilate(full, np.ones((5, 5), np.uint8))
    if STEADY:
        plate = _steady_scene(model, frames, gains, ring > 0, plate)
    plate = cv2.inpaint(plate, ring, 5, cv2.INPAINT_TELEA)
    conf = np.where(still, 0.0, model.confidence).astype(np.float32)
    return replace(model, plate=plate, never_seen=(model.never_seen & ~seen) | still,
                   confidence=conf, still_person=still, person_plate=model.plate), ABSORBED


#: The detector's boxes of a person who stands still overlap this much (IoU) from one
#: sample to the next: the person moves, and nothing is cut, when the first three
#: boxes overlap less than this pairwise. cdnet_office_stand (tuning, he stands still):
#: 0.67-1.0 (0.67 where he steps aside), pose2sim_balance cam1's experimenter (tuning)
#: 0.91-1.0; the 1000x1000 speed clip (from onebyone_room, a man walks in): 0.41, 0.
BOX_STILL = 0.5
#: Share of the best-scoring box a larger detection must hold to be taken as the
#: whole person the best box is a part of.
NESTED = 0.8


def enclosing_box(boxes: np.ndarray, scores: np.ndarray) -> np.ndarray:
    """The whole person among a frame's detections: the largest box that holds at
    least :data:`NESTED` of the best-scoring one.

    The HOG detector also fires on parts of a still person (the legs alone), and
    which of the nested boxes scores best changes from sample to sample: the cuts of
    a person who never moved then looked like a person who moves (05_04 front).

    Parameters
    ----------
    boxes : numpy.ndarray, shape (N, 4), int
        ``x0, y0, x1, y1`` (:func:`detect_people`), N >= 1.
    scores : numpy.ndarray, shape (N,)

    Returns
    -------
    numpy.ndarray, shape (4,)
    """
    boxes = np.asarray(boxes)
    best = boxes[int(np.argmax(scores))]
    iw = np.clip(np.minimum(boxes[:, 2], best[2]) - np.maximum(boxes[:, 0], best[0]), 0, None)
    ih = np.clip(np.minimum(boxes[:, 3], best[3]) - np.maximum(boxes[:, 1], best[1]), 0, None)
    area = (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])
    holds = iw * ih >= NESTED * max(1, (best[2] - best[0]) * (best[3] - best[1]))
    return boxes[int(np.argmax(np.where(holds, area, -1)))]


def _whole_of(box, first):
    """``first`` when ``box`` lies inside it (:data:`NESTED` of its area) and is
    under :data:`MIN_PART` of its size: the detector found a part of the person it
    found whole in the first box (a head and a raised arm), else ``box``."""
    area = (box[2] - box[0]) * (box[3] - box[1])
    whole = (first[2] - first[0]) * (first[3] - first[1])
    inside = _box_inter(box, first) >= NESTED * max(area, 1)
    return first if inside and area < MIN_PART * whole else box


def _box_inter(a, b) -> int:
    """Area of the overlap of two ``x0, y0, x1, y1`` boxes, pixels."""
    iw = max(0, min(a[2], b[2]) - max(a[0], b[0]))
    ih = max(0, min(a[3], b[3]) - max(a[1], b[1]))
    return iw * ih


def _box_iou(a, b) -> float:
    """IoU of two ``x0, y0, x1, y1`` boxes."""
    inter = _box_inter(a, b)
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return float(inter / max(union, 1))


def _boxes_move(boxes) -> bool:
    """The first three boxes (``x0, y0, x1, y1``) of a person who moves: neither
    consecutive pair overlaps :data:`BOX_STILL`."""
    return max(_box_iou(boxes[0], boxes[1]), _box_iou(boxes[1], boxes[2])) < BOX_STILL


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    return float((a & b).sum() / max(1, (a | b).sum()))


def _consecutive_ious(masks: np.ndarray) -> np.ndarray:
    """IoU of each of ``masks`` (K, H, W) bool with the next, (K - 1,)."""
    inter = (masks[1:] & masks[:-1]).sum(axis=(1, 2))
    return inter / np.maximum((masks[1:] | masks[:-1]).sum(axis=(1, 2)), 1)


#: Share of the cut samples (and at least 2) a pixel the person covered must be seen
#: uncovered in to be re-taken from them (a cut that misses a leg in one sample must
#: not put the leg in the plate). cdnet_office_stand (tuning): he steps aside for the
#: last 40 % of the clip, and only 2 of the 7 cut samples show where he stood; 0.34
#: asked for 3 and left it all never seen (0.781 / 0.558 median / p10 IoU), 0.25 takes
#: it from those 2 (0.797 / 0.608); every validation row the same.
MIN_UNCOVERED = 0.25


def _uncovered_plate(model, frames, gains, cuts):
    """The plate re-taken, where the person was cut in some samples, from the samples
    that show the pixel outside the (dilated) person; returns the plate and where it
    was re-taken, (H, W) bool."""
    from vidcap.video.platemedian import robust_plate

    k, h, w = cuts.shape
    r = max(1, int(round(0.02 * h)))
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    plate = model.plate.copy()
    seen = np.zeros((h, w), bool)
    # All that follows happens in the cuts' bounding box and r pixels round it (the
    # dilation reaches no further, and nothing is re-taken outside it): the same
    # values as over the whole frame, a fraction of the work on a large frame.
    box = padded_box(cuts.any(axis=0).view(np.uint8), r)
    if box is None:
        return plate, seen
    covered = np.stack([cv2.dilate(c[box].view(np.uint8), kernel) for c in cuts]) > 0
    outside = ~covered
    need = max(2, int(np.ceil(MIN_UNCOVERED * k)))
    seen_box = covered.any(axis=0) & (outside.sum(axis=0) >= need)
    if seen_box.any():
        again = robust_plate(frames[:, box[0], box[1]], gains, outside.view(np.uint8))
        # Only where the uncovered samples show something else than the plate: the
        # same colour means they show the person too (a cut that missed a leg).
        tmap = np.maximum(model.threshold, 3.0 * model.noise_map)[box]
        seen_box &= np.abs(again.astype(np.float32) - plate[box]).sum(axis=-1) > tmap
        plate[box][seen_box] = again[seen_box]
        seen[box] = seen_box
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
    k = len(frames)
    tmap = np.maximum(model.threshold, 3.0 * model.noise_map)
    # Where the median differs from the plate by more than tmap (L1 over the
    # channels), one channel differs by more than tmap / 3, and half the samples or
    # more (at least k // 2) lie beyond the median in that channel: each of them
    # differs from the plate by more than tmap / 3 in that channel. So the median,
    # and the rest, are only needed where k // 2 samples do: at a few per cent of the
    # pixels, instead of a (K, H, W, 3) median that took 3 s of the 5 s this pass
    # cost on a 1080x1920 clip. The count runs on the samples scaled in uint8 (cv2,
    # rounded: within 0.5 of the float values), so its threshold is lowered by 0.51
    # and by 1 % for the float sums' rounding: it can only take more pixels.
    low = (0.99 * tmap / 3.0 - 0.51)[..., None]
    beyond = np.zeros(frames.shape[1:], np.int16)
    for t in range(k):  # sample by sample (K of them, never pixel by pixel)
        scale = tuple(float(v) for v in 1.0 / gains[t]) + (0.0,)
        beyond += cv2.absdiff(cv2.multiply(frames[t], scale), plate) > low
    cand = (beyond.max(axis=-1) >= k // 2) & ~person
    if model.self_lit is not None:
        cand &= ~model.self_lit
    if not cand.any():
        return plate
    # The same float32 values, division and median as over the whole frame, as
    # (N, 3, K): the median along the contiguous last axis is faster.
    picked = np.ascontiguousarray(frames[:, cand].transpose(1, 2, 0))
    scaled = np.clip(picked / gains.T, 0, 255)
    med = np.median(scaled, axis=-1)
    scaled = scaled.transpose(2, 0, 1)  # (K, N, 3)
    t_c = tmap[cand]
    agree_n = (np.abs(scaled - med).sum(axis=-1) <= t_c).sum(axis=0)
    agree = agree_n / k >= STEADY_SHARE
    far = np.abs(med - plate[cand].astype(np.float32)).sum(axis=-1) > t_c
    redo = agree & far
    plate = plate.copy()
    idx = np.flatnonzero(cand.ravel())[redo]
    plate.reshape(-1, 3)[idx] = np.clip(med[redo], 0, 255).astype(np.uint8)
    return plate
