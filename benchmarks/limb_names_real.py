"""The limbs' names on real side-view clips against MediaPipe's 2D names (issue 33).

For each real clip seen mostly from the side (ido_walk, sports2d_run, sports2d_walk_turn;
validation: nothing was chosen on them), vidcap's pipeline as ``real_clips`` runs it
(stage cache), then the 3D stage with the front/back cue, without and with the colour
frame's limb order (:mod:`vidcap.video.legorder`). Per frame, the body-side names of the
3D stage's 2D joints are compared with MediaPipe Pose's (its ``left_knee`` is the body's
left): a pair (knees and ankles; elbows and wrists) agrees where its joints lie nearer
MediaPipe's same-named joints than the exchanged ones. Only frames where MediaPipe's
two limbs are at least 2 % of the height apart count (where they coincide, names say
nothing). MediaPipe's names in a side view are **not** the truth: it too must guess
which leg is the near one.

Run:  VIDCAP_DATA=/work/data python benchmarks/limb_names_real.py
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from vidcap.body import JOINT_INDEX as J  # noqa: E402
from vidcap.body import BodyModel  # noqa: E402

CLIPS = ("ido_walk", "sports2d_run", "sports2d_walk_turn")
PAIRS = {"arms": ("elbow", "wrist"), "legs": ("knee", "ankle")}


def _paths(name):
    data = Path(os.environ.get("VIDCAP_DATA", "/nonexistent"))
    if name == "ido_walk":
        return ROOT.parent / "shared" / "data" / "video" / "ido_walk.avi", \
            data / "lift" / "ido_walk_mediapipe.npz"
    return data / "video" / f"{name}.mp4", data / "video" / f"{name}.mediapipe.npz"


def _mediapipe_2d(path, n):
    """MediaPipe's 2D landmarks as (n, 15, 2) px in vidcap's joint order, NaN where none."""
    ref = np.load(path)
    names = [str(v) for v in ref["names_vidcap_map"]]
    out = np.full((n, 15, 2), np.nan)
    m = min(n, len(ref["landmarks"]))
    for j, name in enumerate(names):
        if name in J:
            out[:m, J[name]] = ref["landmarks"][:m, j]
    return out


def agreement(j2, ref, pair, min_apart):
    """(agree share, frames) of ``pair``'s names in ``j2`` against ``ref`` (F, 15, 2)."""
    a = [J[f"l_{n}"] for n in PAIRS[pair]]
    b = [J[f"r_{n}"] for n in PAIRS[pair]]
    same = (np.linalg.norm(j2[:, a] - ref[:, a], axis=-1).sum(-1)
            + np.linalg.norm(j2[:, b] - ref[:, b], axis=-1).sum(-1))
    cross = (np.linalg.norm(j2[:, a] - ref[:, b], axis=-1).sum(-1)
             + np.linalg.norm(j2[:, b] - ref[:, a], axis=-1).sum(-1))
    apart = np.linalg.norm(ref[:, a] - ref[:, b], axis=-1).mean(-1) >= min_apart
    ok = apart & np.isfinite(same) & np.isfinite(cross) & np.isfinite(j2).all(axis=(1, 2))
    return (float(np.mean(same[ok] <= cross[ok])) if ok.any() else np.nan), int(ok.sum())


def main():
    from real_clips import pipeline_result

    from vidcap.io.video import iter_frames
    from vidcap.video.lifting import lift_pose
    from vidcap.video.pipeline import colour_cues

    body = BodyModel()
    print("Limb names against MediaPipe's 2D names (real side views; validation; "
          "MediaPipe's names are not the truth in a side view)")
    print("clip | pair | frames | front cue only | + limb cue | frames cued")
    print("--- | --- | --- | --- | --- | ---")
    for name in CLIPS:
        video, ref_path = _paths(name)
        if not (video.exists() and ref_path.exists()):
            print(f"{name} | skipped: needs {video} and {ref_path}")
            continue
        res = pipeline_result(video, height=body.height)
        j2 = res.image_joints2d
        near, limbs = colour_cues(iter_frames(video, stop=len(j2)), j2, res.model_height,
                                  res.body, front=True, limbs=True, fps=res.fps)
        ref = _mediapipe_2d(ref_path, len(j2))
        size = (res.masks.shape[2], res.masks.shape[1])
        out = {}
        for tag, order in (("front", None), ("limbs", limbs)):
            lr = lift_pose(j2, fps=res.fps, body=body, image_sides=True, spread=res.spread,
                           track=res.track, frame_size=size, model_height=res.model_height,
                           near_side=near, limb_order=order)
            out[tag] = lr.joints2d
        h = np.nanmedian(res.model_height)
        for c, pair in enumerate(PAIRS):
            a0, n = agreement(out["front"], ref, pair, 0.02 * h)
            a1, _ = agreement(out["limbs"], ref, pair, 0.02 * h)
            cued = int(np.isfinite(limbs[:, c]).sum())
            print(f"{name} | {pair} | {n} | {a0:.2f} | {a1:.2f} | {cued} of {len(j2)}")
    return 0


if __name__ == "__main__":
    main()
