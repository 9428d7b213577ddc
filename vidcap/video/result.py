"""What a conversion computed (:class:`ConvertResult`, returned by
:func:`vidcap.video.pipeline.run`): the stages' arrays, the motion, what the user should be
told (:meth:`ConvertResult.notices`) and the ``vidcap convert --save`` file."""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass, field

import numpy as np

from vidcap.body import JOINT_NAMES, SEGMENT_NAMES
from vidcap.fileio import savez_atomic
from vidcap.video.lifting import LiftResult
from vidcap.video.masks import MaskStack, edges_reached

#: Median 2D-fit similarity (Eq. 3.1) below which a result is reported as a poor fit.
POOR_FIT = 0.5
#: Share of the frames without a person above which, with an estimated plate, the user is
#: told a still person may have been taken into it (issue 26, Build 6: dancers holding a
#: pose for 3 s left 23 of 90 frames without a person and the rest fitted at S 0.36).
MISSING_HINT = 0.2

#: A proposal that reads this share of frames or more both as a side view and as a
#: three-quarter (or front/back) view is reported (see :meth:`ConvertResult.notices`).
MIXED_VIEW = 0.2

#: Share of the frames with a person whose silhouette reaches one edge of the picture
#: from which the user is told the body is cut off there (a person filmed from the
#: thighs up by a webcam, feet below a tripod's frame): the 2D model is a whole body
#: scaled to the silhouette's height, so what is out of view makes the fit a guess.
CUT_SHARE = 0.1
#: What an edge of the picture cuts off.
_CUT_PARTS = {"bottom": "the feet or legs", "top": "the head", "left": "a side of the body",
              "right": "a side of the body"}

@dataclass
class ConvertResult:
    """Everything :func:`vidcap.video.pipeline.run` computed.

    Arrays as in ``vidcap convert --save``.
    """

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
    #: Frames left out as mostly outside the image
    #: (:func:`vidcap.video.person.partly_outside`), (F,) bool; their ``image_joints2d`` are NaN.
    outside: np.ndarray | None = None
    #: What the user said of the view (:data:`vidcap.video.lifting.VIEWS`).
    view: str = "auto"
    #: When each frame was shown, seconds from the first (the container's timestamps),
    #: (F,); None where the container keeps none.
    frame_times: np.ndarray | None = None
    #: The body the 2D fit, the lift and the motion used (``--height`` tall); None: the
    #: seed's proportions at 1.75 m.
    body: object = None
    #: The subject's proportions as estimated from the clip
    #: (:class:`vidcap.video.fit.proportions.ProportionEstimate`; None: the seed's used).
    proportions: object = None
    #: The plate was estimated from the clip (no ``--background`` given).
    plate_estimated: bool = True
    #: The camera's perspective k and the body's ankle share (``above_feet``) the fit drew
    #: with; the 3D stage read the joints un-warped by them
    #: (:func:`vidcap.video.flatview.flat_view`). ``(0.0, 1.0)``: a level camera.
    perspective: tuple[float, float] = (0.0, 1.0)

    @property
    def n_frames(self) -> int:
        return len(self.masks)

    @property
    def variable_rate(self) -> bool:
        """Whether the video's frames are unevenly spaced in time
        (:func:`vidcap.io.video.variable_rate`: a phone's variable frame rate, dropped
        frames)."""
        from vidcap.io.video import variable_rate

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

    def motion_and_times(self, path: str | os.PathLike) -> tuple[object, np.ndarray | None]:
        """The motion a file at ``path`` gets and its frame times: glTF keeps every
        frame at the video's own times (:attr:`motion`, :attr:`frame_times` for a
        variable-rate video), BVH's fixed frame time needs :attr:`bvh_motion`."""
        from vidcap.io.motionfile import is_gltf

        if not is_gltf(path):
            return self.bvh_motion, None
        return self.motion, (np.asarray(self.frame_times, float) if self.variable_rate
                             else None)

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
        cut = cut_notice(self.masks, ~missing & ~outside)
        if cut:
            out.append(cut)
        s = np.asarray(self.similarity, float)[~missing & ~outside]
        s = s[np.isfinite(s)]
        poor = bool(s.size) and np.median(s) < POOR_FIT
        if poor:
            out.append(f"the body model fits the silhouettes poorly (median similarity "
                       f"{np.median(s):.2f}; one whole person gives 0.7-0.9): is it one "
                       "person, seen whole, in front of a background with nothing else "
                       "moving?")
        still = None
        if self.plate_estimated:
            from vidcap.video.stillcheck import still_warning

            still = still_warning(self.bbox, self.masks.shape[1:])
        if still:
            out.insert(0, still)  # (first: the rest follows from it)
        elif self.plate_estimated and (poor or (n and missing.sum() > MISSING_HINT * n)):
            # the plate is estimated from the clip itself: whatever stands still in most
            # of it (a person holding a pose) is taken for the scene, and the silhouettes
            # then miss it without any sign in the plate
            out.append("a person who keeps still for much of the clip can be taken into the "
                       "background estimated from it: if the silhouettes (vidcap review) "
                       "miss them, give a photo of the empty scene with --background "
                       "plate.png")
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
            **self._body_arrays(),
        )

    def _body_arrays(self) -> dict:
        """``body_lengths`` and ``body_widths`` (10,) m, ``body_height`` () m,
        ``body_shoulder_drop`` () m (the shoulder joints below the torso's top corners)
        and ``body_estimated`` () bool (proportions other than the seed's: the subject's
        own or, with ``proportions='human'``, a real adult's)."""
        from vidcap.body import BodyModel

        body = self.body if self.body is not None else BodyModel()
        return {"body_lengths": body.segment_lengths(),
                "body_widths": 2.0 * body.segment_radii(),
                "body_height": np.float64(body.height),
                "body_shoulder_drop": np.float64(body.shoulder_drop),
                "body_estimated": np.bool_(self.proportions is not None)}


def cut_notice(masks, seen) -> str | None:
    """The sentence telling the user the picture's edges cut the person off, or None.

    Parameters
    ----------
    masks : MaskStack or numpy.ndarray, shape (F, H, W) bool
    seen : numpy.ndarray of bool, shape (F,)
        The frames with a fitted person (the others are not counted).

    Returns
    -------
    str or None
        Each edge (bottom, top, left, right) reached in at least :data:`CUT_SHARE` of
        the ``seen`` frames, with its frame count and runs; None when none is.
    """
    seen = np.asarray(seen, bool)
    if not seen.any():
        return None
    reached = edges_reached(masks) & seen[:, None]
    parts, cut_off = [], []
    # bottom first: feet below the frame are the common case
    for i, edge in ((1, "bottom"), (0, "top"), (2, "left"), (3, "right")):
        n = int(reached[:, i].sum())
        if n >= CUT_SHARE * seen.sum():
            parts.append(f"{edge} edge in {n} of {int(seen.sum())} frames "
                         f"({frame_runs(reached[:, i])})")
            if _CUT_PARTS[edge] not in cut_off:
                cut_off.append(_CUT_PARTS[edge])
    if not parts:
        return None
    return (f"the person reaches the picture's {' and its '.join(parts)}: the picture "
            f"cuts off {' and '.join(cut_off)} there, and the 2D model, a whole body fitted "
            "to what is in view, guesses its scale and the parts it cannot see in those "
            "frames; frame the whole body, head to feet")


def true_runs(flags) -> list[tuple[int, int]]:
    """The runs of True in ``flags`` (F,) as (first, last) frame pairs."""
    f = np.r_[False, np.asarray(flags, bool), False].astype(int)
    starts, stops = np.flatnonzero(np.diff(f) == 1), np.flatnonzero(np.diff(f) == -1) - 1
    return [(int(a), int(b)) for a, b in zip(starts, stops, strict=True)]


def frame_runs(flags, limit: int = 4) -> str:
    """``'0-14, 30-37'``: the runs of True in ``flags`` (F,), the first ``limit``."""
    parts = [f"{a}" if a == b else f"{a}-{b}" for a, b in true_runs(flags)]
    return ", ".join(parts[:limit]) + (", ..." if len(parts) > limit else "")


__all__ = ["CUT_SHARE", "MIXED_VIEW", "POOR_FIT", "ConvertResult", "cut_notice", "frame_runs",
           "true_runs"]
