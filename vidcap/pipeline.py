"""Video -> BVH: the stages in sequence, with caching and progress.

Stages (``../shared/design.md``)::

    frames -> background plate -> silhouettes -> 2D pose -> 3D lift -> motion -> BVH

The expensive image stages (plate, silhouettes, 2D pose) are cached as ``.npz``
files in a cache folder (default ``.vidcap-cache`` beside the output), each keyed by
a hash of the video's identity (absolute path, size, modification time), the
stage's parameters and the key of the stage before it, so changing an option or the
video redoes exactly the stages that depend on it. The 3D stage (:func:`lift_pose`)
is cheap and always rerun, since it depends on the user's annotations.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter1d, median_filter

from vidcap.annotations import PAIRS, Annotations, default_path
from vidcap.body import JOINT_NAMES, LIMB_PAIR_JOINTS, ORIENTATIONS, SEGMENT_NAMES, BodyModel
from vidcap.errors import AnnotationError, VidcapError
from vidcap.fileio import savez_atomic
from vidcap.lift import (
    assign_sides,
    estimate_scales,
    lift,
    torso_width_ratio,
    yaw_from_orientation,
)
from vidcap.masks import MaskStack, frames_with_pixels
from vidcap.motion import build_motion, keyframes_by_confidence
from vidcap.proposals import propose_orientation, propose_signs

#: Foreshortening |dZ|/length below which a segment counts as "in the image plane"
#: (a depth annotation is carried forward until the segment next enters it).
NEAR_PLANE = 0.15

#: Chunks per fitting process in ``run``: the fit of each chunk starts as soon as its
#: silhouettes are out, so shorter chunks leave less of the fit to wait for after the
#: last frame is extracted (each chunk after the first costs ``overlap`` extra frames).
_CHUNKS_PER_JOB = 2


def plane_passages(zeta, *, near: float = NEAR_PLANE, window: int = 5) -> np.ndarray:
    """Frames where each segment passes through the image plane.

    A passage is a frame where ``zeta = |dZ| / length`` is below ``near`` and is the
    smallest within ``window`` frames (a run of equal minima, e.g. clamped zeros,
    counts as a whole). Given to :meth:`vidcap.annotations.Annotations.resolve` as
    ``near_plane``, a depth event then holds until its segment next passes through
    the plane, also when the segment never leaves the near-plane zone (a side-view
    walk), where "until it next enters the zone" would hold across a sign change.

    Parameters
    ----------
    zeta : array_like, shape (F, 10)
        Out-of-plane fraction of every segment (:attr:`SignProposal.zeta`).
    near : float
        Only minima below this count.
    window : int
        Frames over which a minimum must be the smallest (odd).

    Returns
    -------
    numpy.ndarray of bool, shape (F, 10)
    """
    from scipy.ndimage import minimum_filter1d

    z = np.asarray(zeta, dtype=float)
    if z.shape[0] == 0:
        return np.zeros(z.shape, bool)
    low = minimum_filter1d(z, size=max(1, int(window)), axis=0, mode="nearest")
    return (z <= low + 1e-12) & (z < near)


@dataclass(frozen=True)
class LiftResult:
    """The 3D stage's output (:func:`lift_pose`).

    Attributes
    ----------
    joints2d : (F, 15, 2) px, body-side named, user joint fixes applied, gaps filled.
    joints3d : (F, 15, 3) m, camera-aligned world (X right, Y up, Z toward camera).
    proposed_signs, signs : (F, 10) int8, proposed and final (user events applied).
    proposed_orientation, orientation : (F,) str.
    yaw : (F,) rad. scale : px per metre, one number or (F,) (the subject's distance
    changes): where the root is. segment_scale : (F,) px per metre the segments were
    read at (:func:`model_scales`), or None (``scale``). clamped : (F, 10) bool;
    excess : (F, 10) how much longer than the model a clamped segment was (0 elsewhere).
    checks : ranked list of (frame, segment) pairs to check (see
        :meth:`vidcap.proposals.SignProposal.checks`).
    margin, zeta : (F, 10) sign confidence and out-of-plane amount.
    """

    joints2d: np.ndarray
    joints3d: np.ndarray
    proposed_signs: np.ndarray
    signs: np.ndarray
    proposed_orientation: np.ndarray
    orientation: np.ndarray
    yaw: np.ndarray
    scale: float | np.ndarray
    clamped: np.ndarray
    checks: list
    margin: np.ndarray
    zeta: np.ndarray
    segment_scale: np.ndarray | None = None
    excess: np.ndarray | None = None


def fill_gaps(joints2d) -> np.ndarray:
    """Linearly interpolate frames with NaN joints (no silhouette), (F, 15, 2).

    Raises
    ------
    VidcapError
        No frame has joints.
    """
    j = np.array(joints2d, float)
    ok = np.isfinite(j).all(axis=(1, 2))
    if not ok.any():
        raise VidcapError("no person was found in any frame")
    if ok.all():
        return j
    t = np.arange(len(j))
    flat = j.reshape(len(j), -1)
    for c in range(flat.shape[1]):  # 30 coordinate series, vectorised over frames
        flat[:, c] = np.interp(t, t[ok], flat[ok, c])
    return flat.reshape(j.shape)


#: What ``view`` (``vidcap convert --view``) accepts: how the camera sees the subject
#: for the whole clip. ``auto`` proposes the orientation per frame; ``side``,
#: ``front`` and ``back`` fix the sector and leave which way the subject faces (image
#: left or right) to the proposal; one of the six labels fixes the orientation.
VIEWS: tuple[str, ...] = ("auto", "side", "front", "back", *ORIENTATIONS)

#: A proposal that reads this share of frames or more both as a side view and as a
#: three-quarter (or front/back) view is reported (see :meth:`ConvertResult.notices`).
MIXED_VIEW = 0.2


def _check_view(view: str) -> None:
    """Raise ValueError unless ``view`` is one of :data:`VIEWS`."""
    if view not in VIEWS:
        raise ValueError(f"unknown view {view!r}; expected one of {list(VIEWS)}")


def constrain_orientation(labels, view: str = "auto") -> np.ndarray:
    """The orientation labels within what the user said of the view.

    Parameters
    ----------
    labels : array_like of str, shape (F,)
        Proposed labels (:data:`vidcap.body.ORIENTATIONS`).
    view : str
        One of :data:`VIEWS`. ``side`` keeps each label's facing (``front_right``
        becomes ``right``), ``front``/``back`` put it in that half (``right`` becomes
        ``front_right``), a label replaces every frame's.

    Returns
    -------
    numpy.ndarray of str, shape (F,)

    Raises
    ------
    ValueError
        ``view`` is not one of :data:`VIEWS`.
    """
    labels = np.asarray(labels).astype(str)
    _check_view(view)
    if view == "auto":
        return labels
    if view in ORIENTATIONS:
        return np.full(labels.shape, view)
    facing = np.where(np.char.endswith(labels, "left"), "left", "right")
    return facing if view == "side" else np.char.add(f"{view}_", facing)


def apply_user_view(joints2d, proposed_orientation, spread, user_orientation, user_joints,
                    *, image_sides: bool = True, user_sides=None):
    """Orientation, yaw and side-named 2D joints once the user's events are applied.

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, 2)
        Gap-filled 2D joints, pixels.
    proposed_orientation : array_like of str, shape (F,)
        The automatic orientation proposal.
    spread : array_like, shape (F,)
        Torso horizontal foreshortening (0 side view, 1 front view).
    user_orientation : array_like of str, shape (F,)
        The user's orientation per frame, ``""`` where none.
    user_joints : numpy.ndarray, shape (F, 15, 2)
        The user's joint positions, NaN where none.
    image_sides : bool
        ``joints2d`` names limbs by image side (the 2D fitter's naming).
    user_sides : array_like of bool, shape (F, 2), optional
        :meth:`vidcap.annotations.Annotations.sides`: frames where the user swapped
        the arms' (column 0) or legs' (column 1) left and right.

    Returns
    -------
    orientation : numpy.ndarray of str, shape (F,)
    yaw : numpy.ndarray, shape (F,), radians
    joints2d : numpy.ndarray, shape (F, 15, 2)
        Named by the body's true sides, with the user's joints in place.
    """
    orientation = np.where(user_orientation != "", user_orientation,
                           proposed_orientation).astype(str)
    yaw = yaw_from_orientation(orientation, spread)
    j2 = assign_sides(joints2d, yaw) if image_sides else joints2d
    if user_sides is not None:
        j2 = swap_pairs(j2, user_sides)
    j2 = np.where(np.isfinite(user_joints), user_joints, j2)
    return orientation, yaw, j2


def swap_pairs(joints2d, swapped) -> np.ndarray:
    """Exchange the left and right arms and/or legs where ``swapped`` says so.

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, D)
    swapped : array_like of bool, shape (F, 2)
        Per frame: swap the arms (column 0), the legs (column 1)
        (:data:`vidcap.annotations.PAIRS`).

    Returns
    -------
    numpy.ndarray, shape (F, 15, D)
        A copy.
    """
    j = np.array(joints2d, dtype=float)
    sw = np.asarray(swapped, dtype=bool)
    if sw.shape != (len(j), len(PAIRS)):
        raise ValueError(f"swapped must be ({len(j)}, {len(PAIRS)}), got {sw.shape}")
    for col, pair in enumerate(PAIRS):
        left, right = LIMB_PAIR_JOINTS[pair]
        rows = np.flatnonzero(sw[:, col])
        j[np.ix_(rows, left + right)] = j[np.ix_(rows, right + left)]
    return j


#: Knot spacing (seconds) of the per-frame scale (:func:`vidcap.lift.estimate_scales`).
SCALE_WINDOW_S = 3.0


def frame_scales(joints2d, fps: float, body: BodyModel | None = None, *,
                 window_s: float = SCALE_WINDOW_S):
    """:func:`vidcap.lift.estimate_scales` with its window in seconds: pixels per metre,
    one number or (F,) for gap-filled (F, 15, 2) joints."""
    return estimate_scales(joints2d, body, window=max(3, int(round(window_s * fps)) | 1))


def model_scales(model_height, n_frames: int, body: BodyModel | None = None):
    """Pixels per metre at which the 2D fit drew its model in each frame.

    The fitter scales its model to each frame's silhouette (seed 004 section 4.2),
    and a walker's silhouette is a few per cent shorter with the feet apart than in
    mid-stance, so every drawn segment is that much shorter there. Read against one
    scale for the clip, Eq. 2.2 turns that into depth in every segment (sqrt(1 -
    0.96^2) = 0.28 of its length); read against the frame's own model scale, a
    segment's ratio is the foreshortening the fit found.

    Parameters
    ----------
    model_height : array_like, shape (F,), or None
        :attr:`vidcap.fit.pose2d.Pose2D.model_height`: body height in pixels per
        frame, NaN where there was no fit (interpolated here).
    n_frames : int
    body : BodyModel, optional
        The subject (its height in metres).

    Returns
    -------
    numpy.ndarray, shape (F,), or None
        None when ``model_height`` is None or has no usable value.
    """
    if model_height is None:
        return None
    body = body or BodyModel()
    h = np.asarray(model_height, dtype=float).reshape(-1)
    if h.shape != (n_frames,):
        raise ValueError(f"model_height must be ({n_frames},), got shape {h.shape}")
    ok = np.isfinite(h) & (h > 0)
    if not ok.any():
        return None
    t = np.arange(n_frames)
    return np.interp(t, t[ok], h[ok]) / body.height


def lift_pose(
    joints2d,
    *,
    fps: float,
    body: BodyModel | None = None,
    annotations: Annotations | None = None,
    image_sides: bool = True,
    spread=None,
    track=None,
    smooth_2d: float = 0.0,
    yaw_window_s: float = 1.0,
    scale_window_s: float = SCALE_WINDOW_S,
    frame_size: tuple[int, int] | None = None,
    model_height=None,
    view: str = "auto",
) -> LiftResult:
    """The 3D stage: orientation, sides, depth signs (proposed + user) and lifting.

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        2D joints in pixels; NaN frames are interpolated.
    fps : float
    body : BodyModel, optional
    annotations : Annotations, optional
        User events (orientation, depth, joint positions), true-side names.
    image_sides : bool
        ``l_*`` means the image's left limb (the 2D fitter's naming) rather than the
        body's left (ground truth).
    spread : array_like, shape (F,), optional
        Torso horizontal foreshortening (0 side view, 1 front view), e.g.
        :attr:`vidcap.fit.pose2d.Pose2D.spread`; default from the 2D shoulders/hips.
    track : array_like, shape (F,), optional
        Horizontal image position of the subject (walking direction).
    smooth_2d : float
        Gaussian smoothing of the 2D joints over time before lifting, in frames
        (0 = none): Eq. 2.2 amplifies image noise where a segment is nearly in plane.
    yaw_window_s : float
        Running-median window (seconds) of the torso's horizontal foreshortening.
    scale_window_s : float
        Window (seconds) of the per-frame scale (:func:`vidcap.lift.estimate_scales`).
    frame_size : (int, int), optional
        (width, height) of the frames in pixels: their centre is the camera's axis
        when the scale changes per frame.
    model_height : array_like, shape (F,), optional
        The height in pixels the 2D model was drawn at per frame
        (:attr:`vidcap.fit.pose2d.Pose2D.model_height`): segments are then read at
        that frame's scale (:func:`model_scales`), the root at the clip's.
    view : str
        What the user said of the view for the whole clip (:data:`VIEWS`), applied to
        the proposed orientation (:func:`constrain_orientation`); the annotations'
        orientation events still override it from their frames.

    Returns
    -------
    LiftResult
    """
    body = body or BodyModel()
    annotations = annotations or Annotations()
    j2 = fill_gaps(joints2d)
    F = len(j2)
    # one scale, or one per frame when the subject's distance changes (weak perspective)
    scale = frame_scales(j2, fps, body, window_s=scale_window_s)
    seg_scale = model_scales(model_height, F, body)
    geometry = scale if seg_scale is None else seg_scale  # what segments are read at
    if smooth_2d > 0 and F > 2:
        j2 = gaussian_filter1d(j2, smooth_2d, axis=0, mode="nearest")
    if spread is None:
        rho = torso_width_ratio(j2, geometry, body)
    else:
        rho = np.asarray(spread, float)
        rho = np.where(np.isfinite(rho), rho, torso_width_ratio(j2, geometry, body))
    # the body turns slowly: a running median over ~1 s removes single-frame misfits
    rho = median_filter(rho, size=max(1, int(round(yaw_window_s * fps)) | 1), mode="nearest")
    proposed_orient = propose_orientation(j2, scale=geometry, fps=fps, body=body,
                                          sides_known=not image_sides, track=track,
                                          window_s=yaw_window_s, turn_window_s=yaw_window_s)
    proposed_orient = constrain_orientation(proposed_orient, view)
    _, user_orient, user_joints = annotations.resolve(F)
    orient, yaw, j2 = apply_user_view(j2, proposed_orient, rho, user_orient, user_joints,
                                      image_sides=image_sides,
                                      user_sides=annotations.sides(F))
    free = propose_signs(j2, yaw, scale=geometry, body=body)
    user_signs, _, _ = annotations.resolve(F, near_plane=plane_passages(free.zeta))
    final = propose_signs(j2, yaw, scale=geometry, body=body, fixed=user_signs) \
        if (user_signs != 0).any() else free
    centre = None if frame_size is None else (0.5 * frame_size[0], 0.5 * frame_size[1])
    out = lift(j2, final.signs, yaw, body=body, scale=scale, principal_point=centre,
               segment_scale=seg_scale)
    return LiftResult(
        joints2d=j2, joints3d=out.joints3d, proposed_signs=free.signs, signs=final.signs,
        proposed_orientation=proposed_orient, orientation=orient, yaw=yaw, scale=scale,
        clamped=out.clamped, checks=final.checks(body), margin=final.margin, zeta=final.zeta,
        segment_scale=seg_scale, excess=out.excess,
    )


# --------------------------------------------------------------------------- caching
def _video_identity(video: Path) -> dict:
    st = video.stat()
    return {"path": str(video.resolve()), "size": st.st_size, "mtime_ns": st.st_mtime_ns}


#: Median 2D-fit similarity (Eq. 3.1) below which a result is reported as a poor fit.
POOR_FIT = 0.5
#: Bumped when the silhouette stage's results change for the same video and options
#: (2: no shadow test on grey video; 3: the person followed, not the largest blob), so
#: caches written by older versions are redone.
_SILHOUETTE_VERSION = 3


def _key(*parts) -> str:
    text = json.dumps(parts, sort_keys=True, default=str)
    return hashlib.sha1(text.encode()).hexdigest()[:16]


class StageCache:
    """``.npz`` stage results in a folder, keyed by parameters (or disabled: ``None``)."""

    def __init__(self, folder: str | os.PathLike | None):
        self.folder = None if folder is None else Path(folder)

    def path(self, stage: str, key: str) -> Path | None:
        return None if self.folder is None else self.folder / f"{stage}-{key}.npz"

    def load(self, stage: str, key: str) -> dict | None:
        p = self.path(stage, key)
        if p is None or not p.exists():
            return None
        try:
            with np.load(p, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError):  # a damaged cache entry is just redone
            return None

    def save(self, stage: str, key: str, **arrays) -> None:
        p = self.path(stage, key)
        if p is not None:
            savez_atomic(p, **arrays)


# --------------------------------------------------------------------------- the run
@dataclass
class ConvertResult:
    """Everything :func:`run` computed (arrays as in ``vidcap convert --save``)."""

    video: str
    fps: float
    masks: MaskStack
    bbox: np.ndarray
    scores: np.ndarray
    similarity: np.ndarray
    lifted: LiftResult
    motion: object
    jitter_before: float
    jitter_after: float
    timings: dict = field(default_factory=dict)
    #: The 2D stage's own joints (F, 15, 2): image-side limb names, NaN where no fit.
    image_joints2d: np.ndarray | None = None
    #: Torso spread per frame from the 2D stage (0 = side view, 1 = front view), (F,).
    spread: np.ndarray | None = None
    #: Horizontal centre of the person per frame in pixels, gaps interpolated, (F,).
    track: np.ndarray | None = None
    #: Body height in pixels the 2D model was drawn at per frame (NaN: no fit), (F,).
    model_height: np.ndarray | None = None
    #: Frames left out as mostly outside the image (:func:`partly_outside`), (F,) bool;
    #: their ``image_joints2d`` are NaN.
    outside: np.ndarray | None = None
    #: What the user said of the view (:data:`VIEWS`).
    view: str = "auto"
    #: When each frame was shown, seconds from the first (the container's timestamps),
    #: (F,); None where the container keeps none.
    frame_times: np.ndarray | None = None

    @property
    def n_frames(self) -> int:
        return len(self.masks)

    @property
    def variable_rate(self) -> bool:
        """Whether the video's frames are unevenly spaced in time
        (:func:`vidcap.video.variable_rate`: a phone's variable frame rate, dropped
        frames)."""
        from vidcap.video import variable_rate

        t = self.frame_times
        return t is not None and len(t) == self.n_frames and variable_rate(t, self.fps)

    @functools.cached_property
    def bvh_motion(self):
        """The motion the BVH gets: :attr:`motion` (one frame per video frame), or, for
        a variable-rate video, :attr:`motion` resampled evenly over the frames' own
        times at the rate of their median interval (the camera's rate when it dropped
        frames, not the lower average), so the BVH plays in step with the video."""
        if not self.variable_rate:
            return self.motion
        rate = 1.0 / float(np.median(np.diff(self.frame_times)))
        return self.motion.resampled(rate, times=self.frame_times)

    def notices(self) -> list[str]:
        """What the user should know about this result, one sentence each: frames
        without a person, frames left out as mostly outside the picture, and a body
        model that fits the silhouettes poorly overall (median similarity below
        :data:`POOR_FIT`: a person gives 0.7-0.9, a moving box 0.36)."""
        out = []
        n = self.n_frames
        j2 = self.image_joints2d
        missing = (np.zeros(n, bool) if j2 is None
                   else ~np.isfinite(j2).all(axis=(1, 2)))
        outside = (np.zeros(n, bool) if self.outside is None
                   else np.asarray(self.outside, bool))
        if outside.any():
            out.append(f"person mostly outside the picture in {int(outside.sum())} frames "
                       f"({frame_runs(outside)}): left out like frames without a person")
        missing &= ~outside
        if missing.any():
            out.append(f"no person in {int(missing.sum())} of {len(missing)} frames "
                       f"({frame_runs(missing)}): poses interpolated across them, held "
                       "at the ends")
        s = np.asarray(self.similarity, float)[~missing & ~outside]
        s = s[np.isfinite(s)]
        if s.size and np.median(s) < POOR_FIT:
            out.append(f"the body model fits the silhouettes poorly (median similarity "
                       f"{np.median(s):.2f}; one whole person gives 0.7-0.9): is it one "
                       "person, seen whole, in front of a background with nothing else "
                       "moving?")
        if self.variable_rate:
            gaps = np.diff(self.frame_times) * 1e3
            out.append(f"variable frame rate (frames {gaps.min():.0f}-{gaps.max():.0f} ms "
                       f"apart): the BVH is resampled evenly at {self.bvh_motion.fps:.3g} "
                       f"fps ({self.bvh_motion.n_frames} frames for the video's {n}), so it "
                       "keeps time with the video")
        side = np.isin(np.asarray(self.lifted.proposed_orientation).astype(str),
                       ("left", "right"))
        if self.view == "auto" and n and min(side.mean(), 1.0 - side.mean()) >= MIXED_VIEW:
            # the side/three-quarter call rests on how far apart the fit sets the
            # shoulders and hips, which a real silhouette pins down poorly (ido_walk fits
            # better read from the front in 67 % of its frames, RESULTS): say so where
            # the proposal wavers between the two
            out.append(f"the view was read as a side view in {int(side.sum())} frames and as "
                       f"three-quarter or front/back in {int((~side).sum())} (from how far "
                       "apart the shoulders and hips fit, which real bodies and clothes "
                       "blur): if the camera sees the subject from one side throughout, "
                       "pass --view side (or --view front / --view back)")
        return out

    def save_npz(self, path: str | os.PathLike) -> None:
        """Write the ``--save`` arrays atomically."""
        lr = self.lifted
        savez_atomic(
            path,
            masks=self.masks, joint_names=np.array(JOINT_NAMES),
            segment_names=np.array(SEGMENT_NAMES), joints2d=lr.joints2d,
            joints3d=lr.joints3d, proposed_signs=lr.proposed_signs, signs=lr.signs,
            proposed_orientation=lr.proposed_orientation.astype(str),
            orientation=lr.orientation.astype(str), yaw=lr.yaw,
            scale=np.asarray(lr.scale, dtype=np.float64),
            scores=self.scores, similarity=self.similarity, clamped=lr.clamped,
            margin=np.minimum(lr.margin, 1e6), zeta=lr.zeta, fps=np.float64(self.fps),
            check_frame=np.array([c["frame"] for c in lr.checks], dtype=int),
            check_segment=np.array([c["segment"] for c in lr.checks], dtype="U16"),
            check_sign=np.array([c["sign"] for c in lr.checks], dtype=int),
            check_priority=np.array([c["priority"] for c in lr.checks], dtype=float),
            bvh_joints3d=self.motion.positions(),
            outside=(np.zeros(self.n_frames, bool) if self.outside is None
                     else np.asarray(self.outside, bool)),
            frame_times=(np.arange(self.n_frames) / self.fps if self.frame_times is None
                         else np.asarray(self.frame_times, dtype=np.float64)),
        )


def run(
    video: str | os.PathLike,
    *,
    annotations: str | os.PathLike | Annotations | None = None,
    background: str | os.PathLike | None = None,
    height: float = 1.75,
    smooth_sigma: float = 1.0,
    keyframe_score: float | None = None,
    cache_dir: str | os.PathLike | None = None,
    progress: bool | None = None,
    log=None,
    jobs: int | None = None,
    view: str = "auto",
) -> ConvertResult:
    """Run the whole video path on ``video``.

    Parameters
    ----------
    video : str or path-like
    annotations : path or Annotations, optional
        Default: ``VIDEO_STEM.vidcap.json`` beside the video when it exists.
    background : path, optional
        A background plate image; default: estimated from the video.
    height : float
        Subject's height in metres.
    smooth_sigma : float
        Gaussian smoothing of the motion in frames (0 = none).
    keyframe_score : float, optional
        Key only the frames whose 2D fit similarity is at least this (plus enough
        frames to leave no gap over 10 frames) and Slerp between them (seed 004
        section 3.1.5 keys the poses); default: every frame is a key.
    cache_dir : path, optional
        Stage cache folder (None = no caching).
    progress : bool, optional
        Progress bars (default: when stderr is a terminal).
    log : callable, optional
        Called with one-line status messages.
    jobs : int, optional
        Worker processes for the 2D fit (default: the usable CPUs, at most
        :data:`vidcap.fit.parallel.MAX_JOBS`); 1 fits in this process. Clips of
        fewer than 120 frames are fitted in this process anyway
        (:func:`vidcap.fit.parallel.fit_sequence_chunked`). The workers start, and
        load the fit's compiled kernels, while the silhouettes are extracted.
    view : str
        How the camera sees the subject for the whole clip (:data:`VIEWS`; default
        ``auto``: proposed per frame); see :func:`constrain_orientation`.

    Returns
    -------
    ConvertResult
    """
    from vidcap.background import estimate_background, load_plate
    from vidcap.fileio import progress as bar
    from vidcap.fit.parallel import (
        FitPool,
        StreamedFit,
        chunk_bounds,
        default_jobs,
        fit_sequence_chunked,
    )
    from vidcap.silhouette import extract_silhouettes
    from vidcap.video import frame_times, probe

    log = log or (lambda msg: None)
    _check_view(view)  # before any work
    video = Path(video)
    info = probe(video)
    body = BodyModel(height=height)
    cache = StageCache(cache_dir)
    timings = {}

    if annotations is None and default_path(video).exists():
        annotations = default_path(video)
    ann_source = video
    if isinstance(annotations, (str, os.PathLike)):
        log(f"annotations: {annotations}")
        ann_source = annotations
        annotations = Annotations.load(annotations)  # frames are checked once decoded
    ann = annotations or Annotations()

    # a given plate is read first: a bad file is reported before any worker starts
    t0 = time.perf_counter()
    plate_model = load_plate(background) if background is not None else None
    t_plate = time.perf_counter() - t0
    ident = _video_identity(video)
    k_plate = (_key("plate-file", _video_identity(Path(background))) if background is not None
               else _key("plate", ident))
    k_sil = _key("silhouettes", _SILHOUETTE_VERSION, ident, k_plate)
    jobs = default_jobs() if jobs is None else max(1, int(jobs))
    # the 2D fit's worker processes start first and load their compiled kernels while
    # this process estimates the plate and extracts the silhouettes (unless the fit is
    # cached or serial)
    per_job = _CHUNKS_PER_JOB if jobs > 1 else 1  # jobs=1: fitted here, one chunk
    expected = chunk_bounds(info.n_frames or 0, jobs, per_job=per_job)
    pose_path = cache.path("pose2d", _key("pose2d", k_sil, expected))
    pool = (FitPool(min(jobs, len(expected)))
            if len(expected) > 1 and not (pose_path and pose_path.exists()) else None)
    try:
        # 1. background plate
        t0 = time.perf_counter()
        if plate_model is None:
            hit = cache.load("plate", k_plate)
            if hit is None:
                log("estimating the background plate")
                plate_model = estimate_background(video, rng=np.random.default_rng(0),
                                                  progress=progress)
                cache.save("plate", k_plate, plate=plate_model.plate)
            else:
                from vidcap.background import BackgroundModel

                plate_model = BackgroundModel.from_plate(hit["plate"])
        timings["plate"] = t_plate + time.perf_counter() - t0

        # 2. silhouettes
        t0 = time.perf_counter()
        hit = cache.load("silhouettes", k_sil)
        if hit is not None and "mask_boxes" not in hit:
            hit = None  # written before the masks were stored cropped: extract again
        # each chunk of frames is fitted as soon as its silhouettes are there
        streamed = (StreamedFit(pool, info.n_frames or 0, jobs=jobs, per_job=per_job)
                    if pool is not None else None)
        so_far = None  # MaskStack of the frames so far

        def arrived(_start, chunk_masks):
            nonlocal so_far
            if so_far is None:
                so_far = MaskStack(chunk_masks.frame_shape)
            so_far.extend(chunk_masks)
            streamed.feed(so_far)

        if hit is None:
            sil = extract_silhouettes(video, plate_model, progress=progress,
                                      on_masks=None if streamed is None else arrived)
            masks, bbox, n_other = sil.masks, sil.bbox, sil.n_other_blobs
            cache.save("silhouettes", k_sil, bbox=bbox, n_other=n_other, **masks.to_arrays())
        else:
            masks = MaskStack.from_arrays(hit["mask_shape"], hit["mask_boxes"],
                                          hit["mask_bits"], hit["mask_sizes"])
            bbox = hit["bbox"]
            n_other = hit["n_other"] if "n_other" in hit else np.zeros(len(masks), np.int64)
        timings["silhouettes"] = time.perf_counter() - t0
        crowded = int(np.count_nonzero(n_other))
        if crowded >= max(3, 0.05 * len(masks)):
            # vidcap follows one person: say so rather than silently mixing people (an
            # extra blob in a frame or two is a plate artefact, not a person, and is not
            # told)
            log(f"more than one person-sized blob in {crowded} of {len(masks)} frames "
                f"(up to {int(n_other.max()) + 1} at once); one is followed from frame to frame "
                "(the largest at first)")
        if len(masks) != info.n_frames and info.n_frames:
            log(f"decoded {len(masks)} frames (container says {info.n_frames})")

        # 3. 2D pose
        t0 = time.perf_counter()
        # chunked fits may differ from a serial one (rarely, see fit.parallel): keyed apart
        chunks = chunk_bounds(len(masks), jobs, per_job=per_job)
        k_pose = _key("pose2d", k_sil) if len(chunks) < 2 else _key("pose2d", k_sil, chunks)
        hit = cache.load("pose2d", k_pose)
        if hit is not None and "model_height" not in hit:
            hit = None  # written before the model's height was kept: fit again
        if hit is None:
            def wrap(it, total):
                return bar(it, total=total, desc="2D pose", unit="frame", enabled=progress)

            if streamed is not None:
                # this process only waits for the workers now: meanwhile, load what
                # the lift needs (a core is free while the last chunk is fitted)
                _preload_lift()
                pose = streamed.finish(masks, progress=wrap)
            else:
                pose = fit_sequence_chunked(masks, jobs=jobs, progress=wrap, per_job=per_job)
            hit = {"joints2d": pose.joints2d, "scores": pose.scores, "spread": pose.spread,
                   "similarity": pose.similarity, "model_height": pose.model_height}
            cache.save("pose2d", k_pose, **hit)
        timings["pose2d"] = time.perf_counter() - t0
    finally:
        if pool is not None:
            pool.close()

    # 4. 3D lift and 5. motion
    t0 = time.perf_counter()
    outside = partly_outside(masks)
    joints2d, model_height = hit["joints2d"], hit["model_height"]
    if outside.any():  # filled from the neighbouring frames, like frames without a fit
        joints2d, model_height = joints2d.copy(), np.array(model_height, float)
        joints2d[outside] = np.nan
        model_height[outside] = np.nan
    track = person_track(bbox, masks, exclude=outside)
    _check_events(ann, len(masks), ann_source)
    lifted = lift_pose(joints2d, fps=info.fps, body=body, annotations=ann,
                       image_sides=True, spread=hit["spread"], track=track,
                       frame_size=(info.width, info.height),
                       model_height=model_height, view=view)
    keys = None
    if keyframe_score is not None:
        keys = keyframes_by_confidence(hit["similarity"], min_score=keyframe_score)
        log(f"{len(keys)} keyframes of {len(masks)}")
    mres = build_motion(lifted.joints3d, info.fps, body=body, smooth_sigma=smooth_sigma,
                        keys=keys)
    timings["lift+motion"] = time.perf_counter() - t0
    return ConvertResult(
        video=str(video), fps=info.fps, masks=masks, bbox=np.asarray(bbox),
        scores=hit["scores"], similarity=hit["similarity"], lifted=lifted,
        motion=mres.motion, jitter_before=mres.jitter_before,
        jitter_after=mres.jitter_after, timings=timings,
        image_joints2d=joints2d, spread=hit["spread"], track=track,
        model_height=model_height, outside=outside, view=view,
        frame_times=frame_times(video),
    )


def _preload_lift() -> None:
    """Import ``scipy.optimize`` (for :func:`vidcap.lift.estimate_scales`, ~0.2 s once
    per process) on a daemon thread; an import error is left to the lift to report.

    Only once this process forks no more workers: a fork must not copy a thread
    midway through an import.
    """
    def load():
        try:
            import scipy.optimize  # noqa: F401
        except Exception:  # noqa: BLE001 - the lift itself reports it
            pass

    threading.Thread(target=load, name="vidcap-preload", daemon=True).start()


def true_runs(flags) -> list[tuple[int, int]]:
    """The runs of True in ``flags`` (F,) as (first, last) frame pairs."""
    f = np.r_[False, np.asarray(flags, bool), False].astype(int)
    starts, stops = np.flatnonzero(np.diff(f) == 1), np.flatnonzero(np.diff(f) == -1) - 1
    return [(int(a), int(b)) for a, b in zip(starts, stops, strict=True)]


def frame_runs(flags, limit: int = 4) -> str:
    """``'0-14, 30-37'``: the runs of True in ``flags`` (F,), the first ``limit``."""
    parts = [f"{a}" if a == b else f"{a}-{b}" for a, b in true_runs(flags)]
    return ", ".join(parts[:limit]) + (", ..." if len(parts) > limit else "")


def partly_outside(masks, *, min_share: float = 0.7, min_reference: int = 5) -> np.ndarray:
    """Frames where much of the person is outside the image, (F,) bool.

    A silhouette that reaches the image's border and covers less than ``min_share``
    of the person's usual area (the median over the frames that do not reach it) is
    a person walking out of (or into) the picture. The 2D model fitted to what is
    left of them is mostly guesswork (a synthetic walk leaving the frame: 2D error
    6-81 % of the body's height in those frames, against 1-2 % before), so the
    pipeline fills such frames from their neighbours, as frames without a person.
    Gait moves the area by about 15 %; a person cut for the whole clip (feet below
    the frame) has no reference and nothing is dropped.

    Parameters
    ----------
    masks : MaskStack or numpy.ndarray, shape (F, H, W) bool
    min_share : float
        Share of the usual area below which a border-touching frame is dropped.
    min_reference : int
        Fewest frames clear of the border that make a usable reference area.

    Returns
    -------
    numpy.ndarray of bool, shape (F,)
    """
    from vidcap.masks import pixel_counts, touches_border

    area = pixel_counts(masks)
    edge = touches_border(masks)
    clear = (area > 0) & ~edge
    if clear.sum() < min_reference:
        return np.zeros(len(area), bool)
    return edge & (area < min_share * np.median(area[clear]))


def person_track(bbox, masks, *, exclude=None) -> np.ndarray | None:
    """Horizontal centre of the person's box per frame, gaps interpolated.

    Parameters
    ----------
    bbox : array_like, shape (F, 4)
        ``x0, y0, x1, y1`` per frame (pixels).
    masks : MaskStack or numpy.ndarray, shape (F, H, W) bool
        Frames with an empty mask count as gaps.
    exclude : array_like of bool, shape (F,), optional
        More frames to treat as gaps (:func:`partly_outside`).

    Returns
    -------
    numpy.ndarray, shape (F,), or None
        Pixels; None when no frame shows the person or ``bbox`` is malformed.
    """
    bb = np.asarray(bbox, float)
    if bb.ndim != 2 or bb.shape[1] != 4:
        return None
    seen = frames_with_pixels(masks)
    if exclude is not None:
        seen = seen & ~np.asarray(exclude, bool)
    track = np.where(seen, 0.5 * (bb[:, 0] + bb[:, 2]), np.nan)
    ok = np.isfinite(track)
    if not ok.any():
        return None
    t = np.arange(len(track))
    return np.interp(t, t[ok], track[ok])


def _check_events(ann: Annotations, n_frames: int, source) -> None:
    late = [e for e in ann.events if e.frame >= n_frames]
    if late:
        e = late[0]
        raise AnnotationError(
            f"{e.type} event at frame {e.frame} is beyond the video's {n_frames} frames "
            f"(frames count from 0)", source)


def convert(
    video: str | os.PathLike,
    out_bvh: str | os.PathLike,
    *,
    save: str | os.PathLike | None = None,
    cache_dir: str | os.PathLike | None | bool = True,
    **options,
) -> ConvertResult:
    """:func:`run` and write the BVH (atomically) and optionally the ``--save`` npz.

    ``cache_dir=True`` puts the cache in ``.vidcap-cache`` beside ``out_bvh``;
    ``False``/``None`` disables it.
    """
    from vidcap.bvh import write_bvh

    out_bvh = Path(out_bvh)
    if cache_dir is True:
        cache_dir = out_bvh.parent / ".vidcap-cache"
    elif cache_dir is False:
        cache_dir = None
    result = run(video, cache_dir=cache_dir, **options)
    write_bvh(out_bvh, result.bvh_motion)
    if save is not None:
        result.save_npz(save)
    return result


__all__ = ["VIEWS", "ConvertResult", "LiftResult", "StageCache", "constrain_orientation",
           "convert", "fill_gaps", "frame_scales", "lift_pose", "run"]
