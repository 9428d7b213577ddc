"""The clip solve in two halves on two processes (vidcap.video.solve.split)."""

from __future__ import annotations

import numpy as np

from vidcap.body import BodyModel
from vidcap.synth import make_motion, prepare_clip, truth_arrays
from vidcap.video.lift import estimate_scale
from vidcap.video.solve import solve_clip
from vidcap.video.solve import split as split_mod
from vidcap.video.solve.split import SPLIT_MIN_FRAMES

BODY = BodyModel()


def _noisy_walk(n=SPLIT_MIN_FRAMES + 40, noise=0.01):
    m = make_motion("walk", body=BODY, fps=30.0, n_frames=n, rng=np.random.default_rng(0))
    clip = prepare_clip(m, body=BODY, yaw_deg=60.0, rng=np.random.default_rng(1))
    t = truth_arrays(clip, np.zeros((m.n_frames, 1, 1), bool))
    cam = t["camera"]
    s = np.linalg.norm(cam[0, :3])
    rot = np.stack([cam[0, :3] / s, -cam[1, :3] / s, -t["view_dir"]])
    true3 = t["joints3d"] @ rot.T
    scale = estimate_scale(t["joints2d"], BODY)
    j2 = t["joints2d"] + np.random.default_rng(7).normal(0.0, noise * BODY.height * scale,
                                                          t["joints2d"].shape)
    kw = dict(scale=scale, fps=30.0, body=BODY, yaw=np.deg2rad(t["yaw_deg"]),
              prior_signs=t["depth_signs"], robust=3.0)
    return j2, kw, true3


def _rel(a):
    return a - a[:, :1]


def _error(a, b):
    return np.linalg.norm(_rel(a) - _rel(b), axis=-1).mean(axis=1)  # (F,) m


def test_the_split_solve_is_as_accurate_as_one_solve_and_continuous_at_the_join(monkeypatch):
    j2, kw, true3 = _noisy_walk()
    one = solve_clip(j2, jobs=1, **kw)
    forks = []
    start = split_mod._start
    monkeypatch.setattr(split_mod, "_start", lambda *a: forks.append(a) or start(*a))
    two = solve_clip(j2, jobs=2, **kw)
    assert len(forks) == 1  # the first half went to a child
    assert two.joints3d.shape == one.joints3d.shape
    e1, e2 = _error(one.joints3d, true3), _error(two.joints3d, true3)
    # 1 % noise: the whole clip's solve is within 3 cm a joint; the split within 5 mm of it
    assert e1.mean() < 0.03
    assert e2.mean() < e1.mean() + 0.005
    # no step at the join: the joints' frame-to-frame acceleration there is like elsewhere
    acc = np.linalg.norm(np.diff(two.joints3d, 2, axis=0), axis=-1).max(axis=1)  # (F-2,)
    mid = len(j2) // 2
    seam = acc[mid - 4:mid + 2]
    assert seam.max() < 3.0 * np.percentile(acc, 90)
    # the bone lengths stay the body's
    from vidcap.body import segment_vectors

    lengths = np.linalg.norm(segment_vectors(two.joints3d), axis=-1)
    np.testing.assert_allclose(lengths, np.broadcast_to(BODY.segment_lengths(), lengths.shape),
                               atol=1e-9)


def test_a_short_clip_or_one_job_is_solved_whole(monkeypatch):
    calls = []
    monkeypatch.setattr(split_mod, "_start", lambda *a: calls.append(a))
    j2, kw, _ = _noisy_walk(n=SPLIT_MIN_FRAMES - 20)
    a = solve_clip(j2, jobs=2, **kw)
    b = solve_clip(j2, jobs=1, **kw)
    assert calls == []
    np.testing.assert_array_equal(a.params, b.params)


def test_without_the_child_the_first_half_is_solved_here(monkeypatch):
    j2, kw, _ = _noisy_walk()
    forked = solve_clip(j2, jobs=2, **kw)
    monkeypatch.setattr(split_mod, "_start", lambda *a: None)  # no fork (or it failed)
    here = solve_clip(j2, jobs=2, **kw)
    np.testing.assert_allclose(here.params, forked.params, atol=1e-9)


def test_a_daemonic_process_solves_both_halves_itself():
    import multiprocessing

    j2, kw, _ = _noisy_walk()
    ctx = multiprocessing.get_context("fork")
    out = ctx.Queue()

    def work():
        sol = solve_clip(j2, jobs=2, **kw)
        out.put(sol.params)

    proc = ctx.Process(target=work, daemon=True)  # may not start children of its own
    proc.start()
    params = out.get(timeout=120)
    proc.join()
    assert proc.exitcode == 0
    expected = solve_clip(j2, jobs=2, **kw)
    np.testing.assert_allclose(params, expected.params, atol=1e-9)


_SOLVE_FOREVER = """
import sys
sys.path.insert(0, {tests!r})
from test_solve_split import _noisy_walk
from vidcap.video.solve import solve_clip
j2, kw, _ = _noisy_walk(n=900)
print("ready", flush=True)
while True:
    solve_clip(j2, jobs=2, **kw)
"""


def test_ctrl_c_while_the_halves_are_solved_leaves_no_process(tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    from vidcap.interrupt import descendants

    script = _SOLVE_FOREVER.format(tests=str(Path(__file__).parent))
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        assert proc.stdout.readline().strip() == "ready"
        t0 = time.monotonic()
        kids = []
        while not kids and time.monotonic() - t0 < 60:  # the half's child is forked
            kids = descendants(proc.pid)
            time.sleep(0.02)
        assert kids, "no child process was started for the first half"
        os.killpg(proc.pid, signal.SIGINT)  # Ctrl-C in a terminal
        proc.communicate(timeout=10)
        assert proc.returncode != 0
        time.sleep(0.2)
        alive = [k for k in kids if os.path.exists(f"/proc/{k}")
                 and open(f"/proc/{k}/stat").read().rsplit(")", 1)[1].split()[0] != "Z"]
        assert alive == []
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
