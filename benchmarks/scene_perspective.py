"""The camera's perspective k read from the scene (``vidcap convert --camera auto``).

Per real video (``$VIDCAP_DATA/video/*.mp4``, ``$VIDCAP_DATA/masks/*.mp4`` and
``ido_walk.avi``): vidcap's own plate and silhouettes (as ``silhouettes_real.py`` makes them),
then :func:`vidcap.video.vanishing.scene_perspective`: k, the family of vertical lines it
chose and how far the person's axis is from its point, and the CPU time of the estimate.
The reference, computed in the same run: for the three Pose2Sim cameras, k from their
Qualisys calibration and the triangulated subject (``real_clips.known_camera``, as
``pose2d_real.py --rows human-cam`` uses it); the other clips have no calibration (their
cameras are level or, for SBI candela and ibmtest2, high corridor mounts, by eye).

Usage: ``VIDCAP_DATA=/work/data PYTHONPATH=. python benchmarks/scene_perspective.py
[--only NAME]`` (≈ 1 min; skips, saying so, without ``$VIDCAP_DATA``).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from real_clips import known_camera  # noqa: E402
from silhouettes_real import run_vidcap  # noqa: E402

from vidcap.video.fit.perspective import camera_perspective  # noqa: E402
from vidcap.video.vanishing import scene_perspective  # noqa: E402

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "video"


def videos() -> list[Path]:
    """The real videos measured: ido_walk, then ``$VIDCAP_DATA``'s (empty without it)."""
    out = [SHARED / "ido_walk.avi"] if (SHARED / "ido_walk.avi").exists() else []
    data = os.environ.get("VIDCAP_DATA")
    if data:
        for folder in ("video", "masks"):
            out += sorted((Path(data) / folder).glob("*.mp4"))
    return out


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    only = argv[argv.index("--only") + 1] if "--only" in argv else None
    found = [v for v in videos() if not only or only in v.name]
    if not os.environ.get("VIDCAP_DATA"):
        print("(the $VIDCAP_DATA clips: skipped, VIDCAP_DATA is not set; "
              "benchmarks/get_data.sh makes them)")
    print("k from the scene's vertical vanishing point (vidcap.video.vanishing) against a "
          "calibration where one exists")
    print(f"{'video':28} {'k':>6} {'calibrated':>10} {'lines':>5} {'person off':>10} "
          f"{'CPU s':>6}  what was read")
    for video in found:
        masks, plate = run_vidcap(video, "felzenszwalb")
        t = time.process_time()
        got = scene_perspective(plate.plate, masks)
        cpu = time.process_time() - t
        cam = known_camera(video.stem)
        ref = f"{camera_perspective(*cam):10.3f}" if cam is not None else f"{'':>10}"
        off = f"{got.misfit_deg:9.1f}°" if got.segments else f"{'':>10}"
        print(f"{video.name:28} {got.k:6.3f} {ref} {got.segments:5d} {off} {cpu:6.2f}  "
              f"{got.reason}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
