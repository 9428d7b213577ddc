"""Front or back: which arm the colour frame shows in front of the body.

An orthographic view of joints, and a silhouette, is the same for a body and for its
reflection through the image plane with left and right renamed: a body facing the
camera and one turned away look alike. The 2D fit's joints, the clip solve's cost and
every anatomical cue (knees fold backward, people walk forward) are symmetric under
that reflection, so none of them can tell front from back. The colour frame can: the
arm nearer the camera covers the torso and the hips, the farther one is hidden behind
them. With the side the body faces in the image known (image right or left:
:func:`vidcap.video.proposals.propose_orientation` reads it from the knees, elbows and
the direction of travel), the nearer arm tells front from back: a body facing image
right shows its right side to the camera, and its right arm is on the image's left when
it faces the camera, on the image's right when it is turned away.

The cue (:func:`arm_visibility`) is the skin likelihood along each fitted forearm's
hand end, skin and clothing colours learned from this clip's fitted head and torso
(:class:`vidcap.video.fit.cues.ColourModel`): an arm hidden behind the body shows
clothing where the fit put it, one in front shows skin; arms swung clear of the body
both show skin and give no evidence. :func:`near_side` is the image-left arm's minus
the image-right arm's. Where a face is found on the fitted head
(:mod:`vidcap.video.facecue`) it overrules the arms
(:func:`vidcap.video.proposals.propose_front`).
"""

from __future__ import annotations

import numpy as np

from vidcap.body import JOINT_INDEX
from vidcap.video.fit.cues import ColourModel, chroma_bins

#: Where along each segment the samples lie (0 = its first joint, 1 = its second):
#: the head between neck and crown, the torso's core between pelvis and neck (the
#: clothing), the forearm from its middle to just past the wrist (the hand).
_HEAD_T = np.linspace(0.35, 0.75, 5)
_TORSO_T = np.linspace(0.3, 0.7, 5)
_ARM_T = np.linspace(0.5, 1.15, 8)
#: Offsets across a segment, in units of the segment's image length (the torso's core
#: is sampled over a band, the head and the forearm along their axis).
_TORSO_ACROSS = np.array([-0.08, 0.0, 0.08])
#: The forearm directions tried about the fitted one (radians), from the fitted elbow:
#: the fit places a forearm that the silhouette does not show (one in front of the
#: torso, or hidden behind it) by its prior, so the skin is looked for where the
#: forearm could be, not only where the fit put it.
SEARCH = np.deg2rad(np.arange(-60.0, 61.0, 15.0))


def _along(j2, a: str, b: str, ts, across=(0.0,)):
    """Points (F, n, 2) along the image segment a -> b at ``ts``, each repeated at the
    ``across`` offsets (units of the segment's length, perpendicular to it)."""
    p, q = j2[:, JOINT_INDEX[a]], j2[:, JOINT_INDEX[b]]
    d = q - p
    n = np.stack([-d[:, 1], d[:, 0]], -1)
    pts = (p[:, None, None] + np.asarray(ts)[None, :, None, None] * d[:, None, None]
           + np.asarray(across)[None, None, :, None] * n[:, None, None])
    return pts.reshape(len(j2), -1, 2)


def _forearms(j2, elbow: str, wrist: str, search):
    """Points (F, len(search) * len(_ARM_T), 2) of the forearm elbow -> wrist turned by
    each angle of ``search`` about the elbow."""
    e, w = j2[:, JOINT_INDEX[elbow]], j2[:, JOINT_INDEX[wrist]]
    d = w - e
    c, s = np.cos(search), np.sin(search)
    rot = np.stack([c[:, None] * d[None, :, 0] - s[:, None] * d[None, :, 1],
                    s[:, None] * d[None, :, 0] + c[:, None] * d[None, :, 1]], -1)  # (A, F, 2)
    pts = e[None, :, None] + _ARM_T[None, None, :, None] * rot[:, :, None]  # (A, F, T, 2)
    return pts.transpose(1, 0, 2, 3).reshape(len(j2), -1, 2)


def sample_points(joints2d, search=SEARCH) -> dict:
    """The frame pixels each cue reads, {name: (F, n, 2) float px}: ``head``, ``cloth``
    (the torso's core), ``arm_left`` and ``arm_right`` (the forearms of the arms on the
    image's left and right, told by their shoulders' image x, whatever their names).

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Fitted 2D joints, pixels (x right, y down).
    """
    j2 = np.asarray(joints2d, dtype=float)
    la = _forearms(j2, "l_elbow", "l_wrist", search)
    ra = _forearms(j2, "r_elbow", "r_wrist", search)
    l_is_left = (j2[:, JOINT_INDEX["l_shoulder"], 0] <= j2[:, JOINT_INDEX["r_shoulder"], 0])
    sel = l_is_left[:, None, None]
    return {"head": _along(j2, "neck", "head_top", _HEAD_T),
            "cloth": _along(j2, "pelvis", "neck", _TORSO_T, _TORSO_ACROSS),
            "arm_left": np.where(sel, la, ra), "arm_right": np.where(sel, ra, la)}


def _nearest_pixels(pts: np.ndarray) -> np.ndarray:
    """The pixels (..., 2) int64 x, y nearest ``pts`` (..., 2); -1 where not finite."""
    ok = np.isfinite(pts).all(-1)
    return np.where(ok[..., None], np.round(pts), -1).astype(np.int64)


def read_bounds(joints2d, shape, search=SEARCH) -> np.ndarray:
    """The box of the pixels :func:`arm_visibility` reads in each frame of ``shape`` (H, W),
    (F, 4) ``x_min, x_max, y_min, y_max`` px (inclusive; ``inf, -inf`` where it reads
    none)."""
    pts = sample_points(joints2d, search)
    xy = _nearest_pixels(np.concatenate([pts[k] for k in ("head", "cloth", "arm_left",
                                                          "arm_right")], axis=1))
    return pixel_bounds(xy[..., 0], xy[..., 1], shape)


def pixel_bounds(x, y, shape) -> np.ndarray:
    """(F, 4) ``x_min, x_max, y_min, y_max`` of the pixels ``x``, ``y`` (F, ...) inside a
    frame of ``shape`` (H, W) (``inf, -inf`` where none is)."""
    H, W = shape[:2]
    x, y = x.reshape(len(x), -1), y.reshape(len(y), -1)
    inside = (x >= 0) & (x < W) & (y >= 0) & (y < H)
    return np.stack([np.where(inside, x, np.inf).min(-1, initial=np.inf),
                     np.where(inside, x, -np.inf).max(-1, initial=-np.inf),
                     np.where(inside, y, np.inf).min(-1, initial=np.inf),
                     np.where(inside, y, -np.inf).max(-1, initial=-np.inf)], -1)


def _bins_at(frame: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Chromaticity bins (n,) of ``frame`` (H, W, 3) at the pixels nearest ``pts`` (n, 2),
    -1 where a point is not finite or outside the frame."""
    H, W = frame.shape[:2]
    xy = _nearest_pixels(pts)
    ok = (xy[:, 0] >= 0) & (xy[:, 0] < W) & (xy[:, 1] >= 0) & (xy[:, 1] < H)
    out = np.full(len(pts), -1, np.int64)
    if ok.any():
        px = frame[xy[ok, 1], xy[ok, 0]].astype(np.float32)
        out[ok] = chroma_bins(px[None])[0]
    return out


def arm_visibility(frames, joints2d, search=SEARCH) -> np.ndarray:
    """How much skin each forearm shows where the fit put it, per frame.

    Parameters
    ----------
    frames : iterable of numpy.ndarray, shape (H, W, 3) uint8
        The clip's colour frames (BGR), in order, one per row of ``joints2d``; ``None``
        for a frame not available (frames beyond the last one given count as such).
    joints2d : array_like, shape (F, 15, 2)
        Fitted 2D joints, pixels; NaN where none.

    Returns
    -------
    numpy.ndarray, shape (F, 2)
        Mean skin likelihood (0-1) along the hand end of the image-left (column 0) and
        image-right (column 1) forearm; NaN where the frame, the joints or the colour
        model (no head or torso seen) are missing.
    """
    pts = sample_points(joints2d, search)
    F = len(pts["head"])
    names = ("head", "cloth", "arm_left", "arm_right")
    bins = {k: np.full(pts[k].shape[:2], -1, np.int64) for k in names}
    for k, frame in enumerate(frames):
        if k >= F:
            break
        if frame is None:
            continue
        for name in names:
            bins[name][k] = _bins_at(np.asarray(frame), pts[name][k])
    model = ColourModel()
    n_bins = model.counts.shape[1]
    for c, name in enumerate(("head", "cloth")):
        b = bins[name][bins[name] >= 0]
        model.counts[c] += np.bincount(b, minlength=n_bins)
    out = np.full((F, 2), np.nan)
    if not model.learned:
        return out
    table = model.table()
    for c, name in enumerate(("arm_left", "arm_right")):
        b = bins[name]
        ok = (b >= 0).reshape(F, -1, len(_ARM_T))
        p = np.where(b >= 0, table[np.maximum(b, 0)], 0.0).reshape(ok.shape)
        n = ok.sum(-1)  # (F, A): samples of each tried forearm inside the frame
        mean = np.where(n > 0, p.sum(-1) / np.maximum(n, 1), -1.0)
        best = mean.max(-1)
        out[:, c] = np.where(best >= 0, best, np.nan)
    return out


def near_side(visibility) -> np.ndarray:
    """Which arm the image shows nearer the camera, (F,): the image-left forearm's skin
    likelihood minus the image-right one's (> 0: the image-left arm is in front), 0
    where either is unknown.

    Parameters
    ----------
    visibility : array_like, shape (F, 2)
        :func:`arm_visibility`.
    """
    v = np.asarray(visibility, dtype=float)
    return np.nan_to_num(v[:, 0] - v[:, 1])
