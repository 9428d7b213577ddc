"""Joints the image cannot show, placed from the 3D clip solve (issue 27).

An arm behind the torso (the far arm of a side view) or in front of it covers the same
silhouette pixels at any angle, and the frame shows nothing of the far one, so the 2D
fit leaves it where its search ended (hanging, under-bent). The clip solve
(:mod:`vidcap.video.solve`) places the same arm with what the rest of the body says:
rigid bones, joint limits, the pose prior learned from motion capture (how people hold
an arm, in the torso's frame, whichever way they face) and smoothness over the clip.
:func:`fill_hidden` reprojects the solve's 3D joints into the image (scaled
orthographic, each frame aligned on the pelvis, neck and head top the 2D fit found)
and puts them in place of the 2D fit's shoulders and hips, of every wrist the fit drew
inside the torso's outline and of every elbow drawn there or hanging such a wrist
(:func:`hidden_joints`); everything else, a wrist out in the open included, stays as
fitted.

Measured (HISTORY.md, "Joints the image cannot show"): on the 15 side and three-quarter
tuning renders PCK@0.05 93.77 -> 95.04 %, where which joints to replace was chosen (the
arms inside and the shoulders; every arm joint or the upper body as good, every joint or
the legs too worse); on the 40 held-out renders (``benchmarks/pose2d_accuracy.py
--held-out --hidden solve``) 86.37 -> 87.23 % with the cues, 85.04 -> 85.77 % with the
outline; on real clips against MediaPipe equal or nearer with the default body. The hips
from the solve as well (wt-farm, session 32, chosen on the tuning renders: 93.52 -> 93.60 %
on pose2d_attribution's 19 with ``--extra``, 64.87 -> 65.16 on the 17 low poses): held out
89.06 -> 89.22 % with the cues, 87.84 -> 87.93 with the outline (same fits, one run).
"""

from __future__ import annotations

import numpy as np

from vidcap.body import JOINT_INDEX, SEGMENT_INDEX, SEGMENTS

#: ``hidden=`` choices: the 2D fit's own joints, or the solve's where the image shows none.
HIDDEN_CHOICES = ("fit", "solve")
#: The library's default (:func:`vidcap.video.pipeline.run`, the annotate session) and
#: ``vidcap pose2d --hidden``'s: there the solve would cost about as much as the fit.
DEFAULT_HIDDEN = "fit"
#: ``vidcap convert --hidden``'s default: its 3D stage runs the solve anyway, and on real
#: clips the default body's 12 limb joints came nearer MediaPipe's or stayed (HISTORY.md).
CONVERT_HIDDEN = "solve"

#: The joints each frame's reprojection is aligned on (the axis the silhouette pins down).
AXIS = (JOINT_INDEX["pelvis"], JOINT_INDEX["neck"], JOINT_INDEX["head_top"])
_ARMS = {s: (JOINT_INDEX[f"{s}_shoulder"], JOINT_INDEX[f"{s}_elbow"], JOINT_INDEX[f"{s}_wrist"])
         for s in "lr"}
_LEGS = {s: (JOINT_INDEX[f"{s}_hip"], JOINT_INDEX[f"{s}_knee"], JOINT_INDEX[f"{s}_ankle"])
         for s in "lr"}
#: Pelvis to head top as a share of the body height (Table 3.1: torso + head).
_AXIS_SHARE = (SEGMENTS[SEGMENT_INDEX["torso"]].length_ratio
               + SEGMENTS[SEGMENT_INDEX["head"]].length_ratio)


def check_hidden(hidden: str) -> None:
    """Raise :class:`vidcap.errors.UsageError` (a one-line ``vidcap: error``) unless
    ``hidden`` is one of :data:`HIDDEN_CHOICES`."""
    if hidden not in HIDDEN_CHOICES:
        from vidcap.errors import UsageError

        raise UsageError(f"unknown --hidden {hidden!r}; use one of {', '.join(HIDDEN_CHOICES)}")


def reproject(joints3d, joints2d) -> np.ndarray:
    """The 3D joints drawn in the 2D fit's image, (F, 15, 2) pixels.

    Scaled orthographic: world X right and Y up become image x and -y; each frame's
    scale and offset are the least-squares fit of the :data:`AXIS` joints onto the 2D
    ones (no rotation: both are upright in the camera's frame).

    Parameters
    ----------
    joints3d : numpy.ndarray, shape (F, 15, 3)
        Metres, camera-aligned world (:attr:`vidcap.video.lifting.LiftResult.joints3d`).
    joints2d : numpy.ndarray, shape (F, 15, 2)
        The 2D fit's joints, pixels (NaN frames give NaN).
    """
    j3 = np.asarray(joints3d, dtype=float)
    j2 = np.asarray(joints2d, dtype=float)
    p = np.stack([j3[..., 0], -j3[..., 1]], axis=-1)
    a = p[:, AXIS] - p[:, AXIS].mean(axis=1, keepdims=True)
    b = j2[:, AXIS] - j2[:, AXIS].mean(axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = (a * b).sum(axis=(1, 2)) / (a * a).sum(axis=(1, 2))
    return s[:, None, None] * (p - p[:, AXIS].mean(axis=1, keepdims=True)) + \
        j2[:, AXIS].mean(axis=1, keepdims=True)


def hidden_joints(joints2d) -> np.ndarray:
    """(F, 2, 2) bool: the image-left (``[:, 0]``) and right arm's elbow (``[..., 0]``)
    and wrist (``[..., 1]``) that lie inside the torso's outline (within the torso
    cylinder's radius of the pelvis-neck segment; the body height read off pelvis to
    head top, Table 3.1)."""
    j = np.asarray(joints2d, dtype=float)
    pel, neck = j[:, JOINT_INDEX["pelvis"]], j[:, JOINT_INDEX["neck"]]
    height = np.linalg.norm(j[:, JOINT_INDEX["head_top"]] - pel, axis=-1) / _AXIS_SHARE
    radius = 0.5 * SEGMENTS[SEGMENT_INDEX["torso"]].width_ratio * height
    ab = neck - pel
    ab2 = np.maximum((ab * ab).sum(-1), 1e-9)
    out = np.zeros((len(j), 2, 2), dtype=bool)
    for col, s in enumerate("lr"):
        for row, k in enumerate(_ARMS[s][1:]):
            q = j[:, k] - pel
            t = np.clip((q * ab).sum(-1) / ab2, 0.0, 1.0)
            with np.errstate(invalid="ignore"):
                out[:, col, row] = np.linalg.norm(q - t[:, None] * ab, axis=-1) < radius
    return out


def hidden_arms(joints2d) -> np.ndarray:
    """(F, 2) bool: the image-left (column 0) and right arm whose elbow or wrist lies
    inside the torso's outline (:func:`hidden_joints`)."""
    return hidden_joints(joints2d).any(axis=2)


def _matched(rep: np.ndarray, j2: np.ndarray) -> np.ndarray:
    """``rep`` with its arms, and apart from them its legs, exchanged in the frames where
    the other order lies nearer the 2D fit's (the solve names limbs by the body's sides,
    the fit by the image's)."""
    out = rep.copy()
    for left, right in ((list(_ARMS["l"]), list(_ARMS["r"])),
                        (list(_LEGS["l"]), list(_LEGS["r"]))):
        same = (np.linalg.norm(rep[:, left] - j2[:, left], axis=-1).sum(1)
                + np.linalg.norm(rep[:, right] - j2[:, right], axis=-1).sum(1))
        swap = (np.linalg.norm(rep[:, left] - j2[:, right], axis=-1).sum(1)
                + np.linalg.norm(rep[:, right] - j2[:, left], axis=-1).sum(1))
        f = swap < same
        out[np.ix_(f, left + right)] = rep[np.ix_(f, right + left)]
    return out


def solve_in_image(joints2d, joints3d) -> np.ndarray:
    """(F, 15, 2) the 3D solve drawn in the 2D fit's image (:func:`reproject`) with its
    arms and legs named as the fit's (each frame's pair matched to the nearer 2D one):
    the joints :func:`fill_hidden` takes from."""
    j2 = np.asarray(joints2d, dtype=float)
    return _matched(reproject(joints3d, j2), j2)


def fill_hidden(joints2d, joints3d) -> np.ndarray:
    """The 2D fit's joints with the shoulders, the hips, the wrists
    :func:`hidden_joints` names and the elbows it names or that hang such a wrist taken
    from the 3D solve (:func:`reproject`).

    The hips, like the shoulders, are points inside the outline the silhouette does not
    mark: the fit draws them at the pelvis across its spread, the solve with the torso's
    3D turn (on the tuning renders the solve's hips gained 0.1 PCK point upright and 0.3
    on the low poses; its knees and ankles, which the outline shows, lost; RESULTS.md).

    A wrist out beside or in front of the torso is where the image shows it, even when
    its elbow lies inside the outline: it stays as fitted (the whole arm taken from
    the solve, as before, lost such wrists; benchmarks/RESULTS.md, 2D pose).

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, 2)
        The 2D fit's joints, pixels, image-side names (NaN frames stay NaN).
    joints3d : numpy.ndarray, shape (F, 15, 3)
        The clip solve's joints for the same frames (any names: each frame's arms and
        legs are matched to the nearer 2D ones).

    Returns
    -------
    numpy.ndarray, shape (F, 15, 2)
    """
    j2 = np.asarray(joints2d, dtype=float)
    rep = solve_in_image(j2, joints3d)
    out = j2.copy()
    ok = np.isfinite(rep).all(axis=(1, 2)) & np.isfinite(j2).all(axis=(1, 2))
    hid = hidden_joints(j2) & ok[:, None, None]
    for col, s in enumerate("lr"):
        sh, el, wr = _ARMS[s]
        out[ok, sh] = rep[ok, sh]
        out[ok, _LEGS[s][0]] = rep[ok, _LEGS[s][0]]
        # a wrist the torso hides hides its elbow's place too (the fit hangs both
        # from it); a wrist out in the open is kept where the image shows it
        elbow, wrist = hid[:, col, 0] | hid[:, col, 1], hid[:, col, 1]
        out[elbow, el] = rep[elbow, el]
        out[wrist, wr] = rep[wrist, wr]
    return out


#: Spread (the fit's, per frame) from which :func:`rehang_arms` may hang a frame's
#: forearms from the other shoulders: below it the shoulders nearly coincide in the
#: image, and the exchange would only rename the arms.
REHANG_SPREAD = 0.25
#: Frames over which :func:`rehang_arms` averages the two hypotheses' residuals (a
#: hanging is changed where it is the better over a few frames, not one).
REHANG_WINDOW = 5
_FOREARMS = [*_ARMS["l"][1:], *_ARMS["r"][1:]]
_FOREARMS_EXCHANGED = [*_ARMS["r"][1:], *_ARMS["l"][1:]]


def exchange_forearms(joints2d, frames) -> np.ndarray:
    """``joints2d`` (F, 15, 2) with the elbows and wrists exchanged between the
    shoulders in the frames ``frames`` ((F,) bool) names: each forearm hung from the
    other shoulder, where it is in the image."""
    out = np.array(joints2d, dtype=float)
    f = np.asarray(frames, dtype=bool)
    out[np.ix_(f, _FOREARMS)] = np.asarray(joints2d, dtype=float)[np.ix_(f, _FOREARMS_EXCHANGED)]
    return out


def arm_residual(joints3d, joints2d) -> np.ndarray:
    """(F,) how far the 3D solve's arms, drawn in the image (:func:`reproject`, each
    frame's arms matched to the nearer 2D ones), lie from the 2D arms: the sum over the
    shoulders, elbows and wrists, in body heights (pelvis to head top, Table 3.1)."""
    j2 = np.asarray(joints2d, dtype=float)
    rep = solve_in_image(j2, joints3d)
    arms = [*_ARMS["l"], *_ARMS["r"]]
    height = np.linalg.norm(j2[:, JOINT_INDEX["head_top"]] - j2[:, JOINT_INDEX["pelvis"]],
                            axis=-1) / _AXIS_SHARE
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.linalg.norm(rep[:, arms] - j2[:, arms], axis=-1).sum(1) / height


def rehang_arms(joints2d, joints3d, solve, spread) -> tuple[np.ndarray, np.ndarray]:
    """The arms hung from the shoulders the clip solve fits the better (side views).

    A side view's track names its arms by the limbs it followed, and where the arms
    pass each other inside the torso's outline the cue step can hand the forearm the
    frame shows to the model arm that was following the hidden one (07_07 at 110
    degrees: the arms hung from the wrong shoulders in 27 of 60 frames; RESULTS.md).
    With the torso turned a little (spread at least :data:`REHANG_SPREAD`) the two
    shoulders lie apart in the image, and a forearm hung from the wrong one asks the
    solve's rigid arm for a reach it cannot make: the solve is run again on every
    forearm hung from the other shoulder (:func:`exchange_forearms`), and where that
    one's arms lie nearer the 2D arms (:func:`arm_residual`, averaged over
    :data:`REHANG_WINDOW` frames) the frame's forearms are exchanged and the clip
    solved once more.

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, 2)
        The 2D fit's joints, pixels.
    joints3d : numpy.ndarray, shape (F, 15, 3)
        ``solve(joints2d)``.
    solve : callable
        ``solve(joints2d) -> joints3d``: the clip solve.
    spread : numpy.ndarray, shape (F,)
        The fit's spread per frame.

    Returns
    -------
    joints2d, joints3d : numpy.ndarray
        The inputs where no frame is exchanged, else the exchanged 2D joints and
        their solve.
    """
    from scipy.ndimage import uniform_filter1d

    sp = np.asarray(spread, dtype=float)
    with np.errstate(invalid="ignore"):
        turned = sp >= REHANG_SPREAD
    if not turned.any():
        return joints2d, joints3d
    exchanged = exchange_forearms(joints2d, np.ones(len(sp), dtype=bool))
    gain = arm_residual(solve(exchanged), exchanged) - arm_residual(joints3d, joints2d)
    gain = uniform_filter1d(np.nan_to_num(gain, nan=0.0), REHANG_WINDOW, mode="nearest")
    pick = turned & (gain < 0.0)
    if not pick.any():
        return joints2d, joints3d
    mixed = exchange_forearms(joints2d, pick)
    return mixed, solve(mixed)


def leg_order(frames, joints2d, model_height, body=None) -> np.ndarray:
    """(F, 2) the colour frame's limb order (:func:`vidcap.video.legorder.near_limb`: which
    of the fit's legs the frame shows nearer, column 1) with the arms' column NaN: the
    solve then names a side view's legs by it (as ``vidcap convert`` does), the arms by
    the fit. On the side-view tuning renders the legs' order alone gained where the arms'
    as well did not (RESULTS.md)."""
    from vidcap.video.legorder import limb_edges, limb_radii, near_limb

    strength, count = limb_edges(frames, joints2d, limb_radii(model_height, body))
    order = near_limb(strength, count)
    order[:, 0] = np.nan
    return order


def solve_hidden(joints2d, *, fps: float, body=None, spread=None, model_height=None,
                 frame_size=None, frames=None, rehang: bool = False) -> np.ndarray:
    """:func:`fill_hidden` with the clip solve run here (``vidcap pose2d --hidden solve``):
    :func:`vidcap.video.lifting.lift_pose` on the fit's joints (image-side names), its
    ``spread``, ``model_height`` and the frame's size, with ``body``'s proportions.

    ``rehang`` (off: not validated, see below): the forearms hung from the shoulders the
    solve fits the better (:func:`rehang_arms`, given ``spread``), and with the colour
    ``frames`` (an iterable of (H, W, 3) BGR frames; with ``model_height``) a side view's
    legs named by the limb order (:func:`leg_order`). Side tuning renders
    (``pose2d_attribution.py --hidden solve --extra --rehang``) PCK@0.05 92.44 -> 93.21 %,
    but held out (``pose2d_accuracy.py --held-out --hidden solve --rehang``) side 84.10 ->
    83.77, mean 87.59 -> 87.55 (benchmarks/RESULTS.md)."""
    from vidcap.video.lifting import lift_pose

    order = None if not rehang or frames is None or model_height is None else \
        leg_order(frames, joints2d, model_height, body)

    def solve(j2):
        return lift_pose(j2, fps=fps, body=body, image_sides=True, spread=spread,
                         model_height=model_height, frame_size=frame_size,
                         limb_order=order).joints3d

    j2, j3 = np.asarray(joints2d, dtype=float), solve(joints2d)
    if rehang and spread is not None:
        j2, j3 = rehang_arms(j2, j3, solve, spread)
    return fill_hidden(j2, j3)


__all__ = ["AXIS", "CONVERT_HIDDEN", "DEFAULT_HIDDEN", "HIDDEN_CHOICES", "REHANG_SPREAD",
           "REHANG_WINDOW", "arm_residual", "check_hidden", "exchange_forearms", "fill_hidden",
           "hidden_arms", "hidden_joints", "leg_order", "rehang_arms", "reproject", "solve_hidden",
           "solve_in_image"]
