"""Joints the image cannot show, placed from the 3D clip solve (issue 27).

An arm behind the torso (the far arm of a side view) or in front of it covers the same
silhouette pixels at any angle, and the frame shows nothing of the far one, so the 2D
fit leaves it where its search ended (hanging, under-bent). The clip solve
(:mod:`vidcap.video.solve`) places the same arm with what the rest of the body says:
rigid bones, joint limits, the pose prior learned from motion capture (how people hold
an arm, in the torso's frame, whichever way they face) and smoothness over the clip.
:func:`fill_hidden` reprojects the solve's 3D joints into the image (scaled
orthographic, each frame aligned on the pelvis, neck and head top the 2D fit found)
and puts them in place of the 2D fit's shoulders and of the elbows and wrists of every
arm the fit drew inside the torso's outline (:func:`hidden_arms`); everything else
stays as fitted.

Measured (HISTORY.md, "Joints the image cannot show"): on the 15 side and three-quarter
tuning renders PCK@0.05 93.77 -> 95.04 %, where which joints to replace was chosen (the
arms inside and the shoulders; every arm joint or the upper body as good, every joint or
the legs too worse); on the 40 held-out renders (``benchmarks/pose2d_accuracy.py
--held-out --hidden solve``) 86.37 -> 87.23 % with the cues, 85.04 -> 85.77 % with the
outline; on real clips against MediaPipe equal or nearer with the default body.
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


def hidden_arms(joints2d) -> np.ndarray:
    """(F, 2) bool: the image-left (column 0) and right arm whose elbow or wrist lies
    inside the torso's outline (within the torso cylinder's radius of the pelvis-neck
    segment; the body height read off pelvis to head top, Table 3.1)."""
    j = np.asarray(joints2d, dtype=float)
    pel, neck = j[:, JOINT_INDEX["pelvis"]], j[:, JOINT_INDEX["neck"]]
    height = np.linalg.norm(j[:, JOINT_INDEX["head_top"]] - pel, axis=-1) / _AXIS_SHARE
    radius = 0.5 * SEGMENTS[SEGMENT_INDEX["torso"]].width_ratio * height
    ab = neck - pel
    ab2 = np.maximum((ab * ab).sum(-1), 1e-9)
    out = np.zeros((len(j), 2), dtype=bool)
    for col, s in enumerate("lr"):
        for k in _ARMS[s][1:]:
            q = j[:, k] - pel
            t = np.clip((q * ab).sum(-1) / ab2, 0.0, 1.0)
            with np.errstate(invalid="ignore"):
                out[:, col] |= np.linalg.norm(q - t[:, None] * ab, axis=-1) < radius
    return out


def _matched(rep: np.ndarray, j2: np.ndarray) -> np.ndarray:
    """``rep`` with its arms exchanged in the frames where the other order lies nearer
    the 2D fit's arms (the solve names arms by the body's sides, the fit by the image's)."""
    left, right = list(_ARMS["l"]), list(_ARMS["r"])
    same = (np.linalg.norm(rep[:, left] - j2[:, left], axis=-1).sum(1)
            + np.linalg.norm(rep[:, right] - j2[:, right], axis=-1).sum(1))
    swap = (np.linalg.norm(rep[:, left] - j2[:, right], axis=-1).sum(1)
            + np.linalg.norm(rep[:, right] - j2[:, left], axis=-1).sum(1))
    out = rep.copy()
    f = swap < same
    out[np.ix_(f, left + right)] = rep[np.ix_(f, right + left)]
    return out


def fill_hidden(joints2d, joints3d) -> np.ndarray:
    """The 2D fit's joints with the shoulders, and the elbows and wrists of the arms
    :func:`hidden_arms` names, taken from the 3D solve (:func:`reproject`).

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, 2)
        The 2D fit's joints, pixels, image-side names (NaN frames stay NaN).
    joints3d : numpy.ndarray, shape (F, 15, 3)
        The clip solve's joints for the same frames (any names: each frame's arms are
        matched to the nearer 2D arms).

    Returns
    -------
    numpy.ndarray, shape (F, 15, 2)
    """
    j2 = np.asarray(joints2d, dtype=float)
    rep = _matched(reproject(joints3d, j2), j2)
    out = j2.copy()
    ok = np.isfinite(rep).all(axis=(1, 2)) & np.isfinite(j2).all(axis=(1, 2))
    hid = hidden_arms(j2) & ok[:, None]
    for col, s in enumerate("lr"):
        sh, el, wr = _ARMS[s]
        out[ok, sh] = rep[ok, sh]
        out[np.ix_(hid[:, col], [el, wr])] = rep[np.ix_(hid[:, col], [el, wr])]
    return out


def solve_hidden(joints2d, *, fps: float, body=None, spread=None, model_height=None,
                 frame_size=None) -> np.ndarray:
    """:func:`fill_hidden` with the clip solve run here (``vidcap pose2d --hidden solve``):
    :func:`vidcap.video.lifting.lift_pose` on the fit's joints (image-side names), its
    ``spread``, ``model_height`` and the frame's size, with ``body``'s proportions."""
    from vidcap.video.lifting import lift_pose

    lifted = lift_pose(joints2d, fps=fps, body=body, image_sides=True, spread=spread,
                       model_height=model_height, frame_size=frame_size)
    return fill_hidden(joints2d, lifted.joints3d)


__all__ = ["AXIS", "CONVERT_HIDDEN", "DEFAULT_HIDDEN", "HIDDEN_CHOICES", "check_hidden",
           "fill_hidden", "hidden_arms", "reproject", "solve_hidden"]
