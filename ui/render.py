"""Pictures for the annotate and review pages: the 2D model over a frame, the
silhouette with the model, a side view of the 3D pose, and image encoding.

All drawing is done with OpenCV on BGR ``uint8`` images; coordinates are pixels,
x right and y down (as everywhere in vidcap).
"""

from __future__ import annotations

import base64

import cv2
import numpy as np

from vidcap.body import JOINT_NAMES, SEGMENT_JOINTS, SEGMENT_NAMES

#: Segment colours (BGR) by depth sign: distal end toward the camera / away from it.
TOWARD_BGR = (40, 160, 255)  # orange
AWAY_BGR = (230, 120, 40)  # blue
LOW_CONFIDENCE_BGR = (40, 40, 230)  # red ring at the segment's middle
USER_JOINT_BGR = (60, 220, 60)  # green: a joint the user placed
JOINT_BGR = (255, 255, 255)
#: CSS colours matching the above, for the page's legend.
TOWARD_CSS = "rgb(255,160,40)"
AWAY_CSS = "rgb(40,120,230)"
LOW_CSS = "rgb(230,40,40)"
USER_CSS = "rgb(60,220,60)"


def _pt(p) -> tuple[int, int]:
    return int(round(float(p[0]) * 4)), int(round(float(p[1]) * 4))


def draw_model(image: np.ndarray, joints2d: np.ndarray, signs: np.ndarray, *,
               low_confidence=None, user_signs=None, user_joints=None,
               selected: str | None = None, thickness: int | None = None) -> np.ndarray:
    """Draw the 2D body model over ``image``.

    Parameters
    ----------
    image : numpy.ndarray, shape (H, W, 3) uint8
        BGR picture (not modified).
    joints2d : numpy.ndarray, shape (15, 2)
        Joints in pixels (x right, y down), :data:`vidcap.body.JOINT_NAMES` order.
    signs : numpy.ndarray, shape (10,)
        Depth sign per segment: +1 toward the camera (orange), -1 away (blue).
    low_confidence : numpy.ndarray of bool, shape (10,), optional
        Segments to mark with a red ring (the fit or the sign is doubtful).
    user_signs : numpy.ndarray of bool, shape (10,), optional
        Segments whose sign the user set (drawn solid; proposals are drawn thinner).
    user_joints : numpy.ndarray of bool, shape (15,), optional
        Joints the user placed (green, larger).
    selected : str, optional
        A segment name to highlight.
    thickness : int, optional
        Line width in pixels (default from the image size).

    Returns
    -------
    numpy.ndarray, shape (H, W, 3) uint8
    """
    out = np.ascontiguousarray(image).copy()
    h, w = out.shape[:2]
    t = thickness or max(2, int(round(min(h, w) / 110)))
    low = np.zeros(len(SEGMENT_NAMES), bool) if low_confidence is None else low_confidence
    usr = np.zeros(len(SEGMENT_NAMES), bool) if user_signs is None else user_signs
    uj = np.zeros(len(JOINT_NAMES), bool) if user_joints is None else user_joints
    j = np.asarray(joints2d, dtype=float)
    shift = dict(shift=2, lineType=cv2.LINE_AA)
    ok = np.isfinite(j).all(axis=1)  # frames without a fit have NaN joints: draw what there is
    for k, (a, b) in enumerate(SEGMENT_JOINTS):
        if not (ok[a] and ok[b]):
            continue
        colour = TOWARD_BGR if signs[k] >= 0 else AWAY_BGR
        if SEGMENT_NAMES[k] == selected:
            cv2.line(out, _pt(j[a]), _pt(j[b]), (255, 255, 255), t + 4, **shift)
        cv2.line(out, _pt(j[a]), _pt(j[b]), colour, t + (1 if usr[k] else 0), **shift)
        if low[k]:
            mid = (j[a] + j[b]) / 2
            cv2.circle(out, _pt(mid), 4 * (t + 3), LOW_CONFIDENCE_BGR, max(1, t // 2), **shift)
    r = t + 1
    for i, p in enumerate(j):
        if not ok[i]:
            continue
        if uj[i]:
            cv2.circle(out, _pt(p), 4 * (r + 2), USER_JOINT_BGR, -1, **shift)
        cv2.circle(out, _pt(p), 4 * r, JOINT_BGR, -1, **shift)
        cv2.circle(out, _pt(p), 4 * r, (0, 0, 0), 1, **shift)
    return out


def silhouette_image(mask: np.ndarray | None, shape: tuple[int, int]) -> np.ndarray:
    """The silhouette as a BGR picture (person light grey on dark), shape (H, W, 3)."""
    img = np.full((*shape, 3), 30, np.uint8)
    if mask is not None:
        img[np.asarray(mask, bool)] = 200
    return img


def side_view(joints3d: np.ndarray, signs: np.ndarray, *, size=(240, 320),
              height_m: float = 2.0) -> np.ndarray:
    """The 3D pose seen from the side: depth (Z, toward the camera = right) against height.

    Parameters
    ----------
    joints3d : numpy.ndarray, shape (15, 3)
        Joints in metres, X right, Y up, Z toward the camera.
    signs : numpy.ndarray, shape (10,)
        Depth signs, for the segment colours.
    size : tuple of int
        (width, height) of the picture in pixels.
    height_m : float
        Metres shown from top to bottom.

    Returns
    -------
    numpy.ndarray, shape (H, W, 3) uint8 BGR
    """
    w, h = size
    img = np.full((h, w, 3), 250, np.uint8)
    p = np.asarray(joints3d, dtype=float)
    s = (h - 20) / height_m
    if not np.isfinite(p).any():
        return img
    floor_y = np.nanmin(p[:, 1])
    centre_z = np.nanmean(p[:, 2])
    uv = np.column_stack([w / 2 + (p[:, 2] - centre_z) * s, h - 10 - (p[:, 1] - floor_y) * s])
    cv2.line(img, (0, h - 10), (w, h - 10), (170, 170, 170), 1)
    cv2.putText(img, "camera ->", (w - 78, h - 14), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (120, 120, 120),
                1, cv2.LINE_AA)
    return draw_model(img, uv, signs, thickness=2)


def data_url(image: np.ndarray, *, fmt: str = ".jpg", quality: int = 85) -> str:
    """Encode a BGR image as a ``data:`` URL for an ``<img src>``."""
    params = [cv2.IMWRITE_JPEG_QUALITY, quality] if fmt == ".jpg" else []
    ok, buf = cv2.imencode(fmt, np.ascontiguousarray(image), params)
    if not ok:  # pragma: no cover - OpenCV always encodes uint8 BGR
        raise ValueError("could not encode the image")
    mime = "jpeg" if fmt == ".jpg" else fmt.lstrip(".")
    return f"data:image/{mime};base64," + base64.b64encode(buf.tobytes()).decode("ascii")


def fit_width(image: np.ndarray, width: int) -> np.ndarray:
    """Scale ``image`` (nearest for small upscales of tiny clips, area when shrinking)."""
    h, w = image.shape[:2]
    if w == width:
        return image
    interp = cv2.INTER_AREA if width < w else cv2.INTER_LINEAR
    return cv2.resize(image, (width, max(1, round(h * width / w))), interpolation=interp)


#: Colours (BGR) of the user's regions over the frame: scene (never the person), the
#: person's box; and of the silhouette laid over the frame.
SCENE_REGION_BGR = (60, 60, 230)  # red
PERSON_BOX_BGR = (60, 220, 60)  # green
SILHOUETTE_BGR = (255, 200, 0)  # cyan
SCENE_REGION_CSS = "rgb(230,60,60)"
PERSON_BOX_CSS = "rgb(60,220,60)"
SILHOUETTE_CSS = "rgb(0,200,255)"


def overlay_silhouette(image: np.ndarray, mask: np.ndarray | None, *,
                       alpha: float = 0.4) -> np.ndarray:
    """``image`` (H, W, 3) BGR with the silhouette ``mask`` (any size, bool; scaled to
    the image) tinted over it and outlined, so what was taken for the person shows."""
    out = np.ascontiguousarray(image).copy()
    if mask is None:
        return out
    h, w = out.shape[:2]
    m = np.asarray(mask, np.uint8)
    if m.shape != (h, w):
        m = cv2.resize(m, (w, h), interpolation=cv2.INTER_NEAREST)
    sel = m > 0
    tint = np.array(SILHOUETTE_BGR, np.float32)
    out[sel] = (out[sel] * (1 - alpha) + tint * alpha).astype(np.uint8)
    contours, _ = cv2.findContours(m, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    cv2.drawContours(out, contours, -1, SILHOUETTE_BGR, 1, cv2.LINE_AA)
    return out


def draw_regions(image: np.ndarray, regions, scale: float) -> np.ndarray:
    """The user's regions over ``image``: scene regions hatched red, the person box
    green. ``regions``: dicts with ``type`` and ``box`` or ``polygon`` (video pixels,
    as :func:`vidcap.ui.regionedit.region_items` lists them); ``scale``: image pixels
    per video pixel."""
    out = np.ascontiguousarray(image).copy()
    for r in regions:
        colour = SCENE_REGION_BGR if r["type"] == "scene_region" else PERSON_BOX_BGR
        if "box" in r:
            x0, y0, x1, y1 = r["box"]
            pts = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float)
        else:
            pts = np.asarray(r["polygon"], float)
        poly = np.round(pts * scale * 4).astype(np.int32).reshape(-1, 1, 2)
        if r["type"] == "scene_region":  # shaded: these pixels are never the person
            shade = out.copy()
            cv2.fillPoly(shade, [poly], colour, cv2.LINE_AA, shift=2)
            out = cv2.addWeighted(shade, 0.3, out, 0.7, 0)
        cv2.polylines(out, [poly], True, colour, 2, cv2.LINE_AA, shift=2)
    return out
