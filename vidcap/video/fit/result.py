"""The fit's result types and their file I/O: :class:`FramePose` (one frame) and
:class:`Pose2D` (a clip, ``pose2d.npz``).

During 2D fitting ``l_*`` and ``r_*`` name image-left and image-right limbs, not the
performer's sides (:mod:`vidcap.video.fit.pose2d`, "Left and right").
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from vidcap.body import SEGMENT_NAMES


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
    arm_candidates : dict or None
        With the frame's cues (:mod:`vidcap.video.fit.cues`): per arm label ``'l'``,
        ``'r'``, a few good placements of that arm, ``(elbows (K, 2), wrists (K, 2)
        in original pixels, costs (K,))``, the fitted one first (cost 0), for the
        solve over time (:func:`vidcap.video.fit.temporal.arm_path`); None otherwise.
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
    arm_candidates: dict | None = None


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


__all__ = ["FramePose", "Pose2D"]
