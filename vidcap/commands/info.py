"""``vidcap info VIDEO...``: what a video holds (frames, fps, size, codec)."""

from __future__ import annotations

from vidcap.io.video import probe

NAME = "info"
HELP = "print frame count, frame rate, size and codec of videos (checks they decode)"
ORDER = 90


def add_arguments(parser) -> None:
    parser.add_argument("videos", nargs="+", metavar="VIDEO", help="video files")
    parser.add_argument(
        "--count", action="store_true",
        help="decode every frame to count them (slower; proves the file decodes to the end)",
    )


def run(args) -> int:
    """Run ``vidcap info``: one line per video; a bad file is reported in its place
    (``vidcap: error: ...``) and the others still listed; exit 2 if any was bad."""
    import sys

    from vidcap.errors import VidcapError

    bad = 0
    for path in args.videos:
        try:
            info = probe(path, count=args.count)
        except VidcapError as exc:
            if len(args.videos) == 1:
                raise
            print(f"vidcap: error: {exc}", file=sys.stderr)
            bad += 1
            continue
        print(
            f"{path}: {info.n_frames} frames, {info.fps:g} fps, {info.width}x{info.height}, "
            f"{info.codec}, {info.duration:.2f} s", flush=True
        )
    return 2 if bad else 0
