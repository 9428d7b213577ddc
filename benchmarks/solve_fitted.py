"""The clip solve on fitted 2D only, quickly: the 2D fit's joints are computed once and
kept (``$VIDCAP_DATA/cache/solve_fitted/*.npz``, not in git), then only the 3D stage runs.

Clips: tuning renders (vidcap.synth's walk at yaw 60 and 120, jacks at 30, arms at 120,
60 frames: the set ``FITTED_NOISE_FLOOR`` was chosen on) and validation (the three
samples, the four held-out renders of ``lift_accuracy.py --solve``). The validation rows
are for reporting: choose nothing on them. For the front/back cue of the colour frame
(``--front``, :mod:`vidcap.video.frontback`) the three samples were tuning too; the
held-out renders stay validation, but for 07_07 end (seen when choosing
``vidcap.video.lifting.SIDE_FACING_SPREAD``) and 07_07 0.7-2.7 s yaw 30 (its thighs' depths
looked at when designing the heading residual, ``vidcap.video.solve.clip.HEADING_WEIGHT``,
whose weight was chosen on the tuning rows; tagged tuning since, :data:`LOOKED_AT`, and
in the tuning mean).

``--front`` reads the clips' colour frames (renders drawn again, the samples decoded;
kept in ``$VIDCAP_DATA/cache/frontback/``) and hands the 3D stage the near-side cue; the
extra column "front/back right" is the share of frames (not within 15 degrees of a side
view) whose solved torso faces the camera as the truth does.

``--attribute`` prints where the error comes from instead (front/back cue on; with
``--legs`` the limb-order cue too, :mod:`vidcap.video.legorder`): each clip
solved again with the truth in place of one thing the 3D stage reads (the 2D joints, the
limbs' names, the depth signs, front/back, the yaw), alone and all but one
(:mod:`solve_attribution`), and the per-joint 2D error of walk_side as named and with the
truth's names.

Run:  python benchmarks/solve_fitted.py [--tuning-only] [--method solve|segment] [--front]
                                        [--legs] [--labels] [--attribute [--joints]]
                                        [--consistent-names] [--split]

``--split`` (:mod:`solve_error_split`): where the error lives, frame by frame (the
frames banded by their worst 2D joint, the best reflection, the grossly wrong joints).

``--legs``: the colour frame's limb order (:mod:`vidcap.video.legorder`) names the arms
and legs (tuning: the renders and the samples, as for ``--front``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import lift_solve_tables as st  # noqa: E402
from lift_accuracy import DATA, SOLVE_RENDERS, truth_in_camera_frame  # noqa: E402

from vidcap.body import BodyModel  # noqa: E402
from vidcap.synth import make_motion  # noqa: E402

#: Held-out renders looked at closely when something was chosen: their rows count as
#: tuning (07_07 0.7-2.7 s: its thighs' depths, for the heading residual).
LOOKED_AT = ("07_07 0.7-2.7s",)
TUNING = (("walk yaw 60", "walk", 60.0), ("walk yaw 120", "walk", 120.0),
          ("jacks yaw 30", "jacks", 30.0), ("arms yaw 120", "arms", 120.0))
FRAMES = 60


def _cache_dir() -> Path:
    d = Path(os.environ.get("VIDCAP_DATA", "/tmp")) / "cache" / "solve_fitted"
    d.mkdir(parents=True, exist_ok=True)
    return d


def _frames_path(name) -> Path:
    d = Path(os.environ.get("VIDCAP_DATA", "/tmp")) / "cache" / "frontback"
    d.mkdir(parents=True, exist_ok=True)
    return d / (name.replace(" ", "_").replace("/", "_") + ".npz")


def clip_frames(name, body):
    """The colour frames (F, H, W, 3) of a clip of :func:`tuning_clips` /
    :func:`validation_clips` (its name without the tag), rendered or decoded once."""
    path = _frames_path(name)
    if not path.exists():
        np.savez_compressed(path, frames=_make_frames(name, body))
    return np.load(path)["frames"]


def _make_frames(name, body):
    from vidcap.io.video import iter_frames
    from vidcap.synth import render_clip

    for n, motion_name, yaw in TUNING:
        if name == n:
            m = make_motion(motion_name, body=body, fps=30.0, n_frames=FRAMES,
                            rng=np.random.default_rng(0))
            return render_clip(m, yaw_deg=yaw, size=(640, 480), noise=0.0,
                               rng=np.random.default_rng(0))[0]
    for n, source, first, yaw in SOLVE_RENDERS:
        if name == f"{n} yaw {yaw:.0f}":
            m = _source_motion(source, body)
            start = first if first >= 0 else m.n_frames + first
            return render_clip(m.frames(start, min(start + FRAMES, m.n_frames)), yaw_deg=yaw,
                               size=(640, 480), noise=0.0, rng=np.random.default_rng(0))[0]
    return np.array(list(iter_frames(ROOT / "sample_videos" / f"{name}.mp4")))


def _source_motion(source, body):
    if source == "131_01":
        return make_motion(DATA / "131_01.bvh", body=body, fps=30.0)
    return make_motion(DATA / "07.asf", amc=DATA / "07_07.amc", body=body, fps=30.0)


def true_yaw(true3) -> np.ndarray:
    """The true torso's yaw (F,) radians in the lift's frame (0 facing the camera, +pi/2
    facing image right), from joints (F, 15, 3) X right, Y up, Z toward the camera."""
    from vidcap.body import JOINT_INDEX as J

    lat = (true3[:, J["r_hip"]] - true3[:, J["l_hip"]]
           + true3[:, J["r_shoulder"]] - true3[:, J["l_shoulder"]])
    fwd = np.cross(np.array([0.0, 1.0, 0.0]), lat)
    return np.arctan2(fwd[:, 0], fwd[:, 2])


def front_back_right(yaw, true3, margin_deg: float = 15.0) -> float:
    """Share of frames, not within ``margin_deg`` of a side view, whose ``yaw`` (F,)
    faces the camera (cos > 0) as the truth does; NaN where every frame is a side view."""
    c = np.cos(true_yaw(true3))
    m = np.abs(c) > np.sin(np.deg2rad(margin_deg))
    return float(np.mean(np.sign(np.cos(yaw[m])) == np.sign(c[m]))) if m.any() else np.nan


def _render_fit(motion, yaw):
    from vidcap.synth import render_clip
    from vidcap.video.fit.pose2d import fit_sequence

    _, truth = render_clip(motion, yaw_deg=yaw, size=(640, 480), noise=0.0,
                           rng=np.random.default_rng(0))
    pose = fit_sequence(truth["masks"])
    return dict(joints2d=pose.joints2d, spread=pose.spread, model_height=pose.model_height,
                true3=truth_in_camera_frame(truth), true2=truth["joints2d"],
                fps=float(truth["fps"]), size=np.array([640, 480]))


def _clip(name, make):
    path = _cache_dir() / (name.replace(" ", "_").replace("/", "_") + ".npz")
    if not path.exists():
        np.savez(path, **make())
    return dict(np.load(path))


def tuning_clips(body):
    out = []
    for name, motion_name, yaw in TUNING:
        def make(motion_name=motion_name, yaw=yaw):
            m = make_motion(motion_name, body=body, fps=30.0, n_frames=FRAMES,
                            rng=np.random.default_rng(0))
            return _render_fit(m, yaw)
        out.append((name + " (tuning)", _clip(name, make)))
    return out


def validation_clips(body):
    from vidcap.video.pipeline import run

    out = []
    for video in sorted((ROOT / "sample_videos").glob("*.mp4")):
        truth_path = video.with_name(video.stem + "_truth.npz")
        if not truth_path.exists():
            continue

        def make(video=video, truth_path=truth_path):
            t = dict(np.load(truth_path))
            res = run(video, height=body.height, smooth_sigma=0.0, progress=False,
                      cache_dir=ROOT / ".vidcap-cache", lift="segment",
                      proportions="seed")  # the samples are renders of the seed's body
            return dict(joints2d=res.image_joints2d, spread=res.spread,
                        model_height=res.model_height, track=res.track,
                        true3=truth_in_camera_frame(t), true2=t["joints2d"],
                        fps=float(t["fps"]),
                        size=np.array([res.masks.shape[2], res.masks.shape[1]]))
        out.append((f"{video.stem} (sample)", _clip(video.stem, make)))
    full = {}
    for name, source, first, yaw in SOLVE_RENDERS:
        def make(name=name, source=source, first=first, yaw=yaw):
            if source not in full:
                full[source] = _source_motion(source, body)
            m = full[source]
            start = first if first >= 0 else m.n_frames + first
            return _render_fit(m.frames(start, min(start + 60, m.n_frames)), yaw)
        tag = "tuning: looked at" if name in LOOKED_AT else "held out"
        out.append((f"{name} yaw {yaw:.0f} ({tag})", _clip(f"{name} yaw {yaw:.0f}", make)))
    return out


def pa_per_frame(pred, true):
    """PA-MPJPE of each frame (F,), mm."""
    return np.array([st.pa_mpjpe_mm(pred[f:f + 1], true[f:f + 1]) for f in range(len(pred))])


def mirrored(true3):
    """The truth reflected through the image plane with its sides renamed: the body an
    orthographic image cannot tell from it (front/back)."""
    from vidcap.video.lift import swap_sides

    return swap_sides(true3 * np.array([1.0, 1.0, -1.0]))


def near_sides(clips, body):
    """{clip name: the front/back cue} from each clip's colour frames, as the pipeline
    reads it (:func:`vidcap.video.pipeline.colour_cues`: the near side (F,), with the
    face (F, 2) where ``pipeline.FACE_CUE``)."""
    from vidcap.video.pipeline import colour_cues

    return {name: colour_cues(clip_frames(name.split(" (")[0], body), c["joints2d"],
                              front=True, limbs=False, fps=float(c["fps"]))[0]
            for name, c in clips}


def limb_orders(clips, body):
    """{clip name: the limb-order cue (F, 2)} from each clip's colour frames
    (:mod:`vidcap.video.legorder`)."""
    from vidcap.video.legorder import limb_edges, limb_radii, near_limb

    return {name: near_limb(*limb_edges(clip_frames(name.split(" (")[0], body),
                                        c["joints2d"], limb_radii(c["model_height"], body)))
            for name, c in clips}


def evaluate(clips, body, method="solve", near=None, legs=None):
    """Rows (name, frames, PA-MPJPE mm, MPJPE mm, 2D error % of height, CPU s, PA-MPJPE
    with the front/back mirror free per frame mm, share of frames front/back right)."""
    from vidcap.video.lifting import lift_pose
    from vidcap.video.solve.skeleton import YAW

    rows = []
    for name, c in clips:
        t0 = time.process_time()
        lr = lift_pose(c["joints2d"], fps=float(c["fps"]), body=body, image_sides=True,
                       spread=c["spread"], track=c.get("track"),
                       frame_size=tuple(int(v) for v in c["size"]),
                       model_height=c["model_height"], method=method,
                       near_side=None if near is None else near[name],
                       limb_order=None if legs is None else legs[name])
        secs = time.process_time() - t0
        yaw = lr.yaw if lr.solve_params is None else lr.solve_params[:, YAW]
        e2 = np.linalg.norm(lr.joints2d - c["true2"], axis=-1).mean()
        h_px = np.mean(lr.scale) * body.height
        rows.append((name, len(lr.joints3d), st.pa_mpjpe_mm(lr.joints3d, c["true3"]),
                     st.mpjpe_mm(lr.joints3d, c["true3"]), e2 / h_px * 100, secs,
                     float(np.minimum(pa_per_frame(lr.joints3d, c["true3"]),
                                      pa_per_frame(lr.joints3d, mirrored(c["true3"]))).mean()),
                     front_back_right(yaw, c["true3"])))
    return rows


def attribute(clips, body, limbs=False, joints=False, split=False):
    """Print the oracle attribution table (:mod:`solve_attribution`); with ``limbs`` the
    limb-order cue on too; with ``joints`` the table by limb instead
    (:func:`solve_attribution.joint_rows`); with ``split`` the error by frame band
    (:mod:`solve_error_split`)."""
    import solve_attribution as sa

    from vidcap.video.pipeline import colour_cues

    def near_fn(name, joints2d):
        c = dict(clips)[name]
        near, order = colour_cues(clip_frames(name.split(" (")[0], body), joints2d,
                                  c["model_height"], body, front=True, limbs=limbs,
                                  fps=float(c["fps"]))
        return {"near_side": near, "limb_order": order}

    cues = "front/back and limb-order cues" if limbs else "front/back cue"
    if split:
        import solve_error_split as se

        print(f"Where the error lives ({cues} on): frames by their worst limb joint's "
              "2D error (% of height)")
        se.print_split([se.split_row(name, c, body, near_fn) for name, c in clips])
        return 0
    if joints:
        print(f"PA-MPJPE mm, the 3D stage ({cues} on) with the truth of one limb group, or "
              f"the 2D joints more than a share of the height off weighted "
              f"{sa.DROP_WEIGHT:g}")
        sa.print_attribution(sa.joint_rows(clips, body, near_fn), sa.joint_settings)
        return 0
    print(f"PA-MPJPE mm, the 3D stage ({cues} on) with the truth in place of ...")
    sa.print_attribution(sa.attribution_rows(clips, body, near_fn))
    for name, c in clips:
        if name.startswith("walk_side"):
            print(f"\n{name}: 2D error per joint, % of height: as the stage names it | "
                  "with the truth's names")
            for j, a, b in sa.joint_errors(c, body, near_fn(name, c["joints2d"])):
                print(f"{j} | {a:.1f} | {b:.1f}")
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tuning-only", action="store_true")
    ap.add_argument("--method", default="solve")
    ap.add_argument("--labels", action="store_true",
                    help="let the solve choose the arms' and legs' names "
                         "(vidcap.video.solve.stage.LABELS)")
    ap.add_argument("--front", action="store_true",
                    help="the colour frame's near-side cue for front/back "
                         "(vidcap.video.frontback)")
    ap.add_argument("--consistent-names", action="store_true",
                    help="repair the 2D fit's limb names where they jump "
                         "(vidcap.video.lifting.CONSISTENT_NAMES, off by default)")
    ap.add_argument("--legs", action="store_true",
                    help="the colour frame's limb-order cue names the arms and legs "
                         "(vidcap.video.legorder)")
    ap.add_argument("--attribute", action="store_true",
                    help="oracle substitutions: where the error comes from")
    ap.add_argument("--joints", action="store_true",
                    help="with --attribute: by limb (the arms' or legs' true 2D or signs) "
                         "and the ceiling of a per-joint confidence (bad 2D joints dropped)")
    ap.add_argument("--split", action="store_true",
                    help="where the error lives: frames by their worst 2D joint, the best "
                         "reflection, the grossly wrong joints (solve_error_split.py)")
    st.add_front_options(ap)
    args = ap.parse_args(argv)
    st.apply_front_options(args)
    body = BodyModel()
    clips = tuning_clips(body)
    if not args.tuning_only:
        clips += validation_clips(body)
    if args.labels:
        import vidcap.video.solve.stage as solve_stage

        solve_stage.LABELS = True
    if args.consistent_names:
        import vidcap.video.lifting as lifting

        lifting.CONSISTENT_NAMES = True
    if args.attribute or args.split:
        return attribute(clips, body, limbs=args.legs, joints=args.joints, split=args.split)
    near = near_sides(clips, body) if args.front else None
    legs = limb_orders(clips, body) if args.legs else None
    rows = evaluate(clips, body, args.method, near, legs)
    print("clip | frames | PA-MPJPE mm | PA-MPJPE, front/back free mm | MPJPE mm | "
          "2D error % of height (body sides) | CPU s | front/back right")
    print("--- | --- | --- | --- | --- | --- | --- | ---")
    for r in rows:
        print(f"{r[0]} | {r[1]} | {r[2]:.0f} | {r[6]:.0f} | {r[3]:.0f} | {r[4]:.1f} | "
              f"{r[5]:.2f} | {r[7]:.2f}")
    for tag in ("tuning", "sample", "held out"):
        sel = [(r[2], r[6]) for r in rows if tag in r[0]]
        if sel:
            m = np.mean(sel, axis=0)
            print(f"mean PA-MPJPE, {tag}: {m[0]:.1f} mm (front/back free {m[1]:.1f} mm)")
    return 0


if __name__ == "__main__":
    main()
