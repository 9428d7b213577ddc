"""Hostile motion files: an ASF hierarchy with a cycle, absurd ASF/AMC and BVH values,
a BVH nested beyond recursion: one line naming the file, exit 2, no hang."""

from __future__ import annotations

import pytest

from tests.hostile.mutate import digest, first_error, listing, outcome, run_capped


def _check(tmp_path, bad, args, named):
    inputs = [p for p in args if str(p).startswith(str(tmp_path)) and p.exists()]
    before, files = digest(inputs), listing(tmp_path)
    run = run_capped(args, cwd=tmp_path, timeout=60)
    got = outcome(run, name=str(bad), inputs_before=before, inputs_after=digest(inputs),
                  files_before=files, files_after=listing(tmp_path))
    assert got == "clean error", (run.returncode, run.stderr[-800:])
    assert named in first_error(run), first_error(run)


@pytest.fixture
def asf_amc(shared_data, tmp_path):
    asf, amc = tmp_path / "s.asf", tmp_path / "m.amc"
    asf.write_text(shared_data("motion/07.asf").read_text())
    amc.write_text(shared_data("motion/07_07.amc").read_text())
    return asf, amc


def _synth(tmp_path, asf, amc):
    return ["synth", "--motion", asf, "--amc", amc, "--frames", "3", "--size", "64x48",
            "-o", tmp_path / "out" / "c.mp4"]


def test_asf_hierarchy_cycle_is_refused_not_looped(asf_amc, tmp_path):
    asf, amc = asf_amc
    asf.write_text(asf.read_text().replace("    ltibia lfoot", "    ltibia lfoot lfemur"))
    _check(tmp_path, asf, _synth(tmp_path, asf, amc), "twice")


@pytest.mark.parametrize("old,new,named", [
    ("  length 0.45", "  length 0", ":units length"),
    ("direction 0.", "direction nan 0 0 0.", "direction"),
])
def test_asf_absurd_values(asf_amc, tmp_path, old, new, named):
    asf, amc = asf_amc
    text = asf.read_text()
    assert old in text
    asf.write_text(text.replace(old, new, 1))
    _check(tmp_path, asf, _synth(tmp_path, asf, amc), named)


def test_amc_absurd_angle(asf_amc, tmp_path):
    asf, amc = asf_amc
    lines = amc.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("root"))
    lines[k] = "root 1e300 0 0 0 0 0"
    amc.write_text("\n".join(lines) + "\n")
    _check(tmp_path, amc, _synth(tmp_path, asf, amc), "out of range")


def _bvh(depth: int, *, frame_time="0.0083333", value="0.0") -> str:
    head = ["HIERARCHY", "ROOT hips", "{", "OFFSET 0 0 0",
            "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
    for i in range(depth):
        head += [f"JOINT j{i}", "{", "OFFSET 0 10 0", "CHANNELS 3 Zrotation Xrotation Yrotation"]
    head += ["End Site", "{", "OFFSET 0 10 0", "}"] + ["}"] * (depth + 1)
    n = 6 + 3 * depth
    return "\n".join(head + ["MOTION", "Frames: 1", f"Frame Time: {frame_time}",
                             " ".join([value] * n)]) + "\n"


@pytest.mark.parametrize("kind,named", [("deep", "nested"), ("frame time", "Frame Time"),
                                        ("nan", "not finite")])
def test_bvh_hostile(tmp_path, kind, named):
    bad = tmp_path / "m.bvh"
    text = {"deep": _bvh(5000), "frame time": _bvh(3, frame_time="1e-300"),
            "nan": _bvh(3, value="nan")}[kind]
    bad.write_text(text)
    _check(tmp_path, bad, ["synth", "--motion", bad, "--frames", "2", "--size", "64x48",
                           "-o", tmp_path / "out" / "c.mp4"], named)


def test_view_without_a_display_says_so(tmp_path, shared_data):
    """No display and no --screenshot: one line saying so (a pyvista traceback on main)."""
    import os

    bvh = shared_data("motion/131_01.bvh")
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    run = run_capped(["view", bvh], cwd=tmp_path, timeout=60, env=env)
    assert run.returncode == 2, run.stderr[-800:]
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vidcap: error: no display"), lines
    assert "--screenshot" in lines[0] and "Traceback" not in run.stderr
