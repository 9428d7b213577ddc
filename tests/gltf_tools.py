"""The outside checkers of our glTF files: the Khronos glTF Validator and Blender.

Both live outside the repository (``.ci/run`` installs them when missing):

* the validator, the ``gltf-validator`` npm package, in ``$VIDCAP_GLTF_VALIDATOR`` or
  ``~/.cache/vidcap-gltf-validator`` (its ``node_modules`` folder), run with ``node``;
* Blender as a Python module (``pip install bpy``, wheels for one Python version
  each), in the venv ``$VIDCAP_BPY_VENV`` or ``~/.cache/vidcap-bpy``.

Tests skip with the reason when one is absent, except under ``CI=true`` for the
validator (``.ci/run`` always installs it); bpy may not exist for the machine's Python.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent

_VALIDATE_JS = r"""
const v = require('gltf-validator'), fs = require('fs'), path = require('path');
const file = process.argv[1], dir = path.dirname(file);
const read = (uri) => new Promise((ok, fail) => {
  try { ok(new Uint8Array(fs.readFileSync(path.join(dir, decodeURIComponent(uri))))); }
  catch (e) { fail(e.toString()); } });
v.validateBytes(new Uint8Array(fs.readFileSync(file)), {uri: file, externalResourceFunction: read})
  .then((r) => console.log(JSON.stringify(r.issues)))
  .catch((e) => { console.error(String(e)); process.exit(1); });
"""


def _missing(reason: str, *, required_in_ci: bool):
    if required_in_ci and os.environ.get("CI") == "true":
        pytest.fail(f"{reason}; .ci/run must install it")
    pytest.skip(reason)


def validator_modules() -> Path:
    """The ``node_modules`` folder holding ``gltf-validator`` (skip or fail when absent)."""
    root = Path(os.environ.get("VIDCAP_GLTF_VALIDATOR",
                               Path.home() / ".cache" / "vidcap-gltf-validator"))
    modules = root if root.name == "node_modules" else root / "node_modules"
    if shutil.which("node") is None:
        _missing("node is not installed (the glTF Validator runs on it)", required_in_ci=True)
    if not (modules / "gltf-validator" / "package.json").exists():
        _missing(f"the Khronos glTF Validator is not in {modules} "
                 "(npm install gltf-validator there)", required_in_ci=True)
    return modules


def validate(path: str | os.PathLike) -> dict:
    """The validator's ``issues`` report (numErrors, numWarnings, messages...) for a file."""
    env = dict(os.environ, NODE_PATH=str(validator_modules()))
    run = subprocess.run(["node", "-e", _VALIDATE_JS, str(path)], capture_output=True,
                         text=True, env=env, timeout=120)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


def bpy_python() -> Path:
    """A Python that can ``import bpy`` (skip with the reason when there is none)."""
    venv = Path(os.environ.get("VIDCAP_BPY_VENV", Path.home() / ".cache" / "vidcap-bpy"))
    python = venv / "bin" / "python"
    if not python.exists():
        pytest.skip(f"no Blender Python module: no venv at {venv} (pip install bpy there; "
                    "bpy wheels exist for one Python version per Blender release)")
    check = subprocess.run([str(python), "-c", "import bpy"], capture_output=True, text=True,
                           timeout=300)
    if check.returncode != 0:
        pytest.skip(f"bpy is not importable in {venv}: {check.stderr.strip()[-300:]}")
    return python


def blender_import(path: str | os.PathLike, fps: float, out_json: Path) -> dict:
    """Import ``path`` with Blender's own importer; every bone's head and tail per frame."""
    python = bpy_python()
    run = subprocess.run([str(python), str(HERE / "blender_probe.py"), str(path), str(fps),
                          str(out_json)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    return json.loads(out_json.read_text())
