"""Silhouette accuracy: per-frame IoU against ground truth, ours vs the temporal median.

    /work/venv/bin/python benchmarks/silhouette_accuracy.py

Clips: ../shared/data/video/ido_walk.avi with the dataset's own masks
(ido_walk_masks.npz), the full vtest crowd clip (people counted, no truth), and
synthetic clips with exact masks (tests/_synthframes.py: a figure doing jumping
jacks in place, the same under lighting drift, a walker under lighting drift).
When the ``synth`` branch's ``vidcap.synth`` is present, its 'jacks' clip is used too.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests._synthframes import clip  # noqa: E402
from vidcap.video.background import estimate_background  # noqa: E402
from vidcap.video.silhouette import extract_silhouettes  # noqa: E402

DATA = ROOT.parent / "shared" / "data" / "video"


def iou(a, b):
    return (a & b).sum((1, 2)) / np.maximum((a | b).sum((1, 2)), 1)


def score(name, source, truth):
    rows = []
    for method in ("felzenszwalb", "median"):
        t = time.perf_counter()
        bg = estimate_background(source, method=method)
        sil = extract_silhouettes(source, bg, require_person=False)
        dt = time.perf_counter() - t
        if truth is None:
            rows.append((name, method, float("nan"), float("nan"), dt,
                         f"max people {sil.max_people}, frames >1: "
                         f"{int((sil.n_other_blobs > 0).sum())}/{len(sil)}"))
            continue
        i = iou(sil.masks, truth)
        rows.append((name, method, float(np.median(i)), float(np.percentile(i, 10)), dt,
                     f"never seen {100 * bg.never_seen_fraction:.1f}%"))
    return rows


def main() -> int:
    rows = []
    if (DATA / "ido_walk.avi").exists():
        truth = np.load(DATA / "ido_walk_masks.npz")["masks"].astype(bool)
        rows += score("ido_walk (Weizmann)", DATA / "ido_walk.avi", truth)
        rows += score("vtest (PETS crowd, 795 fr)", DATA / "vtest_480x360.avi", None)
    rng = np.random.default_rng
    for name, kw in [("synthetic jacks in place", {}),
                     ("synthetic jacks + drift 25%", {"drift": 0.25}),
                     ("synthetic walk + drift 25%", {"walk": True, "drift": 0.25})]:
        f, m = clip(90, 240, 320, rng=rng(0), **kw)
        rows += score(name, f, m)
    try:
        from vidcap import synth
    except ImportError:
        print("(vidcap.synth not available: its clips are not scored)")
    else:
        # vidcap synth clips rendered in memory at the CLI's default 640x480, 90 frames.
        for name, motion, kw in [
                ("synth jacks, front (yaw 0)", "jacks", {"yaw_deg": 0}),
                ("synth jacks, front, drift 0.1", "jacks",
                 {"yaw_deg": 0, "lighting_drift": 0.1}),
                ("synth jacks, side (yaw 90)", "jacks", {"yaw_deg": 90}),
                ("synth walk, side, drift 0.1", "walk", {"yaw_deg": 90, "lighting_drift": 0.1}),
                ("synth arms, front", "arms", {"yaw_deg": 0})]:
            mo = synth.make_motion(motion, n_frames=90, rng=rng(0))
            f, truth = synth.render_clip(mo, rng=rng(0), **kw)
            rows += score(name, f, truth["masks"])
        # As `vidcap synth --motion jacks --yaw 0 [--lighting-drift 0.1] -o x.mp4`: H.264
        # files (4:2:0 colour, compression) scored as `vidcap silhouettes` reads them.
        import tempfile

        with tempfile.TemporaryDirectory() as tmp:
            for name, kw in [("synth jacks front, H.264 file", {}),
                             ("synth jacks front, drift, H.264", {"lighting_drift": 0.1})]:
                video, tpath = Path(tmp) / "j.mp4", Path(tmp) / "j.npz"
                truth = synth.synth_clip(video, tpath, "jacks", yaw_deg=0,
                                         show_progress=False, **kw)
                rows += score(name, video, truth["masks"])
        # The committed sample clips (H.264 files and their truth).
        for stem in ("walk_side", "walk_three_quarter", "arms"):
            video = ROOT / "sample_videos" / f"{stem}.mp4"
            if video.exists():
                truth = np.load(ROOT / "sample_videos" / f"{stem}_truth.npz")["masks"]
                rows += score(f"sample_videos/{stem}.mp4", video, truth)
    print(f"{'clip':30s} {'method':13s} {'IoU med':>8s} {'IoU p10':>8s} {'secs':>6s}  note")
    for name, method, med, p10, dt, note in rows:
        print(f"{name:30s} {method:13s} {med:8.3f} {p10:8.3f} {dt:6.2f}  {note}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
