"""The motion a ground-truth clip is posed with (:func:`make_motion`): a built-in
procedural one or a BVH / ASF+AMC file retargeted onto our skeleton, optionally cut to a
frame range (:func:`parse_range`) and resampled."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from vidcap.body import (
    BodyModel,
)
from vidcap.errors import InputFileError, UsageError
from vidcap.kinematics import Motion
from vidcap.synth.procedural import (
    BUILTIN_MOTIONS,
    arms_motion,
    jacks_motion,
    sit_motion,
    walk_motion,
)
from vidcap.synth.retarget import (
    retarget,
)

#: The built-in motions by name.
_PROCEDURAL = {"walk": walk_motion, "jacks": jacks_motion, "arms": arms_motion,
               "sit": sit_motion}


def parse_range(text: str | None) -> tuple[int | None, int | None]:
    """Parse ``"START:END"`` (either may be empty; END exclusive) into integers."""
    if text is None:
        return None, None
    head, sep, tail = str(text).partition(":")
    try:
        if not sep:
            raise ValueError
        a = int(head) if head.strip() else None
        b = int(tail) if tail.strip() else None
    except ValueError:
        raise UsageError(f"--range must be START:END in frames, got {text!r}") from None
    return a, b


def make_motion(
    name_or_path: str | os.PathLike,
    *,
    body: BodyModel | None = None,
    amc: str | os.PathLike | None = None,
    frame_range: tuple[int | None, int | None] | None = None,
    fps: float | None = None,
    n_frames: int = 90,
    rng: np.random.Generator | None = None,
) -> Motion:
    """A motion on our skeleton: a built-in one or a retargeted motion file.

    Parameters
    ----------
    name_or_path : str or path-like
        ``'walk'``, ``'jacks'``, ``'arms'``, ``'sit'`` (:data:`BUILTIN_MOTIONS`), a ``.bvh`` file
        or an ``.asf`` file (with ``amc``).
    body : BodyModel, optional
        Target body (default 1.75 m).
    amc : str or path-like, optional
        The AMC motion for an ASF skeleton.
    frame_range : (start, stop), optional
        Source frames to keep (stop exclusive; ``None`` = open end), before resampling.
    fps : float, optional
        Output frame rate: resamples a file's motion; the rate of a built-in one
        (default 30).
    n_frames : int
        Frames of a built-in motion (before ``frame_range``).
    rng : numpy.random.Generator, optional
        Variations of a built-in motion.

    Raises
    ------
    VidcapError
        Unknown motion, missing/malformed file, unmappable skeleton, empty range.
    """
    body = body or BodyModel()
    name = str(name_or_path)
    if name in _PROCEDURAL:
        if n_frames < 1:
            raise UsageError(f"need at least one frame, got {n_frames}")
        motion = _PROCEDURAL[name](body, n_frames=n_frames, fps=fps or 30.0, rng=rng)
        return _slice(motion, frame_range, name)
    path = Path(name)
    suffix = path.suffix.lower()
    if not path.exists():
        raise InputFileError(
            f"no such motion file (built-in motions: {', '.join(BUILTIN_MOTIONS)})", path
        )
    if suffix == ".bvh":
        from vidcap.io.bvh import read_bvh

        src = read_bvh(path)
    elif suffix == ".asf":
        if amc is None:
            raise UsageError("an ASF skeleton needs its motion: pass --amc M.amc", path)
        from vidcap.io.asf import read_asf_amc

        src = read_asf_amc(path, amc)
    elif suffix == ".amc":
        raise UsageError("pass the .asf skeleton as the motion and this file as --amc", path)
    else:
        raise UsageError("motion must be a .bvh or .asf file or a built-in name", path)
    src = _slice(src, frame_range, path)
    if fps is not None and abs(fps - src.fps) > 1e-6 and src.n_frames > 1:
        src = src.resampled(fps)
    return retarget(src, body, source=path)


def _slice(motion: Motion, frame_range, source) -> Motion:
    if frame_range is None or frame_range == (None, None):
        return motion
    start, stop = frame_range
    F = motion.n_frames
    a = 0 if start is None else (start + F if start < 0 else start)
    b = F if stop is None else (stop + F if stop < 0 else stop)
    a, b = max(a, 0), min(b, F)
    if b <= a:
        raise UsageError(
            f"frame range {start}:{stop} selects no frames of the {F} in the motion", source
        )
    return motion.frames(a, b)
