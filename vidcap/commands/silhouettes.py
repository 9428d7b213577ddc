"""``vidcap silhouettes``: background plate and the person's silhouette per frame."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

NAME = "silhouettes"
HELP = "estimate the background and extract the person's silhouette in every frame (.npz)"
ORDER = 30
OUTPUT_FILES = ("output", "plate_out")
INPUT_FILES = ("video", "background")


def add_arguments(parser) -> None:
    parser.add_argument("video", type=Path, help="input video (static camera)")
    parser.add_argument("-o", "--output", type=Path, required=True,
                        help="output .npz: masks (F,H,W) bool, bbox (F,4) x0,y0,x1,y1 "
                             "(exclusive ends), plate (H,W,3) uint8, confidence (H,W), ...")
    parser.add_argument("--background", type=Path, metavar="PLATE.png|START:END",
                        help="use this image of the empty scene instead of estimating one, "
                             "or frames of the video that show the scene empty (START:END, "
                             "counted from 0, END excluded; either may be left out)")
    parser.add_argument("--method", choices=("felzenszwalb", "median"), default="felzenszwalb",
                        help="background estimate: Felzenszwalb regions + per-pixel votes "
                             "(default) or the plain temporal median")
    parser.add_argument("--threshold", type=float, metavar="T",
                        help="foreground threshold on the colour difference summed over "
                             "B, G, R (grey levels, 0-765; default: from the video's noise)")
    parser.add_argument("--samples", type=int, default=24, metavar="N",
                        help="frames sampled for the background (default 24)")
    parser.add_argument("--no-shadows", action="store_true",
                        help="do not suppress shadows")
    parser.add_argument("--graph-cut", action=argparse.BooleanOptionalAction, default=None,
                        help="re-decide a band round the person by a graph cut on the clip's "
                             "colours where they tell the person from the scene (default as in "
                             "vidcap convert: on; better on the in-place renders, level on "
                             "real clips; see benchmarks/RESULTS.md); needs the estimated "
                             "felzenszwalb plate")
    parser.add_argument("--still-person", action=argparse.BooleanOptionalAction, default=None,
                        help="also re-take the plate from frames that show the empty scene, "
                             "and look for a person who never moves with a person detector "
                             "(OpenCV's HOG) and a cut in its box (default as in vidcap "
                             "convert; see benchmarks/RESULTS.md); needs the estimated "
                             "felzenszwalb plate")
    parser.add_argument("--plate-out", type=Path, metavar="PNG",
                        help="also write the background plate as an image")


def run(args) -> int:
    import cv2
    import numpy as np

    from vidcap.errors import UsageError
    from vidcap.fileio import atomic_path, savez_atomic
    from vidcap.io.video import probe
    from vidcap.video.background import estimate_plate, load_plate
    from vidcap.video.silhouette import extract_silhouettes

    if args.output.suffix.lower() != ".npz":
        raise UsageError("the output must be a .npz file", args.output)
    if args.threshold is not None and not 0 < args.threshold < 765:
        raise UsageError(f"--threshold must be in (0, 765), got {args.threshold}")
    if args.samples < 2:
        raise UsageError("--samples must be at least 2")
    from vidcap.video.pipeline import DEFAULT_GRAPH_CUT, default_still_person

    # the cut's colour models and the still-person passes are the plate stage's own
    graph_cut = _on_estimated_plate(args, "--graph-cut", args.graph_cut, DEFAULT_GRAPH_CUT)
    still = _on_estimated_plate(args, "--still-person", args.still_person,
                                default_still_person())
    info = probe(args.video)
    if args.background is not None:
        bg = load_plate(args.background, args.video)
        if bg.plate.shape[:2] != (info.height, info.width):
            raise UsageError(
                f"the background image is {bg.plate.shape[1]}x{bg.plate.shape[0]} but the "
                f"video is {info.width}x{info.height}", args.background)
    else:
        bg = estimate_plate(args.video, colour_models=graph_cut, still_person=still,
                            method=args.method, n_samples=args.samples)
    sil = extract_silhouettes(args.video, bg, threshold=args.threshold,
                              shadows=not args.no_shadows,
                              graph_cut=graph_cut and bg.colours is not None)
    savez_atomic(
        args.output, masks=sil.masks, bbox=sil.bbox, heights=sil.heights, areas=sil.areas,
        found=sil.found, n_other_blobs=sil.n_other_blobs, others=sil.others,
        foreground_fraction=sil.foreground_fraction, gains=sil.gains,
        plate=bg.plate, confidence=bg.confidence, never_seen=bg.never_seen,
        threshold=np.float64(sil.threshold), method=np.str_(bg.method), fps=info.fps,
    )
    if args.plate_out is not None:
        with atomic_path(args.plate_out) as tmp:
            if not cv2.imwrite(str(tmp), bg.plate):
                raise UsageError("cannot write an image with this suffix", args.plate_out)
    n = len(sil)
    from vidcap.video.inputchecks import plate_notice

    notice = plate_notice(bg)
    if notice:
        print(notice, file=sys.stderr)
    if args.background is None:
        from vidcap.video.stillcheck import still_warning

        still = still_warning(sil.bbox, (info.height, info.width))
        if still:
            print(still, file=sys.stderr)
    multi = int((sil.n_other_blobs > 0).sum())
    print(f"{args.output}: {n} frames, person found in {int(sil.found.sum())}, "
          f"threshold {sil.threshold:.1f}, background {bg.method}"
          f" (never seen uncovered: {100 * bg.never_seen_fraction:.1f}% of the frame)")
    if multi:
        print(f"more than one person-sized blob in {multi} of {n} frames (up to "
              f"{sil.max_people} at once); the largest is kept", file=sys.stderr)
    unreliable = int((sil.foreground_fraction > 0.5).sum())
    if unreliable:
        print(f"warning: {unreliable} frames differ from the background almost everywhere "
              "(camera moved or lighting jumped); their masks are unreliable", file=sys.stderr)
    return 0


def _on_estimated_plate(args, flag: str, asked: bool | None, default: bool) -> bool:
    """Whether an option of the estimated plate (``flag``) is on: ``asked`` (None: not
    given, then ``default``), off where the plate is not estimated by the Felzenszwalb
    regions (``--background``, ``--method median``), and an error where the user asked
    for it there."""
    on = default if asked is None else asked
    if on and (args.background is not None or args.method != "felzenszwalb"):
        if asked:
            from vidcap.errors import UsageError

            raise UsageError(f"{flag} needs the estimated plate (not --background, not "
                             "--method median)")
        return False
    return on
