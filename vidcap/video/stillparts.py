"""Parts of the person that never move, found by appearance (issue 26, Build 1-2).

A person who stays in place (jumping jacks seen from the side, waving while
standing, someone reading at a desk) covers some pixels in every frame: the
temporal evidence the plate is built from shows the person there, so the plate
absorbs the torso and legs and background subtraction cannot see them. What still
tells them from the wall is that they are *attached to what moves* and look like
the person, not like the scene around them.

On a few sampled frames, at the plate's low working resolution:

1. the pixels that differ from the plate (the moving limbs) are sure person;
2. a box around them, grown while the cut reaches its edge, is the uncertain
   area; everything outside it is sure background;
3. :func:`cv2.grabCut` (colour models of person and background, a graph cut over
   the image) decides the uncertain area by appearance.

The parts the cut gives as person in most of the sampled frames, and that never
differed from the plate, are the still parts: static pixels the person covers in
every frame. Their plate value is the person's own colour; the background behind
them is never seen, so it is a guess inpainted from around them. Per frame, a
still-part pixel is person unless it now looks like that guess and not like the
person (the person moved away).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["still_parts", "self_lit"]

#: Frames cut by appearance (evenly among the samples showing movement).
N_CUTS = 6
#: A pixel is a still part when the cut gives it as person in this share of them.
MIN_AGREEMENT = 0.6
#: A cut may be at most this many times the moving area and this share of the
#: frame (more has leaked into the scene: a background colour the person's model
#: took); the still parts at most that share of the frame too.
MAX_GROWTH = 15.0
MAX_SHARE = 0.15
#: A self-lit pixel's spread with the frame gains divided out is within this factor of
#: the spread the gains predict for its level (:func:`self_lit`).
PREDICTED_RATIO = 2.5
#: Self-lit areas smaller than this share of the frame are chance (:func:`self_lit`).
MIN_LIT_SHARE = 0.003


def _box(fg: np.ndarray, pad: float) -> tuple[int, int, int, int]:
    x, y, w, h = cv2.boundingRect(fg)
    px, py = int(pad * max(w, h)) + 2, int(pad * max(w, h)) + 2
    H, W = fg.shape
    return max(0, x - px), max(0, y - py), min(W, x + w + px), min(H, y + h + py)


def _largest(fg: np.ndarray) -> np.ndarray:
    """The largest 8-connected blob of a 0/1 uint8 image (the moving person)."""
    n, lab, st, _ = cv2.connectedComponentsWithStats(fg, connectivity=8)
    if n <= 2:
        return fg
    return (lab == 1 + int(np.argmax(st[1:, cv2.CC_STAT_AREA]))).astype(np.uint8)


def cut_person(image: np.ndarray, sure: np.ndarray, *, pad: float = 1.0,
               grow: int = 2, iterations: int = 3) -> np.ndarray:
    """The person in one frame by appearance, from the pixels sure to be person.

    Parameters
    ----------
    image : numpy.ndarray, shape (h, w, 3), uint8
        The frame (BGR).
    sure : numpy.ndarray, shape (h, w), bool
        Pixels sure to be person (they differ from the plate).
    pad : float
        The uncertain box extends this share of the sure pixels' larger side
        beyond them.
    grow : int
        Times the box is widened where the cut reaches its edge (a torso reaching
        down to legs the box did not hold).
    iterations : int
        GrabCut iterations.

    Returns
    -------
    numpy.ndarray, shape (h, w), bool
        The person (sure pixels included); all False without sure pixels.
    """
    sure = sure.astype(np.uint8)
    if not sure.any():
        return np.zeros(sure.shape, bool)
    H, W = sure.shape
    x0, y0, x1, y1 = _box(sure, pad)
    person = sure.astype(bool)
    for _ in range(grow + 1):
        # The cut runs on the box and a margin of background around it as wide as
        # the box (the background model's samples): not on the whole frame.
        mx, my = x1 - x0, y1 - y0
        ox0, oy0 = max(0, x0 - mx), max(0, y0 - my)
        ox1, oy1 = min(W, x1 + mx), min(H, y1 + my)
        mask = np.full((oy1 - oy0, ox1 - ox0), cv2.GC_BGD, np.uint8)
        mask[y0 - oy0:y1 - oy0, x0 - ox0:x1 - ox0] = cv2.GC_PR_FGD
        mask[sure[oy0:oy1, ox0:ox1] > 0] = cv2.GC_FGD
        bgd, fgd = np.zeros((1, 65)), np.zeros((1, 65))
        cv2.setRNGSeed(0)  # GrabCut's k-means start: the same cut whatever ran before
        try:
            cv2.grabCut(np.ascontiguousarray(image[oy0:oy1, ox0:ox1]), mask, None, bgd, fgd,
                        iterations, cv2.GC_INIT_WITH_MASK)
        except cv2.error:  # one colour everywhere: no model to learn
            return sure.astype(bool)
        person = np.zeros((H, W), bool)
        person[oy0:oy1, ox0:ox1] = (mask == cv2.GC_FGD) | (mask == cv2.GC_PR_FGD)
        # Widen the box where the person reaches its edge (not the frame's).
        step = max(2, int(0.25 * max(x1 - x0, y1 - y0)))
        nx0 = x0 - step if x0 > 0 and person[y0:y1, x0].any() else x0
        nx1 = x1 + step if x1 < W and person[y0:y1, x1 - 1].any() else x1
        ny0 = y0 - step if y0 > 0 and person[y0, x0:x1].any() else y0
        ny1 = y1 + step if y1 < H and person[y1 - 1, x0:x1].any() else y1
        nx0, ny0, nx1, ny1 = max(0, nx0), max(0, ny0), min(W, nx1), min(H, ny1)
        if (nx0, ny0, nx1, ny1) == (x0, y0, x1, y1):
            break
        x0, y0, x1, y1 = nx0, ny0, nx1, ny1
    return person


def still_parts(small: np.ndarray, plate: np.ndarray, threshold: float, *,
                min_area: int = 12, exclude: np.ndarray | None = None) -> np.ndarray:
    """Static pixels the person covers in every sampled frame, at low resolution.

    Parameters
    ----------
    small : numpy.ndarray, shape (K, h, w, 3), uint8
        Sampled frames, brightness-normalised, at the working resolution.
    plate : numpy.ndarray, shape (h, w, 3), uint8
        The plate at the same resolution.
    threshold : float
        L1 foreground threshold (grey levels over B, G, R).
    min_area : int
        Fewest sure pixels (low resolution) for a frame to be cut.
    exclude : numpy.ndarray, shape (h, w), bool, optional
        Pixels that are never person (self-lit ones, a region the user marked).

    Returns
    -------
    numpy.ndarray, shape (h, w), bool
        Still parts: person by appearance in at least :data:`MIN_AGREEMENT` of the
        cut frames, and never different from the plate in any sample.
    """
    k, h, w = small.shape[:3]
    l1 = np.abs(small.astype(np.int16) - plate.astype(np.int16)).sum(axis=-1)
    fg = (l1 > threshold).astype(np.uint8)
    if exclude is not None:
        fg[:, exclude] = 0
    fg = np.stack([_largest(cv2.morphologyEx(cv2.medianBlur(f, 3), cv2.MORPH_OPEN,
                                             np.ones((2, 2), np.uint8))) for f in fg])
    area = fg.reshape(k, -1).sum(axis=1)
    moving = np.flatnonzero(area >= min_area)
    if not len(moving):
        return np.zeros((h, w), bool)
    pick = moving[np.unique(np.linspace(0, len(moving) - 1, min(N_CUTS, len(moving)))
                            .round().astype(int))]
    votes = np.zeros((h, w), np.float32)
    n_cut = 0
    for t in pick:
        cut = cut_person(small[t], fg[t] > 0)
        if cut.sum() <= min(MAX_GROWTH * area[t], MAX_SHARE * h * w):
            votes += cut
            n_cut += 1
    if n_cut < max(2, len(pick) // 2):
        return np.zeros((h, w), bool)
    ever = fg.any(axis=0)
    if exclude is not None:
        votes[exclude] = 0
    # (a pixel that differs from the plate in most samples is found without help)
    out = (votes >= MIN_AGREEMENT * n_cut) & (fg.mean(axis=0) < 0.5)
    # Only what is attached to the moving person (a blob the cut found elsewhere is not).
    # (within a pixel or two: the clean-up of the moving pixels eats their outline)
    near = cv2.dilate(ever.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    n, lab = cv2.connectedComponents((out | near).astype(np.uint8), connectivity=8)
    keep = np.zeros(n, bool)
    keep[np.unique(lab[near])] = True
    keep[0] = False
    out &= keep[lab]
    if out.sum() > MAX_SHARE * h * w:
        return np.zeros((h, w), bool)  # more than a body's worth: not trusted
    return out


def self_lit(raw: np.ndarray, gains: np.ndarray, noise: float) -> np.ndarray:
    """Pixels that keep their level while the exposure drifts (lamps, screens, windows).

    A lamp's core saturates, a screen lights itself: when the camera's exposure or
    white balance drifts, the rest of the scene scales with it and they do not, so
    against a plate scaled by the frame's gain they differ in every frame without
    ever moving. Such a pixel varies *less* over the samples as recorded than after
    the frame gains are divided out, and by as much as the gains say it should.

    Both spreads are medians over the samples, so that a person who passes in front
    of the lamp in a few of them does not hide it (a mean took the passing person's
    colour for the lamp's variation: the lit wall a dancer crossed, 06_07, was found
    in part and became a false blob joined to her). A pixel the person covers in
    most samples can show the pattern by chance: its spread after the gains are
    divided out need not match the one the gains predict for its level (a lamp's
    does, within :data:`PREDICTED_RATIO`), and such chance pixels come in small
    specks (kept: areas of at least :data:`MIN_LIT_SHARE` of the frame).

    Parameters
    ----------
    raw : numpy.ndarray, shape (K, h, w, 3), float32
        Sampled frames as recorded (not normalised).
    gains : numpy.ndarray, shape (K, 3)
        Per-frame, per-channel gains relative to the plate.
    noise : float
        Per-channel noise, grey levels.

    Returns
    -------
    numpy.ndarray, shape (h, w), bool
    """
    if len(raw) < 3 or np.abs(gains - 1).max() < 0.03:
        return np.zeros(raw.shape[1:3], bool)
    # as recorded and with the gains divided out, side by side: one median pass for both
    both = np.concatenate([raw, raw / gains[:, None, None, :]], axis=-1)
    level = np.median(both, axis=0)
    # the median absolute deviation over the samples, largest channel
    spread = np.median(np.abs(both - level), axis=0)
    s_raw, s_norm = spread[..., :3].max(axis=-1), spread[..., 3:].max(axis=-1)
    lit = (s_raw < 0.5 * s_norm) & (s_norm > 2.0 * max(noise, 1.0))
    # what dividing out the gains does to a pixel that keeps its level
    inverse = 1.0 / gains
    drift = np.median(np.abs(inverse - np.median(inverse, axis=0)), axis=0)  # (3,)
    predicted = (level[..., :3] * drift).max(axis=-1)
    lit &= (s_norm <= PREDICTED_RATIO * predicted) & (s_norm >= predicted / PREDICTED_RATIO)
    lit = cv2.morphologyEx(lit.astype(np.uint8), cv2.MORPH_OPEN, np.ones((2, 2), np.uint8))
    _, lab, stats, _ = cv2.connectedComponentsWithStats(lit, connectivity=8)
    big = stats[:, cv2.CC_STAT_AREA] >= MIN_LIT_SHARE * lit.size
    big[0] = False
    lit = big[lab].astype(np.uint8)
    # Its glow (part lamp, part scene) follows the exposure only in part: widened.
    return cv2.dilate(lit, np.ones((5, 5), np.uint8)).astype(bool)
