"""The per-silhouette engine of the fit: :class:`_MaskEngine`.

Built once per :class:`~vidcap.video.fit.normalise.NormalisedMask`, it holds what every
move of that frame's fit reads and nothing a move changes: the silhouette and its
count tables, the model's segment lengths and radii at the body's height, and the
joints and similarity of the states scored so far (caches keyed on the state's
value, memoised on the states). A pose is a :class:`~vidcap.video.fit.state.FitState`.

Backends: each operation with a compiled and a numpy path is a thin dispatcher over
a ``*_compiled``/``*_numpy`` pair with one contract; :func:`fit_kernels` makes the
choice for the whole fit (tests switch it off to compare the paths).
"""

from __future__ import annotations

import numpy as np

from vidcap.body import SEGMENTS, BodyModel
from vidcap.video.fit.limits import S
from vidcap.video.fit.normalise import NormalisedMask
from vidcap.video.fit.raster import (
    _DIST,
    _KERNEL_TABLES,
    _PROX,
    _carray,
    _kernels,
    draw_pose,
    model_dimensions,
    model_shoulder,
    pose_joints_batch,
    span_counts,
)
from vidcap.video.fit.similarity import similarity_from_counts
from vidcap.video.fit.state import FitState

_TABLE_0 = np.zeros(1, np.int64)  # one candidate counted against table 0


def fit_kernels():
    """The compiled kernels every dual-path move of the fit uses, or None (numpy paths,
    the same results)."""
    return _kernels()


class _MaskEngine:
    """What the moves of one silhouette's fit read (all lengths in normalised px).

    Attributes
    ----------
    norm : NormalisedMask
    sil : numpy.ndarray, shape (h, w), bool
    H : float
        Body height the model is drawn at.
    L, R : numpy.ndarray, shape (10,)
        Segment lengths and radii.
    shoulder, hip : float
        Lateral offsets of the shoulders and hips at spread 1.
    top : float
        Where the head's end sits (the silhouette's top row, less a capsule's cap).
    taller : bool
        The silhouette is taller than the body (raised arms): its top need not be
        the head.
    caps : bool
        Segments drawn as capsules (else rectangles).
    """

    def __init__(self, norm: NormalisedMask, *, caps: bool, body: BodyModel | None = None,
                 foot: float = 0.0):
        self.norm = norm
        self.body, self.foot_share = body, foot  # as given (:mod:`.headzone` makes another)
        self.sil = norm.mask
        self.h, self.w = self.sil.shape
        # Body height = silhouette height (or the body's, when given apart from it),
        # less the round ends of the head and the lower legs when segments are drawn
        # as capsules (they reach beyond the joints).
        if body is None:
            ends = (SEGMENTS[S["head"]].width_ratio + SEGMENTS[S["l_lower_leg"]].width_ratio) / 2
        else:  # the subject's own proportions (vidcap.video.fit.proportions)
            ends = (body.radius("head") + body.radius("l_lower_leg")) / body.height
        height = norm.body_height
        # a real person's feet reach below the ankles, where the model ends: the model
        # is the standing height less the feet's share (``foot``, 0: the seed's body)
        self.foot = foot * height
        self.H = (height - self.foot) / (1.0 + ends) if caps else height - self.foot
        # a silhouette taller than the body (raised arms): its top need not be the head
        self.taller = norm.height > 1.02 * (self.H + self.foot)
        self.L, self.R, lateral, self.hip = model_dimensions(self.H, body)
        self.shoulder = model_shoulder(lateral, self.H, body)  # (lateral, drop)
        self.top = norm.top + (self.R[S["head"]] if caps else 0.0)
        self.caps = caps
        self.sil_rows, self.sil_cum = norm.count_tables  # shared by every fit of this mask
        self.sil_cum4 = self.sil_cum[None]  # as one table of the counting kernel
        self.sil_c = _carray(self.sil, np.bool_)  # what the kernels read
        self.L_c = _carray(self.L, np.float64)
        self.R_c = _carray(self.R, np.float64)

    # -- a state's joints and similarity ------------------------------------------
    # Memoised on the state itself (a FitState is never changed; FitState.replace
    # passes a memo on only while the fields it depends on are the same).
    def _posed(self, st: FitState):
        kernels = fit_kernels()
        j = (_pose_joints_numpy(self, st) if kernels is None
             else _pose_joints_compiled(kernels, self, st))
        memo = st.__dict__["_joints"] = (self, j, j[_PROX], j[_DIST])
        return memo

    def joints(self, st: FitState) -> np.ndarray:
        """Joints of ``st``, (15, 2), normalised pixels (shared: not to be written to)."""
        memo = st.__dict__.get("_joints")
        if memo is None or memo[0] is not self:
            memo = self._posed(st)
        return memo[1]

    def ends(self, st: FitState) -> tuple[np.ndarray, np.ndarray]:
        """Every segment's proximal and distal joint in ``st``, each (10, 2)."""
        memo = st.__dict__.get("_joints")
        if memo is None or memo[0] is not self:
            memo = self._posed(st)
        return memo[2], memo[3]

    def model(self, st: FitState, segments=None) -> np.ndarray:
        """The drawn segments of ``st`` (or ``segments``) as a mask (h, w), bool."""
        seg = np.flatnonzero(st.drawn) if segments is None else segments
        return draw_pose(self.joints(st), self.R, (self.h, self.w), segments=seg,
                         caps=self.caps)

    def similarity(self, st: FitState) -> float:
        """S (Eq. 3.3) of the drawn model of ``st`` against the whole silhouette."""
        memo = st.__dict__.get("_similarity")
        if memo is None or memo[0] is not self:
            d = drawn_counts(self, st)
            s = similarity_from_counts(int(self.sil_rows[-1]), int(d[0]), int(d[1]))
            memo = st.__dict__["_similarity"] = (self, s)
        return memo[1]

    def rows(self, rows) -> tuple[int, int]:
        """A search's rows ``(r0, r1)``: all of them (None), or ``rows`` within the image."""
        if rows is None:
            return 0, self.h
        # Both ends clamped: a small silhouette fitted at a body height known apart from
        # it (a person half out of the picture) puts a limb's rows below the image.
        r0 = min(max(0, int(rows[0])), self.h)
        return r0, min(max(r0, int(rows[1])), self.h)

    def pixels(self, r0: int, r1: int) -> int:
        """Silhouette pixels in rows ``[r0, r1)``."""
        return int(self.sil_rows[r1] - self.sil_rows[r0])


# -- dual-path operations --------------------------------------------------------------
def pose_joints(eng: _MaskEngine, st: FitState) -> np.ndarray:
    """The joints (15, 2) of ``st``, normalised pixels."""
    kernels = fit_kernels()
    if kernels is None:
        return _pose_joints_numpy(eng, st)
    return _pose_joints_compiled(kernels, eng, st)


def _pose_joints_numpy(eng, st):
    return pose_joints_batch(st.root[None], st.angles[None], st.fore[None],
                             np.array([st.spread], dtype=float), eng.L, eng.shoulder,
                             eng.hip)[0]


def _pose_joints_compiled(kernels, eng, st):
    out = np.empty((1, 15, 2))  # one pose: one compiled call, no batch set-up
    kernels.pose_one(_carray(st.root, np.float64), _carray(st.angles, np.float64),
                     _carray(st.fore, np.float64), float(st.spread), eng.L_c,
                     eng.shoulder, float(eng.hip), *_KERNEL_TABLES, out)
    return out[0]


def drawn_counts(eng: _MaskEngine, st: FitState) -> np.ndarray:
    """Pixels of the drawn model of ``st`` and those of them on the silhouette, (2,)."""
    seg = np.flatnonzero(st.drawn)
    kernels = fit_kernels()
    if kernels is None or not seg.size:
        return _drawn_counts_numpy(eng, st, seg)
    return _drawn_counts_compiled(kernels, eng, st, seg)


def _drawn_counts_numpy(eng, st, seg):
    j = eng.joints(st)
    return span_counts(j[None, _PROX[seg]], j[None, _DIST[seg]], eng.R[seg], eng.sil_cum,
                       caps=eng.caps)[0]


def _drawn_counts_compiled(kernels, eng, st, seg):
    # the same compiled count as span_counts', without its argument checks
    jp0, jp1 = eng.ends(st)
    d = np.zeros((1, 2), np.int64)
    kernels.counts(jp0[seg][None], jp1[seg][None], eng.R[seg][None], _TABLE_0, eng.sil_cum4,
                   0, eng.h, bool(eng.caps), d)
    return d[0]


__all__ = ["fit_kernels", "drawn_counts", "pose_joints"]
