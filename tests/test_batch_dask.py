"""``vidcap batch --scheduler``: the Dask executor on a loopback LocalCluster."""

from __future__ import annotations

import csv
import os
import signal
import socket
import subprocess
import sys
import time

import pytest

distributed = pytest.importorskip("distributed", reason="needs vidcap[dask]")

from tests.conftest import REPO  # noqa: E402
from vidcap.batch.cluster import check_workers, run_dask  # noqa: E402
from vidcap.batch.job import ClipTask  # noqa: E402
from vidcap.cli import main  # noqa: E402
from vidcap.errors import UsageError  # noqa: E402

MOTIONS = ("walk", "jacks", "arms")


@pytest.fixture(scope="module")
def clips(tmp_path_factory):
    """Three tiny synthetic clips (8 frames, 96x72) in one folder."""
    folder = tmp_path_factory.mktemp("clips")
    for k, motion in enumerate(MOTIONS):
        code = main(["synth", "--motion", motion, "--frames", "8", "--size", "96x72",
                     "--seed", str(k), "-o", str(folder / f"{motion}.mp4"),
                     "--truth", str(tmp_path_factory.mktemp("truth") / f"{motion}.npz")])
        assert code == 0
    return folder


@pytest.fixture(scope="module")
def cluster():
    """Two single-thread worker processes on loopback; a clip whose workers die twice fails."""
    import dask

    # worker-saturation 1.0 as vidcap's own local cluster: a healthy clip never waits
    # on a worker that a dying clip takes down.
    with dask.config.set({"distributed.scheduler.allowed-failures": 1,
                          "distributed.scheduler.worker-saturation": 1.0}), \
            distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                     host="127.0.0.1", dashboard_address="127.0.0.1:0",
                                     silence_logs=50) as c, \
            distributed.Client(c, set_as_default=False) as client:
        yield c.scheduler_address, client


def _summary(outdir):
    """summary.csv without the timing columns, by file name."""
    rows = csv.DictReader((outdir / "summary.csv").open())
    return {os.path.basename(r["file"]): (r["frames"], r["status"], r["message"]) for r in rows}


def _env():
    return {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}


def _batch_process(clips, outdir, address):
    return subprocess.Popen(
        [sys.executable, "-m", "vidcap", "batch", str(clips), "-o", str(outdir),
         "--scheduler", address], cwd=REPO, env=_env(), stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True)


def _busy_worker(client, deadline_s=90.0):
    """The address of a worker running a clip, once one is (polling the scheduler)."""
    end = time.monotonic() + deadline_s
    while time.monotonic() < end:
        busy = [w for w, keys in client.processing().items()
                if any(str(k).startswith("convert_clip-") for k in keys)]
        if busy:
            return busy[0]
        time.sleep(0.05)
    pytest.fail("no worker started a clip")


def test_same_bvhs_and_summary_as_the_local_batch(clips, cluster, tmp_path):
    address, _ = cluster
    local, dask_out = tmp_path / "local", tmp_path / "dask"
    assert main(["batch", str(clips), "-o", str(local), "--jobs", "2"]) == 0
    assert main(["batch", str(clips), "-o", str(dask_out), "--scheduler", address]) == 0
    for motion in MOTIONS:
        ours = (dask_out / f"{motion}.bvh").read_bytes()
        assert ours == (local / f"{motion}.bvh").read_bytes(), motion
    assert _summary(dask_out) == _summary(local)
    assert {s for _, s, _ in _summary(dask_out).values()} == {"ok"}
    # up to date: skipped without touching the cluster; --force redoes them
    stamp = (dask_out / "walk.bvh").stat().st_mtime_ns
    assert main(["batch", str(clips), "-o", str(dask_out), "--scheduler", address]) == 0
    assert {s for _, s, _ in _summary(dask_out).values()} == {"skipped"}
    assert main(["batch", str(clips / "walk.mp4"), "-o", str(dask_out), "--scheduler",
                 address, "--force"]) == 0
    assert (dask_out / "walk.bvh").stat().st_mtime_ns > stamp


def test_a_worker_killed_mid_clip_has_its_clip_rescheduled(clips, cluster, tmp_path):
    address, client = cluster
    pids = client.run(os.getpid)
    proc = _batch_process(clips, tmp_path, address)
    try:
        victim = _busy_worker(client)
        os.kill(pids[victim], signal.SIGKILL)
        _, err = proc.communicate(timeout=180)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    assert victim not in client.run(os.getpid)  # it really died (the nanny starts another)
    assert {s for _, s, _ in _summary(tmp_path).values()} == {"ok"}
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == [".vidcap-cache", "arms.bvh", "jacks.bvh", "summary.csv", "walk.bvh"]


def test_a_clip_whose_workers_die_every_time_is_reported(clips, cluster, tmp_path):
    address, _ = cluster

    def die_on_walk(task):
        if task.video.endswith("walk.mp4"):
            os.kill(os.getpid(), signal.SIGKILL)
        return {"file": task.video, "output": task.output, "frames": 1, "seconds": 0.0,
                "fps": 0.0, "status": "ok", "message": ""}

    tasks = [ClipTask(str(clips / f"{m}.mp4"), str(tmp_path / f"{m}.bvh")) for m in MOTIONS]
    rows = {os.path.basename(r["file"]): r
            for r in run_dask(tasks, address, outdir=tmp_path, job=die_on_walk)}
    assert rows["walk.mp4"]["status"] == "failed"
    assert "every Dask worker that ran this clip died" in rows["walk.mp4"]["message"]
    assert rows["arms.mp4"]["status"] == rows["jacks.mp4"]["status"] == "ok"


def test_the_startup_check_names_an_input_the_workers_cannot_see(cluster, tmp_path):
    _, client = cluster
    with pytest.raises(UsageError, match="a Dask worker .* cannot read this input"):
        check_workers(client, str(tmp_path / "elsewhere.mp4"), str(tmp_path), timeout=30)
    seen = tmp_path / "seen.mp4"
    seen.write_bytes(b"")
    check_workers(client, str(seen), str(tmp_path), timeout=30)  # both shared: passes
    with pytest.raises(UsageError, match="--clip-jobs 2: the Dask workers .* may not start"):
        check_workers(client, str(seen), str(tmp_path), timeout=30, clip_jobs=2)


def test_ctrl_c_cancels_the_batch_and_exits_130(clips, cluster, tmp_path):
    address, client = cluster
    proc = _batch_process(clips, tmp_path, address)
    try:
        _busy_worker(client)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "interrupted" in err and "Traceback" not in err
    assert not (tmp_path / "summary.csv").exists()


def test_an_unreachable_scheduler_is_one_line_naming_it(clips, tmp_path, capsys):
    with socket.socket() as s:  # a loopback port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    t0 = time.monotonic()
    code = main(["batch", str(clips), "-o", str(tmp_path), "--scheduler", address,
                 "--connect-timeout", "1"])
    assert code == 2 and time.monotonic() - t0 < 10
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"vidcap: error: {address}: cannot reach the Dask scheduler "
                   "(no answer within 1 s)"]


def test_the_environment_names_the_scheduler(clips, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", "tcp://127.0.0.1:1")
    assert main(["batch", str(clips), "-o", str(tmp_path), "--connect-timeout", "0.5"]) == 2
    assert "tcp://127.0.0.1:1: cannot reach the Dask scheduler" in capsys.readouterr().err
