"""Mutated real files through their commands: the engine of tests/hostile/test_fuzz.py
(a seeded slice, in CI) and benchmarks/fuzz.py (thousands).

Every case is one mutation (truncation, byte flips, a header or parameter field set to
an extreme, a number token made absurd, a line dropped or repeated) of one real file
from ``../shared/data`` (or a marker set shipped with vidcap), run through the command
that reads it, in its own folder, in a child process under an address-space cap and a
timeout, and classified by :func:`tests.hostile.mutate.outcome`.

Children are forked from a process that has already imported vidcap (see
:func:`run_forked`), so a case costs its work, not an interpreter start-up; the cap is
set in the child before the command runs, as ``preexec_fn`` would.
"""

from __future__ import annotations

import io
import os
import re
import resource
import signal
import struct
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tests.hostile.mutate import CAP_BYTES, REPO, Run, c3d_set, digest, listing, outcome

SHARED = REPO.parent / "shared" / "data"
MARKERSETS = REPO / "vidcap" / "mocap" / "markersets"
EXTREMES_INT = (0, 1, -1, 127, 255, 32767, -32768, 65535)
EXTREMES_FLOAT = (0.0, -1.0, 1e-30, 1e30, -3e38, float("nan"), float("inf"))
EXTREME_TOKENS = ("0", "-1", "1e308", "-1e308", "nan", "inf", "99999999999999999999",
                  "1e-320", "", "x", "[", "{", "}", "\"")
C3D_FIELDS = ("header:points", "header:analog", "header:first", "header:last",
              "header:scale", "header:rate", "header:data_start", "POINT:USED",
              "POINT:FRAMES", "POINT:SCALE", "POINT:RATE", "POINT:DATA_START",
              "POINT:LABELS:ndims", "POINT:SCALE:ndims", "ANALOG:USED", "ANALOG:RATE",
              "ANALOG:USED:ndims")


# ---------------------------------------------------------------- mutations
def truncate(data: bytes, rng) -> bytes:
    return data[: int(rng.integers(0, max(1, len(data))))]


def flip_bytes(data: bytes, rng, *, head: int | None = None) -> bytes:
    """Flip 1..8 random bytes (within the first ``head`` bytes when given)."""
    out = bytearray(data)
    span = min(len(out), head or len(out))
    for _ in range(int(rng.integers(1, 9))):
        i = int(rng.integers(0, max(1, span)))
        if out:
            out[i] ^= int(rng.integers(1, 256))
    return bytes(out)


def c3d_field(data: bytes, rng) -> bytes:
    """One C3D header or parameter field set to an extreme value of its type."""
    for _ in range(10):
        field = C3D_FIELDS[int(rng.integers(len(C3D_FIELDS)))]
        extremes = (EXTREMES_FLOAT if field.split(":")[-1] in ("scale", "rate", "SCALE",
                                                                 "RATE") else EXTREMES_INT)
        value = extremes[int(rng.integers(len(extremes)))]
        try:
            return c3d_set(data, field, _fit(field, value))
        except (KeyError, struct.error, IndexError, ValueError):
            continue  # the file has no such parameter
    return flip_bytes(data, rng, head=2048)


def _fit(field: str, value):
    if field.startswith("header:") and field not in ("header:scale", "header:rate"):
        return int(value) & 0xFFFF
    if field.endswith(":ndims"):
        return int(value) & 0xFF
    return value


def text_token(data: bytes, rng) -> bytes:
    """One number-like token of a text file replaced by an extreme or broken one."""
    text = data.decode("latin-1")
    spans = [m.span() for m in re.finditer(r"-?\d+(\.\d+)?(e[-+]?\d+)?", text[:200_000])]
    if not spans:
        return flip_bytes(data, rng)
    a, b = spans[int(rng.integers(len(spans)))]
    new = EXTREME_TOKENS[int(rng.integers(len(EXTREME_TOKENS)))]
    return (text[:a] + new + text[b:]).encode("latin-1")


def text_lines(data: bytes, rng) -> bytes:
    """A line dropped, repeated (up to 1000 times) or swapped with another."""
    lines = data.decode("latin-1").splitlines(keepends=True)
    if len(lines) < 2:
        return flip_bytes(data, rng)
    i, j = (int(v) for v in rng.integers(0, len(lines), 2))
    kind = int(rng.integers(3))
    if kind == 0:
        del lines[i]
    elif kind == 1:
        lines[i:i] = [lines[i]] * int(rng.integers(1, 1000))
    else:
        lines[i], lines[j] = lines[j], lines[i]
    return "".join(lines).encode("latin-1")


BINARY = (truncate, flip_bytes, lambda d, r: flip_bytes(d, r, head=4096))
TEXT = (truncate, flip_bytes, text_token, text_token, text_lines)


# ---------------------------------------------------------------- targets
@dataclass(frozen=True)
class Target:
    """A real file, how to mutate it and the command that reads it."""

    name: str  # format label (the table's row)
    source: Path
    mutations: tuple
    argv: object  # (case folder, mutated file) -> argv
    companions: tuple = ()  # other real files copied beside it (name, source[, shrink])
    shrink: object = None  # bytes -> bytes applied before mutating (keep cases fast)


def _head_lines(n: int):
    def cut(data: bytes) -> bytes:
        return b"".join(data.splitlines(keepends=True)[:n])
    return cut


def _bvh_frames(n: int):
    def cut(data: bytes) -> bytes:
        text = data.decode("latin-1")
        head, _, motion = text.partition("MOTION")
        lines = motion.splitlines(keepends=True)
        frames = [ln for ln in lines[3:] if ln.strip()][:n]
        body = re.sub(r"Frames:\s*\d+", f"Frames: {n}", "".join(lines[:3]))
        return (head + "MOTION" + body + "".join(frames)).encode("latin-1")
    return cut


def _amc_frames(n: int):
    def cut(data: bytes) -> bytes:
        out, frames = [], 0
        for ln in data.splitlines(keepends=True):
            if ln.strip().isdigit():
                frames += 1
                if frames > n:
                    break
            out.append(ln)
        return b"".join(out)
    return cut


def targets(shared: Path = SHARED) -> list[Target]:
    """Every reader with its real source file and command (those whose file is here)."""
    synth = ["--size", "48x40", "--ppm", "20"]
    t = [
        Target("C3D", shared / "c3d" / "Optotrak.c3d", BINARY + (c3d_field,) * 3,
               lambda d, f: ["joints", f, "-o", d / "out" / "j.bvh"]),
        Target("C3D", shared / "c3d" / "07_01.c3d", BINARY + (c3d_field,) * 3,
               lambda d, f: ["joints", f, "--centres", d / "out" / "c.csv"]),
        Target("C3D", shared / "c3d" / "BTS.c3d", (c3d_field,) * 3 + BINARY,
               lambda d, f: ["joints", f, "-o", d / "out" / "j.bvh"]),
        Target("video", shared / "video" / "ido_walk.avi", BINARY,
               lambda d, f: ["info", f]),
        Target("video", REPO / "sample_videos" / "walk_side.mp4", BINARY,
               lambda d, f: ["info", f]),
        Target("BVH", shared / "motion" / "131_01.bvh", TEXT,
               lambda d, f: ["synth", "--motion", f, *synth, "-o", d / "out" / "c.mp4"],
               shrink=_bvh_frames(4)),
        Target("ASF/AMC", shared / "motion" / "07.asf", TEXT,
               lambda d, f: ["synth", "--motion", f, "--amc", d / "m.amc", *synth, "-o",
                             d / "out" / "c.mp4"],
               companions=(("m.amc", shared / "motion" / "07_07.amc", _amc_frames(4)),)),
        Target("ASF/AMC", shared / "motion" / "07_07.amc", TEXT,
               lambda d, f: ["synth", "--motion", d / "s.asf", "--amc", f, *synth, "-o",
                             d / "out" / "c.mp4"],
               companions=(("s.asf", shared / "motion" / "07.asf"),),
               shrink=_amc_frames(4)),
        Target("TOML", MARKERSETS / "cmu41.toml", TEXT,
               lambda d, f: ["joints", d / "t.c3d", "--markerset", f, "-o", d / "out" / "j.bvh"],
               companions=(("t.c3d", shared / "c3d" / "07_01.c3d"),)),
        # the sample clip itself (not a copy: its stage cache, beside the shared output
        # folder, is then computed once and every case only lifts)
        Target("JSON", REPO / "tests" / "hostile" / "walk_side.vidcap.json", TEXT,
               lambda d, f: ["convert", REPO / "sample_videos" / "walk_side.mp4",
                             "--annotations", f, "-o", d.parent / "convert-out" / "w.bvh",
                             "--quiet"]),
    ]
    return [x for x in t if x.source.exists() and all(c[1].exists() for c in x.companions)]


# ---------------------------------------------------------------- running
def preload() -> None:
    """Import what the commands import (and compile their kernels) once, in the parent,
    so each forked case pays only for its own work."""
    import importlib

    for name in ("vidcap.cli", "vidcap.commands.joints", "vidcap.commands.synth",
                 "vidcap.commands.convert", "vidcap.commands.info", "vidcap.mocap.c3d",
                 "vidcap.mocap.markerset", "vidcap.mocap.skeleton", "vidcap.synth",
                 "vidcap.video.pipeline", "vidcap.io.asf", "vidcap.io.bvh", "vidcap.io.video",
                 "ezc3d", "av", "scipy.optimize", "scipy.spatial"):
        try:
            importlib.import_module(name)
        except ImportError:
            pass
    try:
        from vidcap.video.fit.parallel import warm_up

        warm_up()
    except Exception:  # noqa: BLE001 - only a speed-up
        pass


def run_forked(argv, *, cwd: Path, timeout: float) -> Run:
    """``vidcap ARGV`` in a forked child under :data:`CAP_BYTES` and ``timeout``.

    A traceback escaping ``main`` is printed (and so classified) like the real CLI's;
    a crash shows as a negative return code (the signal).
    """
    from vidcap.cli import main

    r_err, w_err = os.pipe()
    t0 = time.monotonic()
    pid = os.fork()
    if pid == 0:  # the child: never returns
        code = 1
        try:
            os.setsid()
            os.chdir(cwd)
            os.dup2(w_err, 2)
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, 1)
            os.close(r_err)
            resource.setrlimit(resource.RLIMIT_AS, (CAP_BYTES, CAP_BYTES))
            sys.stdout, sys.stderr = open(1, "w"), open(2, "w")
            code = main([str(a) for a in argv])
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 2
        except BaseException:  # noqa: BLE001 - what the user would see
            traceback.print_exc()
            code = 1
        finally:
            try:
                sys.stderr.flush()
            except Exception:  # noqa: BLE001
                pass
            os._exit(code if isinstance(code, int) else 1)
    os.close(w_err)
    err = io.BytesIO()
    deadline = t0 + timeout
    status = None
    os.set_blocking(r_err, False)
    while True:
        try:
            chunk = os.read(r_err, 65536)
            if chunk:
                err.write(chunk[: max(0, 200_000 - err.tell())])
        except BlockingIOError:
            pass
        done, st = os.waitpid(pid, os.WNOHANG)
        if done:
            status = st
            break
        if time.monotonic() > deadline:
            try:
                os.killpg(pid, signal.SIGKILL)
            except OSError:
                os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            break
        time.sleep(0.005)
    try:
        while chunk := os.read(r_err, 65536):
            err.write(chunk[: max(0, 200_000 - err.tell())])
    except (BlockingIOError, OSError):
        pass
    os.close(r_err)
    try:  # workers of a finished case must not outlive it
        os.killpg(pid, signal.SIGKILL)
    except OSError:
        pass
    rc = None if status is None else os.waitstatus_to_exitcode(status)
    return Run(rc, err.getvalue().decode("utf-8", "replace"), "", time.monotonic() - t0)


def run_case(target: Target, mutation, rng, *, root: Path, timeout: float = 60.0,
             subprocess_runner=None) -> tuple[str, Run, Path]:
    """Mutate ``target.source`` once, run its command, return (outcome, run, folder)."""
    folder = Path(tempfile.mkdtemp(prefix="case-", dir=root))
    for name, src, *cut in target.companions:
        data = src.read_bytes()
        (folder / name).write_bytes(cut[0](data) if cut else data)
    data = target.source.read_bytes()
    if target.shrink is not None:
        data = target.shrink(data)
    bad = folder / f"fuzz{target.source.suffix}"
    bad.write_bytes(mutation(data, rng))
    inputs = sorted(p for p in folder.iterdir() if p.is_file())
    before, files = digest(inputs), listing(folder)
    argv = target.argv(folder, bad)
    if subprocess_runner is None:
        run = run_forked(argv, cwd=folder, timeout=timeout)
    else:
        run = subprocess_runner(argv, cwd=folder, timeout=timeout)
    after = listing(folder)
    allowed = {f for f in after if f.startswith(("out/", ".vidcap-cache/"))} \
        if run.returncode == 0 else {f for f in after if f.startswith(".vidcap-cache/")}
    # a companion (the other half of an ASF/AMC pair) may be what the error names
    names = [str(bad), *(str(folder / c[0]) for c in target.companions)]
    got = outcome(run, name=str(bad), inputs_before=before, inputs_after=digest(inputs),
                  files_before=files, files_after=after, allowed_new=allowed)
    if got == "traceback" and run.returncode == 2:
        lines = [ln for ln in run.stderr.splitlines() if ln.strip()]
        if len(lines) == 1 and lines[0].startswith("vidcap: error: ") and \
                any(n in lines[0] for n in names):
            got = "clean error"
    return got, run, folder


def mutation_plan(n: int, seed: int, shared: Path = SHARED):
    """``n`` (target, mutation, rng) cases, cycling through the targets, seeded."""
    ts = targets(shared)
    rng = np.random.default_rng(seed)
    for k in range(n):
        t = ts[k % len(ts)]
        m = t.mutations[int(rng.integers(len(t.mutations)))]
        yield t, m, np.random.default_rng(rng.integers(2**63))
