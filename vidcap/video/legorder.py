"""Which leg (arm) is nearer the camera: the colour frame's occlusion where limbs overlap.

In a side view a body and its mirror image through the image plane differ only in
which leg and arm is which: the 2D joints, the silhouette and every orthographic
geometry are the same for both, so the 2D fit's limb names there are a coin toss. The
colour frame is not: where the two legs overlap in the image, the nearer leg covers the
farther one. The nearer leg's borders then show as image edges (a shading or texture
step) running across the farther leg, while the farther leg's borders inside the nearer
leg's area are hidden: only the nearer leg's smooth shading is there. An arm in front
of the torso shows its borders across it; one behind it is hidden.

:func:`limb_edges` measures this per frame: each fitted leg's thigh and shin is a band
of the body model's width about its 2D segment; along each band's two borders, at the
samples that lie well inside the other leg's band, the image gradient across the border
(its ridge, taken as the largest a little inside or outside the fitted border, which is
a few pixels off) is averaged; the arms likewise over the torso.
:func:`near_limb` turns the two sides' averages into a signed score in the fit's names
(> 0: the fit's ``l_`` limb is the nearer), NaN where they do not overlap, and
:func:`side_limb_names` names each linked run of frames by it.
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
#: The search's smallest spacing (pixels): a ridge needs its neighbours a pixel or more
#: away (a thin arm's 0.15 radii is less).
MIN_SPACING = 1.5
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


def border_edges(frame, segs, radius, cover, cover_radius) -> tuple[float, float]:
    """Mean edge strength across the borders of one limb's segments where they lie over
    ``cover`` (another limb or the torso), and how many border samples that was.

    Parameters
    ----------
    frame : numpy.ndarray, shape (H, W, 3) uint8
    segs : numpy.ndarray, shape (S, 2 ends, 2)
        The limb's segments, pixels.
    radius : numpy.ndarray, shape (S,)
        Their radii, pixels.
    cover : numpy.ndarray, shape (M, 2 ends, 2)
        The segments the borders may lie over, pixels.
    cover_radius : numpy.ndarray, shape (M,)

    Returns
    -------
    strength : float
        Grey levels per pixel (a ridge of the gradient across the border); NaN where no
        border sample lies :data:`INSIDE` the cover.
    count : float
    """
    r = np.asarray(radius, float)
    a, b = segs[:, 0], segs[:, 1]
    d = b - a
    u = d / np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-9)
    nrm = np.stack([-u[:, 1], u[:, 0]], -1)
    S, T = len(segs), len(_ALONG)
    centre = a[:, None] + _ALONG[None, :, None] * d[:, None]  # (S, T, 2)
    out_dir = np.array([-1.0, 1.0])[None, None, :, None] * nrm[:, None, None, :]  # (S,1,2,2)
    base = np.broadcast_to(centre[:, :, None], (S, T, 2, 2)).reshape(-1, 2)
    odir = np.broadcast_to(out_dir, (S, T, 2, 2)).reshape(-1, 2)
    seg_of = np.repeat(np.arange(S), T * 2)
    nominal = base + r[seg_of][:, None] * odir
    inside = _inside(nominal, cover, cover_radius)
    if not inside.any():
        return np.nan, 0.0
    odir = odir[inside]
    ri = r[seg_of[inside]][:, None]
    unit = np.maximum(ri, MIN_SPACING / (_ACROSS[1] - _ACROSS[0]))
    offset = ri + (_ACROSS[None] - 1.0) * unit  # (k, offsets) px from the axis
    search = base[inside][:, None] + offset[..., None] * odir[:, None]
    g = _gradients(frame, search.reshape(-1, 2)).reshape(len(odir), len(_ACROSS), 3, 2)
    across = np.sqrt(((g * odir[:, None, None]).sum(-1) ** 2).sum(-1))  # (k, offsets)
    across = across[:, 1:-1] - 0.5 * (across[:, :-2] + across[:, 2:])
    best = np.max(np.where(np.isfinite(across), across, -np.inf), axis=1)
    ok = np.isfinite(best)
    if not ok.any():
        return np.nan, 0.0
    return float(np.maximum(best[ok], 0.0).mean()), float(ok.sum())


def _inside(pts, cover, cover_radius):
    """(n,) bool: points (n, 2) within :data:`INSIDE` radii of a cover segment's axis."""
    a, b = cover[:, 0], cover[:, 1]
    d = b - a
    L2 = np.maximum((d * d).sum(-1), 1e-9)
    t = np.clip(((pts[:, None] - a[None]) * d[None]).sum(-1) / L2[None], 0.0, 1.0)
    near = a[None] + t[..., None] * d[None]
    dist = np.sqrt(((pts[:, None] - near) ** 2).sum(-1))
    return (dist <= INSIDE * np.asarray(cover_radius, float)[None]).any(-1)


def frame_leg_edges(frame, j2, radius) -> tuple[np.ndarray, np.ndarray]:
    """The legs of :func:`limb_edges` in one frame: (2,) mean edge strength across the borders of
    the fit's l and r legs where they lie over the other leg (:func:`border_edges`), and
    (2,) how many border samples that was; NaN strength where none.

    Parameters
    ----------
    frame : numpy.ndarray, shape (H, W, 3) uint8
    j2 : numpy.ndarray, shape (15, 2)
        The frame's fitted joints, pixels.
    radius : numpy.ndarray, shape (2,)
        The thigh's and the shin's radius, pixels.
    """
    segs = _segments(np.asarray(j2, float))
    strength, count = np.full(2, np.nan), np.zeros(2)
    if not np.isfinite(segs).all():
        return strength, count
    r = np.asarray(radius, float)
    for c in range(2):
        strength[c], count[c] = border_edges(frame, segs[c], r, segs[1 - c], r)
    return strength, count


#: The columns of :func:`limb_radii`.
RADII = ("upper_arm", "lower_arm", "torso", "upper_leg", "lower_leg")


def limb_radii(model_height, body: BodyModel | None = None) -> np.ndarray:
    """The radii (F, 5) in pixels of :data:`RADII` at the height in pixels the 2D fit
    drew its model in each frame (``model_height`` (F,))."""
    body = body or BodyModel()
    px = np.asarray(model_height, float).reshape(-1, 1) / body.height
    names = ("l_upper_arm", "l_lower_arm", "torso", "l_upper_leg", "l_lower_leg")
    return px * np.array([body.radius(n) for n in names])[None]


def frame_limb_edges(frame, j2, radii) -> tuple[np.ndarray, np.ndarray]:
    """(2 pairs: arms, legs; 2 sides: l, r) mean edge strengths and counts of one frame:
    :func:`frame_arm_edges` and :func:`frame_leg_edges`, ``radii`` (5,) :data:`RADII`."""
    r = np.asarray(radii, float)
    arms = frame_arm_edges(frame, j2, r[:2], r[2])
    legs = frame_leg_edges(frame, j2, r[3:])
    return np.stack([arms[0], legs[0]]), np.stack([arms[1], legs[1]])


def limb_edges(frames, joints2d, radii) -> tuple[np.ndarray, np.ndarray]:
    """Edge strength along each fitted arm's borders where they lie over the torso and
    each leg's where they lie over the other leg.

    Parameters
    ----------
    frames : iterable of numpy.ndarray, shape (H, W, 3) uint8
        The clip's colour frames (BGR), in order, one per row of ``joints2d``; ``None``
        for a frame not available.
    joints2d : array_like, shape (F, 15, 2)
        Fitted 2D joints, pixels, the fit's names; NaN where none.
    radii : array_like, shape (F, 5)
        :func:`limb_radii`.

    Returns
    -------
    strength : numpy.ndarray, shape (F, 2, 2)
        Per frame, pair (arms, legs) and the fit's side (l, r): the mean ridge of the
        gradient across the border (grey levels per pixel); NaN where none lies over
        the torso (arms) or the other leg (legs).
    count : numpy.ndarray, shape (F, 2, 2)
        Border samples each mean is over.
    """
    F = len(joints2d)
    strength, count = np.full((F, 2, 2), np.nan), np.zeros((F, 2, 2))
    for _ in tap_limb_edges(frames, joints2d, radii, strength, count):
        pass
    return strength, count


def tap_limb_edges(frames, joints2d, radii, strength, count):
    """Yield ``frames`` unchanged, filling ``strength`` and ``count`` (F, 2, 2) (as
    :func:`limb_edges` returns them) as each frame passes: one decode of the clip serves
    this cue and the front/back one (:func:`vidcap.video.frontback.arm_visibility`)."""
    j2 = np.asarray(joints2d, float)
    rad = np.asarray(radii, float)
    for k, frame in enumerate(frames):
        if k < len(j2) and frame is not None and np.isfinite(rad[k]).all():
            strength[k], count[k] = frame_limb_edges(np.asarray(frame), j2[k], rad[k])
        yield frame


def near_limb(strength, count, *, min_count: int = 4) -> np.ndarray:
    """Which of the fit's arms (legs) the frame shows nearer the camera, (...): (l - r) /
    (l + r) of :func:`limb_edges`' strengths (...,  2 sides) (> 0: the fit's ``l_`` limb
    is the nearer), NaN where either has fewer than ``min_count`` border samples over
    the torso (the other leg)."""
    s = np.asarray(strength, float)
    ok = (np.asarray(count) >= min_count).all(-1) & np.isfinite(s).all(-1)
    tot = np.where(ok, s.sum(-1), 1.0)
    return np.where(ok & (tot > 0), (s[..., 0] - s[..., 1]) / np.maximum(tot, 1e-9), np.nan)


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


def side_limb_names(order, edge_on, facing_right, link, swapped=None, *,
                   min_frames: int = MIN_FRAMES,
                   min_mean: float = MIN_MEAN) -> np.ndarray:
    """Where a limb pair's distal joints (knee and ankle; elbow and wrist) are to be
    exchanged so that, in each run of ``edge_on`` frames, the limb the colour frame shows
    nearer the camera is of the body side that faces it.

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
        :func:`near_limb` of the pair in the fit's names (> 0: the fit's ``l_`` limb is nearer), NaN
        where unknown.
    edge_on : array_like of bool, shape (F,)
        Frames to name (runs of these are named).
    facing_right : array_like of bool, shape (F,)
        The body faces image right.
    link : array_like of bool, shape (F,)
        Frames whose limbs the linking exchanges.
    swapped : array_like of bool, shape (F,), optional
        Frames whose image-side names the view swaps to name the body's sides
        (:func:`vidcap.video.lift.assign_sides`); none by default (a side view keeps
        the fit's names).
    min_frames, min_mean : see :data:`MIN_FRAMES`, :data:`MIN_MEAN`.

    Returns
    -------
    numpy.ndarray of bool, shape (F,)
        Limbs exchanged against the fit's names; False outside the named runs.
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


def frame_arm_edges(frame, j2, radius, torso_radius) -> tuple[np.ndarray, np.ndarray]:
    """The arms' counterpart of :func:`frame_leg_edges`: (2,) mean edge strength across
    the borders of the fit's l and r arms (upper arm and forearm, ``radius`` (2,) px)
    where they lie over the torso (pelvis to neck, ``torso_radius`` px), and (2,) how
    many border samples that was. The nearer arm covers the torso, the farther one is
    hidden behind it."""
    j = np.asarray(j2, float)
    torso = j[[JOINT_INDEX["pelvis"], JOINT_INDEX["neck"]]][None]
    strength, count = np.full(2, np.nan), np.zeros(2)
    for c, side in enumerate("lr"):
        pts = j[[JOINT_INDEX[f"{side}_{n}"] for n in ("shoulder", "elbow", "wrist")]]
        segs = np.stack([pts[:2], pts[1:]])
        if np.isfinite(segs).all() and np.isfinite(torso).all():
            strength[c], count[c] = border_edges(frame, segs, np.asarray(radius, float),
                                                 torso, np.array([float(torso_radius)]))
    return strength, count
