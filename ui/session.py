"""The state behind the annotate page: one clip, its cached stage results, the
user's annotations, and the lifted pose, re-lifted after every edit.

The page (:mod:`ui.annotate`) only talks to :class:`AnnotateSession`; the session
talks to the library through two small seams, so that it can be tested alone:

* :class:`ClipData`, the results of the pipeline's heavy stages (frames,
  silhouettes, 2D fit, proposals' inputs), built by :func:`load_clip`;
* a *lifter* (:class:`VidcapLifter`): body yaw from orientation labels, depth-sign
  proposals with the user's signs as constraints, and lifting to 3D.
"""

from __future__ import annotations

import os
import shutil
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vidcap.body import JOINT_INDEX, JOINT_NAMES, ORIENTATIONS, SEGMENT_INDEX, SEGMENT_NAMES
from vidcap.errors import AnnotationError, VidcapError


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
        ``read_frame(i) -> (H, W, 3) uint8`` BGR frame ``i``.
    joints2d : numpy.ndarray, shape (F, 15, 2)
        Fitted 2D joints in pixels (x right, y down), named by the body's sides.
    masks : numpy.ndarray of bool, shape (F, H, W), or None
        Silhouettes.
    fit_score : numpy.ndarray, shape (F,)
        Quality of the 2D fit per frame in [0, 1] (the silhouette similarity);
        frames below :attr:`AnnotateSession.low_fit` are flagged.
    scale : float
        Pixels per metre of the subject.
    width_ratio : numpy.ndarray, shape (F,)
        Torso width foreshortening per frame (for the yaw from orientation labels).
    orientation : numpy.ndarray of str, shape (F,)
        Proposed orientation labels (:data:`vidcap.body.ORIENTATIONS`).
    """

    video: Path
    fps: float
    read_frame: Callable[[int], np.ndarray]
    joints2d: np.ndarray
    masks: np.ndarray | None
    fit_score: np.ndarray
    scale: float
    width_ratio: np.ndarray
    orientation: np.ndarray
    size: tuple[int, int] = field(default=(0, 0))  # (width, height), filled in post-init

    def __post_init__(self):
        self.video = Path(self.video)
        self.joints2d = np.asarray(self.joints2d, dtype=float)
        F = self.joints2d.shape[0]
        if self.joints2d.shape != (F, len(JOINT_NAMES), 2):
            raise ValueError(f"joints2d must be (F, 15, 2), got {self.joints2d.shape}")
        self.fit_score = np.broadcast_to(np.asarray(self.fit_score, float), (F,)).copy()
        self.width_ratio = np.broadcast_to(np.asarray(self.width_ratio, float), (F,)).copy()
        self.orientation = np.broadcast_to(np.asarray(self.orientation).astype(str), (F,)).copy()
        if self.size == (0, 0):
            h, w = self.read_frame(0).shape[:2]
            self.size = (w, h)

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return self.joints2d.shape[0]


class VidcapLifter:
    """The library's lifting, as the session needs it (``vidcap.lift``, ``vidcap.proposals``).

    Parameters
    ----------
    body : vidcap.body.BodyModel, optional
        The subject's body (default 1.75 m).
    """

    def __init__(self, body=None):
        from vidcap.body import BodyModel

        self.body = body or BodyModel()

    def yaw(self, orientation: np.ndarray, width_ratio: np.ndarray) -> np.ndarray:
        """Body yaw (F,) in radians from labels (F,) and torso foreshortening (F,)."""
        from vidcap.lift import yaw_from_orientation

        return yaw_from_orientation(orientation, width_ratio)

    def propose(self, joints2d, yaw, fixed, scale, *, tau: float = 0.2):
        """Depth-sign proposals with the user's ``fixed`` signs as constraints.

        Returns
        -------
        signs : numpy.ndarray of int, shape (F, 10)
        doubt : numpy.ndarray, shape (F, 10)
            Expected displacement of each segment's distal joint if its sign is wrong,
            metres: ``2 zeta l p_wrong`` with ``p_wrong = 1 / (1 + exp(margin / tau))``
            (as :meth:`vidcap.proposals.SignProposal.checks` ranks them).
        checks : list of dict
            The proposals' ranked list of (frame, segment) pairs to check.
        """
        from vidcap.proposals import propose_signs

        p = propose_signs(joints2d, yaw, scale=scale, body=self.body, fixed=fixed)
        with np.errstate(over="ignore"):
            p_wrong = 1.0 / (1.0 + np.exp(np.minimum(p.margin / tau, 700.0)))
        doubt = 2.0 * p.zeta * self.body.segment_lengths() * p_wrong
        return p.signs, doubt, p.checks(self.body, limit=200, tau=tau)

    def lift(self, joints2d, signs, yaw, scale) -> np.ndarray:
        """3D joints (F, 15, 3) in metres (X right, Y up, Z toward the camera)."""
        from vidcap.lift import lift

        return lift(joints2d, signs, yaw, body=self.body, scale=scale).joints3d


def _hold_missing(joints2d: np.ndarray) -> np.ndarray:
    """Frames without a fit (NaN joints, e.g. no silhouette) take the nearest fitted frame's
    joints, so that lifting and proposals run over the whole clip; (F, 15, 2) -> same."""
    ok = np.isfinite(joints2d).all(axis=(1, 2))
    if ok.all() or not ok.any():
        return joints2d
    idx = np.flatnonzero(ok)
    pos = np.clip(np.searchsorted(idx, np.arange(len(ok))), 0, len(idx) - 1)
    prev = idx[np.maximum(pos - 1, 0)]
    nxt = idx[pos]
    frames = np.arange(len(ok))
    nearest = np.where(np.abs(frames - prev) <= np.abs(nxt - frames), prev, nxt)
    return joints2d[nearest]


def backup_path(path: Path) -> Path:
    """A free ``.bak`` name beside ``path`` (``x.json.bak``, ``x.json.bak1``, ...)."""
    for n in range(1000):
        cand = path.with_name(path.name + (".bak" if n == 0 else f".bak{n}"))
        if not cand.exists():
            return cand
    raise AnnotationError("too many backups beside the annotations file", path)


class AnnotateSession:
    """One clip being annotated: edits, re-lifting and autosave.

    Parameters
    ----------
    clip : ClipData
        The cached stage results.
    annotations_path : str or path-like
        The annotations JSON (read if it exists; written after every edit).
    lifter : VidcapLifter, optional
        The lifting seam (default: the library's).
    low_fit : float
        Fit scores below this mark a frame as needing attention (keyword-only knob).
    low_doubt : float
        A segment's sign is marked doubtful when a wrong sign would move its distal
        joint by more than this (expected value, metres).
    annotations_cls : type, optional
        The annotations class (default :class:`vidcap.annotations.Annotations`).
    defer_refresh : bool
        If True an edit only resolves the events and re-lifts with the current
        proposals (milliseconds even for long clips) and marks the session
        :attr:`stale`; the caller then runs :meth:`refresh` (e.g. in a worker thread)
        to re-propose the other signs with the new constraints. If False (default)
        every edit does both at once.

    Attributes
    ----------
    load_error : str or None
        Why the annotations file could not be read. The file is then copied to
        :attr:`backup` and not written until the user makes an edit.
    """

    def __init__(self, clip: ClipData, annotations_path, *, lifter=None, low_fit: float = 0.5,
                 low_doubt: float = 0.05, annotations_cls=None, defer_refresh: bool = False):
        if annotations_cls is None:
            from vidcap.annotations import Annotations as annotations_cls
        self.clip = clip
        self.path = Path(annotations_path)
        self.lifter = lifter or VidcapLifter()
        self.low_fit = float(low_fit)
        self.low_doubt = float(low_doubt)
        self.load_error: str | None = None
        self.backup: Path | None = None
        self.last_edit_ms = 0.0
        self.saved = False
        self._visited: set[tuple[int, str]] = set()
        self.defer_refresh = bool(defer_refresh)
        self.stale = False
        self._version = 0
        self._lock = threading.RLock()
        self._proposed = np.ones((clip.n_frames, len(SEGMENT_NAMES)), int)
        self.annotations = annotations_cls()
        if self.path.exists():
            try:
                self.annotations = annotations_cls.load(self.path, clip.n_frames)
            except AnnotationError as exc:
                self.load_error = str(exc)
                self.backup = backup_path(self.path)
                shutil.copy2(self.path, self.backup)
        self._recompute()

    # ------------------------------------------------------------------ derived state
    def _resolve_user(self) -> None:
        """The user's events over the clip, and the lift with the current proposals (fast:
        no re-proposal)."""
        clip = self.clip
        F = clip.n_frames
        user_signs, user_orient, user_joints = self.annotations.resolve(F)
        user_orient = np.asarray(user_orient).astype(str)
        orientation = np.where(user_orient != "", user_orient, clip.orientation)
        joints2d = clip.joints2d.copy()
        have = np.isfinite(user_joints).all(axis=-1)
        joints2d[have] = user_joints[have]
        yaw = self.lifter.yaw(orientation, clip.width_ratio)
        signs = np.where(user_signs != 0, user_signs, self._proposed).astype(int)
        joints3d = self.lifter.lift(_hold_missing(joints2d), signs, yaw, clip.scale)
        (self.user_signs, self.user_orient, self.user_joints, self.orientation, self.joints2d,
         self.yaw, self.signs, self.joints3d) = (user_signs, user_orient, user_joints,
                                                 orientation, joints2d, yaw, signs, joints3d)

    def _recompute(self) -> None:
        with self._lock:
            self._resolve_user()
            self._proposed, self.doubt, self.checks = self.lifter.propose(
                _hold_missing(self.joints2d), self.yaw, self.user_signs, self.clip.scale)
            self._resolve_user()
            self.stale = False

    def refresh(self) -> bool:
        """Re-propose the depth signs with the user's as constraints and re-lift (the slow
        part of an edit with ``defer_refresh``). Safe to run in a worker thread: the result
        is dropped if another edit came in meanwhile.

        Returns
        -------
        bool
            Whether the result was kept.
        """
        with self._lock:
            version = self._version
            joints2d, yaw, fixed = self.joints2d, self.yaw, self.user_signs
        proposed, doubt, checks = self.lifter.propose(_hold_missing(joints2d), yaw, fixed,
                                                      self.clip.scale)
        with self._lock:
            if version != self._version:
                return False
            self._proposed, self.doubt, self.checks = proposed, doubt, checks
            self._resolve_user()
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
    def _edited(self, t0: float) -> float:
        with self._lock:
            self._version += 1
            if self.defer_refresh:
                self._resolve_user()
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
        bad = np.flatnonzero(self.clip.fit_score < self.low_fit)
        for f in bad[np.argsort(self.clip.fit_score[bad], kind="stable")]:
            out.append({"frame": int(f), "segment": "",
                        "reason": f"2D fit poor ({self.clip.fit_score[f]:.2f})"})
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
    """``VIDEO_STEM.vidcap.json`` beside the video (:func:`vidcap.annotations.default_path`)."""
    from vidcap.annotations import default_path

    return default_path(video)


def load_clip(video: str | os.PathLike) -> ClipData:
    """Run (or load from the cache) the pipeline's heavy stages for ``video``.

    Raises
    ------
    vidcap.errors.VidcapError
        If the video cannot be read, or the pipeline is not part of this build.
    """
    try:
        from vidcap import pipeline  # noqa: F401
    except ImportError:
        raise VidcapError("vidcap annotate needs the video pipeline (vidcap.pipeline), which"
                          " this build does not have yet", video) from None
    raise VidcapError("the video pipeline's interface is not connected to the annotate page"
                      " yet", video)
