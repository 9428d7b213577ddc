"""2D pose by fitting the 10-cylinder model to a silhouette (seed 004 section 3.1.4).

The order of section 3.1.4, per frame (:func:`fit_pose` with ``previous=None``):

1. Normalise the silhouette to a fixed height (section 4.2), so the body height in
   pixels is the silhouette's height and every length follows Table 3.1.
2. Torso position: the pelvis' y from the Table 3.1 ratios (head + torso below the
   top of the silhouette), its x the horizontal middle of the silhouette (the median
   over the torso's scan lines of the middle of each line's widest run).
3. Torso angle with the head attached (Algorithm 1, Table 3.3 "Waist" limits), then
   the head angle (Algorithm 1, "Neck" limits).
4. Arms by contour analysis (Algorithms 2-4): the silhouette left over beside the
   fitted torso and head, on each side, ordered into a curve away from the shoulder
   and split at the elbow corner.
5. Lower legs by scan-line contour analysis (Algorithm 2), knee crossing
   (Algorithm 5) and swap.
6. Upper legs with their lower legs as one unit (Algorithm 1, "hip" limits).
7. Foreshortening of every segment (Algorithm 6).

Beyond the seed:

* Segments are drawn as rectangles (``caps=False``, the default) or capsules; the
  renderer's cylinders seen from the side are rectangles, and rectangles measured
  better on rendered clips (RESULTS.md).
* Torso: after the seed's torso+head and head searches, the model is shifted so
  the head lines up with the silhouette and the torso is searched again turning
  about the neck (the silhouette's middle is pulled by arms and legs; the head is
  not), so a leaning torso under an upright head is found.
* Arms: residual slivers along the torso's edges are removed (an opening about an
  arm's width) before the contour curves are built; the curves are rings of
  distance from the shoulder rather than horizontal scan lines, so a raised or
  horizontal arm gives a curve too.
* ``spread``: how far the shoulders and hips sit from the torso axis (0 side view,
  1 front view) is searched like a foreshortening ratio (the seed draws one view).
* When Algorithm 5 reports crossed legs, both leg assignments are fitted and the
  better one kept; near-ties go to the straighter legs (the seed always swaps).
* ``refine`` (default on): the whole model is centred (shift search), each arm is
  searched whole (lower arm rigid, within 90 degrees of the contour estimate) and
  its length (Algorithm 6 on the arm as a unit), then every limb segment again
  with Algorithm 1 against the whole silhouette (+-30 degrees; lower limbs within
  150 degrees of their parent, thighs over 180-360 degrees rather than Table 3.3's
  240-300 so high steps fit), the torso once more with every limb drawn, and the
  final Algorithm 6 pass starts from the current ratios.
* ``arm_grid`` (default on, with ``refine``): after the limb refinement each whole
  arm is scored at every (upper, lower) angle pair 15 degrees apart in one batch
  (:meth:`_Fitter.search_arm_grid`), so a forearm poking out far from the contour
  estimate (raised beside the head, bent forward) is found; near-ties (an arm
  inside the torso's silhouette covers the same pixels at any angle) go to the
  arm hanging along the torso. Run on fresh fits only: in tracked frames it
  measured worse (it re-places carried arms on slivers along the torso's edges),
  so warm frames carry their arms from the previous frame. ``refine=False``
  (``--no-refine``) runs the seed's order only.
* ``leg_grid`` (default on): in tracked frames each whole leg is scored at every
  (thigh, shin) angle pair 15 degrees apart in one batch
  (:meth:`_Fitter.search_leg_grid`) and the best kept when it fits better than the
  tracked leg by more than 3 pixels' worth of S, so a leg that swung beyond the
  track's +-8 degrees (a knee raised across the other leg) is found again.
* Tracking (:func:`fit_sequence`, ``tracked=True``): a frame whose silhouette is
  still covered by the previous frame's pose (S >= ``warm_threshold``) starts every
  search from that pose with narrow intervals, skips the contour analysis, and
  searches the four upper limbs, then the head and four lower limbs, then all
  ratios in lockstep (one batch per iteration for a whole group,
  :meth:`_Fitter.search_group`). Limbs then keep their labels through crossings. A
  warm fit losing more than 3 % of the previous frame's S is redone from scratch
  and the better kept, and 10 frames after the last fresh fit another one challenges
  the track (so a wrong but stable track is left). In a side view (spread < 0.3) a fresh fit that
  takes over keeps the track's limb names (:func:`_keep_labels`): its image-side
  names would swap the legs against the frames before after every crossing.
  ``tracked=False`` (``--per-frame``) fits every frame independently, as the seed does.
* Temporal priors in tracked mode (:func:`fit_sequence`): when a fresh fit replaces
  the track, the frames before it are re-tracked backward from it while that fits
  them better (a track that began in a wrong pose is corrected from where the right
  one was found); and a frame whose ``spread`` jumps away from its neighbours'
  running median is refitted with the spread fixed at that median.
* Warm starts take part in their own search's first batch, so a search never ends
  below where it started.

Left and right
--------------
During 2D fitting ``l_*`` and ``r_*`` do NOT mean the performer's left and right.
Per frame (seed 004 section 3.1.4) ``l_*`` is the limb on the image's left. In
tracked mode a limb keeps its label from the frame where tracking (re)started, where
it was the image-left one, so labels follow limbs through crossings. The 3D stage
assigns true sides from the body orientation.

Angles are image-plane angles in radians, counter-clockwise from the image's +x axis
with y up (``pi/2`` straight up, ``3 pi/2`` straight down), in [0, 2 pi), of the
vector from the segment's proximal to its distal joint; the same convention as
:data:`vidcap.body.IMAGE_ANGLE_LIMITS_DEG` (which is in degrees).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np

from vidcap.body import (
    IMAGE_ANGLE_LIMITS_DEG,
    JOINT_INDEX,
    JOINT_NAMES,
    LIMB_PAIR_JOINTS,
    SEGMENT_NAMES,
    SEGMENTS,
)
from vidcap.fit.contour import (
    arm_angles,
    fit_angle,
    knees_crossed,
    leg_curves,
    limb_curve,
    row_runs,
)
from vidcap.fit.raster import (
    _DIST,
    _KERNEL_TABLES,
    _PROX,
    _SEG,
    DESCENDANTS,
    SEARCH_LIMB_ANGLE,
    SEARCH_LIMB_RATIO,
    SEARCH_POSE_ANGLES,
    SEARCH_POSE_FORE,
    SEARCH_POSE_SPREAD,
    SEARCH_POSE_TORSO_NECK,
    NormalisedMask,
    _carray,
    _kernels,
    base_tables,
    direction,
    draw_pose,
    group_scorer,
    group_span_tables,
    image_angle,
    limb_scorer,
    model_dimensions,
    normalise_mask,
    pose_joints_batch,
    pose_scorer,
    shift_overlaps,
    span_counts,
    span_similarity,
)
from vidcap.fit.search import interval_search, interval_search_many
from vidcap.fit.similarity import similarity_from_counts
from vidcap.masks import MaskStack

S = {name: i for i, name in enumerate(SEGMENT_NAMES)}
J = JOINT_INDEX
TWO_PI = 2 * np.pi
_LIMITS = {k: np.deg2rad(v) for k, v in IMAGE_ANGLE_LIMITS_DEG.items()}
_ONE_DEGREE = np.deg2rad(1.0)
_THIRTY_DEGREES = np.deg2rad(30.0)
#: Largest image-plane bend at an elbow or knee (the 150 degree flexion limit of
#: vidcap.body.FLEXION_LIMITS_DEG): a lower limb does not fold back over its parent.
_MAX_BEND = np.deg2rad(150.0)
#: Thigh directions allowed when refining and tracking: Table 3.3's hip limits
#: (240-300 degrees) keep the seed's first estimate upright, but a knee lifted to
#: hip height (a high step, a kick) points the thigh nearly horizontal (beyond the
#: seed).
_THIGH_WIDE = (np.deg2rad(180.0), np.deg2rad(360.0))
_REST_DEG = np.array([90, 90, 270, 270, 270, 270, 270, 270, 270, 270], dtype=float)


def _into_range(angle, lo, hi):
    """The representative of ``angle`` (mod 2 pi) in ``[lo, hi]``, or the nearer bound."""
    if np.ndim(angle) == 0 and np.ndim(lo) == 0 and np.ndim(hi) == 0:
        # scalars: Python's float % is numpy's np.mod (the same remainder), cheaper
        lo, hi = float(lo), float(hi)
        x = lo + (float(angle) - lo) % TWO_PI
        if x > hi:
            return lo if (lo + TWO_PI - x) < (x - hi) else hi
        return x
    x = lo + np.mod(np.asarray(angle, dtype=float) - lo, TWO_PI)
    beyond = x > hi
    nearer_lo = (lo + TWO_PI - x) < (x - hi)
    out = np.where(beyond, np.where(nearer_lo, lo, hi), x)
    return float(out) if np.ndim(out) == 0 else out


@dataclass(frozen=True)
class FramePose:
    """The fitted 2D pose of one frame.

    Attributes
    ----------
    joints : numpy.ndarray, shape (15, 2)
        Joints in :data:`vidcap.body.JOINT_NAMES` order, original-frame pixels
        ``(x, y)``, x right, y down. ``l_*``/``r_*`` are image-left/right limbs (see
        the module docstring), not the performer's sides.
    angles : numpy.ndarray, shape (10,)
        Image-plane angle of every segment (:data:`vidcap.body.SEGMENT_NAMES`
        order), radians in [0, 2 pi), counter-clockwise from +x with y up.
    foreshortening : numpy.ndarray, shape (10,)
        Apparent / true length of every segment, in (0, 1].
    scores : numpy.ndarray, shape (10,)
        The best similarity S (Eq. 3.3) found for every segment's last search.
    margins : numpy.ndarray, shape (10,)
        The best S minus the runner-up's (a distinct solution more than one
        division away); small margins flag doubtful segments.
    spread : float
        Lateral spread of shoulders and hips, 0 (side view) to 1 (front view).
    crossed : bool
        Algorithm 5's verdict on this frame (per-frame fitting only).
    similarity : float
        S of the whole fitted model against the whole silhouette.
    warm : bool
        True if the frame was fitted from the previous frame's pose.
    height_px : float
        Body height in original-frame pixels the model was scaled to (the
        silhouette's height, unless ``body_height`` was given).
    """

    joints: np.ndarray
    angles: np.ndarray
    foreshortening: np.ndarray
    scores: np.ndarray
    margins: np.ndarray
    spread: float
    crossed: bool
    similarity: float
    warm: bool
    height_px: float


@dataclass(frozen=True)
class Pose2D:
    """2D poses of a sequence (the output of ``vidcap pose2d``).

    ``l_*``/``r_*`` joints and segments are image-left/right limbs, not the
    performer's sides: per frame the limb on the image's left (seed 004 section
    3.1.4); in tracked mode the limb that was on the image's left where tracking
    (re)started, followed through crossings. The 3D stage assigns true sides.

    Attributes
    ----------
    joint_names : tuple of str, (15,)
        :data:`vidcap.body.JOINT_NAMES`.
    joints2d : numpy.ndarray, shape (F, 15, 2)
        Joints in original-frame pixels ``(x, y)``, x right, y down; NaN for frames
        without a silhouette.
    angles : numpy.ndarray, shape (F, 10)
        Segment image-plane angles, radians in [0, 2 pi), counter-clockwise from +x
        with y up (the convention of :data:`vidcap.body.IMAGE_ANGLE_LIMITS_DEG`).
    foreshortening : numpy.ndarray, shape (F, 10)
        Apparent / true segment length, in (0, 1].
    scores : numpy.ndarray, shape (F, 10)
        Best similarity S per segment.
    margins : numpy.ndarray, shape (F, 10)
        Best S minus the runner-up S per segment.
    spread : numpy.ndarray, shape (F,)
        Shoulder/hip lateral spread (0 side view, 1 front view).
    similarity : numpy.ndarray, shape (F,)
        S of the whole model per frame.
    warm : numpy.ndarray, shape (F,), bool
        Frames fitted from the previous frame's pose.
    tracked : bool
        Whether labels follow limbs over time (True) or are per-frame image sides.
    segment_names : tuple of str, (10,)
        :data:`vidcap.body.SEGMENT_NAMES`.
    model_height : numpy.ndarray, shape (F,), or None
        The body height, original-frame pixels, the model was drawn at in each frame
        (:attr:`FramePose.height_px`; NaN without a silhouette; None when unknown, as in
        files written before it was kept). Every segment's drawn length is its Table
        3.1 share of it times its foreshortening, so the 3D stage reads each
        segment's foreshortening against it rather than against one scale for the
        clip: the silhouette's height changes over a gait cycle, and so does the
        model's.
    """

    joint_names: tuple
    joints2d: np.ndarray
    angles: np.ndarray
    foreshortening: np.ndarray
    scores: np.ndarray
    margins: np.ndarray
    spread: np.ndarray
    similarity: np.ndarray
    warm: np.ndarray
    tracked: bool
    segment_names: tuple = field(default=SEGMENT_NAMES)
    model_height: np.ndarray | None = None

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return len(self.joints2d)

    def arrays(self) -> dict[str, np.ndarray]:
        """The pose as a dict of arrays (the keys of ``pose2d.npz``)."""
        return {
            "joint_names": np.array(self.joint_names),
            "segment_names": np.array(self.segment_names),
            "joints2d": self.joints2d,
            "angles": self.angles,
            "foreshortening": self.foreshortening,
            "scores": self.scores,
            "margins": self.margins,
            "spread": self.spread,
            "similarity": self.similarity,
            "warm": self.warm,
            "tracked": np.array(self.tracked),
            **({} if self.model_height is None else {"model_height": self.model_height}),
        }

    def save(self, path) -> None:
        """Write ``pose2d.npz`` atomically (keys of :meth:`arrays`)."""
        from vidcap.fileio import savez_atomic

        savez_atomic(path, **self.arrays())

    @classmethod
    def load(cls, path) -> Pose2D:
        """Read a file written by :meth:`save`."""
        from vidcap.errors import InputFileError

        try:
            with np.load(path, allow_pickle=False) as d:
                return cls(
                    joint_names=tuple(str(s) for s in d["joint_names"]),
                    joints2d=d["joints2d"], angles=d["angles"],
                    foreshortening=d["foreshortening"], scores=d["scores"],
                    margins=d["margins"], spread=d["spread"], similarity=d["similarity"],
                    warm=d["warm"], tracked=bool(d["tracked"]),
                    segment_names=tuple(str(s) for s in d["segment_names"]),
                    model_height=d["model_height"] if "model_height" in d.files else None,
                )
        except (OSError, KeyError, ValueError) as exc:
            raise InputFileError(f"not a pose2d file ({exc})", path) from exc


# placeholders for the kind of candidate a compiled search does not use (the kernel
# takes both; their types match the real ones, so one compiled version serves)
_NO_LIMB = (0.0, 0.0, 0.0, np.zeros(2), np.zeros(2), np.zeros((1, 2)), np.zeros((1, 2)),
            np.zeros(1))
_NO_POSE = (np.zeros(1, np.int64), np.zeros(1), np.zeros(2), 0.0, np.zeros(2), np.zeros(10),
            np.zeros(10), 0.0, np.zeros(10), 0.0, 0.0, *_KERNEL_TABLES, np.zeros(1, np.int64),
            np.zeros(1, np.int64))
_TABLE_0 = np.zeros(1, np.int64)  # one candidate counted against table 0
_PROX64, _DIST64 = _PROX.astype(np.int64), _DIST.astype(np.int64)  # as the kernels take them
#: each segment's child limb segment (-1: none)
_CHILD = tuple(DESCENDANTS[s][1] if len(DESCENDANTS[s]) > 1 else -1 for s in range(10))
# _DESCENDANT_OF[s, d]: segment d moves with segment s (s itself included)
_DESCENDANT_OF = np.array([[d in DESCENDANTS[s] for d in range(10)] for s in range(10)])
_FALLBACK = 0.97  # fit_pose's default: a warm fit below this share of the last S slipped
#: Normalised silhouettes :func:`fit_sequence` keeps for backward re-tracking (frames)
_NORMS_KEPT = 64
#: Spread below which shoulders and hips nearly coincide in the image (a side view), so
#: a fresh fit's image-side limb names mean nothing and a track's are kept
#: (:func:`_keep_labels`); above it a limb's name says which hip or shoulder it hangs
#: from, which the image shows.
_SIDE_SPREAD = 0.3
_LABEL_TIE = 0.002  # S a fresh fit may lose to keep a track's limb names
#: (joints, segments) of the image-left and image-right member of each limb pair.
LIMB_PAIRS = {
    pair: tuple((joints, [S[f"{side}_{p}_{pair[:-1]}"] for p in ("upper", "lower")])
                for side, joints in zip("lr", LIMB_PAIR_JOINTS[pair], strict=True))
    for pair in ("arms", "legs")
}
_NOWHERE = np.zeros(2)  # no neck (an action that does not turn the torso about it)
assert _SEG["torso"] == 0  # search_1d places the shoulders from angle 0's cos/sin


@functools.lru_cache(maxsize=8)
def _pair_grid(step_deg: float, legs: bool = False):
    """Every (upper, lower) angle pair ``step_deg`` apart whose elbow (knee) bend is
    within the flexion limit: the candidates of :meth:`_Fitter.search_arm_grid`
    (any direction) or, with ``legs``, of :meth:`_Fitter.search_leg_grid` (thigh
    within ``_THIGH_WIDE``, shin within the lower leg's limits: both point down),
    radians, each (N,), and their directions (:func:`direction`), each (N, 2)
    (read-only: shared by every call)."""
    if legs:
        def within(lim):  # whole degrees from the limits, as the arms' grid
            lo, hi = np.round(np.rad2deg(lim), 6)
            return np.deg2rad(np.arange(lo, hi + 1e-9, step_deg))

        up, low = within(_THIGH_WIDE), within(_LIMITS["l_lower_leg"])
    else:
        up = low = np.deg2rad(np.arange(0.0, 360.0, step_deg))
    ua, la = (g.ravel() for g in np.meshgrid(up, low, indexing="ij"))
    bend = np.abs(np.angle(np.exp(1j * (la - ua))))
    keep = bend <= _MAX_BEND + 1e-9
    ua, la = ua[keep], la[keep]
    du, dl = direction(ua), direction(la)
    for x in (ua, la, du, dl):
        x.flags.writeable = False
    return ua, la, du, dl


def _searched(out: np.ndarray) -> tuple[float, float, float, int, int]:
    """A compiled search's out (5,) as ``run`` returns it to :func:`interval_search`:
    value, score, runner-up, evaluations, iterations."""
    return float(out[0]), float(out[1]), float(out[2]), int(out[3]), int(out[4])


@dataclass(frozen=True)
class _GroupConstants:
    """What :meth:`_Fitter.search_group` needs of its segments alone (cached)."""

    segs: np.ndarray  # (N,) int64
    child: np.ndarray  # (N,) int64: the child each moves (itself for a leaf)
    n_k: int  # 2 if any has a child, else 1
    limits: np.ndarray  # (N, 2) angle limits, radians (thighs: _THIGH_WIDE)
    arm: np.ndarray  # (N,) bool: an arm segment (hangs down on ties)


@functools.lru_cache(maxsize=32)
def _group_constants(segs: tuple[int, ...]) -> _GroupConstants:
    s = np.array(segs, dtype=np.int64)
    child = np.array([x if _CHILD[x] < 0 else _CHILD[x] for x in segs], dtype=np.int64)
    limits = np.array([_THIGH_WIDE if "upper_leg" in SEGMENT_NAMES[x]
                       else _LIMITS[SEGMENT_NAMES[x]] for x in segs], dtype=float)
    arm = np.array([SEGMENT_NAMES[x].endswith("arm") for x in segs])
    for x in (s, child, limits, arm):
        x.flags.writeable = False
    return _GroupConstants(s, child, 1 if bool((child == s).all()) else 2, limits, arm)


def _median(values: np.ndarray) -> float:
    """``np.median`` of a short 1-D array (the same value, without its set-up cost)."""
    v = np.sort(values)
    mid = v.size // 2
    return float(v[mid] if v.size % 2 else (v[mid - 1] + v[mid]) / 2)


class _Fitter:
    """Fitting state for one normalised silhouette (all lengths in normalised px)."""

    def __init__(self, norm: NormalisedMask, *, caps: bool):
        self.norm = norm
        self.sil = norm.mask
        self.h, self.w = self.sil.shape
        # Body height = silhouette height (or the body's, when given apart from it),
        # less the round ends of the head and the lower legs when segments are drawn
        # as capsules (they reach beyond the joints).
        ends = (SEGMENTS[S["head"]].width_ratio + SEGMENTS[S["l_lower_leg"]].width_ratio) / 2
        body = norm.body_height
        self.H = body / (1.0 + ends) if caps else body
        # a silhouette taller than the body (raised arms): its top need not be the head
        self.taller = norm.height > 1.02 * self.H
        self.L, self.R, self.shoulder, self.hip = model_dimensions(self.H)
        self.top = norm.top + (self.R[S["head"]] if caps else 0.0)
        self.caps = caps
        self.root = np.zeros(2)
        self.angles = np.deg2rad(_REST_DEG)
        self.fore = np.ones(10)
        self.spread = 0.5
        self.scores = np.zeros(10)
        self.margins = np.zeros(10)
        self.drawn = np.zeros(10, dtype=bool)
        self.sil_rows, self._sil_cum = norm.count_tables  # shared by every fit of this mask
        self._sil_cum4 = self._sil_cum[None]  # as one table of the counting kernel
        self._sil_c = _carray(self.sil, np.bool_)  # what the kernels read
        self._L_c = _carray(self.L, np.float64)
        self._R_c = _carray(self.R, np.float64)
        self._similarity = None
        self.batches = 0
        self._joints = None

    # -- pose --------------------------------------------------------------------
    def joints(self) -> np.ndarray:
        """Joints of the current pose, (15, 2), cached until the pose changes."""
        key = (self.root.tobytes(), self.angles.tobytes(), self.fore.tobytes(), self.spread)
        if self._joints is None or self._joints[0] != key:
            j = self._pose_joints()
            self._joints = (key, j, j[_PROX], j[_DIST])
        return self._joints[1]

    def ends(self) -> tuple[np.ndarray, np.ndarray]:
        """Every segment's proximal and distal joint, each (10, 2), for the current pose."""
        self.joints()
        return self._joints[2], self._joints[3]

    def _pose_joints(self) -> np.ndarray:
        kernels = _kernels()
        if kernels is None:
            return pose_joints_batch(self.root[None], self.angles[None], self.fore[None],
                                     np.array([self.spread], dtype=float), self.L,
                                     self.shoulder, self.hip)[0]
        out = np.empty((1, 15, 2))  # one pose: one compiled call, no batch set-up
        kernels.pose_one(_carray(self.root, np.float64), _carray(self.angles, np.float64),
                         _carray(self.fore, np.float64), float(self.spread), self._L_c,
                         float(self.shoulder), float(self.hip), *_KERNEL_TABLES, out)
        return out[0]

    def model(self, segments=None) -> np.ndarray:
        seg = np.flatnonzero(self.drawn) if segments is None else segments
        return draw_pose(self.joints(), self.R, (self.h, self.w), segments=seg, caps=self.caps)

    def similarity(self) -> float:
        """S of the drawn model against the whole silhouette, counted from row spans."""
        self.joints()
        key = (self._joints[0], self.drawn.tobytes())  # the pose and what is drawn
        if self._similarity is None or self._similarity[0] != key:
            seg = np.flatnonzero(self.drawn)
            kernels = _kernels()
            # channel 0 counts model pixels, channel 1 model pixels on the silhouette
            if kernels is None or not seg.size:
                j = self.joints()
                d = span_counts(j[None, _PROX[seg]], j[None, _DIST[seg]], self.R[seg],
                                self._sil_cum, caps=self.caps)[0]
            else:  # the same compiled count, without span_counts' argument checks
                jp0, jp1 = self.ends()
                d = np.zeros((1, 2), np.int64)
                kernels.counts(jp0[seg][None], jp1[seg][None], self.R[seg][None], _TABLE_0,
                               self._sil_cum4, 0, self.h, bool(self.caps), d)
                d = d[0]
            s = similarity_from_counts(int(self.sil_rows[-1]), int(d[0]), int(d[1]))
            self._similarity = (key, s)
        return self._similarity[1]

    # -- scoring -----------------------------------------------------------------
    def _rows(self, rows) -> tuple[int, int]:
        """A search's rows ``(r0, r1)``: all of them (None), or ``rows`` within the image."""
        if rows is None:
            return 0, self.h
        return max(0, int(rows[0])), min(self.h, int(rows[1]))

    def _still(self, ends, moving, rows):
        """What a search adds its candidates to: the rows searched, the rows its
        candidates can reach, the segments that do not move ((K, 2) ends, (K,) radii)
        and the silhouette's pixels in those rows."""
        r0, r1 = self._rows(rows)
        still = self.drawn.copy()
        still[moving] = False
        still = np.flatnonzero(still)
        j = self.joints()
        limb = getattr(ends, "limb", None)
        reach = None
        if limb is not None:
            # a limb's candidates stay within its moving segments' full lengths of the
            # fixed proximal joint: the table is needed only in those rows
            y, ext = limb[2][1], float(self.L[moving].sum() + self.R.max()) + 4.0
            reach = (int(np.floor(y - ext)), int(np.ceil(y + ext)) + 1)
        a = int(self.sil_rows[r1] - self.sil_rows[r0])
        return (r0, r1), reach, j[_PROX[still]], j[_DIST[still]], self.R[still], a

    def _tables(self, ends, moving, rows):
        """The still segments of a search, drawn once (not per candidate): row prefix
        sums of the pixels a candidate may add to the model, the counts of what does
        not move, and the silhouette's pixels in the rows searched."""
        (r0, r1), reach, p0, p1, radii, a = self._still(ends, moving, rows)
        cum, m_base, i_base = base_tables(p0, p1, radii, self.sil, rows=(r0, r1), reach=reach,
                                          sil_cum=self._sil_cum[1], caps=self.caps)
        return (r0, r1), cum, a, np.array([m_base], np.int64), np.array([i_base], np.int64)

    def search(self, ends, moving, rows, lo, hi, *, divisions, min_step, start=None,
               interval=None, periodic=None, prefer=None):
        """:func:`interval_search` of the candidates ``ends`` describes (see
        :meth:`scorer`): one compiled call that also sets the search up when ``ends``
        carries a pose ``action`` (:func:`_kernels.pose_fit`; a limb segment's own
        searches are :meth:`_limb_search`), else with :meth:`scorer`."""
        action = getattr(ends, "action", None)
        kernels = _kernels()
        moving = np.asarray(moving, dtype=np.int64)
        r0, r1 = self._rows(rows)
        if kernels is None or divisions < 3 or action is None or r1 <= r0:
            return interval_search(self.scorer(ends, moving, rows), lo, hi,
                                   divisions=divisions, min_step=min_step, start=start,
                                   interval=interval, periodic=periodic, prefer=prefer)
        mode, idx, coef, neck, length = action[:5]
        # the spread's candidates hold the moving segments' distal ends still
        fixed = _carray(action[5], np.float64) if len(action) > 5 else _NO_LIMB[6]
        jp0, jp1 = self.ends()
        a = int(self.sil_rows[r1] - self.sil_rows[r0])
        f64 = np.float64
        pose = (np.asarray(idx, np.int64), np.asarray(coef, f64), np.asarray(neck, f64),
                float(length), fixed, _carray(self.root, f64), _carray(self.angles, f64),
                _carray(self.fore, f64), float(self.spread), self._L_c, float(self.shoulder),
                float(self.hip), *_KERNEL_TABLES)

        def run(lo_, hi_, centre, warm, width, period, gap_period, pref, divisions_, min_step_):
            out = np.empty(5)
            kernels.pose_fit(jp0, jp1, self._R_c, self.drawn, moving, _PROX64, _DIST64, mode,
                             *pose, _NO_LIMB, self._sil_c, self._sil_cum[1], a, r0, r1,
                             bool(self.caps), lo_, hi_, divisions_, min_step_, centre, warm,
                             width, period, gap_period, 0.0 if np.isnan(pref) else pref,
                             not np.isnan(pref), out)
            return _searched(out)

        self.batches += 1
        return interval_search(None, lo, hi, divisions=divisions, min_step=min_step,
                               start=start, interval=interval, periodic=periodic,
                               prefer=prefer, run=run)

    def scorer(self, ends, moving, rows=None):
        """Score function for :func:`interval_search`.

        ``ends(values) -> (p0, p1)``, each (B, K, 2), gives the end points of the
        ``moving`` segments for every candidate; every other drawn segment is drawn
        once into a base mask. Counts outside the candidates' bounding window are
        constant and computed once, so a batch only draws and counts its window.
        """
        moving = np.asarray(moving, dtype=int)
        (r0, r1), cum, a, m_base, i_base = self._tables(ends, moving, rows)
        radii = self.R[moving][None]  # (1, K): one table
        limb = getattr(ends, "limb", None)
        tables = {}

        pose = getattr(ends, "pose", None)
        # candidate end points built inside the compiled pass where possible
        if limb is not None:
            fast = limb_scorer(*limb, radii, cum, a, m_base, i_base, rows=(r0, r1),
                               caps=self.caps)
        elif pose is not None:
            poses = pose_scorer(self.L, self.shoulder, self.hip, moving, radii, cum, a, m_base,
                                i_base, rows=(r0, r1), caps=self.caps)

            def fast(values):
                return poses(*pose(values))
        else:
            fast = None

        def score(values):
            self.batches += 1
            values = np.asarray(values, dtype=float)
            if fast is not None:
                return fast(values)
            p0, p1 = ends(values)
            n_b = len(p0)
            if n_b not in tables:
                tables[n_b] = np.zeros(n_b, np.int64)
            # each candidate's rows are limited to its segments' extent in the kernel
            return span_similarity(_carray(p0, np.float64), _carray(p1, np.float64), radii,
                                   cum, a, m_base, i_base, rows=(r0, r1), table=tables[n_b],
                                   caps=self.caps)

        return score

    def _general_ends(self, make, moving, action=None):
        """End points from whole candidate poses (torso, head, spread, root searches).

        ``action``: what ``make`` does, for the compiled search
        (:meth:`search`): ``(mode, idx, coef, neck, length[, fixed])`` with ``mode``
        one of ``raster.SEARCH_POSE_*`` (``fixed`` (K, 2): the moving segments'
        distal ends, held still by ``SEARCH_POSE_SPREAD``).
        """
        moving = np.asarray(moving, dtype=int)

        def poses(v):
            n = len(v)
            return make(
                v, np.repeat(self.root[None], n, 0), np.repeat(self.angles[None], n, 0),
                np.repeat(self.fore[None], n, 0), np.full(n, self.spread))

        def ends(v):
            jb = pose_joints_batch(*poses(v), self.L, self.shoulder, self.hip)
            return jb[:, _PROX[moving]], jb[:, _DIST[moving]]

        ends.pose = poses  # what the scorer's compiled pass needs instead
        ends.action = action
        return ends

    def _limb_search(self, seg, form, scale, rows, lo, hi, **search):
        """:meth:`search` of one limb segment's angle (``form='angle'``, ``scale`` its
        drawn length) or foreshortening (``'ratio'``, ``scale`` its full (2,) vector)
        as one compiled call that also sets the search up (:func:`_kernels.limb_fit`);
        None where that call does not apply (then :meth:`search` does it)."""
        kernels = _kernels()
        if kernels is None or search["divisions"] < 3:
            return None
        r0, r1 = self._rows(rows)
        if r1 <= r0:
            return None
        jp0, jp1 = self.ends()
        if form == "angle":
            mode, sign, k0, k1 = SEARCH_LIMB_ANGLE, -1.0, float(scale), float(scale)
        else:
            mode, sign, k0, k1 = SEARCH_LIMB_RATIO, 1.0, float(scale[0]), float(scale[1])
        a = int(self.sil_rows[r1] - self.sil_rows[r0])
        child = _CHILD[seg]

        def run(lo_, hi_, centre, warm, width, period, gap_period, pref, divisions_, min_step_):
            out = np.empty(5)
            kernels.limb_fit(jp0, jp1, self._R_c, self._L_c, self.drawn, seg, child, mode,
                             sign, k0, k1, _NO_POSE, self._sil_c, self._sil_cum[1], a, r0, r1,
                             bool(self.caps), lo_, hi_, divisions_, min_step_, centre, warm,
                             width, period, gap_period, 0.0 if np.isnan(pref) else pref,
                             not np.isnan(pref), out)
            return _searched(out)

        self.batches += 1
        return interval_search(None, lo, hi, run=run, **search)

    def _limb_ends(self, seg, moving, form, scale):
        """End points when one limb segment's distal end moves (its children follow).

        The segment's new proximal -> distal vector is ``direction(v) * scale``
        (``form='angle'``) or ``v[:, None] * scale`` (``form='ratio'``).
        """
        if form == "angle":
            def vector(v):
                return direction(v) * scale
        else:
            def vector(v):
                return v[:, None] * scale

        j = self.joints()
        moving = np.asarray(moving, dtype=int)
        p0s, p1s = j[_PROX[moving]], j[_DIST[moving]]
        own = moving == seg
        start, old_end = j[_PROX[seg]], j[_DIST[seg]]

        def ends(v):
            delta = start + vector(v) - old_end  # (B, 2)
            p0 = p0s[None] + delta[:, None] * ~own[None, :, None]
            p1 = p1s[None] + delta[:, None]
            return p0, p1

        ends.limb = (form, scale, start, old_end, p0s, p1s, own)  # for the compiled pass
        return ends

    def search_angle(self, seg, *, with_segments=(), lo=None, hi=None, rows=None,
                     start=None, interval=None, min_step=_ONE_DEGREE, divisions=8,
                     prefer=None):
        """Algorithm 1 on segment ``seg`` (``with_segments`` rotate rigidly with it).

        ``prefer``: the angle that wins ties (default: the centre of the interval).
        """
        name = SEGMENT_NAMES[seg]
        lim_lo, lim_hi = _LIMITS[name]
        lo = lim_lo if lo is None else lo
        hi = lim_hi if hi is None else hi
        periodic = TWO_PI if hi - lo >= TWO_PI - 1e-9 else None
        if start is not None and periodic is None:
            # keep a warm start's interval inside the limits (angles are periodic)
            start = _into_range(start, lo, hi)
        if prefer is not None and periodic is None:
            prefer = _into_range(prefer, lo, hi)
        limb = seg >= 2 and not with_segments
        if limb:
            self.drawn[seg] = True
            res = self._limb_search(seg, "angle", self.L[seg] * self.fore[seg], rows, lo, hi,
                                    divisions=divisions, min_step=min_step, start=start,
                                    interval=interval, periodic=periodic, prefer=prefer)
            if res is not None:
                self.angles[seg] = np.mod(res.value, TWO_PI)
                self.scores[seg], self.margins[seg] = res.score, res.margin
                return res
        together = [seg, *with_segments]
        offsets = self.angles[together] - self.angles[seg]
        self.drawn[together] = True
        moving = np.flatnonzero(self.drawn & _DESCENDANT_OF[together].any(axis=0))
        if limb:
            length = self.L[seg] * self.fore[seg]
            ends = self._limb_ends(seg, moving, "angle", length)
        else:
            def make(v, root, ang, fore, spread):
                ang[:, together] = v[:, None] + offsets
                return root, ang, fore, spread

            ends = self._general_ends(make, moving, (SEARCH_POSE_ANGLES, together, offsets,
                                                     _NOWHERE, 0.0))
        res = self.search(ends, moving, rows, lo, hi, divisions=divisions, min_step=min_step,
                          start=start, interval=interval, periodic=periodic, prefer=prefer)
        self.angles[together] = np.mod(res.value + offsets, TWO_PI)
        self.scores[together] = res.score
        self.margins[together] = res.margin
        return res

    def search_fore(self, seg, *, start=None, interval=None, divisions=5, unit=False):
        """Algorithm 6 on segment ``seg`` (its descendants move with its end).

        ``unit``: scale the segment and its child limb segment together (a whole
        limb's foreshortening, beyond the seed).
        """
        self.drawn[seg] = True
        moving = [d for d in DESCENDANTS[seg] if self.drawn[d]]
        length = max(self.L[seg], 1.0)
        if unit:
            together = list(DESCENDANTS[seg])
            base = self.fore[together].copy()
            length = max(float((self.L[together] * base).sum()), 1.0)

            def make(v, root, ang, fore, spread):
                fore[:, together] = np.minimum(v[:, None] * base, 1.0)
                return root, ang, fore, spread

            ends = self._general_ends(make, moving, (SEARCH_POSE_FORE, together, base,
                                                     _NOWHERE, 0.0))
            res = self.search(ends, moving, None, 1.0 / length, 1.0, divisions=divisions,
                              min_step=1.0 / length, prefer=1.0)
            self.fore[together] = np.minimum(res.value * base, 1.0)
            return res
        step = 1.0 / length
        if seg >= 2:
            u = direction(self.angles[seg]) * self.L[seg]
            res = self._limb_search(seg, "ratio", u, None, step, 1.0, divisions=divisions,
                                    min_step=step, start=start, interval=interval,
                                    prefer=1.0)
            if res is not None:
                self.fore[seg], self.scores[seg], self.margins[seg] = (res.value, res.score,
                                                                       res.margin)
                return res
            ends = self._limb_ends(seg, moving, "ratio", u)
        else:
            def make(v, root, ang, fore, spread):
                fore[:, seg] = v
                return root, ang, fore, spread

            ends = self._general_ends(make, moving, (SEARCH_POSE_FORE, [seg], [1.0], _NOWHERE,
                                                     0.0))
        res = self.search(ends, moving, None, step, 1.0, divisions=divisions, min_step=step,
                          start=start, interval=interval, prefer=1.0)
        self.fore[seg] = res.value
        self.scores[seg] = res.score
        self.margins[seg] = res.margin
        return res

    def search_group(self, segs, *, kind="angle", start=None, interval=None, lo=None, hi=None,
                     divisions=8, min_step=_ONE_DEGREE, prefer=None):
        """Search one parameter of several limb segments at once (beyond the seed).

        The searches run in lockstep (:func:`interval_search_many`): every
        iteration scores all segments' candidates in one batch, each against the
        model without that segment (and its child), counted from row spans. Each
        segment's search is Algorithm 1 (``kind='angle'``) or Algorithm 6
        (``kind='fore'``) exactly as alone; only the order differs (each sees the
        others as they were when the group started).

        Parameters
        ----------
        segs : sequence of int
            Segments other than the torso (a segment moves itself and, for an upper
            limb, its lower limb).
        """
        consts = _group_constants(tuple(int(x) for x in segs))
        segs = consts.segs
        n = len(segs)
        self.drawn[:] = True
        length = self.L[segs]
        if kind == "angle":
            lo_a = consts.limits[:, 0] if lo is None else lo
            hi_a = consts.limits[:, 1] if hi is None else hi
            st = np.array(self.angles[segs] if start is None else start, dtype=float)
            full = hi_a - lo_a >= TWO_PI - 1e-9
            # a full circle is searched as the circle centred on the start (no wrap);
            # a limited range with the start unwrapped into it
            st = np.where(full, st, _into_range(st, lo_a, hi_a))
            lo_a = np.where(full, st - np.pi, lo_a)
            hi_a = np.where(full, st + np.pi, hi_a)
            if prefer is None:  # hidden arms hang down on ties
                prefer = np.where(consts.arm, self._hang(), np.nan)
            form, scale, periodic = "angle", length * self.fore[segs], TWO_PI
        else:
            step = 1.0 / np.maximum(length, 1.0)
            lo_a, hi_a, min_step, prefer = step, np.ones(n), float(step.min()), 1.0
            st = self.fore[segs] if start is None else start
            form, periodic = "ratio", None
            scale = direction(self.angles[segs]) * length[:, None]
        kernels = _kernels()
        if kernels is not None and divisions >= 3:  # the whole search, one compiled call
            value, best, runner = self._group_fit(kernels, consts, form, scale, lo_a, hi_a, st,
                                                  interval, periodic, prefer, divisions,
                                                  min_step)
        else:  # batch by batch
            value, best, runner = self._group_batches(consts, form, scale, lo_a, hi_a, st,
                                                      interval, periodic, prefer, divisions,
                                                      min_step)
        if kind == "angle":
            self.angles[segs] = np.mod(value, TWO_PI)
        else:
            self.fore[segs] = value
        self.scores[segs] = best
        self.margins[segs] = np.where(np.isfinite(runner), best - runner, best)

    def _group_fit(self, kernels, consts, form, scale, lo, hi, start, interval, periodic,
                   prefer, divisions, min_step):
        """:meth:`search_group`'s search as one compiled call (:func:`_kernels.group_fit`)."""
        n = len(consts.segs)
        current = (self.angles if form == "angle" else self.fore)[consts.segs]
        f64 = np.float64
        if form == "angle":
            sign, k0 = -1.0, _carray(scale, f64)
            k1 = k0
        else:
            sign, k0, k1 = 1.0, _carray(scale[:, 0], f64), _carray(scale[:, 1], f64)
        best, best_score, runner = np.empty(n), np.empty(n), np.empty(n)

        def full(x, default):
            if x is None:
                return np.full(n, default)
            return np.full(n, float(x)) if np.ndim(x) == 0 else _carray(x, f64)

        it = kernels.group_fit(
            *self.ends(), self._R_c, self._L_c, consts.segs, consts.child, consts.n_k,
            self._sil_c, bool(self.caps), int(self.sil_rows[-1]), full(lo, 0.0), full(hi, 0.0),
            full(start, 0.0), full(interval, 0.0), interval is not None,
            0.0 if periodic is None else float(periodic), True, full(prefer, np.nan),
            int(divisions), float(min_step), form == "angle", sign, k0, k1, current, best,
            best_score, runner)
        self.batches += 1
        if it < 0:
            raise ValueError("empty search interval")
        return best, best_score, runner

    def _group_batches(self, consts, form, scale, lo, hi, start, interval, periodic, prefer,
                       divisions, min_step):
        """:meth:`search_group`'s search batch by batch (without the compiled kernels, or
        with fewer than 3 divisions)."""
        segs, child = consts.segs, consts.child
        j = self.joints()
        own0, own1 = j[_PROX[segs]], j[_DIST[segs]]
        # every candidate of search n (and the pair as it is) lies within the segment's
        # and its child's full lengths of the segment's proximal joint (angles turn it,
        # ratios are at most 1): its table needs only those rows (+ margins)
        reach = self.L[segs] + np.where(child != segs, self.L[child], 0.0) + self.R.max() + 4
        rows = np.stack([np.floor(own0[:, 1] - reach), np.ceil(own0[:, 1] + reach) + 1], 1)
        cum, m_base, i_base = group_span_tables(j[_PROX], j[_DIST], self.R, segs, child,
                                                self._sil_c, rows=rows.astype(np.int64),
                                                caps=self.caps)
        a = int(self.sil_rows[-1])
        ch0, ch1 = j[_PROX[child]], j[_DIST[child]]
        leaf = child == segs
        radii = np.ascontiguousarray(self.R[np.stack([segs, child], 1)][:, :consts.n_k])
        scores = group_scorer(form, scale, own0, own1, ch0, ch1, leaf, radii, cum, a,
                              m_base, i_base, caps=self.caps)

        def score(values):  # values (N, B)
            self.batches += 1
            return scores(values)

        value, best, runner, _ = interval_search_many(
            score, lo, hi, divisions=divisions, min_step=min_step, start=start,
            interval=interval, prefer=prefer, periodic=periodic)
        return value, best, runner

    def search_spread(self, *, start=None, interval=None, min_step=0.05):
        """Lateral spread of shoulders and hips in [0, 1] (beyond the seed).

        Candidates move the shoulders and hips sideways while the elbows and knees
        stay put (the upper limbs pivot and stretch to reach them), so the limbs
        already fitted are not dragged off the silhouette; afterwards the upper
        limbs' angles and foreshortening are recomputed from their new ends.
        """
        self.drawn[:] = True
        uppers = np.array([S["l_upper_arm"], S["r_upper_arm"], S["l_upper_leg"],
                           S["r_upper_leg"]])
        j = self.joints()
        fixed_ends = j[_DIST[uppers]]

        def make(v, root, ang, fore, spread):
            return root, ang, fore, v

        general = self._general_ends(make, uppers)

        def ends(v):
            p0, _ = general(v)
            return p0, np.broadcast_to(fixed_ends, p0.shape)

        ends.action = (SEARCH_POSE_SPREAD, [0], [0.0], _NOWHERE, 0.0, fixed_ends)
        res = self.search(ends, uppers, None, 0.0, 1.0, divisions=4, min_step=min_step,
                          start=start, interval=interval, prefer=0.5)
        self.spread = res.value
        vec = fixed_ends - self.joints()[_PROX[uppers]]
        self.angles[uppers] = image_angle(vec)
        self.fore[uppers] = np.clip(np.hypot(*vec.T) / self.L[uppers], 1e-3, 1.0)
        return res

    def search_root(self, axis, half_range, *, rows=None):
        """Shift the whole model by whole pixels along x (axis 0) or y (axis 1).

        Beyond the seed (which fixes the torso from ratios and the silhouette's
        middle). All shifts in ``[-half_range, half_range]`` are scored in one batch
        as a 1-D cross-correlation of the drawn model with the silhouette.
        """
        n = max(1, int(round(half_range)))
        model = self.model()
        sil = self.sil
        r0, r1 = 0, self.h
        if rows is not None:
            r0 = min(max(0, int(rows[0])), self.h)
            r1 = max(r0, min(self.h, int(rows[1])))
            sil, model = sil[r0:r1], model[r0:r1]
        sil = sil if axis == 0 else sil.T
        mod = model if axis == 0 else model.T
        i = shift_overlaps(sil, mod, n)  # (2n+1,)
        n_sil = int(self.sil_rows[r1] - self.sil_rows[r0])  # counted once per mask
        scores = similarity_from_counts(n_sil, np.count_nonzero(mod), i)
        shifts = np.arange(-n, n + 1)
        best = np.flatnonzero(scores >= scores.max() - 1e-12)
        k = best[np.argmin(np.abs(shifts[best]))]
        self.batches += 1
        self.root[axis] += shifts[k]
        return scores[k]

    # -- seed steps --------------------------------------------------------------
    def place_torso(self):
        """Pelvis from the Table 3.1 ratios and the silhouette's horizontal middle."""
        neck_y = self.top + self.L[S["head"]]
        pelvis_y = neck_y + self.L[S["torso"]]
        if self.taller:  # stand on the silhouette's bottom
            legs = self.L[S["l_upper_leg"]] + self.L[S["l_lower_leg"]]
            pelvis_y = self.norm.bottom - legs
            neck_y = pelvis_y - self.L[S["torso"]]

        band = self.sil[int(round(neck_y)) : int(round(pelvis_y)) + 1]
        kernels = _kernels()
        if kernels is not None:  # the same middles, one compiled pass
            mid = np.empty(band.shape[0])
            count = kernels.widest_run_middles(_carray(band, np.bool_), mid)
            x = (_median(mid[:count]) if count
                 else float(np.median(np.nonzero(self.sil)[1])))
            self.root = np.array([x, pelvis_y])
            return
        rows, starts, ends = row_runs(band)
        if rows.size:
            widest = np.zeros(band.shape[0], dtype=int)
            mid = np.zeros(band.shape[0])
            width = ends - starts + 1
            order = np.lexsort((width, rows))  # per row, widest run last
            widest[rows[order]] = width[order]
            mid[rows[order]] = 0.5 * (starts[order] + ends[order])
            x = float(np.median(mid[widest > 0]))
        else:
            x = float(np.median(np.nonzero(self.sil)[1]))
        self.root = np.array([x, pelvis_y])

    def fit_torso_head(self, *, warm=False):
        top_rows = (0, self.root[1] + 1)
        if warm:
            self.search_torso_about_neck(start=self.angles[S["torso"]],
                                         interval=np.deg2rad(20), rows=top_rows)
            neck_y = self.joints()[J["neck"], 1]
            self.search_angle(S["head"], rows=(0, neck_y + self.R[S["torso"]]),
                              start=self.angles[S["head"]], interval=np.deg2rad(30))
            return
        # The seed: torso with the head attached (Alg. 1) about the pelvis, then the head.
        self.angles[S["head"]] = self.angles[S["torso"]]
        self.search_angle(S["torso"], with_segments=(S["head"],), rows=top_rows)
        neck_y = self.joints()[J["neck"], 1]
        head_rows = (0, neck_y + self.R[S["torso"]])
        self.search_angle(S["head"], rows=head_rows)
        # Beyond the seed: the silhouette's middle is pulled by arms and legs, the head
        # is not. Line the head up with the silhouette (shift the whole model), then
        # turn the torso about the neck so a leaning torso under an upright head is
        # found, and look at the head again.
        self.search_root(0, 0.1 * self.H, rows=(0, neck_y))
        self.search_torso_about_neck(start=self.angles[S["torso"]], interval=np.deg2rad(40),
                                     rows=top_rows)
        self.search_angle(S["head"], rows=head_rows, start=self.angles[S["head"]],
                          interval=np.deg2rad(20))

    def search_torso_about_neck(self, *, start, interval, rows=None, alone=False):
        """Algorithm 1 on the torso angle with the neck held still (beyond the seed).

        ``alone``: score the torso's candidates with the limbs left where they are
        (they re-attach afterwards); a cheaper approximation for small, warm steps.
        """
        seg = S["torso"]
        self.drawn[seg] = True
        lo, hi = _LIMITS["torso"]
        neck = self.joints()[J["neck"]].copy()
        length = self.L[seg] * self.fore[seg]
        moving = [seg] if alone else [d for d in range(10) if self.drawn[d]]

        def make(v, root, ang, fore, spread):
            ang[:, seg] = v
            return neck - direction(v) * length, ang, fore, spread

        ends = self._general_ends(make, moving, (SEARCH_POSE_TORSO_NECK, [seg], [0.0], neck,
                                                 length))
        res = self.search(ends, moving, rows, lo, hi, divisions=8, min_step=_ONE_DEGREE,
                          start=start, interval=interval)
        self.angles[seg] = res.value
        self.root = neck - direction(res.value) * length
        self.scores[seg], self.margins[seg] = res.score, res.margin
        return res

    def contour_arms(self):
        """Algorithms 2-4 on the silhouette left beside the torso and head."""
        self.drawn[[S["torso"], S["head"]]] = True
        body = self.model([S["torso"], S["head"]])
        body = cv2.dilate(body.view(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
        rest = self.sil & ~body
        # Slivers along the torso's edges (the model is not the silhouette's exact
        # shape) are not arms: keep only parts at least ~an arm's width across.
        k = max(2, int(round(1.5 * self.R[S["l_upper_arm"]])))
        rest = cv2.morphologyEx(rest.view(np.uint8), cv2.MORPH_OPEN,
                                cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))).astype(bool)
        j = self.joints()
        rest[max(int(j[J["pelvis"], 1]), 0) :] = False  # below the pelvis: legs
        ys, xs = np.nonzero(rest)
        axis = j[J["neck"]] - j[J["pelvis"]]
        side = axis[0] * (ys - j[J["pelvis"], 1]) - axis[1] * (xs - j[J["pelvis"], 0])
        # side < 0: image-left of an upward torso axis (cross product, y down).
        min_pixels = max(4.0, (2 * self.R[S["l_upper_arm"]]) ** 2)
        # Algorithm 4's minimumCornerDistance is 4 points in the seed; we also ask for
        # a third of an upper arm, so a handful of noisy points is not a segment.
        min_dist = max(4, int(round(0.33 * self.L[S["l_upper_arm"]])))
        for s, sel in (("l", side < 0), ("r", side > 0)):
            up, lo = S[f"{s}_upper_arm"], S[f"{s}_lower_arm"]
            hang = np.mod(self.angles[S["torso"]] + np.pi, TWO_PI)
            if np.count_nonzero(sel) < min_pixels:
                self.angles[[up, lo]] = hang
                continue
            curve = limb_curve(np.stack([xs[sel], ys[sel]], 1), j[J[f"{s}_shoulder"]])
            if len(curve) < 3:
                self.angles[[up, lo]] = hang
                continue
            lower, upper, _ = arm_angles(curve, min_distance=min_dist)
            self.angles[up], self.angles[lo] = upper, lower
        self.drawn[[S["l_upper_arm"], S["l_lower_arm"], S["r_upper_arm"], S["r_lower_arm"]]] = True

    def contour_lower_legs(self):
        """Algorithm 2 on the lower legs, Algorithm 5 for crossing; returns crossed."""
        # From the knees (Table 3.1 height above the lowest silhouette row) down.
        bottom = self.norm.bottom
        top = bottom - self.L[S["l_lower_leg"]] - (self.R[S["l_lower_leg"]] if self.caps else 0)
        left, right, merged = leg_curves(self.sil, int(round(top)), bottom,
                                         self.R[S["l_lower_leg"]])

        for s, curve in (("l", left), ("r", right)):
            seg = S[f"{s}_lower_leg"]
            if len(curve) >= 3:
                a = fit_angle(curve)
                lo, hi = _LIMITS[SEGMENT_NAMES[seg]]
                self.angles[seg] = np.clip(a if a >= np.pi / 2 else a + TWO_PI, lo, hi)
            else:
                self.angles[seg] = 1.5 * np.pi
        return knees_crossed(merged)

    def fit_upper_legs(self, *, warm=False, passes=2):
        rows = (self.root[1] - self.R[S["torso"]], self.h)
        for _ in range(passes):
            for s in ("l", "r"):
                up = S[f"{s}_upper_leg"]
                kw = dict(start=self.angles[up], interval=np.deg2rad(20)) if warm else {}
                # the lower leg keeps its (contour) angle and hangs from the knee
                self.search_angle(up, rows=rows, **kw)
            warm = True

    def fit_foreshortening(self, *, warm=False, interval=0.4):
        for seg in range(10):
            kw = dict(start=self.fore[seg], interval=interval) if warm else {}
            self.search_fore(seg, **kw)

    def refine_limbs(self, half_width=_THIRTY_DEGREES, *, whole_arms=False):
        """Algorithm 1 again on every limb segment against the whole silhouette.

        ``whole_arms``: first search each whole arm (lower arm rigidly attached) within
        90 degrees of the contour estimate (ties: hanging down), and its length, to undo
        a contour curve that went astray (beyond the seed, which avoids Algorithm 1 on
        the arms for fear of occlusion; the contour estimate is the tie-breaker).
        """
        if whole_arms:
            for s in ("l", "r"):
                up, lo = S[f"{s}_upper_arm"], S[f"{s}_lower_arm"]
                self.angles[lo] = self.angles[up]  # a straight arm first
                self.fore[[up, lo]] = 1.0
                self.search_angle(up, with_segments=(lo,), start=self.angles[up],
                                  interval=np.pi, prefer=self._hang())
                self.search_fore(up, unit=True)
        for seg_name in ("upper_leg", "lower_leg", "upper_arm", "lower_arm"):
            for s in ("l", "r"):
                seg = S[f"{s}_{seg_name}"]
                lo = hi = None
                if seg_name == "upper_leg":
                    lo, hi = _THIGH_WIDE
                if seg_name.startswith("lower"):
                    # the projected elbow/knee bend stays within the flexion limit
                    parent = S[f"{s}_upper_{seg_name.split('_')[1]}"]
                    lo = self.angles[parent] - _MAX_BEND
                    hi = self.angles[parent] + _MAX_BEND
                    if seg_name == "lower_leg":
                        lim = _LIMITS["l_lower_leg"]
                        lo, hi = max(lo, lim[0]), min(hi, lim[1])
                        if hi <= lo:
                            lo, hi = lim
                start = self.angles[seg]
                if lo is not None:
                    start = _into_range(start, lo, hi)
                # a shin may swing far from its contour estimate (a raised foot), so
                # the lower legs get their whole range; an arm hidden in the torso
                # covers the same pixels at any angle: ties go to hanging down
                width = (hi - lo) if seg_name == "lower_leg" else 2 * half_width
                prefer = self._hang() if seg_name.endswith("arm") else None
                self.search_angle(seg, start=start, interval=width, lo=lo, hi=hi,
                                  prefer=prefer)

    def search_arm_grid(self, s, *, prior=None, step_deg=15.0, tie_px=10.0, fine_deg=10.0):
        """Search one whole arm over every (upper, lower) angle pair at once (beyond the seed).

        Algorithm 1 searches one angle within an interval, so a forearm poking out of
        the silhouette far from its current estimate (raised beside the head, bent
        forward across the chest) is never reached, and an arm inside the torso's
        silhouette covers the same pixels at any angle. Here every pair of
        image-plane angles ``step_deg`` apart (elbow bend within the flexion limit)
        is scored in one batch against the rest of the model; among the candidates
        within ``tie_px`` pixels' worth of similarity of the best, the one closest
        to ``prior`` wins (the previous frame's arm when tracking, else an arm
        hanging along the torso), so a hidden arm is carried rather than put at an
        arbitrary angle. The winner is refined by Algorithm 1 (+-``fine_deg``) and
        kept unless the arm already in place fits better by more than the tie.

        Parameters
        ----------
        s : {'l', 'r'}
            Which arm (image-left/right label).
        prior : tuple of float, optional
            ``(upper, lower)`` angles in radians preferred among near-ties.
        """
        if prior is None:
            prior = (self._hang(), self._hang())
        self._search_pair_grid(S[f"{s}_upper_arm"], S[f"{s}_lower_arm"], J[f"{s}_shoulder"],
                               _pair_grid(float(step_deg)), prior, tie_px=tie_px,
                               fine_deg=fine_deg, keep_px=tie_px)

    def search_leg_grid(self, s, *, step_deg=15.0, tie_px=3.0, fine_deg=10.0):
        """Search one whole leg over every (thigh, shin) angle pair at once (beyond the seed).

        A tracked frame searches each leg segment within +-8 degrees of the previous
        frame's, so a leg that swung further between frames (a knee raised across
        the other leg, a kick, a step seen from three-quarter view) is lost and the
        track goes on with it wrong. Here every thigh direction within
        ``_THIGH_WIDE`` and shin direction within the lower leg's limits,
        ``step_deg`` apart (knee bend within the flexion limit), is scored in one
        batch against the rest of the model; near-ties (``tie_px`` pixels' worth of
        similarity) go to the candidate closest to the leg in place. The winner is
        refined by Algorithm 1 (+-``fine_deg``) and Algorithm 6, and kept only if it
        fits better than the leg in place by more than the tie: a leg is bigger than
        an arm and rarely hidden whole, so a smaller tie than the arms' serves. A
        winner within one grid step of the leg in place is what the track's own
        search already found, and is not refined (about two calls in three in the
        accuracy benchmark's clips: the grid then costs one compiled batch,
        ~0.2 ms).

        Parameters
        ----------
        s : {'l', 'r'}
            Which leg (its label: image side, or the track's).
        """
        up, lo = S[f"{s}_upper_leg"], S[f"{s}_lower_leg"]
        self._search_pair_grid(up, lo, J[f"{s}_hip"], _pair_grid(float(step_deg), legs=True),
                               (self.angles[up], self.angles[lo]), tie_px=tie_px,
                               fine_deg=fine_deg, keep_px=-tie_px, upper_range=_THIGH_WIDE,
                               lengths=True, skip_within=np.deg2rad(step_deg))

    def _search_pair_grid(self, up, lo, base, grid, prior, *, tie_px, fine_deg, keep_px,
                          upper_range=(0.0, TWO_PI), lengths=False, skip_within=0.0):
        """The whole-limb grid of :meth:`search_arm_grid` and :meth:`search_leg_grid`.

        ``up``, ``lo``: the limb's segments; ``base``: the joint it hangs from;
        ``grid``: :func:`_pair_grid`'s candidates; ``prior``: (upper, lower)
        radians preferred among candidates within ``tie_px`` pixels' worth of S of
        the best. The refined winner replaces the limb in place unless it fits
        worse than it by more than ``keep_px`` pixels' worth (negative: unless it
        fits better by more than ``-keep_px``), or within that and farther from
        ``prior``. ``upper_range``: the upper segment's refinement limits;
        ``lengths``: also refine both segments' foreshortening (Algorithm 6).
        ``skip_within``: radians (upper + lower); a winner this close to ``prior``
        is left unrefined and the limb in place kept.
        """
        prior = np.asarray(prior, dtype=float)
        self.drawn[[up, lo]] = True
        ua, la, du, dl = grid
        root = self.joints()[base]
        len_u, len_l = self.L[up] * self.fore[up], self.L[lo] * self.fore[lo]

        def ends(idx):
            k = idx.astype(int)
            mid = root + du[k] * len_u
            tip = mid + dl[k] * len_l
            p0 = np.stack([np.broadcast_to(root, mid.shape), mid], axis=1)
            p1 = np.stack([mid, tip], axis=1)
            return p0, p1

        kernels = _kernels()
        if kernels is None:
            score = self.scorer(ends, [up, lo])(np.arange(len(ua), dtype=float))
        else:  # the candidates' ends built inside the compiled pass (the same floats)
            (r0, r1), cum, a, m_base, i_base = self._tables(ends, np.array([up, lo]), None)
            score, q = np.empty(len(ua)), np.empty(len(ua))
            kernels.arm_pair_terms(du, dl, _carray(root, np.float64), float(len_u),
                                   float(len_l), _carray(self.R[[up, lo]], np.float64), cum,
                                   r0, r1, bool(self.caps), a, int(m_base[0]), int(i_base[0]),
                                   score, q)
            np.exp(score, out=score)  # S = exp(-p - n) (1 - p), as _similarity_terms
            score *= q
        n_sil = max(int(self.sil_rows[-1]), 1)
        per_px = 2.0 * float(score.max()) / n_sil  # S worth one pixel, about
        tie = tie_px * per_px

        def distance(u, low):
            return (np.abs(np.angle(np.exp(1j * (u - prior[0]))))
                    + np.abs(np.angle(np.exp(1j * (low - prior[1])))))

        near = np.flatnonzero(score >= score.max() - tie)
        k = near[np.argmin(distance(ua[near], la[near]))]
        if distance(ua[k], la[k]) < skip_within:
            return  # the limb in place is (near) the winner: nothing to refine
        kept, s_kept = self.state(), self.similarity()
        self.angles[up], self.angles[lo] = ua[k], la[k]
        fine = np.deg2rad(fine_deg)
        self.search_angle(up, with_segments=(lo,), start=ua[k], interval=2 * fine,
                          lo=upper_range[0], hi=upper_range[1], prefer=ua[k])
        if lengths:
            self.search_angle(lo, start=la[k], interval=2 * fine, prefer=la[k])
            self.search_fore(up)
            self.search_fore(lo)
        else:
            self.search_angle(lo, start=la[k], interval=2 * fine, lo=0.0, hi=TWO_PI,
                              prefer=la[k])
        s_new = self.similarity()
        keep = keep_px * per_px
        if s_new < s_kept - keep or (s_new <= s_kept + abs(keep) and distance(
                self.angles[up], self.angles[lo]) > distance(kept[1][up], kept[1][lo])):
            self.set_state(kept)

    def _hang(self) -> float:
        """The direction of an arm hanging along the torso, radians."""
        return float(np.mod(self.angles[S["torso"]] + np.pi, TWO_PI))

    def state(self):
        return (self.root.copy(), self.angles.copy(), self.fore.copy(), self.spread,
                self.scores.copy(), self.margins.copy())

    def set_state(self, st):
        self.root, self.angles, self.fore, self.spread = (st[0].copy(), st[1].copy(),
                                                          st[2].copy(), st[3])
        self.scores, self.margins = st[4].copy(), st[5].copy()


def _knee_bend(f: _Fitter) -> float:
    """Sum of the image-plane knee bends (radians) of the current pose."""
    d = f.angles[[S["l_lower_leg"], S["r_lower_leg"]]] - f.angles[[S["l_upper_leg"],
                                                                   S["r_upper_leg"]]]
    return float(np.abs(np.angle(np.exp(1j * d))).sum())


def _segments_cross(a0, a1, b0, b1) -> bool:
    """Do 2D segments a0-a1 and b0-b1 intersect (proper crossing)?"""
    def side(p, q, r):
        return np.sign((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))

    return (side(a0, a1, b0) * side(a0, a1, b1) < 0) and (side(b0, b1, a0) * side(b0, b1, a1) < 0)


def _untangle_thighs(f: _Fitter, *, tie: float) -> None:
    """Swap whole legs between the hips when the thighs cross (beyond the seed).

    With the hips apart (spread > 0.3), thighs that cross each other in a fresh
    fit most likely mean the image-left hip was given the image-right leg; the
    swapped legs (re-searched +-15 degrees) are kept unless they fit worse. Only
    fresh fits are untangled: a track keeps each leg on its hip, crossings
    included (see :func:`fit_normalised`).
    """
    j = f.joints()
    if f.spread <= 0.3 or not _segments_cross(j[J["l_hip"]], j[J["l_knee"]],
                                               j[J["r_hip"]], j[J["r_knee"]]):
        return
    kept, s_kept = f.state(), f.similarity()
    legs_l = [S["l_upper_leg"], S["l_lower_leg"]]
    legs_r = [S["r_upper_leg"], S["r_lower_leg"]]
    f.angles[legs_l + legs_r] = f.angles[legs_r + legs_l]
    f.fore[legs_l + legs_r] = f.fore[legs_r + legs_l]
    for seg in (S["l_upper_leg"], S["r_upper_leg"], S["l_lower_leg"], S["r_lower_leg"]):
        f.search_angle(seg, start=f.angles[seg], interval=np.deg2rad(30), lo=_THIGH_WIDE[0],
                       hi=_THIGH_WIDE[1]) if seg in (S["l_upper_leg"], S["r_upper_leg"]) \
            else f.search_angle(seg, start=f.angles[seg], interval=np.deg2rad(30))
    if f.similarity() < s_kept - tie:
        f.set_state(kept)


def _keep_labels(f: _Fitter, reference: np.ndarray, *, tie: float) -> None:
    """Give a fresh fit's limbs the labels a track gave them (in place).

    A fresh fit names limbs by image side; a track keeps the names it started with
    through crossings, so where a fresh fit takes over a track (a slipping warm fit,
    a challenge) its pairs can come out swapped against the frames
    before, and the 3D stage, which reads one limb as the body's left for the whole
    clip, would put that leg on the other hip from then on. Each pair (arms, legs)
    is swapped when the swapped labelling's joints are closer to ``reference`` (15,
    2), the previous frame's joints in this fit's pixels, and the swapped pose fits
    within ``tie`` as well (with the shoulders or hips apart, a limb drawn from the
    other one is a different pose).
    """
    j = f.joints()
    for (jl, sl), (jr, sr) in LIMB_PAIRS.values():
        both = jl + jr
        keep = np.linalg.norm(j[both] - reference[both], axis=-1).sum()
        swap = np.linalg.norm(j[jr + jl] - reference[both], axis=-1).sum()
        if not swap < keep:
            continue
        kept, s_kept = f.state(), f.similarity()
        for a in (f.angles, f.fore, f.scores, f.margins):
            a[sl + sr] = a[sr + sl]
        if f.similarity() < s_kept - tie:
            # each limb now hangs from the other shoulder (hip): settle it there
            f.search_group([sl[0], sr[0]], interval=np.deg2rad(16))
            f.search_group([sl[1], sr[1]], interval=np.deg2rad(16))
        if f.similarity() < s_kept - tie:
            f.set_state(kept)


def _swap_lower_legs(f: _Fitter):
    a, b = S["l_lower_leg"], S["r_lower_leg"]
    f.angles[[a, b]] = f.angles[[b, a]]


def fit_normalised(norm: NormalisedMask, *, previous: FramePose | None = None,
                   refine: bool = True, spread: bool = True, verify_crossing: bool = True,
                   caps: bool = False, warm_threshold: float = 0.55, tie: float = 0.01,
                   warm_step_deg: float = 2.0, arm_grid: bool = True,
                   leg_grid: bool = True, spread_value: float | None = None):
    """Fit the model to a normalised silhouette; see :func:`fit_pose`.

    Returns
    -------
    fitter : _Fitter
        The final fitting state (normalised pixels).
    crossed : bool
    warm : bool
    """
    fixed_spread = 0.5 if spread_value is None else float(spread_value)
    spread = spread and spread_value is None  # search the spread?
    f = _Fitter(norm, caps=caps)
    f.spread = fixed_spread
    f.place_torso()
    crossed = False
    warm = False
    if previous is not None:
        f.angles = np.array(previous.angles, dtype=float)
        f.fore = np.array(previous.foreshortening, dtype=float)
        f.spread = float(previous.spread) if spread else fixed_spread
        f.drawn[:] = True
        if f.taller:
            # the head need not be at the silhouette's top (a shorter silhouette, a
            # crouch, still has the head on top)
            f.search_root(1, 0.25 * f.H)
        warm = f.similarity() >= warm_threshold
    if warm:
        # Tracking: every search starts from the previous frame's pose with a narrow
        # interval (2 iterations of Algorithm 1: +-8 degrees in 2 degree steps, then
        # 0.5; 2 of Algorithm 6); no contour step.
        f.drawn[:] = True
        f.search_root(0, 0.1 * f.H)
        step = np.deg2rad(warm_step_deg)
        f.search_torso_about_neck(start=f.angles[S["torso"]], interval=8 * step, alone=True)
        uppers = [S[f"{s}_upper_{p}"] for p in ("arm", "leg") for s in "lr"]
        leaves = [S["head"]] + [S[f"{s}_lower_{p}"] for p in ("arm", "leg") for s in "lr"]
        f.search_group(uppers, interval=8 * step)
        f.search_group(leaves, interval=8 * step)
        if spread:
            f.search_spread(start=f.spread, interval=0.2, min_step=0.1)
        f.search_group(uppers + leaves, kind="fore", interval=0.2, divisions=5)
        if leg_grid:
            for s in ("l", "r"):
                f.search_leg_grid(s)
        # no _untangle_thighs here: a tracked leg stays on the hip it was found on.
        # Thighs crossing in the image are no error in a three-quarter view (the
        # forward knee passes the other across the narrow hips every step), and
        # undoing them within the tie put the legs on the wrong hips for half of
        # each gait cycle (07_07 at 45 deg: PCK@0.05 89.3 -> 90.8 %, RESULTS.md).
    else:
        f.angles = np.deg2rad(_REST_DEG)
        f.fore = np.ones(10)
        f.drawn[:] = False
        f.fit_torso_head()
        f.contour_arms()
        crossed = f.contour_lower_legs()
        if crossed:
            _swap_lower_legs(f)  # Algorithm 2: swap the lower legs when crossed
        f.drawn[:] = True

        def legs_and_spread():
            f.fit_upper_legs()
            if spread:
                f.search_spread()
                f.fit_upper_legs(warm=True, passes=1)
            return f.similarity()

        s_kept = legs_and_spread()
        if crossed and verify_crossing:
            # Beyond the seed: keep the swap only if it covers the silhouette better
            # than the unswapped legs (Algorithm 5 also fires on some bent knees).
            # An X at the knees looks the same as two legs bent toward each other, so
            # near-ties go to the straighter legs (smaller image-plane knee bends).
            kept = f.state()
            bend_kept = _knee_bend(f)
            _swap_lower_legs(f)
            f.spread = kept[3] if not spread else 0.5
            s_other = legs_and_spread()
            if s_other < s_kept - tie or (s_other <= s_kept + tie and _knee_bend(f) >= bend_kept):
                f.set_state(kept)
        if refine:
            f.drawn[:] = True
            f.search_root(0, 0.05 * f.H)
            f.refine_limbs(whole_arms=True)
            if arm_grid:
                for s in ("l", "r"):
                    f.search_arm_grid(s)
            # the torso once more with every limb drawn (the arms no longer pull it)
            f.search_torso_about_neck(start=f.angles[S["torso"]], interval=np.deg2rad(16))
            _untangle_thighs(f, tie=tie)
            if spread:
                f.search_spread(start=f.spread, interval=0.4)
        f.fit_foreshortening(warm=refine)
    return f, crossed, warm


def fit_pose(mask: np.ndarray | NormalisedMask, *, previous: FramePose | None = None,
             height: int = 80, refine: bool = True, spread: bool = True,
             verify_crossing: bool = True, caps: bool = False, warm_threshold: float = 0.55,
             fallback: float = _FALLBACK, warm_step_deg: float = 2.0,
             challenge: bool = False, arm_grid: bool = True, leg_grid: bool = True,
             spread_value: float | None = None,
             body_height: float | None = None) -> FramePose:
    """Fit the 2D cylinder model to one silhouette (seed 004 section 3.1.4).

    Parameters
    ----------
    mask : numpy.ndarray, shape (H, W), bool, or NormalisedMask
        The silhouette in the original frame, or already normalised by
        :func:`vidcap.fit.raster.normalise_mask` (then ``height`` and ``body_height``
        are not used: a sequence fit reuses a frame's for its refits).
    previous : FramePose, optional
        The previous frame's pose. If it still covers this silhouette with
        similarity >= ``warm_threshold``, every search starts from it with narrow
        intervals (tracking); otherwise the frame is fitted from scratch.
    height : int
        Height in pixels the silhouette is normalised to before fitting.
    refine : bool
        Run the extra Algorithm 1 pass over the limbs (beyond the seed).
    spread : bool
        Search the shoulders' and hips' lateral spread (beyond the seed); if false
        the spread is fixed at 0.5.
    spread_value : float, optional
        Fix the spread at this value in [0, 1] instead (no search);
        :func:`fit_sequence` uses it to refit frames whose spread jumps away from
        their neighbours'.
    verify_crossing : bool
        When Algorithm 5 says the legs cross, keep the swap only if it fits better.
    caps : bool
        Draw segments as capsules (true) or rectangles.
    warm_threshold : float
        Similarity of the previous pose needed to warm-start.
    fallback : float
        A warm fit whose similarity is below ``fallback`` times the previous
        frame's is redone from scratch and the better of the two kept.
    warm_step_deg : float
        First step of a warm angle search in degrees (8 divisions, so the search
        spans +-4 steps around the previous angle, then refines by a quarter).
    challenge : bool
        Also fit a warm-started frame from scratch and keep the better fit (how a
        track escapes a wrong but stable pose; :func:`fit_sequence` does this
        ``reinit_every`` frames after the last fresh fit).
    arm_grid : bool
        With ``refine``, search each whole arm over every (upper, lower) angle pair
        in fresh (not warm-started) fits; near-ties go to a hanging arm
        (:meth:`_Fitter.search_arm_grid`).
    leg_grid : bool
        In warm-started (tracked) fits, search each whole leg over every (thigh,
        shin) angle pair and keep the best if it fits clearly better than the
        tracked leg (:meth:`_Fitter.search_leg_grid`).

    Returns
    -------
    FramePose

    Raises
    ------
    ValueError
        If ``mask`` is empty.
    """
    norm = (mask if isinstance(mask, NormalisedMask)
            else normalise_mask(mask, height=height, body_height=body_height))
    kw = dict(refine=refine, spread=spread, verify_crossing=verify_crossing, caps=caps,
              warm_step_deg=warm_step_deg, arm_grid=arm_grid, leg_grid=leg_grid,
              spread_value=spread_value)
    f, crossed, warm = fit_normalised(norm, previous=previous, warm_threshold=warm_threshold,
                                      **kw)
    if warm and (challenge or f.similarity() < fallback * previous.similarity):
        # the track is slipping: fit this frame from scratch, keep the better fit
        g, g_crossed, _ = fit_normalised(norm, **kw)
        if g.similarity() > f.similarity():
            if max(previous.spread, g.spread) < _SIDE_SPREAD:
                # a side view: no image cue names the limbs, the track's names stand
                _keep_labels(g, norm.to_normalised(previous.joints), tie=_LABEL_TIE)
            f, crossed, warm = g, g_crossed, False
    return FramePose(
        joints=norm.to_original(f.joints()),
        angles=np.mod(f.angles, TWO_PI),
        foreshortening=f.fore.copy(),
        scores=f.scores.copy(),
        margins=f.margins.copy(),
        spread=float(f.spread),
        crossed=bool(crossed),
        similarity=f.similarity(),
        warm=bool(warm),
        height_px=norm.body_height / norm.scale,
    )


def fit_sequence(masks: np.ndarray | Sequence[np.ndarray], *, tracked: bool = True,
                 progress=None, reinit_every: int = 10, spread_window: int = 31,
                 spread_jump: float = 0.25, spread_tie: float = 0.01,
                 back_tie: float | None = 0.002, body_window: int = 91,
                 body_tolerance: float = 0.05, **kw) -> Pose2D:
    """Fit every frame of a silhouette sequence.

    Parameters
    ----------
    masks : numpy.ndarray, shape (F, H, W), bool (or a sequence of (H, W) masks)
        Silhouettes in original-frame pixels.
    tracked : bool
        Warm-start each frame from the previous one when its pose still fits
        (beyond the seed); ``False`` fits every frame independently (the seed).
    progress : callable, optional
        Wraps the frame iterator (e.g. :func:`vidcap.fileio.progress`); called as
        ``progress(iterable, total=F)``.
    reinit_every : int
        In tracked mode a frame this many frames after the last one fitted from
        scratch (a challenge, or a fresh fit that took over a slipping track) is also
        fitted from scratch and the better fit kept (0: never).
    back_tie : float or None
        Tracked mode: when a fresh fit replaces the track at a frame, the frames
        before it (back to where that track began) are refitted warm from the new
        pose, backward, while that improves their similarity by more than
        ``back_tie`` (None: off). A track that started in a wrong pose is thus
        corrected from the frame where the right one was found.
    spread_window, spread_jump, spread_tie
        Temporal prior on the spread (tracked mode, beyond the seed): the spread
        follows the body's yaw, which changes slowly, but a single silhouette
        barely shows it (the torso cylinder looks the same from every side), so
        per-frame estimates wander. After the pass, a frame whose spread is more
        than ``spread_jump`` from the running median over ``spread_window``
        frames (shifted inside the clip at its ends) is refitted with the spread
        fixed at that median (warm from its own pose, from scratch, and within
        a run of such frames warm from the one before), and the best refit
        kept unless its similarity is more than ``spread_tie`` lower. 0 window:
        off. A median passes a steady turn through unchanged (but within half a
        window of the clip's ends, where a turn reads as the first or last
        window's median and the similarity check decides), so the window (about
        1 s at 30 fps) only has to be longer than twice the runs of misread
        frames.
    body_window, body_tolerance
        The body's height in pixels (tracked mode, beyond the seed): the seed
        scales the model to each silhouette's height, which assumes an upright
        body; a crouch makes the silhouette shorter and raised arms make it
        taller. After the pass, the body's height is estimated per frame as the
        median silhouette height of the well-fitted frames (similarity at least
        the window's median) within ``body_window`` frames; a frame whose
        silhouette height is more than ``body_tolerance`` (a fraction) from it is
        refitted at that height, warm from the frame before, and the refit kept
        if its similarity is higher. 0 window: off.
    **kw
        Passed to :func:`fit_pose` (``height``, ``refine``, ``spread``, ...).

    Returns
    -------
    Pose2D
        Frames with an empty silhouette get NaN joints and angles and zero scores.
    """
    n = len(masks)
    out = _Frames(n)
    it = range(n) if progress is None else progress(range(n), total=n)
    prev = None
    start = 0  # first frame of the current track
    last_fresh = -reinit_every  # the last frame fitted from scratch (the first one is)
    # frames' normalised silhouettes, reused by backward re-tracking (bounded memory)
    norms: dict[int, NormalisedMask] = {}
    size = dict(height=kw.get("height", 80), body_height=kw.get("body_height"))
    fit_kw = _fit_options(kw)

    def normalised(k: int) -> NormalisedMask:
        norm = norms.get(k)
        if norm is None:
            norm = _normalise_frame(masks, k, **size)
            if len(norms) >= _NORMS_KEPT:
                del norms[min(norms)]
            norms[k] = norm
        return norm

    for k in it:
        if not _frame_has_pixels(masks, k):
            prev = None
            start = k + 1
            continue
        # a fresh fit that took over (a slipping track) challenged the track as well
        challenge = bool(reinit_every) and k - last_fresh >= reinit_every
        fp = fit_pose(normalised(k), previous=prev if tracked else None, challenge=challenge,
                      **fit_kw)
        if challenge or not fp.warm:
            last_fresh = k
        out.put(k, fp)
        if tracked and prev is not None and not fp.warm and back_tie is not None:
            # A fresh fit replaced the track: the frames before it were probably
            # tracked in a wrong pose too. Carry the new pose backward while it fits
            # those frames better (beyond the seed).
            back = fp
            fallback = kw.get("fallback", _FALLBACK)
            for b in range(k - 1, start - 1, -1):
                nb = normalised(b)
                fb = fit_pose(nb, previous=back, **{**fit_kw, "fallback": 0.0})
                if not fb.warm or fb.similarity <= out.sim[b] + back_tie:
                    break
                # fit_pose's fallback, only where its outcome matters: a fresh fit
                # that beats the slipping warm one ends the backward track
                if (fb.similarity < fallback * back.similarity
                        and fit_pose(nb, **fit_kw).similarity > fb.similarity):
                    break
                out.put(b, fb)
                back = fb
            start = k
        prev = fp
    body = np.full(n, np.nan)  # the body's height where a frame was fitted at it, px
    if tracked and body_window > 1 and n > 2:
        # the heights the main pass scaled the model to (the silhouettes', unless given)
        body = _refit_body_height(masks, body_window, body_tolerance, kw, out.height.copy(),
                                  out)
    if tracked and spread_window > 1 and kw.get("spread", True) and n > 2:
        _smooth_spread(masks, spread_window, spread_jump, spread_tie, kw, body, out)
    return Pose2D(JOINT_NAMES, out.joints, out.angles, out.fore, out.scores, out.margins,
                  out.spread, out.sim, out.warm, bool(tracked), model_height=out.height)


class _Frames:
    """:func:`fit_sequence`'s per-frame results as arrays, filled frame by frame."""

    def __init__(self, n: int):
        self.joints = np.full((n, 15, 2), np.nan)
        self.angles = np.full((n, 10), np.nan)
        self.fore = np.full((n, 10), np.nan)
        self.scores = np.zeros((n, 10))
        self.margins = np.zeros((n, 10))
        self.spread = np.full(n, np.nan)
        self.sim = np.zeros(n)
        self.warm = np.zeros(n, dtype=bool)
        self.height = np.full(n, np.nan)  # the body height the model was drawn at, px

    def put(self, k: int, fp: FramePose, *, warm: bool = True) -> None:
        """Store frame k's fit (``warm``: its warm flag too)."""
        self.joints[k], self.angles[k], self.fore[k] = fp.joints, fp.angles, fp.foreshortening
        self.scores[k], self.margins[k], self.spread[k] = fp.scores, fp.margins, fp.spread
        self.sim[k] = fp.similarity
        self.height[k] = fp.height_px
        if warm:
            self.warm[k] = fp.warm

    def get(self, k: int, *, spread: float | None = None, height_px: float = 0.0) -> FramePose:
        """Frame k's stored fit as a :class:`FramePose` to warm-start from."""
        return FramePose(joints=self.joints[k], angles=self.angles[k],
                         foreshortening=self.fore[k], scores=self.scores[k],
                         margins=self.margins[k],
                         spread=float(self.spread[k] if spread is None else spread),
                         crossed=False, similarity=float(self.sim[k]),
                         warm=bool(self.warm[k]), height_px=float(height_px))


def body_heights(heights: np.ndarray, similarity: np.ndarray, window: int) -> np.ndarray:
    """The body's standing height per frame, from the silhouettes' heights.

    Parameters
    ----------
    heights : numpy.ndarray, shape (F,)
        Silhouette height per frame, pixels (NaN: no silhouette).
    similarity : numpy.ndarray, shape (F,)
        S of each frame's fit at that height.
    window : int
        Frames (centred; truncated at the clip's ends).

    Returns
    -------
    numpy.ndarray, shape (F,)
        The median height over the window's well-fitted frames (S at least the
        window's median S): a body whose silhouette is not as tall as it (a
        crouch, raised arms) fits worse at that height, so those frames drop out
        while they are fewer than half the window. NaN where the window has no
        frame.
    """
    h = np.asarray(heights, dtype=float)
    s = np.where(np.isfinite(h), np.asarray(similarity, dtype=float), np.nan)
    half = max(1, int(window) // 2)
    pad = np.full(half, np.nan)

    def windows(x):  # (F, 2 half + 1), NaN beyond the clip
        return np.lib.stride_tricks.sliding_window_view(np.concatenate([pad, x, pad]),
                                                        2 * half + 1)

    out = np.full(h.shape, np.nan)
    have = np.isfinite(windows(s)).any(axis=1)
    if not have.any():
        return out
    sw, hw = windows(s)[have], windows(h)[have]
    good = sw >= np.nanmedian(sw, axis=1, keepdims=True)
    out[have] = np.nanmedian(np.where(good, hw, np.nan), axis=1)
    return out


def _normalise_frame(masks, k: int, *, height: int = 80,
                     body_height: float | None = None) -> NormalisedMask:
    """Frame ``k`` of ``masks`` normalised: a :class:`MaskStack` frame from its crop
    (the same result as from the full frame, without building it)."""
    if isinstance(masks, MaskStack):
        crop, origin = masks.crop(k)
        return normalise_mask(crop, height=height, body_height=body_height, origin=origin)
    return normalise_mask(np.asarray(masks[k], dtype=bool), height=height,
                          body_height=body_height)


def _frame_has_pixels(masks, k: int) -> bool:
    if isinstance(masks, MaskStack):
        return bool(masks.bits[k].any())
    return bool(np.asarray(masks[k]).any())


def _fit_options(kw: dict) -> dict:
    """``fit_sequence``'s keywords for :func:`fit_pose` on a normalised mask (the
    normalisation's own, ``height`` and ``body_height``, are used already)."""
    return {key: v for key, v in kw.items() if key not in ("height", "body_height")}


def _refit_body_height(masks, window, tolerance, kw, height, out: _Frames):
    """Refit frames whose silhouette is not as tall as the body (in place); returns
    the body height (px) each refitted frame was fitted at, NaN elsewhere."""
    body = body_heights(height, out.sim, window)
    off = np.isfinite(height) & np.isfinite(body) & (np.abs(height / body - 1) > tolerance)
    used = np.full(len(height), np.nan)
    prev = None
    for k in range(len(height)):
        if not np.isfinite(height[k]):
            prev = None
            continue
        if off[k]:
            norm = _normalise_frame(masks, k, height=kw.get("height", 80),
                                    body_height=float(body[k]))
            fp = fit_pose(norm, previous=prev, **_fit_options(kw))
            if fp.similarity > out.sim[k]:
                out.put(k, fp)
                used[k] = body[k]
                prev = fp
                continue
        prev = out.get(k, height_px=height[k])
    return used


def _window_median(values: np.ndarray, window: int) -> np.ndarray:
    """Running median of ``values`` (N,) over ``window`` samples, the window shifted to
    stay inside the array near its ends rather than padded there: a clip whose first
    frames were misread is judged by the frames after them, not by copies of its own
    first value (as ``median_filter(mode="nearest")`` would). (N,)."""
    n = values.shape[0]
    w = max(1, min(int(window), n))
    first = np.clip(np.arange(n) - w // 2, 0, n - w)
    return np.median(values[first[:, None] + np.arange(w)], axis=1)


def _smooth_spread(masks, window, jump, tie, kw, body, out: _Frames):
    """Refit frames whose spread jumps away from the running median (in place), each at
    the height it was fitted at (``body``: px, NaN for the silhouette's).

    Each such frame is fitted at the median's spread warm from its own pose, from
    scratch (its limbs were found for the other spread), and, inside a run of such
    frames, warm from the frame before once that was refitted (a run is tracked at
    the new spread, as the main pass would have); the best is kept unless it fits
    more than ``tie`` worse than the frame's fit.
    """
    spread = out.spread
    ok = np.isfinite(spread)
    if ok.sum() < 3:
        return
    idx = np.flatnonzero(ok)
    med = np.full_like(spread, np.nan)
    med[idx] = _window_median(spread[idx], window)
    refitted = -2
    for k in np.flatnonzero(ok & (np.abs(spread - med) > jump)):
        at = float(body[k]) if np.isfinite(body[k]) else None
        norm = _normalise_frame(masks, k, height=kw.get("height", 80), body_height=at)
        options = {**_fit_options(kw), "spread_value": float(med[k])}
        # warm from its own pose, challenged by a fresh fit (which, in a side view,
        # takes the track's limb names, as in the main pass)
        fp = fit_pose(norm, previous=out.get(k, spread=med[k]), challenge=True, **options)
        if refitted == k - 1:
            chained = fit_pose(norm, previous=out.get(k - 1, spread=med[k]), **options)
            if chained.similarity > fp.similarity:
                fp = chained
        if fp.similarity >= out.sim[k] - tie:
            out.put(k, fp, warm=False)
            refitted = k


__all__ = ["FramePose", "Pose2D", "body_heights", "fit_normalised", "fit_pose", "fit_sequence"]
