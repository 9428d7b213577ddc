"""``vidcap convert``: one video -> BVH through the whole video path."""

from __future__ import annotations

import argparse
import sys

NAME = "convert"
HELP = "convert a single-camera video of one person into BVH or glTF motion"
ORDER = 10
OUTPUT_FILES = ("output", "save")
INPUT_FILES = ("video", "annotations", "background")


def implicit_outputs(args) -> dict:
    """The ``.bin`` that a ``-o OUT.gltf`` writes beside it."""
    from vidcap.io.motionfile import output_files

    return {"gltf_bin": output_files(args.output)[1:] if args.output else None}


def implicit_inputs(args) -> dict:
    """The annotations read by default (``VIDEO_STEM.vidcap.json`` beside the video)."""
    from vidcap.video.annotations import default_path

    return {"implicit_annotations": None if args.annotations else default_path(args.video)}
#: ``--view`` values (:data:`vidcap.video.lifting.VIEWS`, spelled here so that ``--help``
#: does not import the pipeline).
VIEW_CHOICES = ("auto", "side", "front", "back", "left", "right", "back_left", "back_right",
                "front_left", "front_right")
#: ``--rig`` values (:data:`vidcap.io.rigs.RIGS`, spelled here for a light ``--help``).
RIG_CHOICES = ("vidcap", "mixamo", "humanik")
#: ``--cues`` default (:data:`vidcap.video.pipeline.DEFAULT_CUES`, spelled here for a
#: light ``--help``; a test checks they agree).
DEFAULT_CUES = "outline"
#: ``--proportions`` default (:data:`vidcap.video.pipeline.DEFAULT_PROPORTIONS`, spelled
#: here for a light ``--help``; a test checks they agree).
DEFAULT_PROPORTIONS = "human"
#: ``--hidden`` values and the defaults of ``vidcap convert`` and ``vidcap pose2d``
#: (:data:`vidcap.video.hidden.HIDDEN_CHOICES`, ``CONVERT_HIDDEN``, ``DEFAULT_HIDDEN``,
#: spelled here for a light ``--help``; a test checks they agree).
HIDDEN_CHOICES = ("fit", "solve")
CONVERT_HIDDEN = "solve"
POSE2D_HIDDEN = "fit"
#: ``--proportions`` values of the commands that fit the body model.
PROPORTION_CHOICES = ("human", "seed", "auto")
#: ``--graph-cut`` default (:data:`vidcap.video.pipeline.DEFAULT_GRAPH_CUT`, spelled here
#: for a light ``--help``; a test checks they agree).
DEFAULT_GRAPH_CUT = True
#: ``--still-person`` default (:func:`vidcap.video.pipeline.default_still_person`, spelled
#: here for a light ``--help``; a test checks they agree).
DEFAULT_STILL_PERSON = True
#: ``--ensemble``'s largest value (``len(vidcap.video.fit.ensemble.MEMBERS)``, spelled here
#: for a light ``--help``; a test checks they agree).
ENSEMBLE_MAX = 5
#: Segments more than this much longer than the model are reported (a fraction).
CLAMP_NOTICE = 0.02


def add_rig_argument(parser: argparse.ArgumentParser) -> None:
    """``--rig``, shared by every command that writes a skeleton's motion."""
    parser.add_argument("--rig", default="vidcap", choices=RIG_CHOICES,
                        help="joint names and hierarchy of the BVH/glTF: ours (default), "
                        "Mixamo's (mixamorig:Hips...) or MotionBuilder HumanIK's (Hips...), "
                        "T-pose rest; mixamo and humanik face +Z as those characters do")


def add_proportions_argument(parser: argparse.ArgumentParser, help_text: str) -> None:
    """``--proportions``, shared by ``vidcap convert`` and ``vidcap pose2d`` (one default
    and one set of choices; ``help_text`` says what the command does with them)."""
    parser.add_argument("--proportions", default=DEFAULT_PROPORTIONS,
                        choices=PROPORTION_CHOICES, help=help_text)


def add_cues_argument(parser: argparse.ArgumentParser) -> None:
    """``--cues``, shared by ``vidcap convert`` and ``vidcap pose2d`` (checked by
    :func:`vidcap.api.check_cues_option`: a bad value is a one-line error)."""
    parser.add_argument("--cues", default=None, metavar="all|outline",
                        help="what places the 2D body model: 'all' = the silhouette's outline "
                        "and the colour frame inside it (skin colour and edges place arms "
                        "in front of the body), 'outline' = the silhouette only (the "
                        "seed's method; 2.7x faster). Default: " + DEFAULT_CUES)


def add_ensemble_argument(parser: argparse.ArgumentParser) -> None:
    """``--ensemble``, shared by ``vidcap convert`` and ``vidcap pose2d`` (checked by
    :func:`vidcap.api.check_ensemble_option`: a bad value is a one-line error)."""
    parser.add_argument("--ensemble", default=1, metavar="N",
                        help="fit the 2D model on N versions of the silhouettes changed by one "
                        "pixel at the outline (as given, eroded, dilated, outline pixels "
                        "flipped) and take each joint's median: a steadier fit (about +1 "
                        "point of PCK on renders) for N times the fit's time; 1 to "
                        f"{ENSEMBLE_MAX}. Default: 1 (one fit)")


def add_camera_argument(parser: argparse.ArgumentParser) -> None:
    """``--camera``, shared by ``vidcap convert`` and ``vidcap pose2d`` (checked by
    :func:`vidcap.api.check_camera_option`: a bad value is a one-line error)."""
    parser.add_argument("--camera", default=None, metavar="HEIGHT,DISTANCE[,PITCH]|auto",
                        help="where the camera stands: its lens's height above the floor "
                        "and its horizontal distance from the subject, metres, and "
                        "optionally its downward tilt in degrees (default: aimed at the "
                        "subject's middle), e.g. 2.5,3. A camera high above the subject (a "
                        "wall or ceiling mount) images the head larger than the feet; "
                        "the 2D model is drawn so. 'auto': read "
                        "from where the scene's vertical lines meet and the person standing "
                        "(none when the background shows no such lines). Default: no "
                        "perspective")


def add_seated_argument(parser: argparse.ArgumentParser) -> None:
    """``--seated``, shared by the commands that fit the 2D body model."""
    parser.add_argument("--seated", action="store_true",
                        help="the subject sits (or crouches) for seconds at a time: the 2D "
                        "fit then tries the body larger than its silhouette where the "
                        "silhouette says so (a seated person's is ~0.8 of the standing "
                        "height; seated renders 53 -> 67 %% PCK). Off by default: on some "
                        "real clips of people standing it draws the body too large")


def add_hidden_argument(parser: argparse.ArgumentParser, where: str, default: str) -> None:
    """``--hidden``, shared by ``vidcap convert`` and ``vidcap pose2d``; ``where``: what
    the 2D joints it changes are, in the command's words."""
    parser.add_argument("--hidden", default=default, choices=HIDDEN_CHOICES,
                        help="joints the frame cannot show (an arm behind or in front of the "
                        "torso, the shoulders): 'fit' = as the 2D fit left them, 'solve' = "
                        "from the 3D clip solve drawn back into the image (bones, joint "
                        "limits and the motion-capture pose prior place them from the rest "
                        f"of the body); changes {where}. Default: {default}")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``vidcap convert`` parser."""
    parser.add_argument("video", help="input video (static camera, one person)")
    parser.add_argument("-o", "--output", required=True, metavar="OUT.bvh|OUT.glb",
                        help="motion to write: glTF 2.0 for .glb or .gltf (+ .bin), else BVH")
    add_rig_argument(parser)
    parser.add_argument("--annotations", metavar="A.json",
                        help="depth/orientation/joint annotations (default: "
                        "VIDEO_STEM.vidcap.json beside the video, if present)")
    parser.add_argument("--background", metavar="PLATE.png|START:END",
                        help="background plate: an image of the empty scene, or frames of "
                        "the video that show it empty (START:END, counted from 0, END "
                        "excluded; either may be left out; the plate is their median). "
                        "Default: estimated from the video")
    parser.add_argument("--height", type=float, default=1.75, metavar="M",
                        help="subject's height in metres (default 1.75)")
    parser.add_argument("--smooth", type=float, default=1.0, metavar="SIGMA",
                        help="Gaussian smoothing of the motion in frames (0 = none; default 1)")
    parser.add_argument("--keyframes", type=float, metavar="MIN_SIMILARITY",
                        help="key only frames whose 2D fit similarity is at least this and "
                        "interpolate the rest (default: every frame)")
    parser.add_argument("--view", default="auto", choices=VIEW_CHOICES, metavar="VIEW",
                        help="how the camera sees the subject for the whole clip: side, front "
                        "or back (which way the subject faces is still read per frame), or "
                        "one orientation (left, right, front_left, front_right, back_left, "
                        "back_right); default auto: read per frame. Orientation events in "
                        "the annotations override it from their frames")
    parser.add_argument("--lift", default="solve", choices=("solve", "segment"),
                        help="3D from the 2D joints: one kinematic solve over the clip "
                        "(default; bone lengths constant, joint limits, smooth, feet planted "
                        "on walks and stands) or the seed's per-segment lift (segment)")
    add_proportions_argument(parser,
                             "the body's proportions: human (default): a real adult's from an "
                             "anthropometric table (joints where a person's are, the ankles above "
                             "the soles), seed: the seed's Table 3.1/3.2 ratios, or auto: this "
                             "subject's segment lengths and widths estimated from the clip (the "
                             "2D fit done again with them); the 2D fit, the lift and the skeleton "
                             "use them (--height stays the standing height)")
    add_cues_argument(parser)
    add_ensemble_argument(parser)
    add_camera_argument(parser)
    add_seated_argument(parser)
    add_hidden_argument(parser, "the 2D joints of --save (with --lift solve; the solve runs "
                        "anyway)", CONVERT_HIDDEN)
    parser.add_argument("--graph-cut", action=argparse.BooleanOptionalAction, default=None,
                        help="re-decide a band round the person (and the parts of the scene "
                        "never seen uncovered) by a graph cut on the clip's person and scene "
                        "colours (the plate stage learns them), in the frames where those "
                        "colours tell the person from the scene; better silhouettes on the "
                        "in-place renders, no real clip measured loses more than 0.01 median "
                        "IoU, the 2D fit and the 3D on them level (benchmarks/RESULTS.md, "
                        "Silhouettes); not with --background. Default: "
                        + ("on" if DEFAULT_GRAPH_CUT else "off"))
    parser.add_argument("--still-person", action=argparse.BooleanOptionalAction, default=None,
                        help="the plate stage also re-takes the plate from frames that show "
                        "the empty scene (a person who came in and stands still) and looks "
                        "for a person who never moves with a person detector (OpenCV's HOG) "
                        "and a cut in its box (benchmarks/RESULTS.md, Silhouettes); not with "
                        "--background. Default: " + ("on" if DEFAULT_STILL_PERSON else "off"))
    parser.add_argument("--save", metavar="OUT.npz",
                        help="also save masks, joints2d, joints3d, proposed and final depth "
                        "signs, orientation and scores")
    parser.add_argument("--no-cache", action="store_true",
                        help="do not read or write the stage cache (.vidcap-cache beside OUT)")
    parser.add_argument("--jobs", "-j", type=int, metavar="N",
                        help="processes fitting the 2D pose (default: the CPUs, at most 8; "
                        "1 = this process only)")
    parser.add_argument("--quiet", action="store_true", help="print nothing on success")


def run(args) -> int:
    """Run ``vidcap convert``."""
    import numpy as np

    from vidcap.api import check_camera_option, check_convert_options, check_ensemble_option
    from vidcap.video.annotations import default_path
    from vidcap.video.pipeline import convert

    cues = DEFAULT_CUES if args.cues is None else args.cues
    check_convert_options(height=args.height, jobs=args.jobs, view=args.view,
                          smooth=args.smooth, keyframes=args.keyframes, cues=cues)
    ensemble = check_ensemble_option(args.ensemble)
    camera = check_camera_option(args.camera, args.height)
    log = (lambda m: None) if args.quiet else (lambda m: print(f"vidcap: {m}", file=sys.stderr))
    res = convert(
        args.video, args.output, save=args.save, cache_dir=not args.no_cache,
        annotations=args.annotations, background=args.background, height=args.height,
        smooth_sigma=args.smooth, keyframe_score=args.keyframes, log=log, jobs=args.jobs,
        view=args.view, rig=args.rig, lift=args.lift, proportions=args.proportions,
        cues=cues, graph_cut=args.graph_cut, still_person=args.still_person,
        hidden=args.hidden, ensemble=ensemble, camera=camera, seated=args.seated,
    )
    if not args.quiet:
        lr = res.lifted
        bvh = res.bvh_motion
        print(f"{args.output}: {bvh.n_frames} frames at {bvh.fps:.4g} fps; orientation "
              f"{', '.join(sorted(set(lr.orientation)))}; jitter {res.jitter_before:.1f} -> "
              f"{res.jitter_after:.1f} m/s^2")
        if lr.contact is not None and lr.contact.any():
            print(f"  foot contact on (the clip walks or stands): a foot stays put in "
                  f"{int(lr.contact.any(axis=1).sum())} of {len(lr.contact)} frames")
        if res.proportions is not None:
            print(f"  {res.proportions.summary()}")
        for notice in res.notices():
            print(f"  {notice}")
        # the normalised silhouette's width is whole pixels, which stretches a fitted
        # segment by up to about 1 %: only more than that says the model does not fit
        long = lr.excess > CLAMP_NOTICE if lr.excess is not None else lr.clamped
        if long.any():
            print(f"  {int(long.any(axis=1).sum())} frames had a segment more than "
                  f"{CLAMP_NOTICE:.0%} longer in the image than the model (depth clamped to 0)")
        side = np.isin(lr.orientation, ("left", "right"))
        if side.mean() >= 0.5:
            # no silhouette tells the near leg from the far one: the colour frame's
            # occlusion edges (legorder) read it where the limbs overlap, which can fail
            # (plain clothing, a poor 2D fit), and one event fixes a wrong reading
            print(f"  side view in {int(side.sum())} of {len(side)} frames: which leg (and arm) "
                  "is the left one is read from where one covers the other, and can be "
                  "wrong.\n  If `vidcap review` shows the legs on "
                  f"the wrong hips, add this event to the \"events\" of "
                  f"{default_path(args.video).name}\n"
                  '    {"frame": 0, "type": "sides", "pair": "legs", "value": "swapped"}\n'
                  '  or use "swap legs" in vidcap annotate.')
        if lr.checks:
            print("  check these depth signs first (frame, segment, proposed):")
            for c in lr.checks[:5]:
                word = "toward" if c["sign"] > 0 else "away"
                print(f"    {c['frame']:5d}  {c['segment']:<12s} {word:<6s} "
                      f"(frames {c['run'][0]}-{c['run'][1]})")
    return 0
