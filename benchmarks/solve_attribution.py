"""Where the 3D stage's error on fitted 2D comes from: oracle substitutions, one at a time
(``python benchmarks/solve_fitted.py --attribute``).

Each oracle replaces one thing the 3D stage reads by the truth and leaves the rest as the
stage has it (front/back cue on, as by default):

* ``2D``: the true 2D joints with the fit's names (per frame and limb pair, the truth's
  labeling nearest the fitted joints; the scale read from them, no model height);
* ``names``: the fitted joints, each limb pair per frame named as the truth names the
  limb nearest it (after the stage's own naming: :func:`vidcap.video.lifting.apply_user_view`);
* ``signs``: the truth's depth signs, under the 2D's names, hard (as user events);
* ``front/back``: the proposed yaw reflected front for back where the truth faces the
  other way (frames more than 15 degrees from a side view), and the image-side names
  read in that front/back;
* ``yaw``: the truth's yaw as a user's orientation (tight prior), names read from it.

The table gives PA-MPJPE (mm) with each oracle alone, with all of them, and with all but
one (what is left when only that one is the stage's own).

``--joints`` (:func:`joint_rows`) splits the 2D and the signs by limb instead: the true
2D of the arms' (elbows, wrists) or the legs' (knees, ankles) joints alone, the true
depth signs of the arms' or the legs' segments alone, and the ceiling of any per-joint
confidence the 3D stage could be given: every 2D joint more than
:data:`DROP_THRESHOLDS` of the height off the truth weighted :data:`DROP_WEIGHT`
(a perfect detector of the fit's bad joints), the solve's prior and smoothness placing it.
"""

from __future__ import annotations

from contextlib import contextmanager

import lift_solve_tables as st
import numpy as np

from vidcap.body import JOINT_NAMES, LIMB_PAIR_JOINTS, SEGMENT_JOINTS
from vidcap.video.annotations import PAIRS

ORACLES = ("2D", "names", "signs", "front/back", "yaw")
#: :func:`joint_rows`: the 2D joints each limb oracle takes from the truth, and the
#: segments (:data:`vidcap.body.SEGMENT_NAMES`) whose true depth signs it sets.
JOINT_GROUPS = {"arms": ("l_elbow", "l_wrist", "r_elbow", "r_wrist"),
                "legs": ("l_knee", "l_ankle", "r_knee", "r_ankle")}
SEGMENT_GROUPS = {"arms": ("l_upper_arm", "l_lower_arm", "r_upper_arm", "r_lower_arm"),
                  "legs": ("l_upper_leg", "l_lower_leg", "r_upper_leg", "r_lower_leg")}
#: :func:`joint_rows`' confidence ceiling: 2D joints this far off the truth (fraction of
#: the fit's model height) weigh :data:`DROP_WEIGHT` (of 1) in the solve.
DROP_THRESHOLDS = (0.05, 0.08)
DROP_WEIGHT = 1e-3
#: Frames within this of a side view (degrees) keep the stage's front/back (the truth's
#: is then no better defined than the stage's).
SIDE_MARGIN_DEG = 15.0


def nearest_labeling(joints2d, reference2d) -> np.ndarray:
    """(F, 2) bool: per frame, whether each limb pair of ``joints2d`` (F, 15, 2) is nearer
    ``reference2d`` (F, 15, 2) with its left and right exchanged (summed distance of the
    pair's six joints)."""
    j, r = np.asarray(joints2d, float), np.asarray(reference2d, float)
    out = np.zeros((len(j), len(PAIRS)), bool)
    for col, pair in enumerate(PAIRS):
        left, right = LIMB_PAIR_JOINTS[pair]
        as_is = np.linalg.norm(j[:, left + right] - r[:, left + right], axis=-1).sum(1)
        swapped = np.linalg.norm(j[:, right + left] - r[:, left + right], axis=-1).sum(1)
        out[:, col] = swapped < as_is
    return out


def true_signs(true3) -> np.ndarray:
    """(F, 10) int8 depth signs of joints (F, 15, 3) (Z toward the camera): +1 where a
    segment's distal joint is nearer the camera."""
    dz = true3[:, SEGMENT_JOINTS[:, 1], 2] - true3[:, SEGMENT_JOINTS[:, 0], 2]
    return np.where(dz < 0, -1, 1).astype(np.int8)


def true_2d_fit_names(fitted2d, true2) -> np.ndarray:
    """The true 2D joints (body-side named) named as the fit named the limbs it drew
    nearest them (image-side names)."""
    from vidcap.video.lifting import swap_pairs

    return swap_pairs(true2, nearest_labeling(true2, fitted2d))


@contextmanager
def oracles(clip, used):
    """Patch :mod:`vidcap.video.lifting` so that ``lift_pose`` reads the truth of
    ``clip`` (dict with ``true2``, ``true3``) for each oracle in ``used`` but ``2D``
    (which the caller substitutes in the input)."""
    import solve_fitted as sf

    import vidcap.video.lifting as lifting
    from vidcap.video.lift import assign_sides
    from vidcap.video.solve.labels import exchange_distal

    true2, true3 = clip["true2"], clip["true3"]
    t_yaw = sf.true_yaw(true3)
    off_side = np.abs(np.cos(t_yaw)) > np.sin(np.deg2rad(SIDE_MARGIN_DEG))
    orig_view, orig_solve = lifting.apply_user_view, lifting.solve_lift

    def view(joints2d, proposed, spread, user_orient, user_joints, **kw):
        orient, yaw, j2 = orig_view(joints2d, proposed, spread, user_orient, user_joints, **kw)
        if "yaw" in used or "front/back" in used:
            if "yaw" in used:
                yaw = t_yaw.copy()
            else:
                wrong = off_side & (np.sign(np.cos(yaw)) != np.sign(np.cos(t_yaw)))
                yaw = np.arctan2(np.sin(yaw), np.where(wrong, -1.0, 1.0) * np.cos(yaw))
            # image-side names read in the true front/back where it is defined, the
            # stage's own (the side rule) within SIDE_MARGIN_DEG of a side view
            fit = joints2d
            if kw.get("names_swapped") is not None:  # the stage's repaired names
                fit = exchange_distal(fit, kw["names_swapped"])
            read = assign_sides(fit, yaw, swap=np.cos(t_yaw) > 0)
            if kw.get("user_sides") is not None:
                read = lifting.swap_pairs(read, kw["user_sides"])
            j2 = np.where(off_side[:, None, None], read, j2)
            j2 = np.where(np.isfinite(user_joints), user_joints, j2)
        if "names" in used:
            j2 = lifting.swap_pairs(j2, nearest_labeling(j2, true2))
        return orient, yaw, j2

    def solve(j2, **kw):
        if "signs" in used:
            named = lifting.swap_pairs(true3, nearest_labeling(true2, j2))
            s = true_signs(named)
            kw["user_signs"] = s
            kw["proposal"] = kw["proposal"].__class__(signs=s, margin=kw["proposal"].margin,
                                                      zeta=kw["proposal"].zeta)
        if "yaw" in used:
            kw["user_orientation"] = np.full(len(j2), "oracle")
        return orig_solve(j2, **kw)

    lifting.apply_user_view, lifting.solve_lift = view, solve
    try:
        yield
    finally:
        lifting.apply_user_view, lifting.solve_lift = orig_view, orig_solve


def _run(name, c, body, used, near_fn):
    from vidcap.video.lifting import lift_pose

    j2, mh = c["joints2d"], c["model_height"]
    if "2D" in used:
        j2, mh = true_2d_fit_names(c["joints2d"], c["true2"]), None
    with oracles(c, used):
        lr = lift_pose(j2, fps=float(c["fps"]), body=body, image_sides=True,
                       spread=c["spread"], track=c.get("track"),
                       frame_size=tuple(int(v) for v in c["size"]), model_height=mh,
                       **near_fn(name, j2))
    return st.pa_mpjpe_mm(lr.joints3d, c["true3"])


def settings():
    """(column label, set of oracles) of the attribution table."""
    cols = [("stage", frozenset())]
    cols += [(f"+{o}", frozenset({o})) for o in ORACLES]
    everything = frozenset(ORACLES) - {"front/back"}  # the true yaw includes it
    cols += [("all", everything)]
    cols += [(f"all but {o}", everything - {o}) for o in ORACLES if o != "front/back"]
    return cols


def attribution_rows(clips, body, near_fn):
    """Rows (clip, [PA-MPJPE mm per :func:`settings` column])."""
    return [(name, [_run(name, c, body, used, near_fn) for _, used in settings()])
            for name, c in clips]


def with_true_joints(fitted2d, true2, joints) -> np.ndarray:
    """The fitted 2D joints (F, 15, 2) with ``joints`` (names) taken from the truth
    ``true2`` named as the fit names its limbs (:func:`true_2d_fit_names`)."""
    from vidcap.body import JOINT_INDEX

    out = np.array(fitted2d, dtype=float)
    idx = [JOINT_INDEX[n] for n in joints]
    out[:, idx] = true_2d_fit_names(fitted2d, true2)[:, idx]
    return out


def bad_joint_weights(joints2d, true2, height_px, threshold: float,
                      weight: float = DROP_WEIGHT) -> np.ndarray:
    """(F, 15) ``weight`` where a 2D joint of ``joints2d`` (F, 15, 2), in whatever names,
    lies more than ``threshold`` x ``height_px`` (F,) from the truth's joint of the same
    limb (each limb pair matched per frame, :func:`nearest_labeling`), else 1."""
    from vidcap.video.lifting import swap_pairs

    j = np.asarray(joints2d, dtype=float)
    t = swap_pairs(true2, nearest_labeling(true2, j))
    e = np.linalg.norm(j - t, axis=-1) / np.asarray(height_px, float)[:, None]
    return np.where(e > threshold, weight, 1.0)


@contextmanager
def solve_inputs(clip, *, drop=None, sign_segments=()):
    """Patch the 3D stage's solve (:func:`vidcap.video.solve.stage.solve_clip`) so that
    it weighs the 2D joints by :func:`bad_joint_weights` at threshold ``drop`` (None:
    as the stage does) and takes the truth's depth signs of ``sign_segments`` (names)
    as hard signs, both read under the names the stage hands the solve."""
    import vidcap.video.solve.stage as stage
    from vidcap.body import SEGMENT_INDEX
    from vidcap.video.lifting import swap_pairs

    orig = stage.solve_clip
    segs = [SEGMENT_INDEX[n] for n in sign_segments]

    def solve(joints2d, **kw):
        j = np.asarray(joints2d, dtype=float)
        if drop is not None:
            w = bad_joint_weights(j, clip["true2"], clip["model_height"], drop)
            user = kw.get("confidence")
            kw["confidence"] = w if user is None else np.where(user > 1.0, user, w)
        if segs:
            named = swap_pairs(clip["true3"], nearest_labeling(clip["true2"], j))
            hard = np.zeros((len(j), 10), np.int8) if kw.get("hard_signs") is None \
                else np.array(kw["hard_signs"])
            hard[:, segs] = true_signs(named)[:, segs]
            kw["hard_signs"] = hard
        return orig(joints2d, **kw)

    stage.solve_clip = solve
    try:
        yield
    finally:
        stage.solve_clip = orig


def joint_settings():
    """(column label, keywords of :func:`_run_joints`) of the ``--joints`` table."""
    cols = [("stage", {})]
    cols += [(f"+{g} 2D", {"joints": JOINT_GROUPS[g]}) for g in JOINT_GROUPS]
    cols += [(f"+{g} signs", {"sign_segments": SEGMENT_GROUPS[g]}) for g in SEGMENT_GROUPS]
    cols += [(f"2D > {t:.0%} dropped", {"drop": t}) for t in DROP_THRESHOLDS]
    return cols


def _run_joints(name, c, body, near_fn, joints=(), drop=None, sign_segments=()):
    from vidcap.video.lifting import lift_pose

    j2 = with_true_joints(c["joints2d"], c["true2"], joints) if joints else c["joints2d"]
    with solve_inputs(c, drop=drop, sign_segments=sign_segments):
        lr = lift_pose(j2, fps=float(c["fps"]), body=body, image_sides=True,
                       spread=c["spread"], track=c.get("track"),
                       frame_size=tuple(int(v) for v in c["size"]),
                       model_height=c["model_height"], **near_fn(name, j2))
    return st.pa_mpjpe_mm(lr.joints3d, c["true3"])


def joint_rows(clips, body, near_fn):
    """Rows (clip, [PA-MPJPE mm per :func:`joint_settings` column])."""
    return [(name, [_run_joints(name, c, body, near_fn, **kw) for _, kw in joint_settings()])
            for name, c in clips]


def print_attribution(rows, settings_fn=None):
    cols = [label for label, _ in (settings_fn or settings)()]
    print("clip | " + " | ".join(cols))
    print("---" + " | ---" * len(cols))
    for name, vals in rows:
        print(f"{name} | " + " | ".join(f"{v:.0f}" for v in vals))
    for tag in ("tuning", "sample", "held out"):
        sel = [v for n, v in rows if tag in n]
        if sel:
            m = np.mean(sel, axis=0)
            print(f"mean, {tag} | " + " | ".join(f"{v:.1f}" for v in m))


def joint_errors(clip, body, near) -> list[tuple[str, float, float]]:
    """Per joint (name, 2D error as the stage names it, with the truth's names), % of the
    height, of the stage's body-side named joints; ``near``: the colour cues' keywords
    of ``lift_pose`` (``near_side``, ``limb_order``)."""
    from vidcap.video.lifting import lift_pose, swap_pairs

    lr = lift_pose(clip["joints2d"], fps=float(clip["fps"]), body=body, image_sides=True,
                   spread=clip["spread"], track=clip.get("track"),
                   frame_size=tuple(int(v) for v in clip["size"]),
                   model_height=clip["model_height"], **near)
    h = np.mean(lr.scale) * body.height
    e = np.linalg.norm(lr.joints2d - clip["true2"], axis=-1) / h * 100
    renamed = swap_pairs(lr.joints2d, nearest_labeling(lr.joints2d, clip["true2"]))
    e2 = np.linalg.norm(renamed - clip["true2"], axis=-1) / h * 100
    return [(n, float(e[:, j].mean()), float(e2[:, j].mean())) for j, n in enumerate(JOINT_NAMES)]
