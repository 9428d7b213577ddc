"""More held-out motions for the 2D fit (issue 27): CMU trials nobody tuned the fit on.

``pose2d_accuracy.py --held-out`` fitted 40 clips cut from five motions (CMU 131_01 and
07_07, the built-in walk, jacks and arms). Issue 27 asks for motions nobody tuned on; the
CMU iClone trials of ``$VIDCAP_DATA/mocap/cmu_iclone_humanik`` (subjects 1, 2, 3, 5 and 6:
playground, everyday chores, walks on uneven ground, dance, basketball; benchmarks/DATA.md)
give 43 more. One 2 s stretch per trial, by a rule fixed before any was rendered or
fitted (session 38):

* the stretch starts 1 s before the trial's middle; when it overlaps a stretch the fit
  was tuned on (``pose2d_accuracy.LOW``) or a silhouette render marked tuning in
  ``silhouettes_real.RENDERS`` (the 2D fit's ensemble was chosen on those), the stretch
  at a quarter, then at three quarters of the trial is taken instead, else the trial
  is left out;
* two views per trial, in turn: a side view from (90, 75, 120, 105) and a
  three-quarter or front view from (45, 0, 30, 150, 60, 20, 135, 160).

The clip solve's pose prior (``vidcap/data/pose_prior.npz``, ``build_pose_prior.py``) was
fitted on these trials: the table's ``+solve`` columns are not held out from the prior,
its plain columns are.

:func:`cmu_motions` yields them as ``pose2d_accuracy.held_out_motions`` does its own.
"""

from __future__ import annotations

import os
from pathlib import Path

#: Seconds per stretch (60 frames at 30 fps, as the other held-out clips).
STRETCH_S = 2.0
#: The side views and the other views taken in turn, one of each per trial.
SIDE_YAWS = (90, 75, 120, 105)
OTHER_YAWS = (45, 0, 30, 150, 60, 20, 135, 160)
#: The trials' source rate (the iClone BVH files), frames per second.
SOURCE_FPS = 60.0


def _folder() -> Path | None:
    data = os.environ.get("VIDCAP_DATA")
    folder = Path(data) / "mocap" / "cmu_iclone_humanik" if data else None
    return folder if folder and folder.is_dir() else None


def _used_stretches() -> dict[str, list[tuple[float, float]]]:
    """Per trial ("02_06"), the stretches (seconds) something was tuned on."""
    import silhouettes_real
    from pose2d_accuracy import LOW

    used: dict[str, list[tuple[float, float]]] = {}
    for _, source, first, _ in LOW:
        if source != "131_01":
            used.setdefault(source[1:], []).append((first, first + STRETCH_S))
    for row in silhouettes_real.RENDERS:
        motion, use = row[1], row[-1]
        if use != "tuning" or not isinstance(motion, tuple):
            continue
        if motion[0] == "hold":  # a held pose: the source frames it sways through
            start = motion[2] / SOURCE_FPS
            used.setdefault(motion[1], []).append((start, start + 1.0))
        elif len(motion) == 3:
            used.setdefault(motion[0], []).append((motion[1] / SOURCE_FPS,
                                                   motion[2] / SOURCE_FPS))
    return used


def cmu_stretches() -> list[tuple[str, Path, float, tuple[int, int]]]:
    """The rule's stretches: ``(name, bvh path, start s, (side yaw, other yaw))``;
    empty when ``$VIDCAP_DATA`` has no trials."""
    from vidcap.io.bvh import read_bvh

    folder = _folder()
    if folder is None:
        return []
    used = _used_stretches()
    out = []
    for path in sorted(folder.glob("*_humanik.bvh")):
        trial = path.stem.removesuffix("_humanik")[1:]  # "002_06" -> "02_06"
        clip = read_bvh(path)
        length = clip.n_frames / clip.fps
        for at in (0.5, 0.25, 0.75):
            start = max(0.0, round(at * length - STRETCH_S / 2, 1))
            if start + STRETCH_S > length:
                continue
            if not any(start < b and start + STRETCH_S > a for a, b in used.get(trial, [])):
                break
        else:
            continue
        i = len(out)
        yaws = (SIDE_YAWS[i % len(SIDE_YAWS)], OTHER_YAWS[i % len(OTHER_YAWS)])
        out.append((f"{trial} {start:g}-{start + STRETCH_S:g}s", path, start, yaws))
    return out


def cmu_motions(frames: int, body=None):
    """``(name, motion of ``frames`` frames at 30 fps, yaws)`` per :func:`cmu_stretches`
    stretch, on ``body``'s skeleton (default: the seed's)."""
    from vidcap.synth import make_motion

    for name, path, start, yaws in cmu_stretches():
        first = int(round(start * SOURCE_FPS))
        motion = make_motion(path, body=body, fps=30.0,
                             frame_range=(first, first + int(round(STRETCH_S * SOURCE_FPS)) + 1))
        yield name, motion.frames(0, min(frames, motion.n_frames)), yaws
