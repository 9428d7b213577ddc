"""``vidcap review``: a side-by-side review video of a conversion."""

from __future__ import annotations

import argparse
import zipfile
from pathlib import Path

import numpy as np

from vidcap.errors import InputFileError, UsageError
from vidcap.video.masks import frames_with_pixels, read_npz_masks

NAME = "review"
HELP = "write a review video: frame | silhouette with the 2D model | 3D pose"
ORDER = 12
OUTPUT_FILES = ("output",)
INPUT_FILES = ("video", "from_npz")
OUTPUT_DIRS = ("png",)

_KEYS = ("masks", "joints2d", "bvh_joints3d")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``vidcap review`` parser."""
    parser.add_argument("video", help="the input video")
    parser.add_argument("-o", "--output", metavar="review.mp4",
                        help="review video to write")
    parser.add_argument("--from", dest="from_npz", metavar="OUT.npz",
                        help="results saved by `vidcap convert --save` (default: convert now)")
    parser.add_argument("--png", metavar="DIR", help="write PNG frames into DIR instead")
    parser.add_argument("--height", type=float, default=1.75, metavar="M",
                        help="subject's height in metres when converting (default 1.75)")
    parser.add_argument("--min-height", type=int, default=360, metavar="PX",
                        help="enlarge the panels of smaller videos by a whole factor to at "
                             "least PX pixels tall (default 360; 0: never)")
    parser.add_argument("--max-height", type=int, default=720, metavar="PX",
                        help="shrink the panels of taller videos to PX pixels tall, so the "
                             "review stays playable (default 720; 0: never)")


def _load(path) -> dict:
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in _KEYS if k not in z.files]
            if missing:
                raise InputFileError(f"not a `vidcap convert --save` file (lacks {missing})",
                                     path)
            out = {k: z[k] for k in z.files if k != "masks"}
        out["masks"] = read_npz_masks(path)  # frame by frame: a long clip's are big
        return out
    except InputFileError:
        raise
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as exc:
        raise InputFileError(f"cannot read ({exc})", path) from None


def run(args) -> int:
    """Run ``vidcap review``."""
    import cv2

    from vidcap.io.video import iter_frames, probe
    from vidcap.video.review import review_frames

    if args.max_height < 0 or args.min_height < 0:
        raise UsageError("--min-height and --max-height are pixels (0 or more)")
    if not args.output and not args.png:
        raise UsageError("give -o review.mp4 or --png DIR")
    info = probe(args.video)
    if args.from_npz:
        d = _load(args.from_npz)
    else:
        from vidcap.video.pipeline import run as run_pipeline

        res = run_pipeline(args.video, height=args.height)
        d = {"masks": res.masks, "joints2d": res.lifted.joints2d,
             "bvh_joints3d": res.motion.positions(), "scores": res.scores,
             "similarity": res.similarity, "outside": res.outside}
    n = len(d["masks"])
    if args.from_npz:
        # results of another video (or of another cut of it) would be drawn over
        # frames they do not belong to: refuse them
        h, w = d["masks"].shape[1:]
        if (w, h) != (info.width, info.height):
            raise InputFileError(f"saved for a {w}x{h} video, but {args.video} is "
                                 f"{info.width}x{info.height}", args.from_npz)
        if info.n_frames and abs(info.n_frames - n) > 1:
            raise InputFileError(f"saved for {n} frames, but {args.video} has "
                                 f"{info.n_frames}", args.from_npz)
    filled = ~frames_with_pixels(d["masks"])
    if d.get("outside") is not None:  # (saved by versions that leave such frames out)
        filled |= np.asarray(d["outside"], bool)
    frames = (f for i, f in enumerate(iter_frames(args.video)) if i < n)
    imgs = review_frames(frames, d["masks"], d["joints2d"], d["bvh_joints3d"],
                         scores=d.get("scores"), similarity=d.get("similarity"),
                         height=args.height, min_height=args.min_height, filled=filled,
                         max_height=args.max_height)
    if args.png:
        out = Path(args.png)
        out.mkdir(parents=True, exist_ok=True)
        for i, img in enumerate(imgs):
            if not cv2.imwrite(str(out / f"review_{i:05d}.png"), img):
                raise InputFileError("cannot write PNG frames here", out)
        print(f"{out}: {n} review frames")
    if args.output:
        from vidcap.io.video import write_video

        if args.png:
            imgs = (cv2.imread(str(Path(args.png) / f"review_{i:05d}.png")) for i in range(n))
        count = write_video(args.output, imgs, info.fps)
        print(f"{args.output}: {count} review frames")
    return 0
