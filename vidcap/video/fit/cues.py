"""Cues inside the outline: what the colour frame says where the silhouette says nothing.

Beyond the seed (issue 27). The seed's S = e^(-p-n)(1-p) scores a model against the
silhouette only, so an arm in front of the torso covers the same silhouette pixels at
any angle. The frame shows it: a forearm or hand in skin colour on a shirt, and the
limb's borders as image edges. This module gives the fit

- :func:`cue_image`: the colour frame resampled onto the normalised silhouette's grid
  (:class:`~vidcap.video.fit.normalise.NormalisedMask`), so cues and mask share pixels;
- :class:`ColourModel`: a skin-versus-clothing colour model learned from *this clip*
  (chromaticity histograms of the fitted head and of the torso's core, learned once
  before the fit from a few of the clip's frames, :mod:`vidcap.video.fit.cuecolours`;
  no fixed colour threshold);
- :class:`CueMaps`: per frame, a skin likelihood image and an edge structure tensor
  (Sobel over the three colour channels), both zero outside the silhouette;
- :func:`search_arms_cues`: each arm scored over (upper, lower) angle pairs by
  J = S + w_skin * skin(forearm) + w_edge * edges(limb borders) - w_prior * |angles -
  prior|, S computed by the same batched kernel as the outline-only arm grid; the
  arm is moved only where its forearm shows skin (:data:`SKIN_MIN`): inside the
  torso's outline edges alone do not tell an arm (the far arm of a side view is hidden
  there, and the edges it finds are the torso's shading and the other arm's).

The weights are :data:`WEIGHTS` (chosen on the four tuning clips of
``benchmarks/pose2d_accuracy.py``; the held-out clips measure them).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np

from vidcap.video.fit.candidates import still_tables
from vidcap.video.fit.engine import fit_kernels
from vidcap.video.fit.grids import _pair_scores, pair_grid
from vidcap.video.fit.limits import MAX_BEND, J, S, angle_gap
from vidcap.video.fit.normalise import NormalisedMask
from vidcap.video.fit.raster import _carray, _kernels, direction, draw_pose
from vidcap.video.fit.state import FitState, hang

#: Which cues the fit uses: the seed's outline only, or the frame's cues as well.
CUE_MODES = ("outline", "all")

#: Weights of the cue terms against S (S of one silhouette pixel is about
#: 2 S / silhouette pixels, ~0.001 at the normalised height 80): ``skin``, the mean
#: skin likelihood along the forearm (0-1); ``edge``, the mean edge strength across the
#: arm's borders (0-1); ``prior``, per radian away from the arm's prior (the previous
#: frame's arm, else hanging), so an arm with no evidence either way stays put.
WEIGHTS = {"skin": 0.03, "edge": 0.02, "prior": 0.01}
#: A cue move must put the forearm on skin: the mean skin likelihood along the chosen
#: forearm (:func:`arm_cue_terms`) at least this, else the arm stays where the outline
#: fit (or the last frame) left it. Edges alone do not move an arm: inside the torso's
#: outline the far arm of a side view is hidden behind the torso, and the edges and
#: stray skin it can reach there are the torso's shading, the other arm's borders or
#: the neck's. Chosen on the tuning renders (0.1-0.4 all gained; HISTORY.md).
SKIN_MIN = 0.2

_BINS = 32  # chromaticity histogram bins per axis
_EPS = 1e-6


def cue_image(frame: np.ndarray, norm: NormalisedMask) -> np.ndarray:
    """The colour frame on the normalised silhouette's pixel grid.

    Parameters
    ----------
    frame : numpy.ndarray, shape (H, W, 3), uint8
        The original frame (BGR), the one ``norm`` was cut from.
    norm : NormalisedMask

    Returns
    -------
    numpy.ndarray, shape (h, w, 3), float32
        ``norm.mask.shape``; pixel (i, j) is the frame at ``norm.to_original((j, i))``,
        low-pass filtered to the normalised pixel size first (no aliasing).
    """
    h, w = norm.mask.shape
    sx, sy = (float(v) for v in norm.scale_xy)
    ox, oy = (float(v) for v in norm.offset)
    H, W = frame.shape[:2]
    # the part of the frame the normalised image covers, area-averaged to about the
    # normalised pixel size (no aliasing), then moved onto the grid exactly
    x0, y0 = min(max(int(np.floor(ox)), 0), W - 1), min(max(int(np.floor(oy)), 0), H - 1)
    x1 = min(max(int(np.ceil(ox + w / sx)) + 1, x0 + 1), W)
    y1 = min(max(int(np.ceil(oy + h / sy)) + 1, y0 + 1), H)
    k = max(1, int(1.0 / max(sx, sy)))  # whole original pixels per averaged pixel
    x1, y1 = x0 + max(k, (x1 - x0) // k * k), y0 + max(k, (y1 - y0) // k * k)
    crop = frame[y0:y1, x0:x1]
    if k > 1 and crop.shape[0] >= k and crop.shape[1] >= k:
        # INTER_AREA by a whole factor: its fast path (a plain k x k box average)
        small = cv2.resize(crop, (crop.shape[1] // k, crop.shape[0] // k),
                           interpolation=cv2.INTER_AREA).astype(np.float32)
    else:
        k, small = 1, crop.astype(np.float32)
    m = np.array([[1.0 / (sx * k), 0.0, (ox - x0 + 0.5) / k - 0.5],
                  [0.0, 1.0 / (sy * k), (oy - y0 + 0.5) / k - 0.5]])
    return cv2.warpAffine(small, m, (w, h), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)


def chroma_bins(img: np.ndarray) -> np.ndarray:
    """Each pixel's chromaticity bin, (h, w) int: normalised (r, g) = (R, G) / (R + G + B),
    each in ``_BINS`` steps; chromaticity does not change with shading (a limb's lit
    and shadowed sides fall in one bin)."""
    total = img.sum(axis=-1) + 3.0
    r = (img[..., 2] + 1.0) / total
    g = (img[..., 1] + 1.0) / total
    ri = np.minimum((r * _BINS).astype(np.int64), _BINS - 1)
    gi = np.minimum((g * _BINS).astype(np.int64), _BINS - 1)
    return ri * _BINS + gi


class ColourModel:
    """Skin and clothing chromaticity, learned from the frames of one clip.

    Two histograms over :func:`chroma_bins`: ``skin`` from the fitted head's core, and
    ``cloth`` from the torso's core (where no arm is drawn). :meth:`skin_map` turns them
    into a likelihood ratio: near 1 where a colour was seen on the head and not on the
    torso, near 0 where it was seen on the torso or on neither (background, trousers).
    """

    def __init__(self):
        self.counts = np.zeros((2, _BINS * _BINS))
        self._table = None
        self._learned = None

    @property
    def learned(self) -> bool:
        """Both regions have been seen (at least a few pixels each)."""
        if self._learned is None:  # read by every frame's cue maps: kept till learn()
            self._learned = bool((self.counts.sum(axis=1) >= 8).all())
        return self._learned

    def learn(self, bins: np.ndarray, skin: np.ndarray, cloth: np.ndarray) -> None:
        """Add the pixels of the ``skin`` and ``cloth`` masks (h, w bool) of one frame,
        ``bins`` as :func:`chroma_bins` gives them."""
        n = _BINS * _BINS
        self.counts[0] += np.bincount(bins[skin], minlength=n)
        self.counts[1] += np.bincount(bins[cloth], minlength=n)
        self._table = self._learned = None

    def table(self) -> np.ndarray:
        """P(skin | chromaticity bin), (``_BINS`` ** 2,) float32."""
        if self._table is None:
            dens = []
            for c in self.counts:
                hist = cv2.GaussianBlur(c.reshape(_BINS, _BINS).astype(np.float32), (0, 0), 1.0)
                dens.append(hist / max(float(hist.sum()), _EPS) * hist.size)  # uniform = 1
            skin, cloth = dens
            # a colour seen on neither (density below the uniform's) is not skin
            self._table = (skin / (skin + cloth + 1.0)).ravel().astype(np.float32)
        return self._table

    def skin_map(self, bins: np.ndarray) -> np.ndarray:
        """P(skin) of every pixel, (h, w) float32."""
        return self.table()[bins]


@dataclass(frozen=True)
class CueMaps:
    """The cues of one frame on the normalised grid, zero outside the silhouette.

    Attributes
    ----------
    stack : numpy.ndarray, shape (h, w, 4), float32
        Skin likelihood (0-1) and the edge structure tensor ``Jxx, Jxy, Jyy`` of the
        colour image (Sobel per channel, summed over channels, divided by a robust
        scale of the frame's edges inside the silhouette), sampled together.
    bins : numpy.ndarray, shape (h, w), int
        Chromaticity bins (:func:`chroma_bins`), for :meth:`ColourModel.learn`.
    """

    stack: np.ndarray
    bins: np.ndarray


def cue_maps(img: np.ndarray, sil: np.ndarray, model: ColourModel) -> CueMaps:
    """:class:`CueMaps` of one normalised colour image ``img`` (h, w, 3) and its
    silhouette ``sil`` (h, w) bool, the skin likelihood from ``model`` (zero while it
    has not learned both colours)."""
    inside = cv2.dilate(sil.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    gx = cv2.Sobel(img, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(img, cv2.CV_32F, 0, 1, ksize=3)
    kernels = cue_kernels()
    if kernels is None:
        return _cue_maps_numpy(img, gx, gy, sil, inside, model)
    table = model.table() if model.learned else np.zeros(0, np.float32)
    bins = np.empty(sil.shape, np.int64)
    stack = np.empty((*sil.shape, 4), np.float32)
    energy = np.empty(sil.size, np.float32)
    n = kernels.cue_stack(np.ascontiguousarray(img, np.float32), gx, gy, sil, inside, table,
                          _BINS, bins, stack, energy)
    _scale_edges(stack, energy[:n])
    return CueMaps(stack, bins)


def _scale_edges(stack: np.ndarray, energy: np.ndarray) -> None:
    """Divide the structure tensor (``stack[..., 1:]``) by the 90th percentile of the
    edge energy inside the silhouette, in place: edges measured against this frame's."""
    if not energy.size:
        return
    k = int(0.9 * (energy.size - 1))
    scale = float(np.partition(energy, k)[k])
    if scale > 0:
        kernels = cue_kernels()
        if kernels is None:
            stack[..., 1:] *= np.float32(1.0 / scale)
        else:
            kernels.scale_tensor(stack, np.float32(1.0 / scale))
    else:
        stack[..., 1:] = 0.0


def _cue_maps_numpy(img, gx, gy, sil, inside, model):
    bins = chroma_bins(img)
    stack = np.zeros((*sil.shape, 4), np.float32)
    if model.learned:
        stack[..., 0] = np.where(sil, model.skin_map(bins), 0.0)
    for k, t in enumerate(((gx * gx).sum(-1), (gx * gy).sum(-1), (gy * gy).sum(-1)), start=1):
        stack[..., k] = np.where(inside, t, 0.0)
    _scale_edges(stack, (stack[..., 1] + stack[..., 3])[inside])
    return CueMaps(stack, bins)


def learn_colours(model: ColourModel, bins: np.ndarray, eng, st: FitState) -> None:
    """Add one fitted frame's head core (skin) and torso core (clothing) to ``model``:
    the head and torso drawn at 0.7 and 0.6 of their radii, within the silhouette,
    the torso's less every arm segment (a forearm across it is not clothing).
    ``bins``: the frame's chromaticity bins on ``eng``'s grid (:func:`chroma_bins` of
    its :func:`cue_image`)."""
    joints = eng.joints(st)
    shape = eng.sil.shape
    head_j = joints.copy()
    # the head's lower two thirds: its top may be hair
    top, neck = joints[J["head_top"]], joints[J["neck"]]
    head_j[J["head_top"]] = neck + (top - neck) * 0.67
    r = eng.R.copy()
    r[S["head"]] *= 0.7
    r[S["torso"]] *= 0.6
    head = draw_pose(head_j, r, shape, segments=[S["head"]], caps=False) & eng.sil
    torso = draw_pose(joints, r, shape, segments=[S["torso"]], caps=False) & eng.sil
    arms = [S[f"{s}_{p}_arm"] for s in "lr" for p in ("upper", "lower")]
    torso &= ~draw_pose(joints, eng.R * 1.5, shape, segments=arms, caps=True)
    model.learn(bins, head, torso)


def _sample(stack: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Bilinear samples of ``stack`` (h, w, 4) at points (..., 2) ``(x, y)``, (..., 4);
    zero beyond the image (the compiled kernel's arithmetic)."""
    h, w = stack.shape[:2]
    x, y = pts[..., 0], pts[..., 1]
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    out = np.zeros((*pts.shape[:-1], stack.shape[2]))
    for dy, wy in ((0, 1.0 - fy), (1, fy)):
        yy = y0.astype(np.int64) + dy
        for dx, wx in ((0, 1.0 - fx), (1, fx)):
            xx = x0.astype(np.int64) + dx
            ok = (yy >= 0) & (yy < h) & (xx >= 0) & (xx < w)
            v = stack[np.clip(yy, 0, h - 1), np.clip(xx, 0, w - 1)] * ok[..., None]
            out += wy * wx * v
    return out


_T_AXIS = np.linspace(0.1, 0.9, 6)  # along a segment, for the edge samples
_T_SKIN = np.linspace(0.25, 1.0, 6)  # along the forearm toward the hand


def arm_cue_terms(maps: CueMaps, shoulder: np.ndarray, du: np.ndarray, dl: np.ndarray,
                  len_u: float, len_l: float, r_u: float, r_l: float):
    """The cue terms of whole-arm candidates.

    Parameters
    ----------
    maps : CueMaps
    shoulder : numpy.ndarray, shape (2,)
        The shoulder, normalised pixels.
    du, dl : numpy.ndarray, shape (N, 2)
        Unit directions of the upper and lower arm of each candidate.
    len_u, len_l, r_u, r_l : float
        Drawn lengths and radii of the upper and lower arm, normalised pixels.

    Returns
    -------
    skin : numpy.ndarray, shape (N,)
        Mean skin likelihood on the forearm's axis and half way to its borders,
        toward the hand.
    edge : numpy.ndarray, shape (N,)
        Mean edge strength across both segments' borders (the structure tensor
        along each border's normal, square-rooted, capped at 1 per sample).
    """
    kernels = cue_kernels()
    if kernels is None:
        return _arm_cue_terms_numpy(maps, shoulder, du, dl, len_u, len_l, r_u, r_l)
    n = len(du)
    skin, edge = np.empty(n), np.empty(n)
    kernels.arm_cue_terms(maps.stack, _carray(shoulder, np.float64), _carray(du, np.float64),
                          _carray(dl, np.float64), float(len_u), float(len_l), float(r_u),
                          float(r_l), _T_SKIN, _T_AXIS, skin, edge)
    return skin, edge


def arm_cue_grid_terms(maps: CueMaps, shoulder: np.ndarray, du: np.ndarray, dl: np.ndarray,
                       lens: np.ndarray, r_u: float, r_l: float):
    """:func:`arm_cue_terms` of one set of candidates at several drawn lengths.

    Parameters
    ----------
    lens : numpy.ndarray, shape (F, 2)
        Drawn lengths of the upper and lower arm, normalised pixels, one row per
        foreshortening.

    Returns
    -------
    skin, edge : numpy.ndarray, shape (F, N)
        Row f: :func:`arm_cue_terms` with the lengths ``lens[f]``.
    """
    kernels = cue_kernels()
    lens = np.asarray(lens, np.float64).reshape(-1, 2)
    if kernels is None:
        rows = [_arm_cue_terms_numpy(maps, shoulder, du, dl, lu, ll, r_u, r_l)
                for lu, ll in lens]
        return (np.array([r[0] for r in rows]).reshape(len(lens), len(du)),
                np.array([r[1] for r in rows]).reshape(len(lens), len(du)))
    skin, edge = np.empty((len(lens), len(du))), np.empty((len(lens), len(du)))
    kernels.arm_cue_grid(maps.stack, _carray(shoulder, np.float64), _carray(du, np.float64),
                         _carray(dl, np.float64), _carray(lens, np.float64), float(r_u),
                         float(r_l), _T_SKIN, _T_AXIS, skin, edge)
    return skin, edge


def cue_kernels():
    """The compiled cue kernel module, or None (numpy path; the same terms)."""
    if _kernels() is None:  # the fit's switch (tests turn the compiled paths off)
        return None
    return _cue_module()


@functools.cache
def _cue_module():
    from vidcap.video.fit import _cue_kernels
    return _cue_kernels


def _arm_cue_terms_numpy(maps, shoulder, du, dl, len_u, len_l, r_u, r_l):
    elbow = shoulder + du * len_u
    wrist = elbow + dl * len_l
    nu = np.stack([-du[:, 1], du[:, 0]], axis=-1)
    nl = np.stack([-dl[:, 1], dl[:, 0]], axis=-1)
    # skin: forearm samples (N, 6, 3)
    axis_l = elbow[:, None] + (wrist - elbow)[:, None] * _T_SKIN[None, :, None]
    across = 0.5 * r_l * np.array([-1.0, 0.0, 1.0])
    skin_pts = axis_l[:, :, None] + nl[:, None, None] * across[None, None, :, None]
    # edges: both borders of both segments (N, 6, 2 sides)
    axis_u = shoulder + du[:, None] * len_u * _T_AXIS[None, :, None]
    axis_lo = elbow[:, None] + dl[:, None] * len_l * _T_AXIS[None, :, None]
    side = np.array([-1.0, 1.0])
    bu = axis_u[:, :, None] + nu[:, None, None] * (r_u * side)[None, None, :, None]
    bl = axis_lo[:, :, None] + nl[:, None, None] * (r_l * side)[None, None, :, None]
    n = len(du)
    skin = _sample(maps.stack, skin_pts.reshape(n, -1, 2))[..., 0].mean(axis=1)
    edge = np.zeros(n)
    for pts, nrm in ((bu, nu), (bl, nl)):
        v = _sample(maps.stack, pts.reshape(n, -1, 2))
        nx, ny = nrm[:, 0:1], nrm[:, 1:2]
        e = nx * nx * v[..., 1] + 2 * nx * ny * v[..., 2] + ny * ny * v[..., 3]
        edge += np.minimum(np.sqrt(np.maximum(e, 0.0)), 1.0).sum(axis=1)
    return skin, edge / (4 * len(_T_AXIS))


@functools.lru_cache(maxsize=8)
def _offsets(half_deg: float, step_deg: float):
    """The (upper, lower) offset pairs of :func:`_fine_grid`, radians, each (N,)."""
    off = np.deg2rad(np.arange(-half_deg, half_deg + 1e-9, step_deg))
    du, dl = (g.ravel() for g in np.meshgrid(off, off, indexing="ij"))
    for x in (du, dl):
        x.flags.writeable = False
    return du, dl


def _fine_grid(u0: float, l0: float, half_deg: float, step_deg: float, *, here: bool = False):
    """(upper, lower) pairs within ``half_deg`` of ``(u0, l0)``, ``step_deg`` apart, the
    bend within the limit, as :func:`pair_grid` returns them; with ``here``, the pair
    ``(u0, l0)`` itself last (whatever its bend)."""
    du, dl = _offsets(float(half_deg), float(step_deg))
    kernels = cue_kernels()
    if kernels is not None:
        n = len(du) + 1
        ua, la, d_u, d_l = np.empty(n), np.empty(n), np.empty((n, 2)), np.empty((n, 2))
        k = kernels.fine_grid(float(u0), float(l0), du, dl, MAX_BEND + 1e-9, here, ua, la,
                              d_u, d_l)
        return ua[:k], la[:k], d_u[:k], d_l[:k]
    ua, la = u0 + du, l0 + dl
    keep = angle_gap(la, ua) <= MAX_BEND + 1e-9
    ua, la = ua[keep], la[keep]
    if here:
        ua, la = np.append(ua, u0), np.append(la, l0)
    ua, la = np.mod(ua, 2 * np.pi), np.mod(la, 2 * np.pi)
    return ua, la, direction(ua), direction(la)


def fore_options(fu: float, fl: float) -> list[tuple[float, float]]:
    """:func:`_fore_options` (a new list of its cached options)."""
    return list(_fore_options(float(fu), float(fl)))


@functools.lru_cache(maxsize=512)
def _fore_options(fu: float, fl: float) -> tuple[tuple[float, float], ...]:
    """The (upper, lower) foreshortenings :func:`search_arm_cues` tries: the arm's own
    (the outline's), its forearm at full length, and the whole arm at full length.

    An arm in front of the torso leaves the outline nothing to measure its length by,
    so the outline fit draws it short; the frame's skin and edges can show it whole.
    """
    out = [(float(fu), float(fl))]
    for u in (float(fu), 0.7, 1.0):
        for low in (float(fl), 1.0):
            if all(max(abs(u - a), abs(low - b)) > 0.05 for a, b in out):
                out.append((u, low))
    return tuple(out)


@functools.lru_cache(maxsize=512)
def _fore_steps(fore: tuple[float, float]) -> tuple[tuple[float, float], ...]:
    """Foreshortenings near ``fore`` (the upper arm 0.1 and 0.2 either way, within
    [0.3, 1]), ``fore`` left out."""
    opts = []
    for a in (-0.2, -0.1, 0.0, 0.1, 0.2):
        for b in (0.0,):
            f = (min(max(fore[0] + a, 0.3), 1.0), min(max(fore[1] + b, 0.3), 1.0))
            if f != fore and f not in opts:
                opts.append(f)
    return tuple(opts)


def _masked(stack: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """A copy of ``stack`` (h, w, C), zero where ``mask`` (h, w) is set."""
    kernels = cue_kernels()
    if kernels is None:
        out = stack.copy()
        out[mask] = 0.0
        return out
    out = np.empty_like(stack)
    kernels.masked_copy(stack, mask, out)
    return out


def _pair_scorer(eng, st: FitState, up: int, lo: int, root: np.ndarray):
    """``score(grid, fores)``: S of every candidate of ``grid`` (:func:`pair_grid`'s
    form), (len(fores), N), the limb ``up``, ``lo`` from ``root`` at each of the
    foreshortenings ``fores`` ((upper, lower) pairs), the rest of the model as in
    ``st``: :func:`grids._pair_scores`, with the still segments' tables drawn once for
    every grid and foreshortening (they do not depend on the moving limb's)."""
    kernels = fit_kernels()
    if kernels is None:
        def numpy_score(grid, fores):
            return np.stack([_pair_scores(eng, st.with_entries(fore=([up, lo], list(f))), up,
                                          lo, root, grid) for f in fores])
        return numpy_score
    tables = _still_args(eng, st, up, lo, root)
    radii, cum, r0, r1, caps, a, m0, i0 = tables[1:]
    len_u, len_l = eng.L[up], eng.L[lo]

    def score(grid, fores):
        _, _, du, dl = grid
        out, q = np.empty((len(fores), len(du))), np.empty((len(fores), len(du)))
        for f, (fu, fl) in enumerate(fores):
            kernels.arm_pair_terms(du, dl, tables[0], float(len_u * fu), float(len_l * fl),
                                   radii, cum, r0, r1, caps, a, m0, i0, out[f], q[f])
        np.exp(out, out=out)  # S = exp(-p - n) (1 - p), as grids._pair_scores
        out *= q
        return out

    score.tables = tables
    return score


def _still_args(eng, st: FitState, up: int, lo: int, root: np.ndarray):
    """The arm pair kernel's arguments but the candidates and lengths: the shoulder,
    the arm's radii, the still segments' table (:func:`still_tables`), its rows, caps,
    the silhouette's pixels there and the still model's counts."""
    (r0, r1), cum, a, m_base, i_base = still_tables(eng, st, None, np.array([up, lo]), None)
    return (_carray(root, np.float64), _carray(eng.R[[up, lo]], np.float64), cum, r0, r1,
            bool(eng.caps), a, int(m_base[0]), int(i_base[0]))


def _j_scorer(eng, st: FitState, up: int, lo: int, shoulder, own: CueMaps, prior, fore0, w):
    """``score(grid, fores)``: J of :func:`search_arm_cues` for every candidate of
    ``grid`` at each of ``fores``, (len(fores), N): S, the cues of ``own`` and the pull
    of ``prior`` (each segment's weighed by its foreshortening in ``fore0``)."""
    pair_s = _pair_scorer(eng, st, up, lo, shoulder)
    lengths = np.array([eng.L[up], eng.L[lo]])
    r_u, r_l = float(eng.R[up]), float(eng.R[lo])
    kernels = cue_kernels()
    if kernels is not None:  # the whole of J in one compiled call per grid
        j_args = (*pair_s.tables[1:], own.stack, r_u, r_l, _T_SKIN, _T_AXIS,
                  np.array([prior[0], prior[1]], np.float64), np.array(fore0, np.float64),
                  np.array([w["skin"], w["edge"], w["prior"]], np.float64))

    def score(grid, fores):
        ua, la, du, dl = grid
        if kernels is not None:
            shape = (len(fores), len(du))
            x, q, skin, edge, j = (np.empty(shape) for _ in range(5))
            kernels.arm_j_grid(ua, la, du, dl, pair_s.tables[0], lengths * np.array(fores),
                               *j_args, x, q, skin, edge, j)
            return j
        sim = pair_s(grid, fores)
        skin, edge = arm_cue_grid_terms(own, shoulder, du, dl, lengths * np.array(fores),
                                        r_u, r_l)
        # a segment the outline drew short is one it hardly sees: its angle is held
        # by the prior that much less
        gap = fore0[0] * angle_gap(ua, prior[0]) + fore0[1] * angle_gap(la, prior[1])
        return sim + w["skin"] * skin + w["edge"] * edge - w["prior"] * gap

    return score


#: A tracked frame's cue search: pairs within this many degrees of the arm in place
#: (each segment), 10 degrees apart, then 2.5 degrees apart about the best.
LOCAL_HALF_DEG = 30.0


def search_arm_cues(eng, st: FitState, s: str, maps: CueMaps, *, prior=None,
                    weights=None, coarse_deg: float = 15.0, local: bool = False,
                    out: dict | None = None, skin_min: float = SKIN_MIN) -> FitState:
    """One whole arm placed by S and the frame's cues together (beyond the seed).

    Every (upper, lower) pair ``coarse_deg`` apart, at each foreshortening of
    :func:`fore_options`, is scored by J (the module's docstring; the prior's pull
    on each segment's angle weighed by the segment's own foreshortening), then pairs 2.5
    degrees apart within one coarse step of the best, at the best's foreshortening,
    and the arm is moved there if that J beats the arm in place. The other arm's
    drawn pixels carry no cue for this one (its skin and edges are masked out), so
    both arms do not settle on the one the frame shows.

    Parameters
    ----------
    s : {'l', 'r'}
        Which arm (its label).
    prior : tuple of float, optional
        ``(upper, lower)`` radians the arm keeps without evidence (default: as it is).
    weights : dict, optional
        :data:`WEIGHTS`' keys.
    local : bool
        Only pairs within :data:`LOCAL_HALF_DEG` of the arm in place (a tracked
        frame: the arm moved little since the last frame), 10 then 2.5 degrees apart.
    out : dict, optional
        Filled with ``out[s]``: the arm's candidates for the solve over time
        (:func:`_candidates`).
    skin_min : float
        The arm is moved only to a place whose forearm shows at least this mean skin
        likelihood (:data:`SKIN_MIN`; 0: wherever J is best).
    """
    w = WEIGHTS if weights is None else weights
    up, lo = S[f"{s}_upper_arm"], S[f"{s}_lower_arm"]
    other = "r" if s == "l" else "l"
    st = st.drawing([up, lo])
    joints = eng.joints(st)
    shoulder = joints[J[f"{s}_shoulder"]]
    if prior is None:
        prior = (st.angles[up], st.angles[lo])
    fore0 = (float(st.fore[up]), float(st.fore[lo]))
    r_u, r_l = float(eng.R[up]), float(eng.R[lo])
    # the other arm's pixels and the head's (skin, but the head's) are no cue for this arm
    oth = draw_pose(joints, eng.R, eng.sil.shape,
                    segments=[S[f"{other}_upper_arm"], S[f"{other}_lower_arm"]], caps=True)
    oth |= draw_pose(joints, eng.R * 1.25, eng.sil.shape, segments=[S["head"]], caps=True)
    own = CueMaps(_masked(maps.stack, oth), maps.bins)

    lengths = np.array([eng.L[up], eng.L[lo]])
    score = _j_scorer(eng, st, up, lo, shoulder, own, prior, fore0, w)

    # the arm in place (even beyond the bend limit, where the outline fit left it)
    # is scored with the coarse grid (one batch, its last), at its own foreshortening
    if local:
        with_here = _fine_grid(st.angles[up], st.angles[lo], LOCAL_HALF_DEG, 10.0, here=True)
        half = 5.0
    else:
        g, half = pair_grid(float(coarse_deg)), coarse_deg
        a_here = np.mod([st.angles[up]], 2 * np.pi), np.mod([st.angles[lo]], 2 * np.pi)
        here = (*a_here, direction(a_here[0]), direction(a_here[1]))
        with_here = tuple(np.concatenate([c, h]) for c, h in zip(g, here, strict=True))
    coarse = tuple(x[:-1] for x in with_here)
    here = tuple(x[-1:] for x in with_here)
    fores = fore_options(*fore0)  # fores[0] is fore0
    j_all = score(with_here, fores)
    j_coarse, j_here = j_all[:, :-1], j_all[0, -1:]
    v = int(np.argmax(j_coarse.max(axis=1)))
    k = int(np.argmax(j_coarse[v]))
    u_k, l_k = coarse[0][k], coarse[1][k]
    fore = fores[v]
    fine = _fine_grid(u_k, l_k, half, 2.5)
    steps = []
    if fore != fore0 or fore0[0] > 0.95 or fore0[1] > 0.95:
        # an arm the cues lengthened (or drawn whole): its lengths between the coarse
        # options, too
        steps = _fore_steps(tuple(fore))
    j_steps = score(fine, [fore, *steps])
    j_fine = j_steps[0]
    for f, j_f in zip(steps, j_steps[1:], strict=True):
        if j_f.max() > j_fine.max():
            j_fine, fore = j_f, f
    best = int(np.argmax(j_fine)) if j_fine.max() > j_here[0] else -1
    if best >= 0 and skin_min > 0:
        skin, _ = arm_cue_terms(own, shoulder, fine[2][best:best + 1], fine[3][best:best + 1],
                                float(lengths[0] * fore[0]), float(lengths[1] * fore[1]),
                                r_u, r_l)
        if skin[0] < skin_min:  # no skin where the arm would go: the cues show no arm
            best = -1
    if best >= 0:
        d_best, j_best = (fine[2][best], fine[3][best]), float(j_fine[best])
    else:
        fore = fore0
        d_best, j_best = (here[2][0], here[3][0]), float(j_here[0])
    if out is not None:
        # the candidates at the chosen foreshortening (the solve over time compares
        # places, not lengths)
        both = tuple(np.concatenate([a, b]) for a, b in zip(here, fine, strict=True))
        j_both = np.concatenate([j_here, j_fine])
        cg, cj = (coarse, j_coarse[fores.index(fore)]) if fore in fores else (coarse,
                                                                             j_coarse[0])
        out[s] = _candidates(eng, shoulder, eng.L[up] * fore[0], eng.L[lo] * fore[1],
                             (cg, both), (cj, j_both), d_best[0], d_best[1], j_best)
    if best < 0:
        return st
    return st.with_entries(angles=([up, lo], [fine[0][best], fine[1][best]]),
                           fore=([up, lo], list(fore)))


#: Candidates kept per arm and frame for the solve over time, and how far apart (the
#: sum of the upper and lower arm's angle differences) two must be to count as two.
N_CANDIDATES = 4
_APART = np.deg2rad(30.0)


def _candidates(eng, shoulder, len_u, len_l, grids, scores, du_best, dl_best, j_best):
    """The chosen arm and up to ``N_CANDIDATES - 1`` others from the searched grids,
    best J first and each ``_APART`` from those kept: ``(elbows (K, 2), wrists (K, 2)``
    in original pixels, ``costs (K,)``: J below the chosen arm's, in units of S)."""
    ua = np.concatenate([g[0] for g in grids])
    la = np.concatenate([g[1] for g in grids])
    du = np.concatenate([g[2] for g in grids])
    dl = np.concatenate([g[3] for g in grids])
    jj = np.concatenate(scores)
    u, low = np.arctan2(-du_best[1], du_best[0]), np.arctan2(-dl_best[1], dl_best[0])
    keep = _greedy_apart(ua, la, jj, u, low)
    kept_du = [du_best, *du[keep]]
    kept_dl = [dl_best, *dl[keep]]
    cost = [0.0, *(max(float(j_best - jj[k]), 0.0) for k in keep)]
    elbow = shoulder + np.array(kept_du) * len_u
    wrist = elbow + np.array(kept_dl) * len_l
    return (eng.norm.to_original(elbow), eng.norm.to_original(wrist), np.array(cost))


def _greedy_apart(ua, la, jj, u0, l0):
    """Indices of up to ``N_CANDIDATES - 1`` candidates (angles ``ua``, ``la``, J
    ``jj``), best J first (ties: first listed), each at least ``_APART`` (the upper
    plus lower angle difference) from ``(u0, l0)`` and from those kept before it."""
    kernels = cue_kernels()
    if kernels is not None:
        keep = np.empty(N_CANDIDATES - 1, np.int64)
        n = kernels.greedy_apart(_carray(ua, np.float64), _carray(la, np.float64),
                                 _carray(jj, np.float64), float(u0), float(l0), _APART, keep)
        return keep[:n]
    order = np.argsort(-jj, kind="stable")
    alive = np.ones(len(jj), bool)
    u, low, keep = u0, l0, []
    while len(keep) < N_CANDIDATES - 1:
        alive &= angle_gap(ua[order], u) + angle_gap(la[order], low) >= _APART
        if not alive.any():
            break
        k = order[int(np.argmax(alive))]
        keep.append(k)
        u, low = ua[k], la[k]
    return np.array(keep, np.int64)


def refine_arms_with_cues(eng, st: FitState, maps: CueMaps, *, priors=None,
                          weights=None, local: bool = False, out: dict | None = None) -> FitState:
    """Both arms by :func:`search_arm_cues`, each with the other's pixels masked out,
    the image-left arm first. ``priors``: ``{'l': (upper, lower), 'r': ...}`` radians
    (default: each arm as it is, hanging where not yet drawn)."""
    for s in ("l", "r"):
        prior = None if priors is None else priors.get(s)
        if prior is None and not st.drawn[S[f"{s}_upper_arm"]]:
            prior = (hang(st), hang(st))
        st = search_arm_cues(eng, st, s, maps, prior=prior, weights=weights, local=local,
                             out=out)
    return st


__all__ = ["CUE_MODES", "SKIN_MIN", "ColourModel", "CueMaps", "WEIGHTS", "apply_cues",
           "arm_cue_grid_terms", "arm_cue_terms", "chroma_bins", "cue_image", "cue_maps",
           "fore_options", "learn_colours", "refine_arms_with_cues", "search_arm_cues"]


def apply_cues(eng, st: FitState, image: np.ndarray, model: ColourModel, *,
               weights=None, local: bool = False, out: dict | None = None) -> FitState:
    """The cue step of one frame's fit: the frame's :class:`CueMaps` from ``image``
    (:func:`cue_image`) and the clip's ``model`` (learned before the fit, the same for
    every frame: :mod:`vidcap.video.fit.cuecolours`), and both arms placed by them
    (:func:`refine_arms_with_cues`; ``local``: near the arms in place, a tracked
    frame)."""
    maps = cue_maps(image, eng.sil, model)
    return refine_arms_with_cues(eng, st, maps, weights=weights, local=local, out=out)
