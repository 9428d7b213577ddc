"""Write a motion to the file format its name asks for, on the rig asked for.

``.glb`` and ``.gltf`` give glTF 2.0 (:mod:`vidcap.io.gltf`); every other name gives BVH
(:mod:`vidcap.io.bvh`), as ``vidcap`` always wrote. Both take the same joint-rotation
data, a :class:`vidcap.kinematics.Motion`, renamed and re-jointed first for
``--rig mixamo|humanik`` (:func:`vidcap.io.rigs.retarget`).
"""

from __future__ import annotations

import os
from pathlib import Path

from vidcap.kinematics import Motion

#: ``--format`` choices of ``vidcap batch`` and the extension each writes.
FORMATS = {"bvh": ".bvh", "glb": ".glb", "gltf": ".gltf"}


def is_gltf(path: str | os.PathLike) -> bool:
    """Whether ``path``'s extension selects glTF output."""
    from vidcap.io.gltf import GLTF_SUFFIXES

    return Path(path).suffix.lower() in GLTF_SUFFIXES


def output_files(path: str | os.PathLike) -> list[Path]:
    """Every file that writing ``path`` creates (a ``.gltf`` brings its ``.bin``)."""
    p = Path(path)
    return [p, p.with_suffix(".bin")] if p.suffix.lower() == ".gltf" else [p]


def write_motion(path: str | os.PathLike, motion: Motion, *, rig: str = "vidcap",
                 times=None) -> list[Path]:
    """Write ``motion`` as BVH or glTF by ``path``'s extension, atomically.

    Parameters
    ----------
    path : str or path-like
        Output file: ``.glb`` / ``.gltf`` for glTF 2.0, anything else for BVH.
    motion : Motion
        Our skeleton's motion (-Z forward, metres); for ``rig`` other than
        ``"vidcap"`` it must be the video path's 15-joint skeleton.
    rig : {'vidcap', 'mixamo', 'humanik'}
        Joint names and hierarchy (:mod:`vidcap.io.rigs`).
    times : array_like, shape (F,), optional
        Frame times in seconds for glTF (BVH has a fixed frame time, 1/fps).

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    vidcap.errors.UsageError
        If ``rig`` is unknown or does not fit the skeleton.
    """
    from vidcap.io.rigs import get_rig, retarget

    spec = get_rig(rig)
    out = retarget(motion, spec)
    if is_gltf(path):
        from vidcap.io.gltf import write_gltf

        name = "Armature" if spec.name == "mixamo" else spec.name
        return write_gltf(path, out, times=times, end_names=spec.end_site_names(),
                          forward=spec.forward, name=name)
    from vidcap.io.bvh import write_bvh

    write_bvh(path, out)
    return [Path(path)]


__all__ = ["FORMATS", "is_gltf", "output_files", "write_motion"]
