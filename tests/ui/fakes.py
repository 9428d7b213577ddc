"""Test-only stand-ins for the stage results, the lifter and the annotations, so that
the annotate page can be tested before (and independently of) the real pipeline.

Nothing here is used by the library or the CLI.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from ui.session import ClipData
from vidcap.body import (
    JOINT_INDEX,
    JOINT_NAMES,
    ORIENTATIONS,
    SEGMENT_INDEX,
    SEGMENT_JOINTS,
    SEGMENT_NAMES,
    BodyModel,
)
from vidcap.errors import AnnotationError
from vidcap.fileio import write_text_atomic


def synthetic_clip(n_frames: int = 12, size=(160, 120), *, seed: int = 0) -> ClipData:
    """A stick figure swinging its limbs, seen from the side, with masks and 2D joints."""
    rng = np.random.default_rng(seed)
    body = BodyModel()
    w, h = size
    scale = 0.8 * h / body.height
    rest = body.rest_positions()  # (15, 3), Y up
    t = np.arange(n_frames) / n_frames * 2 * np.pi
    joints = np.repeat(rest[None], n_frames, axis=0)
    # swing the limbs in the image plane (X = image right) about their proximal joints
    for seg, amp, phase in (("l_upper_arm", 0.9, 0), ("r_upper_arm", 0.9, np.pi),
                            ("l_upper_leg", 0.4, np.pi), ("r_upper_leg", 0.4, 0)):
        a, b = SEGMENT_JOINTS[SEGMENT_INDEX[seg]]
        chain = [b] + ([b + 1] if JOINT_NAMES[b].endswith(("elbow", "knee")) else [])
        ang = amp * np.sin(t + phase)
        for j in chain:
            v = rest[j] - rest[a]
            if seg.endswith("arm"):
                v = np.array([0.0, -np.linalg.norm(v), 0.0])
            c, s = np.cos(ang), np.sin(ang)
            joints[:, j, 0] = rest[a, 0] + c * v[0] - s * v[1]
            joints[:, j, 1] = rest[a, 1] + s * v[0] + c * v[1]
    j2 = np.stack([w / 2 + scale * joints[..., 0] + 1.5 * np.arange(n_frames)[:, None] - 8,
                   h - 5 - scale * joints[..., 1]], axis=-1)
    j2 += rng.normal(0, 0.3, j2.shape)
    frames = np.empty((n_frames, h, w, 3), np.uint8)
    masks = np.zeros((n_frames, h, w), bool)
    for f in range(n_frames):
        img = np.full((h, w, 3), (90, 110, 100), np.uint8)
        m = np.zeros((h, w), np.uint8)
        for a, b in SEGMENT_JOINTS:
            p, q = tuple(np.round(j2[f, a]).astype(int)), tuple(np.round(j2[f, b]).astype(int))
            cv2.line(img, p, q, (200, 190, 180), 5)
            cv2.line(m, p, q, 1, 5)
        frames[f] = img
        masks[f] = m > 0
    fit = np.full(n_frames, 0.9)
    fit[n_frames // 2] = 0.3
    return ClipData(video=Path("synthetic.mp4"), fps=10.0, read_frame=lambda i: frames[i],
                    joints2d=j2, masks=masks, fit_score=fit, scale=scale,
                    width_ratio=np.full(n_frames, 0.3),
                    orientation=np.full(n_frames, "right"))


class FakeLifter:
    """Signs +1 unless fixed; doubtful margins on the arms; straightforward Eq. 2.2 lift."""

    def __init__(self):
        self.body = BodyModel()
        self.calls = 0

    def yaw(self, orientation, width_ratio):
        table = {"left": -np.pi / 2, "right": np.pi / 2, "front_left": -0.5, "front_right": 0.5,
                 "back_left": -2.6, "back_right": 2.6}
        return np.array([table[str(o)] for o in orientation])

    def propose(self, joints2d, yaw, fixed, scale):
        self.calls += 1
        F = joints2d.shape[0]
        signs = np.where(np.asarray(fixed) != 0, fixed, 1).astype(int)
        margin = np.full((F, 10), 5.0)
        margin[:, SEGMENT_INDEX["l_lower_arm"]] = 0.1 + np.arange(F) / F
        margin[np.asarray(fixed) != 0] = np.inf
        checks = [{"frame": int(f), "segment": "l_lower_arm", "sign": 1,
                   "margin": float(margin[f, 3]), "priority": 1.0 - f / F}
                  for f in range(0, F, 3) if np.isfinite(margin[f, 3])]
        return signs, margin, checks

    def lift(self, joints2d, signs, yaw, scale):
        L = self.body.segment_lengths()
        vec = (joints2d[:, SEGMENT_JOINTS[:, 1]] - joints2d[:, SEGMENT_JOINTS[:, 0]]) / scale
        vec[..., 1] *= -1
        dz = np.sqrt(np.clip(L**2 - (vec**2).sum(-1), 0, None)) * np.where(signs < 0, -1, 1)
        out = np.zeros(joints2d.shape[:2] + (3,))
        out[..., :2] = joints2d / scale * [1, -1]
        for k, (a, b) in enumerate(SEGMENT_JOINTS):
            out[:, b, 2] = out[:, a, 2] + dz[:, k]
        return out


@dataclass(frozen=True)
class _Event:
    frame: int
    type: str
    key: str
    value: object


class FakeAnnotations:
    """The parts of ``vidcap.annotations.Annotations`` the session uses (same JSON)."""

    def __init__(self):
        self._ev = {}

    def add_depth(self, frame, segment, sign):
        self._ev[(frame, "depth", segment)] = _Event(frame, "depth", segment, int(sign))

    def add_orientation(self, frame, label):
        assert label in ORIENTATIONS
        self._ev[(frame, "orientation", "")] = _Event(frame, "orientation", "", label)

    def add_joint(self, frame, joint, u, v):
        self._ev[(frame, "joint", joint)] = _Event(frame, "joint", joint, (u, v))

    def remove(self, frame, type, key=""):
        return self._ev.pop((frame, type, key), None) is not None

    @property
    def events(self):
        return sorted(self._ev.values(), key=lambda e: (e.frame, e.type, e.key))

    @property
    def n_user_inputs(self):
        return len(self._ev)

    def resolve(self, n_frames):
        signs = np.zeros((n_frames, 10), np.int8)
        orient = np.full(n_frames, "", dtype=object)
        joints = np.full((n_frames, 15, 2), np.nan)
        for e in self.events:
            if e.type == "depth":
                signs[e.frame:, SEGMENT_INDEX[e.key]] = e.value
            elif e.type == "orientation":
                orient[e.frame:] = e.value
            else:
                joints[e.frame, JOINT_INDEX[e.key]] = e.value
        return signs, orient.astype(str), joints

    def to_json(self):
        out = []
        for e in self.events:
            if e.type == "depth":
                out.append({"frame": e.frame, "type": "depth", "segment": e.key,
                            "value": {1: "toward", -1: "away", 0: "auto"}[e.value]})
            elif e.type == "orientation":
                out.append({"frame": e.frame, "type": "orientation", "value": e.value})
            else:
                out.append({"frame": e.frame, "type": "joint", "joint": e.key,
                            "u": e.value[0], "v": e.value[1]})
        return {"version": 1, "events": out}

    def save(self, path):
        write_text_atomic(path, json.dumps(self.to_json(), indent=1) + "\n")

    @classmethod
    def load(cls, path, n_frames=None):
        try:
            data = json.loads(Path(path).read_text())
            a = cls()
            for ev in data["events"]:
                if ev["type"] == "depth":
                    a.add_depth(ev["frame"], ev["segment"],
                                {"toward": 1, "away": -1, "auto": 0}[ev["value"]])
                elif ev["type"] == "orientation":
                    a.add_orientation(ev["frame"], ev["value"])
                else:
                    assert ev["joint"] in JOINT_NAMES
                    a.add_joint(ev["frame"], ev["joint"], ev["u"], ev["v"])
            return a
        except (ValueError, KeyError, TypeError, AssertionError) as exc:
            raise AnnotationError(f"malformed annotations ({exc!r})", path) from None


SEGMENTS = SEGMENT_NAMES
