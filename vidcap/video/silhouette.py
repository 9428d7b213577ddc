"""Silhouettes by background subtraction (seed 004 section 3.1.3).

The fixed-height normalisation the pose fitter works on (seed 004 section 4.2) is
:func:`vidcap.video.fit.raster.normalise_mask`, beside the rasteriser that shares its
coordinate convention.

Per frame: the plate is scaled by the frame's own brightness per channel (slow lighting
drift; by table lookup, :mod:`vidcap.video.gaintable`), the L1 colour difference
``sum_c |frame_c - plate_c|`` (grey levels, 0..765) is compared with a per-pixel threshold
``max(threshold, local_factor * noise_map)``, pixels that are merely darker with the
background's chromaticity (shadows) are dropped, a 3x3 median removes specks, a closing
joins fragments, and the largest connected blob - holes filled - is the person (from the
second frame on, a blob of similar size that overlaps the person's previous box is
followed instead: two people do not trade places). Other person-sized blobs are
reported, not silently dropped. The person's mirror image in a glossy floor or desk
below them is cut (:mod:`vidcap.video.reflection`).

All image operations are OpenCV on uint8 or one-pass compiled loops where a run of whole-array
calls went over the same pixels (:mod:`vidcap.video._silhouette_kernels`: the channel sum, the
shadow test, the edge band's steps): a 640x480 frame takes ~2 ms (~3 with the graph cut).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

import cv2
import numpy as np

from vidcap.errors import VidcapError
from vidcap.video import reflection
from vidcap.video.background import BackgroundModel, _threshold_from_sigma
from vidcap.video.blobholes import open_large_holes
from vidcap.video.edgeband import edge_by_contrast, rect_within, refine_edges
from vidcap.video.gaintable import GainedPlate, apply_gain
from vidcap.video.masks import MaskStack

__all__ = [
    "NoPersonError",
    "Silhouettes",
    "extract_silhouettes",
    "is_monochrome",
    "iter_silhouettes",
    "load_kernels",
    "silhouette_frame",
]


#: Frames whose shorter side has at least this many pixels are processed at half
#: resolution by default (see ``work_scale`` of :func:`extract_silhouettes`).
MIN_SIDE_FOR_HALF = 480
#: Default half-width, full-resolution pixels, of the band around the outline
#: re-decided by the person's own contrast (see ``edge_band`` of
#: :func:`extract_silhouettes`).
EDGE_BAND = 3


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
    masks : MaskStack, shape (F, H, W), bool
        The person's blob, holes filled, at the video's resolution (``masks[k]`` is
        frame k's (H, W) mask; only each frame's box is stored, see
        :mod:`vidcap.video.masks`; ``numpy.asarray(masks)`` gives the full array).
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
        ``min_area`` pixels that move (more people, a moving object): not in
        ``masks``. Blobs that stay put are scene (:func:`vidcap.video.staticblobs.static_rows`)
        and not counted.
    others : numpy.ndarray, shape (N, 6), int
        One row per other blob, static ones included: ``frame, x0, y0, x1, y1, area``.
    others_static : numpy.ndarray, shape (N,), bool
        Rows of ``others`` that stay put (scene, not a person).
    foreground_fraction : numpy.ndarray, shape (F,), float
        Share of the frame above threshold before clean-up; near 1 means the
        camera moved or the light changed abruptly (the mask is unreliable).
    threshold : float
        The L1 threshold used (grey levels summed over B, G, R).
    gains : numpy.ndarray, shape (F, 3), float
        Per-channel brightness of each frame relative to the plate.
    """

    masks: MaskStack
    bbox: np.ndarray
    heights: np.ndarray
    areas: np.ndarray
    found: np.ndarray
    n_other_blobs: np.ndarray
    others: np.ndarray
    foreground_fraction: np.ndarray
    threshold: float
    gains: np.ndarray
    others_static: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    def __len__(self) -> int:
        return len(self.masks)

    @property
    def max_people(self) -> int:
        """Most blobs (the person plus others) seen in one frame."""
        if not len(self.found):
            return 0
        return int((self.found + self.n_other_blobs).max())


# --------------------------------------------------------------------------- extraction
class _Params:
    def __init__(self, bg: BackgroundModel, threshold, local_factor, shadows, min_area,
                 other_fraction, close_size, work_scale=1, edge_band=0,
                 edge_fraction=0.3, graph_cut=False):
        full_h, full_w = bg.plate.shape[:2]
        self.full_shape = (full_h, full_w)
        s = max(1, int(work_scale))
        h, w = max(1, full_h // s), max(1, full_w // s)
        self.work_size = None if s == 1 else (w, h)
        # Work pixel centre i maps to full-resolution coordinate (i + 0.5) * f - 0.5.
        self.fx, self.fy = full_w / w, full_h / h
        self.threshold = float(threshold)
        tmap = np.maximum(self.threshold, local_factor * bg.noise_map).astype(np.float32)
        plate = bg.plate
        if s > 1:
            tmap = cv2.resize(tmap, (w, h), interpolation=cv2.INTER_AREA)
            plate = cv2.resize(plate, (w, h), interpolation=cv2.INTER_AREA)
        self.tmap = np.clip(np.ceil(tmap), 0, 255).astype(np.uint8)
        self.plate = plate
        self.plate_full = bg.plate
        # Plate channels at the clip level (:data:`SATURATED`): only a frame darker than
        # the scaled plate there differs from it (:func:`_one_sided`).
        sat = plate >= SATURATED if SATURATED is not None else None
        self.saturated = sat.view(np.uint8) if sat is not None and sat.any() else None
        high = None
        if HIGHLIGHT is not None:
            high = plate >= HIGHLIGHT
            if sat is not None:
                high &= ~sat
        self.highlight = high.view(np.uint8) if high is not None and high.any() else None
        still = getattr(bg, "still_person", None)
        self.still = None
        if still is not None and still.any():
            if s > 1:
                still = cv2.resize(still.view(np.uint8), (w, h),
                                   interpolation=cv2.INTER_NEAREST)
            self.still = np.nonzero(still)
            colour = bg.person_plate if bg.person_plate is not None else bg.plate
            if s > 1:
                colour = cv2.resize(colour, (w, h), interpolation=cv2.INTER_AREA)
            self.still_colour = colour[self.still].astype(np.float32)
        # Self-lit pixels (see vidcap.video.stillparts.self_lit): compared unscaled.
        lit = getattr(bg, "self_lit", None)
        self.lit = None
        if lit is not None and lit.any():
            if s > 1:
                lit = cv2.resize(lit.view(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST)
            self.lit = np.nonzero(lit)
        self.tmap_full = np.clip(np.ceil(np.maximum(
            self.threshold, local_factor * bg.noise_map)), 0, 255).astype(np.uint8)
        # Luma threshold for the edge band: the L1 threshold over three channels
        # is about three times a per-channel one.
        self.edge_luma = True
        self.tmap_luma = np.ceil(self.tmap_full / 3.0).astype(np.uint8)
        self.plate_f = plate.astype(np.float32)
        self.edge_band = int(edge_band)
        self.edge_fraction = float(edge_fraction)
        self.shadows = shadows
        self.reflections = reflection.CUT_REFLECTIONS  # read per run: a switch
        # A shadow darkens every channel by the same factor (alpha) and keeps the
        # colour: its chromatic distortion is at noise level, a share of the
        # threshold. Dark clothes on a grey background also look like that, so only
        # darkening with the colour kept counts, in two zones: a cast shadow (up to
        # 40 % darker, distortion under a fifth of the threshold) and the soft shade a
        # body throws on a lit wall or a glossy floor (up to 30 % darker, under half of
        # it). Measured on a real walk past a white wall (sports2d_walk_turn, tuning
        # since): the false foreground round the body is 3-24 % darker at 0.4-6 grey
        # levels of distortion (threshold 13.9), the body 27-84 % darker at 8-34; the
        # first zone alone left half of the shade: IoU 0.52 -> 0.84 against
        # MediaPipe's masks. The second zone reaching 40 % cut into ido_walk's dark
        # trousers (0.928 -> 0.913 against its true masks).
        self.shadow_zones = ((0.6, 0.95, 0.2), (0.7, 0.99, 0.5))  # alpha lo, hi, cd
        # The same in float32 as the shadow test compares them (the distortion's
        # limit a share of the threshold).
        self.shadow_limits = np.array([(lo, hi, share * self.threshold)
                                       for lo, hi, share in self.shadow_zones], np.float32)
        # In full-resolution pixels.
        self.min_area = (max(16, int(2e-3 * full_h * full_w)) if min_area is None
                         else int(min_area))
        self.other_fraction = other_fraction
        if close_size is None:
            close_size = max(3, int(round(min(h, w) / 120)) | 1)
        elif s > 1:  # given in full-resolution pixels
            close_size = max(1, int(round(close_size / s)))
        self.kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (close_size, close_size))
        # The frame's gain is the median ratio over ~1000 pixels spread on a grid.
        step = max(1, int(np.sqrt(h * w / 1024)))
        self.step = step
        sub = self.plate_f[::step, ::step].reshape(-1, 3)
        self.gain_sel = sub.sum(axis=1) > 30  # too dark to measure a ratio
        self.plate_inv_t = np.ascontiguousarray((1.0 / (sub[self.gain_sel] + 1.0)).T)
        # Plate channels (+1 against division by zero) for the shadow test.
        self.plate_planes = cv2.split(self.plate_f + 1.0)
        self.cut = None
        colours = getattr(bg, "colours", None)
        if graph_cut and colours is None:
            raise ValueError("graph_cut needs the clip's colour models: estimate the plate "
                             "with estimate_background(..., colour_models=True)")
        if graph_cut:
            from vidcap.video.graphcut import CutParams

            never = bg.never_seen
            if s > 1:
                never = cv2.resize(never.view(np.uint8), (w, h),
                                   interpolation=cv2.INTER_NEAREST) > 0
            self.cut = CutParams.make(colours, never)


def _gain(frame: np.ndarray, p: _Params) -> np.ndarray:
    sub = frame[:: p.step, :: p.step].reshape(-1, 3)[p.gain_sel]
    if not len(sub):
        return np.ones(3, np.float32)
    # The ratios channel by channel, each a contiguous row: ``np.median(ratio,
    # axis=0)`` by one partition along memory (the same values: the middle one, or the
    # float32 mean of the middle two).
    ratio = (sub.T + np.float32(1.0)) * p.plate_inv_t
    k = ratio.shape[1] // 2
    if ratio.shape[1] % 2:
        med = np.partition(ratio, k, axis=1)[:, k]
    else:
        part = np.partition(ratio, (k - 1, k), axis=1)
        med = (part[:, k - 1] + part[:, k]) / np.float32(2.0)
    return np.clip(med, 0.25, 4.0).astype(np.float32)


#: A blob at least this share of the largest one's area may be followed instead of it.
FOLLOW_SHARE = 0.5


def _follow(contours, areas, order, prev_box, p: _Params) -> int:
    """Index of the blob to take as the person: of the blobs at least
    :data:`FOLLOW_SHARE` of the largest, the one whose box overlaps ``prev_box`` (the
    person's in the previous frame, full-resolution ``x0, y0, x1, y1``) most, if it
    overlaps it by an IoU above 0.2; else the largest. Two people of similar size
    then do not trade places from frame to frame; one much larger still takes over.
    """
    best, best_iou = order[0], 0.2
    px0, py0, px1, py1 = (float(v) for v in prev_box)
    for i in order:
        if areas[i] < max(p.min_area, FOLLOW_SHARE * areas[order[0]]):
            break  # (sorted by area)
        x, y, w, h = cv2.boundingRect(_to_full(contours[i], p))
        ix = max(0.0, min(px1, x + w) - max(px0, x))
        iy = max(0.0, min(py1, y + h) - max(py0, y))
        inter = ix * iy
        iou = inter / ((px1 - px0) * (py1 - py0) + w * h - inter)
        if iou > best_iou:
            best, best_iou = i, iou
    return best


#: Per frame, the threshold rule of the plate (median + K_SIGMA MADs of the L1
#: difference, :func:`vidcap.video.background._threshold_from_sigma`) is applied to the
#: frame's own difference on the gain grid; when it exceeds the plate's threshold by
#: FRAME_RAISE, it is the frame's floor: a stretch of heavier compression or sensor
#: noise than the plate's samples saw (sbi_cavignal's last 80 frames: the median
#: difference of the scene 0 -> 6 grey levels, 12-19 % of it beyond the threshold) would
#: otherwise fill the frame with specks that join the person. None: off.
FRAME_RAISE: float | None = 1.25
#: The floor goes this share of the way from the plate's threshold to the frame's: the
#: whole way cut a small low-contrast runner in the noisy first frames of sports2d_run
#: (tuning; p10 IoU against MediaPipe's masks 0.649 -> 0.371, 0.519 at 0.5, 0.433 at
#: 0.3); CaVignal p10 0.904 at 1.0 and 0.5, 0.897 at 0.3.
FRAME_SHARE = 0.5


#: Plate channels at or above this level are clipped: the scene there is at least
#: as bright as the camera records, its level above that unknown. Scaled by a frame's
#: gain below 1, the plate says the frame should be darker there, but a highlight
#: stays at the clip level while the rest of the scene darkens (auto-exposure with
#: highlight compression): cdnet_office_enter (tuning) drops to 0.87 of the plate's
#: exposure in its first 3 s while its whiteboard stays at 246-253 (the plate there
#: 255, the samples scaled by 1 / 0.87 clipped): compared two-sided, a 1,300-pixel
#: false blob on the whiteboard in every empty frame, chosen over the man coming in
#: (frames 82-87, IoU 0). There only a frame darker than the scaled plate differs
#: (:func:`_one_sided`). None: off.
SATURATED: int | None = 250


def _one_sided(diff: np.ndarray, frame: np.ndarray, ref: np.ndarray,
               saturated: np.ndarray) -> None:
    """In ``diff`` (H, W, 3) uint8, in place: where ``saturated`` (H, W, 3) is
    non-zero, ``max(ref - frame, 0)`` instead of ``|frame - ref|`` (a frame brighter
    than the scaled plate at a clipped plate channel does not differ from it)."""
    darker = cv2.subtract(ref, frame)  # saturates at 0
    cv2.copyTo(darker, saturated, diff)


#: Plate channels at or above this level (and below :data:`SATURATED`) are highlights:
#: the camera compresses its top range, so when the exposure drifts they keep more of
#: their level than the frame's gain says. There a frame anywhere between the plate
#: and the plate scaled by the gain does not differ from it; only its distance from
#: that interval counts (:func:`_between`). cdnet_office_enter (tuning): at 0.87 of the
#: plate's exposure the whiteboard's top-left corner (plate 239-249, under
#: SATURATED) stays at 229-255, 20-30 grey levels a channel above the scaled plate: a
#: 230-900-pixel false blob in the empty frames, the one chosen over the man coming in
#: (frames 88-89, IoU 0 -> 0.49-0.54) and joined to his head later (frames 124-149,
#: 0.64-0.75 -> 0.75-0.97); its p10 0.781 -> 0.817 (any level from 220 to 245 the
#: same to 0.001; wt-sil6). None: off.
HIGHLIGHT: int | None = 240


def _between(diff: np.ndarray, frame: np.ndarray, ref: np.ndarray, plate: np.ndarray,
             where: np.ndarray) -> None:
    """In ``diff`` (H, W, 3) uint8, in place: where ``where`` (H, W, 3) is non-zero,
    the distance of ``frame`` from the interval between ``plate`` and ``ref`` (the plate
    scaled by the frame's gain), per channel: 0 inside it."""
    lo, hi = cv2.min(ref, plate), cv2.max(ref, plate)
    out = cv2.add(cv2.subtract(lo, frame), cv2.subtract(frame, hi))
    cv2.copyTo(out, where, diff)


def _frame_tmap(l1: np.ndarray, p: _Params) -> tuple[np.ndarray, int]:
    """The frame's threshold map and its floor (0: the plate's map as it is)."""
    if FRAME_RAISE is None:
        return p.tmap, 0
    from vidcap.video.background import K_SIGMA

    sub = l1[:: p.step, :: p.step].ravel()
    m = _median_u8(sub)
    dev2 = np.abs(2 * sub.astype(np.int16) - int(2 * m))  # twice |v - m|: integers
    t = m + K_SIGMA * 1.4826 * _median_u8(dev2) / 2
    if t <= FRAME_RAISE * p.threshold:
        return p.tmap, 0
    floor = int(min(255, np.ceil(p.threshold + FRAME_SHARE * (t - p.threshold))))
    return np.maximum(p.tmap, np.uint8(floor)), floor


def _median_u8(v: np.ndarray) -> float:
    """``np.median`` of small non-negative integers (uint8, or int16 up to 510), by
    counting (no sort)."""
    c = np.cumsum(np.bincount(v, minlength=256))
    n = len(v)
    if n % 2:
        return float(np.searchsorted(c, (n + 1) // 2))
    return 0.5 * float(np.searchsorted(c, n // 2) + np.searchsorted(c, n // 2 + 1))


def silhouette_frame(frame: np.ndarray, p: _Params, prev_box=None, keep=None
                     ) -> tuple[FrameSilhouette, np.ndarray]:
    """One frame (internal; use :func:`extract_silhouettes`). ``prev_box``: the
    person's box in the previous frame where one was found (:func:`_follow`);
    ``keep``: where the user allows the person in this frame
    (:meth:`vidcap.video.userregions.UserRegions.keep_masks`), or None."""
    full_frame = frame
    if p.work_size is not None:
        frame = cv2.resize(frame, p.work_size, interpolation=cv2.INTER_AREA)
    g = _gain(frame, p)
    scaled = np.abs(g - 1).max() > 0.01
    if scaled:
        ref = apply_gain(p.plate, g)
        if p.lit is not None:  # lamps and screens keep their level
            ref[p.lit] = p.plate[p.lit]
    else:
        ref = p.plate
    diff = cv2.absdiff(frame, ref)
    if scaled and p.saturated is not None:
        _one_sided(diff, frame, ref, p.saturated)
    if scaled and p.highlight is not None:
        _between(diff, frame, ref, p.plate, p.highlight)
    l1 = np.empty(diff.shape[:2], np.uint8)
    _kernels().l1_sum(diff, l1)  # saturating uint8 sum over channels
    tmap, floor = _frame_tmap(l1, p)
    fg = cv2.compare(l1, tmap, cv2.CMP_GT)
    if p.still is not None:  # parts of the person that never move, still there
        ys, xs = p.still
        near = np.abs(frame[ys, xs] - p.still_colour * g).sum(axis=-1) <= tmap[ys, xs]
        fg[ys[near], xs[near]] = 255
    if keep is not None:  # the user's regions: never the person, nor chosen as them
        fg = cv2.bitwise_and(fg, keep[0])
    n_fg = cv2.countNonZero(fg)
    frac = n_fg / fg.size
    fg = cv2.medianBlur(fg, 3)
    # (the median can leave nothing: a frame without the person, noise specks only)
    x, y, w, h = cv2.boundingRect(fg) if n_fg else (0, 0, 0, 0)
    if p.shadows and w and h:
        # Only inside the (de-specked) foreground's bounding rectangle. Shadow:
        # darker by a common factor in every channel (Horprasert et al. 1999
        # brightness / chromaticity distortion). One compiled pass; a shadow is no
        # difference from the plate for the cut either (l1 is not used after it).
        _kernels().drop_shadows(
            frame[y:y + h, x:x + w], *(q[y:y + h, x:x + w] for q in p.plate_planes),
            np.asarray(g, np.float32) if scaled else _ONES, p.shadow_limits,
            fg[y:y + h, x:x + w], l1[y:y + h, x:x + w], p.cut is not None)
        fg = cv2.medianBlur(fg, 3)
    fg = cv2.morphologyEx(fg, cv2.MORPH_CLOSE, p.kernel)
    plain = None
    if p.cut is not None:
        from vidcap.video.graphcut import cut_frame

        plain = fg if keep is None else cv2.bitwise_and(fg, keep[0])
        fg = cut_frame(frame, l1, tmap, fg, g, p.cut)
        if keep is not None:
            fg = cv2.bitwise_and(fg, keep[0])
    contours, _ = cv2.findContours(fg, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    mask = np.zeros(p.full_shape, np.uint8)
    bbox = np.full(4, -1, np.int64)
    others = np.zeros((0, 5), np.int64)
    area = 0
    if contours:
        px = p.fx * p.fy  # full-resolution pixels per work pixel
        areas = np.array([cv2.contourArea(c) for c in contours]) * px
        order, parts = _person_parts(contours, areas, prev_box, fg, p, plain)
        best = parts[0]
        if areas[best] >= p.min_area:
            # ``reach``: a box that holds every pixel of the mask (it only grows in
            # the edge band): the rectangles and counts below are taken inside it.
            reach = None
            for i in parts:
                c = _to_full(contours[i], p)
                cv2.drawContours(mask, [c], 0, 1, cv2.FILLED)
                reach = _union(reach, cv2.boundingRect(c), mask.shape)
            for i in parts:
                open_large_holes(mask, contours[i], fg, p)
            # the full-resolution plate at the frame's gain, scaled once for both
            gained = GainedPlate(p.plate_full, g if scaled else None)
            if p.edge_band > 0:
                reach = edge_by_contrast(mask, full_frame, g, p, floor, reach, gained)
            elif p.work_size is not None:
                reach = refine_edges(mask, full_frame, g, p, floor, reach, gained)
            x, y, w, h = rect_within(mask, reach)
            if p.reflections and reflection.drop_reflection(
                    mask, full_frame, gained, None, max(1, round(p.fy)), (x, y, w, h)):
                x, y, w, h = rect_within(mask, reach)
            if keep is not None:  # (the edge refinement may reach into a region)
                mask &= keep[1]
                x, y, w, h = rect_within(mask, reach)
            bbox = np.array([x, y, x + w, y + h], np.int64)
            area = int(cv2.countNonZero(mask[reach[1]:reach[3], reach[0]:reach[2]]))
            keep = [i for i in order if i not in parts
                    and areas[i] >= max(p.min_area, p.other_fraction * areas[best])]
            rows = []
            for i in keep:
                x, y, w, h = cv2.boundingRect(_to_full(contours[i], p))
                rows.append((x, y, x + w, y + h, int(areas[i])))
            if rows:
                others = np.array(rows, np.int64)
    return FrameSilhouette(mask.view(bool), bbox, area, others, frac, p.threshold), g


def _union(box, rect, shape, pad: int = 2):
    """The box ``(x0, y0, x1, y1)`` grown to hold the rectangle ``rect`` ``(x, y, w, h)``
    padded by ``pad`` pixels (a filled contour's pixels lie within its points'
    rectangle; the pad is a margin), within an image of ``shape``."""
    x, y, w, h = rect
    new = (max(0, x - pad), max(0, y - pad), min(shape[1], x + w + pad),
           min(shape[0], y + h + pad))
    if box is None:
        return new
    return (min(box[0], new[0]), min(box[1], new[1]), max(box[2], new[2]),
            max(box[3], new[3]))


def _person_parts(contours, areas, prev_box, fg, p: _Params, plain=None):
    """``(order, parts)``: the blobs by decreasing area, and the person's blobs, the
    followed one first (:func:`_follow`) and those joined to it (:func:`_joined`).

    ``plain``: the plain threshold's foreground when ``fg`` is the graph cut's
    (:mod:`vidcap.video.graphcut`); the cut's blobs that lie in the plain foreground's
    person (:func:`_in_plain_person`) are the person too. The cut trims each blob's
    outline by a pixel or two, and that can widen the gap between two blobs the plain
    foreground has joined (:data:`JOIN_GAP`) past the join: sports2d_run's runner,
    torso and legs apart at the black shorts against a dark hedge, lost the torso in
    3 of 33 frames (IoU against MediaPipe's masks 0.79 -> 0.33).
    """
    order = np.argsort(areas)[::-1]
    best = order[0]
    if prev_box is not None and len(order) > 1:
        best = _follow(contours, areas, order, prev_box, p)
    parts = [best] + _joined(contours, areas, best, fg, p)
    # Most frames hold no other blob as large as JOIN_SHARE of the person (specks at
    # most): then the plain person's blobs need not be found at all.
    if plain is not None and (np.delete(areas, parts) >= JOIN_SHARE * areas[parts[0]]).any():
        parts += _in_plain_person(contours, areas, parts, fg, plain, prev_box, p)
    return order, parts


def _in_plain_person(contours, areas, parts, fg, plain, prev_box, p: _Params) -> list[int]:
    """Indices of the blobs of ``fg`` (the cut's; ``contours``, ``areas``), not yet in
    ``parts``, of at least :data:`JOIN_SHARE` of the person's area, at least half of
    whose pixels lie in the blobs the plain foreground ``plain`` takes as the person
    (:func:`_person_parts` on it)."""
    pc, _ = cv2.findContours(plain, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not pc:
        return []
    pa = np.array([cv2.contourArea(c) for c in pc]) * (p.fx * p.fy)
    person = np.zeros(fg.shape, np.uint8)
    cv2.drawContours(person, [pc[i] for i in _person_parts(pc, pa, prev_box, plain, p)[1]],
                     -1, 1, cv2.FILLED)
    n, lab = cv2.connectedComponents(fg, connectivity=8)
    inside = np.bincount(lab[person > 0], minlength=n)
    size = np.bincount(lab.ravel(), minlength=n)
    out = []
    for i in range(len(contours)):
        if i in parts or areas[i] < JOIN_SHARE * areas[parts[0]]:
            continue
        c = lab[contours[i][0, 0, 1], contours[i][0, 0, 0]]
        if 2 * inside[c] >= size[c]:
            out.append(i)
    return out


#: Blobs at least :data:`JOIN_SHARE` of the person's area within :data:`JOIN_GAP` of
#: the person's height of it are the person too (see :func:`_joined`). Chosen on the
#: tuning render 14_19 10-13 s 3/4: p10 IoU 0.486 -> 0.608 (0.05 of the height; 0.1
#: joined a plate error to jacks side: 0.884 -> 0.795; a share of 0.3 joined less,
#: p10 0.567); the other tuning rows unchanged.
JOIN_SHARE, JOIN_GAP = 0.1, 0.05


def _joined(contours, areas, best: int, fg: np.ndarray, p: _Params) -> list[int]:
    """Indices of the blobs that are the person with blob ``best``: at least
    :data:`JOIN_SHARE` of its area and within :data:`JOIN_GAP` of its height of it
    or of a blob already joined (up to three rounds).

    A plate that absorbed part of a person who stays in place (a leg that stands on
    the same floorboards in most frames) cuts a band through the person: torso and
    legs come out as two blobs of similar size, and following one of them from frame
    to frame (:func:`_follow`) can lose the other for good.
    """
    if len(contours) < 2:
        return []
    big = [i for i in range(len(contours))
           if i != best and areas[i] >= JOIN_SHARE * areas[best]]
    if not big:
        return []
    h = cv2.boundingRect(contours[best])[3]
    gap = max(1, int(round(JOIN_GAP * h)))
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * gap + 1, 2 * gap + 1))
    # (a contour's first point lies on its own 8-connected component)
    _, lab = cv2.connectedComponents(fg, connectivity=8)
    comp = {i: lab[contours[i][0, 0, 1], contours[i][0, 0, 0]] for i in big}
    union = np.zeros(fg.shape, np.uint8)
    cv2.drawContours(union, contours, best, 1, cv2.FILLED)
    out: list[int] = []
    for _ in range(3):
        hit = set(np.unique(lab[cv2.dilate(union, kernel) > 0]).tolist())
        new = [i for i in big if i not in out and comp[i] in hit]
        if not new:
            break
        for i in new:
            cv2.drawContours(union, contours, i, 1, cv2.FILLED)
        out += new
    return out


_ONES = np.ones(3, np.float32)


def _kernels():
    from vidcap.video import _silhouette_kernels

    return _silhouette_kernels


def load_kernels() -> None:
    """Load numba and the first of the stage's compiled kernels in this process now
    (~0.3 s of CPU for numba's import, ~0.2 s for LLVM's start-up: every frame needs
    them). Called before forking processes that compile or load kernels of their own
    (the 2D fit's workers), so that they inherit both instead of paying them again."""
    out = np.empty((1, 1), np.uint8)
    _kernels().l1_sum(np.zeros((1, 1, 3), np.uint8), out)


def _to_full(contour: np.ndarray, p: _Params) -> np.ndarray:
    """Contour points from work to full-resolution pixels, int32 (N, 1, 2)."""
    if p.work_size is None:
        return contour
    f = np.array([p.fx, p.fy], np.float32)
    return np.round((contour + np.float32(0.5)) * f - np.float32(0.5)).astype(np.int32)


def _params_for(background, frames_for_noise, threshold, local_factor, shadows, min_area,
                other_fraction, close_size, work_scale=None, edge_band=None,
                edge_fraction=0.3, graph_cut=False):
    thr = threshold
    if thr is None:
        thr = background.threshold
        if not np.isfinite(thr):  # a given plate: measure the noise on the video
            thr = _measure_threshold(frames_for_noise, background.plate)
    if work_scale is None:
        # Large frames: a person 200+ rows tall at half resolution loses nothing
        # the fitter uses, and every image operation is four times cheaper.
        # Larger still (1440p, 4K): shrunk to a shorter side of 480-720 pixels.
        short = min(background.plate.shape[:2])
        work_scale = max(2, short // MIN_SIDE_FOR_HALF) if short >= MIN_SIDE_FOR_HALF else 1
    if edge_band is None:
        edge_band = EDGE_BAND
    if shadows and is_monochrome(background.plate):
        # The shadow test looks for pixels darker than the plate *with the plate's
        # colour*; in a grey video every pixel has it, so a person darker than the
        # background by 5-40 % would be cut out as shadow (a third of the figure on
        # a synthetic walk: IoU 0.93 -> 0.65). Without colour, shadows stay in. The
        # plate decides, not the first frames, which may be black (a fade-in).
        shadows = False
    return _Params(background, thr, local_factor, shadows, min_area, other_fraction,
                   close_size, work_scale, edge_band, edge_fraction, graph_cut)


def is_monochrome(frames, *, max_spread: int = 4) -> bool:
    """Whether frames are grey: B, G and R within ``max_spread`` grey levels of each
    other at 99 % of (sampled) pixels.

    Monochrome cameras (infrared, many machine-vision and surveillance cameras) and
    grey encodings decode to three equal channels; a colour encoder's chroma noise on
    grey content stays within a level or two. Faded colour video is well above
    (the plate of ``ido_walk.avi``: 21 at the 99th percentile).

    Parameters
    ----------
    frames : array_like, shape (N, H, W, 3) or (H, W, 3), uint8

    Returns
    -------
    bool
    """
    f = np.asarray(frames)
    if f.ndim == 3:
        f = f[None]
    step = max(1, int(np.sqrt(f.shape[1] * f.shape[2] / 4096)))
    sub = f[:, ::step, ::step].astype(np.int16)
    spread = sub.max(axis=-1) - sub.min(axis=-1)
    return bool(np.quantile(spread, 0.99) <= max_spread)


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
    work_scale: int | None = None, edge_band: int | None = None,
    edge_fraction: float = 0.3, regions=None, graph_cut: bool = False,
) -> Iterator[tuple[np.ndarray, list[FrameSilhouette], np.ndarray]]:
    """Silhouettes chunk by chunk (for long videos); see :func:`extract_silhouettes`.

    Yields
    ------
    frames : sequence of numpy.ndarray, each (H, W, 3), uint8
        The chunk's frames (a list for a video file: stacking them would copy every
        frame once more for nothing).
    results : list of FrameSilhouette
    gains : numpy.ndarray, shape (n, 3)
    """
    if isinstance(source, np.ndarray):
        if source.ndim == 3:
            source = source[None]
        chunks = (source[i:i + chunk_size] for i in range(0, len(source), chunk_size))
    else:
        from vidcap.io.video import iter_frame_lists

        chunks = iter_frame_lists(source, chunk_size=chunk_size)
    params = None
    prev_box = None
    index = 0  # of the frame in the clip (for the user's regions)
    for chunk in chunks:
        h, w = chunk[0].shape[:2]
        if (h, w) != background.plate.shape[:2]:
            raise VidcapError(
                f"the background is {background.plate.shape[1]}x{background.plate.shape[0]} "
                f"but the video is {w}x{h} pixels",
                None if isinstance(source, np.ndarray) else source)
        if params is None:
            # (the noise is measured on the first 8 frames)
            params = _params_for(background, np.asarray(chunk[:8]), threshold, local_factor,
                                 shadows, min_area, other_fraction, close_size, work_scale,
                                 edge_band, edge_fraction, graph_cut)
        results, gains = [], []
        for frame in chunk:
            if frame.shape[:2] != background.plate.shape[:2]:
                raise VidcapError(
                    f"the frame size changes mid-stream (from {w}x{h} to "
                    f"{frame.shape[1]}x{frame.shape[0]}); re-encode the video at one size",
                    None if isinstance(source, np.ndarray) else source)
            keep = None if not regions else regions.keep_masks(index, params.work_size)
            index += 1
            r, g = silhouette_frame(frame, params, prev_box, keep)
            if r.bbox[0] >= 0:
                prev_box = r.bbox  # the person is followed, not the largest blob
            results.append(r)
            gains.append(g)
        yield chunk, results, np.array(gains)
    if params is None:
        raise VidcapError("the video has no frames",
                          None if isinstance(source, np.ndarray) else source)


def extract_silhouettes(
    source, background: BackgroundModel, *, threshold: float | None = None,
    local_factor: float = 3.0, shadows: bool = True, min_area: int | None = None,
    other_fraction: float = 0.2, close_size: int | None = None, chunk_size: int = 64,
    progress: bool | None = None, require_person: bool = True,
    work_scale: int | None = None, edge_band: int | None = None,
    edge_fraction: float = 0.3, on_masks=None, regions=None, crops=None,
    graph_cut: bool = False,
) -> Silhouettes:
    """Separate the person from the background in every frame.

    Parameters
    ----------
    source : str, path-like or numpy.ndarray
        A video file (decoded in chunks of ``chunk_size``) or frames (F, H, W, 3)
        uint8 BGR.
    background : BackgroundModel
        From :func:`vidcap.video.background.estimate_background` or
        :func:`vidcap.video.background.load_plate`.
    threshold : float, optional
        L1 colour-difference threshold (sum over B, G, R, grey levels). Default: the
        background's own, measured from the noise of background pixels.
    local_factor : float
        Per-pixel threshold is ``max(threshold, local_factor * noise_map)``.
    shadows : bool
        Drop pixels that look like shadows (darker, same chromaticity). Off by
        itself when the background plate is grey (:func:`is_monochrome`): in grey
        video every pixel has the background's chromaticity.
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
    work_scale : int, optional
        Difference, threshold, shadow test and clean-up run on frames shrunk by
        this factor (area averaging); the person's outline is scaled back and the
        mask drawn at the video's resolution. Default: 1 when the frame's shorter
        side is below ``MIN_SIDE_FOR_HALF`` (480) pixels, else ``max(2, side //
        480)`` (2 up to 1080p, 4 at 4K).
    edge_band : int, optional
        Pixels (full resolution) either side of the outline that are re-decided
        at full resolution by the person's own contrast: a pixel stays when its
        difference from the plate is at least ``edge_fraction`` of that of the
        person's interior nearby (a blurred edge is a mixture of the two).
        Default ``EDGE_BAND`` (3);
        0 = off (the plain threshold decides; at ``work_scale`` 2 a 2-pixel
        band is then re-decided on luma).
    edge_fraction : float
        Share of the interior's contrast an edge pixel needs, in (0, 1). Under
        pure mixing 0.5 keeps the pixels that are more than half person; real
        edges (motion blur, a limb's own shading, contrast varying along the
        body, which the interior mean blurs) favour a lower share: 0.3 keeps
        ido_walk's median IoU at 0.93 (0.88 at 0.5) and the synthetic H.264 clips
        at 0.98-0.99 (0.88 before, see benchmarks/RESULTS.md).
    on_masks : callable, optional
        Called as ``on_masks(start, masks)`` after each chunk with its frames' masks
        (a :class:`MaskStack` of frames ``start`` on; final: nothing later
        changes them), so a caller can start on them (the pipeline fits the first
        chunk of frames while the rest are still being extracted).
    regions : vidcap.video.userregions.UserRegions, optional
        The user's scene regions and person boxes: pixels the person may not be in.
    crops : FrameCrops, optional
        Each frame's colour crop around its silhouette is appended to it
        (:class:`vidcap.video.fit.cueframes.FrameCrops`, the 2D fit's cues), before
        ``on_masks`` is called for the chunk.
    graph_cut : bool
        Re-decide the band round the person and the never-seen area by a graph cut
        over space and time (:mod:`vidcap.video.graphcut`: plate difference, the
        clip's colour models); needs a plate estimated with ``colour_models=True``.
        Off here, and in ``vidcap convert`` and ``vidcap silhouettes`` by default
        (:data:`vidcap.video.pipeline.DEFAULT_GRAPH_CUT`: the fit on its silhouettes
        loses on the samples). A frame
        whose colours do not tell its scene from the person keeps the plain
        threshold's foreground (:data:`vidcap.video.graphcut.SCENE_KEPT_MIN`); about
        1.6x the silhouettes' time (benchmarks/RESULTS.md, Silhouettes).

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
    options = dict(threshold=threshold, local_factor=local_factor, shadows=shadows,
                   min_area=min_area, other_fraction=other_fraction, close_size=close_size,
                   chunk_size=chunk_size, work_scale=work_scale, edge_band=edge_band,
                   edge_fraction=edge_fraction, regions=regions, graph_cut=graph_cut)
    acc = _Collected()
    acc.run(source, background, options, progress, on_masks, crops)
    name = None if isinstance(source, np.ndarray) else source
    return acc.result(name, require_person)


class _Collected:
    """The per-frame results of :func:`iter_silhouettes`, gathered into arrays."""

    def __init__(self):
        self.masks = None  # MaskStack, made with the first frame
        self.bbox, self.areas, self.others, self.fracs, self.gains = [], [], [], [], []
        self.threshold = float("nan")

    def run(self, source, background, options, progress, on_masks, crops=None) -> None:
        from vidcap.fileio import progress as bar

        total = len(source) if isinstance(source, np.ndarray) else None
        if total is None:
            try:
                from vidcap.io.video import probe

                total = probe(source).n_frames
            except VidcapError:
                total = None
        start = 0
        pbar = bar(total=total, desc="silhouettes", unit="frame", enabled=progress)
        try:
            for chunk, res, gains in iter_silhouettes(source, background, **options):
                for j, r in enumerate(res):
                    self.add(start + j, r)
                    if crops is not None:
                        x0, y0, x1, y1 = (int(v) for v in r.bbox)
                        crops.append(chunk[j], (0, 0, 0, 0) if x0 < 0 else (y0, y1, x0, x1))
                self.gains.append(gains)
                if on_masks is not None:
                    on_masks(start, self.masks[start:])
                start += len(chunk)
                pbar.update(len(chunk))
        finally:
            pbar.close()

    def add(self, frame: int, r: FrameSilhouette) -> None:
        self.threshold = r.threshold
        if self.masks is None:
            self.masks = MaskStack(r.mask.shape)
        x0, y0, x1, y1 = (int(v) for v in r.bbox)
        # only the person's box is kept, bit-packed (the frame is not)
        self.masks.append(r.mask, None if x0 < 0 else (y0, y1, x0, x1))
        self.bbox.append(r.bbox)
        self.areas.append(r.area)
        self.fracs.append(r.foreground_fraction)
        if len(r.others):
            self.others.append(np.column_stack([np.full(len(r.others), frame), r.others]))

    def result(self, name, require_person: bool) -> Silhouettes:
        bbox = np.array(self.bbox, np.int64).reshape(-1, 4)
        found = bbox[:, 0] >= 0
        if require_person and not found.any():
            raise NoPersonError(
                "no frame differs from the background: nobody to extract (a static scene, "
                "or a background plate that shows the person?)", name)
        from vidcap.video.staticblobs import static_rows

        others = np.concatenate(self.others) if self.others else np.zeros((0, 6), np.int64)
        static = static_rows(others, len(bbox))
        n_other = np.bincount(others[~static, 0], minlength=len(bbox)).astype(np.int64)
        return Silhouettes(
            masks=self.masks,
            bbox=bbox,
            heights=np.where(found, bbox[:, 3] - bbox[:, 1], 0),
            areas=np.array(self.areas, np.int64),
            found=found,
            n_other_blobs=n_other,
            others=others,
            others_static=static,
            foreground_fraction=np.array(self.fracs, np.float32),
            threshold=float(self.threshold),
            gains=np.concatenate(self.gains),
        )
