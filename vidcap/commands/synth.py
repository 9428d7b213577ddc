"""``vidcap synth``: render a ground-truth clip of the body model moving."""

from __future__ import annotations

import argparse

import numpy as np

from vidcap.errors import UsageError

NAME = "synth"
HELP = "render a ground-truth clip (video + truth .npz) of the body model performing a motion"
ORDER = 90
OUTPUT_FILES = ("output", "truth", "bvh")
INPUT_FILES = ("motion", "amc", "background")


def parse_size(text: str) -> tuple[int, int]:
    """Parse ``WIDTHxHEIGHT`` (even, at least 8x8) into ``(width, height)``."""
    try:
        w, h = (int(v) for v in str(text).lower().split("x"))
    except ValueError:
        raise UsageError(f"--size must be WIDTHxHEIGHT, got {text!r}") from None
    if w < 8 or h < 8:
        raise UsageError(f"--size must be at least 8x8, got {text!r}")
    if w % 2 or h % 2:  # H.264 (yuv420p) needs even sizes; padding would break the truth
        raise UsageError(f"--size must be even in both directions, got {text!r}")
    return w, h


def parse_proportions(text: str) -> dict[str, float]:
    """Parse ``NAME=FACTOR,...`` (``--proportions``) into a dict; UsageError if malformed
    or a name is unknown."""
    from vidcap.body import body_with_proportions

    out = {}
    for part in str(text).split(","):
        name, sep, value = part.partition("=")
        try:
            if not sep:
                raise ValueError
            out[name.strip()] = float(value)
        except ValueError:
            raise UsageError(f"--proportions must be NAME=FACTOR,..., got {text!r}") from None
    try:
        body_with_proportions(1.75, out)
    except ValueError as exc:
        raise UsageError(f"--proportions: {exc}") from None
    return out


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``vidcap synth`` parser."""
    parser.add_argument(
        "--motion", default="walk", metavar="walk|jacks|arms|sit|M.bvh|M.asf",
        help="built-in motion or a BVH / ASF file to retarget onto the body (default: walk)",
    )
    parser.add_argument("--amc", metavar="M.amc", help="AMC motion for an ASF skeleton")
    parser.add_argument(
        "--range", metavar="START:END", help="source frames to use (END exclusive, either optional)"
    )
    parser.add_argument(
        "--fps", type=float, help="output frame rate (resamples a file's motion; default: "
        "the file's rate, 30 for built-in motions)",
    )
    parser.add_argument(
        "--frames", type=int, default=90, help="frames of a built-in motion (default 90)"
    )
    parser.add_argument(
        "--yaw", type=float, default=90.0, metavar="DEG",
        help="body yaw relative to the camera, from the motion's mean heading: 0 = facing "
        "the camera, 90 = side view facing image right (default 90)",
    )
    parser.add_argument(
        "--elevation", type=float, default=0.0, metavar="DEG",
        help="downward tilt of the camera in degrees (default 0)",
    )
    parser.add_argument(
        "--ppm", type=float, metavar="PX", help="pixels per metre (default: the figure fills "
        "3/4 of the image height, less if the motion needs more room)",
    )
    parser.add_argument(
        "--floor", type=float, metavar="FRAC", help="image row of the floor as a fraction of "
        "the height from the top (default: centre the motion vertically)",
    )
    parser.add_argument("--size", default="640x480", metavar="WxH",
                        help="image size (default 640x480)")
    parser.add_argument("-o", "--output", required=True, metavar="CLIP.mp4", help="video to write")
    parser.add_argument("--truth", metavar="TRUTH.npz",
                        help="truth to write (default: CLIP_truth.npz beside the video)")
    parser.add_argument("--bvh", metavar="OUT.bvh", help="also write the motion on our skeleton")
    parser.add_argument("--background", metavar="IMG", help="background image (default: a "
                        "procedural room)")
    parser.add_argument("--noise", type=float, default=2.0,
                        help="Gaussian pixel noise sigma in grey levels (default 2)")
    parser.add_argument("--lighting-drift", type=float, default=0.0, metavar="AMOUNT",
                        help="relative amplitude of a slow brightness/colour drift (e.g. 0.1)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--height", type=float, default=1.75, help="body height in metres")
    parser.add_argument("--proportions", metavar="human|seed|NAME=FACTOR,...",
                        default="human",
                        help="the body: a real adult's (human, the default: the body vidcap "
                        "convert and pose2d fit by default, feet drawn below the ankles), the "
                        "seed's Table 3.1/3.2 ratios (seed: ankles on the floor), "
                        "or one scaled away from the seed's ratios, e.g. "
                        "legs=1.15,arms=0.9,shoulders=1.2 (groups: head, torso, upper_arms, "
                        "lower_arms, upper_legs, lower_legs, arms, legs; widths: shoulders, "
                        "head_width, arm_width, leg_width); --height stays the standing height")


def run(args: argparse.Namespace) -> int:
    """Render the clip and write the video, the truth and optionally the BVH."""
    from pathlib import Path

    from vidcap.body import BodyModel, body_with_proportions
    from vidcap.synth import make_motion, parse_range, synth_clip

    if not (np.isfinite(args.height) and 0.5 <= args.height <= 3.0):
        raise UsageError(f"--height must be between 0.5 and 3 metres, got {args.height}")
    if args.fps is not None and not args.fps > 0:
        raise UsageError(f"--fps must be positive, got {args.fps}")
    if args.frames < 1:
        raise UsageError(f"--frames must be at least 1, got {args.frames}")
    size = parse_size(args.size)
    out = Path(args.output)
    truth = Path(args.truth) if args.truth else out.with_name(out.stem + "_truth.npz")
    foot = 0.0
    if args.proportions in (None, "seed"):
        body = BodyModel(height=args.height)
    elif args.proportions == "human":
        from vidcap.video.fit.proportions import human_proportions

        est = human_proportions()
        body, foot = est.body(args.height), est.foot
    else:
        body = body_with_proportions(args.height, parse_proportions(args.proportions))
    rng = np.random.default_rng(args.seed)
    motion = make_motion(
        args.motion, body=body, amc=args.amc, frame_range=parse_range(args.range),
        fps=args.fps, n_frames=args.frames, rng=rng,
    )
    result = synth_clip(
        out, truth, motion, bvh_path=args.bvh, rng=rng, body=body, size=size,
        yaw_deg=args.yaw, elevation_deg=args.elevation, pixels_per_metre=args.ppm,
        floor_frac=args.floor, background=args.background, noise=args.noise,
        lighting_drift=args.lighting_drift, foot=foot,
    )
    print(f"wrote {out} ({len(result['joints3d'])} frames, {size[0]}x{size[1]}, "
          f"{motion.fps:g} fps) and {truth}")
    return 0
