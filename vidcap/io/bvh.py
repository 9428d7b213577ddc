"""Read and write Biovision Hierarchy (BVH) motion files.

Files we write: root channels ``Xposition Yposition Zposition Zrotation Xrotation
Yrotation``, every other joint ``Zrotation Xrotation Yrotation``; angles in degrees,
lengths in metres, Y up, -Z forward, root OFFSET ``0 0 0``, non-zero End Site
offsets, rest pose = the skeleton's T-pose, ``Frame Time`` = 1/fps.

The reader takes real files from other tools: any channel order per joint, position
channels on any joint, and lengths in any unit (``units='auto'`` picks metres,
centimetres, millimetres, inches or the CMU database's 1/0.45 inch from the
skeleton's size).

Channel semantics: for ``CHANNELS ... Zrotation Xrotation Yrotation`` the joint's
local rotation is ``Rz @ Rx @ Ry`` (rotations applied in the listed order to the
joint's frame, i.e. intrinsic), which is scipy's ``Rotation.from_euler('ZXY', ...)``.
"""

from __future__ import annotations

import io
import os
import re
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from vidcap.errors import MotionFileError
from vidcap.fileio import atomic_path
from vidcap.kinematics import Motion, Skeleton

#: Metres per unit for the units the reader knows.
UNIT_SCALES = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "inch": 0.0254,
    "cmu": 0.0254 / 0.45,  # CMU mocap database: ASF "length 0.45" => 1 unit = 1/0.45 inch
}

_ROT_AXES = {"Xrotation": "X", "Yrotation": "Y", "Zrotation": "Z"}
_POS_AXES = {"Xposition": 0, "Yposition": 1, "Zposition": 2}


# --------------------------------------------------------------------------- writing
def write_bvh(
    path: str | os.PathLike,
    motion: Motion,
    *,
    rotation_order: str = "ZXY",
    precision: int = 6,
) -> None:
    """Write ``motion`` to a BVH file atomically.

    Parameters
    ----------
    path : str or path-like
        Output file; written to a temporary file first and renamed, so a failure
        never leaves a partial file.
    motion : Motion
        F frames of a J-joint skeleton (metres, radians inside quaternions).
    rotation_order : str
        Euler order of the CHANNELS lines (default ``"ZXY"``: Zrotation Xrotation
        Yrotation). Angles are unwrapped over time, so there are no 360 degree jumps.
    precision : int
        Decimals written for every number.
    """
    text = bvh_text(motion, rotation_order=rotation_order, precision=precision)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def euler_degrees(quats: np.ndarray, order: str = "ZXY") -> np.ndarray:
    """Intrinsic Euler angles (degrees) of quaternions, unwrapped along axis 0.

    Parameters
    ----------
    quats : numpy.ndarray, shape (F, ..., 4)
        Unit quaternions (x, y, z, w).
    order : str
        Intrinsic axis order, e.g. ``"ZXY"``.

    Returns
    -------
    numpy.ndarray, shape (F, ..., 3)
        Angles in degrees in ``order``, continuous over frames.
    """
    q = np.asarray(quats, dtype=float)
    e1 = Rotation.from_quat(q.reshape(-1, 4)).as_euler(order.upper(), degrees=True)
    e1 = e1.reshape(q.shape[:-1] + (3,))
    # Every rotation has two Tait-Bryan solutions, (a, b, c) and (a+180, 180-b, c+180);
    # as_euler picks |b| <= 90, which jumps by ~180 degrees when the middle angle passes
    # 90. Follow the motion instead: per frame take whichever solution, shifted by
    # multiples of 360, lies nearest the previous frame's angles. The recursion runs
    # over frames and is vectorised over joints.
    e2 = e1 + np.array([180.0, 0.0, 180.0])
    e2[..., 1] = 180.0 - e1[..., 1]
    out = np.empty_like(e1)
    if len(e1) == 0:
        return out
    out[0] = e1[0]
    for f in range(1, len(e1)):
        prev = out[f - 1]
        c1 = e1[f] + 360.0 * np.round((prev - e1[f]) / 360.0)
        c2 = e2[f] + 360.0 * np.round((prev - e2[f]) / 360.0)
        d1 = np.abs(c1 - prev).sum(-1, keepdims=True)
        d2 = np.abs(c2 - prev).sum(-1, keepdims=True)
        out[f] = np.where(d2 < d1, c2, c1)
    return out


def bvh_text(motion: Motion, *, rotation_order: str = "ZXY", precision: int = 6) -> str:
    """The BVH file contents for ``motion`` (see :func:`write_bvh`)."""
    order = rotation_order.upper()
    if sorted(order) != ["X", "Y", "Z"]:
        raise ValueError(f"rotation_order must be a permutation of XYZ, got {rotation_order!r}")
    sk = motion.skeleton
    rot_channels = " ".join(f"{a}rotation" for a in order)
    fmt = f"{{:.{precision}f}}"

    def vec(v):
        return " ".join(fmt.format(x + 0.0) for x in v)

    lines = ["HIERARCHY"]

    def emit(j: int, depth: int):
        pad = "\t" * depth
        name = sk.joint_names[j]
        if sk.parents[j] < 0:
            lines.append(f"{pad}ROOT {name}")
            offset = np.zeros(3)  # root offset folds into the position channels
            channels = f"CHANNELS 6 Xposition Yposition Zposition {rot_channels}"
        else:
            lines.append(f"{pad}JOINT {name}")
            offset = sk.offsets[j]
            channels = f"CHANNELS 3 {rot_channels}"
        lines.append(f"{pad}{{")
        lines.append(f"{pad}\tOFFSET {vec(offset)}")
        lines.append(f"{pad}\t{channels}")
        kids = sk.children(j)
        for k in kids:
            emit(k, depth + 1)
        if not kids:
            end = sk.end_sites.get(name)
            if end is None or not np.linalg.norm(end) > 0:
                end = _default_end_site(sk, j)
            lines.append(f"{pad}\tEnd Site")
            lines.append(f"{pad}\t{{")
            lines.append(f"{pad}\t\tOFFSET {vec(end)}")
            lines.append(f"{pad}\t}}")
        lines.append(f"{pad}}}")

    emit(0, 0)
    F, J = motion.n_frames, sk.n_joints
    angles = euler_degrees(motion.rotations, order)  # (F, J, 3)
    root = motion.root_positions + sk.offsets[0]
    data = np.concatenate([root, angles.reshape(F, 3 * J)], axis=1)
    data[np.abs(data) < 0.5 * 10.0**-precision] = 0.0  # no "-0.000000"
    lines.append("MOTION")
    lines.append(f"Frames: {F}")
    lines.append(f"Frame Time: {1.0 / motion.fps:.8f}")
    buf = io.StringIO()
    np.savetxt(buf, data, fmt=f"%.{precision}f", delimiter=" ")
    return "\n".join(lines) + "\n" + buf.getvalue()


def _default_end_site(sk: Skeleton, j: int) -> np.ndarray:
    """A non-zero End Site continuing the bone into joint ``j`` by a quarter of its length."""
    off = sk.offsets[j]
    n = np.linalg.norm(off)
    return off * 0.25 if n > 0 else np.array([0.0, 0.05, 0.0])


# --------------------------------------------------------------------------- reading
_TOKEN = re.compile(r"\S+")


#: Larger than this no BVH angle (degrees) or offset (any unit) is.
MAX_VALUE = 1e7


def read_bvh(path: str | os.PathLike, *, units: str | float = "auto") -> Motion:
    """Read a BVH file into a :class:`Motion` in metres.

    Parameters
    ----------
    path : str or path-like
        The BVH file.
    units : {'auto', 'm', 'cm', 'mm', 'inch', 'cmu'} or float
        Length unit of the file, or metres per file unit. ``'auto'`` picks the unit
        that makes the rest skeleton's height closest to 1.7 m.

    Returns
    -------
    Motion
        Joints named as in the file (End Sites are kept as ``end_sites`` of their
        joint). Position channels on non-root joints are folded into the rotation-
        only representation by their first frame's value (they are rare and almost
        always constant).

    Raises
    ------
    MotionFileError
        If the file is missing or malformed; the message names the file and line.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise MotionFileError(f"cannot read BVH file: {exc.strerror or exc}", path) from None
    try:
        return parse_bvh(text, source=path, units=units)
    except RecursionError:
        raise MotionFileError("joints nested too deeply to be a skeleton", path) from None


def parse_bvh(text: str, *, source: str | os.PathLike = "<bvh>", units="auto") -> Motion:
    """Parse BVH ``text``; see :func:`read_bvh`."""
    head, sep, motion_part = text.partition("MOTION")
    if not sep or "HIERARCHY" not in head:
        raise MotionFileError("not a BVH file (no HIERARCHY ... MOTION sections)", source)
    h = _Hierarchy(_TOKEN.findall(head[head.index("HIERARCHY") + len("HIERARCHY"):]), source)
    h.parse()
    data, frame_time = _frame_values(motion_part, sum(len(c) for c in h.channels), source)
    rotations, root_pos, offsets = _channels_to_pose(data, h.channels, h.parents, h.offsets)
    # The root OFFSET and its position channels add (most readers, Blender included).
    skeleton = Skeleton(tuple(h.names), tuple(h.parents), offsets, h.ends)
    motion = Motion(skeleton, root_pos, rotations, 1.0 / frame_time)
    scale = _resolve_units(units, skeleton, source)
    if scale != 1.0:
        motion = Motion(skeleton.scaled(scale), root_pos * scale, rotations, motion.fps)
    return motion


class _Hierarchy:
    """The HIERARCHY section's tokens read into joints: ``names``, ``parents`` (index,
    -1 for the root), ``offsets`` (J, 3 list), ``channels`` (per joint, in file order)
    and ``ends`` (End Site offsets by joint name)."""

    def __init__(self, tokens: list[str], source):
        self.tokens, self.source, self.pos = tokens, source, 0
        self.names, self.parents, self.offsets, self.channels, self.ends = [], [], [], [], {}

    def parse(self) -> None:
        if not self.tokens or self.tokens[0] != "ROOT":
            raise MotionFileError("malformed hierarchy: it must start with ROOT", self.source)
        self.joint(-1)

    def expect(self, tok: str) -> None:
        tokens, pos = self.tokens, self.pos
        if pos >= len(tokens) or tokens[pos] != tok:
            got = tokens[pos] if pos < len(tokens) else "end of hierarchy"
            raise MotionFileError(f"malformed hierarchy: expected {tok!r}, got {got!r}",
                                  self.source)
        self.pos += 1

    def floats(self, n: int) -> list[float]:
        try:
            vals = [float(t) for t in self.tokens[self.pos : self.pos + n]]
        except ValueError:
            raise MotionFileError(
                f"malformed hierarchy: expected {n} numbers near {self.tokens[self.pos]!r}",
                self.source,
            ) from None
        if len(vals) != n:
            raise MotionFileError("malformed hierarchy: file ends inside an OFFSET",
                                  self.source)
        if not all(abs(v) <= MAX_VALUE for v in vals):  # also NaN
            raise MotionFileError(f"OFFSET {vals} beyond {MAX_VALUE:g}", self.source)
        self.pos += n
        return vals

    def joint(self, parent: int) -> None:
        """One ROOT/JOINT block with its children, or an End Site, from :attr:`pos`."""
        kind = self.tokens[self.pos]
        self.pos += 1
        if kind == "End":
            for tok in ("Site", "{", "OFFSET"):
                self.expect(tok)
            off = self.floats(3)
            self.expect("}")
            if parent >= 0:
                self.ends[self.names[parent]] = np.array(off)
            return
        name = self.tokens[self.pos]
        self.pos += 1
        if name in self.names:
            raise MotionFileError(f"joint {name!r} appears twice", self.source)
        idx = len(self.names)
        self.names.append(name)
        self.parents.append(parent)
        self.expect("{")
        self.expect("OFFSET")
        self.offsets.append(self.floats(3))
        self.expect("CHANNELS")
        self.channels.append(self.channel_list(name))
        while self.pos < len(self.tokens) and self.tokens[self.pos] in ("JOINT", "End"):
            self.joint(idx)
        self.expect("}")

    def channel_list(self, name: str) -> list[str]:
        """The count and names after ``CHANNELS``, checked."""
        try:
            n = int(self.tokens[self.pos])
        except (ValueError, IndexError):
            raise MotionFileError(f"malformed CHANNELS line for joint {name!r}",
                                  self.source) from None
        self.pos += 1
        chans = self.tokens[self.pos : self.pos + n]
        bad = [c for c in chans if c not in _ROT_AXES and c not in _POS_AXES]
        if len(chans) != n or bad:
            raise MotionFileError(f"bad channels for joint {name!r}: {bad or chans}",
                                  self.source)
        self.pos += n
        return chans


def _frame_values(motion_part: str, n_channels: int, source) -> tuple[np.ndarray, float]:
    """The MOTION section's values, (frames, n_channels), and its frame time in seconds."""
    m = re.search(r"Frames:\s*(\d+)\s*Frame Time:\s*([0-9.eE+-]+)", motion_part)
    if not m:
        raise MotionFileError("MOTION section lacks 'Frames:' and 'Frame Time:'", source)
    n_frames, frame_time = int(m.group(1)), float(m.group(2))
    if not 1e-5 <= frame_time <= 10:  # 100 kHz .. 0.1 Hz; also NaN
        raise MotionFileError(f"Frame Time {frame_time} s is outside 1e-05..10 s", source)
    try:
        values = np.array(motion_part[m.end():].split(), dtype=float)
    except ValueError:
        raise MotionFileError("MOTION data contains something that is not a number", source)\
            from None
    if not np.isfinite(values).all() or np.abs(values).max(initial=0) > MAX_VALUE:
        raise MotionFileError(f"MOTION data holds a value beyond {MAX_VALUE:g} (or not"
                              " finite)", source)
    if n_frames == 0 or values.size < n_frames * n_channels:
        have = values.size // max(n_channels, 1)
        raise MotionFileError(
            f"header says {n_frames} frames of {n_channels} channels but the file holds "
            f"{have} complete frames (truncated?)",
            source,
        )
    return values[: n_frames * n_channels].reshape(n_frames, n_channels), frame_time


def _channels_to_pose(data: np.ndarray, channels, parents, offsets):
    """Per-joint rotations (F, J, 4) quaternions (x, y, z, w), the root's position
    (F, 3) and the offsets (J, 3), a non-root joint's given by its position channels
    (their first frame) where it has them, from the frame values (F, n_channels) in
    file units (angles in degrees)."""
    n_frames = len(data)
    offsets_arr = np.array(offsets, dtype=float)
    rotations = np.empty((n_frames, len(channels), 4))
    root_pos = np.zeros((n_frames, 3))
    col = 0
    for j, chans in enumerate(channels):
        cols = np.arange(col, col + len(chans))
        col += len(chans)
        rot_idx = [i for i, c in enumerate(chans) if c in _ROT_AXES]
        pos_idx = [i for i, c in enumerate(chans) if c in _POS_AXES]
        if rot_idx:
            order = "".join(_ROT_AXES[chans[i]] for i in rot_idx)
            angles = data[:, cols[rot_idx]]
            if len(order) < 3:  # pad missing axes with zero rotation
                missing = [a for a in "XYZ" if a not in order]
                order += "".join(missing)
                angles = np.concatenate([angles, np.zeros((n_frames, len(missing)))], 1)
            rotations[:, j] = Rotation.from_euler(order, angles, degrees=True).as_quat()
        else:
            rotations[:, j] = (0.0, 0.0, 0.0, 1.0)
        if pos_idx:
            p = np.zeros((n_frames, 3))
            for i in pos_idx:
                p[:, _POS_AXES[chans[i]]] = data[:, cols[i]]
            if parents[j] < 0:
                root_pos = p
            else:
                offsets_arr[j] = p[0]
    return rotations, root_pos, offsets_arr


def _skeleton_extent(skeleton: Skeleton) -> float:
    pts = [skeleton.rest_positions()]
    rest = pts[0]
    for name, off in skeleton.end_sites.items():
        pts.append((rest[skeleton.index(name)] + off)[None])
    allp = np.concatenate(pts)
    return float(np.max(np.ptp(allp, axis=0)))


def _resolve_units(units, skeleton: Skeleton, source) -> float:
    if isinstance(units, int | float):
        return float(units)
    if units != "auto":
        try:
            return UNIT_SCALES[units]
        except KeyError:
            raise MotionFileError(
                f"unknown units {units!r}; use one of {sorted(UNIT_SCALES)} or a number", source
            ) from None
    extent = _skeleton_extent(skeleton)
    if not extent > 0:
        raise MotionFileError("the skeleton has no size (all offsets are zero)", source)
    # A T-pose's largest extent is its height or arm span, both ~1.7 m for an adult.
    best = min(UNIT_SCALES.values(), key=lambda s: abs(np.log(extent * s / 1.7)))
    return best
