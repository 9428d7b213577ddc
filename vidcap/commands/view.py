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


def has_display() -> bool:
    """Whether a window can be opened: an X11 or Wayland display on Linux and the BSDs
    (macOS and Windows always have one)."""
    import os
    import sys

    if sys.platform.startswith(("linux", "freebsd", "openbsd", "netbsd")):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


def run(args) -> int:
    from vidcap.commands._ui import require

    size = _size(args.size)
    if not args.screenshot and not has_display():
        raise UsageError("no display to open a window on (DISPLAY and WAYLAND_DISPLAY are"
                         " unset): add --screenshot OUT.png to render to a file instead")
    view = require("vidcap.ui.view", needs=("pyvista",))
    view.view(args.file, screenshot=args.screenshot, frame=args.frame, centres=args.centres,
              window_size=size)
    if args.screenshot:
        print(f"wrote {args.screenshot}")
    return 0
