"""``vidcap batch``: convert many videos in parallel processes."""

from __future__ import annotations

import argparse
import csv
import glob
import io
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from vidcap.commands.convert import VIEW_CHOICES
from vidcap.errors import UsageError

NAME = "batch"
HELP = "convert many videos to BVH in parallel, with a summary table"
ORDER = 11

VIDEO_SUFFIXES = {".mp4", ".avi", ".mov", ".mkv", ".m4v", ".webm", ".mpg", ".mpeg", ".wmv"}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the ``vidcap batch`` parser."""
    parser.add_argument("inputs", nargs="+", metavar="INPUT",
                        help="video files, folders (their videos) or glob patterns")
    parser.add_argument("-o", "--outdir", required=True, metavar="OUTDIR",
                        help="folder for the BVH files and summary.csv")
    parser.add_argument("--jobs", "-j", type=int, default=max(1, (os.cpu_count() or 2) // 2),
                        help="parallel processes (default: half the CPUs)")
    parser.add_argument("--height", type=float, default=1.75, metavar="M",
                        help="subjects' height in metres (default 1.75)")
    parser.add_argument("--view", default="auto", choices=VIEW_CHOICES, metavar="VIEW",
                        help="how the camera sees every subject (as in vidcap convert: side, "
                        "front, back or one orientation; default auto)")
    parser.add_argument("--force", action="store_true",
                        help="redo outputs that are newer than their inputs")


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


def _one(video: str, out: str, height: float, view: str = "auto") -> dict:
    """Convert one video in a worker; never raises."""
    from vidcap.pipeline import convert

    t0 = time.perf_counter()
    row = {"file": video, "output": out, "frames": 0, "seconds": 0.0, "fps": 0.0,
           "status": "ok", "message": ""}
    try:
        # files already run in parallel processes: each fits its frames serially
        res = convert(video, out, height=height, progress=False, jobs=1, view=view)
        row["frames"] = res.n_frames
        row["message"] = " ".join("; ".join(res.notices()).split())
    except Exception as exc:  # noqa: BLE001 - a bad file must never stop the others
        row["status"] = "failed"
        row["message"] = " ".join(str(exc).split()) or type(exc).__name__
    row["seconds"] = round(time.perf_counter() - t0, 3)
    row["fps"] = round(row["frames"] / row["seconds"], 2) if row["seconds"] > 0 else 0.0
    return row


def _stem_counts(videos) -> list[int]:
    """How many earlier videos share each video's stem (its output's ``_k`` suffix)."""
    seen: dict[str, int] = {}
    counts = []
    for v in videos:
        counts.append(seen.get(v.stem, 0))
        seen[v.stem] = counts[-1] + 1
    return counts


def run(args) -> int:
    """Run ``vidcap batch``."""
    from vidcap.annotations import default_path
    from vidcap.fileio import progress, write_text_atomic
    from vidcap.outputguard import check_outputs

    if args.jobs < 1:
        raise UsageError(f"--jobs must be at least 1, got {args.jobs}")
    videos = expand_inputs(args.inputs)
    if not videos:
        raise UsageError("no input videos")
    outdir = Path(args.outdir)
    try:
        outdir.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        what = ("is a file" if outdir.exists() else
                "cannot be created: part of the path is a file")
        raise UsageError(f"{what}; OUTDIR must be a folder (created if missing)",
                         args.outdir) from None
    except PermissionError:
        raise UsageError("cannot create the output folder: permission denied",
                         args.outdir) from None
    planned = [outdir / (v.stem + (f"_{k}" if k else "") + ".bvh")
               for v, k in zip(videos, _stem_counts(videos), strict=True)]
    check_outputs({"outdir": [*planned, outdir / "summary.csv"]},
                  {"video": videos, "implicit_annotations": [default_path(v) for v in videos]})
    todo, rows = [], []
    for v, out in zip(videos, planned, strict=True):
        if (not args.force and out.exists()
                and out.stat().st_mtime >= v.stat().st_mtime):
            rows.append({"file": str(v), "output": str(out), "frames": "", "seconds": 0.0,
                         "fps": "", "status": "skipped", "message": "output is up to date"})
        else:
            todo.append((str(v), str(out)))
    bar = progress(total=len(todo), desc="batch", unit="video")
    with ProcessPoolExecutor(max_workers=min(args.jobs, max(1, len(todo)))) as pool:
        futs = [pool.submit(_one, v, o, args.height, args.view) for v, o in todo]
        for f in as_completed(futs):
            rows.append(f.result())
            bar.update(1)
    bar.close()
    order = {str(v): i for i, v in enumerate(videos)}
    rows.sort(key=lambda r: order.get(r["file"], 0))
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
    failed = sum(r["status"] == "failed" for r in rows)
    print(f"{len(rows) - failed} of {len(rows)} converted or up to date; {failed} failed; "
          f"summary: {outdir / 'summary.csv'}", file=sys.stderr)
    return 1 if failed else 0
