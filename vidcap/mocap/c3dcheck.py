"""Check a C3D file's header and parameter section in Python before ezc3d reads it.

ezc3d trusts the counts, dimensions, rates and sizes a file declares: a parameter with
255 dimensions, or an analog channel count in the tens of thousands, crashes the whole
process inside the reader (SIGSEGV), and an absurd frame count makes it allocate tens of
gigabytes. This module walks the same structures with bounds checks against the file's
own length, so ezc3d only ever sees a file whose declared sizes it can hold: the data
the header and parameters describe must fit in the bytes the file has, hence memory is
bounded by a small multiple of the file's size.

The layout (C3D.org, "The C3D File Format User Guide"): a 512-byte header block; a
parameter section of 512-byte blocks of group and parameter records; a data section of
frames, each ``points x 4`` values then ``analog`` values, int16 or float32 (a negative
scale factor) in the processor's byte order (Intel, DEC or MIPS).
"""

from __future__ import annotations

import math
import os
import struct
from dataclasses import dataclass, field

from vidcap.errors import C3DError

BLOCK = 512
#: Processor type byte (parameter section byte 4) -> byte order of integers.
_PROCESSORS = {84: "<", 85: "<", 86: ">"}  # Intel, DEC, MIPS
#: Parameter data types: -1 char, 1 byte, 2 int16, 4 float32.
_TYPES = {-1: 1, 1: 1, 2: 2, 4: 4}
#: The spec allows 0..7 dimensions.
MAX_DIMS = 7
#: Frame and analog rates a motion-capture system can record at, Hz.
MAX_POINT_RATE = 1e5
MAX_ANALOG_RATE = 1e7
#: Bytes of data a file may declare beyond what it holds (a cut recording).
MAX_DECLARED_DATA = 64 << 20


@dataclass
class C3DLayout:
    """What the header and parameter section declare (checked for consistency)."""

    n_points: int
    n_analog: int  # analog values per 3D frame (channels x samples per frame)
    n_frames: int
    float_data: bool
    data_start: int  # byte offset
    rate: float
    params: dict = field(default_factory=dict)  # (GROUP, NAME) -> tuple of values


def _float(raw: bytes, proc: int, order: str) -> float:
    if proc == 85:  # DEC: little-endian words swapped, exponent offset by 2
        return struct.unpack("<f", raw[2:4] + raw[0:2])[0] / 4.0
    return struct.unpack(order + "f", raw)[0]


def _param_values(body: bytes, ptype: int, dims: tuple[int, ...], proc: int, order: str):
    n = math.prod(dims) if dims else 1
    if ptype == -1:
        if len(dims) <= 1:
            return (body.decode("latin-1").strip(),)
        width = dims[0]
        if width == 0:
            return ()
        return tuple(body[i:i + width].decode("latin-1").strip()
                     for i in range(0, width * math.prod(dims[1:]), width))
    if ptype == 1:
        return tuple(body[:n])
    if ptype == 2:
        return struct.unpack(f"{order}{n}h", body[:2 * n])
    return tuple(_float(body[4 * i:4 * i + 4], proc, order) for i in range(n))


def _records(data: bytes, start: int, end: int, proc: int, order: str, path) -> dict:
    """Walk the group and parameter records; (GROUP, NAME) -> values of the small ones."""
    groups: dict[int, str] = {}
    params: list[tuple[int, str, tuple]] = []
    pos = start + 4
    for _ in range(100_000):
        if pos + 2 > end:
            break
        nlen, gid = struct.unpack("bb", data[pos:pos + 2])
        nlen = abs(nlen)
        if nlen == 0:
            break
        name_end = pos + 2 + nlen
        if name_end + 2 > end:
            raise C3DError(f"parameter record at byte {pos} runs past the parameter"
                           f" section (byte {end})", path)
        name = data[pos + 2:name_end].decode("latin-1").strip().upper()
        (offset,) = struct.unpack(order + "h", data[name_end:name_end + 2])
        body = name_end + 2
        if gid < 0:
            groups[-gid] = name
        elif gid > 0:
            if body + 2 > end:
                raise C3DError(f"parameter {name!r} runs past the parameter section", path)
            ptype, ndims = struct.unpack("bb", data[body:body + 2])
            if ptype not in _TYPES:
                raise C3DError(f"parameter {name!r} has data type {ptype}"
                               " (expected -1, 1, 2 or 4)", path)
            if not 0 <= ndims <= MAX_DIMS:
                raise C3DError(f"parameter {name!r} declares {ndims} dimensions"
                               f" (at most {MAX_DIMS})", path)
            if body + 2 + ndims > end:
                raise C3DError(f"parameter {name!r} runs past the parameter section", path)
            dims = tuple(data[body + 2:body + 2 + ndims])
            size = _TYPES[ptype] * (math.prod(dims) if dims else 1)
            vstart = body + 2 + ndims
            if vstart + size > end:
                raise C3DError(f"parameter {name!r} declares dimensions {list(dims)}"
                               f" ({size} bytes) past the parameter section", path)
            if size <= 65536:
                params.append((gid, name, _param_values(data[vstart:vstart + size], ptype,
                                                        dims, proc, order)))
        if offset == 0:
            break
        nxt = name_end + offset
        if nxt > end or offset < 0:
            raise C3DError(f"parameter record {name!r} points to byte {nxt}, outside"
                           f" the parameter section (bytes {start}..{end})", path)
        pos = nxt
    return {(groups.get(g, f"#{g}"), n): v for g, n, v in params}


def _count(params, key, default):
    v = params.get(key)
    if not v or isinstance(v[0], str):
        return default
    return int(v[0]) & 0xFFFF if v[0] < 0 else int(v[0])  # counts are stored unsigned


def _first_number(params, key, default: float) -> float:
    v = params.get(key)
    return float(v[0]) if v and not isinstance(v[0], str) else float(default)


def _check_rate(value, field_name: str, top: float, path, *, zero_ok: bool = False) -> None:
    ok = math.isfinite(value) and (0 < value <= top or (zero_ok and value == 0))
    if not ok:
        raise C3DError(f"{field_name} {value!r} Hz is outside 0..{top:g} Hz", path)


def check_c3d(path: str | os.PathLike) -> C3DLayout:
    """Check the header and parameter section of a C3D file against its length.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    C3DLayout
        The declared counts, once they are known to fit in the file.

    Raises
    ------
    C3DError
        A count, dimension, rate, scale or size the file cannot hold, named.
    """
    size = os.path.getsize(path)
    if size < BLOCK + 4:
        raise C3DError(f"{size} bytes: too short for a C3D file", path)
    with open(path, "rb") as fh:
        head = fh.read(BLOCK)
        if head[1] != 0x50:
            raise C3DError("not a C3D file (byte 2 of the header is not 0x50)", path)
        pblock = head[0]
        if pblock < 2 or (pblock - 1) * BLOCK + 4 > size:
            raise C3DError(f"the header puts the parameters in block {pblock}, outside the"
                           " file", path)
        fh.seek((pblock - 1) * BLOCK)
        phead = fh.read(4)
        proc = phead[3]  # the spec writes 83 + processor number (1 Intel, 2 DEC, 3 MIPS)
        if proc not in _PROCESSORS:
            raise C3DError(f"unknown processor type {phead[3]} in the parameter section"
                           " (expected 84 Intel, 85 DEC or 86 MIPS)", path)
        order = _PROCESSORS[proc]
        nblocks = phead[2]
        start = (pblock - 1) * BLOCK
        end = min(start + max(nblocks, 1) * BLOCK, size)
        fh.seek(start)
        psection = fh.read(end - start)
    params = _records(psection, 0, len(psection), proc, order, path)

    n_points, n_analog, first, last, _gap = struct.unpack(order + "5H", head[2:12])
    scale = _float(head[12:16], proc, order)
    (data_block,) = struct.unpack(order + "H", head[16:18])
    rate = _float(head[20:24], proc, order)
    n_points = _count(params, ("POINT", "USED"), n_points)
    frames = last - first + 1 if last >= first else 0
    frames = _count(params, ("POINT", "FRAMES"), frames)  # ezc3d prefers the parameter
    data_block = data_block or _count(params, ("POINT", "DATA_START"), 0)
    if not math.isfinite(scale) or scale == 0 or abs(scale) > 1e6:
        raise C3DError(f"header scale factor {scale!r} is absurd", path)
    _check_rate(rate, "header frame rate", MAX_POINT_RATE, path, zero_ok=frames <= 1)
    for key, top in ((("POINT", "RATE"), MAX_POINT_RATE), (("ANALOG", "RATE"), MAX_ANALOG_RATE)):
        v = params.get(key)
        if v and not isinstance(v[0], str):
            _check_rate(float(v[0]), ":".join(key), top, path, zero_ok=key[0] == "ANALOG")
    pscale = params.get(("POINT", "SCALE"))
    if pscale and not isinstance(pscale[0], str):
        s = float(pscale[0])
        if not math.isfinite(s) or s == 0 or abs(s) > 1e3:
            raise C3DError(f"POINT:SCALE {s!r} is absurd (expected a small factor such as"
                           " -0.1 or 0.01)", path)
    float_data = scale < 0
    analog_used = _count(params, ("ANALOG", "USED"), 0)
    if analog_used > max(n_analog, 0):
        raise C3DError(f"ANALOG:USED says {analog_used} channels but the header has room"
                       f" for {n_analog} analog values per frame", path)
    for name in ("SCALE", "OFFSET", "LABELS"):
        v = params.get(("ANALOG", name))
        if analog_used and v is not None and len(v) < analog_used:
            raise C3DError(f"ANALOG:{name} has {len(v)} entries for {analog_used} channels",
                           path)
    data_start = (data_block - 1) * BLOCK
    if data_block < 2 or data_start > size:
        raise C3DError(f"the data start block {data_block} lies outside the file", path)
    # ezc3d sizes its analog frames from ANALOG:RATE / POINT:RATE, not from the header
    point_rate = _first_number(params, ("POINT", "RATE"), rate)
    analog_rate = _first_number(params, ("ANALOG", "RATE"), 0.0)
    per_sample = round(analog_rate / point_rate) if analog_used and point_rate > 0 else 0
    n_analog_read = max(n_analog, per_sample * analog_used)
    per_frame = (4 * n_points + n_analog_read) * (4 if float_data else 2)
    need = per_frame * frames
    have = size - data_start
    # ezc3d reads a short data section up to its end (a cut recording keeps its frames),
    # so a shortfall is allowed while what it declares stays a modest allocation
    if need > max(have + BLOCK, MAX_DECLARED_DATA):
        raise C3DError(f"the header and parameters declare {frames} frames of {n_points}"
                       f" points and {n_analog_read} analog values ({need} bytes) but the file"
                       f" has {have} bytes of data", path)
    return C3DLayout(n_points=n_points, n_analog=n_analog, n_frames=frames,
                     float_data=float_data, data_start=data_start, rate=rate, params=params)
