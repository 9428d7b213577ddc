"""``vidcap annotate``: the web page for depth directions, orientation and occluded joints."""

from __future__ import annotations

import sys
from pathlib import Path

from vidcap.commands.convert import (
    DEFAULT_CUES,
    add_camera_argument,
    add_cues_argument,
    add_ensemble_argument,
    add_proportions_argument,
    add_seated_argument,
)
from vidcap.errors import UsageError

NAME = "annotate"
HELP = ("annotate depth directions, orientation, occluded joints and the regions that are"
        " not the person of a video in a web page")
ORDER = 50

#: Packages of the ``ui`` extra the page needs.
UI_PACKAGES = ("trame", "trame_vuetify", "trame_pyvista")


def add_arguments(parser) -> None:
    parser.add_argument("video", help="the video to annotate")
    parser.add_argument("--annotations", metavar="A.json",
                        help="annotations file to read and autosave"
                             " (default: VIDEO_STEM.vidcap.json beside the video)")
    parser.add_argument("--port", type=int, default=0,
                        help="TCP port of the page (default: a free one, printed)")
    parser.add_argument("--no-browser", action="store_true",
                        help="do not open a browser; print the page's address (with its token)")
    parser.add_argument("--height", type=float, default=1.75,
                        help="the subject's height in metres (default 1.75)")
    parser.add_argument("--cache-dir", metavar="DIR",
                        help="stage cache (default: .vidcap-cache beside the video)")
    # the 2D fit's options, as `vidcap convert` takes them: give the same ones to both,
    # and the page shows (and its cache holds) the fit the motion file will get
    add_proportions_argument(parser, "the body model's proportions, as `vidcap convert "
                             "--proportions` (default human)")
    add_cues_argument(parser)
    add_ensemble_argument(parser)
    add_camera_argument(parser)
    add_seated_argument(parser)
    parser.add_argument("--background", metavar="PLATE.png|START:END",
                        help="the background plate, as `vidcap convert --background`: an "
                        "image of the empty scene or frames of the video that show it "
                        "(default: estimated from the video)")


def run(args) -> int:
    from vidcap.commands._ui import require

    if not 0 <= args.port <= 65535:
        raise UsageError(f"--port must be 0..65535, got {args.port}")
    video = Path(args.video)
    if not video.is_file():
        raise UsageError("no such video file", video)
    annotate = require("vidcap.ui.annotate", needs=UI_PACKAGES)
    from vidcap.ui.session import AnnotateSession, default_annotations_path, load_clip

    if not 0.5 <= args.height <= 2.5:
        raise UsageError(f"--height must be 0.5..2.5 metres, got {args.height}")
    from vidcap.api import check_camera_option, check_cues_option, check_ensemble_option

    cues = DEFAULT_CUES if args.cues is None else args.cues
    check_cues_option(cues)
    fit = {"proportions": args.proportions, "cues": cues,
           "ensemble": check_ensemble_option(args.ensemble),
           "camera": check_camera_option(args.camera, args.height), "seated": args.seated,
           "background": args.background}

    def log(msg: str) -> None:
        print(f"vidcap annotate: {msg}", file=sys.stderr, flush=True)

    path = args.annotations or default_annotations_path(video)
    # the file's regions shape the silhouettes; its other events are the session's
    clip = load_clip(video, cache_dir=args.cache_dir, height=args.height, log=log,
                     annotations=path, **fit)
    session = AnnotateSession(clip, path)
    annotate.serve(session, port=args.port, open_browser=not args.no_browser)
    return 0
