"""``vidcap joints``: joint centres and a BVH skeleton from C3D marker data."""

from __future__ import annotations

import json
import sys

import numpy as np

# implicit_outputs is read from here by the output guard (a .gltf's .bin)
from vidcap.commands.convert import add_rig_argument, implicit_outputs  # noqa: F401

NAME = "joints"
HELP = "joint centres (sphere fits) and a BVH or glTF skeleton from C3D marker trajectories"
ORDER = 60
OUTPUT_FILES = ("output", "centres", "report", "draft_markerset")
INPUT_FILES = ("trial", "also", "markerset", "static")  # a marker-set name is no file: skipped


def add_arguments(parser) -> None:
    """Fill the ``vidcap joints`` parser."""
    parser.add_argument("trial", nargs="?", help="the C3D trial to convert")
    parser.add_argument("--also", nargs="+", default=[], metavar="OTHER.c3d",
                        help="more trials of the same subject and marker set, pooled for fitting")
    parser.add_argument("--markerset", metavar="NAME|FILE",
                        help="built-in marker set name or a TOML file (default: detect)")
    parser.add_argument("--noise-mm", type=float, default=None, metavar="MM",
                        help="marker noise standard deviation in mm: unbiased fits (UGDK)")
    parser.add_argument("--static", metavar="STATIC.c3d",
                        help="a static trial of the subject: calibrates the joints placed "
                        "by definition (anatomical, pelvis regression) once, as constant "
                        "points of their parent segments")
    parser.add_argument("-o", "--output", metavar="OUT.bvh|OUT.glb",
                        help="skeleton motion to write: glTF 2.0 for .glb or .gltf (+ .bin), "
                        "else BVH")
    add_rig_argument(parser)
    parser.add_argument("--centres", metavar="OUT.csv",
                        help="CSV of joint centres in the C3D lab frame (metres)")
    parser.add_argument("--report", metavar="OUT.json", help="JSON fit-quality report per joint")
    parser.add_argument("--list-markersets", action="store_true",
                        help="list the built-in marker sets and exit")
    parser.add_argument("--draft-markerset", metavar="OUT.toml",
                        help="write a draft marker set read from the trial (rigid groups of "
                        "markers, joined where they turn about a point) for an unknown "
                        "marker set, and exit: rename and check it, then pass --markerset")
    parser.add_argument("--rigid-mm", type=float, default=None, metavar="MM",
                        help="with --draft-markerset: largest spread (standard deviation, "
                        "mm) of a distance between two markers of one segment (default 6)")


def centres_csv(sol) -> str:
    """CSV text ``frame,time_s,joint,x_m,y_m,z_m``, one row per frame and joint."""
    F, J = sol.positions.shape[:2]
    frame = np.repeat(np.arange(F), J)
    time = frame / sol.fps
    names = np.tile(np.array(sol.joint_names, dtype=object), F)
    xyz = sol.positions.reshape(-1, 3)
    rows = [
        f"{f},{t:.6f},{n},{x:.6f},{y:.6f},{z:.6f}"
        for f, t, n, (x, y, z) in zip(frame, time, names, xyz, strict=True)
    ]
    return "frame,time_s,joint,x_m,y_m,z_m\n" + "\n".join(rows) + "\n"


def report_dict(sol, trials, noise_mm, static=None) -> dict:
    """The ``--report`` JSON content."""
    return {
        "markerset": sol.markerset.name,
        "trials": [t.path for t in trials],
        "static": None if static is None else static.path,
        "frames": int(sol.positions.shape[0]),
        "fps": sol.fps,
        "noise_mm": noise_mm,
        "missing_markers": sol.missing_markers,
        "joints": [r.as_dict() for r in sol.reports],
    }


def run(args) -> int:
    """Run ``vidcap joints``."""
    from vidcap.errors import UsageError
    from vidcap.fileio import progress, write_text_atomic
    from vidcap.mocap.c3d import read_c3d
    from vidcap.mocap.markerset import builtin_markersets, load_markerset

    if args.list_markersets:
        for name, ms in builtin_markersets().items():
            print(f"{name:12s} {len(ms.segment_markers()):3d} markers  {ms.description}")
        return 0
    if not args.trial:
        raise UsageError("give a TRIAL.c3d (or --list-markersets)")
    if args.rigid_mm is not None and not args.rigid_mm > 0:
        raise UsageError(f"--rigid-mm must be positive, got {args.rigid_mm}")
    if args.draft_markerset:
        from vidcap.mocap.draft import MAX_SD_MM, draft_markerset

        text = draft_markerset(read_c3d(args.trial), max_sd_mm=args.rigid_mm or MAX_SD_MM)
        write_text_atomic(args.draft_markerset, text)
        n = text.count("[segments.")
        print(f"{args.draft_markerset}: draft marker set, {n} segments: rename the joints, "
              "check the parents and rest directions, then use --markerset")
        return 0
    if not (args.output or args.centres or args.report):
        raise UsageError("nothing to write: give -o OUT.bvh, --centres OUT.csv or --report")
    if args.noise_mm is not None and not args.noise_mm > 0:
        raise UsageError(f"--noise-mm must be positive, got {args.noise_mm}")

    from vidcap.io.motionfile import write_motion
    from vidcap.mocap.skeleton import solution_to_motion, solve_joints

    steps = progress(total=3 + len(args.also), desc="joints", unit="step")
    trials = []
    for p in [args.trial, *args.also]:
        trials.append(read_c3d(p))
        steps.update()
    ms = load_markerset(args.markerset) if args.markerset else None
    static = read_c3d(args.static) if args.static else None
    sol = solve_joints(trials, ms, noise_mm=args.noise_mm, static=static)
    steps.update()
    from vidcap.api import solution_notices

    for notice in solution_notices(sol, trials[0].path):
        print(f"vidcap: warning: {notice}", file=sys.stderr)
    if args.output:
        write_motion(args.output, solution_to_motion(sol), rig=args.rig)
    if args.centres:
        write_text_atomic(args.centres, centres_csv(sol))
    if args.report:
        report = report_dict(sol, trials, args.noise_mm, static)
        write_text_atomic(args.report, json.dumps(report, indent=2) + "\n")
    steps.update()
    steps.close()
    n_bad = sum(bool(r.warning()) for r in sol.reports)
    print(f"{trials[0].path}: {sol.markerset.name}, {len(sol.joint_names)} joints, "
          f"{sol.positions.shape[0]} frames, {n_bad} poorly placed")
    return 0
