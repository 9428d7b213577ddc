"""``vidcap view``: look at a BVH skeleton or C3D markers in 3D (or save a PNG)."""

from __future__ import annotations

from vidcap.errors import UsageError

NAME = "view"
HELP = "show a BVH skeleton or C3D marker cloud in 3D (or save a PNG with --screenshot)"
ORDER = 60
OUTPUT_FILES = ("screenshot",)
INPUT_FILES = ("file", "centres")


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise UsageError(f"--size must look like 800x600, got {text!r}") from None
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise UsageError(f"--size {text} is out of range (16..8192 pixels a side)")
    return w, h


def add_arguments(parser) -> None:
    parser.add_argument("file", help="a .bvh motion or a .c3d marker file")
    parser.add_argument("--screenshot", metavar="PNG",
                        help="render offscreen to this PNG instead of opening a window")
    parser.add_argument("--frame", type=int, default=None,
                        help="frame to show (0-based, negative from the end; default 0)")
    parser.add_argument("--centres", metavar="CSV",
                        help="joint centres (frame,time_s,joint,x_m,y_m,z_m) to draw over a C3D")
    parser.add_argument("--size", default="800x600", help="window/PNG size WxH (default 800x600)")


def run(args) -> int:
    from vidcap.commands._ui import require

    size = _size(args.size)
    view = require("vidcap.ui.view", needs=("pyvista",))
    view.view(args.file, screenshot=args.screenshot, frame=args.frame, centres=args.centres,
              window_size=size)
    if args.screenshot:
        print(f"wrote {args.screenshot}")
    return 0
