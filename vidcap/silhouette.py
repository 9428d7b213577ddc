"""Silhouettes by background subtraction (seed 004 section 3.1.3), and their
normalisation to a fixed height for the pose fitter (seed 004 section 4.2).

Per frame: the plate is scaled by the frame's own brightness per channel (slow
lighting drift), the L1 colour difference ``sum_c |frame_c - plate_c|`` (grey
levels, 0..765) is compared with a per-pixel threshold ``max(threshold,
local_factor * noise_map)``, pixels that are merely darker with the background's
chromaticity (shadows) are dropped, a 3x3 median removes specks, a closing joins
fragments, and the largest connected blob - holes filled - is the person. Other
person-sized blobs are reported, not silently dropped.

All image operations are OpenCV on uint8, so a 640x480 frame takes ~1-2 ms.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import cv2
import numpy as np

from vidcap.background import BackgroundModel, _threshold_from_sigma
from vidcap.errors import VidcapError

__all__ = [
    "NoPersonError",
    "NormalisedSilhouette",
    "Silhouettes",
    "extract_silhouettes",
    "iter_silhouettes",
    "normalise_silhouette",
    "silhouette_frame",
]


class NoPersonError(VidcapError):
    """No frame of the video shows anything that differs from the background."""


@dataclass(frozen=True)
class FrameSilhouette:
    """One frame's result (see :class:`Silhouettes` for the fields)."""

    mask: np.ndarray
    bbox: np.ndarray
    area: int
    others: np.ndarray
    foreground_fraction: float
    threshold: float


@dataclass(frozen=True)
class Silhouettes:
    """The person's silhouette in every frame.

    Attributes
    ----------
    masks : numpy.ndarray, shape (F, H, W), bool
        The person's blob, holes filled, at the video's resolution.
    bbox : numpy.ndarray, shape (F, 4), int
        ``x0, y0, x1, y1`` in pixels, x right, y down, **x1 and y1 exclusive**
        (``mask[y0:y1, x0:x1]`` holds the whole blob); all -1 where no person.
    heights : numpy.ndarray, shape (F,), int
        ``y1 - y0`` in pixels (0 where no person).
    areas : numpy.ndarray, shape (F,), int
        Pixels in the person's mask.
    found : numpy.ndarray, shape (F,), bool
        A person-sized blob was found.
    n_other_blobs : numpy.ndarray, shape (F,), int
        Other blobs of at least ``other_fraction`` of the person's area and at least
        ``min_area`` pixels (more people, a moving object): not in ``masks``.
    others : numpy.ndarray, shape (N, 6), int
        One row per such blob: ``frame, x0, y0, x1, y1, area``.
    foreground_fraction : numpy.ndarray, shape (F,), float
        Share of the frame above threshold before clean-up; near 1 means the
        camera moved or the light changed abruptly (the mask is unreliable).
    threshold : float
        The L1 threshold used (grey levels summed over B, G, R).
    gains : numpy.ndarray, shape (F, 3), float
        Per-channel brightness of each frame relative to the plate.
    """

    masks: np.ndarray
    bbox: np.ndarray
    heights: np.ndarray
    areas: np.ndarray
    found: np.ndarray
    n_other_blobs: np.ndarray
    others: np.ndarray
    foreground_fraction: np.ndarray
    threshold: float
    gains: np.ndarray

    def __len__(self) -> int:
        return len(self.masks)

    @property
    def max_people(self) -> int:
        """Most blobs (the person plus others) seen in one frame."""
        if not len(self.found):
            return 0
        return int((self.found + self.n_other_blobs).max())


@dataclass(frozen=True)
class NormalisedSilhouette:
    """A silhouette scaled to a fixed height, and the map back to the frame.

    ``mask`` has shape ``(height + 2 * pad, width)``. A point ``(x, y)`` in frame
    pixels maps to ``(u, v) = scale * ((x, y) - origin)`` in the normalised
    crop and back by ``(x, y) = (u, v) / scale + origin`` (:meth:`to_frame`).
    The person's bbox top lies at ``v = pad`` and its bottom at
    ``v = pad + height``; its horizontal centre is at ``u = width / 2``.

    Attributes
    ----------
    mask : numpy.ndarray, shape (height + 2 * pad, width), bool
    scale : float
        Normalised pixels per frame pixel.
    origin : numpy.ndarray, shape (2,), float
        Frame coordinates (x, y) of the crop's (0, 0) corner.
    clipped : bool
        Part of the silhouette fell outside the crop's width.
    """

    mask: np.ndarray
    scale: float
    origin: np.ndarray
    clipped: bool

    def to_frame(self, uv) -> np.ndarray:
        """Map normalised points (..., 2) ``(u, v)`` to frame pixels ``(x, y)``."""
        return np.asarray(uv, float) / self.scale + self.origin

    def to_normalised(self, xy) -> np.ndarray:
        """Map frame points (..., 2) ``(x, y)`` to normalised pixels ``(u, v)``."""
        return (np.asarray(xy, float) - self.origin) * self.scale


def normalise_silhouette(
    mask: np.ndarray, bbox=None, *, height: int = 128, width: int | None = None,
    pad: int = 4,
) -> NormalisedSilhouette:
    """Scale a silhouette so that its bounding box is ``height`` pixels tall.

    Seed 004 section 4.2: the fitter's cost must not depend on the frame size, so
    it works on the silhouette normalised to a fixed size.

    Parameters
    ----------
    mask : numpy.ndarray, shape (H, W), bool
        The person's silhouette in the frame.
    bbox : array-like, shape (4,), optional
        ``x0, y0, x1, y1`` (exclusive ends) of the person; computed from ``mask``
        when omitted.
    height : int
        Output height of the person, pixels.
    width : int, optional
        Output width (default ``height``: a square crop plus vertical padding).
    pad : int
        Empty rows above and below the person.

    Returns
    -------
    NormalisedSilhouette
        ``mask`` of shape ``(height + 2 * pad, width)``.

    Raises
    ------
    ValueError
        The mask is empty.
    """
    mask = np.asarray(mask, bool)
    width = height if width is None else int(width)
    if bbox is None:
        ys, xs = np.nonzero(mask)
        if not len(ys):
            raise ValueError("the mask is empty")
        bbox = (xs.min(), ys.min(), xs.max() + 1, ys.max() + 1)
    x0, y0, x1, y1 = (float(v) for v in bbox)
    if y1 <= y0 or x1 <= x0:
        raise ValueError("the mask is empty")
    scale = height / (y1 - y0)
    origin = np.array([(x0 + x1) / 2 - width / 2 / scale, y0 - pad / scale])
    # u = scale * (x - ox): affine from frame to crop (pixel centres at +0.5).
    # Pixel centres: frame pixel i covers [i, i+1), crop pixel j covers [j, j+1).
    m = np.array([[scale, 0, -scale * origin[0] + 0.5 * scale - 0.5],
                  [0, scale, -scale * origin[1] + 0.5 * scale - 0.5]], np.float64)
    out_h = height + 2 * pad
    src = mask.astype(np.float32)
    if scale < 0.75:
        # Area-like downscaling: box-average over one output pixel's footprint.
        k = int(round(1 / scale))
        src = cv2.blur(src, (k, k))
    out = cv2.warpAffine(src, m, (width, out_h), flags=cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    inside_x = (origin[0] <= x0) and (origin[0] + width / scale >= x1)
    return NormalisedSilhouette(mask=out >= 0.5, scale=float(scale), origin=origin,
                                clipped=not inside_x)


# --------------------------------------------------------------------------- extraction
class _Params:
    def __init__(self, bg: BackgroundModel, threshold, local_factor, shadows, min_area,
                 other_fraction, close_size):
        h, w = bg.plate.shape[:2]
        self.threshold = float(threshold)
        tmap = np.maximum(self.threshold, local_factor * bg.noise_map)
        self.tmap = np.clip(np.ceil(tmap), 0, 255).astype(np.uint8)
        self.plate = bg.plate
        self.plate_f = bg.plate.astype(np.float32)
        self.shadows = shadows
        # A shadow darkens every channel by the same factor (alpha) and keeps the
        # colour: its chromatic distortion is at noise level, a share of the
        # threshold. Dark clothes on a grey background also look like that, so
        # only mild darkening (a cast shadow, not a dark object) counts.
        self.shadow_alpha = (0.6, 0.95)
        self.shadow_cd = 0.2
        self.min_area = (max(16, int(2e-3 * h * w)) if min_area is None else int(min_area))
        self.other_fraction = other_fraction
        if close_size is None:
            close_size = max(3, int(round(min(h, w) / 120)) | 1)
        self.kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (close_size, close_size))
        step = max(1, int(np.sqrt(h * w / 4096)))
        self.step = step
        sub = self.plate_f[::step, ::step].reshape(-1, 3)
        self.gain_sel = sub.sum(axis=1) > 30  # too dark to measure a ratio
        self.plate_sub = sub
        self.ones = np.ones((1, 3), np.float32)


def _gain(frame: np.ndarray, p: _Params) -> np.ndarray:
    sub = frame[:: p.step, :: p.step].reshape(-1, 3).astype(np.float32)
    ratio = (sub[p.gain_sel] + 1.0) / (p.plate_sub[p.gain_sel] + 1.0)
    if not len(ratio):
        return np.ones(3, np.float32)
    return np.clip(np.median(ratio, axis=0), 0.25, 4.0).astype(np.float32)


def silhouette_frame(frame: np.ndarray, p: _Params) -> tuple[FrameSilhouette, np.ndarray]:
    """One frame (internal; use :func:`extract_silhouettes`)."""
    g = _gain(frame, p)
    if np.abs(g - 1).max() > 0.01:
        ref = cv2.multiply(p.plate, (float(g[0]), float(g[1]), float(g[2]), 0.0))
    else:
        ref = p.plate
    diff = cv2.absdiff(frame, ref)
    l1 = cv2.transform(diff, p.ones)  # saturating uint8 sum over channels
    fg = cv2.compare(l1, p.tmap, cv2.CMP_GT)
    n_fg = cv2.countNonZero(fg)
    frac = n_fg / fg.size
    if p.shadows and n_fg:
        ys, xs = np.nonzero(fg)
        f = frame[ys, xs].astype(np.float32)
        b = ref[ys, xs].astype(np.float32) + 1.0
        # Shadow: darker by a common factor in every channel (Horprasert et al.
        # 1999 brightness / chromaticity distortion).
        alpha = (f * b).sum(axis=1) / (b * b).sum(axis=1)
        cd = np.abs(f - alpha[:, None] * b).sum(axis=1)
        shadow = ((alpha > p.shadow_alpha[0]) & (alpha < p.shadow_alpha[1])
                  & (cd < p.shadow_cd * p.threshold))
        if shadow.any():
            fg[ys[shadow], xs[shadow]] = 0
    fg = cv2.medianBlur(fg, 3)
    fg = cv2.morphologyEx(fg, cv2.MORPH_CLOSE, p.kernel)
    contours, _ = cv2.findContours(fg, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    mask = np.zeros(fg.shape, np.uint8)
    bbox = np.full(4, -1, np.int64)
    others = np.zeros((0, 5), np.int64)
    area = 0
    if contours:
        areas = np.array([cv2.contourArea(c) for c in contours])
        order = np.argsort(areas)[::-1]
        best = order[0]
        if areas[best] >= p.min_area:
            cv2.drawContours(mask, contours, int(best), 1, cv2.FILLED)
            x, y, w, h = cv2.boundingRect(contours[best])
            bbox = np.array([x, y, x + w, y + h], np.int64)
            area = int(cv2.countNonZero(mask))
            keep = [i for i in order[1:]
                    if areas[i] >= max(p.min_area, p.other_fraction * areas[best])]
            rows = []
            for i in keep:
                x, y, w, h = cv2.boundingRect(contours[i])
                rows.append((x, y, x + w, y + h, int(areas[i])))
            if rows:
                others = np.array(rows, np.int64)
    return FrameSilhouette(mask.view(bool), bbox, area, others, frac, p.threshold), g


def _params_for(background, frames_for_noise, threshold, local_factor, shadows, min_area,
                other_fraction, close_size):
    thr = threshold
    if thr is None:
        thr = background.threshold
        if not np.isfinite(thr):  # a given plate: measure the noise on the video
            thr = _measure_threshold(frames_for_noise, background.plate)
    return _Params(background, thr, local_factor, shadows, min_area, other_fraction,
                   close_size)


def _measure_threshold(frames: np.ndarray, plate: np.ndarray) -> float:
    """Threshold from the L1 differences of a few frames against a given plate."""
    sub = frames[:8, ::2, ::2].astype(np.float32)
    l1 = np.abs(sub - plate[::2, ::2].astype(np.float32)).sum(axis=-1).ravel()
    # Most pixels are background: the median and MAD describe its noise.
    return _threshold_from_sigma(np.zeros(3), l1)


def iter_silhouettes(
    source, background: BackgroundModel, *, threshold: float | None = None,
    local_factor: float = 3.0, shadows: bool = True, min_area: int | None = None,
    other_fraction: float = 0.2, close_size: int | None = None, chunk_size: int = 64,
) -> Iterator[tuple[np.ndarray, list[FrameSilhouette], np.ndarray]]:
    """Silhouettes chunk by chunk (for long videos); see :func:`extract_silhouettes`.

    Yields
    ------
    frames : numpy.ndarray, shape (n, H, W, 3), uint8
        The chunk's frames.
    results : list of FrameSilhouette
    gains : numpy.ndarray, shape (n, 3)
    """
    if isinstance(source, np.ndarray):
        if source.ndim == 3:
            source = source[None]
        chunks = (source[i:i + chunk_size] for i in range(0, len(source), chunk_size))
    else:
        from vidcap.video import iter_chunks

        chunks = iter_chunks(source, chunk_size=chunk_size)
    params = None
    for chunk in chunks:
        if chunk.shape[1:3] != background.plate.shape[:2]:
            raise VidcapError(
                f"the background is {background.plate.shape[1]}x{background.plate.shape[0]} "
                f"but the video is {chunk.shape[2]}x{chunk.shape[1]} pixels",
                None if isinstance(source, np.ndarray) else source)
        if params is None:
            params = _params_for(background, chunk, threshold, local_factor, shadows,
                                 min_area, other_fraction, close_size)
        res, gains = [], []
        for frame in chunk:
            r, g = silhouette_frame(frame, params)
            res.append(r)
            gains.append(g)
        yield chunk, res, np.array(gains)
    if params is None:
        raise VidcapError("the video has no frames",
                          None if isinstance(source, np.ndarray) else source)


def extract_silhouettes(
    source, background: BackgroundModel, *, threshold: float | None = None,
    local_factor: float = 3.0, shadows: bool = True, min_area: int | None = None,
    other_fraction: float = 0.2, close_size: int | None = None, chunk_size: int = 64,
    progress: bool | None = None, require_person: bool = True,
) -> Silhouettes:
    """Separate the person from the background in every frame.

    Parameters
    ----------
    source : str, path-like or numpy.ndarray
        A video file (decoded in chunks of ``chunk_size``) or frames (F, H, W, 3)
        uint8 BGR.
    background : BackgroundModel
        From :func:`vidcap.background.estimate_background` or
        :func:`vidcap.background.load_plate`.
    threshold : float, optional
        L1 colour-difference threshold (sum over B, G, R, grey levels). Default: the
        background's own, measured from the noise of background pixels.
    local_factor : float
        Per-pixel threshold is ``max(threshold, local_factor * noise_map)``.
    shadows : bool
        Drop pixels that look like shadows (darker, same chromaticity).
    min_area : int, optional
        Smallest blob that counts as a person, pixels (default 0.2% of the frame).
    other_fraction : float
        Other blobs at least this share of the person's area are reported.
    close_size : int, optional
        Closing kernel, pixels (default ~frame size / 120, odd, >= 3).
    chunk_size : int
        Frames decoded and processed at a time.
    progress : bool, optional
        Show a progress bar (default: when stderr is a terminal).
    require_person : bool
        Raise :class:`NoPersonError` if no frame shows a person.

    Returns
    -------
    Silhouettes

    Raises
    ------
    NoPersonError
        Nothing differs from the background in any frame.
    VidcapError
        The plate's size differs from the video's; the video has no frames.
    """
    from vidcap.fileio import progress as bar

    total = len(source) if isinstance(source, np.ndarray) else None
    if total is None:
        try:
            from vidcap.video import probe

            total = probe(source).n_frames
        except VidcapError:
            total = None
    masks, bbox, areas, others, fracs, gains_all = [], [], [], [], [], []
    n_other = []
    start = 0
    pbar = bar(total=total, desc="silhouettes", unit="frame", enabled=progress)
    try:
        for chunk, res, gains in iter_silhouettes(
                source, background, threshold=threshold, local_factor=local_factor,
                shadows=shadows, min_area=min_area, other_fraction=other_fraction,
                close_size=close_size, chunk_size=chunk_size):
            for j, r in enumerate(res):
                thr = r.threshold
                masks.append(r.mask)
                bbox.append(r.bbox)
                areas.append(r.area)
                fracs.append(r.foreground_fraction)
                n_other.append(len(r.others))
                if len(r.others):
                    others.append(np.column_stack(
                        [np.full(len(r.others), start + j), r.others]))
            gains_all.append(gains)
            start += len(chunk)
            pbar.update(len(chunk))
    finally:
        pbar.close()
    bbox = np.array(bbox, np.int64).reshape(-1, 4)
    found = bbox[:, 0] >= 0
    name = None if isinstance(source, np.ndarray) else source
    if require_person and not found.any():
        raise NoPersonError(
            "no frame differs from the background: nobody to extract (a static scene, "
            "or a background plate that shows the person?)", name)
    return Silhouettes(
        masks=np.stack(masks),
        bbox=bbox,
        heights=np.where(found, bbox[:, 3] - bbox[:, 1], 0),
        areas=np.array(areas, np.int64),
        found=found,
        n_other_blobs=np.array(n_other, np.int64),
        others=np.concatenate(others) if others else np.zeros((0, 6), np.int64),
        foreground_fraction=np.array(fracs, np.float32),
        threshold=float(thr),
        gains=np.concatenate(gains_all),
    )
