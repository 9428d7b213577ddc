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

:func:`clear_head_zone`: where an elbow or a wrist lies in the head zone (within
:data:`ZONE_HEADS` head lengths, neck to head top, of the head's centre, and above the
neck along the head's direction), both arms are searched again
(:func:`~vidcap.video.fit.armpairs.search_arm_pairs`, the hanging prior for arms the
torso hides) against the silhouette with the head zone replaced by the model's own
head: there the image cannot tell an arm from hair, so a model arm drawn there beyond
the head overreaches instead of covering. An arm raised above the head still finds
the silhouette beyond the zone; one folded up beside the head to cover hair goes back
to where the rest of the silhouette puts it.
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
_ARM_ENDS = (J["l_elbow"], J["l_wrist"], J["r_elbow"], J["r_wrist"])


def head_zone(joints: np.ndarray, points: np.ndarray, heads: float = ZONE_HEADS) -> np.ndarray:
    """(...) bool: ``points`` (..., 2) inside the head zone of the pose ``joints`` (15, 2):
    within ``heads`` head lengths (neck to head top) of the head's centre and above the
    neck along the neck-to-head-top direction."""
    neck, top = joints[J["neck"]], joints[J["head_top"]]
    axis = top - neck
    length = float(np.hypot(*axis))
    if not length > 0:
        return np.zeros(np.shape(points)[:-1], dtype=bool)
    p = np.asarray(points, dtype=float)
    near = np.hypot(*np.moveaxis(p - 0.5 * (neck + top), -1, 0)) < heads * length
    return near & (((p - neck) @ axis) > 0.0)


def zone_engine(eng: _MaskEngine, st: FitState, heads: float = ZONE_HEADS) -> _MaskEngine:
    """An engine of ``eng``'s silhouette with the head zone of ``st`` (:func:`head_zone`)
    replaced by the model's head there: a model arm drawn in the zone beyond the head
    then overreaches, whatever the silhouette shows."""
    j = eng.joints(st)
    ys, xs = np.mgrid[0:eng.h, 0:eng.w]
    zone = head_zone(j, np.stack([xs, ys], -1).astype(float), heads)
    head = eng.model(st, segments=[S["head"]])
    mask = np.where(zone, head, eng.sil)
    norm = dataclasses.replace(eng.norm, mask=mask)
    return _MaskEngine(norm, caps=eng.caps, body=eng.body, foot=eng.foot_share)


def clear_head_zone(eng: _MaskEngine, st: FitState, heads: float = ZONE_HEADS) -> FitState:
    """``st`` with both arms searched again (:func:`search_arm_pairs`) against the
    silhouette whose head zone is the model's head (:func:`zone_engine`), where an
    elbow or a wrist of ``st`` lies in the zone; ``st`` itself otherwise. Writes the
    arms' angles, scores and margins."""
    j = eng.joints(st)
    if not head_zone(j, j[list(_ARM_ENDS)], heads).reshape(2, 2).all(axis=1).any():
        return st
    out = search_arm_pairs(zone_engine(eng, st, heads), st)
    return st if out is st else st.replace(angles=out.angles, scores=out.scores,
                                           margins=out.margins)


__all__ = ["ZONE_HEADS", "clear_head_zone", "head_zone", "zone_engine"]
