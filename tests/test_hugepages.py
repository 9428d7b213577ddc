"""vidcap.video.hugepages: NumPy's huge pages off inside the block, restored after it."""

from __future__ import annotations

import pytest

from vidcap.video import hugepages

np_switch = hugepages._switch()
pytestmark = pytest.mark.skipif(np_switch is None, reason="this NumPy has no switch")


def _current() -> bool:
    before = np_switch(True)  # returns the setting it replaces
    np_switch(before)
    return bool(before)


@pytest.mark.parametrize("start", [True, False])
def test_off_inside_and_restored_after_even_on_an_error(start, monkeypatch):
    monkeypatch.delenv("NUMPY_MADVISE_HUGEPAGE", raising=False)
    old = np_switch(start)
    try:
        with hugepages.small_pages():
            assert _current() is False
        assert _current() is start
        with pytest.raises(RuntimeError), hugepages.small_pages():
            raise RuntimeError("stage failed")
        assert _current() is start
    finally:
        np_switch(old)


def test_a_users_setting_is_kept(monkeypatch):
    monkeypatch.setenv("NUMPY_MADVISE_HUGEPAGE", "1")
    old = np_switch(True)
    try:
        with hugepages.small_pages():
            assert _current() is True
    finally:
        np_switch(old)
