"""Which leg is nearer the camera: the colour frame's occlusion where the legs overlap.

In a side view a body and its mirror image through the image plane differ only in
which leg (and arm) is which: the 2D joints, the silhouette and every orthographic
geometry are the same for both, so the 2D fit's leg names there are a coin toss. The
colour frame is not: where the two legs overlap in the image, the nearer leg covers the
farther one. The nearer leg's borders then show as image edges (a shading or texture
step) running across the farther leg, while the farther leg's borders inside the nearer
leg's area are hidden: only the nearer leg's smooth shading is there.

:func:`leg_edges` measures this per frame: each fitted leg's thigh and shin is a band
of the body model's width about its 2D segment; along each band's two borders, at the
samples that lie well inside the other leg's band, the image gradient across the border
(taken as the largest a little inside or outside the fitted border, which is a few
pixels off) is averaged. :func:`near_leg` turns the two legs' averages into a signed
score in the fit's names (> 0: the fit's ``l_`` leg is the nearer), NaN where the legs
do not overlap.
"""

from __future__ import annotations

import numpy as np

from vidcap.body import JOINT_INDEX, BodyModel

#: Where along each leg segment the border samples lie (0 its proximal joint, 1 the
#: distal one); the ends are left out (the rounded joints are not bands).
_ALONG = np.linspace(0.1, 0.9, 17)
#: Offsets of the border search, in units of the segment's radius from its axis: the
#: fitted border is a few pixels off (the 2D fit is 1-2 % of the height off). At each
#: offset but the outermost two, the edge is the gradient across the border less the
#: mean of its neighbours' (a ridge: a shading step, not the smooth shading of a
#: cylinder, which is steep near its own outline). Per frame on the fitted 2D of the
#: tuning renders and walk_side (197 frames with a cue; ``benchmarks/solve_fitted.py
#: --legs``): 79 % of frames right; the plain gradient 58 % (71 % with a search of 0.7-1.3).
_ACROSS = np.array([0.55, 0.7, 0.85, 1.0, 1.15, 1.3, 1.45])
#: A border sample counts as over the other leg where its nominal point (offset 1) lies
#: this many of the other leg's radii from that leg's axis, or less: well inside, so the
#: other leg's own borders are outside the search.
INSIDE = 0.6
#: The gradient's step (pixels): central differences over 2 * STEP, smoothed across
#: over the same span (a Sobel operator on a grid of STEP pixels).
STEP = 2
_LEG = {"l": ("l_hip", "l_knee", "l_ankle"), "r": ("r_hip", "r_knee", "r_ankle")}
_LUMA = np.array([0.114, 0.587, 0.299])  # BGR


def _segments(j2):
    """(2 legs, 2 segments, 2 ends, 2) px of one frame's thighs and shins (l, r)."""
    out = np.empty((2, 2, 2, 2))
    for c, side in enumerate("lr"):
        hip, knee, ankle = (j2[JOINT_INDEX[n]] for n in _LEG[side])
        out[c, 0] = hip, knee
        out[c, 1] = knee, ankle
    return out


def _distance_to_segments(pts, segs):
    """Distance (n,) of points (n, 2) to the nearest of segments (m, 2 ends, 2)."""
    a, b = segs[:, 0], segs[:, 1]
    d = b - a
    L2 = np.maximum((d * d).sum(-1), 1e-9)
    t = np.clip(((pts[:, None] - a[None]) * d[None]).sum(-1) / L2[None], 0.0, 1.0)
    near = a[None] + t[..., None] * d[None]
    return np.sqrt(((pts[:, None] - near) ** 2).sum(-1)).min(-1)


def _gradients(frame, pts):
    """Image gradient (n, 3 channels, 2) of ``frame`` (H, W, 3) at the pixels nearest
    ``pts`` (n, 2): a Sobel operator on a grid of :data:`STEP` pixels; NaN off the frame."""
    H, W = frame.shape[:2]
    s = STEP
    xy = np.round(pts).astype(np.int64)
    ok = (xy[:, 0] >= s) & (xy[:, 0] < W - s) & (xy[:, 1] >= s) & (xy[:, 1] < H - s)
    xy = np.where(ok[:, None], xy, s)
    off = np.array([-s, 0, s])
    # (n, 3 rows dy, 3 cols dx, 3 channels)
    patch = frame[xy[:, 1, None, None] + off[None, :, None],
                  xy[:, 0, None, None] + off[None, None, :]].astype(np.float32)
    w = np.array([1.0, 2.0, 1.0], np.float32)
    gx = ((patch[:, :, 2] - patch[:, :, 0]) * w[None, :, None]).sum(1) / (8.0 * s)
    gy = ((patch[:, 2, :] - patch[:, 0, :]) * w[None, :, None]).sum(1) / (8.0 * s)
    g = np.stack([gx, gy], -1)
    g[~ok] = np.nan
    return g


def frame_leg_edges(frame, j2, radius) -> np.ndarray:
    """:func:`leg_edges` of one frame: (2,) mean edge strength across the borders of
    the fit's l and r legs where they lie over the other leg, and (2,) how many
    border samples that was; NaN strength where none.

    Parameters
    ----------
    frame : numpy.ndarray, shape (H, W, 3) uint8
    j2 : numpy.ndarray, shape (15, 2)
        The frame's fitted joints, pixels.
    radius : numpy.ndarray, shape (2,)
        The thigh's and the shin's radius, pixels.
    """
    segs = _segments(np.asarray(j2, float))
    if not np.isfinite(segs).all():
        return np.full(2, np.nan), np.zeros(2)
    r = np.asarray(radius, float)
    a, b = segs[..., 0, :], segs[..., 1, :]  # (2, 2, 2)
    d = b - a
    L = np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-9)
    u = d / L
    nrm = np.stack([-u[..., 1], u[..., 0]], -1)  # (2 legs, 2 segs, 2)
    # nominal border points (leg, seg, t, side, 2)
    sides = np.array([-1.0, 1.0])
    centre = a[:, :, None] + _ALONG[None, None, :, None] * d[:, :, None]
    out_dir = sides[None, None, None, :, None] * nrm[:, :, None, None, :]
    nominal = centre[:, :, :, None] + r[None, :, None, None, None] * out_dir
    strength, count = np.full(2, np.nan), np.zeros(2)
    for c in range(2):
        pts = nominal[c].reshape(-1, 2)
        inside = _distance_to_segments(pts, segs[1 - c]) <= INSIDE * r.min()
        if not inside.any():
            continue
        # the search across the border (k samples, offsets, 2)
        seg_of = np.repeat(np.arange(2), len(_ALONG) * 2)[inside]
        base = np.broadcast_to(centre[c][:, :, None], (2, len(_ALONG), 2, 2)).reshape(-1, 2)
        odir = np.broadcast_to(out_dir[c], (2, len(_ALONG), 2, 2)).reshape(-1, 2)[inside]
        search = (base[inside][:, None] + (_ACROSS[None, :, None] * r[seg_of][:, None, None])
                  * odir[:, None])
        g = _gradients(frame, search.reshape(-1, 2)).reshape(len(odir), len(_ACROSS), 3, 2)
        across = np.sqrt(((g * odir[:, None, None]).sum(-1) ** 2).sum(-1))  # (k, offsets)
        across = across[:, 1:-1] - 0.5 * (across[:, :-2] + across[:, 2:])
        best = np.nanmax(np.where(np.isfinite(across), across, -np.inf), axis=1)
        ok = np.isfinite(best)
        best = np.maximum(best, 0.0)
        if ok.any():
            strength[c], count[c] = float(best[ok].mean()), float(ok.sum())
    return strength, count


def leg_radii(model_height, body: BodyModel | None = None) -> np.ndarray:
    """The thigh's and the shin's radius (F, 2) in pixels at the height in pixels the
    2D fit drew its model in each frame (``model_height`` (F,))."""
    body = body or BodyModel()
    px = np.asarray(model_height, float).reshape(-1, 1) / body.height
    return px * np.array([body.radius("l_upper_leg"), body.radius("l_lower_leg")])[None]


def leg_edges(frames, joints2d, radii) -> tuple[np.ndarray, np.ndarray]:
    """Edge strength along each fitted leg's borders where they lie over the other leg.

    Parameters
    ----------
    frames : iterable of numpy.ndarray, shape (H, W, 3) uint8
        The clip's colour frames (BGR), in order, one per row of ``joints2d``; ``None``
        for a frame not available.
    joints2d : array_like, shape (F, 15, 2)
        Fitted 2D joints, pixels, the fit's names; NaN where none.
    radii : array_like, shape (F, 2)
        :func:`leg_radii`.

    Returns
    -------
    strength : numpy.ndarray, shape (F, 2)
        Mean gradient across the border (grey levels per pixel) of the fit's l (column
        0) and r (1) leg over the other leg; NaN where they do not overlap.
    count : numpy.ndarray, shape (F, 2)
        Border samples each mean is over.
    """
    F = len(joints2d)
    strength, count = np.full((F, 2), np.nan), np.zeros((F, 2))
    for _ in tap_leg_edges(frames, joints2d, radii, strength, count):
        pass
    return strength, count


def tap_leg_edges(frames, joints2d, radii, strength, count):
    """Yield ``frames`` unchanged, filling ``strength`` and ``count`` (F, 2) (as
    :func:`leg_edges` returns them) as each frame passes: one decode of the clip serves
    this cue and the front/back one (:func:`vidcap.video.frontback.arm_visibility`)."""
    j2 = np.asarray(joints2d, float)
    rad = np.asarray(radii, float)
    for k, frame in enumerate(frames):
        if k < len(j2) and frame is not None and np.isfinite(rad[k]).all():
            strength[k], count[k] = frame_leg_edges(np.asarray(frame), j2[k], rad[k])
        yield frame


def near_leg(strength, count, *, min_count: int = 4) -> np.ndarray:
    """Which of the fit's legs the frame shows nearer the camera, (F,): (l - r) / (l +
    r) of :func:`leg_edges`' strengths (> 0: the fit's ``l_`` leg covers the other), NaN
    where either leg has fewer than ``min_count`` border samples over the other."""
    s = np.asarray(strength, float)
    ok = (np.asarray(count) >= min_count).all(-1) & np.isfinite(s).all(-1)
    tot = np.where(ok, s.sum(-1), 1.0)
    return np.where(ok & (tot > 0), (s[:, 0] - s[:, 1]) / np.maximum(tot, 1e-9), np.nan)


def _runs(flags, key) -> list[tuple[int, int]]:
    """[start, stop) of every run of True in ``flags`` (F,) bool over which ``key`` (F,)
    stays the same."""
    f = np.asarray(flags, bool)
    k = np.asarray(key)
    start = f & np.r_[True, ~f[:-1] | (k[1:] != k[:-1])]
    stop = f & np.r_[~f[1:] | (k[1:] != k[:-1]), True]
    return list(zip(np.flatnonzero(start).tolist(), (np.flatnonzero(stop) + 1).tolist(),
                    strict=True))


#: A run of edge-on frames is named by the leg cue only when at least this many of its
#: frames have a cue and their mean score (in the linked names) is at least
#: :data:`MIN_MEAN` from 0; otherwise the fit's names stay.
MIN_FRAMES = 5
MIN_MEAN = 0.1


def side_leg_names(order, edge_on, facing_right, link, swapped=None, *,
                   min_frames: int = MIN_FRAMES,
                   min_mean: float = MIN_MEAN) -> np.ndarray:
    """Where the legs' distal joints (knee and ankle) are to be exchanged so that, in
    each run of edge-on side-view frames, the leg the colour frame shows nearer the
    camera is the body side that faces it.

    A body facing image right (yaw +90 degrees) turns its right side to the camera,
    one facing image left its left side (:func:`vidcap.video.lift.body_axes`). Per
    frame the cue is noisy (a misplaced fitted leg reads the wrong pixels), so each run
    is named as a whole: its frames are first linked into two leg tracks by ``link``
    (the exchanges that make each named knee and ankle move smoothly,
    :func:`vidcap.video.solve.labels.consistent_labels`), and the track with the larger
    mean score is the near leg throughout the run.

    Parameters
    ----------
    order : array_like, shape (F,)
        :func:`near_leg` in the fit's names (> 0: the fit's ``l_`` leg is nearer), NaN
        where unknown.
    edge_on : array_like of bool, shape (F,)
        Frames to name: side views whose torso is edge-on (runs of these are named).
    facing_right : array_like of bool, shape (F,)
        The body faces image right.
    link : array_like of bool, shape (F,)
        Frames whose legs the linking exchanges.
    swapped : array_like of bool, shape (F,), optional
        Frames whose image-side names the view swaps to name the body's sides
        (:func:`vidcap.video.lift.assign_sides`); none by default (a side view keeps
        the fit's names).
    min_frames, min_mean : see :data:`MIN_FRAMES`, :data:`MIN_MEAN`.

    Returns
    -------
    numpy.ndarray of bool, shape (F,)
        Legs exchanged against the fit's names; False outside the named runs.
    """
    d = np.asarray(order, float)
    link = np.asarray(link, bool)
    right = np.asarray(facing_right, bool)
    edge = np.asarray(edge_on, bool)
    flip = np.zeros(len(d), bool) if swapped is None else np.asarray(swapped, bool)
    out = np.zeros(len(d), bool)
    for lo, hi in _runs(edge, right):  # a run also ends where the body turns round
        s = link[lo:hi]
        dl = np.where(s, -d[lo:hi], d[lo:hi])  # the score of the linked 'l' track
        cued = np.isfinite(dl)
        if cued.sum() < min_frames:
            continue
        m = float(dl[cued].mean())
        if abs(m) < min_mean:
            continue
        # the linked 'l' track is near: it is the body's right one facing right
        out[lo:hi] = s ^ ((m > 0) == right[lo:hi]) ^ flip[lo:hi]
    return out
