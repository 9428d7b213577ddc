"""2D pose on real clips against MediaPipe Pose's landmarks (issue 27).

For every real single-person clip with silhouettes (today: Weizmann ``ido_walk.avi`` with
the dataset's own silhouettes, ``../shared/data/video``), fits the model tracked
(``fit_sequence``'s defaults) and scores the 12 limb joints (shoulders, elbows, wrists,
hips, knees, ankles) against MediaPipe Pose's landmarks with the reference tool's
``compare.py``: per joint the median distance and the share of frames where vidcap and
MediaPipe disagree by more than 10 % of the height (the larger side of the box around
MediaPipe's 33 landmarks, about 0.9 of stature). MediaPipe is a reference, not the truth
(about 2.4 % of height off on lab footage). vidcap's ``l_*``/``r_*`` are image-side labels,
so each frame's arms and legs are matched either way round ("swap" in compare.py).

The reference's output is cached as ``$VIDCAP_DATA/fit2d/<clip>.mediapipe.npz`` (outside
git); when absent it is made with the reference tool
(``/work/shared/tools/mediapipe-reference``, set up in
``~/.cache/vidcap-mediapipe-reference``), and the clip is skipped, saying why, when neither
exists. No clip here chose a threshold of the fit (validation).

Then every clip of ``real_clips.py`` (``$VIDCAP_DATA/video``: onebyone_room's six
one-person visits, the three pose2sim_balance cameras, the Sports2D walk and run,
the TensorFlow.js squats and dance, mmskeleton's tai chi and clean and jerk) and ido_walk
again, this time
through vidcap's own pipeline (silhouettes from the video, the tracked fit, the seed's body:
``proportions='seed'``), with ``--cues outline`` (the default) and ``--cues all``: one row
per clip, the median of the 12 joints' medians, the share of frames more than 10 % apart over all 12
joints, and per joint for the default cues; and the fit to MediaPipe's masks instead of
vidcap's silhouettes (``mp-masks``); and both again with ``proportions='human'`` (``human``,
``mp-human``: an anthropometric table's body, the ankles above the soles; ``vidcap
convert``'s default body). Tuning clips
(``pose2d_real_pipeline.TUNING``, the "use" column): pose2sim_balance cam1 and
onebyone_room 233-445 (the ``human`` body's hips and feet), cam4 and cam3 (wt-cam
diagnosed their pipeline losses on them and chose the appearance pass's scene-beside
gate and the lean fit's head row on cam4), mmskeleton_taichi (session 27 chose the plate's
scene-ring switch, ``regionvote.SCENE_RING``, on it), onebyone_room 66-194 and 1242-1357
(session 29 tuned the came-stayed-went plate pass, ``vidcap.video.stayed``, on their
silhouettes); the others are validation.

Usage: ``VIDCAP_DATA=/work/data PYTHONPATH=. python benchmarks/pose2d_real.py [--no-all]
[--only NAME] [--tuning | --validation] [--rows R1,R2] [--human] [--graph-cut | --no-graph-cut]
[--passed-by | --no-passed-by] [--ensemble N]`` (``--only``: just
the clips whose name contains NAME; ``--tuning`` / ``--validation``: just the tuning or the
validation clips of the pipeline table; ``--rows``: the pipeline table's row kinds, of
outline, all, mp-masks, human, mp-human, all-human (without ``--no-all``: all six),
mp-all-human (``mp-human`` with ``--cues all``), and
``human-kK`` (the pipeline's silhouettes fitted again, serially, with the human body as a
camera of perspective K draws it: :mod:`vidcap.video.fit.perspective`; ``human-k0`` the same
fit unwarped), ``human-auto`` (``vidcap convert --camera auto``: the perspective read from
the plate's verticals and the person, :mod:`vidcap.video.vanishing`; ``human-cam`` with
a calibrated camera's), ``human-erode`` / ``human-dilate`` (the ``human`` row's silhouettes eroded
or dilated by a 3x3 cross, as an ensemble's members change them, and fitted again),
``human-eN`` / ``outline-eN`` (that row's silhouettes fitted again
as the pipeline fits them, each chunk as :func:`vidcap.video.fit.ensemble.fit_ensemble` of
N members; ``-e1``: the plain row's fit again); ``--ensemble N``: a ``human-eN`` /
``outline-eN`` row beside each ``human`` / ``outline`` row of the pipeline table (with
``+solve`` alike), and the
first table's fit also as an ensemble of N (its ``eN 12 jts`` line); ``--human``:
the first table with ``proportions='human'``;
``--graph-cut``: the pipeline rows' silhouettes with or without the graph cut, default
``vidcap.video.pipeline.DEFAULT_GRAPH_CUT``; ``benchmarks/cut_fit.py`` compares the two;
``--passed-by``: the plate's passed-by pass on or off, default
``vidcap.video.passedby.PASSED_BY``: the stage cache does not key on it, so give each
setting its own, ``VIDCAP_BENCH_CACHE=DIR``, or delete it between runs).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

SHARED = REPO.parent / "shared"
TOOL = SHARED / "tools" / "mediapipe-reference"
TOOL_PY = Path.home() / ".cache" / "vidcap-mediapipe-reference" / "bin" / "python"
#: (name, video, silhouettes .npz and its key)
CLIPS = (("ido_walk", SHARED / "data" / "video" / "ido_walk.avi",
          SHARED / "data" / "video" / "ido_walk_masks.npz", "masks"),)
LIMB_JOINTS = tuple(f"{s}_{j}" for j in ("shoulder", "elbow", "wrist", "hip", "knee", "ankle")
                    for s in "lr")


def reference(name: str, video: Path) -> Path | None:
    """MediaPipe's landmarks of ``video`` (cached), or None with a note why not."""
    data = os.environ.get("VIDCAP_DATA")
    if not data:
        print(f"{name}: skipped (VIDCAP_DATA is not set: where the reference is cached)")
        return None
    out = Path(data) / "fit2d" / f"{name}.mediapipe.npz"
    if out.exists():
        return out
    lifted = Path(data) / "lift" / f"{name}_mediapipe.npz"  # the same tool's output
    if lifted.exists():
        return lifted
    if not TOOL_PY.exists():
        print(f"{name}: skipped (no cached reference and no MediaPipe tool at {TOOL_PY})")
        return None
    out.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run([str(TOOL_PY), str(TOOL / "reference.py"), str(video), str(out)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return out


def score(ref: Path, masks: np.ndarray, human: bool = False, ensemble: int = 1) -> dict:
    """compare.py's joint scores of the tracked fit to ``masks`` against ``ref``
    (``human``: with ``proportions='human'``; ``ensemble``: the fit as
    :func:`vidcap.video.fit.ensemble.fit_ensemble` of that many members)."""
    from vidcap.video.fit.ensemble import fit_ensemble
    from vidcap.video.fit.proportions import fit_keywords, human_proportions

    pose = fit_ensemble(masks, ensemble=ensemble,
                        **(fit_keywords(human_proportions().factors) if human else {}))
    with tempfile.TemporaryDirectory() as tmp:
        pred = Path(tmp) / "pose2d.npz"
        pose.save(pred)
        return compare(ref, pred)


def compare(ref: Path, pred: Path) -> dict:
    """The mediapipe-reference tool's ``compare.py --json`` joint scores."""
    run = subprocess.run([sys.executable, str(TOOL / "compare.py"), str(ref), str(pred),
                          "--json"], check=True, capture_output=True, text=True)
    return json.loads(run.stdout)["joints"]


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    only = argv[argv.index("--only") + 1] if "--only" in argv else None
    ensemble = int(argv[argv.index("--ensemble") + 1]) if "--ensemble" in argv else 1
    if "--graph-cut" in argv or "--no-graph-cut" in argv:  # the stage cache keys on it
        import vidcap.video.pipeline as pipeline

        pipeline.DEFAULT_GRAPH_CUT = "--graph-cut" in argv
    if "--passed-by" in argv or "--no-passed-by" in argv:
        # (the stage cache does not key on it: VIDCAP_BENCH_CACHE)
        from vidcap.video import passedby

        passedby.PASSED_BY = "--passed-by" in argv
    if "--unsteady-plate" in argv or "--no-unsteady-plate" in argv:
        # (the stage cache does not key on it: VIDCAP_BENCH_CACHE)
        from vidcap.video import steadyscene

        steadyscene.UNSTEADY_PLATE = "--unsteady-plate" in argv
    print("2D pose on real clips: 12 limb joints against MediaPipe Pose (image-side labels "
          "matched either way per frame)")
    print(f"{'clip':10} {'joint':11} {'median':>7} {'>10 %':>6}")
    for name, video, masks_file, key in CLIPS:
        if only and only not in name:
            continue
        if not (video.exists() and masks_file.exists()):
            print(f"{name}: skipped ({video.name} or {masks_file.name} absent)")
            continue
        ref = reference(name, video)
        if ref is None:
            continue
        with np.load(masks_file) as d:
            masks = d[key].astype(bool)
        res = score(ref, masks, human="--human" in argv)
        medians = []
        for joint in LIMB_JOINTS:
            s = res["joints"][joint]["swap"]
            medians.append(s["median"])
            print(f"{name:10} {joint:11} {s['median']:7.1%} {1 - s['pck10']:6.0%}")
        print(f"{name:10} {'12 joints':11} {np.median(medians):7.1%}   (median of the joints' "
              f"medians; {res['frames_with_reference']} frames, height "
              f"{res['median_height_px']:.0f} px)")
        if ensemble > 1:
            res = score(ref, masks, human="--human" in argv, ensemble=ensemble)
            medians = [res["joints"][j]["swap"]["median"] for j in LIMB_JOINTS]
            print(f"{name:10} {f'e{ensemble} 12 jts':11} {np.median(medians):7.1%}   "
                  f"(the 12 joints of the fit as an ensemble of {ensemble})")
    from pose2d_real_pipeline import pipeline_tables

    rows = ("outline", "mp-masks", "human", "mp-human")
    rows = rows if "--no-all" in argv else rows[:1] + ("all",) + rows[1:] + ("all-human",)
    if "--rows" in argv:
        rows = tuple(argv[argv.index("--rows") + 1].split(","))
    if ensemble > 1:  # each plain fit's ensemble beside it (human+solve: human-eN+solve)
        rows = tuple(r for row in rows for r in (
            (row, row.replace("+", f"-e{ensemble}+", 1) if "+" in row else f"{row}-e{ensemble}")
            if row.removesuffix("+solve") in ("human", "outline") else (row,)))
    use = "tuning" if "--tuning" in argv else "validation" if "--validation" in argv else None
    pipeline_tables(CLIPS[0][:2], reference, compare, LIMB_JOINTS, cues=rows, only=only, use=use)
    return 0


if __name__ == "__main__":
    sys.exit(main())
