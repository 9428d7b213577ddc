"""The fuzz suite's CI slice (under a minute): mutated real files through every reader.

* a seeded set of mutants through their commands in child processes under a 3 GiB
  address-space cap (``python -m vidcap`` with ``preexec_fn`` for a few, forked from
  this process for the rest): exit 2 with one line naming the file, or success; never
  a signal death, a hang, a traceback, a changed input or a stray file;
* hypothesis-driven byte and token mutations of each reader called directly: only
  vidcap's own one-line errors come out.

``benchmarks/fuzz.py`` runs thousands of the same cases.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from tests.hostile import fuzzing
from tests.hostile.mutate import run_capped

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

ALLOWED = {"clean error", "success"}


def _need_data():
    if not fuzzing.SHARED.exists():
        if os.environ.get("CI") == "true":
            pytest.fail(f"{fuzzing.SHARED} is missing")
        pytest.skip("../shared/data is not here")


@pytest.fixture(scope="module")
def preloaded():
    _need_data()
    fuzzing.preload()


def test_forked_mutants_of_every_format(preloaded, tmp_path):
    seen, bad = set(), []
    for target, mutation, rng in fuzzing.mutation_plan(24, seed=2026):
        got, run, folder = fuzzing.run_case(target, mutation, rng, root=tmp_path, timeout=60)
        seen.add(target.name)
        if got not in ALLOWED:
            bad.append((target.source.name, got, run.returncode, run.stderr[-400:], folder))
    assert seen == {"C3D", "video", "BVH", "ASF/AMC", "TOML", "JSON"}
    assert bad == []


def test_cli_subprocess_mutants(preloaded, tmp_path):
    """The real entry point, capped through ``preexec_fn``: one mutant per format."""
    rng = np.random.default_rng(7)
    bad = []
    for target in fuzzing.targets():
        if target.name == "JSON":
            continue  # its success path runs the whole video pipeline: the forked slice has it
        mutation = fuzzing.truncate if target.name != "C3D" else fuzzing.c3d_field
        got, run, folder = fuzzing.run_case(target, mutation, rng, root=tmp_path, timeout=60,
                                            subprocess_runner=run_capped)
        if got not in ALLOWED:
            bad.append((target.source.name, got, run.returncode, run.stderr[-400:]))
    assert bad == []


# ---------------------------------------------------------------- the readers, in-process
def _mutate(data: bytes, ops) -> bytes:
    out = bytearray(data)
    for kind, where, value in ops:
        if not out:
            break
        i = where % len(out)
        if kind == 0:
            out[i] ^= value or 1
        elif kind == 1:
            del out[i:]
        else:
            out[i:i] = bytes([value]) * (value % 64 + 1)
    return bytes(out)


OPS = st.lists(st.tuples(st.integers(0, 2), st.integers(0, 2**31), st.integers(0, 255)),
               min_size=1, max_size=6)
FAST = settings(max_examples=20, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])


def _only_vidcap_errors(fn, path):
    from vidcap.errors import VidcapError

    try:
        fn(path)
    except VidcapError as exc:
        assert str(path) in str(exc) and "\n" not in str(exc)


@FAST
@given(ops=OPS, head=st.booleans())
def test_c3d_reader(ops, head, tmp_path_factory):
    _need_data()
    from vidcap.mocap.c3d import read_c3d

    data = (fuzzing.SHARED / "c3d" / "Optotrak.c3d").read_bytes()
    if head:  # aim at the header and the parameter section
        ops = [(k, w % 3072, v) for k, w, v in ops]
    p = tmp_path_factory.mktemp("c3d") / "m.c3d"
    p.write_bytes(_mutate(data, ops))
    _only_vidcap_errors(read_c3d, p)


@FAST
@given(field=st.sampled_from(fuzzing.C3D_FIELDS),
       value=st.one_of(st.integers(-2**15, 2**16 - 1), st.floats(allow_nan=True, width=32)))
def test_c3d_fields(field, value, tmp_path_factory):
    _need_data()
    from vidcap.mocap.c3d import read_c3d

    data = (fuzzing.SHARED / "c3d" / "Vicon.c3d").read_bytes()
    is_float = field.split(":")[-1].lower() in ("scale", "rate")
    v = float(value) if is_float else fuzzing._fit(field, int(value) if not isinstance(
        value, float) or np.isfinite(value) else 0)
    try:
        mutated = fuzzing.c3d_set(data, field, v)
    except Exception:  # noqa: BLE001 - a value the field's type cannot hold
        return
    p = tmp_path_factory.mktemp("c3d") / "f.c3d"
    p.write_bytes(mutated)
    _only_vidcap_errors(read_c3d, p)


@FAST
@given(ops=OPS)
def test_text_readers(ops, tmp_path_factory):
    _need_data()
    from vidcap.io.bvh import read_bvh
    from vidcap.mocap.markerset import load_markerset
    from vidcap.video.annotations import Annotations

    cases = [(fuzzing._bvh_frames(4)((fuzzing.SHARED / "motion" / "131_01.bvh").read_bytes()),
              ".bvh", read_bvh),
             ((fuzzing.MARKERSETS / "cmu41.toml").read_bytes(), ".toml", load_markerset),
             ((fuzzing.REPO / "tests" / "hostile" / "walk_side.vidcap.json").read_bytes(),
              ".json", Annotations.load)]
    folder = tmp_path_factory.mktemp("text")
    for data, suffix, reader in cases:
        p = folder / f"m{suffix}"
        p.write_bytes(_mutate(data, ops))
        _only_vidcap_errors(reader, p)
