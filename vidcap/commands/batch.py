"""``vidcap batch``: convert many videos in parallel, on this machine or a Dask cluster.

This module plans the batch (which outputs, which are up to date) and writes the
summary; the work for one clip is :func:`vidcap.batch.job.convert_clip`, run by
the local process pool (:mod:`vidcap.batch.local`) or by Dask workers
(:mod:`vidcap.batch.cluster`), so both paths give the same outputs and summary.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import glob
import io
import os
import sys
from pathlib import Path

from vidcap.commands.convert import (
    VIEW_CHOICES,
    add_camera_argument,
    add_ensemble_argument,
    add_rig_argument,
    add_seated_argument,
)
from vidcap.errors import UsageError

NAME = "batch"
HELP = "convert many videos to BVH or glTF in parallel, with a summary table"
ORDER = 11

VIDEO_SUFFIXES = {".mp4", ".avi", ".mov", ".mkv", ".m4v", ".webm", ".mpg", ".mpeg", ".wmv"}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``vidcap batch`` parser."""
    parser.add_argument("inputs", nargs="+", metavar="INPUT",
                        help="video files, folders (their videos) or glob patterns")
    parser.add_argument("-o", "--outdir", required=True, metavar="OUTDIR",
                        help="folder for the motion files and summary.csv")
    parser.add_argument("--jobs", "-j", type=int, default=max(1, (os.cpu_count() or 2) // 2),
                        help="parallel processes (default: half the CPUs)")
    parser.add_argument("--height", type=float, default=1.75, metavar="M",
                        help="subjects' height in metres (default 1.75)")
    parser.add_argument("--view", default="auto", choices=VIEW_CHOICES, metavar="VIEW",
                        help="how the camera sees every subject (as in vidcap convert: side, "
                        "front, back or one orientation; default auto)")
    parser.add_argument("--format", default="bvh", choices=("bvh", "glb", "gltf"),
                        help="file written per video: BVH (default), binary glTF (.glb) or "
                        "glTF JSON + .bin")
    add_rig_argument(parser)
    add_camera_argument(parser)  # one rig filmed every clip: its camera, as in convert
    add_ensemble_argument(parser)
    add_seated_argument(parser)
    parser.add_argument("--force", action="store_true",
                        help="redo outputs that are newer than their inputs")
    parser.add_argument("--clip-jobs", type=int, default=1, metavar="N",
                        help="processes each clip's fit uses (default 1: the clips already "
                        "run in parallel)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        default=os.environ.get("DASK_SCHEDULER_ADDRESS") or None,
                        help="run the clips on a Dask cluster: tcp://HOST:PORT of its "
                        "scheduler, or local[:N] for N workers on this machine (default: "
                        "$DASK_SCHEDULER_ADDRESS; unset: the local process pool of --jobs)")
    parser.add_argument("--connect-timeout", type=float, default=10.0, metavar="S",
                        help="seconds to wait for the Dask scheduler and a first worker "
                        "(default 10)")


def expand_inputs(items) -> list[Path]:
    """Files, folders (their video files) and glob patterns -> unique paths, in order."""
    out: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            out += sorted(q for q in p.iterdir() if q.suffix.lower() in VIDEO_SUFFIXES)
        elif p.exists():
            out.append(p)
        else:
            hits = sorted(glob.glob(item, recursive=True))
            if not hits:
                raise UsageError(f"{item}: no such file, folder or matching files")
            out += [Path(h) for h in hits if Path(h).is_file()]
    seen, unique = set(), []
    for p in out:
        if p.resolve() not in seen:
            seen.add(p.resolve())
            unique.append(p)
    return unique


def _stem_counts(videos) -> list[int]:
    """How many earlier videos share each video's stem (its output's ``_k`` suffix)."""
    seen: dict[str, int] = {}
    counts = []
    for v in videos:
        counts.append(seen.get(v.stem, 0))
        seen[v.stem] = counts[-1] + 1
    return counts


def output_paths(videos: list[Path], outdir: Path, suffix: str = ".bvh") -> list[Path]:
    """Each video's output: ``outdir/STEM{suffix}``, ``STEM_1``... for repeated stems."""
    return [outdir / (v.stem + (f"_{k}" if k else "") + suffix)
            for v, k in zip(videos, _stem_counts(videos), strict=True)]


def plan(videos: list[Path], outputs: list[Path], force: bool, options: dict):
    """Split the clips into rows of up-to-date outputs and tasks to run.

    Returns
    -------
    rows : list of dict
        Summary rows of the clips whose output is newer than the input (unless ``force``).
    tasks : list of ClipTask
        The clips to convert, with ``options`` for :func:`vidcap.video.pipeline.convert`.
    """
    from vidcap.batch.job import ClipTask

    rows, tasks = [], []
    for v, out in zip(videos, outputs, strict=True):
        if (not force and out.exists()
                and out.stat().st_mtime >= v.stat().st_mtime):
            rows.append({"file": str(v), "output": str(out), "frames": "", "seconds": 0.0,
                         "fps": "", "status": "skipped", "message": "output is up to date"})
        else:
            tasks.append(ClipTask(str(v), str(out), dict(options)))
    return rows, tasks


def _executor(args, tasks, outdir: Path):
    """The rows of ``tasks`` as they finish, from the pool or the Dask cluster."""
    if args.scheduler:
        from vidcap.batch.cluster import run_dask

        return run_dask(tasks, args.scheduler, outdir=outdir, default_workers=args.jobs,
                        timeout=args.connect_timeout)
    from vidcap.batch.local import run_local

    return run_local(tasks, args.jobs)


def _make_outdir(given: str) -> Path:
    outdir = Path(given)
    try:
        outdir.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        what = ("is a file" if outdir.exists() else
                "cannot be created: part of the path is a file")
        raise UsageError(f"{what}; OUTDIR must be a folder (created if missing)",
                         given) from None
    except PermissionError:
        raise UsageError("cannot create the output folder: permission denied",
                         given) from None
    return outdir


def write_summary(rows: list[dict], outdir: Path) -> None:
    """Save ``rows`` as ``outdir/summary.csv`` and print them as a table."""
    from vidcap.fileio import write_text_atomic

    cols = ["file", "frames", "seconds", "fps", "status", "message"]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    write_text_atomic(outdir / "summary.csv", buf.getvalue())
    widths = {c: max(len(c), *(len(str(r[c])) for r in rows)) for c in cols[:-1]}
    print("  ".join(c.ljust(widths[c]) for c in cols[:-1]) + "  message")
    for r in rows:
        print("  ".join(str(r[c]).ljust(widths[c]) for c in cols[:-1]) + "  " + r["message"])


def run(args) -> int:
    """Run ``vidcap batch``."""
    from vidcap.fileio import progress, remove_atomic_leftovers
    from vidcap.io.motionfile import FORMATS, output_files
    from vidcap.outputguard import check_outputs
    from vidcap.video.annotations import default_path

    for name in ("jobs", "clip_jobs"):
        if getattr(args, name) < 1:
            raise UsageError(f"--{name.replace('_', '-')} must be at least 1, "
                             f"got {getattr(args, name)}")
    from vidcap.api import check_camera_option, check_ensemble_option

    camera = check_camera_option(args.camera, args.height)
    ensemble = check_ensemble_option(args.ensemble)
    videos = expand_inputs(args.inputs)
    if not videos:
        raise UsageError("no input videos")
    outdir = _make_outdir(args.outdir)
    options = {"height": args.height, "view": args.view, "jobs": args.clip_jobs,
               "rig": args.rig, "camera": camera, "ensemble": ensemble}
    if args.seated:  # (a plain run keeps the options it had before the flag)
        options["seated"] = True
    outputs = output_paths(videos, outdir, FORMATS[args.format])
    written = [f for out in outputs for f in output_files(out)]  # a .gltf brings its .bin
    check_outputs({"outdir": [*written, outdir / "summary.csv"]},
                  {"video": videos, "implicit_annotations": [default_path(v) for v in videos]})
    rows, tasks = plan(videos, outputs, args.force, options)
    if tasks:
        bar = progress(total=len(tasks), desc="batch", unit="video")
        try:
            with contextlib.closing(_executor(args, tasks, outdir)) as finished:
                for row in finished:  # fed by completions, pool or cluster alike
                    rows.append(row)
                    bar.update(1)
        finally:
            bar.close()
        for task in tasks:  # a process killed mid-write leaves its temporary files
            for path in output_files(task.output):
                remove_atomic_leftovers(path)
    order = {str(v): i for i, v in enumerate(videos)}
    rows.sort(key=lambda r: order.get(r["file"], 0))
    write_summary(rows, outdir)
    failed = sum(r["status"] == "failed" for r in rows)
    print(f"{len(rows) - failed} of {len(rows)} converted or up to date; {failed} failed; "
          f"summary: {outdir / 'summary.csv'}", file=sys.stderr)
    return 1 if failed else 0
