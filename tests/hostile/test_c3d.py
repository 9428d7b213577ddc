"""Hostile C3D files: each field the issue found crashing, exhausting memory or silently
writing nonsense now gets one line naming the file and the field, exit 2."""

from __future__ import annotations

import pytest

from tests.hostile.mutate import c3d_set, digest, first_error, listing, outcome, run_capped

CASES = {
    # a parameter's dimension count of 255: SIGSEGV inside ezc3d on main
    "ndims 255": ("07_01", "POINT:LABELS:ndims", 255, "dimensions"),
    "ndims 255 (SCALE)": ("07_01", "POINT:SCALE:ndims", 255, "dimensions"),
    # an analog channel count in the tens of thousands: SIGSEGV
    "analog used": ("Vicon", "ANALOG:USED", 30000, "ANALOG:USED"),
    # an absurd analog rate: std::bad_alloc at the cap (gigabytes of analog frames)
    "analog rate": ("Vicon", "ANALOG:RATE", 1e9, "ANALOG:RATE"),
    "analog rate 1e6": ("Vicon", "ANALOG:RATE", 1e6, "analog values"),
    "points": ("07_01", "POINT:USED", 32000, "points"),
    "header analog": ("07_01", "header:analog", 65535, "analog"),
    "point rate": ("07_01", "POINT:RATE", 3e38, "POINT:RATE"),
    "header rate": ("Vicon", "header:rate", float("nan"), "rate"),
    # absurd POINT:SCALE
    "scale": ("07_01", "POINT:SCALE", -3e38, "POINT:SCALE"),
}


@pytest.fixture
def trial(shared_data):
    return shared_data("c3d/07_01.c3d").read_bytes()


@pytest.mark.parametrize("case", sorted(CASES))
def test_hostile_c3d_field_is_one_line_naming_it(case, shared_data, tmp_path):
    source, field, value, named = CASES[case]
    bad = tmp_path / "bad.c3d"
    bad.write_bytes(c3d_set(shared_data(f"c3d/{source}.c3d").read_bytes(), field, value))
    before, files = digest([bad]), listing(tmp_path)
    out = tmp_path / "out"
    run = run_capped(["joints", bad, "-o", out / "j.bvh", "--centres", out / "c.csv"],
                     cwd=tmp_path, timeout=60)
    got = outcome(run, name=str(bad), inputs_before=before, inputs_after=digest([bad]),
                  files_before=files, files_after=listing(tmp_path))
    assert got == "clean error", (case, run.returncode, run.stderr[-800:])
    assert named.lower() in first_error(run).lower(), first_error(run)


def test_absurd_scale_in_the_reader_names_the_field(trial, tmp_path):
    """Even without the CLI: no 10^38 m markers come out of read_c3d."""
    from vidcap.errors import C3DError
    from vidcap.mocap.c3d import read_c3d

    bad = tmp_path / "s.c3d"
    bad.write_bytes(c3d_set(trial, "POINT:SCALE", -1e30))
    with pytest.raises(C3DError, match="POINT:SCALE"):
        read_c3d(bad)


def test_every_real_c3d_still_reads(shared_data):
    """The checks refuse no file ezc3d reads correctly (Dance.c3d is malformed on purpose)."""
    from vidcap.errors import C3DError
    from vidcap.mocap.c3d import read_c3d

    folder = shared_data("c3d")
    for path in sorted(folder.glob("*.c3d")):
        if path.name == "Dance.c3d":
            with pytest.raises(C3DError):
                read_c3d(path)
            continue
        data = read_c3d(path)
        assert data.positions.shape[0] > 0 and data.fps > 0, path
