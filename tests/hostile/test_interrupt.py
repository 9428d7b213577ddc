"""Ctrl-C (SIGINT to the terminal's process group) or SIGTERM during ``vidcap convert``:
exit 130 within 2 s, every worker gone, no temporary file, no partial output."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from tests.hostile.clips import synth_walk
from tests.hostile.mutate import REPO

#: The promise: stopped this soon after the signal, seconds.
STOP_WITHIN_S = 2.0


@pytest.fixture(scope="module")
def long_clip(tmp_path_factory):
    return synth_walk(tmp_path_factory.mktemp("longclip"), 240, (320, 240), seed=1)


def _session_members(sid: int) -> list[int]:
    """Processes of session ``sid`` still alive (zombies excluded)."""
    out = []
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat") as fh:
                fields = fh.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z":  # state, ppid, pgrp, session
            out.append(int(name))
    return out


@pytest.mark.parametrize("how,when", [("SIGINT", "fit"), ("SIGTERM", "fit"),
                                      ("SIGINT", "start")])
def test_interrupt_stops_everything_at_once(long_clip, tmp_path, how, when):
    import shutil

    video = shutil.copy(long_clip, tmp_path / "long.mp4")
    out = tmp_path / "out" / "long.bvh"
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.Popen([sys.executable, "-m", "vidcap", "convert", str(video), "-o",
                             str(out), "--save", str(tmp_path / "out" / "s.npz"), "--jobs",
                             "2"], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        t0 = time.monotonic()
        while time.monotonic() - t0 < 60:  # until the fit's workers run (or 1 s in)
            if proc.poll() is not None:
                pytest.fail(f"convert ended before the signal: {proc.stderr.read()[-500:]}")
            members = _session_members(proc.pid)
            if when == "start" and time.monotonic() - t0 > 1.0:
                break
            if when == "fit" and len(members) >= 4:  # parent, zygote, two workers
                time.sleep(1.0)
                break
            time.sleep(0.05)
        t_signal = time.monotonic()
        if how == "SIGINT":
            os.killpg(proc.pid, signal.SIGINT)  # what Ctrl-C in a terminal does
        else:
            os.kill(proc.pid, signal.SIGTERM)
        try:
            _, err = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            pytest.fail(f"convert still running 30 s after {how}")
        took = time.monotonic() - t_signal
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    left = []
    for _ in range(20):  # the kernel reaps killed workers within moments
        left = _session_members(proc.pid)
        if not left:
            break
        time.sleep(0.05)
    assert proc.returncode == 130, (proc.returncode, err[-800:])
    assert took < STOP_WITHIN_S, f"{took:.2f} s after {how}"
    assert "Traceback" not in err and err.strip().splitlines()[-1] == "vidcap: interrupted"
    assert not left, f"processes left running: {left}"
    written = [p.name for p in tmp_path.rglob("*") if p.is_file()
               and p.name != "long.mp4" and ".vidcap-cache" not in p.parts]
    assert written == [], written  # no output, no temporary file
    cache = tmp_path / ".vidcap-cache"
    if cache.exists():  # completed stages may stay; no half-written entry
        assert not [p for p in cache.iterdir() if p.name.startswith(".")]


_LOST_IN_A_CALLBACK = """
import ctypes, os, signal, sys, time
from vidcap import interrupt
from vidcap.fileio import atomic_path

interrupt.install()
def busy():  # numba's compiler calls back into Python like this, from LLVM
    os.kill(os.getpid(), signal.SIGTERM)
    t = time.monotonic()
    while time.monotonic() - t < 0.3:
        pass
callback = ctypes.CFUNCTYPE(None)(busy)
with atomic_path(sys.argv[1]) as tmp:
    tmp.write_text("half")
    callback()  # the KeyboardInterrupt raised in here is lost ("Exception ignored")
    time.sleep(5)
print("carried on")
"""


def test_an_interrupt_lost_in_a_ctypes_callback_still_stops_the_command(tmp_path):
    out = tmp_path / "out.txt"
    env = dict(os.environ, PYTHONPATH=str(REPO))
    t0 = time.monotonic()
    proc = subprocess.run([sys.executable, "-c", _LOST_IN_A_CALLBACK, str(out)], env=env,
                          capture_output=True, text=True, timeout=30)
    took = time.monotonic() - t0
    assert proc.returncode == 130, (proc.returncode, proc.stderr[-500:])
    assert "carried on" not in proc.stdout
    assert "Traceback" not in proc.stderr, proc.stderr[-500:]
    assert proc.stderr.strip().splitlines()[-1] == "vidcap: interrupted"
    assert took < 5.0, took
    assert list(tmp_path.iterdir()) == []  # neither the output nor its temporary file


_WRAPPED_BY_A_COMPILED_CALL = """
import os, signal, sys
from vidcap import cli
import vidcap.commands.info as info

def run(args):  # numba's dispatcher hands an interrupt back as another exception
    try:
        os.kill(os.getpid(), signal.SIGTERM)
    except KeyboardInterrupt as exc:
        raise SystemError("CPUDispatcher(...) returned a result with an exception set") from exc
    print("carried on")

info.run = run
sys.argv = ["vidcap", "info", sys.argv[1]]
sys.exit(cli.main())
"""


def test_an_interrupt_that_comes_back_as_another_exception_is_still_an_interrupt(tmp_path):
    """SIGTERM landed inside a numba-compiled call (CI, stop 47: the graph cut's
    ``band_graph``) and came back as ``SystemError``: exit 130 and "interrupted", not
    "internal error" and 1."""
    clip = tmp_path / "clip.mp4"
    clip.write_bytes(b"")
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.run([sys.executable, "-c", _WRAPPED_BY_A_COMPILED_CALL, str(clip)],
                          env=env, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 130, (proc.returncode, proc.stderr[-500:])
    assert "internal error" not in proc.stderr and "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines()[-1] == "vidcap: interrupted"
    assert "carried on" not in proc.stdout
