"""Hostile inputs and a capped CLI runner, for the robustness tests and benchmarks/fuzz.py.

:func:`c3d_set` rewrites one C3D header or parameter field in place (a count, a
dimension, a rate, a scale); :func:`run_capped` runs ``python -m vidcap`` in a child
process under an address-space cap and a timeout, and :func:`outcome` sorts what came
back into the classes the README promises never to show (a crash, a hang, a traceback,
a changed input, a stray file) or the two it allows (a clean one-line error, success).
"""

from __future__ import annotations

import hashlib
import os
import re
import resource
import signal
import struct
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]  # tests/hostile/ -> the checkout
#: Address-space cap of every run (the issue's 3 GiB).
CAP_BYTES = 3 << 30
OUTCOMES = ("clean error", "success", "crash", "hang", "traceback", "input changed",
            "stray file")


# ---------------------------------------------------------------- C3D fields
def _c3d_order(data: bytes) -> str:
    return ">" if data[(data[0] - 1) * 512 + 3] == 86 else "<"


def c3d_parameter_offset(data: bytes, group: str, name: str) -> tuple[int, int, int]:
    """(offset of the type byte, data type, number of dimensions) of ``GROUP:NAME``."""
    start = (data[0] - 1) * 512
    order = _c3d_order(data)
    pos, groups, found = start + 4, {}, []
    while pos + 2 < len(data):
        nlen, gid = struct.unpack("bb", data[pos:pos + 2])
        nlen = abs(nlen)
        if nlen == 0:
            break
        label = data[pos + 2:pos + 2 + nlen].decode("latin-1").upper()
        (off,) = struct.unpack(order + "h", data[pos + 2 + nlen:pos + 4 + nlen])
        body = pos + 4 + nlen
        if gid < 0:
            groups[-gid] = label
        else:
            found.append((gid, label, body))
        if off <= 0:
            break
        pos = pos + 2 + nlen + off
    for gid, label, body in found:
        if groups.get(gid) == group and label == name:
            return body, struct.unpack("b", data[body:body + 1])[0], data[body + 1]
    raise KeyError(f"{group}:{name}")


def c3d_set(data: bytes, field: str, value) -> bytes:
    """A copy of C3D ``data`` with one field rewritten.

    ``field`` is ``"header:points"``, ``"header:analog"``, ``"header:last"``,
    ``"header:rate"``, ``"header:scale"``, ``"GROUP:NAME"`` (the first value of a
    parameter, in its own type) or ``"GROUP:NAME:ndims"`` (its dimension count).
    """
    out = bytearray(data)
    order = _c3d_order(data)
    header = {"points": (2, "H"), "analog": (4, "H"), "first": (6, "H"), "last": (8, "H"),
              "scale": (12, "f"), "data_start": (16, "H"), "rate": (20, "f")}
    parts = field.split(":")
    if parts[0] == "header":
        off, fmt = header[parts[1]]
        struct.pack_into(order + fmt, out, off, value)
        return bytes(out)
    body, ptype, ndims = c3d_parameter_offset(data, parts[0], parts[1])
    if len(parts) == 3 and parts[2] == "ndims":
        out[body + 1] = int(value) & 0xFF
        return bytes(out)
    vstart = body + 2 + ndims
    fmt = {1: "B", 2: "h", 4: "f", -1: "c"}[ptype]
    struct.pack_into(order + fmt, out, vstart, value)
    return bytes(out)


# ---------------------------------------------------------------- running
@dataclass
class Run:
    """What one capped CLI run did."""

    returncode: int | None  # None: killed after the timeout
    stderr: str
    stdout: str
    seconds: float


def _cap():
    resource.setrlimit(resource.RLIMIT_AS, (CAP_BYTES, CAP_BYTES))
    os.setsid()  # a hang is killed with its workers


def run_capped(args, *, cwd: Path, timeout: float = 60.0, env=None) -> Run:
    """``python -m vidcap ARGS`` under :data:`CAP_BYTES` of address space and a timeout."""
    import time

    e = dict(os.environ if env is None else env)
    e["PYTHONPATH"] = str(REPO) + os.pathsep + e.get("PYTHONPATH", "")
    e.setdefault("OMP_NUM_THREADS", "1")
    t0 = time.monotonic()
    proc = subprocess.Popen([sys.executable, "-m", "vidcap", *map(str, args)], cwd=cwd,
                            env=e, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_cap)
    try:
        out, err = proc.communicate(timeout=timeout)
        rc = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        rc = None
    return Run(rc, err, out, time.monotonic() - t0)


def digest(paths) -> dict[str, str]:
    """SHA-256 of each file (to tell an input changed)."""
    return {str(p): hashlib.sha256(Path(p).read_bytes()).hexdigest() for p in paths}


def listing(folder: Path) -> set[str]:
    """Every file under ``folder``, relative."""
    return {str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file()}


def outcome(run: Run, *, name: str, inputs_before: dict, inputs_after: dict,
            files_before: set, files_after: set, allowed_new: set = frozenset()) -> str:
    """Classify a run as one of :data:`OUTCOMES` (the first problem found wins).

    A clean error is exit 2 with exactly one stderr line ``vidcap: error: ...`` naming
    the file ``name``.
    """
    if run.returncode is None:
        return "hang"
    if run.returncode < 0 or run.returncode > 128 and run.returncode != 130:
        return "crash"
    if "Traceback" in run.stderr:
        return "traceback"
    if inputs_after != inputs_before:
        return "input changed"
    if (files_after - files_before) - set(allowed_new):
        return "stray file"
    if run.returncode == 0:
        return "success"
    lines = [ln for ln in run.stderr.splitlines() if ln.strip()]
    errors = [ln for ln in lines if ln.startswith("vidcap: error: ")]
    if run.returncode == 2 and len(errors) == 1 and name in errors[0]:
        return "clean error"
    return "traceback"  # anything else is an unclean failure


def first_error(run: Run) -> str:
    """The ``vidcap: error:`` line of a run, or its last stderr line."""
    m = re.findall(r"^vidcap: error: .*$", run.stderr, re.M)
    return m[0] if m else (run.stderr.strip().splitlines() or [""])[-1]
