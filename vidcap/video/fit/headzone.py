"""Arms that only explain hair (beyond the seed; issue 27, a runner's arms folded up).

The model's head is a narrow segment; a real head of hair, a ponytail above all, makes
the silhouette's head blob up to twice as deep. In a side view the arms lie inside the
torso's outline, where no pose of theirs changes S, so the arm searches are free to fold
an arm up beside the head, where it covers the hair the head leaves over and S rises:
on sports2d_run (a runner with a ponytail, elbows bent at chest height) both arms were
drawn folded up beside the head in most frames, the elbows 25-29 % of the height above
MediaPipe's. The same hair drawn on the side-view run renders of
``benchmarks/pose2d_run.py`` folds the far arm up there (elbow 19-21 %, wrist 24-28 % of
the height too high).

:func:`clear_head_zone` (``FitOptions.head_zone``, **off by default**): where an arm's
elbow and wrist both lie in the head zone (within :data:`ZONE_HEADS` head lengths, neck
to head top, of the head's centre, above the neck and at most :data:`ABOVE_TOP` head
lengths above the head top), and the pieces of the silhouette the torso and head leave
over that touch the head and lie mostly in the zone (:func:`hair_pixels`, maybe hair)
are at least :data:`MIN_HAIR` of it, both arms are searched again
(:func:`~vidcap.video.fit.armpairs.search_arm_pairs`, the hanging prior for arms the
torso hides) against the silhouette without those pieces: a model arm drawn there then
overreaches instead of covering.

Measured (benchmarks/HISTORY.md, session 32, wt-runarms): on the hair renders of
``pose2d_run.py`` the folded arms come down (14 running clips +solve 81.56 -> 84.4 %,
the runs without hair unchanged), but an arm raised beside the head leaves the same
kind of piece: the hands-above-the-head tuning renders (``pose2d_attribution.py
--extra``) lose up to 13 points, and held out (first version, the zone a disc)
``--hidden solve`` fell 89.22 -> 88.82 (arms and 131_01 2-4 s side). A silhouette at
80 px does not tell a ponytail from a forearm beside the head; kept as an option.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from vidcap.video.fit.armpairs import search_arm_pairs
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.limits import J, S
from vidcap.video.fit.state import FitState

#: The head zone's radius in head lengths (neck to head top) round the head's centre
#: (halfway between neck and head top). Chosen on the hair renders of
#: ``benchmarks/pose2d_run.py`` (tuning).
ZONE_HEADS = 1.25
#: How far above the head top the zone reaches, in head lengths: hair hangs beside and
#: behind the head, an arm raised past the head reaches above it.
ABOVE_TOP = 0.25
#: The share of a leftover piece of the silhouette in the head zone from which it may
#: be hair (:func:`hair_pixels`). Chosen on the tuning renders of ``pose2d_run.py``
#: (hair) and ``pose2d_attribution.py --extra`` (hands above the head).
HAIR_SHARE = 0.8
#: The least share of the silhouette's pixels that may be hair (:func:`hair_pixels`) for
#: the arms to be searched again (a few pixels round the head are no head of hair).
MIN_HAIR = 0.03
_ARM_ENDS = (J["l_elbow"], J["l_wrist"], J["r_elbow"], J["r_wrist"])


def head_zone(joints: np.ndarray, points: np.ndarray, heads: float = ZONE_HEADS) -> np.ndarray:
    """(...) bool: ``points`` (..., 2) inside the head zone of the pose ``joints`` (15, 2):
    within ``heads`` head lengths (neck to head top) of the head's centre, above the
    neck and at most :data:`ABOVE_TOP` head lengths above the head top along the
    neck-to-head-top direction."""
    neck, top = joints[J["neck"]], joints[J["head_top"]]
    axis = top - neck
    length = float(np.hypot(*axis))
    if not length > 0:
        return np.zeros(np.shape(points)[:-1], dtype=bool)
    p = np.asarray(points, dtype=float)
    near = np.hypot(*np.moveaxis(p - 0.5 * (neck + top), -1, 0)) < heads * length
    t = ((p - neck) @ axis) / (length * length)
    return near & (t > 0.0) & (t < 1.0 + ABOVE_TOP)


def hair_pixels(eng: _MaskEngine, st: FitState, heads: float = ZONE_HEADS,
                share: float = HAIR_SHARE) -> np.ndarray:
    """(h, w) bool: the silhouette's pixels the torso and head of ``st`` leave over that
    may be hair: each connected piece of them (8-connected) that touches the head and
    has at least ``share`` of its pixels in the head zone (:func:`head_zone`). An arm
    raised past the head leaves a piece that reaches out of the zone (down in front of
    the chest, up above the head) or stands apart from the head; hair grows from the
    head and stays round it."""
    import cv2

    j = eng.joints(st)
    head = eng.model(st, segments=[S["head"]])
    spare = eng.sil & ~head & ~eng.model(st, segments=[S["torso"]])
    n, labels = cv2.connectedComponents(spare.astype(np.uint8), connectivity=8)
    if n <= 1:
        return np.zeros_like(spare)
    ys, xs = np.mgrid[0:eng.h, 0:eng.w]
    zone = head_zone(j, np.stack([xs, ys], -1).astype(float), heads)
    total = np.bincount(labels.ravel(), minlength=n)
    inside = np.bincount(labels[zone], minlength=n)
    ring = cv2.dilate(head.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool) & ~head
    touching = np.zeros(n, dtype=bool)
    touching[labels[ring]] = True
    hair = (inside >= share * np.maximum(total, 1)) & (inside > 0) & touching
    hair[0] = False
    return hair[labels]


def zone_engine(eng: _MaskEngine, hair: np.ndarray) -> _MaskEngine:
    """An engine of ``eng``'s silhouette without the pixels ``hair``
    (:func:`hair_pixels`): a model arm drawn there then overreaches."""
    mask = eng.sil & ~hair
    norm = dataclasses.replace(eng.norm, mask=mask)
    return _MaskEngine(norm, caps=eng.caps, body=eng.body, foot=eng.foot_share)


def clear_head_zone(eng: _MaskEngine, st: FitState, heads: float = ZONE_HEADS) -> FitState:
    """``st`` with both arms searched again (:func:`search_arm_pairs`) against the
    silhouette without the pixels that may be hair (:func:`zone_engine`,
    :func:`hair_pixels`), where the elbow and the wrist of an arm of ``st`` lie in the
    head zone and some may; ``st`` itself otherwise. Writes the arms' angles, scores
    and margins."""
    j = eng.joints(st)
    if not head_zone(j, j[list(_ARM_ENDS)], heads).reshape(2, 2).all(axis=1).any():
        return st
    hair = hair_pixels(eng, st, heads)
    if hair.sum() < MIN_HAIR * eng.sil_rows[-1]:
        return st
    out = search_arm_pairs(zone_engine(eng, hair), st)
    return st if out is st else st.replace(angles=out.angles, scores=out.scores,
                                           margins=out.margins)


__all__ = ["ABOVE_TOP", "HAIR_SHARE", "MIN_HAIR", "ZONE_HEADS", "clear_head_zone",
           "hair_pixels", "head_zone", "zone_engine"]
