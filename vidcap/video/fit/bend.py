"""A tracked body bending at the hips (beyond the seed; issue 27 item 4).

A tracked frame (:func:`vidcap.video.fit.frame._fit_warm`) turns the torso about the
neck, with the pelvis placed from the silhouette's top as for an upright body and
moved only sideways. A body bending over to pick something up, squatting or kneeling
does the opposite: the hips stay where the legs hold them and the neck swings down and
forward, so the silhouette's top drops with the head. Turned about a neck put a torso
length too low, the track keeps an upright torso poking out above the silhouette
(CMU 02_06 at 45 degrees, a tuning render: S 0.66-0.72 and every joint off in frames
28-40) and a fresh fit, started upright, does worse. :func:`track_bend` lets the
track follow the bend: the model moved up and down, and the torso (head and arms
with it) turned about the pelvis, wider than the seed's limits.
"""

from __future__ import annotations

import numpy as np

from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.limits import S
from vidcap.video.fit.moves import search_angle, search_root
from vidcap.video.fit.state import FitState
from vidcap.video.fit.torso import TORSO_WIDE, search_torso_about_neck

#: A tracked torso at least this far from upright (radians) is bending: the searches
#: of :func:`track_bend` run there (and where the silhouette is short, a crouch).
BEND_FROM = np.deg2rad(20.0)
#: How far a tracked frame's torso may turn about the pelvis (radians, either way).
BEND_STEP = np.deg2rad(24.0)


def bending(st: FitState) -> bool:
    """True where the tracked torso leans :data:`BEND_FROM` or more from upright."""
    return abs(st.angles[S["torso"]] - np.pi / 2) >= BEND_FROM


def track_bend(eng: _MaskEngine, st: FitState) -> FitState:
    """The model moved up and down (a tenth of the height), the torso with the head
    turned about the pelvis (:data:`BEND_STEP` either way, within
    :data:`~vidcap.video.fit.torso.TORSO_WIDE`), then about the neck again, narrower.
    Writes ``root`` and the torso's and head's ``angles``, ``scores``, ``margins``.
    """
    st, _ = search_root(eng, st, 1, 0.1 * eng.H)
    lo, hi = TORSO_WIDE
    st, _ = search_angle(eng, st, S["torso"], with_segments=(S["head"],), lo=lo, hi=hi,
                         start=st.angles[S["torso"]], interval=2 * BEND_STEP)
    st, _ = search_torso_about_neck(eng, st, start=st.angles[S["torso"]],
                                    interval=np.deg2rad(16), alone=True)
    return st


__all__ = ["BEND_FROM", "BEND_STEP", "bending", "track_bend"]
