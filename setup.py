"""Package layout that pyproject.toml cannot express on its own.

The interactive apps live in the repository's top-level ``ui/`` folder but are installed
as ``vidcap.ui`` (no top-level ``ui`` package after install, so nothing collides with
another project's ``ui``). Everything else is in ``pyproject.toml``.
"""

from setuptools import find_packages, setup

UI_PACKAGES = ["vidcap.ui", *(f"vidcap.ui.{p}" for p in find_packages("ui"))]

setup(
    packages=find_packages(include=["vidcap", "vidcap.*"]) + UI_PACKAGES,
    package_dir={"vidcap.ui": "ui"},
)
