"""Where the 3D stage's error on fitted 2D lives, frame by frame
(``python benchmarks/solve_fitted.py --split``; issue 33).

Each frame of a clip is put in a band by its worst limb joint's 2D error (the 2D the
3D stage solved with, body-side named, against the truth, :func:`named_errors`, a
fraction of the height): every limb joint within 5 %, the worst 5-10 %, or 10 % and
more (a grossly wrong joint: an arm drawn inside the outline, legs named the wrong way
round). Per band: the frames, the stage's PA-MPJPE there and the same with the best
reflection of each frame (:func:`best_reflection_errors`: the body's mirror through
the image plane and each limb's upper and lower segment reflected in depth, chosen per
frame against the truth), i.e. what the depth signs cost there.

Then three columns on the grossly wrong joints (more than :data:`GROSS` off):

* the solve's own 2D misfit there against the same at the good joints (under 5 %):
  whether the solve could tell them (the fitted 2D is drawn from a skeleton, so it
  need not disagree with one);
* PA-MPJPE with only the fitted joints more than :data:`REPLACED` off the truth (named
  as the fit names its limbs, :func:`fitted_errors`: positions, not names) replaced by
  it (the cost of the few bad ones, to compare with all of the true 2D);
* the same joints dropped instead (weight :data:`solve_attribution.DROP_WEIGHT`: a
  perfect detector of them, the solve's prior and smoothness placing them).
"""

from __future__ import annotations

import itertools

import lift_solve_tables as st
import numpy as np

from vidcap.body import JOINT_INDEX

#: Upper bounds of the frame bands (fraction of the height; the last is open).
BANDS = (0.05, 0.10)
#: 2D error (fraction of the height) from which a joint counts as grossly wrong.
GROSS = 0.10
#: 2D error from which the replacement and drop columns take a joint from the truth.
REPLACED = 0.05
#: (proximal, middle, distal) joints of each limb, in the order of the reflection codes.
LIMBS = (("l_shoulder", "l_elbow", "l_wrist"), ("r_shoulder", "r_elbow", "r_wrist"),
         ("l_hip", "l_knee", "l_ankle"), ("r_hip", "r_knee", "r_ankle"))


def fitted_errors(fitted2d, true2, height_px) -> np.ndarray:
    """(F, 15) distance of each fitted 2D joint (F, 15, 2) to the truth's joint named as
    the fit names that limb (:func:`solve_attribution.true_2d_fit_names`), as a fraction
    of ``height_px`` (one or (F,))."""
    import solve_attribution as sa

    t = sa.true_2d_fit_names(fitted2d, true2)
    h = np.broadcast_to(np.asarray(height_px, float).reshape(-1), (len(t),))
    return np.linalg.norm(np.asarray(fitted2d, float) - t, axis=-1) / h[:, None]


def named_errors(lr, true2, body) -> np.ndarray:
    """(F, 12) distance of the 2D limb joints the 3D stage solved with (body-side named,
    ``LiftResult.joints2d``) to the truth's of the same name, as a fraction of the
    height: a leg named the wrong way round counts as wrong as a misplaced one."""
    s = np.mean(lr.scale) * body.height
    return (np.linalg.norm(lr.joints2d - true2, axis=-1) / s)[:, st.LIMB_JOINTS]


def limb_reflections(joints3d) -> np.ndarray:
    """(512, F, 15, 3): ``joints3d`` (F, 15, 3; Z toward the camera) as is and mirrored
    through the image plane with its sides renamed (the body an orthographic image
    cannot tell from it), each times the 256 codes of :data:`LIMBS` (per limb 0-3: bit
    1 reflects the upper segment in depth about its proximal joint, carrying the rest of
    the limb; bit 2 the lower one about the middle joint)."""
    from vidcap.video.lift import swap_sides

    p = np.asarray(joints3d, dtype=float)
    root = p[:, :1]
    bases = (p, swap_sides((p - root) * np.array([1.0, 1.0, -1.0])) + root)
    out = []
    for base in bases:
        for code in itertools.product(range(4), repeat=len(LIMBS)):
            q = base.copy()
            for (a, b, c), k in zip(LIMBS, code, strict=True):
                a, b, c = JOINT_INDEX[a], JOINT_INDEX[b], JOINT_INDEX[c]
                if k & 1:
                    dz = 2.0 * (q[:, b, 2] - q[:, a, 2])
                    q[:, [b, c], 2] -= dz[:, None]
                if k & 2:
                    q[:, c, 2] -= 2.0 * (q[:, c, 2] - q[:, b, 2])
            out.append(q)
    return np.stack(out)


def best_reflection_errors(joints3d, true3) -> np.ndarray:
    """(F, 12) PA joint errors (m) of the reflection of :func:`limb_reflections` nearest
    the truth in each frame (by its mean)."""
    e = st.pa_joint_errors(limb_reflections(joints3d), np.asarray(true3, float))
    return e[e.mean(axis=-1).argmin(axis=0), np.arange(e.shape[1])]


def band_of(worst) -> np.ndarray:
    """(F,) band index 0..len(BANDS) of each frame's worst limb joint error."""
    return np.searchsorted(np.asarray(BANDS), np.asarray(worst, float), side="right")


def _lift(c, body, near_fn, name, joints2d, drop=None):
    import solve_attribution as sa

    from vidcap.video.lifting import lift_pose

    with sa.solve_inputs(c, drop=drop):
        return lift_pose(joints2d, fps=float(c["fps"]), body=body, image_sides=True,
                         spread=c["spread"], track=c.get("track"),
                         frame_size=tuple(int(v) for v in c["size"]),
                         model_height=c["model_height"], **near_fn(name, joints2d))


def solve_misfit(lr, body) -> np.ndarray:
    """(F, 15) the solve's pelvis-relative 2D misfit to the 2D it was handed, as a
    fraction of the height (scaled orthographic, as the solve projects)."""
    s = np.broadcast_to(np.asarray(lr.scale, float).reshape(-1), (len(lr.joints3d),))
    proj = lr.joints3d[..., :2] * np.array([1.0, -1.0]) * s[:, None, None]
    proj = proj - proj[:, :1]
    seen = lr.joints2d - lr.joints2d[:, :1]
    return np.linalg.norm(proj - seen, axis=-1) / (s[:, None] * body.height)


def split_row(name, c, body, near_fn) -> dict:
    """The figures of one clip (see the module docstring)."""
    import solve_attribution as sa

    lr = _lift(c, body, near_fn, name, c["joints2d"])
    e_named = named_errors(lr, c["true2"], body)
    band = band_of(e_named.max(axis=1))
    per = st.pa_joint_errors(lr.joints3d, c["true3"]).mean(axis=1) * 1e3
    best = best_reflection_errors(lr.joints3d, c["true3"]).mean(axis=1) * 1e3
    mis = solve_misfit(lr, body)[:, st.LIMB_JOINTS]
    err = fitted_errors(c["joints2d"], c["true2"], c["model_height"])
    replaced = np.where((err > REPLACED)[..., None],
                        sa.true_2d_fit_names(c["joints2d"], c["true2"]), c["joints2d"])
    return dict(
        name=name, pa=per.mean(), band=band, per=per, best=best,
        misfit_gross=mis[e_named > GROSS].mean() if (e_named > GROSS).any() else np.nan,
        misfit_good=mis[e_named < BANDS[0]].mean(),
        replaced=st.pa_mpjpe_mm(_lift(c, body, near_fn, name, replaced).joints3d,
                                c["true3"]),
        dropped=st.pa_mpjpe_mm(_lift(c, body, near_fn, name, c["joints2d"],
                                     drop=REPLACED).joints3d, c["true3"]))


def print_split(rows) -> None:
    """The table of :func:`split_row` rows, and the pooled bands per tag."""
    middle = [f"{a:.0%}-{b:.0%}" for a, b in zip(BANDS[:-1], BANDS[1:], strict=True)]
    heads = [f"< {BANDS[0]:.0%}", *middle, f">= {BANDS[-1]:.0%}"]
    print("clip | PA-MPJPE mm | " + " | ".join(f"frames {h}: n, PA, best reflection"
                                               for h in heads)
          + f" | share of the error in >= {BANDS[-1]:.0%} | solve's 2D misfit at joints "
          f"> {GROSS:.0%} / < {BANDS[0]:.0%} off, % | > {REPLACED:.0%} replaced by the "
          f"truth | > {REPLACED:.0%} dropped")
    print("---" + " | ---" * (len(heads) + 5))
    for r in rows:
        cells = [_band_cell(r["per"], r["best"], r["band"] == k) for k in range(len(heads))]
        share = r["per"][r["band"] == len(BANDS)].sum() / r["per"].sum()
        print(f"{r['name']} | {r['pa']:.0f} | " + " | ".join(cells)
              + f" | {share:.0%} | {r['misfit_gross'] * 100:.1f} / "
              f"{r['misfit_good'] * 100:.1f} | {r['replaced']:.0f} | {r['dropped']:.0f}")
    for tag in ("tuning", "sample", "held out"):
        sel = [r for r in rows if tag in r["name"]]
        if not sel:
            continue
        per = np.concatenate([r["per"] for r in sel])
        best = np.concatenate([r["best"] for r in sel])
        band = np.concatenate([r["band"] for r in sel])
        cells = [_band_cell(per, best, band == k) for k in range(len(heads))]
        print(f"all frames, {tag} | {per.mean():.1f} | " + " | ".join(cells)
              + f" | {per[band == len(BANDS)].sum() / per.sum():.0%} | | "
              f"{np.mean([r['replaced'] for r in sel]):.1f} (clip mean; stage "
              f"{np.mean([r['pa'] for r in sel]):.1f}) | "
              f"{np.mean([r['dropped'] for r in sel]):.1f}")


def _band_cell(per, best, sel) -> str:
    if not sel.any():
        return "0"
    return f"{sel.sum()}, {per[sel].mean():.0f}, {best[sel].mean():.0f}"
