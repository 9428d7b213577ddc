"""The installed package: a wheel built from the checkout, and the editable install."""

from __future__ import annotations

import email
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from tests.conftest import REPO

#: Folders of the checkout that never go into a build (venvs, caches, outputs).
_NOT_SOURCE = (".git", ".venv", "venv", ".ci-venv", "build", "dist", "__pycache__",
               "*.egg-info", ".pytest_cache", ".ruff_cache", ".hypothesis", "*.vidcap-cache")


def _source_tree(dest: Path) -> Path:
    """Copy the checkout's source files to ``dest`` (what a clean checkout holds)."""
    try:
        listed = subprocess.run(
            ["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z"],
            cwd=REPO, capture_output=True, check=True).stdout.decode().split("\0")
    except (OSError, subprocess.CalledProcessError):
        shutil.copytree(REPO, dest, ignore=shutil.ignore_patterns(*_NOT_SOURCE))
        return dest
    for rel in filter(None, listed):
        src = REPO / rel
        if src.is_file():
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / rel)
    return dest


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """A wheel built from a copy of the checkout (no build isolation: offline and fast)."""
    pytest.importorskip("setuptools", minversion="77")
    src = _source_tree(tmp_path_factory.mktemp("checkout"))
    out = tmp_path_factory.mktemp("wheel")
    run = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", str(out), str(src)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    (whl,) = out.glob("vidcap-*.whl")
    return whl


@pytest.mark.slow
def test_wheel_maps_ui_into_the_package_and_ships_license_and_types(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    assert "vidcap/py.typed" in names
    assert "vidcap/ui/__init__.py" in names and "vidcap/ui/annotate.py" in names
    assert not [n for n in names if n.startswith("ui/")], "a top-level ui package"
    tops = {n.split("/")[0] for n in names}
    assert tops == {"vidcap", next(t for t in tops if t.endswith(".dist-info"))}
    dist_info = next(t for t in tops if t.endswith(".dist-info"))
    meta = email.message_from_bytes(zipfile.ZipFile(wheel).read(f"{dist_info}/METADATA"))
    assert meta.get_all("License-File") == ["LICENSE"]
    assert meta["License-Expression"] == "MIT"
    assert f"{dist_info}/licenses/LICENSE" in names


@pytest.mark.slow
def test_wheel_holds_every_subpackage_and_data_file(wheel):
    """Every package folder and built-in marker set of the checkout is in the wheel."""
    names = set(zipfile.ZipFile(wheel).namelist())
    for init in (REPO / "vidcap").rglob("__init__.py"):
        rel = init.relative_to(REPO).as_posix()
        assert rel in names, rel
    for init in (REPO / "ui").rglob("__init__.py"):
        assert "vidcap/" + init.relative_to(REPO).as_posix() in names
    for toml in (REPO / "vidcap" / "mocap" / "markersets").glob("*.toml"):
        assert toml.relative_to(REPO).as_posix() in names


def test_installed_package_has_vidcap_ui_and_no_top_level_ui(tmp_path):
    """From outside the checkout (so the repository root is not on sys.path)."""
    code = ("import importlib.util as u, vidcap.ui, vidcap.ui.session;"
            "print(u.find_spec('ui') is None)")
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "True"


def test_pip_check_is_clean():
    run = subprocess.run([sys.executable, "-m", "pip", "check"], capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
