"""Read Acclaim skeleton (ASF) and motion (AMC) files, as in the CMU mocap database.

Each ASF bone b has a rest ``direction`` and ``length`` in the global frame, a local
``axis`` (Euler angles and their order) giving its frame C_b, and the rotational
degrees of freedom the AMC file animates. The AMC values M_b (rotations about the
bone's own axes, applied x then y then z) give the bone's local rotation

    L_b = C_b @ M_b @ C_b^-1,     R_b = R_parent(b) @ L_b,

and the bone's far end is ``p_parent_end + R_b @ (direction * length)``.

We map this onto :class:`vidcap.kinematics.Motion`: one joint per ASF bone at the
bone's *near* end (where its rotation acts), plus the root. A joint's offset is its
parent bone's rest vector; the far end of a leaf bone is that joint's End Site.

Units: the ASF ``:units`` block's ``length`` is a divisor to inches
(CMU: ``length 0.45`` means 1 unit = 1/0.45 inch); AMC root translations use the
same unit. Everything returned is in metres.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from vidcap.errors import MotionFileError
from vidcap.kinematics import Motion, Skeleton

_INCH_M = 0.0254
#: Longer than this no bone of a human is, metres.
MAX_BONE_M = 10.0


def _read(path) -> list[str]:
    try:
        return Path(path).read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as exc:
        raise MotionFileError(f"cannot read file: {exc.strerror or exc}", path) from None


def _numbers(tokens, n: int, what: str) -> np.ndarray:
    """``n`` finite numbers of sane size from ``tokens``, else ValueError naming ``what``."""
    values = np.array([float(t) for t in tokens])
    if len(values) != n:
        raise ValueError(f"{what}: expected {n} numbers, got {len(values)}")
    if not (np.isfinite(values).all() and (np.abs(values) < 1e6).all()):
        raise ValueError(f"{what}: number out of range in {' '.join(tokens)!r}")
    return values


def _parse_asf(path):
    lines = _read(path)
    units = {"length": 1.0, "angle": "deg"}
    root = {"order": ["TX", "TY", "TZ", "RX", "RY", "RZ"], "axis": "XYZ",
            "position": np.zeros(3), "orientation": np.zeros(3)}
    bones: dict[str, dict] = {}
    hierarchy: dict[str, list[str]] = {}
    section = None
    current = None
    i = 0
    try:
        while i < len(lines):
            raw = lines[i].split("#", 1)[0]
            i += 1
            toks = raw.split()
            if not toks:
                continue
            if toks[0].startswith(":"):
                section = toks[0][1:]
                continue
            if section == "units" and len(toks) >= 2:
                units[toks[0]] = float(toks[1]) if toks[0] in ("length", "mass") else toks[1]
            elif section == "root":
                key = toks[0]
                if key == "order":
                    root["order"] = [t.upper() for t in toks[1:]]
                elif key == "axis":
                    root["axis"] = toks[1].upper()
                elif key in ("position", "orientation"):
                    root[key] = _numbers(toks[1:4], 3, key)
            elif section == "bonedata":
                key = toks[0]
                if key == "begin":
                    current = {"dof": [], "axis": np.zeros(3), "axis_order": "XYZ"}
                elif key == "end":
                    if current is None or "name" not in current:
                        raise ValueError("a bone without a name")
                    bones[current["name"]] = current
                    current = None
                elif current is not None:
                    if key == "name":
                        current["name"] = toks[1]
                    elif key == "direction":
                        current["direction"] = _numbers(toks[1:4], 3, key)
                    elif key == "length":
                        current["length"] = float(_numbers(toks[1:2], 1, key)[0])
                    elif key == "axis":
                        current["axis"] = _numbers(toks[1:4], 3, key)
                        current["axis_order"] = toks[4].upper() if len(toks) > 4 else "XYZ"
                    elif key == "dof":
                        current["dof"] = [t.lower() for t in toks[1:]]
            elif section == "hierarchy":
                if toks[0] in ("begin", "end"):
                    continue
                hierarchy.setdefault(toks[0], []).extend(toks[1:])
    except (ValueError, IndexError) as exc:
        raise MotionFileError(f"malformed ASF near line {i}: {exc}", path) from None
    if not bones or not hierarchy:
        raise MotionFileError("not an ASF skeleton (no :bonedata or :hierarchy)", path)
    for name, b in bones.items():
        if "direction" not in b or "length" not in b:
            raise MotionFileError(f"bone {name!r} lacks a direction or length", path)
    return units, root, bones, hierarchy


def _rotation(angles_deg, order: str) -> Rotation:
    # ASF axis/dof orders name rotations about fixed axes applied in sequence
    # (x then y then z for "XYZ"): extrinsic, scipy's lower-case orders.
    return Rotation.from_euler(order.lower(), angles_deg, degrees=True)


def read_asf_amc(
    asf_path: str | os.PathLike, amc_path: str | os.PathLike, *, fps: float = 120.0
) -> Motion:
    """Read a CMU-style ASF skeleton and AMC motion into a :class:`Motion` in metres.

    Parameters
    ----------
    asf_path, amc_path : str or path-like
        The skeleton and motion files.
    fps : float
        Frame rate (AMC files do not record it; the CMU database uses 120 Hz).

    Returns
    -------
    Motion
        Joints ``root`` plus one per ASF bone (named as in the file), located at the
        bone's near end; leaf bones' far ends are End Sites.

    Raises
    ------
    MotionFileError
        Missing or malformed files, or an AMC naming a bone the ASF lacks.
    """
    units, root, bones, hierarchy = _parse_asf(asf_path)
    try:
        length_unit = float(units.get("length", 1.0))
    except (TypeError, ValueError):
        length_unit = float("nan")
    if not (np.isfinite(length_unit) and length_unit > 0):
        raise MotionFileError(f":units length {units.get('length')!r} is not a positive"
                              " number", asf_path)
    scale = _INCH_M / length_unit
    deg = str(units.get("angle", "deg")).lower().startswith("deg")

    # Joint order: depth-first from the root, parents before children.
    names, parents, seen = ["root"], [-1], {"root"}
    stack = [(c, 0) for c in reversed(hierarchy.get("root", []))]
    while stack:
        name, parent = stack.pop()
        if name not in bones:
            raise MotionFileError(f"hierarchy names unknown bone {name!r}", asf_path)
        if name in seen:  # a cycle, or a bone with two parents: the walk would not end
            raise MotionFileError(f":hierarchy reaches bone {name!r} twice (a cycle or two"
                                  " parents)", asf_path)
        seen.add(name)
        idx = len(names)
        names.append(name)
        parents.append(parent)
        stack.extend((c, idx) for c in reversed(hierarchy.get(name, [])))
    J = len(names)
    vec = np.zeros((J, 3))  # each bone's rest vector, metres
    for j, n in enumerate(names[1:], 1):
        b = bones[n]
        norm = float(np.linalg.norm(b["direction"]))
        if not (np.isfinite(norm) and norm > 0):
            raise MotionFileError(f"bone {n!r} has direction {list(b['direction'])}"
                                  " (not a direction)", asf_path)
        if not (np.isfinite(b["length"]) and 0 <= b["length"] * scale <= MAX_BONE_M):
            raise MotionFileError(f"bone {n!r} has length {b['length']!r}: outside 0.."
                                  f"{MAX_BONE_M:g} m", asf_path)
        vec[j] = b["direction"] / norm * b["length"] * scale
    offsets = np.zeros((J, 3))
    offsets[0] = root["position"] * scale
    for j in range(1, J):
        offsets[j] = vec[parents[j]]  # root's "bone" has no length
    leaves = {names[j] for j in range(J) if j not in parents}
    ends = {n: vec[names.index(n)] for n in leaves if np.linalg.norm(vec[names.index(n)]) > 0}
    skeleton = Skeleton(tuple(names), tuple(parents), offsets, ends)

    frames = _parse_amc(amc_path, set(bones) | {"root"})
    F = len(frames)
    if F == 0:
        raise MotionFileError("no frames in AMC file", amc_path)
    to_deg = 1.0 if deg else 180.0 / np.pi

    rot = np.zeros((F, J, 4))
    rot[..., 3] = 1.0
    root_pos = np.zeros((F, 3))
    # Root: translation and rotation channels in the ASF ':root order'.
    rvals = _stack_values(frames, "root", len(root["order"]), amc_path)
    order = root["order"]
    for k, ax in enumerate("XYZ"):
        if f"T{ax}" in order:
            root_pos[:, k] = rvals[:, order.index(f"T{ax}")] * scale
    rot_axes = [c[1] for c in order if c.startswith("R")]
    rot_cols = [order.index(f"R{a}") for a in rot_axes]
    r_root = _rotation(rvals[:, rot_cols] * to_deg, "".join(rot_axes))
    r_root = _rotation(root["orientation"], root["axis"]) * r_root
    rot[:, 0] = r_root.as_quat()

    for j, n in enumerate(names[1:], 1):
        b = bones[n]
        C = _rotation(b["axis"], b["axis_order"])
        dof = [d for d in b["dof"] if d in ("rx", "ry", "rz")]
        if not dof:
            continue
        vals = _stack_values(frames, n, len(b["dof"]), amc_path, allow_missing=True)
        ang = np.zeros((F, 3))
        for k, d in enumerate(b["dof"]):
            if d in ("rx", "ry", "rz"):
                ang[:, "xyz".index(d[1])] = vals[:, k] * to_deg
        M = _rotation(ang, "xyz")
        rot[:, j] = (C * M * C.inv()).as_quat()
    # Root translation is the root joint's position; its offset already holds the
    # ASF rest position, so subtract nothing.
    return Motion(skeleton, root_pos, rot, fps)


def _parse_amc(path, known: set[str]) -> list[dict[str, list[float]]]:
    frames: list[dict[str, list[float]]] = []
    for lineno, line in enumerate(_read(path), 1):
        s = line.strip()
        if not s or s.startswith("#") or s.startswith(":"):
            continue
        toks = s.split()
        if len(toks) == 1 and toks[0].isdigit():
            frames.append({})
            continue
        if not frames:
            raise MotionFileError(f"line {lineno}: data before the first frame number", path)
        if toks[0] not in known:
            raise MotionFileError(f"line {lineno}: bone {toks[0]!r} is not in the ASF", path)
        try:
            values = [float(t) for t in toks[1:]]
        except ValueError:
            raise MotionFileError(f"line {lineno}: not a number in {s!r}", path) from None
        if not all(abs(v) < 1e6 for v in values):  # also NaN; angles and inches alike
            raise MotionFileError(f"line {lineno}: value out of range in {s[:80]!r}", path)
        frames[-1][toks[0]] = values
    return frames


def _stack_values(frames, name, n, path, allow_missing=False) -> np.ndarray:
    out = np.zeros((len(frames), n))
    for f, fr in enumerate(frames):
        v = fr.get(name)
        if v is None:
            if allow_missing:
                continue
            raise MotionFileError(f"frame {f + 1} has no {name!r} line", path)
        if len(v) != n:
            raise MotionFileError(
                f"frame {f + 1}: {name!r} has {len(v)} values, the ASF says {n}", path
            )
        out[f] = v
    return out
