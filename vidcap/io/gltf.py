"""Write (and read back) a skeletal motion as glTF 2.0: ``.glb``, or ``.gltf`` + ``.bin``.

What a file we write holds (glTF 2.0 specification, sections 3.7 Skins and 3.11
Animations):

* one node per joint, named as the skeleton names it, with the joint's rest offset as
  its ``translation`` (metres) and no rest rotation: the rest pose is the skeleton's
  T-pose; every End Site becomes one more (unanimated) leaf node, so that importers
  give the last bones of each chain a length;
* one skin over all those nodes, ``inverseBindMatrices`` the inverses of their rest
  world transforms, ``skeleton`` the root joint;
* a stick figure bound to the skin: per bone an octahedron from the joint to its
  child, weighted wholly to the joint, so that viewers and engines show something
  and Blender builds an armature;
* one animation: a ``rotation`` channel per joint (the motion's local rotations,
  LINEAR, neighbouring quaternions kept in one hemisphere) and a ``translation``
  channel for the root, sampled at the clip's frame times (seconds).

glTF is Y up with the front of a model toward +Z; our motions face -Z
(``../shared/design.md``), so :func:`write_gltf` turns a -Z-facing motion half a turn
about Y first (:func:`vidcap.io.rigs.face_plus_z`, the one place this conversion is
made). Written with numpy and the standard library: ``pygltflib`` would only wrap
the same JSON (see benchmarks/RESULTS.md, "glTF").
"""

from __future__ import annotations

import json
import os
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vidcap.errors import InputFileError, UsageError
from vidcap.fileio import atomic_path
from vidcap.kinematics import Motion

#: Extensions that select glTF output.
GLTF_SUFFIXES = (".glb", ".gltf")

_FLOAT, _USHORT, _UBYTE = 5126, 5123, 5121
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_GLB_MAGIC, _JSON_CHUNK, _BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942
_N_COMPONENTS = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}
#: Half-width of a bone's octahedron as a fraction of the bone's length, and its cap.
_BONE_WIDTH, _BONE_WIDTH_MAX = 0.1, 0.03


class _Buffer:
    """The binary buffer, its views and accessors as they are appended."""

    def __init__(self):
        self.chunks: list[bytes] = []
        self.size = 0
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def add(self, array: np.ndarray, kind: str, *, target: int | None = None,
            bounds: bool = False) -> int:
        """Append ``array`` as one accessor of ``kind``; return the accessor's index."""
        a = np.ascontiguousarray(array)
        ctype = {np.dtype(np.float32): _FLOAT, np.dtype(np.uint16): _USHORT,
                 np.dtype(np.uint8): _UBYTE}[a.dtype]
        data = a.tobytes()
        view = {"buffer": 0, "byteOffset": self.size, "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.views.append(view)
        pad = (-len(data)) % 4  # every view starts 4-byte aligned
        self.chunks.append(data + b"\0" * pad)
        self.size += len(data) + pad
        count = a.shape[0]
        acc = {"bufferView": len(self.views) - 1, "componentType": ctype, "count": int(count),
               "type": kind}
        if bounds:
            flat = a.reshape(count, _N_COMPONENTS[kind]).astype(float)
            acc["min"] = [float(v) for v in flat.min(0)]
            acc["max"] = [float(v) for v in flat.max(0)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def data(self) -> bytes:
        return b"".join(self.chunks)


def _continuous(quats: np.ndarray) -> np.ndarray:
    """Quaternions (F, J, 4) with each frame's sign chosen nearest the previous frame's,
    so LINEAR interpolation between samples takes the short way round."""
    q = np.array(quats, dtype=float)
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    flips = np.sum(q[1:] * q[:-1], axis=-1) < 0  # (F-1, J)
    sign = np.concatenate([np.ones((1,) + flips.shape[1:]),
                           np.cumprod(np.where(flips, -1.0, 1.0), axis=0)])
    return q * sign[..., None]


def _bone_mesh(rest: np.ndarray, parents: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An octahedron per bone in the rest pose: positions (V, 3), joint per vertex (V,),
    triangle indices (T*3,)."""
    tris = np.array([[0, 2, 3], [0, 3, 4], [0, 4, 5], [0, 5, 2],
                     [1, 3, 2], [1, 4, 3], [1, 5, 4], [1, 2, 5]])
    verts, joint, faces = [], [], []
    for child, p in enumerate(parents):
        if p < 0:
            continue
        a, b = rest[p], rest[child]
        axis = b - a
        length = float(np.linalg.norm(axis))
        if length < 1e-6:
            continue
        axis /= length
        side = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
        side /= np.linalg.norm(side)
        up = np.cross(axis, side)
        w = min(_BONE_WIDTH * length, _BONE_WIDTH_MAX)
        ring = a + 0.2 * length * axis
        pts = [a, b, ring + w * side, ring + w * up, ring - w * side, ring - w * up]
        faces.append(tris + len(verts))
        verts += pts
        joint += [p] * 6
    return (np.array(verts, dtype=np.float32), np.array(joint, dtype=np.uint16),
            np.concatenate(faces).reshape(-1).astype(np.uint16))


def gltf_document(motion: Motion, *, times=None, end_names=None,
                  name: str = "vidcap") -> tuple[dict, bytes]:
    """The glTF JSON and binary buffer for a +Z-facing ``motion``.

    Parameters
    ----------
    motion : Motion
        F frames, already facing +Z (see :func:`write_gltf`, which turns ours).
    times : array_like, shape (F,), optional
        Sample times in seconds, increasing; default ``arange(F) / fps``.
    end_names : mapping of str to str, optional
        Name of the End Site node of each leaf joint (default ``"<joint>_end"``).
    name : str
        Name of the skin, the mesh and the animation.

    Returns
    -------
    document : dict
        The glTF JSON (its one buffer has no ``uri``: add it for ``.gltf``).
    buffer : bytes
        The binary data, a multiple of 4 bytes long.
    """
    sk = motion.skeleton
    F, J = motion.n_frames, sk.n_joints
    t = np.arange(F) / motion.fps if times is None else np.asarray(times, dtype=float)
    if t.shape != (F,) or (np.diff(t) <= 0).any() or not np.isfinite(t).all():
        raise ValueError(f"times must be ({F},), finite and increasing")
    end_names = dict(end_names or {})
    names, parents = list(sk.joint_names), list(sk.parents)
    offsets = [np.asarray(o, dtype=float) for o in sk.offsets]
    for j, joint in enumerate(sk.joint_names):
        if joint in sk.end_sites and not sk.children(j):
            names.append(end_names.get(joint, f"{joint}_end"))
            parents.append(j)
            offsets.append(np.asarray(sk.end_sites[joint], dtype=float))
    n_nodes = len(names)
    rest = np.zeros((n_nodes, 3))
    for k, p in enumerate(parents):
        rest[k] = offsets[k] if p < 0 else rest[p] + offsets[k]

    buf = _Buffer()
    ibm = np.tile(np.eye(4), (n_nodes, 1, 1))
    ibm[:, :3, 3] = -rest  # rest world rotations are the identity
    ibm_acc = buf.add(np.swapaxes(ibm, 1, 2).astype(np.float32).reshape(n_nodes, 16), "MAT4")
    pos, joint, idx = _bone_mesh(rest, parents)
    joints4 = np.zeros((len(joint), 4), dtype=np.uint16)
    joints4[:, 0] = joint
    weights4 = np.zeros((len(joint), 4), dtype=np.float32)
    weights4[:, 0] = 1.0
    attributes = {
        "POSITION": buf.add(pos, "VEC3", target=_ARRAY_BUFFER, bounds=True),
        "JOINTS_0": buf.add(joints4, "VEC4", target=_ARRAY_BUFFER),
        "WEIGHTS_0": buf.add(weights4, "VEC4", target=_ARRAY_BUFFER),
    }
    indices = buf.add(idx, "SCALAR", target=_ELEMENT_ARRAY_BUFFER)

    time_acc = buf.add(t.astype(np.float32), "SCALAR", bounds=True)
    quats = _continuous(motion.rotations).astype(np.float32)
    samplers, channels = [], []
    for j in range(J):
        out = buf.add(quats[:, j], "VEC4")
        samplers.append({"input": time_acc, "output": out, "interpolation": "LINEAR"})
        channels.append({"sampler": j, "target": {"node": j, "path": "rotation"}})
    root = (motion.root_positions + sk.offsets[0]).astype(np.float32)
    samplers.append({"input": time_acc, "output": buf.add(root, "VEC3"),
                     "interpolation": "LINEAR"})
    channels.append({"sampler": J, "target": {"node": 0, "path": "translation"}})

    nodes = []
    for k in range(n_nodes):
        node = {"name": names[k], "translation": [float(v) for v in offsets[k]]}
        kids = [c for c in range(n_nodes) if parents[c] == k]
        if kids:
            node["children"] = kids
        nodes.append(node)
    nodes[0]["translation"] = [float(v) for v in root[0]]
    for j in range(J):
        nodes[j]["rotation"] = [float(v) for v in quats[0, j]]
    nodes.append({"name": f"{name}_figure", "mesh": 0, "skin": 0})
    data = buf.data()
    doc = {
        "asset": {"version": "2.0", "generator": f"vidcap {_version()}"},
        "scene": 0,
        "scenes": [{"name": name, "nodes": [0, n_nodes]}],
        "nodes": nodes,
        "skins": [{"name": name, "joints": list(range(n_nodes)), "skeleton": 0,
                   "inverseBindMatrices": ibm_acc}],
        "meshes": [{"name": f"{name}_figure",
                    "primitives": [{"attributes": attributes, "indices": indices, "mode": 4}]}],
        "animations": [{"name": name, "samplers": samplers, "channels": channels}],
        "buffers": [{"byteLength": len(data)}],
        "bufferViews": buf.views,
        "accessors": buf.accessors,
    }
    return doc, data


def _version() -> str:
    from vidcap import __version__

    return __version__


def glb_bytes(doc: dict, data: bytes) -> bytes:
    """A binary glTF (GLB) container: 12-byte header, JSON chunk, BIN chunk."""
    text = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    text += b" " * ((-len(text)) % 4)
    data = data + b"\0" * ((-len(data)) % 4)
    total = 12 + 8 + len(text) + 8 + len(data)
    return b"".join([
        struct.pack("<III", _GLB_MAGIC, 2, total),
        struct.pack("<II", len(text), _JSON_CHUNK), text,
        struct.pack("<II", len(data), _BIN_CHUNK), data,
    ])


def write_gltf(path: str | os.PathLike, motion: Motion, *, times=None, end_names=None,
               forward: str = "-Z", name: str = "vidcap") -> list[Path]:
    """Write ``motion`` as glTF 2.0, binary (``.glb``) or JSON + ``.bin`` (``.gltf``).

    Parameters
    ----------
    path : str or path-like
        Output file; its extension picks the container. ``.gltf`` also writes
        ``<stem>.bin`` beside it. Every file is written atomically.
    motion : Motion
        F frames of a J-joint skeleton, metres, Y up.
    times : array_like, shape (F,), optional
        Frame times in seconds (a variable-rate video's own); default ``arange(F)/fps``.
    end_names : mapping of str to str, optional
        Names of the End Site nodes by leaf joint (see :func:`gltf_document`).
    forward : {'-Z', '+Z'}
        Which way ``motion``'s rest pose faces; ``'-Z'`` (ours) is turned to glTF's +Z.
    name : str
        Name of the skin, mesh and animation.

    Returns
    -------
    list of Path
        The files written.
    """
    from vidcap.io.rigs import face_plus_z

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in GLTF_SUFFIXES:
        raise UsageError(f"a glTF file ends in .glb or .gltf, not {path.suffix!r}", path)
    if forward not in ("-Z", "+Z"):
        raise ValueError(f"forward must be '-Z' or '+Z', got {forward!r}")
    turned = face_plus_z(motion) if forward == "-Z" else motion
    doc, data = gltf_document(turned, times=times, end_names=end_names, name=name)
    if suffix == ".glb":
        with atomic_path(path) as tmp:
            tmp.write_bytes(glb_bytes(doc, data))
        return [path]
    bin_path = path.with_suffix(".bin")
    doc["buffers"][0]["uri"] = bin_path.name
    had_bin = bin_path.exists()
    with atomic_path(bin_path) as tmp:
        tmp.write_bytes(data)
    try:
        with atomic_path(path) as tmp:
            tmp.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    except BaseException:
        if not had_bin:  # no .bin left behind without the .gltf that names it
            bin_path.unlink(missing_ok=True)
        raise
    return [path, bin_path]


# --------------------------------------------------------------------------- reading
@dataclass(frozen=True)
class GltfMotion:
    """The skeleton and animation of a glTF file as :func:`read_gltf` finds them.

    Attributes
    ----------
    joint_names : tuple of str, length N
        The skin's joints, End Site nodes included.
    parents : tuple of int, length N
        Index (into ``joint_names``) of each joint's parent, -1 for the skeleton root.
    translations : numpy.ndarray, shape (N, 3)
        Rest translations of the joint nodes, metres.
    times : numpy.ndarray, shape (F,)
        Sample times of the first animation, seconds.
    rotations : numpy.ndarray, shape (F, N, 4)
        Local rotations (x, y, z, w) per sample; a joint without a rotation channel
        holds its node's rotation.
    root_translations : numpy.ndarray, shape (F, 3)
        The root's animated translation, metres.
    """

    joint_names: tuple[str, ...]
    parents: tuple[int, ...]
    translations: np.ndarray
    times: np.ndarray
    rotations: np.ndarray
    root_translations: np.ndarray


def _read_container(path: Path) -> tuple[dict, bytes]:
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise InputFileError(f"cannot read glTF file: {exc.strerror or exc}", path) from None
    try:
        if raw[:4] == b"glTF":
            _, _, total = struct.unpack_from("<III", raw, 0)
            n, kind = struct.unpack_from("<II", raw, 12)
            doc = json.loads(raw[20:20 + n])
            data = b""
            if 20 + n < total:
                m, _ = struct.unpack_from("<II", raw, 20 + n)
                data = raw[28 + n:28 + n + m]
            return doc, data
        doc = json.loads(raw)
        uri = doc["buffers"][0]["uri"]
        return doc, (path.parent / uri).read_bytes()
    except (ValueError, KeyError, IndexError, struct.error, OSError) as exc:
        raise InputFileError(f"not a glTF file we can read ({exc})", path) from None


def _accessor(doc: dict, data: bytes, index: int) -> np.ndarray:
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    dtype = {_FLOAT: np.float32, _USHORT: np.uint16, _UBYTE: np.uint8}[acc["componentType"]]
    n = _N_COMPONENTS[acc["type"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    arr = np.frombuffer(data, dtype=dtype, count=acc["count"] * n, offset=start)
    return arr.reshape(acc["count"], n) if n > 1 else arr


def read_gltf(path: str | os.PathLike) -> GltfMotion:
    """Read the skin and first animation of a glTF 2.0 file (``.glb`` or ``.gltf``).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    GltfMotion

    Raises
    ------
    InputFileError
        If the file cannot be read or has no skin and animation.
    """
    path = Path(path)
    doc, data = _read_container(path)
    try:
        return _parse_skin_animation(doc, data, path)
    except (KeyError, IndexError, TypeError, ValueError, AttributeError) as exc:
        raise InputFileError(f"glTF file without a readable skin and animation ({exc!r})",
                             path) from None


def _parse_skin_animation(doc: dict, data: bytes, path: Path) -> GltfMotion:
    joints = doc["skins"][0]["joints"]
    nodes = doc["nodes"]
    anim = doc["animations"][0]
    where = {node: k for k, node in enumerate(joints)}
    parents = [-1] * len(joints)
    for k, node in enumerate(joints):
        for child in nodes[node].get("children", []):
            if child in where:
                parents[where[child]] = k
    trans = np.array([nodes[n].get("translation", [0.0, 0.0, 0.0]) for n in joints], float)
    rest_rot = np.array([nodes[n].get("rotation", [0.0, 0.0, 0.0, 1.0]) for n in joints], float)
    times = None
    rot, root = {}, None
    for ch in anim["channels"]:
        sampler = anim["samplers"][ch["sampler"]]
        t = _accessor(doc, data, sampler["input"]).astype(float)
        times = t if times is None else times
        values = _accessor(doc, data, sampler["output"]).astype(float)
        k = where.get(ch["target"]["node"])
        if k is None:
            continue
        if ch["target"]["path"] == "rotation":
            rot[k] = values
        elif ch["target"]["path"] == "translation" and parents[k] < 0:
            root = values
    if times is None:
        raise InputFileError("glTF animation has no channels", path)
    F = len(times)
    rotations = np.broadcast_to(rest_rot, (F, len(joints), 4)).copy()
    for k, v in rot.items():
        rotations[:, k] = v
    root_t = np.broadcast_to(trans[0], (F, 3)).copy() if root is None else root
    return GltfMotion(tuple(nodes[n].get("name", str(n)) for n in joints), tuple(parents),
                      trans, times, rotations, root_t)


__all__ = ["GLTF_SUFFIXES", "GltfMotion", "gltf_document", "glb_bytes", "read_gltf",
           "write_gltf"]
