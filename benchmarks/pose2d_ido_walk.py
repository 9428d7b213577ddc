"""2D pose on a real video: Weizmann ``ido_walk.avi`` with its ground-truth silhouettes.

Fits the model to the dataset's own silhouettes (``ido_walk_masks.npz``; the
silhouette stage is measured elsewhere), prints the similarity S of the fitted model
per frame (no joint ground truth exists for this clip) and writes a contact sheet:
every fifth frame with the tracked fit drawn over it, cropped around the walker
(image-left limbs in orange, image-right limbs in cyan, torso and head in white).

Data: Blank, Gorelick et al., "Actions as Space-Time Shapes", ICCV 2005.
Usage: ``PYTHONPATH=. python benchmarks/pose2d_ido_walk.py [-o docs/pose2d_ido_walk.png]``
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from vidcap.body import SEGMENT_JOINTS, SEGMENT_NAMES  # noqa: E402
from vidcap.io.video import read_frames  # noqa: E402
from vidcap.video.fit.pose2d import fit_pose, fit_sequence  # noqa: E402

DATA = REPO.parent / "shared" / "data" / "video"


def draw(frame: np.ndarray, joints: np.ndarray, scale: int = 3) -> np.ndarray:
    """Frame enlarged ``scale`` times with the 2D skeleton drawn over it."""
    img = cv2.resize(frame, None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)
    if not np.isfinite(joints).all():
        return img
    for name, (a, b) in zip(SEGMENT_NAMES, SEGMENT_JOINTS, strict=True):
        colour = (0, 140, 255) if name.startswith("l_") else (
            (255, 255, 0) if name.startswith("r_") else (255, 255, 255))
        pa = tuple(int(v) for v in np.round((joints[a] + 0.5) * scale - 0.5))
        pb = tuple(int(v) for v in np.round((joints[b] + 0.5) * scale - 0.5))
        cv2.line(img, pa, pb, colour, 2, cv2.LINE_AA)
    return img


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("-o", "--output", default=str(REPO / "docs" / "pose2d_ido_walk.png"))
    ap.add_argument("--every", type=int, default=5)
    args = ap.parse_args(argv)
    frames = read_frames(DATA / "ido_walk.avi")
    masks = np.load(DATA / "ido_walk_masks.npz")["masks"].astype(bool)
    rows = []
    for tracked in (False, True):
        pose = fit_sequence(masks, tracked=tracked)
        s = pose.similarity[pose.similarity > 0]
        rows.append(("tracked" if tracked else "per-frame", s, pose))
    print(f"ido_walk.avi: {len(masks)} frames, {masks.shape[2]}x{masks.shape[1]}, "
          "similarity S of the fitted model to the true silhouette")
    print(f"{'mode':10} {'median S':>9} {'min S':>7} {'warm':>6}")
    for mode, s, pose in rows:
        print(f"{mode:10} {np.median(s):9.3f} {s.min():7.3f} {pose.warm.mean():6.0%}")
    # how much the fit cares whether the body is seen from the side or the front: S of
    # per-frame fits with the shoulders' and hips' spread fixed at 0 (side) and at 1
    # (front), here and on the synthetic side view of sample_videos/ (same run)
    print("\nS of per-frame fits, spread fixed at 0 (side) and 1 (front):")
    print(f"{'clip':22} {'side better':>11} {'front better':>12} {'max |gap|':>9}")
    truth = REPO / "sample_videos" / "walk_side_truth.npz"
    clips = [("ido_walk (real side)", masks)]
    if truth.exists():
        clips.append(("walk_side (synthetic)", np.load(truth)["masks"]))
    for label, ms in clips:
        gap = np.array([fit_pose(m, spread_value=0.0).similarity
                        - fit_pose(m, spread_value=1.0).similarity for m in ms if m.any()])
        print(f"{label:22} {np.mean(gap > 0):11.0%} {np.mean(gap < 0):12.0%} "
              f"{np.abs(gap).max():9.3f}")
    pose = rows[1][2]
    picks = list(range(0, len(frames), args.every))
    scale, tiles = 3, []
    ys = np.flatnonzero(masks.any(axis=(0, 2)))
    y0, y1 = max(ys[0] - 8, 0), min(ys[-1] + 8, masks.shape[1])
    for k in picks:  # a window around the walker, enlarged, with frame number and S
        xs = np.flatnonzero(masks[k].any(axis=0))
        if xs.size == 0:
            continue
        cx = int(xs.mean())
        x0 = int(np.clip(cx - 30, 0, masks.shape[2] - 60))
        t = draw(frames[k], pose.joints2d[k], scale)[y0 * scale : y1 * scale,
                                                    x0 * scale : (x0 + 60) * scale]
        t = np.ascontiguousarray(t)
        cv2.putText(t, f"{k} S={pose.similarity[k]:.2f}", (3, 14), cv2.FONT_HERSHEY_SIMPLEX,
                    0.45, (0, 255, 0), 1, cv2.LINE_AA)
        tiles.append(t)
    sheet = np.hstack(tiles)
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    ok, buf = cv2.imencode(".png", sheet, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    from vidcap.fileio import atomic_path

    with atomic_path(args.output) as tmp:
        tmp.write_bytes(buf.tobytes())
    print(f"contact sheet: {args.output} ({len(buf) // 1024} KiB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
