"""The state behind the annotate page: one clip, its cached stage results, the
user's annotations, and the lifted pose, re-lifted after every edit.

The page (:mod:`vidcap.ui.annotate`) only talks to :class:`AnnotateSession`. The session
holds a :class:`ClipData` (the pipeline's heavy, cached stages: frames, silhouettes,
2D fit; built by :func:`load_clip` with :func:`vidcap.video.pipeline.run`) and reruns the
3D stage, :func:`vidcap.video.lifting.lift_pose`, with the user's annotations after every
edit, exactly as ``vidcap convert`` does.
"""

from __future__ import annotations

import inspect
import os
import shutil
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from vidcap.ui.regionedit import RegionEditing

from vidcap.body import (
    JOINT_INDEX,
    JOINT_NAMES,
    ORIENTATIONS,
    SEGMENT_INDEX,
    SEGMENT_NAMES,
    BodyModel,
)
from vidcap.errors import AnnotationError
from vidcap.video.annotations import PAIRS, Annotations
from vidcap.video.flatview import NO_PERSPECTIVE, flat_points, flat_view


@dataclass
class ClipData:
    """The pipeline's results for one clip that the annotate page needs.

    Attributes
    ----------
    video : pathlib.Path
        The video file.
    fps : float
        Frames per second.
    read_frame : callable
        ``read_frame(i) -> (H, W, 3) uint8`` BGR frame ``i``, at the video's size or
        shrunk (same aspect; ``size`` is the video's).
    joints2d : numpy.ndarray, shape (F, 15, 2)
        2D joints as the 2D stage gives them, pixels (x right, y down); NaN in frames
        without a person.
    masks : numpy.ndarray of bool, shape (F, H, W), vidcap.video.masks.MaskStack, or None
        Silhouettes (read one frame at a time, ``masks[f]``).
    fit_score : numpy.ndarray, shape (F,)
        Quality of the 2D fit per frame in [0, 1] (the model/silhouette similarity);
        frames below :attr:`AnnotateSession.low_fit` are flagged; 0 for a frame that
        was not fitted (no person, or mostly outside the picture).
    image_sides : bool
        ``l_*`` in ``joints2d`` is the image's left limb (the 2D fitter's naming); False
        when the joints are named by the body's sides (ground truth).
    spread : numpy.ndarray, shape (F,), optional
        Torso horizontal foreshortening from the 2D fit (see
        :func:`vidcap.video.lifting.lift_pose`).
    track : numpy.ndarray, shape (F,), optional
        Horizontal image position of the subject (walking direction).
    model_height : numpy.ndarray, shape (F,), optional
        Body height in pixels the 2D model was drawn at per frame (see
        :func:`vidcap.video.lifting.model_scales`).
    body : vidcap.body.BodyModel, optional
        The subject (default 1.75 m).
    size : tuple of int
        (width, height) of the frames in pixels (read from frame 0 if not given).
    resegment : callable, optional
        ``resegment(regions, on_masks) -> MaskStack``: the clip's silhouettes again with
        the user's regions (an :class:`vidcap.video.annotations.Annotations` of region
        events; ``on_masks(start, masks)`` after each chunk, for progress). None: the
        page cannot recompute them (the events are still saved for ``vidcap convert``).
    pose : dict, optional
        The 2D fit's arrays (:data:`vidcap.video.refit.POSE_KEYS`) the frames of changed
        silhouettes are refitted from; needed with ``resegment``.
    fit_kw : dict, optional
        The body keywords (``body``, ``foot``) the 2D fit used, for those refits
        (default: the seed's body).
    near_side : numpy.ndarray, shape (F,), optional
        The colour frames' front/back cue (:func:`vidcap.video.frontback.near_side`), as
        ``vidcap convert`` reads it (:func:`vidcap.video.pipeline.colour_cues`); kept as
        loaded when silhouettes are recomputed.
    limb_order : numpy.ndarray, shape (F, 2), optional
        The colour frames' limb order (:func:`vidcap.video.legorder.near_limb`), as
        ``vidcap convert`` reads it (:func:`vidcap.video.pipeline.colour_cues`); kept as
        loaded when silhouettes are recomputed.
    perspective : (float, float)
        The camera's perspective k and the body's ankle share the 2D fit drew with
        (``vidcap annotate --camera``, :attr:`vidcap.video.result.ConvertResult.perspective`);
        the lift reads the fitted and the user's placed joints un-warped by it, as
        ``vidcap convert`` does (:func:`vidcap.video.flatview.flat_view`), and the page
        shows them on the frame. Default: a level camera.
    """

    video: Path
    fps: float
    read_frame: Callable[[int], np.ndarray]
    joints2d: np.ndarray
    masks: np.ndarray | None
    fit_score: np.ndarray
    image_sides: bool = True
    spread: np.ndarray | None = None
    track: np.ndarray | None = None
    model_height: np.ndarray | None = None
    body: BodyModel | None = None
    size: tuple[int, int] = field(default=(0, 0))
    resegment: Callable | None = None
    pose: dict | None = None
    fit_kw: dict = field(default_factory=dict)
    near_side: np.ndarray | None = None
    limb_order: np.ndarray | None = None
    perspective: tuple[float, float] = NO_PERSPECTIVE

    def __post_init__(self):
        self.video = Path(self.video)
        self.joints2d = np.asarray(self.joints2d, dtype=float)
        F = self.joints2d.shape[0]
        if self.joints2d.shape != (F, len(JOINT_NAMES), 2):
            raise ValueError(f"joints2d must be (F, 15, 2), got {self.joints2d.shape}")
        self.fit_score = np.broadcast_to(np.asarray(self.fit_score, float), (F,)).copy()
        self.body = self.body or BodyModel()
        if self.size == (0, 0):
            h, w = self.read_frame(0).shape[:2]
            self.size = (w, h)

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return self.joints2d.shape[0]


#: Frames are shown (and kept for the page) at most this wide: the page sends every
#: frame as a JPEG, and a 4K one is megabytes.
MAX_DISPLAY_WIDTH = 1280


def sign_doubt(margin: np.ndarray, zeta: np.ndarray, body: BodyModel, *,
               tau: float = 0.2) -> np.ndarray:
    """Expected displacement (metres) of each segment's distal joint if its proposed depth
    sign is wrong: ``2 zeta l p_wrong`` with ``p_wrong = 1 / (1 + exp(margin / tau))``, as
    :meth:`vidcap.video.proposals.SignProposal.checks` ranks them. Shapes (F, 10) -> (F, 10)."""
    with np.errstate(over="ignore", invalid="ignore"):
        p_wrong = 1.0 / (1.0 + np.exp(np.minimum(np.asarray(margin) / tau, 700.0)))
    return 2.0 * np.asarray(zeta) * body.segment_lengths() * np.nan_to_num(p_wrong)


def backup_path(path: Path) -> Path:
    """A free ``.bak`` name beside ``path`` (``x.json.bak``, ``x.json.bak1``, ...)."""
    for n in range(1000):
        cand = path.with_name(path.name + (".bak" if n == 0 else f".bak{n}"))
        if not cand.exists():
            return cand
    raise AnnotationError("too many backups beside the annotations file", path)


class AnnotateSession(RegionEditing):
    """One clip being annotated: edits, re-lifting and autosave.

    Parameters
    ----------
    clip : ClipData
        The cached stage results.
    annotations_path : str or path-like
        The annotations JSON (read if it exists; written after every edit).
    low_fit : float
        Fit scores below this mark a frame as needing attention (keyword-only knob).
    low_doubt : float
        A segment's sign is marked doubtful when a wrong sign would move its distal
        joint by more than this (expected value, metres; :func:`sign_doubt`).
    defer_refresh : bool
        If True an edit only resolves the events and re-lifts with the current
        proposals (milliseconds even for long clips) and marks the session
        :attr:`stale`; the caller then runs :meth:`refresh` (e.g. in a worker thread)
        for the full 3D stage, which re-proposes the other signs with the new
        constraints. If False (default) every edit runs the full 3D stage at once.

    Attributes
    ----------
    load_error : str or None
        Why the annotations file could not be read. The file is then copied to
        :attr:`backup` and not written until the user makes an edit.
    joints2d, joints3d, signs, orientation, yaw : numpy.ndarray
        The current result (as :class:`vidcap.video.lifting.LiftResult`): body-side 2D joints
        with the user's fixes (F, 15, 2), 3D joints (F, 15, 3), depth signs (F, 10),
        orientation labels (F,), yaw (F,).
    user_signs, user_orient, user_joints : numpy.ndarray
        The user's events resolved over the clip (see
        :meth:`vidcap.video.annotations.Annotations.resolve`).
    """

    def __init__(self, clip: ClipData, annotations_path, *, low_fit: float = 0.5,
                 low_doubt: float = 0.05, defer_refresh: bool = False, lift: str = "solve"):
        self.clip = clip
        self.path = Path(annotations_path)
        self.low_fit = float(low_fit)
        self.low_doubt = float(low_doubt)
        self.load_error: str | None = None
        self.backup: Path | None = None
        self.last_edit_ms = 0.0
        self.saved = False
        self._visited: set[tuple[int, str]] = set()
        self.defer_refresh = bool(defer_refresh)
        self.lift = lift
        self.stale = False
        self._version = 0
        self._lock = threading.RLock()
        self._region_version = 0
        self.regions_stale = False  # regions edited since the silhouettes were made
        self._prepare_clip()
        self.annotations = Annotations()
        if self.path.exists():
            try:
                self.annotations = Annotations.load(self.path, clip.n_frames,
                                                    frame_size=clip.size)
            except AnnotationError as exc:
                self.load_error = str(exc)
                self.backup = backup_path(self.path)
                shutil.copy2(self.path, self.backup)
        self._recompute()

    # ------------------------------------------------------------------ derived state
    def _prepare_clip(self) -> None:
        """What :func:`vidcap.video.lifting.lift_pose` derives from the clip's 2D joints
        alone (for the quick re-lift); again after the silhouettes were recomputed."""
        from scipy.ndimage import median_filter

        from vidcap.video.lift import torso_width_ratio
        from vidcap.video.lifting import fill_gaps, frame_scales, lift_pose, model_scales

        clip = self.clip
        flat2d, self._flat_height, _ = flat_view(clip.joints2d, clip.model_height,
                                                 Annotations(), clip.perspective)
        self._filled = fill_gaps(flat2d)
        scale = frame_scales(self._filled, clip.fps, clip.body)  # as lift_pose does
        self._segment_scale = model_scales(self._flat_height, len(self._filled), clip.body)
        rho = torso_width_ratio(self._filled, scale if self._segment_scale is None
                                else self._segment_scale, clip.body)
        if clip.spread is not None:
            spread = np.asarray(clip.spread, float)
            rho = np.where(np.isfinite(spread), spread, rho)
        window = inspect.signature(lift_pose).parameters.get("yaw_window_s")
        if window is not None:  # lift_pose's running median of the foreshortening
            size = max(1, int(round(window.default * clip.fps)) | 1)
            rho = median_filter(rho, size=size, mode="nearest")
        self._rho = rho

    def _lift_pose(self, annotations):
        from vidcap.video.lifting import lift_pose

        c = self.clip
        flat2d, flat_height, flat_events = flat_view(c.joints2d, c.model_height, annotations,
                                                     c.perspective)
        return lift_pose(flat2d, fps=c.fps, body=c.body, annotations=flat_events,
                         image_sides=c.image_sides, spread=c.spread, track=c.track,
                         frame_size=c.size, model_height=flat_height, method=self.lift,
                         near_side=c.near_side, limb_order=c.limb_order)

    def _take(self, res) -> None:
        """Adopt a full 3D-stage result (:class:`vidcap.video.lifting.LiftResult`)."""
        from vidcap.video.lifting import plane_passages

        self._result = res
        self.scale = res.scale  # one number, or one per frame
        self.checks = res.checks
        self.doubt = sign_doubt(res.margin, res.zeta, self.clip.body)
        self.proposed_orientation = np.asarray(res.proposed_orientation).astype(str)
        self._near_plane = plane_passages(res.zeta)
        self.user_signs, user_orient, self.user_joints = self.annotations.resolve(
            self.n_frames, near_plane=self._near_plane)
        self.user_orient = np.asarray(user_orient).astype(str)
        self._user_sides = self.annotations.sides(self.n_frames)
        self.joints2d = self._on_frame(res.joints2d)
        self.joints3d = np.asarray(res.joints3d, float)
        self.signs = np.asarray(res.signs).astype(int)
        self.orientation = np.asarray(res.orientation).astype(str)
        self.yaw = np.asarray(res.yaw, float)
        # the clip solve's poses (None with the per-segment lift): an edit re-solves
        # the frames it reaches from these (:mod:`vidcap.video.solve.local`)
        self._params = None if res.solve_params is None else np.array(res.solve_params)

    def _quick(self) -> None:
        """The user's events with the last proposals: the 3D stage of
        :func:`vidcap.video.lifting.lift_pose` without re-proposing (no dynamic programming);
        with the clip solve, only the frames whose events changed (and a few around)
        are solved again (:func:`vidcap.video.solve.local.resolve_window`)."""
        from vidcap.video.lift import lift
        from vidcap.video.lifting import apply_user_view

        res, body = self._result, self.clip.body
        user_signs, user_orient, user_joints = self.annotations.resolve(
            self.n_frames, near_plane=self._near_plane)
        user_orient = np.asarray(user_orient).astype(str)
        sides = self.annotations.sides(self.n_frames)
        orientation, yaw, j2 = apply_user_view(
            self._filled, self.proposed_orientation, self._rho, user_orient,
            flat_points(user_joints, self.clip.joints2d, self.clip.model_height,
                        self.clip.perspective),
            image_sides=self.clip.image_sides, user_sides=sides, facing=res.facing,
            names_swapped=getattr(res, "names_swapped", None))
        signs = np.where(user_signs != 0, user_signs, res.signs).astype(int)
        centre = (0.5 * self.clip.size[0], 0.5 * self.clip.size[1])
        if self._params is not None:
            joints3d, signs = self._quick_solve(j2, yaw, user_signs, user_orient, user_joints,
                                                sides, signs, centre)
        else:
            joints3d = lift(j2, signs, yaw, body=body, scale=self.scale, principal_point=centre,
                            segment_scale=self._segment_scale).joints3d
        (self.user_signs, self.user_orient, self.user_joints, self.orientation, self.yaw,
         self.joints2d, self.signs, self.joints3d) = (user_signs, user_orient, user_joints,
                                                      orientation, yaw, self._on_frame(j2),
                                                      signs, joints3d)
        self._user_sides = sides

    def _on_frame(self, joints2d) -> np.ndarray:
        """The lift's 2D joints (un-warped) where the frame shows them, for the page."""
        from vidcap.video.fit.perspective import warp_joints

        k, above_feet = self.clip.perspective
        if k == 0 or self._flat_height is None:
            return np.asarray(joints2d, float)
        return warp_joints(joints2d, self._flat_height, k, above_feet)[0]

    def _quick_solve(self, j2, yaw, user_signs, user_orient, user_joints, sides, signs,
                     centre):
        """Re-solve the frames an edit reached; (joints3d, signs) of the clip."""
        from vidcap.video.solve.local import edit_window, resolve_window
        from vidcap.video.solve.stage import USER_JOINT_WEIGHT, YAW_SIGMA_PROPOSED, YAW_SIGMA_USER

        def moved(a, b):
            a, b = np.asarray(a, float), np.asarray(b, float)
            same = (a == b) | (np.isnan(a) & np.isnan(b))
            return ~same.reshape(len(a), -1).all(axis=1)

        changed = (moved(user_signs, self.user_signs) | (user_orient != self.user_orient)
                   | moved(user_joints, self.user_joints) | moved(sides, self._user_sides))
        window = edit_window(changed)
        if window is None:
            return self.joints3d, self.signs
        res = self._result
        self._params, joints3d, wsigns = resolve_window(
            self._params, self.joints3d, window, j2, scale=self.scale, fps=self.clip.fps,
            body=self.clip.body, yaw=yaw, prior_signs=res.signs, hard_signs=user_signs,
            segment_scale=self._segment_scale, principal_point=centre, contact=res.contact,
            yaw_sigma=np.where(user_orient != "", YAW_SIGMA_USER, YAW_SIGMA_PROPOSED),
            confidence=np.where(np.isfinite(user_joints).all(axis=-1), USER_JOINT_WEIGHT, 1.0))
        signs = np.array(self.signs)
        signs[window[0]:window[1]] = wsigns
        return joints3d, signs

    def _recompute(self) -> None:
        with self._lock:
            self._take(self._lift_pose(self.annotations))
            self.stale = False

    def refresh(self) -> bool:
        """Run the full 3D stage (re-proposing the depth signs with the user's as
        constraints): the slow part of an edit with ``defer_refresh``. Safe to run in a
        worker thread: the result is dropped if another edit came in meanwhile.

        Returns
        -------
        bool
            Whether the result was kept.
        """
        from vidcap.video.annotations import Annotations

        with self._lock:
            version = self._version
            snapshot = Annotations(self.annotations.events)
        res = self._lift_pose(snapshot)
        with self._lock:
            if version != self._version:
                return False
            self._take(res)
            self.stale = False
        return True

    @property
    def n_frames(self) -> int:
        """Frames in the clip."""
        return self.clip.n_frames

    @property
    def n_user_inputs(self) -> int:
        """The user's inputs so far (seed 004 section 4.3 counts them)."""
        return int(self.annotations.n_user_inputs)

    def low_confidence(self, frame: int) -> np.ndarray:
        """Segments (10,) bool whose sign is doubtful or whose frame fits badly."""
        doubtful = (self.doubt[frame] > self.low_doubt) & (self.user_signs[frame] == 0)
        return doubtful | (self.clip.fit_score[frame] < self.low_fit)

    def frame_info(self, frame: int) -> dict:
        """What the page shows for ``frame`` (JSON-ready)."""
        f = self._check_frame(frame)
        low = self.low_confidence(f)
        segs = []
        for k, name in enumerate(SEGMENT_NAMES):
            segs.append({
                "name": name,
                "label": name.replace("_", " "),
                "sign": int(self.signs[f, k]),
                "user": bool(self.user_signs[f, k] != 0),
                "event": self._event_at(f, "depth", name),
                "low": bool(low[k]),
                "doubt_cm": round(100.0 * float(self.doubt[f, k]), 1),
            })
        return {
            "frame": f,
            "segments": segs,
            "orientation": str(self.orientation[f]),
            "orientation_user": bool(self.user_orient[f] != ""),
            "fit_score": round(float(self.clip.fit_score[f]), 3),
            # not fitted (no person, or mostly outside the picture): the pose shown is
            # filled from the frames around it, as the review video marks it
            "filled": bool(self.clip.fit_score[f] <= 0),
            "sides_swapped": [p for p, on in zip(PAIRS, self.annotations.sides(f + 1)[f],
                                                 strict=True) if on],
            "user_joints": [JOINT_NAMES[i] for i in
                            np.flatnonzero(np.isfinite(self.user_joints[f]).all(-1))],
        }

    def _event_at(self, frame: int, type_: str, key: str) -> bool:
        return any(e.frame == frame and e.type == type_ and e.key == key
                   for e in self.annotations.events)

    def _check_frame(self, frame) -> int:
        f = int(frame)
        if not 0 <= f < self.n_frames:
            raise ValueError(f"frame {frame} is outside 0..{self.n_frames - 1}")
        return f

    # ------------------------------------------------------------------ edits
    def _edited(self, t0: float, *, full: bool = False) -> float:
        with self._lock:
            self._version += 1
            if self.defer_refresh and not full:
                self._quick()
                self.stale = True
            else:
                self._recompute()
        self.save()
        self.last_edit_ms = (time.perf_counter() - t0) * 1000.0
        return self.last_edit_ms

    def set_depth(self, frame: int, segment: str, sign) -> float:
        """From ``frame`` on, ``segment`` points toward (+1) / away (-1) / auto (0).

        Returns the time the edit took (re-lift and save), milliseconds.
        """
        t0 = time.perf_counter()
        if segment not in SEGMENT_INDEX:
            raise ValueError(f"unknown segment {segment!r}")
        with self._lock:
            self.annotations.add_depth(self._check_frame(frame), segment, int(sign))
        return self._edited(t0)

    def flip_depth(self, frame: int, segment: str) -> float:
        """Set ``segment``'s sign from ``frame`` on to the opposite of what is shown now."""
        current = int(self.signs[self._check_frame(frame), SEGMENT_INDEX[segment]])
        return self.set_depth(frame, segment, -1 if current >= 0 else 1)

    def set_orientation(self, frame: int, label: str) -> float:
        """From ``frame`` on, the body faces ``label``. Returns milliseconds taken."""
        t0 = time.perf_counter()
        if label not in ORIENTATIONS:
            raise ValueError(f"unknown orientation {label!r}")
        with self._lock:
            self.annotations.add_orientation(self._check_frame(frame), label)
        return self._edited(t0)

    def set_sides(self, frame: int, pair: str, swapped: bool) -> float:
        """From ``frame`` on, ``pair`` ('arms' or 'legs') is left-right ``swapped`` or as
        the 2D stage named it. Returns milliseconds taken.

        Always the full 3D stage: the proposed depth signs belong to the limbs, which
        the swap renames.
        """
        t0 = time.perf_counter()
        with self._lock:
            self.annotations.add_sides(self._check_frame(frame), pair, bool(swapped))
        return self._edited(t0, full=True)

    def flip_sides(self, frame: int, pair: str) -> float:
        """Swap ``pair`` from ``frame`` on against what is shown now; flipping back at
        the same frame removes the event rather than adding an "as fitted" one."""
        f = self._check_frame(frame)
        if pair not in PAIRS:
            raise ValueError(f"unknown limb pair {pair!r}; expected one of {PAIRS}")
        col = PAIRS.index(pair)
        t0 = time.perf_counter()
        with self._lock:
            want = not bool(self.annotations.sides(f + 1)[f, col])
            self.annotations.remove(f, "sides", pair)
            if bool(self.annotations.sides(f + 1)[f, col]) != want:
                self.annotations.add_sides(f, pair, want)
        return self._edited(t0, full=True)

    def set_joint(self, frame: int, joint: str, u: float, v: float) -> float:
        """At ``frame``, ``joint`` is at pixel (u, v). Returns milliseconds taken."""
        t0 = time.perf_counter()
        if joint not in JOINT_INDEX:
            raise ValueError(f"unknown joint {joint!r}")
        w, h = self.clip.size
        u = float(np.clip(u, 0, w - 1))
        v = float(np.clip(v, 0, h - 1))
        with self._lock:
            self.annotations.add_joint(self._check_frame(frame), joint, round(u, 2), round(v, 2))
        return self._edited(t0)

    def clear_joint(self, frame: int, joint: str) -> float:
        """Forget the user's position of ``joint`` at ``frame``. Returns milliseconds taken."""
        t0 = time.perf_counter()
        with self._lock:
            self.annotations.remove(self._check_frame(frame), "joint", joint)
        return self._edited(t0)

    def nearest_joint(self, frame: int, u: float, v: float, *, radius: float) -> str | None:
        """Name of the joint nearest pixel (u, v) within ``radius`` pixels, else None."""
        d = np.linalg.norm(self.joints2d[self._check_frame(frame)] - [u, v], axis=1)
        d[~np.isfinite(d)] = np.inf
        i = int(np.argmin(d))
        return JOINT_NAMES[i] if d[i] <= radius else None

    def save(self) -> None:
        """Write the annotations atomically. After a load error an empty set is not written,
        so the user's (malformed) file is never replaced by nothing."""
        if self.load_error is not None and self.n_user_inputs == 0:
            return
        self.annotations.save(self.path)
        self.saved = True

    # ------------------------------------------------------------------ attention
    def flagged(self) -> list[dict]:
        """Frames needing attention, most urgent first: doubtful depth signs (the
        proposals' ranked checks) and badly fitting frames.

        Each item has ``frame``, ``segment`` (or ``""``) and ``reason``.
        """
        out = []
        for c in self.checks:
            k = SEGMENT_INDEX[c["segment"]]
            if self.user_signs[c["frame"], k] == 0:
                out.append({"frame": int(c["frame"]), "segment": c["segment"],
                            "reason": f"{c['segment'].replace('_', ' ')}: depth doubtful"})
        from vidcap.video.result import true_runs

        # frames not fitted at all (score 0): one item per run, at its first frame
        for a, b in true_runs(self.clip.fit_score <= 0):
            where = f"frame {a}" if a == b else f"frames {a}-{b}"
            out.append({"frame": int(a), "segment": "",
                        "reason": f"{where} not fitted (no person, or mostly outside the "
                                  "picture): pose filled from the frames around"})
        score = self.clip.fit_score
        bad = np.flatnonzero((score < self.low_fit) & (score > 0))
        for f in bad[np.argsort(score[bad], kind="stable")]:
            out.append({"frame": int(f), "segment": "",
                        "reason": f"2D fit poor ({score[f]:.2f})"})
        return out

    def next_attention(self, frame: int) -> dict | None:
        """The most urgent flagged item not yet visited (and not at ``frame``); marks it
        visited. Cycles once every item has been visited."""
        items = self.flagged()
        if not items:
            return None
        fresh = [it for it in items if (it["frame"], it["segment"]) not in self._visited
                 and it["frame"] != frame]
        if not fresh:
            self._visited.clear()
            fresh = [it for it in items if it["frame"] != frame] or items
        item = fresh[0]
        self._visited.add((item["frame"], item["segment"]))
        return item


def default_annotations_path(video: str | os.PathLike) -> Path:
    """``VIDEO_STEM.vidcap.json`` beside the video.

    See :func:`vidcap.video.annotations.default_path`.
    """
    from vidcap.video.annotations import default_path

    return default_path(video)


def load_clip(video: str | os.PathLike, *, cache_dir: str | os.PathLike | None = None,
              height: float = 1.75, progress: bool | None = None, log=None,
              annotations: str | os.PathLike | None = None, **fit) -> ClipData:
    """Run the pipeline's heavy stages for ``video`` (or load them from its stage cache).

    Parameters
    ----------
    video : str or path-like
    cache_dir : str or path-like, optional
        Stage cache (default ``.vidcap-cache`` beside the video, shared with
        ``vidcap convert`` runs whose output is beside the video).
    height : float
        Subject's height in metres.
    progress : bool, optional
        Progress bars (default: when stderr is a terminal).
    log : callable, optional
        Called with one-line status messages.
    annotations : str or path-like, optional
        The annotations file: its regions (scene_region, person_box) shape the
        silhouettes, as in ``vidcap convert``. A file that cannot be read counts as
        none (the session reports it).
    **fit
        The 2D fit's options of :func:`vidcap.video.pipeline.run` (``proportions``,
        ``cues``, ``ensemble``, ``camera``): the same as ``vidcap convert``'s give the
        page the fit, and the 3D view, the motion file will get.

    Returns
    -------
    ClipData
        Frames are kept in memory as JPEG (about 30 kB each), at most
        :data:`MAX_DISPLAY_WIDTH` wide, and decoded on demand.

    Raises
    ------
    vidcap.errors.VidcapError
        If the video cannot be read or no person is found in it.
    """
    import cv2

    from vidcap.io.video import iter_frames
    from vidcap.video import pipeline

    video = Path(video)
    cache_dir = video.parent / ".vidcap-cache" if cache_dir is None else Path(cache_dir)
    # the user's annotations are the session's business: run the stages with their
    # regions only (the silhouettes depend on them)
    regions = _file_regions(annotations, video)
    res = pipeline.run(video, annotations=regions, height=height, cache_dir=cache_dir,
                       progress=progress, log=log, **fit)
    joints2d, spread = res.image_joints2d, res.spread
    jpegs = []
    size = (0, 0)

    def frames():  # each frame read once: kept for the page, and read for the front cue
        nonlocal size
        for frame in iter_frames(video):
            yield frame
            h, w = frame.shape[:2]
            size = (w, h)
            if w > MAX_DISPLAY_WIDTH:  # kept at the size the page shows (4K: 1/9 the memory)
                frame = cv2.resize(frame, (MAX_DISPLAY_WIDTH, round(h * MAX_DISPLAY_WIDTH / w)),
                                   interpolation=cv2.INTER_AREA)
            ok, buf = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, 92])
            jpegs.append(buf)

    near, limbs = pipeline.colour_cues(frames(), joints2d, res.model_height, res.body,
                                       fps=res.fps)
    n = min(len(jpegs), res.n_frames)

    def read_frame(i: int) -> np.ndarray:
        return cv2.imdecode(jpegs[i], cv2.IMREAD_COLOR)

    track = res.track
    fit_score = np.asarray(res.similarity, float)
    if res.outside is not None:  # left out of the fit (mostly outside the picture)
        fit_score = np.where(res.outside, 0.0, fit_score)
    return ClipData(video=video, fps=res.fps, read_frame=read_frame, joints2d=joints2d[:n],
                    masks=res.masks[:n], fit_score=fit_score[:n],
                    image_sides=True, spread=None if spread is None else spread[:n],
                    track=None if track is None else track[:n],
                    model_height=None if res.model_height is None else res.model_height[:n],
                    body=res.body or BodyModel(height=height), size=size,
                    fit_kw={**_fit_keywords(res.proportions, res.perspective[0]),
                            **({"low_body": True} if fit.get("seated") else {})},
                    perspective=res.perspective,
                    resegment=_resegmenter(video, cache_dir, log),
                    pose={"joints2d": joints2d[:n], "scores": res.scores[:n],
                          "similarity": res.similarity[:n], "spread": spread[:n],
                          "model_height": res.model_height[:n]},
                    near_side=None if near is None else near[:n],
                    limb_order=None if limbs is None else limbs[:n])


def _fit_keywords(proportions, k: float = 0.0) -> dict:
    """The 2D fit's ``body``/``foot`` keywords for a run's proportions (None: the seed's)
    as a camera of perspective ``k`` images them (the body the run's fit drew)."""
    if proportions is None and k == 0:
        return {}
    from vidcap.video.fit.perspective import perspective_factors
    from vidcap.video.fit.proportions import fit_keywords

    factors = {} if proportions is None else proportions.factors
    return fit_keywords(perspective_factors(factors, k))


def _file_regions(path, video: Path):
    """The region events of the annotations file ``path`` (an empty set when there is
    none, or it cannot be read, or a region lies outside the video's frames)."""
    from vidcap.io.video import probe
    from vidcap.video.annotations import Annotations

    if path is None or not Path(path).exists():
        return Annotations()
    try:
        info = probe(video)
        ann = Annotations.load(path, frame_size=(info.width, info.height))
    except AnnotationError:
        return Annotations()
    return Annotations(ann.region_events())


def _resegmenter(video: Path, cache_dir: Path, log):
    """:attr:`ClipData.resegment` for a video: the pipeline's plate and silhouette stages
    with the user's regions, cached as ``vidcap convert`` caches them."""
    from vidcap.video import pipeline

    def resegment(regions, on_masks):
        return pipeline.silhouettes_only(video, regions, cache_dir=cache_dir,
                                         on_masks=on_masks, log=log).masks

    return resegment


