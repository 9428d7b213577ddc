"""Real clips shrunk to Weizmann's height (``silhouettes_real.py --small``).

Why: the independent checks run on Weizmann action clips (180x144, people 70-90 px tall),
and the only real footage at that size with masks the project may use is ido_walk, a
walk. The other real clips (240-1920 rows) hold the cases a walk does not: a man who
stands still (cdnet_office_stand), one who walks in and stays (cdnet_office_enter),
people who sit, people who stand at a table for 10-25 s (onebyone_room), a lab's
one-leg balance (Pose2Sim). Shrunk to 144 rows they are real bodies at the size the
checks use: the clips with true masks (CDnet, SBI) and those scored against MediaPipe's
masks (MediaPipe run on the full-size clip: a reference, not the truth). The video is
scaled by area averaging (as a camera's sensor at that resolution would see it) and
written to H.264 (crf 18); the masks are scaled the same way and kept where at least
half of a pixel was the person (or unscored).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Rows of the shrunk clips: Weizmann's frame height.
SMALL_ROWS = 144


def small_size(hw) -> tuple[int, int] | None:
    """(width, height) of a clip shrunk to :data:`SMALL_ROWS` rows (even, as H.264
    wants), or None when it is no taller than that already."""
    h, w = int(hw[0]), int(hw[1])
    if h <= SMALL_ROWS:
        return None
    return 2 * round(w * SMALL_ROWS / h / 2), SMALL_ROWS


def shrink_masks(masks: np.ndarray, size) -> np.ndarray:
    """(F, H, W) bool masks scaled to ``size`` (width, height) by area: True where at
    least half of the output pixel was True."""
    import cv2

    return np.stack([cv2.resize(m.astype(np.float32), size, interpolation=cv2.INTER_AREA)
                     >= 0.5 for m in masks])


def small_clip(video: Path, masks, out_dir: Path):
    """A real clip and its masks shrunk to :data:`SMALL_ROWS` rows; the video cached in
    ``out_dir``.

    Parameters
    ----------
    video : pathlib.Path
    masks : sequence of numpy.ndarray, each shape (F, H, W), bool
        The clip's reference masks (the truth, the unscored pixels, MediaPipe's).

    Returns
    -------
    (pathlib.Path, list of numpy.ndarray, (int, int)) or None
        The shrunk video, the masks shrunk (each (F, h, w) bool) and its (width,
        height); None when the clip is no taller than :data:`SMALL_ROWS`.
    """
    import cv2

    from vidcap.io.video import iter_frames, probe, write_video

    size = small_size(masks[0].shape[1:])  # (the frames as decoded: upright)
    if size is None:
        return None
    out = out_dir / f"{video.stem}_{size[0]}x{size[1]}.mp4"
    if not out.exists():
        frames = (cv2.resize(f, size, interpolation=cv2.INTER_AREA)
                  for f in iter_frames(video))
        write_video(out, frames, probe(video).fps, crf=18)
    return out, [shrink_masks(m, size) for m in masks], size
