"""The silhouette's outline re-decided in a band at full resolution.

:func:`vidcap.video.silhouette.silhouette_frame` finds the person at the work scale; the
pixels within a few pixels of the outline are then decided again on the full-resolution
frame, inside the mask's bounding box only (the work grows with the outline, not with the
frame): by the person's own contrast (:func:`edge_by_contrast`, the default: the codec's
and the optics' mixtures of person and scene are dropped) or by the plain full-resolution
threshold test (:func:`refine_edges`). ``p`` is the stage's parameters
(:class:`vidcap.video.silhouette._Params`: the full-resolution plate and threshold maps,
the band's width and the work scale).
"""

from __future__ import annotations

import cv2
import numpy as np

from vidcap.video.gaintable import apply_gain

__all__ = ["edge_by_contrast", "rect_within", "refine_edges"]


def _kernels():
    # numba loads with the first frame, not with the import (commands that never
    # compute a silhouette do not pay for it)
    from vidcap.video import _silhouette_kernels

    return _silhouette_kernels


def _plate_crop(p, g, gained, y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
    """The full-resolution plate's crop at the frame's gain ``g`` (unscaled where the
    gain is within 1 % of 1), from ``gained`` when the caller has it."""
    if gained is not None:
        return gained.crop(y0, y1, x0, x1)
    ref = p.plate_full[y0:y1, x0:x1]
    return apply_gain(ref, g) if np.abs(g - 1).max() > 0.01 else ref


def rect_within(mask: np.ndarray, box) -> tuple[int, int, int, int]:
    """``cv2.boundingRect(mask)`` when every non-zero pixel of ``mask`` lies in ``box``
    ``(x0, y0, x1, y1)``: only the box is scanned (a 640x480 mask took ~35 us)."""
    x0, y0, x1, y1 = box
    x, y, w, h = cv2.boundingRect(mask[y0:y1, x0:x1])
    return (x + x0, y + y0, w, h) if w else (0, 0, 0, 0)


def edge_by_contrast(mask: np.ndarray, frame: np.ndarray, g: np.ndarray, p,
                     floor: int = 0, reach=None, gained=None):
    """Re-decide the pixels near the outline by the person's own contrast.

    Antialiasing, optics and the codec (4:2:0 colour at half resolution, the
    deblocking filter) blur the outline into a band a few pixels wide of mixtures
    ``a * person + (1 - a) * background``. Against the plate such a pixel differs by
    ``a`` times the person's own difference (L1 is linear in ``a``), so the fixed
    noise threshold keeps mixtures with a few per cent of person in them and the
    mask comes out one to three pixels fat all round. In the band of
    ``edge_band`` pixels either side of the outline, a pixel is kept when its
    difference is at least ``edge_fraction`` of the mean difference of the
    person's interior pixels nearby (a box of ``4 * edge_band + 1`` pixels), and
    above the noise threshold. Where no interior pixel is near (limbs thinner
    than the band) the outline stays. Work is confined to the mask's bounding
    rectangle. ``reach``: a box ``(x0, y0, x1, y1)`` holding every pixel of the mask,
    when the caller has one. Returns such a box after the change (the crop worked on).
    ``gained``: the full-resolution plate at the frame's gain ``g``
    (:class:`vidcap.video.gaintable.GainedPlate`), when the caller has one.
    """
    r = p.edge_band
    x, y, w, h = cv2.boundingRect(mask) if reach is None else rect_within(mask, reach)
    x0, y0 = max(0, x - r), max(0, y - r)
    x1, y1 = min(mask.shape[1], x + w + r), min(mask.shape[0], y + h + r)
    m = mask[y0:y1, x0:x1]
    k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    inner = cv2.erode(m, k)
    near = cv2.dilate(m, k)
    ref = _plate_crop(p, g, gained, y0, y1, x0, x1)
    kern = _kernels()
    l1 = np.empty(m.shape, np.uint8)
    kern.l1_sum(cv2.absdiff(frame[y0:y1, x0:x1], ref), l1)
    l1 = cv2.medianBlur(l1, 3)
    box = (4 * r + 1, 4 * r + 1)
    # Box means on uint8 (OpenCV's fast path): the interior's mean difference is
    # num / den with num = mean of l1 over interior pixels (0 elsewhere) and den =
    # 255 * the interior's share of the box.
    masked, inner255 = np.empty_like(l1), np.empty_like(l1)
    kern.interior(l1, inner, masked, inner255)
    num = cv2.blur(masked, box)
    den = cv2.blur(inner255, box)
    fg = np.empty_like(l1)
    kern.edge_keep(l1, den, num, p.tmap_full[y0:y1, x0:x1], int(floor),
                   np.float32(255.0 * p.edge_fraction), fg)
    fg = cv2.medianBlur(fg, 3)
    kern.copy_in_band(m, fg, near, inner, den)  # the band, where an interior is near
    return x0, y0, x1, y1


def refine_edges(mask: np.ndarray, frame: np.ndarray, g: np.ndarray, p,
                 floor: int = 0, reach=None, gained=None):
    """Re-decide, at full resolution, the pixels near an outline found at work scale.

    The band of ``work_scale`` pixels either side of the outline takes the
    full-resolution threshold test (no shadow test); the rest of the mask stays.
    Work is confined to the mask's bounding rectangle, so it grows with the
    person's outline, not with the frame. ``reach``, ``gained`` and the box returned:
    as :func:`edge_by_contrast`'s.
    """
    r = int(np.ceil(max(p.fx, p.fy)))
    x, y, w, h = cv2.boundingRect(mask) if reach is None else rect_within(mask, reach)
    x0, y0 = max(0, x - r), max(0, y - r)
    x1, y1 = min(mask.shape[1], x + w + r), min(mask.shape[0], y + h + r)
    m = mask[y0:y1, x0:x1]
    k = np.ones((2 * r + 1, 2 * r + 1), np.uint8)
    band = cv2.subtract(cv2.dilate(m, k), cv2.erode(m, k))
    ref = _plate_crop(p, g, gained, y0, y1, x0, x1)
    if p.edge_luma:
        # Video codecs keep colour at half resolution (4:2:0): a colour edge
        # bleeds a pixel or two into the background, brightness does not.
        d = cv2.absdiff(cv2.cvtColor(frame[y0:y1, x0:x1], cv2.COLOR_BGR2GRAY),
                        cv2.cvtColor(ref, cv2.COLOR_BGR2GRAY))
        tl = p.tmap_luma[y0:y1, x0:x1]
        fg = cv2.compare(d, np.maximum(tl, np.uint8(-(-floor // 3))) if floor else tl,
                         cv2.CMP_GT)
    else:
        b, g_, r_ = cv2.split(cv2.absdiff(frame[y0:y1, x0:x1], ref))
        tf = p.tmap_full[y0:y1, x0:x1]
        fg = cv2.compare(cv2.add(cv2.add(b, g_), r_),
                         np.maximum(tf, np.uint8(floor)) if floor else tf, cv2.CMP_GT)
    fg = cv2.medianBlur(fg, 3)
    # m = m outside the band, the full-resolution test inside it.
    np.copyto(m, (fg > 0).view(np.uint8), where=band > 0)
    return x0, y0, x1, y1
