"""Background plate estimated from the video itself (seed 004 section 3.1.2).

The seed finds "the regions on video frames that do not change" with
Felzenszwalb-Huttenlocher graph segmentation, each region painted with its mean
colour "to decrease the lighting effect". We do the same on a few sampled,
downscaled frames, and combine the regions with per-pixel temporal statistics so
that a pixel the person covers in *most* frames (jumping jacks, waving, turning on
the spot) still takes its background from the frames where it is uncovered:

1. Sample ``n_samples`` frames spread over the video; downscale them to
   ``work_size`` pixels on the long side and normalise each frame's global
   brightness per channel (slow lighting drift).
2. Segment each sample (:func:`skimage.segmentation.felzenszwalb`) and replace
   every pixel by its region's mean colour.
3. Per pixel, count for each sample how many other samples show the same region
   colour (within ``tau``, from the data's own noise). The most supported colour is
   the pixel's first guess; pixels whose guess has a majority are *confident*.
4. Region test, per frame: a region whose confident pixels agree with their guess
   (a region that "does not change") is background in that frame, and so are all
   its pixels - including pixels covered in most other frames.
5. The per-pixel vote is repeated with every sample weighted by how background-like
   its region was (step 4), which overturns a person's colour that happened to win
   the plain vote.
6. At full resolution, the plate is the robust mean of the samples over the frames
   each pixel was found to be background in. Pixels never found uncovered are
   flagged (``never_seen``); their plate value is the temporal median, unreliable.

``method='median'`` gives the plain per-pixel temporal median as a baseline.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import cv2
import numpy as np

from vidcap.errors import InputFileError, VidcapError

__all__ = [
    "BackgroundError",
    "BackgroundModel",
    "estimate_background",
    "load_plate",
    "sample_frames",
]

#: L1 (sum over B, G, R) threshold floor, grey levels: differences below this are
#: never foreground, whatever the measured noise (guards clean synthetic video).
MIN_THRESHOLD = 12.0
#: Foreground threshold in standard deviations of the background's L1 noise above
#: its mean. Isolated false alarms (~1e-4 of pixels at 4) are removed by the 3x3
#: median of the clean-up, so the threshold can stay close to the noise.
K_SIGMA = 4.0


class BackgroundError(VidcapError):
    """The background cannot be estimated from the video given."""


@dataclass(frozen=True)
class BackgroundModel:
    """A background plate and how much to trust it.

    Attributes
    ----------
    plate : numpy.ndarray, shape (H, W, 3), uint8
        Background colour per pixel, BGR, at the video's resolution and at the
        sampled frames' median lighting.
    confidence : numpy.ndarray, shape (H, W), float32
        In [0, 1]: the share of sampled frames in which the pixel was seen as
        background (1 = never covered; 0 = never seen uncovered).
    never_seen : numpy.ndarray, shape (H, W), bool
        Pixels no sampled frame showed uncovered; their plate value is a guess.
    noise_sigma : numpy.ndarray, shape (3,), float32
        Robust (1.4826 MAD) standard deviation of background pixels about the
        plate, per channel B, G, R, grey levels.
    noise_map : numpy.ndarray, shape (H, W), float32
        Per-pixel mean absolute difference (L1 over the channels, grey levels)
        of background samples from the plate; high where the background itself
        flickers (leaves, screens, compression around edges).
    threshold : float
        Suggested foreground threshold on the L1 colour difference (sum over
        B, G, R of ``|frame - plate|``, 0..765), from the noise of pixels known
        to be background.
    method : str
        ``'felzenszwalb'``, ``'median'`` or ``'given'``.
    n_samples : int
        Frames the plate was estimated from.
    moving_fraction : float
        Share of pixels that were not background in at least one sample: ~0 for
        a static scene with nobody in it.
    sample_indices : numpy.ndarray, shape (K,), int
        Frame indices sampled.
    """

    plate: np.ndarray
    confidence: np.ndarray
    never_seen: np.ndarray
    noise_sigma: np.ndarray
    noise_map: np.ndarray
    threshold: float
    method: str
    n_samples: int = 0
    moving_fraction: float = float("nan")
    sample_indices: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    @property
    def never_seen_fraction(self) -> float:
        """Share of the frame never seen uncovered, in [0, 1]."""
        return float(self.never_seen.mean())

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) of the plate."""
        return self.plate.shape[:2]

    @classmethod
    def from_plate(cls, plate: np.ndarray, *, noise_sigma: float | None = None):
        """Wrap a known plate (e.g. a photo of the empty scene).

        Parameters
        ----------
        plate : numpy.ndarray, shape (H, W, 3), uint8
            BGR background.
        noise_sigma : float, optional
            Per-channel noise in grey levels; when omitted ``threshold`` is NaN and
            :func:`vidcap.silhouette.extract_silhouettes` measures it on the video.
        """
        plate = np.ascontiguousarray(plate)
        if plate.ndim != 3 or plate.shape[2] != 3 or plate.dtype != np.uint8:
            raise ValueError(f"plate must be (H, W, 3) uint8, got {plate.shape} {plate.dtype}")
        h, w = plate.shape[:2]
        sig = np.full(3, np.nan if noise_sigma is None else noise_sigma, np.float32)
        thr = np.nan if noise_sigma is None else _threshold_from_sigma(sig)
        return cls(plate=plate, confidence=np.ones((h, w), np.float32),
                   never_seen=np.zeros((h, w), bool), noise_sigma=sig,
                   noise_map=np.zeros((h, w), np.float32), threshold=float(thr),
                   method="given")


def load_plate(path: str | os.PathLike) -> BackgroundModel:
    """Read a background image (PNG, JPEG, ...) as a :class:`BackgroundModel`.

    Raises
    ------
    InputFileError
        The file is missing or not an image.
    """
    if not os.path.isfile(path):
        raise InputFileError("no such background image", path)
    data = np.fromfile(path, np.uint8)
    img = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    if img is None:
        raise InputFileError("not a readable image (PNG, JPEG, BMP, TIFF)", path)
    return BackgroundModel.from_plate(img)


# --------------------------------------------------------------------------- sampling
def sample_frames(
    source, *, n_samples: int = 32, rng: np.random.Generator | None = None,
    chunk_size: int = 64,
) -> tuple[np.ndarray, np.ndarray]:
    """Pick ``n_samples`` frames spread evenly over a video.

    Parameters
    ----------
    source : str, path-like or numpy.ndarray
        A video file, or frames (F, H, W, 3) uint8 BGR.
    n_samples : int
        How many frames at most.
    rng : numpy.random.Generator, optional
        Jitters the sample positions inside their stride; ``None`` = evenly spaced.
    chunk_size : int
        Frames decoded at a time (a file is never held in memory whole).

    Returns
    -------
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
    indices : numpy.ndarray, shape (K,), int
    """
    if isinstance(source, np.ndarray):
        n = len(source)
        idx = _sample_indices(n, n_samples, rng)
        return np.ascontiguousarray(source[idx]), idx
    from vidcap.video import iter_chunks, probe

    info = probe(source)
    idx = _sample_indices(info.n_frames, n_samples, rng)
    wanted = set(idx.tolist())
    got, got_idx, start = [], [], 0
    for chunk in iter_chunks(source, chunk_size=chunk_size):
        for j in range(len(chunk)):
            if start + j in wanted:
                got.append(chunk[j].copy())
                got_idx.append(start + j)
        start += len(chunk)
    if start < info.n_frames and len(got) < min(n_samples, start):
        # The container over-stated its frame count: resample what exists.
        return sample_frames(source_frames_cache(source, start), n_samples=n_samples, rng=rng)
    if not got:
        raise BackgroundError("no frames decoded", source)
    return np.stack(got), np.asarray(got_idx)


def source_frames_cache(path, n):  # pragma: no cover - rare: wrong frame counts
    from vidcap.video import read_frames

    return read_frames(path, stop=n)


def _sample_indices(n: int, k: int, rng) -> np.ndarray:
    if n <= k:
        return np.arange(n)
    edges = np.linspace(0, n, k + 1)
    if rng is None:
        idx = ((edges[:-1] + edges[1:]) / 2).astype(int)
    else:
        idx = (edges[:-1] + rng.random(k) * np.diff(edges)).astype(int)
    return np.unique(np.clip(idx, 0, n - 1))


# --------------------------------------------------------------------------- estimation
def estimate_background(
    source, *, method: str = "felzenszwalb", n_samples: int = 32,
    work_size: int = 160, segment_scale: float = 60.0, min_region: int = 12,
    rng: np.random.Generator | None = None, progress: bool | None = None,
) -> BackgroundModel:
    """Estimate the background plate of a static-camera video.

    Parameters
    ----------
    source : str, path-like or numpy.ndarray
        A video file (decoded in chunks) or frames (F, H, W, 3) uint8 BGR.
    method : {'felzenszwalb', 'median'}
        Region stability plus per-pixel votes (see the module docstring), or the
        plain per-pixel temporal median of the samples (a baseline).
    n_samples : int
        Frames sampled (>= 2).
    work_size : int
        Long side, pixels, the samples are downscaled to for segmentation.
    segment_scale : float
        Felzenszwalb's ``scale`` (larger = larger regions), at ``work_size``.
    min_region : int
        Felzenszwalb's ``min_size``, pixels at ``work_size``.
    rng : numpy.random.Generator, optional
        Jitters which frames are sampled.
    progress : bool, optional
        Show a progress bar (default: when stderr is a terminal).

    Returns
    -------
    BackgroundModel

    Raises
    ------
    BackgroundError
        Fewer than two frames, or nothing ever changes in the video (a static
        scene with nobody in it).
    VideoError
        The file cannot be decoded.
    """
    if method not in ("felzenszwalb", "median"):
        raise ValueError(f"method must be 'felzenszwalb' or 'median', not {method!r}")
    if n_samples < 2:
        raise ValueError("n_samples must be >= 2")
    name = source if not isinstance(source, np.ndarray) else None
    if isinstance(source, np.ndarray):
        if source.ndim != 4 or source.shape[-1] != 3 or source.dtype != np.uint8:
            raise ValueError(f"frames must be (F, H, W, 3) uint8, got {source.shape}")
        if len(source) == 0:
            raise BackgroundError("the video has no frames")
    frames, idx = sample_frames(source, n_samples=n_samples, rng=rng)
    if len(frames) < 2:
        raise BackgroundError(
            "only one frame: a background cannot be estimated from a single frame; "
            "give a photo of the empty scene (--background plate.png)", name)

    gains = _frame_gains(frames)
    if method == "median":
        weights = np.ones(frames.shape[:3], np.float32)
        plate = _gain_median(frames, gains)
        conf = np.ones(frames.shape[1:3], np.float32)
        model = _finish(frames, gains, plate, weights, conf, "median", idx, name)
        return model
    weights_small = _region_vote(frames, gains, work_size=work_size,
                                 segment_scale=segment_scale, min_region=min_region,
                                 progress=progress)
    return _finish_regions(frames, gains, weights_small, idx, name)


def _frame_gains(frames: np.ndarray) -> np.ndarray:
    """Per-frame, per-channel brightness relative to the samples' median frame, (K, 3)."""
    step = max(1, int(np.sqrt(frames.shape[1] * frames.shape[2] / 4096)))
    sub = frames[:, ::step, ::step].astype(np.float32) + 1.0
    med = np.median(sub, axis=0)
    ratio = sub / med
    g = np.median(ratio.reshape(len(frames), -1, 3), axis=1)
    return np.clip(g, 0.25, 4.0).astype(np.float32)


def _gain_median(frames, gains) -> np.ndarray:
    norm = frames.astype(np.float32) / gains[:, None, None, :]
    return np.clip(np.median(norm, axis=0) + 0.5, 0, 255).astype(np.uint8)


def _region_vote(frames, gains, *, work_size, segment_scale, min_region, progress):
    """Steps 2-5 at low resolution: per-sample background weights (K, h, w) in [0, 1]."""
    from skimage.segmentation import felzenszwalb

    from vidcap.fileio import progress as bar

    k, hh, ww = frames.shape[:3]
    s = min(1.0, work_size / max(hh, ww))
    h, w = max(2, round(hh * s)), max(2, round(ww * s))
    small = np.stack([cv2.resize(f, (w, h), interpolation=cv2.INTER_AREA) for f in frames])
    small = small.astype(np.float32) / gains[:, None, None, :]
    labels = np.empty((k, h, w), np.int32)
    means = np.empty((k, h, w, 3), np.float32)
    offset = 0
    for t in bar(range(k), total=k, desc="background", unit="frame", enabled=progress):
        lab = felzenszwalb(np.clip(small[t], 0, 255).astype(np.uint8), scale=segment_scale,
                           sigma=0.5, min_size=min_region)
        flat = lab.ravel()
        cnt = np.bincount(flat).astype(np.float32)
        for c in range(3):
            means[t, ..., c] = (np.bincount(flat, small[t, ..., c].ravel()) / cnt)[lab]
        labels[t] = lab + offset
        offset += int(lab.max()) + 1
    n_regions = offset

    # Agreement threshold from the data: spread of region colours about their
    # temporal median, most of which is background most of the time.
    med = np.median(means, axis=0)
    resid = np.abs(means - med).max(axis=-1)
    sigma = 1.4826 * float(np.median(resid))
    tau = max(8.0, 4.0 * sigma)

    # agree[t, u, p]: samples t and u show the same region colour at p (max over
    # channels; channel planes keep the arithmetic element-wise and fast).
    planes = np.ascontiguousarray(np.moveaxis(means, -1, 0))  # (3, k, h, w)
    agree = np.empty((k, k, h, w), bool)
    for t in range(k):
        d = np.abs(planes[0] - planes[0, t])
        np.maximum(d, np.abs(planes[1] - planes[1, t]), out=d)
        np.maximum(d, np.abs(planes[2] - planes[2, t]), out=d)
        np.less(d, tau, out=agree[t])

    lab_flat = labels.reshape(k, -1)
    reg_size = np.bincount(lab_flat.ravel(), minlength=n_regions).astype(np.float32)
    weights = np.ones((k, h, w), np.float32)
    for _ in range(2):
        support = np.einsum("tuhw,uhw->thw", agree, weights, dtype=np.float32)
        best = support.argmax(axis=0)
        total = weights.sum(axis=0) + 1e-6
        share = np.take_along_axis(support, best[None], 0)[0] / total
        confident = share >= 0.5
        same = np.take_along_axis(agree, best[None, None], 1)[:, 0]  # (k, h, w)
        good = same & confident
        # Region test: the share of a region's confident pixels that agree.
        n_conf = np.bincount(lab_flat.ravel(), np.broadcast_to(confident, (k, h, w)).ravel(),
                             minlength=n_regions)
        n_good = np.bincount(lab_flat.ravel(), good.ravel(), minlength=n_regions)
        score = np.where(n_conf >= np.maximum(3, 0.2 * reg_size),
                         n_good / np.maximum(n_conf, 1), 0.0).astype(np.float32)
        region_bg = score[labels]  # (k, h, w)
        # Confident pixels keep their own vote; the rest follow their region.
        weights = np.where(confident, good * np.maximum(region_bg, 0.5), region_bg)
        weights = np.where(weights >= 0.5, weights, 0.0).astype(np.float32)
    # A final consistency pass: among the frames kept, keep those agreeing with the
    # weighted mode, so a stray frame does not pollute the plate.
    support = np.einsum("tuhw,uhw->thw", agree, weights, dtype=np.float32)
    best = support.argmax(axis=0)
    same = np.take_along_axis(agree, best[None, None], 1)[:, 0]
    return (weights * same).astype(np.float32)


def _finish_regions(frames, gains, weights_small, idx, name):
    k, hh, ww = frames.shape[:3]
    h, w = weights_small.shape[1:]
    # Keep only samples well inside background regions (low resolution edges are
    # coarse), unless that leaves a pixel with none.
    binary = (weights_small > 0).astype(np.uint8)
    eroded = np.stack([cv2.erode(b, np.ones((3, 3), np.uint8)) for b in binary])
    keep_small = np.where(eroded.any(axis=0), eroded, binary).astype(np.float32)
    wfull = np.stack([cv2.resize(x, (ww, hh), interpolation=cv2.INTER_NEAREST)
                      for x in keep_small])
    seen = wfull.sum(axis=0)
    never = seen <= 0
    conf = (seen / k).astype(np.float32)
    plate = _robust_plate(frames, gains, wfull)
    if never.any():
        plate[never] = _gain_median(frames, gains)[never]
    return _finish(frames, gains, plate, wfull, conf, "felzenszwalb", idx, name,
                   never_seen=never)


def _robust_plate(frames, gains, weights) -> np.ndarray:
    """Weighted mean, then re-weighted without outliers, (H, W, 3) uint8."""
    x = frames.astype(np.float32) / gains[:, None, None, :]
    w = weights[..., None]
    tot = np.maximum(w.sum(axis=0), 1e-6)
    mean = (x * w).sum(axis=0) / tot
    dev = np.abs(x - mean).sum(axis=-1, keepdims=True)
    scale = 1.4826 * np.median(dev[weights > 0]) if (weights > 0).any() else 1.0
    w2 = w * (dev <= max(3.0 * scale, 6.0))
    tot2 = w2.sum(axis=0)
    mean2 = np.where(tot2 > 0, (x * w2).sum(axis=0) / np.maximum(tot2, 1e-6), mean)
    return np.clip(mean2 + 0.5, 0, 255).astype(np.uint8)


def _finish(frames, gains, plate, weights, conf, method, idx, name, never_seen=None):
    """Noise estimates from background samples; the static-scene check."""
    k = len(frames)
    ref = plate.astype(np.float32)[None] * gains[:, None, None, :]
    resid = frames.astype(np.float32) - ref  # (K, H, W, 3)
    l1 = np.abs(resid).sum(axis=-1)
    bgw = weights > 0
    if method == "median":
        # Background = close to the median; the bulk of pixels in most frames.
        bgw = l1 < max(3.0 * 1.4826 * float(np.median(l1)) + 6.0, MIN_THRESHOLD)
        conf = bgw.mean(axis=0).astype(np.float32)
    sel = resid[bgw]
    if len(sel) < 16:
        sel = resid.reshape(-1, 3)
    sigma = (1.4826 * np.median(np.abs(sel - np.median(sel, axis=0)), axis=0)).astype(
        np.float32)
    thr = _threshold_from_sigma(sigma, l1[bgw] if bgw.any() else l1.ravel())
    cnt = bgw.sum(axis=0)
    noise_map = np.where(cnt > 0, (l1 * bgw).sum(axis=0) / np.maximum(cnt, 1), 0.0)
    noise_map = cv2.dilate(noise_map.astype(np.float32), np.ones((3, 3), np.uint8))
    # Static-scene check: pixels far from the plate in some sample (beyond the
    # threshold), in connected areas large enough to be a person.
    moving = (l1 > 2 * thr).any(axis=0)
    moving = cv2.morphologyEx(moving.astype(np.uint8), cv2.MORPH_OPEN,
                              np.ones((3, 3), np.uint8)).astype(bool)
    moving_fraction = float(moving.mean())
    if moving_fraction < 2e-4:
        raise BackgroundError(
            f"nothing moves in the {k} sampled frames: no person to separate from the "
            "background (a static scene?)", name)
    if never_seen is None:
        never_seen = np.zeros(plate.shape[:2], bool)
    return BackgroundModel(
        plate=plate, confidence=np.clip(conf, 0, 1).astype(np.float32),
        never_seen=never_seen, noise_sigma=sigma, noise_map=noise_map.astype(np.float32),
        threshold=float(thr), method=method, n_samples=k,
        moving_fraction=moving_fraction, sample_indices=np.asarray(idx))


def _threshold_from_sigma(sigma, l1=None) -> float:
    """Foreground threshold on the L1 colour difference from background noise.

    With Gaussian noise of standard deviation s per channel, the L1 difference
    over three channels has mean ~2.39 s and standard deviation ~1.04 s; the
    threshold sits K_SIGMA standard deviations above the mean (robustly measured when
    the background differences ``l1`` are given), and never below MIN_THRESHOLD.
    """
    s = float(np.sqrt(np.mean(np.square(np.nan_to_num(sigma, nan=0.0)))))
    t = 2.39 * s + K_SIGMA * 1.04 * s
    if l1 is not None and np.size(l1):
        sub = np.asarray(l1).ravel()
        if sub.size > 200_000:
            sub = sub[:: sub.size // 200_000]
        m = float(np.median(sub))
        mad = 1.4826 * float(np.median(np.abs(sub - m)))
        t = max(t, m + K_SIGMA * mad)
    return float(max(t, MIN_THRESHOLD))
