"""``vidcap pose2d``: 2D joints by fitting the cylinder model to the silhouettes."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from vidcap.commands.convert import (
    DEFAULT_CUES,
    POSE2D_HIDDEN,
    add_camera_argument,
    add_cues_argument,
    add_ensemble_argument,
    add_hidden_argument,
    add_proportions_argument,
    add_seated_argument,
)
from vidcap.errors import InputFileError, UsageError

NAME = "pose2d"
HELP = "fit the 2D body model to every frame's silhouette (seed 004 section 3.1.4) -> .npz"
ORDER = 40
OUTPUT_FILES = ("output",)
INPUT_FILES = ("video", "masks")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``vidcap pose2d`` parser."""
    parser.add_argument("video", help="the video (its size defines the output's pixel frame)")
    parser.add_argument("-o", "--output", required=True, metavar="POSE2D.npz",
                        help="output .npz (joint_names, joints2d, angles, foreshortening, "
                        "scores, margins, ...)")
    parser.add_argument("--masks", metavar="MASKS.npz",
                        help="silhouettes to use: an .npz with 'masks' (F, H, W) "
                        "(default: compute them as `vidcap silhouettes` does)")
    parser.add_argument("--per-frame", action="store_true",
                        help="fit every frame independently (the seed's method); default: "
                        "start each frame from the previous one")
    parser.add_argument("--height", type=int, default=80, metavar="PX",
                        help="silhouette height after normalisation (default 80)")
    parser.add_argument("--no-refine", action="store_true",
                        help="skip the extra Algorithm 1 pass over the limbs")
    add_proportions_argument(parser,
                             "the model's proportions: human (default): a real adult's from an "
                             "anthropometric table, the ankles above the soles; seed: the seed's "
                             "Table 3.1/3.2 ratios; auto: this subject's, estimated from the clip, "
                             "and the clip fitted again with them (all but seed written as "
                             "body_lengths/body_widths, fractions of the standing height)")
    add_cues_argument(parser)
    add_ensemble_argument(parser)
    add_camera_argument(parser)
    add_seated_argument(parser)
    add_hidden_argument(parser, "joints2d (the solve runs after the fit: about 2.6 ms a "
                        "frame)", POSE2D_HIDDEN)


def load_masks(path):
    """Read ``masks`` (F, H, W) from an .npz file, frame by frame, as a
    :class:`vidcap.video.masks.MaskStack`; raise InputFileError naming the file."""
    import zipfile

    from vidcap.video.masks import read_npz_masks

    path = Path(path)
    try:
        return read_npz_masks(path)
    except KeyError:
        try:
            with np.load(path, allow_pickle=False) as d:
                names = ", ".join(d.files) or "nothing"
        except (OSError, ValueError):
            names = "unreadable"
        raise InputFileError(f"no 'masks' array (has: {names})", path) from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise InputFileError(f"cannot read masks ({exc})", path) from None


def compute_masks(video, crops=None, log=None, plates=None) -> np.ndarray:
    """Silhouettes of ``video`` as ``vidcap silhouettes`` computes them (``crops``: a
    :class:`vidcap.video.fit.cueframes.FrameCrops` filled with the colour frames'
    crops meanwhile; ``log``: called with the plate's notice, as ``vidcap silhouettes``
    prints it, when the plate is a guess over a noticeable area; ``plates``: a list the
    plate, a :class:`vidcap.video.background.BackgroundModel`, is appended to)."""
    try:
        from vidcap.video.background import estimate_plate
        from vidcap.video.inputchecks import plate_notice
        from vidcap.video.pipeline import DEFAULT_GRAPH_CUT, default_still_person
        from vidcap.video.silhouette import extract_silhouettes
    except ImportError:
        raise UsageError("silhouette extraction is not available in this build; pass "
                         "--masks MASKS.npz") from None
    # the plate and the cut as `vidcap silhouettes` and `vidcap convert` make them by
    # default (the same sampled frames, colour models and still-person passes)
    background = estimate_plate(video, colour_models=DEFAULT_GRAPH_CUT,
                                still_person=default_still_person())
    if plates is not None:
        plates.append(background)
    notice = plate_notice(background)
    if notice and log is not None:
        log(notice)
    return extract_silhouettes(video, background, crops=crops,
                               graph_cut=DEFAULT_GRAPH_CUT and background.colours is not None
                               ).masks


def _scene_k(video, masks, plates) -> float:
    """``--camera auto``: the perspective read from the plate's verticals and the person
    (:func:`vidcap.video.vanishing.scene_k`), the plate estimated here when the masks were
    given; what the scene gave is printed to stderr."""
    from vidcap.video.background import estimate_plate
    from vidcap.video.vanishing import scene_k

    plate = plates[0] if plates else estimate_plate(video, colour_models=False,
                                                    still_person=False)
    return scene_k(plate.plate, masks, log=lambda msg: print(msg, file=sys.stderr))


def run(args) -> int:
    """Fit the model and write the .npz atomically."""
    from vidcap.api import check_camera_option, check_cues_option, check_ensemble_option
    from vidcap.fileio import progress
    from vidcap.io.video import probe
    from vidcap.video.fit.cueframes import FrameCrops, crops_from_video
    from vidcap.video.fit.ensemble import fit_ensemble
    from vidcap.video.masks import frames_with_pixels

    if args.height < 16:
        raise UsageError(f"--height must be at least 16 pixels, got {args.height}")
    cues = DEFAULT_CUES if args.cues is None else args.cues
    check_cues_option(cues)
    ensemble = check_ensemble_option(args.ensemble)
    camera = check_camera_option(args.camera)  # the subject taken 1.75 m tall
    info = probe(args.video)
    frames = None
    if cues == "all" and not args.masks:
        frames = FrameCrops(height=args.height)  # cut as the silhouettes are extracted
    plates = []  # the plate the silhouettes come from (--camera auto reads its verticals)
    masks = load_masks(args.masks) if args.masks else compute_masks(
        args.video, frames, log=lambda msg: print(msg, file=sys.stderr), plates=plates)
    if masks.shape[1:] != (info.height, info.width):
        raise InputFileError(
            f"masks are {masks.shape[2]}x{masks.shape[1]} but the video is "
            f"{info.width}x{info.height}", args.masks)
    if not frames_with_pixels(masks).any():
        raise InputFileError("no silhouette in any frame", args.masks or args.video)
    if cues == "all" and frames is None:  # the colour frames' crops (video decoded again)
        frames = crops_from_video(args.video, masks, height=args.height, progress=lambda it,
                                  total: progress(it, total=total, desc="colour", unit="frame"))
        if len(frames) != len(masks):
            raise InputFileError(f"{len(masks)} masks but {len(frames)} video frames",
                                 args.masks or args.video)
    from vidcap.video.fit.perspective import camera_perspective
    from vidcap.video.fit.proportions import (
        estimate_proportions,
        fit_keywords,
        human_proportions,
    )
    from vidcap.video.fitbody import ankle_share, fit_keywords_for, unwarped_estimate

    k = (_scene_k(args.video, masks, plates) if camera == "auto"
         else camera_perspective(camera, 1.75))
    # the seed's and a real adult's body drawn as the camera images them, as convert
    # draws them; the estimated one is measured on the image, warped already: fitted as
    # measured, and (as convert hands it on) un-warped for the solve and the lengths
    fit_kw, extra, estimate = fit_keywords_for(args.proportions, 1, k, args.seated), {}, None
    if args.proportions != "seed":
        estimate = (human_proportions() if args.proportions == "human" else
                    estimate_proportions(masks, height=args.height, refine=not args.no_refine))
        if args.proportions == "auto":
            fit_kw = {**fit_keywords(estimate.factors),
                      **({"low_body": True} if args.seated else {})}
            estimate = unwarped_estimate(estimate, k)
        body = estimate.body(1.0)
        extra = {"body_lengths": body.segment_lengths(),
                 "body_widths": 2.0 * body.segment_radii(),
                 "body_shoulder_drop": np.float64(body.shoulder_drop)}
    # (one member: fit_sequence itself, as before the option)
    pose = fit_ensemble(
        masks, ensemble=ensemble, tracked=not args.per_frame, height=args.height,
        refine=not args.no_refine,
        progress=lambda it, total: progress(it, total=total, desc="pose2d", unit="frame"),
        frames=frames, cues=cues, **fit_kw,
    )
    if args.hidden == "solve":
        from dataclasses import replace

        from vidcap.video.fit.perspective import unwarp_joints, warp_joints
        from vidcap.video.fit.proportions import to_ankles
        from vidcap.video.hidden import solve_hidden

        # head top to ankles, as the pipeline hands it to the 3D stage: a body with feet
        # (--proportions human) leaves them out; un-warped for a camera's perspective
        above = ankle_share(estimate)
        joints, height = unwarp_joints(pose.joints2d, to_ankles(pose.model_height, fit_kw),
                                       k, above)
        joints = solve_hidden(joints, fps=info.fps, body=None if estimate is None
                              else estimate.body(), spread=pose.spread,
                              model_height=height, frame_size=(info.width, info.height))
        pose = replace(pose, joints2d=warp_joints(joints, height, k, above)[0])
    from vidcap.fileio import savez_atomic

    savez_atomic(args.output, **pose.arrays(), **extra)
    n = int(np.isfinite(pose.joints2d[:, 0, 0]).sum())
    print(f"{args.output}: 2D pose of {n}/{pose.n_frames} frames "
          f"(median similarity {np.median(pose.similarity[pose.similarity > 0]):.3f})")
    if estimate is not None:
        print(f"  {estimate.summary()}")
    return 0
