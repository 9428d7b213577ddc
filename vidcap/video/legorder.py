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

#: Where along each limb segment the border samples lie (0 its proximal joint, 1 the
#: distal one); the ends are left out (the rounded joints are not bands).
_ALONG = np.linspace(0.1, 0.9, 17)
#: Offsets of the border search, in units of the segment's radius from its axis: the
#: fitted border is a few pixels off (the 2D fit is 1-2 % of the height off). At each
#: offset, the edge is the colour's rate of change across the border less the mean of
#: its neighbours' (a ridge: a shading step, not the smooth shading of a cylinder, which
#: is steep near its own outline). The legs per frame on the fitted 2D of the tuning
#: renders and walk_side (197 frames with a cue; ``benchmarks/solve_fitted.py --legs``):
#: 78 % of frames right; a Sobel gradient with its ridge 79 %, without 58 % (71 % with a
#: search of 0.7-1.3 radii).
_ACROSS = np.array([0.55, 0.7, 0.85, 1.0, 1.15, 1.3, 1.45])
#: The samples along each search line: two more at each end than the search, for the
#: derivative and its ridge.
_LINE = np.r_[_ACROSS[0] - 2 * (_ACROSS[1] - _ACROSS[0]), _ACROSS[0] - (_ACROSS[1] - _ACROSS[0]),
              _ACROSS, _ACROSS[-1] + (_ACROSS[1] - _ACROSS[0]),
              _ACROSS[-1] + 2 * (_ACROSS[1] - _ACROSS[0])]
#: Each search line's colours are averaged over lines this many pixels along the
#: border on either side, weighted 1-2-1 (as a Sobel operator smooths).
_ALONG_SMOOTH = np.array([-2.0, 0.0, 2.0])
_SMOOTH_W = np.array([0.25, 0.5, 0.25], np.float32)
#: The search's smallest spacing (pixels): a ridge needs its neighbours a pixel or more
#: away (a thin arm's 0.15 radii is less).
MIN_SPACING = 1.5
#: A border sample counts as over the other leg where its nominal point (offset 1) lies
#: this many of the other leg's radii from that leg's axis, or less: well inside, so the
#: other leg's own borders are outside the search.
INSIDE = 0.6
#: The four limbs' joints (proximal, middle, distal): arms l, r; legs l, r (the rows of
#: :func:`frame_limb_edges`' (2 pairs, 2 sides) outputs, flattened).
_LIMBS = np.array([[JOINT_INDEX[f"{side}_{j}"] for j in joints] for joints in
                   (("shoulder", "elbow", "wrist"), ("hip", "knee", "ankle")) for side in "lr"])
_TORSO = np.array([JOINT_INDEX["pelvis"], JOINT_INDEX["neck"]])


def _plan(j2, radii):
    """The search lines of frames (n,) with joints ``j2`` (n, 15, 2) and ``radii`` (n,
    5), vectorised over the frames (no pixels are read): per frame and limb (arms l, r;
    legs l, r) and border sample (P), where the line starts (n, 4, P, 2 px), its outward
    normal (n, 4, P, 2), its segment's radius (n, 4, P px) and whether the sample lies
    over the torso (arms) or the other leg (legs) (n, 4, P bool)."""
    j2 = np.asarray(j2, float)
    r5 = np.asarray(radii, float)
    n = len(j2)
    pts = j2[:, _LIMBS]  # (n, 4, 3, 2)
    a, d = pts[:, :, :2], pts[:, :, 1:] - pts[:, :, :2]  # (n, 4 limbs, 2 segs, 2)
    rad = np.stack([r5[:, :2], r5[:, :2], r5[:, 3:], r5[:, 3:]], 1)  # (n, 4, 2)
    torso = np.broadcast_to(j2[:, None, _TORSO], (n, 2, 2, 2))  # twice, as two segments
    cover = np.stack([torso, torso, pts[:, 3, [[0, 1], [1, 2]]], pts[:, 2, [[0, 1], [1, 2]]]],
                     1)  # (n, 4, M=2, 2 ends, 2)
    cover_r = np.stack([r5[:, [2, 2]], r5[:, [2, 2]], r5[:, 3:], r5[:, 3:]], 1)  # (n, 4, M)
    u = d / np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-9)
    nrm = np.stack([-u[..., 1], u[..., 0]], -1)
    T = len(_ALONG)
    shape = (n, 4, 2, T, 2, 2)  # frames, limbs, segments, along, sides, xy
    base = np.broadcast_to((a[:, :, :, None] + _ALONG[:, None] * d[:, :, :, None])[
        :, :, :, :, None], shape).reshape(n, 4, -1, 2)
    odir = np.broadcast_to(np.array([-1.0, 1.0])[:, None] * nrm[:, :, :, None, None],
                           shape).reshape(n, 4, -1, 2)
    r = np.broadcast_to(rad[:, :, :, None, None], shape[:-1]).reshape(n, 4, -1)
    nominal = base + r[..., None] * odir  # (n, 4, P, 2)
    ca, cd = cover[..., 0, :], cover[..., 1, :] - cover[..., 0, :]  # (n, 4, M, 2)
    rel = nominal[:, :, :, None] - ca[:, :, None]  # (n, 4, P, M, 2)
    t = np.clip((rel * cd[:, :, None]).sum(-1)
                / np.maximum((cd * cd).sum(-1), 1e-9)[:, :, None], 0.0, 1.0)
    off = rel - t[..., None] * cd[:, :, None]
    dist2 = off[..., 0] ** 2 + off[..., 1] ** 2
    with np.errstate(invalid="ignore"):
        inside = (dist2 <= (INSIDE * cover_r[:, :, None]) ** 2).any(-1)
    return base, odir, r, inside


class _Chunk:
    """The search lines of up to :data:`_CHUNK` frames as pixel indices (planned at once,
    from the joints alone), the colours read there as each frame passes, and the edges
    measured from them at once when the chunk is done (:meth:`finish`)."""

    def __init__(self, j2, radii, shape):
        H, W = shape[:2]
        base, odir, r, inside = _plan(j2, radii)
        self.n = len(j2)
        f, limb, k = np.nonzero(inside)
        ri, od = r[f, limb, k][:, None], odir[f, limb, k]
        self.unit = np.maximum(ri, MIN_SPACING / (_ACROSS[1] - _ACROSS[0]))  # (K, 1)
        offset = ri + (_LINE[None] - 1.0) * self.unit  # (K, line) px from the axis
        line = base[f, limb, k][:, None] + offset[..., None] * od[:, None]  # (K, line, 2)
        along = np.stack([od[:, 1], -od[:, 0]], -1)[:, None, None] * _ALONG_SMOOTH[:, None]
        # nearest pixel (+0.5 and truncation: a point less than half a pixel off the
        # frame's top or left edge reads the edge pixel)
        xy = (line[:, :, None] + (along + 0.5)).astype(np.int32)  # (K, line, 3, 2)
        self.ok = (xy[..., 0] >= 0) & (xy[..., 0] < W) & (xy[..., 1] >= 0) & (xy[..., 1] < H)
        self.flat = np.where(self.ok, xy[..., 1] * W + xy[..., 0], 0)
        self.row = f * 4 + limb  # (K,) frame and limb of each sample
        self.start = np.searchsorted(f, np.arange(self.n + 1))
        self.colours = np.zeros(self.flat.shape + (3,), np.uint8)
        self.seen = np.zeros(self.n, bool)
        self.shape = (H, W)

    def read(self, i, frame):
        """Read the colours of chunk frame ``i`` (H, W, 3) uint8."""
        if frame.shape[:2] != self.shape:
            return
        a, b = self.start[i], self.start[i + 1]
        self.colours[a:b] = np.ascontiguousarray(frame).reshape(-1, 3)[self.flat[a:b]]
        self.seen[i] = True

    def finish(self):
        """(n, 2, 2) strengths and counts of the chunk's frames (NaN, 0 where unseen)."""
        c = self.colours.astype(np.float32)
        c[~self.ok] = np.nan
        w = _SMOOTH_W
        c = w[0] * c[:, :, 0] + w[1] * c[:, :, 1] + w[2] * c[:, :, 2]  # (K, line, 3 channels)
        # the colour's rate of change across the border at each search offset, then its
        # ridge (the step of a border, not a cylinder's smooth shading)
        step = (c[:, 2:] - c[:, :-2]) / (2.0 * self.unit[..., None])
        across = np.sqrt((step * step).sum(-1))
        across = across[:, 1:-1] - 0.5 * (across[:, :-2] + across[:, 2:])
        best = np.max(np.where(np.isfinite(across), across, -np.inf), axis=1)
        use = np.isfinite(best) & self.seen[self.row // 4]
        count = np.bincount(self.row[use], minlength=4 * self.n).astype(float)
        total = np.bincount(self.row[use], weights=np.maximum(best[use], 0.0),
                            minlength=4 * self.n)
        strength = np.where(count > 0, total / np.maximum(count, 1.0), np.nan)
        return strength.reshape(-1, 2, 2), count.reshape(-1, 2, 2)


def frame_limb_edges(frame, j2, radii) -> tuple[np.ndarray, np.ndarray]:
    """One frame of :func:`limb_edges`: (2 pairs: arms, legs; 2 sides: l, r) mean edge
    strengths across the borders of the fit's arms where they lie over the torso and of
    its legs where they lie over the other leg, and (2, 2) how many border samples each
    is over; NaN strength where none.

    Parameters
    ----------
    frame : numpy.ndarray, shape (H, W, 3) uint8
    j2 : numpy.ndarray, shape (15, 2)
        The frame's fitted joints, pixels.
    radii : array_like, shape (5,)
        :data:`RADII`, pixels.
    """
    frame = np.asarray(frame)
    chunk = _Chunk(np.asarray(j2, float)[None], np.asarray(radii, float)[None], frame.shape)
    chunk.read(0, frame)
    strength, count = chunk.finish()
    return strength[0], count[0]


#: The columns of :func:`limb_radii`.
RADII = ("upper_arm", "lower_arm", "torso", "upper_leg", "lower_leg")


def limb_radii(model_height, body: BodyModel | None = None) -> np.ndarray:
    """The radii (F, 5) in pixels of :data:`RADII` at the height in pixels the 2D fit
    drew its model in each frame (``model_height`` (F,))."""
    body = body or BodyModel()
    px = np.asarray(model_height, float).reshape(-1, 1) / body.height
    names = ("l_upper_arm", "l_lower_arm", "torso", "l_upper_leg", "l_lower_leg")
    return px * np.array([body.radius(n) for n in names])[None]


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


def tap_limb_edges(frames, joints2d, radii, strength, count, lines=None):
    """Yield ``frames`` unchanged, filling ``strength`` and ``count`` (F, 2, 2) (as
    :func:`limb_edges` returns them) as they pass, :data:`_CHUNK` frames at a time (all
    of them once ``frames`` is consumed to its end): one decode of the clip serves this
    cue and the front/back one (:func:`vidcap.video.frontback.arm_visibility`). Each
    frame costs one gather of the pixels its search lines cross. ``lines``: the
    search lines already planned (:func:`plan_lines`, for frames of this size; read
    once)."""
    j2 = np.asarray(joints2d, float)
    rad = np.asarray(radii, float)
    chunk, first = None, 0

    def finish():
        if chunk is not None:
            strength[first:first + chunk.n], count[first:first + chunk.n] = chunk.finish()

    for k, frame in enumerate(frames):
        if k < len(j2) and frame is not None:
            if chunk is None or k >= first + chunk.n:  # the next frames' lines at once
                finish()
                first = k - k % _CHUNK
                chunk = lines[first // _CHUNK] if lines is not None and \
                    lines[first // _CHUNK].shape == np.shape(frame)[:2] else \
                    _Chunk(j2[first:first + _CHUNK], rad[first:first + _CHUNK], np.shape(frame))
            chunk.read(k - first, np.asarray(frame))
        yield frame
    finish()


#: Frames whose search lines are planned at once (:func:`tap_limb_edges`).
_CHUNK = 128


def plan_lines(joints2d, radii, shape) -> list:
    """The search lines of :func:`tap_limb_edges` for the 2D joints (F, 15, 2) and
    :func:`limb_radii` (F, 5) on frames of ``shape`` (H, W), planned :data:`_CHUNK` frames
    at a time: for :func:`read_bounds` and then, the same, for ``tap_limb_edges``."""
    j2, rad = np.asarray(joints2d, float), np.asarray(radii, float)
    return [_Chunk(j2[s:s + _CHUNK], rad[s:s + _CHUNK], shape)
            for s in range(0, len(j2), _CHUNK)]


def read_bounds(lines) -> np.ndarray:
    """The box of the pixels :func:`tap_limb_edges` reads in each frame along ``lines``
    (:func:`plan_lines`), (F, 4) ``x_min, x_max, y_min, y_max`` px (inclusive; ``inf,
    -inf`` where it reads none)."""
    from vidcap.video.frontback import pixel_bounds

    out = np.tile([np.inf, -np.inf, np.inf, -np.inf], (sum(c.n for c in lines), 1))
    first = 0
    for chunk in lines:
        if chunk.flat.size:
            W = chunk.shape[1]
            x = np.where(chunk.ok, chunk.flat % W, -1)
            y = np.where(chunk.ok, chunk.flat // W, -1)
            per_line = pixel_bounds(x, y, chunk.shape)  # (K, 4), the lines frame by frame
            has = chunk.start[1:] > chunk.start[:-1]
            at = chunk.start[:-1][has]
            rows = first + np.flatnonzero(has)
            out[rows, 0] = np.minimum.reduceat(per_line[:, 0], at)
            out[rows, 1] = np.maximum.reduceat(per_line[:, 1], at)
            out[rows, 2] = np.minimum.reduceat(per_line[:, 2], at)
            out[rows, 3] = np.maximum.reduceat(per_line[:, 3], at)
        first += chunk.n
    return out


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
                   min_frames: int | None = None,
                   min_mean: float | None = None) -> np.ndarray:
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
    min_frames = MIN_FRAMES if min_frames is None else min_frames
    min_mean = MIN_MEAN if min_mean is None else min_mean
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
