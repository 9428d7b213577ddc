"""Batched rasteriser of the 2D body model, and silhouette normalisation.

The 2D body model is seed 004's ten cylinders seen in the image plane: every segment
is drawn as a band of the Table 3.2 width around the line from its proximal to its
distal joint, either a rectangle or a capsule (a rectangle with round ends). Many
candidate poses are drawn in one call, as an array of boolean masks ``(B, h, w)``,
so a search can score all its candidates in one vectorised operation.

Coordinates
-----------
Points are ``(x, y)`` in pixels, x right, y down, with pixel ``(row i, column j)``
centred on ``(j, i)`` (the OpenCV convention). Segment *angles* follow
:data:`vidcap.body.IMAGE_ANGLE_LIMITS_DEG`: counter-clockwise from the image's +x axis
with y pointing **up**, in radians inside the library, so an angle ``a`` is the
direction ``(cos a, -sin a)`` in pixel coordinates (``pi/2`` = straight up,
``3 pi/2`` = straight down).

The 2D skeleton
---------------
``pelvis`` is the root; the neck sits ``torso length x foreshortening`` along the
torso angle, the head top beyond it along the head angle. The shoulders sit at the
neck and the hips at the pelvis, displaced sideways (perpendicular to the torso
axis) by ``spread`` times the body model's lateral offsets (:attr:`BodyModel.
shoulder_half_width`, :attr:`BodyModel.hip_half_width`): ``spread = 0`` is a pure side
view (both shoulders on the torso axis), ``spread = 1`` a front or back view. The
``l_`` limbs are displaced toward the image's left: during 2D fitting ``l_*`` means
*the limb on the image's left* (seed 004 section 3.1.4), not the performer's left.

Normalisation
-------------
:func:`normalise_mask` (:mod:`vidcap.video.fit.normalise`, re-exported here) crops a
silhouette to its bounding box and resizes it to a fixed height (seed 004 section
4.2); it shares the rasteriser's pixel convention.

Speed
-----
Searches score candidates with :func:`span_counts`: every segment covers one run
of columns per row (:func:`segment_spans`), so the pixels a candidate covers, and
how many of them are silhouette, are read from row prefix sums without drawing a
mask. It and :func:`draw_segments` run as numba kernels (``vidcap/video/fit/_kernels.py``,
loaded on first use, cached on disk) when numba is importable, else as numpy code
giving the same integers and pixels.
"""

from __future__ import annotations

import functools

import numpy as np

from vidcap.body import (
    JOINT_INDEX,
    SEGMENT_JOINTS,
    SEGMENT_NAMES,
    SEGMENTS,
    BodyModel,
)
from vidcap.video.fit.normalise import NormalisedMask, normalise_mask  # noqa: F401  (re-exported)
from vidcap.video.fit.similarity import similarity_from_counts

#: Joint index of each segment's proximal and distal joint, (S, 2).
_PROX = SEGMENT_JOINTS[:, 0]
_DIST = SEGMENT_JOINTS[:, 1]

#: Limb chains: (segment index, parent joint index) in the order joints are placed.
_SEG = {name: i for i, name in enumerate(SEGMENT_NAMES)}

def direction(angles: np.ndarray) -> np.ndarray:
    """Unit pixel-space direction ``(x, y)`` of image-plane angles (y up), shape (..., 2)."""
    a = np.asarray(angles, dtype=float)
    out = np.empty((*a.shape, 2))  # filled in place: np.stack's set-up dominated here
    np.cos(a, out=out[..., 0])
    np.negative(np.sin(a, out=out[..., 1]), out=out[..., 1])
    return out


def image_angle(vectors: np.ndarray) -> np.ndarray:
    """Image-plane angle in [0, 2 pi) of pixel-space vectors ``(..., 2)`` (y down)."""
    v = np.asarray(vectors, dtype=float)
    return np.mod(np.arctan2(-v[..., 1], v[..., 0]), 2 * np.pi)


def model_dimensions(height_px: float, body: BodyModel | None = None):
    """Segment lengths and radii, and lateral joint offsets, in pixels.

    Parameters
    ----------
    height_px : float
        Body height in pixels.
    body : BodyModel, optional
        Proportions (default: the seed's Table 3.1/3.2 ratios).

    Returns
    -------
    lengths, radii : numpy.ndarray, shape (10,)
    shoulder, hip : float
        Lateral distance of each shoulder (hip) from the torso axis at spread 1.
    """
    height, lengths, radii, shoulder, hip = (_default_body() if body is None
                                             else _body_metres(body))
    k = height_px / height
    return lengths * k, radii * k, shoulder * k, hip * k


def model_shoulder(lateral: float, height_px: float, body: BodyModel | None = None):
    """The shoulder joints from the neck, pixels, as :func:`pose_joints` takes them.

    Parameters
    ----------
    lateral : float
        Their lateral offset at spread 1, pixels (:func:`model_dimensions`' ``shoulder``).
    height_px : float
        Body height in pixels.
    body : BodyModel, optional
        Proportions (default: the seed's, whose shoulders are the torso's top corners).

    Returns
    -------
    numpy.ndarray, shape (2,)
        ``lateral`` and the drop down the torso's axis
        (:attr:`vidcap.body.BodyModel.shoulder_drop`).
    """
    drop = 0.0 if body is None else body.shoulder_drop * (height_px / body.height)
    return np.array([lateral, drop])


def _shoulder_pair(shoulder) -> np.ndarray:
    """``shoulder`` as (lateral, drop) float64: a number is a lateral offset, no drop."""
    pair = np.zeros(2)
    pair[:np.size(shoulder)] = np.ravel(np.asarray(shoulder, dtype=float))[:2]
    return pair


def _body_metres(body: BodyModel):
    """(height, lengths, radii, shoulder, hip) of ``body`` in metres."""
    return (body.height, body.segment_lengths(), body.segment_radii(),
            body.shoulder_half_width, body.hip_half_width)


@functools.lru_cache(maxsize=1)
def _default_body():
    """:func:`_body_metres` of the default body (built once per process; read-only)."""
    out = _body_metres(BodyModel())
    for a in out[1:3]:
        a.setflags(write=False)
    return out


def pose_joints(root, angles, foreshortening, spread, lengths, shoulder, hip) -> np.ndarray:
    """Joint positions of 2D model poses (vectorised over any leading batch shape).

    Parameters
    ----------
    root : array_like, shape (..., 2)
        Pelvis ``(x, y)`` in pixels.
    angles : array_like, shape (..., 10)
        Segment image-plane angles in radians (:data:`SEGMENT_NAMES` order).
    foreshortening : array_like, shape (..., 10)
        Apparent length / true length of every segment, in (0, 1].
    spread : array_like, shape (...)
        Lateral spread of shoulders and hips, 0 (side view) to 1 (front view).
    lengths : array_like, shape (10,)
        Segment lengths in pixels.
    shoulder, hip : float
        Lateral offsets of shoulders and hips in pixels at spread 1; ``shoulder`` may be
        (lateral, drop below the neck down the torso's axis) (:func:`model_shoulder`).

    Returns
    -------
    numpy.ndarray, shape (..., 15, 2)
        Joints in :data:`vidcap.body.JOINT_NAMES` order, pixels.
    """
    angles = np.asarray(angles, dtype=float)
    fs = np.asarray(foreshortening, dtype=float)
    root = np.asarray(root, dtype=float)
    spread = np.asarray(spread, dtype=float)
    shape = np.broadcast_shapes(root.shape[:-1], angles.shape[:-1], fs.shape[:-1], spread.shape)
    vec = direction(angles) * (fs * np.asarray(lengths))[..., None]  # (..., 10, 2)
    # Image-left perpendicular of the torso axis: the torso points up (a ~ 90 deg), its
    # left in the image is the direction rotated +90 deg (counter-clockwise, y up).
    left = direction(angles[..., _SEG["torso"]] + np.pi / 2) * spread[..., None]
    lateral, drop = _shoulder_pair(shoulder)
    lat_s, lat_h = lateral * left, hip * left
    # every joint = its parent + one offset, placed level by level down the tree
    offs = np.empty((*shape, 15, 2))
    offs[..., _BONE_JOINTS, :] = vec[..., _BONE_SEGS, :]
    offs[..., _LATERAL, :] = np.stack([lat_s, -lat_s, lat_h, -lat_h], axis=-2)
    if drop:  # both shoulders down the torso's axis from the neck
        down = drop * direction(angles[..., _SEG["torso"]])
        offs[..., _LATERAL[:2], :] -= down[..., None, :]
    j = np.empty((*shape, 15, 2))
    j[..., JOINT_INDEX["pelvis"], :] = root
    for child, parent in _LEVELS:
        j[..., child, :] = j[..., parent, :] + offs[..., child, :]
    return j


_LATERAL = np.array([JOINT_INDEX[n] for n in ("l_shoulder", "r_shoulder", "l_hip", "r_hip")])
#: Joints placed along a segment from its proximal joint, and those segments.
_BONE_SEGS = np.array([s for s in range(10) if _DIST[s] not in _LATERAL])
_BONE_JOINTS = _DIST[_BONE_SEGS]


def _levels():
    """(children, parents) index arrays of the 2D skeleton, one pair per tree level."""
    parent = {int(d): int(p) for p, d in zip(_PROX, _DIST, strict=True)}
    for n in ("l_shoulder", "r_shoulder"):
        parent[JOINT_INDEX[n]] = JOINT_INDEX["neck"]
    for n in ("l_hip", "r_hip"):
        parent[JOINT_INDEX[n]] = JOINT_INDEX["pelvis"]
    depth = {JOINT_INDEX["pelvis"]: 0}
    while len(depth) < len(parent) + 1:
        for c, p in parent.items():
            if p in depth and c not in depth:
                depth[c] = depth[p] + 1
    levels = []
    for d in range(1, max(depth.values()) + 1):
        kids = np.array(sorted(c for c in parent if depth[c] == d))
        levels.append((kids, np.array([parent[c] for c in kids])))
    return tuple(levels)


_LEVELS = _levels()


def _kernel_tables():
    """(order, parent, kind) of the compiled :func:`pose_joints_batch` kernel."""
    order = np.concatenate([kids for kids, _ in _LEVELS]).astype(np.int64)
    parent = np.zeros(15, np.int64)
    kind = np.zeros(15, np.int64)
    for kids, parents in _LEVELS:
        parent[kids] = parents
    kind[_BONE_JOINTS] = _BONE_SEGS
    kind[_LATERAL] = [-1, -2, -3, -4]  # l/r shoulder, l/r hip: +/- the lateral offset
    return order, parent, kind


_KERNEL_TABLES = _kernel_tables()


def pose_joints_batch(root, angles, foreshortening, spread, lengths, shoulder, hip) -> np.ndarray:
    """:func:`pose_joints` for one flat batch, with less per-call overhead.

    Parameters
    ----------
    root : numpy.ndarray, shape (B, 2)
    angles, foreshortening : numpy.ndarray, shape (B, 10)
    spread : numpy.ndarray, shape (B,)
    lengths : numpy.ndarray, shape (10,)
    shoulder : float or array_like, shape (2,)
    hip : float
        As in :func:`pose_joints`.

    Returns
    -------
    numpy.ndarray, shape (B, 15, 2)
        The same floats as :func:`pose_joints` (the compiled kernel repeats its
        operations; without numba it is called).
    """
    kernels = _kernels()
    if kernels is None:
        return pose_joints(root, angles, foreshortening, spread, lengths, shoulder, hip)
    angles = _carray(angles, np.float64)
    # the same numpy calls as direction() makes, so the same sines and cosines
    c, s = np.cos(angles), np.sin(angles)
    left = angles[:, _SEG["torso"]] + np.pi / 2
    out = np.empty((angles.shape[0], 15, 2))
    kernels.joints(_carray(root, np.float64), c, s, np.cos(left), np.sin(left),
               _carray(foreshortening, np.float64), _carray(spread, np.float64),
               _carray(lengths, np.float64), _shoulder_pair(shoulder), float(hip),
               *_KERNEL_TABLES, out)
    return out

#: Segments moved when a segment's own parameter changes: itself and its descendants.
DESCENDANTS: dict[int, tuple[int, ...]] = {
    _SEG["torso"]: tuple(range(10)),
    _SEG["head"]: (_SEG["head"],),
    **{
        _SEG[f"{s}_upper_{p}"]: (_SEG[f"{s}_upper_{p}"], _SEG[f"{s}_lower_{p}"])
        for s in "lr"
        for p in ("arm", "leg")
    },
    **{_SEG[f"{s}_lower_{p}"]: (_SEG[f"{s}_lower_{p}"],) for s in "lr" for p in ("arm", "leg")},
}


def draw_segments(
    p0: np.ndarray,
    p1: np.ndarray,
    radii: np.ndarray,
    shape: tuple[int, int],
    *,
    origin: tuple[int, int] = (0, 0),
    caps: bool = True,
) -> np.ndarray:
    """Draw a batch of segment sets, each set's union into one mask.

    Parameters
    ----------
    p0, p1 : numpy.ndarray, shape (B, K, 2)
        Proximal and distal ends ``(x, y)`` of K segments for each of B candidates,
        in pixels of the full image.
    radii : numpy.ndarray, shape (K,)
        Half-width of each segment in pixels.
    shape : (int, int)
        ``(h, w)`` of the window drawn.
    origin : (int, int)
        ``(x0, y0)``: the full-image pixel of the window's top-left corner.
    caps : bool
        Round ends (capsules) if true, square-cut rectangles if false.

    Returns
    -------
    numpy.ndarray, shape (B, h, w), bool
        ``True`` where a pixel centre lies inside any of the candidate's segments.
    """
    h, w = shape
    kernels = _kernels()
    if kernels is not None:  # the same pixels, filled span by span
        p0 = _carray(p0, np.float64)
        p1 = _carray(p1, np.float64)
        r = _radii(radii, *p0.shape[:2])
        out = np.zeros((p0.shape[0], h, w), dtype=bool)
        kernels.draw(p0, p1, r, float(origin[0]), float(origin[1]), bool(caps), out)
        return out
    first, last = segment_spans(p0, p1, radii, np.arange(origin[1], origin[1] + h), caps=caps)
    cols = np.arange(origin[0], origin[0] + w)
    inside = (cols >= first[..., None]) & (cols <= last[..., None])  # (B, K, h, w)
    return inside.any(axis=1)


def segment_spans(p0, p1, radii, rows, *, caps: bool = True):
    """Row spans of a batch of segments: which pixel columns each one covers per row.

    A capsule or rectangle is convex, so on every scan line the pixel centres it
    covers form one run of columns. Computing the runs analytically (rather than
    testing every pixel) lets a search count covered pixels from row prefix sums.

    Parameters
    ----------
    p0, p1 : numpy.ndarray, shape (B, K, 2)
        Segment ends ``(x, y)`` in pixels.
    radii : numpy.ndarray, shape (K,) or (B, K)
        Half-widths in pixels.
    rows : numpy.ndarray of int, shape (R,)
        The rows (pixel y) to scan.
    caps : bool
        Capsules (true) or rectangles (false), as in :func:`draw_segments`.

    Returns
    -------
    first, last : numpy.ndarray of int, shape (B, K, R)
        First and last covered column per row; ``last < first`` where a row is not
        covered. Columns are not clipped to any image.
    """
    p0 = np.asarray(p0, dtype=np.float64)
    p1 = np.asarray(p1, dtype=np.float64)
    r = np.asarray(radii, dtype=np.float64)
    r = r[None, :, None] if r.ndim == 1 else r[:, :, None]
    y = np.asarray(rows, dtype=np.float64)[None, None, :]
    v = p1 - p0
    norm = np.sqrt((v * v).sum(-1))[..., None]
    tiny = norm < 1e-9  # a point: any direction will do
    ux = np.where(tiny, 1.0, v[..., 0, None] / np.where(tiny, 1.0, norm))
    uy = np.where(tiny, 0.0, v[..., 1, None] / np.where(tiny, 1.0, norm))
    # Nudge zero components so each constraint below is a finite x-interval: a
    # coefficient of 1e-12 turns "all x" / "no x" into a huge / far-away interval.
    ux = np.where(np.abs(ux) < 1e-12, 1e-12, ux)
    uy = np.where(np.abs(uy) < 1e-12, 1e-12, uy)
    cx = 0.5 * (p0[..., 0, None] + p1[..., 0, None])
    dyc = y - 0.5 * (p0[..., 1, None] + p1[..., 1, None])  # (B, K, R)
    # With X = x - cx: along = X ux + dyc uy in [-L/2, L/2], across = X uy - dyc ux in [-r, r].
    # (1e-7 px of slack so pixel centres exactly on an edge count, as in a <= test)
    half_a = np.abs((0.5 * norm + 1e-7) / ux)
    half_c = np.abs((r + 1e-7) / uy)
    mid_a = cx - dyc * (uy / ux)
    mid_c = cx + dyc * (ux / uy)
    left = np.maximum(mid_a - half_a, mid_c - half_c)
    right = np.minimum(mid_a + half_a, mid_c + half_c)
    if caps:
        empty = left > right  # the rectangle misses this row: only the discs count
        left[empty], right[empty] = np.inf, -np.inf
        with np.errstate(invalid="ignore"):
            for q in (p0, p1):  # end discs; rows missing a disc give NaN, ignored by fmin
                h = np.sqrt(r * r - (y - q[..., 1, None]) ** 2)
                left = np.fmin(left, q[..., 0, None] - h)
                right = np.fmax(right, q[..., 0, None] + h)
    first = np.ceil(np.clip(left, -1e6, 1e6)).astype(np.int64)
    last = np.floor(np.clip(right, -1e6, 1e6)).astype(np.int64)
    return first, last


def draw_pose(joints: np.ndarray, radii: np.ndarray, shape: tuple[int, int], *,
              segments=None, caps: bool = True) -> np.ndarray:
    """Draw whole (or partial) 2D model poses into masks.

    Parameters
    ----------
    joints : numpy.ndarray, shape (B, 15, 2) or (15, 2)
        Joint positions in pixels.
    radii : numpy.ndarray, shape (10,)
        Segment half-widths in pixels.
    shape : (int, int)
        ``(h, w)`` of the output masks.
    segments : sequence of int, optional
        Segment indices to draw (default: all ten).
    caps : bool
        Capsules (true) or rectangles (false).

    Returns
    -------
    numpy.ndarray, shape (B, h, w) or (h, w), bool
    """
    joints = np.asarray(joints, dtype=float)
    single = joints.ndim == 2
    if single:
        joints = joints[None]
    seg = np.arange(10) if segments is None else np.asarray(segments, dtype=int)
    if seg.size == 0:
        out = np.zeros((joints.shape[0], *shape), dtype=bool)
    else:
        out = draw_segments(
            joints[:, _PROX[seg]], joints[:, _DIST[seg]], np.asarray(radii)[seg], shape, caps=caps
        )
    return out[0] if single else out


# --------------------------------------------------------------------------- span counting
@functools.lru_cache(maxsize=1)
def _kernels():
    """The compiled kernels (the module :mod:`vidcap.video.fit._kernels`), or None when numba
    is unavailable (then every caller takes its numpy path, with the same results)."""
    try:  # importing numba costs ~0.5 s: only when a kernel is first needed
        from vidcap.video.fit import _kernels as k
    except ImportError:  # pragma: no cover - numba is a declared dependency
        return None
    return k


def _carray(a, dtype) -> np.ndarray:
    """``a`` as a C-contiguous writable array of ``dtype`` (a copy only if needed)."""
    if (isinstance(a, np.ndarray) and a.dtype == dtype and a.flags.c_contiguous
            and a.flags.writeable):
        return a
    return np.array(a, dtype=dtype, order="C")


def _radii(radii, n_b: int, n_k: int) -> np.ndarray:
    """Radii (K,) or (B, K) as a fresh C-contiguous (B, K) float64 array."""
    out = np.empty((n_b, n_k))
    out[...] = radii
    return out


def row_prefix_sums(weights: np.ndarray) -> np.ndarray:
    """Row prefix sums of per-pixel weights, the table :func:`span_counts` reads.

    Parameters
    ----------
    weights : numpy.ndarray, shape (..., C, h, w), bool or int
        C weight channels per pixel.

    Returns
    -------
    numpy.ndarray, shape (..., C, h, w + 1), int32
        ``out[..., c, y, x]`` = sum of ``weights[..., c, y, :x]``.
    """
    weights = np.asarray(weights)
    out = np.zeros((*weights.shape[:-1], weights.shape[-1] + 1), np.int32)
    np.cumsum(weights, axis=-1, out=out[..., 1:])
    return out


def span_counts(p0, p1, radii, cum, *, rows=None, table=None, caps: bool = True) -> np.ndarray:
    """Weighted pixel counts under the union of each candidate's segments (no masks drawn).

    For every candidate, the pixels covered by any of its K segments (exactly the
    pixels :func:`draw_segments` sets) are summed over C weight channels, read from
    row prefix sums: on each row every segment covers one run of columns
    (:func:`segment_spans`), the runs are merged and each merged run costs one
    difference per channel. With numba this is one compiled pass over candidates,
    rows and segments; without it the masks are drawn and summed with numpy (the
    same integers).

    Parameters
    ----------
    p0, p1 : numpy.ndarray, shape (B, K, 2)
        Segment ends ``(x, y)`` in pixels of the table's image.
    radii : numpy.ndarray, shape (K,) or (B, K)
        Half-widths in pixels.
    cum : numpy.ndarray, shape (C, h, w + 1) or (T, C, h, w + 1), int32
        Row prefix sums of C per-pixel weights (:func:`row_prefix_sums`), one table
        or T tables.
    rows : (int, int), optional
        Only rows ``rows[0] <= y < rows[1]`` are counted (default: all ``h``).
    table : numpy.ndarray of int, shape (B,), optional
        Which of the T tables each candidate is counted against (default: table 0).
    caps : bool
        Capsules (true) or rectangles (false).

    Returns
    -------
    numpy.ndarray, shape (B, C), int64
    """
    # one compiled signature: C-contiguous, writable arrays of fixed dtypes
    p0 = _carray(p0, np.float64)
    p1 = _carray(p1, np.float64)
    n_b, n_k = p0.shape[:2]
    cum = np.asarray(cum)
    if cum.ndim == 3:
        cum = cum[None]
    cum = _carray(cum, np.int32)
    h = cum.shape[2]
    y0, y1 = (0, h) if rows is None else (max(0, int(rows[0])), min(h, int(rows[1])))
    radii = _radii(radii, n_b, n_k)
    table = np.zeros(n_b, np.int64) if table is None else _carray(table, np.int64)
    out = np.zeros((n_b, cum.shape[1]), np.int64)
    if y1 <= y0 or n_b == 0 or n_k == 0:
        return out
    kernels = _kernels()
    if kernels is not None:
        kernels.counts(p0, p1, radii, table, cum, y0, y1, bool(caps), out)
        return out
    w = cum.shape[3] - 1
    first, last = segment_spans(p0, p1, radii, np.arange(y0, y1), caps=caps)  # (B, K, R)
    cols = np.arange(w)
    inside = ((cols >= first[..., None]) & (cols <= last[..., None])).any(axis=1)  # (B, R, w)
    weights = np.diff(cum[:, :, y0:y1], axis=3)  # (T, C, R, w)
    return np.einsum("brx,bcrx->bc", inside.astype(np.int64), weights[table].astype(np.int64))


def span_similarity(p0, p1, radii, cum, a, m_base, i_base, *, rows, table,
                    caps: bool = True) -> np.ndarray:
    """Eq. 3.3's S of candidates that add segments to a fixed part of the model.

    One call per batch of a search: :func:`span_counts` of what each candidate's
    segments add to the model and to its overlap with the silhouette, then
    :func:`vidcap.video.fit.similarity.similarity_from_counts` (the same floats), in one
    compiled pass when numba is available.

    Parameters
    ----------
    p0, p1 : numpy.ndarray, shape (B, K, 2), float64, C-contiguous
        Segment ends of the moving segments.
    radii : numpy.ndarray, shape (T, K), float64
        Half-widths, per table.
    cum : numpy.ndarray, shape (T, 2, h, w + 1), int32
        Row prefix sums of the pixels not yet in the model (channel 0) and of those
        that are silhouette (channel 1), one table per fixed part.
    a : int
        Silhouette pixels counted (in ``rows``).
    m_base, i_base : numpy.ndarray, shape (T,), int64
        Model and overlap pixels of each fixed part.
    rows : (int, int)
        Only rows ``rows[0] <= y < rows[1]`` are counted.
    table : numpy.ndarray, shape (B,), int64
        The table of every candidate.
    caps : bool
        Capsules (true) or rectangles (false).

    Returns
    -------
    numpy.ndarray, shape (B,)
        S of every candidate.
    """
    kernels = _kernels()
    n_b = p0.shape[0]
    y0, y1 = max(0, int(rows[0])), min(cum.shape[2], int(rows[1]))
    if kernels is None or y1 <= y0 or n_b == 0:
        d = span_counts(p0, p1, radii[table], cum, rows=(y0, y1), table=table, caps=caps)
        return similarity_from_counts(a, m_base[table] + d[:, 0], i_base[table] + d[:, 1])
    x = np.empty(n_b)
    q = np.empty(n_b)
    kernels.similarity_terms(p0, p1, radii, table, cum, y0, y1, bool(caps), int(a), m_base,
                             i_base, x, q)
    return np.exp(x) * q


def limb_similarity(values, form, scale, start, old_end, p0s, p1s, own, radii, cum, a, m_base,
                    i_base, *, rows, caps: bool = True) -> np.ndarray:
    """:func:`span_similarity` of candidates that move one limb segment's distal end.

    Parameters
    ----------
    values : numpy.ndarray, shape (B,)
        The candidates: angles in radians (``form='angle'``) or length ratios
        (``form='ratio'``).
    form : {'angle', 'ratio'}
        The segment's proximal -> distal vector is ``direction(values) * scale``
        (``scale`` a length in pixels) or ``values[:, None] * scale`` (``scale`` a
        vector, shape (2,)).
    start, old_end : numpy.ndarray, shape (2,)
        The segment's proximal joint and its distal joint now.
    p0s, p1s : numpy.ndarray, shape (K, 2)
        Ends of the K moving segments now (the segment and its descendants); each
        shifts with the distal end, except the segment's own proximal end.
    own : numpy.ndarray of bool, shape (K,)
        Which moving segment is the segment itself.
    radii, cum, a, m_base, i_base, rows, caps
        As in :func:`span_similarity`, one table.

    Returns
    -------
    numpy.ndarray, shape (B,)
    """
    return limb_scorer(form, scale, start, old_end, p0s, p1s, own, radii, cum, a, m_base,
                       i_base, rows=rows, caps=caps)(values)


def _similarity_terms(kernel, values, angle, sign, k0, k1, rest) -> np.ndarray:
    """S (Eq. 3.3) of every candidate value from a compiled limb/group kernel: the kernel
    writes the exponent and the (1 - p) factor per candidate, flat (values.size,)."""
    x = np.empty(values.size)
    q = np.empty(values.size)
    if angle:  # direction(): (cos, -sin), times the length
        kernel(np.cos(values), np.sin(values), sign, k0, k1, *rest, x, q)
    else:
        kernel(values, values, sign, k0, k1, *rest, x, q)
    np.exp(x, out=x)
    x *= q
    return x


def limb_scorer(form, scale, start, old_end, p0s, p1s, own, radii, cum, a, m_base, i_base, *,
                rows, caps: bool = True):
    """:func:`limb_similarity` with everything but ``values`` bound once per search.

    Returns
    -------
    callable
        ``values (B,) -> S (B,)``.
    """
    kernels = _kernels()
    y0, y1 = max(0, int(rows[0])), min(cum.shape[2], int(rows[1]))
    if kernels is None or y1 <= y0:
        def numpy_path(values):
            values = np.asarray(values, dtype=np.float64)
            vec = direction(values) * scale if form == "angle" else values[:, None] * scale
            delta = start + vec - old_end  # (B, 2)
            p0 = p0s[None] + delta[:, None] * ~own[None, :, None]
            p1 = p1s[None] + delta[:, None]
            return span_similarity(p0, p1, radii, cum, a, m_base, i_base, rows=rows,
                                   table=np.zeros(len(values), np.int64), caps=caps)

        return numpy_path
    angle = form == "angle"
    sign, k0, k1 = (-1.0, float(scale), float(scale)) if angle else (1.0, float(scale[0]),
                                                                      float(scale[1]))
    rest = (start, old_end, _carray(p0s, np.float64), _carray(p1s, np.float64),
            (~np.asarray(own, bool)).astype(np.float64), _carray(radii, np.float64), cum,
            y0, y1, bool(caps), int(a), m_base, i_base)
    kernel = kernels.limb_terms

    def compiled(values):
        return _similarity_terms(kernel, _carray(values, np.float64), angle, sign, k0, k1, rest)

    return compiled


def group_similarity(values, form, scale, own0, own1, ch0, ch1, leaf, radii, cum, a, m_base,
                     i_base, *, caps: bool = True) -> np.ndarray:
    """:func:`span_similarity` of N limb searches' candidates at once (one table each).

    Parameters
    ----------
    values : numpy.ndarray, shape (N, B)
        Search n's candidates: angles (``form='angle'``) or length ratios
        (``form='ratio'``).
    form : {'angle', 'ratio'}
        Segment n's proximal -> distal vector is ``direction(values[n]) * scale[n]``
        (``scale`` (N,), lengths) or ``values[n, :, None] * scale[n]`` (``scale`` (N, 2)).
    own0, own1 : numpy.ndarray, shape (N, 2)
        Segment n's proximal and distal joints now.
    ch0, ch1 : numpy.ndarray, shape (N, 2)
        Its child segment's ends now (moved with the distal end unless ``leaf[n]``).
    leaf : numpy.ndarray of bool, shape (N,)
        Segments without a child.
    radii : numpy.ndarray, shape (N, K)
        Half-widths (segment, child); K = 1 if every segment is a leaf.
    cum, a, m_base, i_base, caps
        As in :func:`span_similarity`: table n for search n (:func:`group_tables`).

    Returns
    -------
    numpy.ndarray, shape (N, B)
    """
    return group_scorer(form, scale, own0, own1, ch0, ch1, leaf, radii, cum, a, m_base,
                        i_base, caps=caps)(values)


def group_scorer(form, scale, own0, own1, ch0, ch1, leaf, radii, cum, a, m_base, i_base, *,
                 caps: bool = True):
    """:func:`group_similarity` with everything but ``values`` bound once per search.

    Returns
    -------
    callable
        ``values (N, B) -> S (N, B)``.
    """
    kernels = _kernels()
    k = radii.shape[1]
    if kernels is None:
        def numpy_path(values):
            n, n_b = values.shape
            vec = (direction(values) * scale[:, None, None] if form == "angle"
                   else values[..., None] * scale[:, None, :])
            end = own0[:, None] + vec  # (N, B, 2)
            delta = end - own1[:, None]
            is_leaf = leaf[:, None, None]
            p0 = np.empty((n, n_b, k, 2))
            p1 = np.empty((n, n_b, k, 2))
            p0[:, :, 0] = own0[:, None]
            p1[:, :, 0] = end
            if k == 2:
                p0[:, :, 1] = np.where(is_leaf, own0[:, None], ch0[:, None] + delta)
                p1[:, :, 1] = np.where(is_leaf, end, ch1[:, None] + delta)
            s = span_similarity(p0.reshape(n * n_b, k, 2), p1.reshape(n * n_b, k, 2), radii,
                                cum, a, m_base, i_base, rows=(0, cum.shape[2]),
                                table=np.repeat(np.arange(n), n_b), caps=caps)
            return s.reshape(n, n_b)

        return numpy_path
    angle = form == "angle"
    if angle:
        sign, k0 = -1.0, _carray(scale, np.float64)
        k1 = k0
    else:
        sign = 1.0
        k0, k1 = np.ascontiguousarray(scale[:, 0]), np.ascontiguousarray(scale[:, 1])
    rest = (_carray(own0, np.float64), _carray(own1, np.float64), _carray(ch0, np.float64),
            _carray(ch1, np.float64), _carray(leaf, np.bool_), k, _carray(radii, np.float64),
            cum, 0, cum.shape[2], bool(caps), int(a), m_base, i_base)
    kernel = kernels.group_terms

    def compiled(values):
        values = _carray(values, np.float64)
        return _similarity_terms(kernel, values, angle, sign, k0, k1, rest).reshape(values.shape)

    return compiled


def pose_similarity(root, angles, foreshortening, spread, lengths, shoulder, hip, segments,
                    radii, cum, a, m_base, i_base, *, rows, caps: bool = True) -> np.ndarray:
    """:func:`span_similarity` of whole candidate poses (:func:`pose_joints_batch`).

    Parameters
    ----------
    root, angles, foreshortening, spread, lengths, shoulder, hip
        As in :func:`pose_joints_batch`: B candidate poses.
    segments : numpy.ndarray of int, shape (K,)
        The segments that move (drawn from each pose); the rest is in ``cum``.
    radii, cum, a, m_base, i_base, rows, caps
        As in :func:`span_similarity`, one table.

    Returns
    -------
    numpy.ndarray, shape (B,)
    """
    return pose_scorer(lengths, shoulder, hip, segments, radii, cum, a, m_base, i_base,
                       rows=rows, caps=caps)(root, angles, foreshortening, spread)


def pose_scorer(lengths, shoulder, hip, segments, radii, cum, a, m_base, i_base, *, rows,
                caps: bool = True):
    """:func:`pose_similarity` with everything but the poses bound once per search.

    Returns
    -------
    callable
        ``(root, angles, foreshortening, spread) -> S (B,)``.
    """
    kernels = _kernels()
    segments = np.asarray(segments, dtype=np.int64)
    y0, y1 = max(0, int(rows[0])), min(cum.shape[2], int(rows[1]))
    if kernels is None or y1 <= y0:
        def numpy_path(root, angles, foreshortening, spread):
            jb = pose_joints_batch(root, angles, foreshortening, spread, lengths, shoulder, hip)
            return span_similarity(_carray(jb[:, _PROX[segments]], np.float64),
                                   _carray(jb[:, _DIST[segments]], np.float64), radii, cum, a,
                                   m_base, i_base, rows=rows,
                                   table=np.zeros(len(root), np.int64), caps=caps)

        return numpy_path
    head = (_carray(lengths, np.float64), _shoulder_pair(shoulder), float(hip), *_KERNEL_TABLES,
            _PROX[segments].astype(np.int64), _DIST[segments].astype(np.int64),
            _carray(radii, np.float64), cum, y0, y1, bool(caps), int(a), m_base, i_base)
    kernel = kernels.pose_terms
    torso = _SEG["torso"]

    def compiled(root, angles, foreshortening, spread):
        angles = _carray(angles, np.float64)
        n_b = len(angles)
        left = angles[:, torso] + np.pi / 2  # as pose_joints_batch
        x = np.empty(n_b)
        q = np.empty(n_b)
        kernel(_carray(root, np.float64), np.cos(angles), np.sin(angles), np.cos(left),
               np.sin(left), _carray(foreshortening, np.float64), _carray(spread, np.float64),
               *head, x, q)
        np.exp(x, out=x)
        x *= q
        return x

    return compiled


def base_tables(p0, p1, radii, sil, *, rows=None, reach=None, sil_cum=None,
                caps: bool = True):
    """What a search adds to: row prefix sums of the pixels outside a drawn model.

    Parameters
    ----------
    p0, p1 : numpy.ndarray, shape (K, 2)
        Ends of the segments drawn (the part of the model that does not move).
    radii : numpy.ndarray, shape (K,)
        Their half-widths.
    sil : numpy.ndarray, shape (h, w), bool
        The silhouette.
    rows : (int, int), optional
        Only rows ``rows[0] <= y < rows[1]`` (default: all).
    reach : (int, int), optional
        Fill the table only in these rows (within ``rows``; zeros elsewhere): the
        rows the search's candidates can reach. The counts still cover ``rows``.
        Default: all of ``rows``.
    sil_cum : numpy.ndarray, shape (h, w + 1), int32, optional
        Row prefix sums of ``sil`` (:func:`row_prefix_sums`), if already at hand.
    caps : bool
        Capsules (true) or rectangles (false).

    Returns
    -------
    cum : numpy.ndarray, shape (1, 2, h, w + 1), int32
        Channel 0: row prefix sums of pixels not in the model; channel 1: of those on
        the silhouette (zero outside ``rows`` and ``reach``); the table
        :func:`span_similarity` reads.
    m, i : int
        Model pixels, and model pixels on the silhouette, in ``rows``.
    """
    h, w = sil.shape
    r0, r1 = (0, h) if rows is None else (max(0, int(rows[0])), min(h, int(rows[1])))
    f0, f1 = (r0, r1) if reach is None else (max(r0, int(reach[0])), min(r1, int(reach[1])))
    cum = np.zeros((1, 2, h, w + 1), dtype=np.int32)
    kernels = _kernels()
    p0 = _carray(p0, np.float64)
    p1 = _carray(p1, np.float64)
    if kernels is not None and r1 > r0:
        sil = _carray(sil, np.bool_)
        sil_cum = row_prefix_sums(sil) if sil_cum is None else _carray(sil_cum, np.int32)
        m, i = kernels.base_tables(p0, p1, _carray(radii, np.float64), sil, sil_cum, r0, r1, f0, f1,
                          bool(caps), cum[0])
        return cum, int(m), int(i)
    base = draw_segments(p0[None], p1[None], np.asarray(radii), (h, w), caps=caps)[0]
    if f1 > f0:
        np.cumsum(~base[f0:f1], axis=1, out=cum[0, 0, f0:f1, 1:])
        np.cumsum(sil[f0:f1] & ~base[f0:f1], axis=1, out=cum[0, 1, f0:f1, 1:])
    return cum, int(np.count_nonzero(base[r0:r1])), int(np.count_nonzero((base & sil)[r0:r1]))


def group_tables(masks, segs, child, sil, *, rows=None):
    """:func:`base_tables` for a group search: one table per segment searched.

    The numpy reference of what the fit uses, :func:`group_span_tables` (which counts
    the segments' spans instead of taking drawn masks).

    Parameters
    ----------
    masks : numpy.ndarray, shape (10, h, w), bool
        Every segment of the model drawn (:func:`draw_segments`).
    segs, child : numpy.ndarray of int, shape (N,)
        The segments searched and the child moving with each (``child == segs``:
        a leaf, no child).
    sil : numpy.ndarray, shape (h, w), bool
        The silhouette.
    rows : numpy.ndarray of int, shape (N, 2), optional
        Fill table n only for rows ``rows[n, 0] <= y < rows[n, 1]`` (zeros elsewhere):
        the rows search n's candidates can reach. Segment ``segs[n]`` and its child
        must cover no pixel outside them. Default: every row.

    Returns
    -------
    cum : numpy.ndarray, shape (N, 2, h, w + 1), int32
        Per segment, row prefix sums of the pixels outside the model without that
        segment and child (channel 0), and of those on the silhouette (channel 1).
    m_base, i_base : numpy.ndarray, shape (N,), int64
        Pixels of each such model, and of those on the silhouette (whole image).
    """
    n = len(segs)
    h, w = sil.shape
    cum = np.zeros((n, 2, h, w + 1), dtype=np.int32)
    segs = np.asarray(segs, dtype=np.int64)
    child = np.asarray(child, dtype=np.int64)
    rows = (np.tile(np.array([0, h], np.int64), (n, 1)) if rows is None
            else np.asarray(rows, dtype=np.int64))
    # pixels covered by more segments than the pair's own
    own = masks[segs].astype(np.uint8)
    own += masks[child] & (child != segs)[:, None, None]
    base = masks.sum(axis=0, dtype=np.uint8)[None] > own  # (N, h, w)
    np.cumsum(~base, axis=2, out=cum[:, 0, :, 1:])
    np.cumsum(sil & ~base, axis=2, out=cum[:, 1, :, 1:])
    y = np.arange(h)
    outside = (y < rows[:, :1]) | (y >= rows[:, 1:])  # (N, h)
    cum[np.broadcast_to(outside[:, None], cum.shape[:3])] = 0
    return (cum, np.count_nonzero(base, axis=(1, 2)).astype(np.int64),
            np.count_nonzero(base & sil, axis=(1, 2)).astype(np.int64))


def group_span_tables(p0, p1, radii, segs, child, sil, *, rows=None, caps: bool = True):
    """:func:`group_tables` of the model with segments ``p0`` -> ``p1``, without drawing it.

    Parameters
    ----------
    p0, p1 : numpy.ndarray, shape (10, 2)
        Every segment's ends (pixels).
    radii : numpy.ndarray, shape (10,)
        Their half-widths.
    segs, child, sil, rows
        As in :func:`group_tables`.
    caps : bool
        Capsules (true) or rectangles (false).

    Returns
    -------
    cum, m_base, i_base
        Exactly :func:`group_tables` of the masks :func:`draw_segments` would draw
        (the compiled path counts the segments' row spans; the fallback draws them).
    """
    h, w = sil.shape
    segs = np.asarray(segs, dtype=np.int64)
    child = np.asarray(child, dtype=np.int64)
    kernels = _kernels()
    if kernels is None:
        masks = draw_segments(np.asarray(p0)[:, None], np.asarray(p1)[:, None],
                              np.asarray(radii)[:, None], (h, w), caps=caps)
        return group_tables(masks, segs, child, sil, rows=rows)
    n = len(segs)
    rows = (np.tile(np.array([0, h], np.int64), (n, 1)) if rows is None
            else np.asarray(rows, dtype=np.int64))
    cum = np.zeros((n, 2, h, w + 1), dtype=np.int32)
    m_base = np.zeros(n, np.int64)
    i_base = np.zeros(n, np.int64)
    kernels.group_span_tables(_carray(p0, np.float64), _carray(p1, np.float64),
                              _carray(radii, np.float64), bool(caps), segs, child,
                              _carray(sil, np.bool_), _carray(rows, np.int64), cum, m_base,
                              i_base)
    return cum, m_base, i_base


def shift_overlaps(sil: np.ndarray, model: np.ndarray, n: int) -> np.ndarray:
    """Overlap of a model mask with a silhouette for every column shift in [-n, n].

    Parameters
    ----------
    sil, model : numpy.ndarray, shape (h, w), bool
    n : int
        Largest shift in pixels.

    Returns
    -------
    numpy.ndarray, shape (2 n + 1,), int64
        Element ``t``: pixels of ``model`` moved by ``t - n`` columns (positive:
        right) that land on ``sil`` (pixels moved out of the image count as empty).
    """
    kernels = _kernels()
    if kernels is not None:
        out = np.empty(2 * n + 1, np.int64)
        kernels.shift_overlap(_carray(sil, np.bool_), _carray(model, np.bool_), int(n), out)
        return out
    padded = np.pad(sil, ((0, 0), (n, n)))
    windows = np.lib.stride_tricks.sliding_window_view(padded, sil.shape[1], axis=1)
    return np.count_nonzero(windows & model[:, None, :], axis=(0, 2)).astype(np.int64)


__all__ = [
    "DESCENDANTS",
    "NormalisedMask",
    "base_tables",
    "SEGMENTS",
    "direction",
    "draw_pose",
    "draw_segments",
    "group_scorer",
    "group_similarity",
    "group_span_tables",
    "group_tables",
    "image_angle",
    "limb_scorer",
    "limb_similarity",
    "model_dimensions",
    "model_shoulder",
    "normalise_mask",
    "pose_joints",
    "pose_joints_batch",
    "pose_scorer",
    "pose_similarity",
    "row_prefix_sums",
    "segment_spans",
    "shift_overlaps",
    "span_counts",
    "span_similarity",
]
