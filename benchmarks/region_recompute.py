"""How long the annotate page takes to redo the silhouettes and fit after a region edit
(issue 26, build item 5: "recomputed within seconds").

For each clip the pipeline runs once (into a temporary stage cache, as ``vidcap annotate``
does), then three edits are timed through :meth:`vidcap.ui.session.AnnotateSession.resegment`:

* "corner": a scene region in a corner the person never enters (nothing changes: the
  silhouette pass only);
* "person box": a box around the upper two thirds of the person in the middle frame (that
  frame and the few after change: the silhouette pass and a refit window);
* "head, whole clip": a scene region over the band the person's head crosses (most frames
  change: the whole clip is refitted).

Reference, same run: decoding the clip with PyAV (``vidcap.io.video.iter_frames``).

Run from the repository root: ``python benchmarks/region_recompute.py``. Clips: the
sample ``walk_side.mp4`` and ``../shared/data/video/ido_walk.avi`` when present.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO)]

from vidcap.ui.session import AnnotateSession, load_clip  # noqa: E402

from vidcap.io.video import iter_frames  # noqa: E402

CLIPS = [REPO / "sample_videos" / "walk_side.mp4",
         REPO.parent / "shared" / "data" / "video" / "ido_walk.avi"]


def _decode_s(video: Path) -> float:
    t0 = time.perf_counter()
    for _ in iter_frames(video):
        pass
    return time.perf_counter() - t0


def _edits(masks, size):
    """The three edits: (name, function of the session making it)."""
    w, h = size
    boxes = masks.boxes  # y0, y1, x0, x1
    found = np.flatnonzero(boxes[:, 1] > boxes[:, 0])
    mid = int(found[len(found) // 2])
    y0, y1, x0, x1 = (int(v) for v in boxes[mid])
    tops = boxes[found, 0]
    head = (0, int(tops.min()), w, int(np.median(tops)) + max(4, (y1 - y0) // 12))
    corner = (0, 0, max(4, w // 12), max(4, h // 12))
    upper = (x0, y0, x1, y0 + 2 * (y1 - y0) // 3)
    return [("corner", lambda s: s.add_scene_region(0, box=corner)),
            ("person box", lambda s: s.add_person_box(mid, upper)),
            ("head, whole clip", lambda s: s.add_scene_region(0, box=head))]


def main() -> None:
    print(f"{'clip':<16} {'frames':>6} {'size':>9} {'edit':<17} {'changed':>7}"
          f" {'recompute s':>11} {'CPU s':>6} {'decode s':>8} {'recompute/decode':>16}")
    for video in CLIPS:
        if not video.exists():
            print(f"{video.name:<16} skipped: not here")
            continue
        with tempfile.TemporaryDirectory() as tmp:
            clip = load_clip(video, cache_dir=Path(tmp) / "cache", progress=False)
            decode = _decode_s(video)
            for name, edit in _edits(clip.masks, clip.size):
                s = AnnotateSession(clip, Path(tmp) / "a.json")
                edit(s)
                t0, c0 = time.perf_counter(), time.process_time()
                out = s.resegment()
                wall, cpu = time.perf_counter() - t0, time.process_time() - c0
                w, h = clip.size
                print(f"{video.name:<16} {clip.n_frames:>6} {f'{w}x{h}':>9} {name:<17}"
                      f" {out['changed']:>7} {wall:>11.2f} {cpu:>6.2f} {decode:>8.2f}"
                      f" {wall / decode:>16.1f}")
                for e in s.region_items():  # back to no regions for the next edit
                    s.remove_region(e["frame"], e["type"], e["key"])
                s.resegment()


if __name__ == "__main__":
    main()
