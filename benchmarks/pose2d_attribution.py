"""Where the 2D fit's misses are on the side and three-quarter tuning renders (issue 27).

Fits the **tuning** renders of :mod:`pose2d_accuracy` (the first 2 s of CMU 131_01 and 07_07
at yaws 90, 110, 70, 100 (side) and 45, 135 (three-quarter); the built-in walk at 100, 45 and
140; 640x480, true silhouettes, tracked) with the frame's cues and with the outline only, and
prints per clip PCK@0.05 of all joints, then per view an attribution table of the cue fit's
misses (limb pairs matched per frame, as ``--held-out`` does):

* misses by class, as PCK points (share of all joint-frames): elbows and wrists of the **far**
  arm (the one whose shoulder is farther from the camera) whose true position lies inside the
  torso's outline, the same of the **near** arm, elbows and wrists outside the outline,
  shoulders, legs (hips, knees, ankles), the axis (pelvis, neck, head top);
* oracle gains, PCK points: each class's joints set to the truth; each frame's elbows and
  wrists exchanged between the shoulders where that is better (an arm hung from the wrong
  shoulder);
* the far and near arms' elbows and wrists inside the outline within 5 % of the height, cues
  vs outline only (the cues find a near arm the frame shows; behind the torso there is
  nothing to find);
* "interpolated": elbows and wrists of frames whose arm lies inside the torso's outline
  (the truth's, or the fit's own) replaced by angles interpolated from the nearest frames
  where it stands clear, PCK points gained (negative: lost).

Nothing here is validation: these clips chose the fit's constants (the held-out renders are
``pose2d_accuracy.py --held-out``). The 70 and 100 degree rows of 131_01 and 07_07 were added
as tuning clips by wt-side (issue 27): same motions and stretch as the ``--frames 60`` clips.

``--extra``: also four side-view tuning renders of CMU 14_19 (a subject no other 2D
benchmark uses; ``$VIDCAP_DATA/mocap/cmu/14_19_humanik.bvh``, benchmarks/get_data.sh) added
by wt-sideview (issue 27): 6-8 s at yaws 90 and 270, 13-15 s at 80, 20-22 s at 100 (hands
above the head throughout). Stretches the silhouette benchmarks do not render.

``--hidden solve``: the cue fit's joints the image cannot show (shoulders, hips, arms inside the
torso's outline) taken from the 3D clip solve first (:func:`vidcap.video.hidden.solve_hidden`,
``vidcap pose2d --hidden solve``), so the table says where the misses are after it.

``--per-joint`` (with ``--hidden solve``, not ``--rehang``): per view and joint, the share of
joint-frames missed after the solve (PCK points) and of those the fit had within 5 % where
the solve's joint replaced it ("fit had") or the solve had where the fit's was kept ("solve
had"): what choosing between the two per joint could gain at most (wt-farm, issue 27).

``--rehang`` (with ``--hidden solve``): :func:`~vidcap.video.hidden.solve_hidden` with
``rehang=True`` (forearms hung from the shoulders the solve fits the better, a side view's
legs named by the render's limb order; not the default, wt-sidearms, issue 27).

Usage: ``PYTHONPATH=. python benchmarks/pose2d_attribution.py [--clips "131_01 110,walk 45"]
[--hidden fit|solve] [--rehang] [--per-joint] [--extra]`` (≈ 4 min).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pose2d_accuracy import (  # noqa: E402
    ARMS,
    LEGS,
    body_height_px,
    hidden_by_torso,
    load_motion,
    side_agnostic_errors,
    view_of,
)

from vidcap.body import JOINT_INDEX as JI  # noqa: E402

#: The side and three-quarter tuning renders: (motion, yaws).
TUNING = (("131_01", (90, 110, 70, 100, 45, 135)), ("07_07", (90, 110, 70, 100, 45, 135)),
          ("walk", (100, 45, 140)))
#: ``--extra``: CMU 14_19 side-view stretches (first, last frame at 30 fps, yaw).
EXTRA = ((180, 240, 90), (390, 450, 80), (600, 660, 100), (180, 240, 270))
_EW = {s: [JI[f"{s}_elbow"], JI[f"{s}_wrist"]] for s in "lr"}
GROUPS = {"shoulders": [JI["l_shoulder"], JI["r_shoulder"]],
          "legs": [JI[f"{s}_{p}"] for s in "lr" for p in ("hip", "knee", "ankle")],
          "axis": [JI["pelvis"], JI["neck"], JI["head_top"]]}


def matched(pred: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """``pred`` (F, 15, 2) with each limb pair relabelled per frame to its closer order."""
    _, swapped = side_agnostic_errors(pred, truth)
    out = pred.copy()
    for k, (a, b) in enumerate((ARMS, LEGS)):
        f = swapped[:, k]
        out[np.ix_(f, a + b)] = pred[np.ix_(f, b + a)]
    return out


def pck(pred: np.ndarray, truth: np.ndarray, h: np.ndarray) -> float:
    """PCK@0.05 of all joints, pairs matched per frame; ``h`` (F,) body heights, px."""
    return float(np.nanmean(side_agnostic_errors(pred, truth)[0] / h[:, None] <= 0.05))


def interpolated(pred: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """``pred`` with each arm's elbow and wrist, in frames where ``inside`` (F, 15) holds
    for either, put at the upper and lower arm angles (and lengths) interpolated linearly
    from the nearest frames where neither does."""
    out = pred.copy()
    frames = np.arange(len(pred))
    for s in "lr":
        hid = inside[:, _EW[s]].any(axis=1)
        clear = np.flatnonzero(~hid)
        if not len(clear) or not hid.any():
            continue
        for p, c in ((JI[f"{s}_shoulder"], JI[f"{s}_elbow"]), (JI[f"{s}_elbow"], JI[f"{s}_wrist"])):
            v = pred[:, c] - pred[:, p]
            ang = np.interp(frames, clear, np.unwrap(np.arctan2(v[clear, 1], v[clear, 0])))
            length = np.interp(frames, clear, np.linalg.norm(v[clear], axis=-1))
            step = np.stack([np.cos(ang), np.sin(ang)], -1) * length[:, None]
            out[hid, c] = out[hid, p] + step[hid]
    return out


def attribute(cues: np.ndarray, outline: np.ndarray, truth: dict) -> dict:
    """The attribution of one clip's cue fit (F, 15, 2) against ``truth``
    (:func:`vidcap.synth.render_clip`'s): PCK points per entry (see the module)."""
    tj = truth["joints2d"]
    h = body_height_px(tj)
    j, jo = matched(cues, tj), matched(outline, tj)
    base = pck(j, tj, h)
    err = np.linalg.norm(j - tj, axis=-1) / h[:, None]
    miss = err > 0.05
    inside = hidden_by_torso(tj, h[:, None])
    depth = truth["joints3d"] @ truth["view_dir"]
    far_l = depth[:, JI["l_shoulder"]] > depth[:, JI["r_shoulder"]]
    far = np.zeros_like(miss)
    far[:, _EW["l"]] = far_l[:, None]
    far[:, _EW["r"]] = ~far_l[:, None]
    arm = np.zeros_like(miss)
    arm[:, _EW["l"] + _EW["r"]] = True
    n = miss.size
    row = {"PCK": 100 * base,
           "far in": 100 * np.sum(miss & arm & inside & far) / n,
           "near in": 100 * np.sum(miss & arm & inside & ~far) / n,
           "arm out": 100 * np.sum(miss & arm & ~inside) / n}
    for name, idx in GROUPS.items():
        row[name] = 100 * np.sum(miss[:, idx]) / n

    def gain(x):
        return 100 * (pck(x, tj, h) - base)

    for name, sel in (("far in", arm & inside & far), ("near in", arm & inside & ~far)):
        x = j.copy()
        x[sel] = tj[sel]
        row[f"O {name}"] = gain(x)
    for name, idx in GROUPS.items():
        x = j.copy()
        x[:, idx] = tj[:, idx]
        row[f"O {name}"] = gain(x)
    swapped = j.copy()
    swapped[:, _EW["l"] + _EW["r"]] = j[:, _EW["r"] + _EW["l"]]
    ok = (side_agnostic_errors(swapped, tj)[0] / h[:, None] <= 0.05).sum(1)
    better = ok > (side_agnostic_errors(j, tj)[0] / h[:, None] <= 0.05).sum(1)
    row["O exchange"] = gain(np.where(better[:, None, None], swapped, j))
    for name, sel in (("far", arm & inside & far), ("near", arm & inside & ~far)):
        within_o = np.linalg.norm(jo - tj, axis=-1) / h[:, None] <= 0.05
        row[f"{name} cues"] = (np.sum(~miss & sel), np.sum(sel))
        row[f"{name} outl"] = (np.sum(within_o & sel), np.sum(sel))
    row["interp true"] = gain(interpolated(j, inside))
    row["interp fit"] = gain(matched(interpolated(cues, hidden_by_torso(cues, h[:, None])), tj))
    return row


def per_joint(fit: np.ndarray, filled: np.ndarray, solved: np.ndarray,
              tj: np.ndarray) -> np.ndarray:
    """(3, 15) counts of joint-frames: missed by ``filled`` (the fit with the solve's
    joints, :func:`vidcap.video.hidden.fill_hidden`), of those the ``fit`` had within 5 %
    where ``filled`` took the solve's joint, and the ``solved`` joint
    (:func:`vidcap.video.hidden.solve_in_image`) had where ``filled`` kept the fit's;
    pairs matched per frame as ``filled``'s."""
    h = body_height_px(tj)[:, None]
    _, swapped = side_agnostic_errors(filled, tj)
    err = []
    for x in (fit, filled, solved):
        y = x.copy()
        for k, (a, b) in enumerate((ARMS, LEGS)):
            f = swapped[:, k]
            y[np.ix_(f, a + b)] = x[np.ix_(f, b + a)]
        err.append(np.linalg.norm(y - tj, axis=-1) / h)
    ef, ei, es = err
    miss, taken = ei > 0.05, np.linalg.norm(filled - fit, axis=-1) > 1e-9
    return np.stack([miss.sum(0), (miss & taken & (ef <= 0.05)).sum(0),
                     (miss & ~taken & (es <= 0.05)).sum(0)])


def _print_per_joint(counts: dict) -> None:
    """The ``--per-joint`` table: per view, :func:`per_joint`'s counts as PCK points."""
    from vidcap.body import JOINT_NAMES

    print("\nPer joint after the solve, PCK points: missed; of those, the fit had it where the "
          "solve's replaced it / the solve had it where the fit's was kept")
    for view in ("side", "three-quarter", "front"):
        sel = [c for (_, yaw), c in counts.items() if view_of(yaw) == view]
        if not sel:
            continue
        n = 15 * sum(c[1] for c in sel)
        tot = np.sum([c[0] for c in sel], axis=0) * 100.0 / n
        print(f"  {view} ({len(sel)}): " + ", ".join(
            f"{name} {m:.2f} ({f:.2f} / {v:.2f})" for name, (m, f, v)
            in zip(JOINT_NAMES, tot.T, strict=True) if m > 0))
        m, f, v = tot.sum(axis=1)
        print(f"  {'':{len(view)}}  sum {m:.2f} ({f:.2f} / {v:.2f})")


COLUMNS = ("PCK", "far in", "near in", "arm out", "shoulders", "legs", "axis", "O far in",
           "O near in", "O exchange", "O shoulders", "O legs", "O axis", "interp true",
           "interp fit")


def _clips(extra: bool):
    """(name, motion, yaw) of every tuning render (:data:`TUNING`, with ``extra``
    :data:`EXTRA` too)."""
    for name, yaws in TUNING:
        motion = load_motion(name, 60)
        motion = motion.frames(0, min(60, len(motion.root_positions)))
        for yaw in yaws:
            yield name, motion, yaw
    if extra:
        from vidcap.synth import make_motion

        path = Path(os.environ.get("VIDCAP_DATA", "/nonexistent")) / "mocap" / "cmu"
        full = make_motion(path / "14_19_humanik.bvh", fps=30.0)
        for first, last, yaw in EXTRA:
            yield f"14_19 {first}-{last}", full.frames(first, last), yaw


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--clips", default=None,
                    help='only these clips, e.g. "131_01 110,walk 45" (default: all)')
    ap.add_argument("--hidden", choices=("fit", "solve"), default="fit",
                    help="solve: the cue fit's hidden joints from the 3D clip solve first")
    ap.add_argument("--rehang", action="store_true",
                    help="--hidden solve: solve_hidden(rehang=True) (forearms re-hung, legs "
                         "named by the limb order; not the default)")
    ap.add_argument("--per-joint", action="store_true",
                    help="--hidden solve: per joint, the misses and what the fit or the "
                         "solve had of them")
    ap.add_argument("--extra", action="store_true",
                    help="also the CMU 14_19 side tuning renders ($VIDCAP_DATA)")
    args = ap.parse_args(argv)
    from vidcap.synth import render_clip
    from vidcap.video.fit.pose2d import fit_sequence
    from vidcap.video.hidden import fill_hidden, solve_hidden, solve_in_image
    from vidcap.video.lifting import lift_pose

    if args.per_joint and (args.hidden != "solve" or args.rehang):
        ap.error("--per-joint needs --hidden solve without --rehang")
    counts = {}
    keep = None if args.clips is None else set(args.clips.split(","))
    rows = {}
    print("Tuning renders (60 frames, 640x480, 30 fps), tracked, true silhouettes: PCK@0.05, "
          "cues / outline only")
    for name, motion, yaw in _clips(args.extra):
        if keep is not None and f"{name} {yaw}" not in keep:
            continue
        video, truth = render_clip(motion, yaw_deg=yaw, size=(640, 480), noise=0.0,
                                   rng=np.random.default_rng(0))
        pose = fit_sequence(truth["masks"], frames=video, cues="all")
        cues = pose.joints2d
        if args.per_joint:  # solve_hidden's own solve, kept to compare joint by joint
            j3 = lift_pose(cues, fps=30.0, image_sides=True, spread=pose.spread,
                           model_height=pose.model_height, frame_size=(640, 480)).joints3d
            filled = fill_hidden(cues, j3)
            counts[(name, yaw)] = (per_joint(cues, filled, solve_in_image(cues, j3),
                                             truth["joints2d"]), len(cues))
            cues = filled
        elif args.hidden == "solve":
            cues = solve_hidden(cues, fps=30.0, spread=pose.spread,
                                model_height=pose.model_height, frame_size=(640, 480),
                                frames=video, rehang=args.rehang)
        outline = fit_sequence(truth["masks"], frames=video, cues="outline").joints2d
        h = body_height_px(truth["joints2d"])
        rows[(name, yaw)] = attribute(cues, outline, truth)
        print(f"{name:13} {yaw:>4} {view_of(yaw):13} {pck(cues, truth['joints2d'], h):7.1%}"
              f" {pck(outline, truth['joints2d'], h):7.1%}", flush=True)
    print("\nAttribution of the cue fit's misses, PCK points (class: share of joint-frames "
          "missed; O: oracle gain with that class set to the truth; exchange: elbows and "
          "wrists exchanged between the shoulders where better; interp: arms inside the "
          "outline interpolated over time, by the truth's or the fit's inside frames)")
    print(f"{'view':13} {'clips':>5} " + " ".join(f"{c:>11}" for c in COLUMNS))
    for view in ("side", "three-quarter", "all"):
        sel = [r for (_, yaw), r in rows.items() if view in ("all", view_of(yaw))]
        if not sel:
            continue
        print(f"{view:13} {len(sel):5d} "
              + " ".join(f"{np.mean([r[c] for r in sel]):11.2f}" for c in COLUMNS))
    print("\nElbows and wrists inside the torso's outline within 5 % of the height, "
          "cues / outline only:")
    for view in ("side", "three-quarter"):
        sel = [r for (_, yaw), r in rows.items() if view_of(yaw) == view]
        if sel:
            cells = []
            for arm in ("far", "near"):
                c, o = (np.sum([r[f"{arm} {k}"] for r in sel], axis=0)
                        for k in ("cues", "outl"))
                cells.append(f"{arm} {c[0] / max(c[1], 1):.1%} / {o[0] / max(o[1], 1):.1%}"
                             f" (of {c[1]})")
            print(f"  {view:13} " + ";  ".join(cells))
    if counts:
        _print_per_joint(counts)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
