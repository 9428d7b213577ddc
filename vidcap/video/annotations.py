"""User annotations: sparse change events carried forward (seed 004 sections 3.1.5, 4.3).

The seed's user gives, for a whole clip, only what the image cannot: the depth
direction of each segment, the body orientation, and the image position of a joint
hidden by occlusion. These rarely change (section 3.1.5), so the file holds *change
events* and every value is carried forward to the next event.

File format (JSON, UTF-8)::

    {
      "version": 1,
      "events": [
        {"frame": 0,  "type": "orientation", "value": "right"},
        {"frame": 12, "type": "depth", "segment": "l_lower_arm", "value": "toward"},
        {"frame": 40, "type": "depth", "segment": "l_lower_arm", "value": "auto"},
        {"frame": 30, "type": "joint", "joint": "l_wrist", "u": 123.5, "v": 240.0},
        {"frame": 0,  "type": "sides", "pair": "legs", "value": "swapped"},
        {"frame": 0,  "type": "scene_region", "box": [400, 0, 480, 120]},
        {"frame": 9,  "type": "scene_region", "polygon": [[10, 300], [60, 290], [40, 350]]},
        {"frame": 25, "type": "person_box", "box": [120, 40, 260, 355]}
      ]
    }

* ``orientation``: from ``frame`` on the body faces ``value`` (one of
  :data:`vidcap.body.ORIENTATIONS`), until the next orientation event.
* ``depth``: from ``frame`` on, segment ``segment``'s distal joint is ``toward``
  (+1) or ``away`` from (-1) the camera; ``auto`` hands the segment back to the
  automatic proposals. A depth event holds until the next event on that segment
  or, when the caller supplies where segments lie in the image plane
  (:meth:`Annotations.resolve` ``near_plane``), until the segment next passes
  through the image plane, the only place its direction can change.
* ``joint``: at ``frame`` only, joint ``joint`` is at pixel ``(u, v)`` (x right,
  y down): the manual fix for occluded joints (section 4.1).
* ``sides`` (beyond the seed): from ``frame`` on, the ``pair`` (``arms`` or ``legs``)
  the 3D stage names left and right is ``swapped`` or ``as_fitted``, until the next
  sides event of that pair. In a side view nothing in a silhouette tells the near
  leg from the far one, so the 2D stage's choice of which leg is the left one is a
  guess, kept for the whole track: one event fixes it.

* ``scene_region`` (beyond the seed, issue 26): pixels that are never the person, for
  the whole clip whatever its ``frame`` (the frame it was drawn on): a ``box``
  ``[x0, y0, x1, y1]`` or a ``polygon`` of ``[x, y]`` points (an area drawn around a
  lamp, a lit wall, a mirror). The silhouette stage removes them from every mask and
  from the choice of the person's blob (:mod:`vidcap.video.userregions`).
* ``person_box`` (beyond the seed): at ``frame`` only, the person is inside ``box``:
  the silhouette there is the blob inside it (nothing outside it is kept), and the
  frames after follow that blob as they follow the person anyway. One per frame.

Boxes are integer pixel edges, x right, y down, ``x1`` and ``y1`` exclusive
(``[0, 0, W, H]`` is the whole frame); polygon points are pixels in ``0..W``,
``0..H``. Frames count from 0. Segment and joint names are those of :mod:`vidcap.body`, with
true (body) sides.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vidcap.body import JOINT_INDEX, JOINT_NAMES, ORIENTATIONS, SEGMENT_INDEX, SEGMENT_NAMES
from vidcap.errors import AnnotationError
from vidcap.fileio import write_text_atomic

#: Farther than this from the picture's corner no joint of a video can be, pixels.
MAX_PIXELS = 1e5

FORMAT_VERSION = 1
_DEPTH_VALUES = {"toward": 1, "away": -1, "auto": 0}
_KEYS = {
    "orientation": {"frame", "type", "value"},
    "depth": {"frame", "type", "segment", "value"},
    "joint": {"frame", "type", "joint", "u", "v"},
    "sides": {"frame", "type", "pair", "value"},
    "scene_region": {"frame", "type"},  # and one of "box", "polygon"
    "person_box": {"frame", "type", "box"},
}
#: The events that change the silhouettes (and only those: see
#: :meth:`Annotations.region_events`).
REGION_TYPES = ("scene_region", "person_box")
#: Most points a scene_region polygon may have.
MAX_POLYGON_POINTS = 2000
#: The limb pairs a sides event names, in the column order of :meth:`Annotations.sides`.
PAIRS = ("arms", "legs")
_SIDES_VALUES = ("as_fitted", "swapped")


@dataclass(frozen=True)
class Event:
    """One annotation event (see the module docstring).

    ``key`` is the segment (depth), joint (joint), pair (sides), the shape
    (scene_region: :func:`region_key`) or ``""`` (orientation, person_box); ``value`` is
    ``+1/-1/0`` (depth), a label (orientation), ``(u, v)`` pixels (joint), a bool,
    swapped (sides), a box ``(x0, y0, x1, y1)`` (person_box, scene_region box) or a
    tuple of ``(x, y)`` points (scene_region polygon).
    """

    frame: int
    type: str
    key: str
    value: object

    def to_json(self) -> dict:
        """The event as its JSON object."""
        if self.type == "orientation":
            return {"frame": self.frame, "type": "orientation", "value": self.value}
        if self.type == "depth":
            word = {1: "toward", -1: "away", 0: "auto"}[self.value]
            return {"frame": self.frame, "type": "depth", "segment": self.key, "value": word}
        if self.type == "sides":
            return {"frame": self.frame, "type": "sides", "pair": self.key,
                    "value": _SIDES_VALUES[bool(self.value)]}
        if self.type == "person_box":
            return {"frame": self.frame, "type": "person_box", "box": list(self.value)}
        if self.type == "scene_region":
            shape = "box" if self.key.startswith("box") else "polygon"
            value = list(self.value) if shape == "box" else [list(p) for p in self.value]
            return {"frame": self.frame, "type": "scene_region", shape: value}
        u, v = self.value
        return {"frame": self.frame, "type": "joint", "joint": self.key, "u": u, "v": v}


def _sign_value(sign) -> int:
    if isinstance(sign, str):
        if sign not in _DEPTH_VALUES:
            raise ValueError(f"depth value must be one of {sorted(_DEPTH_VALUES)}, got {sign!r}")
        return _DEPTH_VALUES[sign]
    if sign in (1, -1, 0) and not isinstance(sign, bool):
        return int(sign)
    raise ValueError(f"depth sign must be +1, -1, 0 or toward/away/auto, got {sign!r}")


def _is_int(x) -> bool:
    return isinstance(x, (int, np.integer)) and not isinstance(x, bool)


def check_box(box) -> tuple[int, int, int, int]:
    """A box ``[x0, y0, x1, y1]`` as a tuple of ints, or ValueError saying what is wrong
    (the frame's size is checked by :meth:`Annotations.check_frame_size`)."""
    if not isinstance(box, (list, tuple)) or len(box) != 4 or not all(map(_is_int, box)):
        raise ValueError(f"'box' must be four integers [x0, y0, x1, y1] (pixels), got {box!r}")
    x0, y0, x1, y1 = (int(v) for v in box)
    if min(x0, y0) < 0 or max(x1, y1) > MAX_PIXELS:
        raise ValueError(f"box {[x0, y0, x1, y1]} must lie within 0..{MAX_PIXELS:g} pixels")
    if not (x0 < x1 and y0 < y1):
        raise ValueError(f"box {[x0, y0, x1, y1]} is empty: it needs x0 < x1 and y0 < y1")
    return x0, y0, x1, y1


def check_polygon(points) -> tuple[tuple[float, float], ...]:
    """A polygon ``[[x, y], ...]`` (3 or more points) as a tuple of float pairs, or
    ValueError saying what is wrong."""
    if (not isinstance(points, (list, tuple)) or not 3 <= len(points) <= MAX_POLYGON_POINTS
            or not all(isinstance(q, (list, tuple)) and len(q) == 2 for q in points)):
        raise ValueError(f"'polygon' must be 3 to {MAX_POLYGON_POINTS} points [x, y]")
    flat = [v for q in points for v in q]
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool)
               and 0 <= v <= MAX_PIXELS for v in flat):  # (NaN fails too)
        raise ValueError(f"'polygon' points must be pixels within 0..{MAX_PIXELS:g}")
    return tuple((float(x), float(y)) for x, y in points)


def region_key(value) -> str:
    """The key of a scene_region event: its shape in words (two regions with the same
    shape are one)."""
    if len(value) == 4 and all(map(_is_int, value)):
        return "box " + " ".join(str(int(v)) for v in value)
    return "polygon " + " ".join(f"{x:g},{y:g}" for x, y in value)


def _region_extent(e: Event) -> tuple[float, float]:
    """The largest x and y a region event reaches."""
    if e.type == "person_box" or e.key.startswith("box"):
        return float(e.value[2]), float(e.value[3])
    pts = np.asarray(e.value, float)
    return float(pts[:, 0].max()), float(pts[:, 1].max())


class Annotations:
    """A set of annotation events for one clip.

    Parameters
    ----------
    events : iterable of Event, optional

    Examples
    --------
    >>> a = Annotations()
    >>> a.add_orientation(0, "right")
    >>> a.add_depth(5, "l_lower_arm", +1)
    >>> signs, orient, joints = a.resolve(8)
    >>> signs[4:7, 3].tolist(), str(orient[0]), a.n_user_inputs
    ([0, 1, 1], 'right', 2)
    """

    def __init__(self, events=()):
        self._events: dict[tuple[int, str, str], Event] = {}
        for e in events:
            self._put(e)

    # ------------------------------------------------------------------ editing
    def _put(self, e: Event) -> None:
        self._events[(e.frame, e.type, e.key)] = e

    @staticmethod
    def _frame(frame) -> int:
        if isinstance(frame, bool) or not isinstance(frame, (int, np.integer)) or frame < 0:
            raise ValueError(f"frame must be a non-negative integer, got {frame!r}")
        return int(frame)

    def add_depth(self, frame: int, segment: str, sign) -> None:
        """From ``frame`` on, ``segment`` points toward (+1) / away (-1) / auto (0)."""
        if segment not in SEGMENT_INDEX:
            raise ValueError(f"unknown segment {segment!r}; expected one of {SEGMENT_NAMES}")
        self._put(Event(self._frame(frame), "depth", segment, _sign_value(sign)))

    def add_orientation(self, frame: int, label: str) -> None:
        """From ``frame`` on, the body faces ``label`` (:data:`vidcap.body.ORIENTATIONS`)."""
        if label not in ORIENTATIONS:
            raise ValueError(f"unknown orientation {label!r}; expected one of {ORIENTATIONS}")
        self._put(Event(self._frame(frame), "orientation", "", label))

    def add_joint(self, frame: int, joint: str, u: float, v: float) -> None:
        """At ``frame``, ``joint`` is at pixel ``(u, v)`` (x right, y down)."""
        if joint not in JOINT_INDEX:
            raise ValueError(f"unknown joint {joint!r}; expected one of {JOINT_NAMES}")
        u, v = float(u), float(v)
        if not (abs(u) <= MAX_PIXELS and abs(v) <= MAX_PIXELS):  # also NaN
            raise ValueError(f"joint position must be pixels within +-{MAX_PIXELS:g}")
        self._put(Event(self._frame(frame), "joint", joint, (u, v)))

    def add_sides(self, frame: int, pair: str, swapped: bool) -> None:
        """From ``frame`` on, the 3D stage's left and right ``pair`` (``'arms'`` or
        ``'legs'``) are ``swapped`` (True) or as the 2D stage named them (False)."""
        if pair not in PAIRS:
            raise ValueError(f"unknown limb pair {pair!r}; expected one of {PAIRS}")
        if not isinstance(swapped, (bool, np.bool_)):
            raise ValueError(f"swapped must be True or False, got {swapped!r}")
        self._put(Event(self._frame(frame), "sides", pair, bool(swapped)))

    def add_scene_region(self, frame: int, *, box=None, polygon=None) -> str:
        """Pixels that are never the person, for the whole clip: a ``box`` ``(x0, y0, x1,
        y1)`` (integer pixel edges, x1 and y1 exclusive) or a ``polygon`` of ``(x, y)``
        points; ``frame`` is where it was drawn. Returns the event's key (for
        :meth:`remove`)."""
        if (box is None) == (polygon is None):
            raise ValueError("a scene region is a box or a polygon (give one)")
        value = check_box(box) if box is not None else check_polygon(polygon)
        key = region_key(value)
        self._put(Event(self._frame(frame), "scene_region", key, value))
        return key

    def add_person_box(self, frame: int, box) -> None:
        """At ``frame``, the person is inside ``box`` ``(x0, y0, x1, y1)`` (replaces an
        earlier person box at that frame)."""
        self._put(Event(self._frame(frame), "person_box", "", check_box(box)))

    def region_events(self) -> list[Event]:
        """The events that change the silhouettes (:data:`REGION_TYPES`), sorted."""
        return [e for e in self.events if e.type in REGION_TYPES]

    def check_frame_size(self, width: int, height: int, source="<annotations>") -> None:
        """Raise :class:`AnnotationError` (naming ``source``) for a region reaching
        beyond a ``width`` x ``height`` frame."""
        for e in self.region_events():
            x, y = _region_extent(e)
            if x > width or y > height:
                shape = e.to_json()
                what = shape.get("box", "polygon")
                raise AnnotationError(
                    f"the {e.type} at frame {e.frame} ({what}) reaches beyond the "
                    f"{width}x{height} frame (x up to {width}, y up to {height})", source)

    def remove(self, frame: int, type: str, key: str = "") -> bool:
        """Remove the event at ``frame`` of ``type`` for ``key``; return whether one was."""
        return self._events.pop((int(frame), type, key), None) is not None

    @property
    def events(self) -> list[Event]:
        """All events sorted by frame, then type and key."""
        return sorted(self._events.values(), key=lambda e: (e.frame, e.type, e.key))

    @property
    def n_user_inputs(self) -> int:
        """Number of events (the seed's count of user inputs, section 4.3)."""
        return len(self._events)

    def __len__(self) -> int:
        return len(self._events)

    def __eq__(self, other) -> bool:
        return isinstance(other, Annotations) and self.events == other.events

    # ------------------------------------------------------------------ resolving
    def resolve(self, n_frames: int, *, near_plane=None):
        """Carry the events forward over ``n_frames`` frames.

        Parameters
        ----------
        n_frames : int
            Frames in the clip.
        near_plane : array_like of bool, shape (F, 10), optional
            Where each segment lies near the image plane. When given, a depth event
            also ends where its segment next *enters* the near-plane zone after
            having been out of it.

        Returns
        -------
        signs : numpy.ndarray of int8, shape (F, 10)
            User depth signs, 0 where the user gave none (use the proposal).
        orientation : numpy.ndarray of str, shape (F,)
            User orientation, ``""`` before the first orientation event.
        joints : numpy.ndarray, shape (F, 15, 2)
            User joint positions in pixels, NaN where none.
        """
        F = int(n_frames)
        signs = np.zeros((F, len(SEGMENT_NAMES)), dtype=np.int8)
        orient = np.full(F, "", dtype=object)
        joints = np.full((F, len(JOINT_NAMES), 2), np.nan)
        enter = None
        if near_plane is not None:
            npl = np.asarray(near_plane, dtype=bool)
            if npl.shape != signs.shape:
                raise ValueError(f"near_plane must be ({F}, 10), got {npl.shape}")
            enter = np.zeros_like(npl)
            enter[1:] = npl[1:] & ~npl[:-1]
        evs = [e for e in self.events if e.frame < F]
        by_seg: dict[str, list[Event]] = {}
        for e in evs:
            if e.type == "orientation":
                orient[e.frame:] = e.value
            elif e.type == "sides" or e.type in REGION_TYPES:
                continue  # see sides(); regions are the silhouette stage's
            elif e.type == "joint":
                joints[e.frame, JOINT_INDEX[e.key]] = e.value
            else:
                by_seg.setdefault(e.key, []).append(e)
        for seg, lst in by_seg.items():
            k = SEGMENT_INDEX[seg]
            for n, e in enumerate(lst):
                stop = lst[n + 1].frame if n + 1 < len(lst) else F
                if enter is not None and e.value != 0:
                    hits = np.flatnonzero(enter[e.frame + 1:stop, k])
                    if hits.size:
                        stop = e.frame + 1 + int(hits[0])
                signs[e.frame:stop, k] = e.value
        return signs, orient.astype(str), joints

    def sides(self, n_frames: int) -> np.ndarray:
        """Which limb pairs the user swapped, per frame.

        Returns
        -------
        numpy.ndarray of bool, shape (F, 2)
            Columns :data:`PAIRS` (arms, legs): True where the pair's left and right
            are to be exchanged (each sides event holds until the pair's next one).
        """
        F = int(n_frames)
        out = np.zeros((F, len(PAIRS)), dtype=bool)
        for e in self.events:  # sorted by frame: later events overwrite
            if e.type == "sides" and e.frame < F:
                out[e.frame:, PAIRS.index(e.key)] = e.value
        return out

    def sides_set(self, n_frames: int) -> np.ndarray:
        """(F, 2) bool: the (frame, pair) a sides event covers (from the pair's first
        event on), whichever way it set them (columns :data:`PAIRS`)."""
        F = int(n_frames)
        out = np.zeros((F, len(PAIRS)), dtype=bool)
        for e in self.events:
            if e.type == "sides" and e.frame < F:
                out[e.frame:, PAIRS.index(e.key)] = True
        return out

    # ------------------------------------------------------------------ files
    def to_json(self) -> dict:
        """The whole file as a JSON-ready dict."""
        return {"version": FORMAT_VERSION, "events": [e.to_json() for e in self.events]}

    def save(self, path: str | os.PathLike) -> None:
        """Write the file atomically: a failure leaves any existing file untouched."""
        text = json.dumps(self.to_json(), indent=1) + "\n"
        write_text_atomic(path, text)

    @classmethod
    def load(cls, path: str | os.PathLike, n_frames: int | None = None, *,
             frame_size: tuple[int, int] | None = None) -> Annotations:
        """Read and validate an annotations file.

        Parameters
        ----------
        path : str or path-like
        n_frames : int, optional
            Frames in the clip; events at or beyond it are errors.
        frame_size : (int, int), optional
            The frames' width and height in pixels; regions beyond them are errors.

        Raises
        ------
        vidcap.errors.AnnotationError
            One line naming the file and the bad entry.
        """
        p = Path(path)
        try:
            text = p.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise AnnotationError("no such annotations file", p) from None
        except (OSError, UnicodeDecodeError) as exc:
            raise AnnotationError(f"cannot read: {exc}", p) from None
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise AnnotationError(
                f"not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})", p
            ) from None
        return cls.from_json(data, n_frames=n_frames, source=p, frame_size=frame_size)

    @classmethod
    def from_json(cls, data, *, n_frames: int | None = None, source="<annotations>",
                  frame_size: tuple[int, int] | None = None):
        """Validate a decoded JSON document (see :meth:`load`)."""
        def fail(msg):
            raise AnnotationError(msg, source)

        if not isinstance(data, dict):
            fail("the top level must be an object with 'version' and 'events'")
        extra = set(data) - {"version", "events", "video", "n_frames"}
        if extra:
            fail(f"unknown top-level key(s) {sorted(extra)}")
        if data.get("version") != FORMAT_VERSION:
            fail(f"'version' must be {FORMAT_VERSION}, got {data.get('version')!r}")
        events = data.get("events")
        if not isinstance(events, list):
            fail("'events' must be a list")
        out = cls()
        seen = set()
        for n, ev in enumerate(events):
            where = f"events[{n}]"
            if not isinstance(ev, dict):
                fail(f"{where}: must be an object, got {type(ev).__name__}")
            typ = ev.get("type")
            if typ not in _KEYS:
                fail(f"{where}: 'type' must be one of {sorted(_KEYS)}, got {typ!r}")
            missing = _KEYS[typ] - set(ev)
            if missing:
                fail(f"{where}: {typ} event lacks {sorted(missing)}")
            unknown = set(ev) - _KEYS[typ] - ({"box", "polygon"} if typ == "scene_region"
                                              else set())
            if unknown:
                fail(f"{where}: unknown key(s) {sorted(unknown)} in a {typ} event")
            frame = ev["frame"]
            if isinstance(frame, bool) or not isinstance(frame, int) or frame < 0:
                fail(f"{where}: 'frame' must be a non-negative integer, got {frame!r}")
            if n_frames is not None and frame >= n_frames:
                fail(f"{where}: frame {frame} is out of range (the clip has {n_frames} frames)")
            if typ == "orientation":
                if ev["value"] not in ORIENTATIONS:
                    fail(f"{where}: orientation {ev['value']!r} is not one of {list(ORIENTATIONS)}")
                e = Event(frame, typ, "", ev["value"])
            elif typ == "depth":
                if ev["segment"] not in SEGMENT_INDEX:
                    fail(f"{where}: unknown segment {ev['segment']!r}"
                         f" (expected one of {', '.join(SEGMENT_NAMES)})")
                if ev["value"] not in _DEPTH_VALUES:
                    fail(f"{where}: depth value {ev['value']!r} is not toward, away or auto")
                e = Event(frame, typ, ev["segment"], _DEPTH_VALUES[ev["value"]])
            elif typ in REGION_TYPES:
                try:
                    e = _region_event(frame, typ, ev)
                except ValueError as exc:
                    fail(f"{where}: {typ}: {exc}")
            elif typ == "sides":
                if ev["pair"] not in PAIRS:
                    fail(f"{where}: unknown limb pair {ev['pair']!r} (expected arms or legs)")
                if ev["value"] not in _SIDES_VALUES:
                    fail(f"{where}: sides value {ev['value']!r} is not swapped or as_fitted")
                e = Event(frame, typ, ev["pair"], ev["value"] == "swapped")
            else:
                if ev["joint"] not in JOINT_INDEX:
                    fail(f"{where}: unknown joint {ev['joint']!r}"
                         f" (expected one of {', '.join(JOINT_NAMES)})")
                uv = (ev["u"], ev["v"])
                if not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                           and abs(x) <= MAX_PIXELS for x in uv):
                    fail(f"{where}: 'u' and 'v' must be finite numbers of pixels within"
                         f" +-{MAX_PIXELS:g}, got {uv!r}")
                e = Event(frame, typ, ev["joint"], (float(uv[0]), float(uv[1])))
            key = (e.frame, e.type, e.key)
            if key in seen:
                fail(f"{where}: a second {typ} event for {e.key or 'the body'} at frame {frame}")
            seen.add(key)
            out._put(e)
        if frame_size is not None:
            out.check_frame_size(*frame_size, source=source)
        return out


def _region_event(frame: int, typ: str, ev: dict) -> Event:
    """A scene_region or person_box event from its JSON object (ValueError if bad)."""
    if typ == "person_box":
        return Event(frame, typ, "", check_box(ev["box"]))
    if ("box" in ev) == ("polygon" in ev):
        raise ValueError("needs one of 'box' [x0, y0, x1, y1] or 'polygon' [[x, y], ...]")
    value = check_box(ev["box"]) if "box" in ev else check_polygon(ev["polygon"])
    return Event(frame, typ, region_key(value), value)


def default_path(video: str | os.PathLike) -> Path:
    """Where annotations for ``video`` live by default: ``VIDEO_STEM.vidcap.json`` beside it."""
    v = Path(video)
    return v.with_name(v.stem + ".vidcap.json")
