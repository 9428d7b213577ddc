"""A damaged stage cache heals: an entry cut short or with a flipped byte is reported in
one line and recomputed (and rewritten), never a traceback."""

from __future__ import annotations

import numpy as np
import pytest

from tests.hostile.clips import synth_walk
from vidcap.video.stagecache import CHECKSUM, StageCache


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    return synth_walk(tmp_path_factory.mktemp("cacheclip"), 16, (160, 120), seed=0)


def test_entries_carry_a_checksum_and_a_mismatch_is_a_miss(tmp_path):
    notes = []
    c = StageCache(tmp_path, log=notes.append)
    c.save("plate", "k", plate=np.arange(12.0).reshape(3, 4))
    with np.load(c.path("plate", "k")) as z:
        assert CHECKSUM in z.files
    np.testing.assert_array_equal(c.load("plate", "k")["plate"], np.arange(12.0).reshape(3, 4))
    assert notes == []
    # the same file with another array under the old checksum: refused
    np.savez(c.path("plate", "k"), plate=np.zeros((3, 4)),
             **{CHECKSUM: np.array(str(np.load(c.path("plate", "k"))[CHECKSUM]))})
    assert c.load("plate", "k") is None
    assert len(notes) == 1 and "checksum" in notes[0] and "recomputing" in notes[0]


@pytest.mark.parametrize("damage", ["truncate", "flip", "empty"])
def test_damaged_entry_is_recomputed_with_one_notice(clip, tmp_path, damage, cli):
    import shutil

    clip = shutil.copy(clip, tmp_path / "walk.mp4")
    cache = tmp_path / ".vidcap-cache"  # beside the video
    out = tmp_path / "a.bvh"
    first = cli("convert", clip, "-o", out, timeout=300)
    assert first.returncode == 0, first.stderr
    entry = sorted(cache.glob("silhouettes-*.npz"))[0]
    data = entry.read_bytes()
    if damage == "truncate":
        entry.write_bytes(data[: len(data) // 2])
    elif damage == "flip":
        mid = len(data) // 2
        entry.write_bytes(data[:mid] + bytes([data[mid] ^ 0xFF]) + data[mid + 1:])
    else:
        entry.write_bytes(b"")
    again = cli("convert", clip, "-o", tmp_path / "b.bvh", timeout=300)
    assert again.returncode == 0, again.stderr
    assert "Traceback" not in again.stderr
    notices = [ln for ln in again.stderr.splitlines() if "cache entry" in ln]
    assert len(notices) == 1 and str(entry) in notices[0] and "recomputing" in notices[0]
    assert (tmp_path / "b.bvh").read_text() == out.read_text()
    healed = cli("convert", clip, "-o", tmp_path / "c.bvh", timeout=300)
    assert "cache entry" not in healed.stderr  # rewritten whole
    assert not [p for p in cache.iterdir() if p.name.startswith(".")]  # no temp file left
