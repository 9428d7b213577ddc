"""vidcap.kernelcache: a cached kernel recompiles when a module it compiles in changes."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

KERNEL = """
from pathlib import Path

import numba

from consts import SCALE


@numba.njit(cache=True)
def scaled(x):
    return x * SCALE
"""

REFRESH = """
from vidcap.kernelcache import refresh_when_changed

refresh_when_changed(globals(), [Path(__file__).with_name("consts.py")])
"""


def _run(folder: Path, module: str) -> str:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(folder), str(ROOT)]))
    env.pop("NUMBA_CACHE_DIR", None)  # the cache beside the module, as installed
    out = subprocess.run([sys.executable, "-c", f"import {module}; print({module}.scaled(2))"],
                         env=env, capture_output=True, text=True, timeout=120, check=True)
    return out.stdout.strip()


@pytest.mark.parametrize("guarded", [True, False])
def test_kernel_follows_a_changed_constant_only_when_guarded(tmp_path, guarded):
    (tmp_path / "consts.py").write_text("SCALE = 3\n")
    module = "guarded" if guarded else "plain"
    (tmp_path / f"{module}.py").write_text(textwrap.dedent(KERNEL) + (REFRESH if guarded else ""))
    assert _run(tmp_path, module) == "6"
    assert list((tmp_path / "__pycache__").glob(f"{module}.scaled-*.nbc"))  # cached
    (tmp_path / "consts.py").write_text("SCALE = 5\n")
    # numba's own cache keeps the stale literal; the guard drops it
    assert _run(tmp_path, module) == ("10" if guarded else "6")
    assert _run(tmp_path, module) == ("10" if guarded else "6")  # and caches the new one


def test_nothing_flushed_while_the_files_stay(tmp_path):
    from vidcap.kernelcache import refresh_when_changed

    (tmp_path / "consts.py").write_text("SCALE = 3\n")
    (tmp_path / "guarded.py").write_text(textwrap.dedent(KERNEL) + REFRESH)
    _run(tmp_path, "guarded")
    stamp = tmp_path / "__pycache__" / "guarded.deps"
    before = stamp.read_text()

    class _Cache:
        cache_path = str(tmp_path / "__pycache__")
        flushed = 0

        def flush(self):
            self.flushed += 1

    def kernel():
        pass

    kernel.__module__ = "guarded"
    kernel._cache = _Cache()
    kernel.py_func = kernel
    namespace = {"__name__": "guarded", "__file__": str(tmp_path / "guarded.py"),
                 "scaled": kernel}
    assert not refresh_when_changed(namespace, [tmp_path / "consts.py"])
    assert kernel._cache.flushed == 0 and stamp.read_text() == before
    (tmp_path / "consts.py").write_text("SCALE = 4\n")
    assert refresh_when_changed(namespace, [tmp_path / "consts.py"])
    assert kernel._cache.flushed == 1 and stamp.read_text() != before
