"""3D lifting accuracy on ground-truth clips (issue 7 benchmark).

For each real motion in ../shared/data/motion/ retargeted onto the body model and
filmed by vidcap.synth's orthographic camera at yaw 90 and 45 degrees, the true 2D
joints are lifted (seed 004 Eq. 2.2, scale estimated from the image height,
orientation proposed) and compared with the true 3D joints after root alignment:

* MPJPE (% of height) with the true depth signs and with the proposed ones;
* share of (frame, segment) signs proposed correctly: all, and where the sign
  matters (segment more than 0.25 of its length out of the image plane, i.e.
  foreshortening ratio < 0.97);
* user inputs (annotation events) needed to reach the true-sign result (MPJPE
  within 0.25 % of height of it), simulating a user who fixes the wrong runs in
  order of their 3D error, each fix being one depth event (carried forward until
  the segment next enters the image plane), and orientation events (carried
  forward) where the proposed orientation's yaw is more than 10 degrees off the
  true one (a wrong label that turns the body by less, such as front_left for
  front_right within a few degrees of facing the camera, is fixed only if the
  target is not reached without it; ``--orient-first`` fixes every wrong label
  first, the previous, stricter user). Seed 004 section 4.3 needed 60 on an
  82-frame walk.

With --end-to-end, also the whole pipeline (silhouettes, 2D fit, lifting) on the
sample clips against their truth: 3D MPJPE after root alignment (also allowing the
body's left/right limbs to be swapped per frame: in a side view the image cannot tell
which leg is which), 2D joint error, orientation agreement.

With --approach, also a subject whose distance from the camera changes: the clips'
true 2D joints are scaled per frame about the image centre (its size from 1 to 2x, or
from 1 to 0.6x, over the clip: walking toward or away from the camera, weak
perspective) and lifted with the true signs and orientation, at the clip's single
scale (``estimate_scale``) and at per-frame scales (``estimate_scales``, what the
pipeline uses).

With --solve, instead, the tables of issue 33 (benchmarks/lift_solve_tables.py): the
per-segment lift against the clip solve on noisy true 2D and end to end (the samples
and held-out renders), MPJPE / PA-MPJPE in mm, foot sliding, jitter, the BVH's bone
lengths and the solve's speed.

Run:  python benchmarks/lift_accuracy.py [--frames 82] [--synth] [--end-to-end] [--approach]
      python benchmarks/lift_accuracy.py --solve [--frames 82] [--no-renders] [--real-only]
                                         [--labels]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from pose2d_accuracy import label_flips  # noqa: E402

from vidcap.body import JOINT_NAMES, SEGMENT_NAMES, BodyModel  # noqa: E402
from vidcap.synth import make_motion, prepare_clip, truth_arrays  # noqa: E402
from vidcap.video.annotations import Annotations  # noqa: E402
from vidcap.video.lift import (  # noqa: E402
    body_axes,
    estimate_scale,
    estimate_scales,
    lift,
    torso_width_ratio,
    yaw_from_orientation,
)
from vidcap.video.lifting import plane_passages  # noqa: E402
from vidcap.video.proposals import propose_orientation, propose_signs  # noqa: E402

DATA = ROOT.parent / "shared" / "data" / "motion"
MATTERS = 0.25  # |dZ| / length above which a sign "matters"
TRACE = False
NEAR_PLANE = 0.15  # |dZ| / length below which a segment is "in the image plane"


def truth_in_camera_frame(t):
    """True joints in lift's frame: X image right, Y up, Z toward the camera."""
    cam = t["camera"]
    s = np.linalg.norm(cam[0, :3])
    right, down, view = cam[0, :3] / s, cam[1, :3] / s, t["view_dir"]
    R = np.stack([right, -down, -view])
    return t["joints3d"] @ R.T


def mpjpe(a, b, height):
    a = a - a[:, :1]
    b = b - b[:, :1]
    return float(np.linalg.norm(a - b, axis=-1).mean() / height * 100)


def true_zeta(truth, body):
    """|dZ| / length of every (frame, segment) from the true 3D joints, shape (F, 10)."""
    from vidcap.body import SEGMENT_JOINTS

    j3 = truth["joints3d"]
    seg = j3[:, SEGMENT_JOINTS[:, 1]] - j3[:, SEGMENT_JOINTS[:, 0]]
    return np.abs(seg @ truth["view_dir"]) / np.linalg.norm(seg, axis=-1)


def sign_scores(signs, truth, body):
    """Share of (frame, segment) depth signs proposed correctly, in %.

    A sign is correct when it equals the true one; a segment *exactly* in the image
    plane (|dZ| < 1e-6 of its length) has no sign (both give the same 3D pose) and
    counts as correct either way. Returns the share over all pairs, over the pairs
    out of the image plane by more than ``MATTERS`` of their length, and over the
    others (near the plane, where a wrong sign moves the distal joint by less than
    ``2 * MATTERS`` lengths), plus the share of pairs that are out of plane.
    """
    z = true_zeta(truth, body)
    ok = (np.asarray(signs) == truth["depth_signs"]) | (z < 1e-6)
    out = z > MATTERS

    def pct(m):
        return float(ok[m].mean() * 100) if m.any() else float("nan")

    return pct(np.ones_like(ok)), pct(out), pct(~out), float(out.mean() * 100)


def arms_inside_torso(truth, body):
    """(F, 10) bool: the arm segments of frames where the *true* elbow or wrist lies
    inside the model's torso (the elliptic section :func:`propose_signs` keeps them
    out of, shoulder to pelvis height).

    The synthetic truth poses this project's body model with a real performer's joint
    rotations, so where the performer's hand or elbow was close to their own body it
    can land inside the model's (wider) torso: a pose no body can take, which the
    proposals are built to avoid.
    """
    import inspect

    depth = inspect.signature(propose_signs).parameters["torso_depth"].default
    j3 = truth_in_camera_frame(truth)
    fwd, left = body_axes(np.deg2rad(truth["yaw_deg"]))
    r, torso = body.radius("torso"), body.segment_lengths()[SEGMENT_NAMES.index("torso")]
    out = np.zeros((len(j3), len(SEGMENT_NAMES)), bool)
    neck = j3[:, JOINT_NAMES.index("neck")]
    axis = neck - j3[:, JOINT_NAMES.index("pelvis")]
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    for side in ("l", "r"):
        rel = j3[:, [JOINT_NAMES.index(f"{side}_elbow"), JOINT_NAMES.index(f"{side}_wrist")]]
        rel = rel - neck[:, None]
        # sections across the true torso axis (a bent torso is not under the neck)
        h = np.einsum("fjc,fc->fj", rel, axis)
        rel = rel - h[..., None] * axis[:, None]
        e = (np.einsum("fjc,fc->fj", rel, left) / r) ** 2 + (
            np.einsum("fjc,fc->fj", rel, fwd) / (depth * r)) ** 2
        level = (h > -torso) & (h < 0.0)
        hit = ((e < 1.0) & level).any(axis=1)
        for seg in ("upper_arm", "lower_arm"):
            out[:, SEGMENT_NAMES.index(f"{side}_{seg}")] = hit
    return out


#: The simulated user fixes an orientation label whose yaw is this far off (degrees).
ORIENT_VISIBLE_DEG = 10.0


def _orientation_events(ann, n, proposed, true, rho=None, *, min_deg=0.0):
    """Simulated user, orientation: fix the first wrong frame until none is wrong.

    With ``min_deg`` > 0 a frame only counts as wrong when its label's yaw (from
    ``rho``, the torso width ratio) is more than ``min_deg`` off the true label's.
    """
    yaw_true = None if not min_deg else yaw_from_orientation(true, rho)
    for _ in range(n):
        _, uo, _ = ann.resolve(n)
        cur = np.where(uo != "", uo, proposed)
        wrong = cur != true
        if yaw_true is not None:
            d = np.angle(np.exp(1j * (yaw_from_orientation(cur, rho) - yaw_true)))
            wrong &= np.abs(d) > np.deg2rad(min_deg)
        wrong = np.flatnonzero(wrong)
        if not wrong.size:
            return
        ann.add_orientation(int(wrong[0]), str(true[wrong[0]]))


def evaluate(truth, body, *, max_events=60, orient_first=False):
    j2 = truth["joints2d"]
    fps = float(truth["fps"])
    true3 = truth_in_camera_frame(truth)
    true_signs = truth["depth_signs"].astype(int)
    s = estimate_scale(j2, body)
    orient = propose_orientation(j2, scale=s, fps=fps, body=body, sides_known=True)
    orient_ok = float(np.mean(orient == truth["orientation"]))
    rho = torso_width_ratio(j2, s, body)
    yaw_true_lbl = yaw_from_orientation(truth["orientation"], rho)
    yaw = yaw_from_orientation(orient, rho)
    e_true = mpjpe(lift(j2, true_signs, yaw_true_lbl, body=body, scale=s).joints3d, true3,
                   body.height)
    prop = propose_signs(j2, yaw, scale=s, body=body)
    e_prop = mpjpe(lift(j2, prop.signs, yaw, body=body, scale=s).joints3d, true3, body.height)
    # the same scores with the true orientation (the signs' own share of the error)
    prop_to = propose_signs(j2, yaw_true_lbl, scale=s, body=body)
    all_ok, out_ok, near_ok, out_share = sign_scores(prop.signs, truth, body)
    all_ok_to, out_ok_to, _, _ = sign_scores(prop_to.signs, truth, body)
    z = true_zeta(truth, body)
    out = z > MATTERS
    ok = (prop.signs == truth["depth_signs"]) | (z < 1e-6)
    inside = arms_inside_torso(truth, body) & out

    # Simulated user. Orientation first where it visibly matters (each event holds
    # until the next one); then depth: the wrong run of frames (per segment) with the
    # largest summed 3D error of its distal joint gets one event at its first frame
    # with the true sign, which holds until the segment next enters the image plane
    # (as in `vidcap annotate`); the proposals are re-run with the user's signs as
    # constraints after each event. Stop when the MPJPE is within 0.25 % of height
    # of the true-sign result; when no wrong sign is left but that is not reached, the
    # remaining (barely visible) orientation labels are fixed too.
    ann = Annotations()
    _orientation_events(ann, len(j2), orient, truth["orientation"], rho,
                        min_deg=0.0 if orient_first else ORIENT_VISIBLE_DEG)
    near = plane_passages(prop.zeta)
    L = body.segment_lengths()
    reached = False
    while True:
        user_signs, user_orient, _ = ann.resolve(len(j2), near_plane=near)
        o = np.where(user_orient != "", user_orient, orient)
        y = yaw_from_orientation(o, rho)
        p = propose_signs(j2, y, scale=s, body=body, fixed=user_signs)
        e_final = mpjpe(lift(j2, p.signs, y, body=body, scale=s).joints3d, true3, body.height)
        if e_final <= e_true + 0.25:
            reached = True
            break
        wrong = p.signs != true_signs
        if ann.n_user_inputs >= max_events:
            break
        if not wrong.any():
            n_before = ann.n_user_inputs
            _orientation_events(ann, len(j2), orient, truth["orientation"])
            if ann.n_user_inputs == n_before:
                break
            continue
        cost = np.where(wrong, 2 * p.zeta * L, 0.0)
        best, best_ev = -1.0, None
        for k in range(len(SEGMENT_NAMES)):
            w = wrong[:, k].astype(int)
            starts = np.flatnonzero(np.diff(np.r_[0, w]) == 1)
            stops = np.flatnonzero(np.diff(np.r_[w, 0]) == -1) + 1
            for a, b in zip(starts, stops, strict=True):
                c = cost[a:b, k].sum()
                if c > best:
                    best, best_ev = c, (int(a), SEGMENT_NAMES[k], int(true_signs[a, k]))
        n_before = ann.n_user_inputs
        ann.add_depth(*best_ev)
        if ann.n_user_inputs == n_before:  # replaced an event: no progress possible
            break
        if TRACE:
            print(ann.n_user_inputs, round(e_final, 3), best_ev, round(best, 3))
    return {
        "frames": len(j2),
        "mpjpe_true": e_true,
        "mpjpe_prop": e_prop,
        "signs_all": all_ok,
        "signs_matter": out_ok,
        "signs_near": near_ok,
        "out_share": out_share,
        "signs_all_true_orient": all_ok_to,
        "signs_matter_true_orient": out_ok_to,
        "orient_ok": orient_ok * 100,
        "events": ann.n_user_inputs,
        "orient_events": sum(e.type == "orientation" for e in ann.events),
        "reached": reached,
        "mpjpe_final": e_final,
        "true_changes": int((np.diff(true_signs, axis=0) != 0).sum()),
        "inside": int(inside.sum()),
        "inside_wrong": int((inside & ~ok).sum()),
        "out_pairs": int(out.sum()),
        "out_wrong": int((out & ~ok).sum()),
        "signs_matter_clear": float(ok[out & ~inside].mean() * 100) if out.any() else np.nan,
    }


def _pairs_swapped_error(res, arms: bool, legs: bool, true3, body) -> float:
    """Mean root-aligned 3D joint error (m) of ``res`` (a pipeline result) lifted again
    with a user's ``sides`` event at frame 0 for the arms and/or the legs: what a user
    who fixes each pair's sides once for the clip gets."""
    from vidcap.video.lifting import lift_pose

    ann = Annotations()
    for pair, on in (("arms", arms), ("legs", legs)):
        if on:
            ann.add_sides(0, pair, True)
    size = (res.masks.shape[2], res.masks.shape[1])
    a = lift_pose(res.image_joints2d, fps=res.fps, body=body, annotations=ann,
                  image_sides=True, spread=res.spread, track=res.track, frame_size=size,
                  model_height=res.model_height).joints3d
    return float(np.linalg.norm((a - a[:, :1]) - (true3 - true3[:, :1]), axis=-1).mean())


def end_to_end(samples: Path, body):
    """vidcap's whole pipeline on the sample clips against their truth."""
    from vidcap.video.lift import swap_sides
    from vidcap.video.pipeline import run

    rows = []
    for video in sorted(samples.glob("*.mp4")):
        truth_path = video.with_name(video.stem + "_truth.npz")
        if not truth_path.exists():
            continue
        t = dict(np.load(truth_path))
        t0 = time.perf_counter()
        # the sample clips are renders of the seed's body: fitted with it
        res = run(video, height=body.height, smooth_sigma=0.0, progress=False,
                  proportions="seed")
        secs = time.perf_counter() - t0
        true3 = truth_in_camera_frame(t)
        ours = res.lifted.joints3d
        a = ours - ours[:, :1]
        b = true3 - true3[:, :1]
        e = np.linalg.norm(a - b, axis=-1).mean(1)
        e_sw = np.linalg.norm(swap_sides(a) - b, axis=-1).mean(1)
        j2 = res.lifted.joints2d
        e2 = np.linalg.norm(j2 - t["joints2d"], axis=-1).mean(1)
        e2_sw = np.linalg.norm(swap_sides(j2) - t["joints2d"], axis=-1).mean(1)
        # each limb pair's sides chosen once for the clip (in a side view no image cue
        # tells the near leg from the far one), and how often a pair's labels flip
        pairs_free = min(_pairs_swapped_error(res, arms, legs, true3, body)
                         for arms in (False, True) for legs in (False, True))
        flips = label_flips(j2, t["joints2d"], np.mean(res.lifted.scale) * body.height
                            * np.ones(len(j2)))
        rows.append((video.name, len(ours), e.mean() / body.height * 100,
                     np.minimum(e, e_sw).mean() / body.height * 100,
                     pairs_free / body.height * 100, flips,
                     np.minimum(e2, e2_sw).mean() / (np.mean(res.lifted.scale) * body.height) * 100,
                     float(np.mean(res.lifted.orientation == t["orientation"]) * 100), secs))
    return rows


def approach(truth, body, gain_end):
    """MPJPE (% of height) with true signs at one scale and per-frame scales, and the
    per-frame scales' largest error (%), when the image grows linearly to gain_end."""
    j2 = truth["joints2d"]
    n = len(j2)
    gain = np.linspace(1.0, gain_end, n)[:, None, None]
    centre = np.array([320.0, 240.0])
    jg = centre + gain * (j2 - centre)
    true3 = truth_in_camera_frame(truth)
    signs = truth["depth_signs"].astype(int)
    s0 = estimate_scale(j2, body)
    rho = torso_width_ratio(j2, s0, body)  # the unscaled clip's: isolates the scale
    yaw = yaw_from_orientation(truth["orientation"], rho)
    out = []
    for scale in (estimate_scale(jg, body), estimate_scales(jg, body)):
        out.append(mpjpe(lift(jg, signs, yaw, body=body, scale=scale).joints3d, true3,
                         body.height))
    per = np.broadcast_to(estimate_scales(jg, body), (n,))
    out.append(float(np.max(np.abs(per / (s0 * gain[:, 0, 0]) - 1)) * 100))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=82, help="frames per clip at 30 fps")
    ap.add_argument("--synth", action="store_true",
                    help="vidcap.synth's built-in motions (walk, arms, jacks) at yaw 90/45/20 "
                         "instead: the set the proposal weights are chosen on")
    ap.add_argument("--orient-first", action="store_true",
                    help="the simulated user fixes every wrong orientation label first, "
                         "however little it turns the body")
    ap.add_argument("--end-to-end", action="store_true",
                    help="also run the whole pipeline on sample_videos/ against their truth")
    ap.add_argument("--approach", action="store_true",
                    help="also a subject walking toward / away from the camera (per-frame scale)")
    ap.add_argument("--solve", action="store_true",
                    help="the issue-33 tables: per-segment lift vs the clip solve")
    ap.add_argument("--no-renders", action="store_true",
                    help="with --solve: skip the held-out renders (each needs a 2D fit)")
    ap.add_argument("--real-only", action="store_true",
                    help="with --solve: only the real-footage table (MediaPipe references)")
    ap.add_argument("--labels", action="store_true",
                    help="with --solve: the solve on fitted 2D chooses the limbs' names "
                         "(vidcap.video.solve.stage.LABELS)")
    ap.add_argument("--consistent-names", action="store_true",
                    help="with --solve: the 3D stage repairs the 2D fit's limb names "
                         "(vidcap.video.lifting.CONSISTENT_NAMES, off by default)")
    ap.add_argument("--real-proportions", choices=("human", "seed"), default="human",
                    help="with --solve: the real clips' body the pipeline fits and lifts (vidcap "
                         "convert's --proportions; default human, as convert)")
    ap.add_argument("--only", metavar="NAME",
                    help="with --solve --real-only: just the real clips whose name contains NAME")
    ap.add_argument("--graph-cut", action=argparse.BooleanOptionalAction, default=None,
                    help="the pipeline's silhouettes with or without the graph cut (default: "
                         "vidcap.video.pipeline.DEFAULT_GRAPH_CUT, as vidcap convert)")
    ap.add_argument("--ensemble", type=int, default=1,
                    help="with --solve: the end-to-end rows' 2D fit as the median of N fits "
                         "(vidcap convert --ensemble N; default 1)")
    import lift_solve_tables as st

    st.add_front_options(ap)
    args = ap.parse_args(argv)
    global ENSEMBLE
    ENSEMBLE = args.ensemble
    st.apply_front_options(args)
    body = BodyModel()
    if args.graph_cut is not None:  # the stage cache keys on it: no stale silhouettes
        import vidcap.video.pipeline as pipeline

        pipeline.DEFAULT_GRAPH_CUT = args.graph_cut
    if args.labels:  # the solve on fitted 2D chooses the limbs' names
        import vidcap.video.solve.stage as solve_stage

        solve_stage.LABELS = True
    if args.consistent_names:
        import vidcap.video.lifting as lifting

        lifting.CONSISTENT_NAMES = True
    if args.solve and args.real_only:
        return _real_table(st, args.real_proportions, args.only)
    if args.solve:
        return solve_tables(args.frames, body, renders=not args.no_renders,
                            real_proportions=args.real_proportions)
    motions = {
        "131_01.bvh": dict(name_or_path=DATA / "131_01.bvh", frame_range=(200, None)),
        "07_07.amc": dict(name_or_path=DATA / "07.asf", amc=DATA / "07_07.amc"),
    }
    yaws = (90.0, 45.0)
    if args.synth:
        motions = {n: dict(name_or_path=n) for n in ("walk", "arms", "jacks")}
        yaws = (90.0, 45.0, 20.0)
    rows = []
    approach_rows = []
    t0 = time.perf_counter()
    for mname, kw in motions.items():
        motion = make_motion(**kw, body=body, fps=30.0, rng=np.random.default_rng(0))
        motion = motion.frames(0, min(args.frames, motion.n_frames))
        for yaw in yaws:
            clip = prepare_clip(motion, body=body, yaw_deg=yaw, rng=np.random.default_rng(1))
            truth = truth_arrays(clip, np.zeros((motion.n_frames, 1, 1), bool))
            rows.append((mname, yaw, evaluate(truth, body, orient_first=args.orient_first)))
            if args.approach:
                for g in (2.0, 0.6):
                    approach_rows.append((mname, yaw, g, approach(truth, body, g)))
    head = ("motion", "yaw", "frames", "MPJPE true %", "MPJPE prop %", "signs ok % (all)",
            "ok out of plane %", "ok near plane %", "out of plane share %",
            "all / out, true orient %", "orient ok %", "events (orient)", "MPJPE after %",
            "true changes")
    print(" | ".join(head))
    print(" | ".join("---" for _ in head))
    for m, yaw, r in rows:
        ev = f"{r['events']} ({r['orient_events']})" + ("" if r["reached"] else " not reached")
        print(f"{m} | {yaw:.0f} | {r['frames']} | {r['mpjpe_true']:.2f} | {r['mpjpe_prop']:.2f} | "
              f"{r['signs_all']:.1f} | {r['signs_matter']:.1f} | {r['signs_near']:.1f} | "
              f"{r['out_share']:.0f} | {r['signs_all_true_orient']:.1f} / "
              f"{r['signs_matter_true_orient']:.1f} | {r['orient_ok']:.0f} | {ev} | "
              f"{r['mpjpe_final']:.2f} | {r['true_changes']}")
    print("\nOut-of-plane depth signs where the true arm is inside the model's torso "
          "(retargeted mocap: see arms_inside_torso):")
    print("motion | yaw | out of plane pairs | wrong | arm pairs inside the torso | wrong "
          "among them | ok out of plane, those left out %")
    print("--- | --- | --- | --- | --- | --- | ---")
    for m, yaw, r in rows:
        print(f"{m} | {yaw:.0f} | {r['out_pairs']} | {r['out_wrong']} | {r['inside']} | "
              f"{r['inside_wrong']} | {r['signs_matter_clear']:.1f}")
    if args.synth:
        keys = ("signs_all", "signs_matter", "events")
        mean = {k: np.nanmean([r[k] for _, _, r in rows]) for k in keys}
        gap = np.mean([r["mpjpe_prop"] - r["mpjpe_true"] for _, _, r in rows])
        dev = np.mean([r["events"] - r["orient_events"] for _, _, r in rows])
        print(f"\nmean: signs ok {mean['signs_all']:.1f} %, out of plane "
              f"{mean['signs_matter']:.1f} %, MPJPE prop - true {gap:.2f} points, "
              f"depth events {dev:.1f}")
    print(f"\n(targets: MPJPE with true signs <= 5 %, signs >= 90 %, events <= 6 on 82 frames;"
          f" seed 004: 60 inputs; {time.perf_counter() - t0:.1f} s)")
    if approach_rows:
        print("\nDistance changing (true 2D joints scaled per frame, true signs):")
        print("motion | yaw | image size at the end | MPJPE one scale % | "
              "MPJPE per-frame scales % | per-frame scale error, max %")
        print("--- | --- | --- | --- | --- | ---")
        for m, yaw, g, (e1, e2, es) in approach_rows:
            print(f"{m} | {yaw:.0f} | {g:.1f}x | {e1:.2f} | {e2:.2f} | {es:.1f}")
    if args.end_to_end:
        rows = end_to_end(ROOT / "sample_videos", body)
        print("\nEnd to end (vidcap's pipeline on sample_videos/, no annotations, no smoothing):")
        print("clip | frames | 3D MPJPE % | 3D MPJPE, sides free % | 3D MPJPE, each pair's "
              "sides once % | label flips | 2D error % | orient ok % | s")
        print("--- | --- | --- | --- | --- | --- | --- | --- | ---")
        for r in rows:
            print(f"{r[0]} | {r[1]} | {r[2]:.1f} | {r[3]:.1f} | {r[4]:.1f} | {r[5]} | "
                  f"{r[6]:.1f} | {r[7]:.0f} | {r[8]:.1f}")


#: Held-out renders for the end-to-end solve table: (name, motion, first frame, yaw);
#: none of them chose a weight of the solve (those were chosen on the built-in walk).
SOLVE_RENDERS = (("131_01 2-4s", "131_01", 60, 60.0), ("131_01 5-7s", "131_01", 150, 135.0),
                 ("07_07 end", "07_07", -60, 90.0), ("07_07 0.7-2.7s", "07_07", 20, 30.0))


#: ``--ensemble N``: the 2D fit of the end-to-end rows (renders and samples) as the median
#: of N fits on masks changed at the outline (``vidcap convert --ensemble N``); 1: one fit.
ENSEMBLE = 1


def _render_clips(body, frames):
    from vidcap.synth import render_clip
    from vidcap.video.fit.ensemble import fit_ensemble
    from vidcap.video.pipeline import colour_cues

    full = {"131_01": make_motion(DATA / "131_01.bvh", body=body, fps=30.0),
            "07_07": make_motion(DATA / "07.asf", amc=DATA / "07_07.amc", body=body, fps=30.0)}
    out = []
    for name, source, first, yaw in SOLVE_RENDERS:
        n = full[source].n_frames
        start = first if first >= 0 else n + first
        motion = full[source].frames(start, min(start + frames, n))
        images, truth = render_clip(motion, yaw_deg=yaw, size=(640, 480), noise=0.0,
                                    rng=np.random.default_rng(0))
        pose = fit_ensemble(truth["masks"], ensemble=ENSEMBLE)
        near, limbs = colour_cues(images, pose.joints2d, pose.model_height, body, front=True,
                                 limbs=True, fps=float(truth["fps"]))
        fit = {"joints2d": pose.joints2d, "spread": pose.spread,
               "model_height": pose.model_height, "near_side": near, "limb_order": limbs}
        out.append((f"{name} yaw {yaw:.0f} (held out)", fit, truth,
                    truth_in_camera_frame(truth), (640, 480)))
    return out


def _sample_clips(body):
    """The samples through the pipeline (tuning for the front/back cue's constants)."""
    from vidcap.io.video import iter_frames
    from vidcap.video.pipeline import colour_cues, run

    out = []
    cache = ROOT / ".vidcap-cache"  # the 2D stage's cache (not in git)
    for video in sorted((ROOT / "sample_videos").glob("*.mp4")):
        truth_path = video.with_name(video.stem + "_truth.npz")
        if not truth_path.exists():
            continue
        t = dict(np.load(truth_path))
        res = run(video, height=body.height, smooth_sigma=0.0, progress=False,
                  cache_dir=cache, lift="segment", proportions="seed",  # seed renders
                  ensemble=ENSEMBLE)
        near, limbs = colour_cues(iter_frames(video, stop=len(res.image_joints2d)),
                                 res.image_joints2d, res.model_height, body, front=True,
                                 limbs=True, fps=res.fps)
        fit = {"joints2d": res.image_joints2d, "spread": res.spread,
               "model_height": res.model_height, "track": res.track,
               "near_side": near, "limb_order": limbs}
        out.append((f"{video.stem} (sample)", fit, t, truth_in_camera_frame(t),
                    (res.masks.shape[2], res.masks.shape[1])))
    return out


def solve_tables(frames, body, *, renders=True, real_proportions="human"):
    """The ``--solve`` tables (see benchmarks/lift_solve_tables.py); the real clips' pipeline
    fits and lifts the ``real_proportions`` body."""
    import lift_solve_tables as st

    motions = {
        "walk (tuning)": dict(name_or_path="walk", n_frames=frames),
        "131_01 (validation)": dict(name_or_path=DATA / "131_01.bvh", frame_range=(200, None)),
        "07_07 (validation)": dict(name_or_path=DATA / "07.asf", amc=DATA / "07_07.amc"),
    }
    rows, bones, speeds = [], [], []
    for mname, kw in motions.items():
        motion = make_motion(**kw, body=body, fps=30.0, rng=np.random.default_rng(0))
        motion = motion.frames(0, min(frames, motion.n_frames))
        for yaw in (90.0, 45.0):
            clip = prepare_clip(motion, body=body, yaw_deg=yaw, rng=np.random.default_rng(1))
            truth = truth_arrays(clip, np.zeros((motion.n_frames, 1, 1), bool))
            r, b, sp = st.noisy_rows(f"{mname} yaw {yaw:.0f}", truth,
                                     truth_in_camera_frame(truth), body)
            rows += r
            bones.append(b)
            speeds += sp
    print(f"True 2D plus noise ({frames} frames, 30 fps; orientation proposed; the solve's "
          "weights were chosen on the walk):")
    st.print_noisy(rows)
    for noise in st.NOISE:
        for lift_name in ("segment", "solve"):
            sel = [r[5] for r in rows if r[1] == noise and r[2] == lift_name
                   and r[3] == "proposed" and "validation" in r[0]]
            print(f"  mean PA-MPJPE, validation, proposed signs, noise {noise * 100:.0f} %, "
                  f"{lift_name}: {np.mean(sel):.0f} mm")
    print(f"\nBVH from the solve, read back: largest bone-length deviation {max(bones):.1e} m; "
          f"solve speed {np.median(speeds):.0f} frames/s (median over clips, this run)")
    clips = _sample_clips(body) + (_render_clips(body, 60) if renders else [])
    print("\nEnd to end (2D fit, no annotations, no smoothing):")
    e2e = st.end_to_end_rows(clips, body)
    st.print_end_to_end(e2e)
    # the metric's own floor: a true ankle "planted" by it moves up to 0.25 m/s (the heel
    # and toe rolls of a stance), which a lift holding the foot still does not follow
    print("  foot sliding of the truth itself, same frames (mm/frame): " + ", ".join(
        f"{name.split(' (')[0]} {st.sliding_mm(t3, st.true_planted(t3, float(tr['fps']))):.1f}"
        for name, _, tr, t3, _ in clips))
    _real_table(st, real_proportions)
    return 0


#: Person-present stretches of onebyone_room.mp4 ($VIDCAP_DATA/video/CLIPS.md: MediaPipe
#: also "finds" a person on the table in empty frames).
ONEBYONE_VISITS = ((66, 195), (233, 446), (510, 695), (749, 866), (936, 1196), (1242, 1358))


def _real_clips():
    """(label, video, MediaPipe reference npz, frames mask or None) of the real clips:
    ido_walk (reference under $VIDCAP_DATA/lift/) and those of $VIDCAP_DATA/video/CLIPS.md;
    onebyone_room on its six visits together, then on each one-person stretch of
    ``real_clips.STRETCHES`` (the ones pose2d_real.py scores) alone."""
    import os

    from real_clips import STRETCHES

    data = Path(os.environ.get("VIDCAP_DATA", "/nonexistent"))
    out = [(None, DATA.parent / "video" / "ido_walk.avi",
            data / "lift" / "ido_walk_mediapipe.npz", None)]
    for video in sorted((data / "video").glob("*.mp4")):
        frames = None
        if video.stem == "onebyone_room":
            frames = np.zeros(1394, bool)
            for a, b in ONEBYONE_VISITS:
                frames[a:b] = True
            out.append((f"{video.name} (6 visits)", video, video.with_suffix(".mediapipe.npz"),
                        frames))
            for a, b in STRETCHES.get(video.stem, ()):
                frames = np.zeros(1394, bool)
                frames[a:b] = True
                out.append((f"{video.name} {a}-{b - 1}", video,
                            video.with_suffix(".mediapipe.npz"), frames))
            continue
        out.append((None, video, video.with_suffix(".mediapipe.npz"), frames))
    return out


#: Real clips looked at closely when something was chosen: their rows count as tuning.
#: The face cue's crop size (mmskeleton_clean_jerk's small faces, pose2sim's anonymised
#: ones) and the face's window not carried on (mmskeleton_taichi: profiles first, a
#: face later) were set after looking at their head crops (vidcap.video.facecue).
REAL_LOOKED_AT = ("mmskeleton_clean_jerk", "mmskeleton_taichi", "pose2sim_balance_cam1")


def _real_table(st, proportions, only=None):
    """Real footage against MediaPipe's world landmarks (mediapipe-reference's npz),
    the pipeline run with ``proportions`` (``vidcap convert --proportions``), skipped with
    the reason when absent."""
    print("\nReal footage, PA-MPJPE against MediaPipe Pose's world landmarks (validation; "
          "MediaPipe is a reference, not the truth). 'standing pose': one fixed pose, arms "
          "down, for every frame (no video read):")
    print("clip | frames | lift | PA-MPJPE mm")
    print("--- | --- | --- | ---")
    for label, video, ref, frames in _real_clips():
        if only and only not in (label or video.name):
            continue
        if not (video.exists() and ref.exists()):
            print(f"  skipped: needs {video} and {ref} (run ../shared/tools/mediapipe-reference/"
                  "reference.py VIDEO OUT.npz with VIDCAP_DATA set)")
            continue
        if video.stem in REAL_LOOKED_AT:
            label = f"{label or video.name} (tuning: looked at)"
        for r in st.real_rows(video, ref, proportions, frames, label):
            print(f"{r[0]} | {r[1]} | {r[2]} | {r[3]:.0f}")

if __name__ == "__main__":
    main()
