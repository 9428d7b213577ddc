"""A camera's perspective on the person read from the scene: the vertical vanishing point.

Beyond the seed (issue 27, real footage). A camera above a standing person looks down on
them: the scene's verticals (door frames, a table's stand, the corners of walls, the person
standing) converge on one image point below the frame, the *vertical vanishing point*. A
vertical body's points at height fraction u (0 at the head's top, 1 at the soles) are
imaged at ``g(u) = u (1 + k) / (1 + k u)`` of its image height
(:mod:`vidcap.video.fit.perspective`); the point at infinity along the body (u -> inf) is
the vanishing point, at ``(1 + k) / k`` body heights from the head's top. So a person whose
head top and soles are imaged at ``top`` and ``bottom`` gives

    k = 1 / (s - 1),   s = (vp - top) . (bottom - top) / |bottom - top|^2

(``s`` -> inf, k -> 0, for a level camera whose verticals stay parallel; a k within
:data:`K_LEVEL` of 0 is taken as 0).

:func:`scene_perspective` finds the vanishing point in the background plate: the near-
vertical line segments of the plate (OpenCV's line segment detector) fall into families
that meet at one point each (:func:`vanishing_families`, RANSAC over pairs). Not every
family is the verticals': a wooden floor's boards, receding from the camera, are near
vertical in the image too and meet on the horizon, above the person. The person tells them
apart: a standing person is a vertical, so the verticals' vanishing point lies on the
line from their head to their feet in every frame (:func:`person_axes`), and a family
whose point does not (:data:`MAX_MISFIT_DEG`) or gives an implausible k
(:data:`K_RANGE`) is left out; of the rest, the family the longest segments support is
taken. No family left: k = 0, the scaled orthography of the seed.

Measured (``benchmarks/pose2d_real.py``, RESULTS.md): the Pose2Sim trial's three
calibrated cameras give k 0.22-0.25 against their calibration's 0.20-0.21; the level
cameras of the other real clips 0.00 ± 0.02.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["K_LEVEL", "K_RANGE", "MAX_MISFIT_DEG", "ScenePerspective", "k_from_vanishing_point",
           "NOTICE_K", "camera_notice", "line_segments", "person_axes", "scene_k",
           "scene_k_for", "scene_perspective", "vanishing_families"]

#: Segments within this many degrees of the image's vertical may be the scene's verticals
#: (a camera pitched 35 degrees down images a vertical at the frame's edge ~20 degrees off).
MAX_TILT_DEG = 25.0
#: ... at least this share of the image height long (shorter ones are texture).
MIN_LENGTH = 0.04
#: A segment belongs to a family whose point lies within this many degrees of its line.
INLIER_DEG = 1.0
#: A family has at least this many segments.
MIN_SEGMENTS = 3
#: Families looked for, one after another, each among the segments the others left.
FAMILIES = 3
#: Pairs of segments tried per family (RANSAC).
TRIALS = 600
#: The person's head-to-feet line passes within this many degrees (median over frames) of
#: a family's point when the family is the scene's verticals. Chosen on the tuning clips
#: (onebyone_room: the verticals 1.7, its floor boards 8.0; Pose2Sim cam1, cam3, cam4, a
#: person balancing on one leg: the verticals 6.1, 5.7, 9.5).
MAX_MISFIT_DEG = 10.0
#: The k a family may give: a camera whose feet are at most twice as far as the head (a
#: steep wall mount) down to one a quarter nearer (a camera low down, looking up).
K_RANGE = (-0.25, 1.0)
#: A k this near 0 is taken as 0: a camera whose view of the feet is within 5 % as far
#: as of the head draws the body as the seed's scaled orthography does (a level camera's
#: verticals meet ever so far away; warping the body by so little only moves the fit by
#: its own swing).
K_LEVEL = 0.05
#: A k at least this far from 0 read from the scene of a clip given no ``--camera`` is
#: told to the user (:func:`camera_notice`): the 16 real videos with a level camera read
#: |k| < 0.05, the 7 high ones 0.14-0.48 (SBI's corridor ceiling cameras, Pose2Sim's lab
#: cameras, onebyone's wall mount; ``benchmarks/scene_perspective.py``), where the level
#: body's shoulders and hips read 2-12 % of the height high.
NOTICE_K = 0.1
#: Frames whose person is at least this share of the clip's 90th-percentile image height
#: give axes (a person standing, not crouched, bent or half out of view).
TALL = 0.85
#: At most this many frames are read for the person's axes.
MAX_FRAMES = 200


@dataclass(frozen=True)
class ScenePerspective:
    """What :func:`scene_perspective` found.

    Attributes
    ----------
    k : float
        The perspective number of :mod:`vidcap.video.fit.perspective` (0: none found, or
        within :data:`K_LEVEL` of 0).
    vanishing_point : numpy.ndarray, shape (2,), or None
        The chosen family's point, image pixels (x right, y down); None when none.
    segments : int
        Segments of the chosen family (0: none).
    misfit_deg : float
        Median angle between the person's axis and the direction to the point (NaN: none).
    reason : str
        One line for the log: what was found, or why no k.
    """

    k: float
    vanishing_point: np.ndarray | None
    segments: int
    misfit_deg: float
    reason: str


def line_segments(image: np.ndarray) -> np.ndarray:
    """Straight line segments of an image (OpenCV's LSD).

    Parameters
    ----------
    image : numpy.ndarray, shape (H, W, 3) or (H, W), uint8

    Returns
    -------
    numpy.ndarray, shape (N, 4), float
        ``x0, y0, x1, y1`` per segment, pixels.
    """
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    found = cv2.createLineSegmentDetector().detect(np.ascontiguousarray(grey, np.uint8))[0]
    return np.zeros((0, 4)) if found is None else found.reshape(-1, 4).astype(float)


def _misfit_deg(points: np.ndarray, mids: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Angle (degrees) between each segment (midpoint ``mids`` (N, 2), unit direction
    ``dirs`` (N, 2)) and the direction from its midpoint to each homogeneous point of
    ``points`` (M, 3): (M, N). A point at infinity (third coordinate 0) is a direction."""
    to = points[:, None, :2] - points[:, None, 2:3] * mids[None]
    norm = np.linalg.norm(to, axis=-1)
    cos = np.abs((to * dirs[None]).sum(-1)) / np.maximum(norm, 1e-12)
    return np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))


def vanishing_families(segments: np.ndarray, height: int, *, rng=None):
    """Families of near-vertical segments that meet at one point each.

    Parameters
    ----------
    segments : numpy.ndarray, shape (N, 4)
        :func:`line_segments`.
    height : int
        The image's height, pixels (the minimum length is :data:`MIN_LENGTH` of it).
    rng : numpy.random.Generator, optional
        For the pairs tried (default: seeded, the same families every run).

    Returns
    -------
    list of (numpy.ndarray (3,), int, float)
        Per family, best supported first: its point (homogeneous, unit norm), its
        segments and their summed length, pixels.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    seg = np.asarray(segments, float).reshape(-1, 4)
    d = seg[:, 2:] - seg[:, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    tilt = np.degrees(np.arctan2(np.abs(d[:, 0]), np.abs(d[:, 1])))
    keep = (tilt <= MAX_TILT_DEG) & (length >= MIN_LENGTH * height)
    seg, d, length = seg[keep], d[keep], length[keep]
    mids, dirs = (seg[:, :2] + seg[:, 2:]) / 2, d / np.maximum(length, 1e-12)[:, None]
    ones = np.ones((len(seg), 1))
    lines = np.cross(np.hstack([seg[:, :2], ones]), np.hstack([seg[:, 2:], ones]))
    lines /= np.maximum(np.linalg.norm(lines[:, :2], axis=1, keepdims=True), 1e-12)
    alive = np.ones(len(seg), bool)
    out = []
    for _ in range(FAMILIES):
        idx = np.flatnonzero(alive)
        if len(idx) < MIN_SEGMENTS:
            break
        pairs = rng.choice(idx, size=(TRIALS, 2))
        points = np.cross(lines[pairs[:, 0]], lines[pairs[:, 1]])
        norm = np.linalg.norm(points, axis=1)
        good = (pairs[:, 0] != pairs[:, 1]) & (norm > 1e-12)
        if not good.any():
            break
        points = points[good] / norm[good, None]
        inlier = (_misfit_deg(points, mids, dirs) < INLIER_DEG) & alive[None]
        support = inlier @ length
        best = inlier[int(np.argmax(support))]
        if best.sum() < MIN_SEGMENTS:
            break
        # the point nearest every inlier's line, each weighed by its length
        point = np.linalg.svd(lines[best] * np.sqrt(length[best])[:, None])[2][-1]
        out.append((point, int(best.sum()), float(length[best].sum())))
        alive &= ~best
    return out


def person_axes(masks, *, max_frames: int = MAX_FRAMES):
    """The standing person's head top and feet in the clip's tallest frames.

    Parameters
    ----------
    masks : sequence of numpy.ndarray (H, W) bool
        The silhouettes (a :class:`vidcap.video.masks.MaskStack` or an (F, H, W) array).
    max_frames : int
        At most this many frames, evenly spread, are read.

    Returns
    -------
    top, bottom : numpy.ndarray, shape (K, 2)
        Per frame read whose silhouette is at least :data:`TALL` of the clip's
        90th-percentile height: the middle of its top and bottom tenth, at its first and
        last row, pixels (x right, y down).
    """
    n = len(masks)
    picks = np.unique(np.linspace(0, n - 1, min(n, max_frames)).round().astype(int)) if n else []
    tops, bottoms = [], []
    for f in picks:
        m = np.asarray(masks[f])
        rows = np.flatnonzero(m.any(axis=1))
        if len(rows) < 10:
            continue
        y0, y1 = int(rows[0]), int(rows[-1])
        band = max(2, (y1 - y0) // 10)
        xs_top = np.nonzero(m[y0:y0 + band])[1]
        xs_bottom = np.nonzero(m[y1 - band + 1:y1 + 1])[1]
        tops.append((xs_top.mean(), y0))
        bottoms.append((xs_bottom.mean(), y1))
    top, bottom = np.array(tops, float).reshape(-1, 2), np.array(bottoms, float).reshape(-1, 2)
    if len(top):
        tall = bottom[:, 1] - top[:, 1]
        keep = tall >= TALL * np.percentile(tall, 90)
        top, bottom = top[keep], bottom[keep]
    return top, bottom


def k_from_vanishing_point(point: np.ndarray, top: np.ndarray, bottom: np.ndarray) -> np.ndarray:
    """k of a vertical body imaged from ``top`` to ``bottom`` (each (K, 2) pixels) under
    the vanishing point ``point`` (homogeneous (3,)): (K,); NaN where the point lies
    between them (no camera images a vertical so)."""
    axis = bottom - top
    length2 = np.maximum((axis * axis).sum(1), 1e-12)
    if abs(point[2]) <= 1e-12 * np.linalg.norm(point[:2]):
        return np.zeros(len(top))  # parallel verticals: a level camera
    s = ((point[:2] / point[2] - top) * axis).sum(1) / length2
    with np.errstate(divide="ignore"):
        k = 1.0 / (s - 1.0)
    return np.where((s > 0.0) & (s <= 1.0), np.nan, k)


def scene_perspective(plate: np.ndarray, masks, *, rng=None) -> ScenePerspective:
    """The camera's perspective k from the plate's verticals and the person's axes.

    Parameters
    ----------
    plate : numpy.ndarray, shape (H, W, 3), uint8
        The background plate (BGR).
    masks : sequence of numpy.ndarray (H, W) bool
        The person's silhouettes (:func:`person_axes`).
    rng : numpy.random.Generator, optional
        For :func:`vanishing_families` (default: seeded).

    Returns
    -------
    ScenePerspective
        k = 0 with the reason when the plate has no family of verticals the person agrees
        with.
    """
    top, bottom = person_axes(masks)
    if not len(top):
        return ScenePerspective(0.0, None, 0, float("nan"), "no standing person to measure")
    families = vanishing_families(line_segments(plate), plate.shape[0], rng=rng)
    if not families:
        return ScenePerspective(0.0, None, 0, float("nan"),
                                "the background shows no family of vertical lines")
    mids = (top + bottom) / 2
    axis = bottom - top
    dirs = axis / np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-12)
    tried = []
    for point, count, _ in families:  # best supported first
        misfit = float(np.median(_misfit_deg(point[None], mids, dirs)[0]))
        k = float(np.nanmedian(k_from_vanishing_point(point, top, bottom)))
        tried.append(f"{count} lines, person {misfit:.1f} deg off, k {k:.2f}")
        if misfit <= MAX_MISFIT_DEG and K_RANGE[0] <= k <= K_RANGE[1]:
            vp = point[:2] / point[2] if abs(point[2]) > 1e-12 else None
            where = ("parallel" if vp is None else
                     f"meet at ({vp[0]:.0f}, {vp[1]:.0f}) px")
            level = abs(k) < K_LEVEL
            return ScenePerspective(0.0 if level else k, vp, count, misfit,
                                    f"the scene's verticals ({count} lines) {where}, "
                                    f"the person's axis {misfit:.1f} deg from them: k = {k:.2f}"
                                    + (" (a level camera: none applied)" if level else ""))
    return ScenePerspective(0.0, None, 0, float("nan"),
                            "no family of lines is the person's vertical ("
                            + "; ".join(tried) + ")")


def scene_k(plate: np.ndarray, masks, log=None) -> float:
    """:func:`scene_perspective`'s k (``vidcap convert --camera auto``), with one line
    to ``log`` saying what the scene gave."""
    found = scene_perspective(plate, masks)
    if log is not None:
        log(f"camera perspective: {found.reason}")
    return found.k


def camera_notice(found: ScenePerspective) -> str | None:
    """One line for a user who described no camera when the scene shows one well above
    or below the subject (|k| >= :data:`NOTICE_K`), else None."""
    if abs(found.k) < NOTICE_K:
        return None
    above = found.k > 0
    return (f"notice: the camera looks {'down on' if above else 'up at'} the subject (the "
            f"scene's verticals meet {'below' if above else 'above'} the frame, k = "
            f"{found.k:.2f}): the 2D body, drawn for a camera level with the subject's "
            f"middle, reads the shoulders and hips {'high' if above else 'low'}; "
            "--camera auto draws it as this camera sees it")


def scene_k_for(camera, k: float, plate: np.ndarray, masks, log=None) -> float:
    """``vidcap convert``'s k once the silhouettes exist.

    Parameters
    ----------
    camera : None, 'auto' or sequence of float
        ``--camera``'s value.
    k : float
        The k of a described camera (:func:`vidcap.video.fit.perspective.camera_perspective`).
    plate : numpy.ndarray, shape (H, W, 3), uint8
        The background plate (BGR).
    masks : sequence of numpy.ndarray (H, W) bool
        The person's silhouettes.
    log : callable, optional
        Gets :func:`scene_k`'s line with 'auto', :func:`camera_notice`'s with no camera.

    Returns
    -------
    float
        The scene's k with 'auto' (:func:`scene_k`), else ``k`` as given: with no
        ``camera`` the scene is read only to tell the user of a camera far from level.
    """
    if camera == "auto":
        return scene_k(plate, masks, log)
    if camera is None and log is not None:
        notice = camera_notice(scene_perspective(plate, masks))
        if notice:
            log(notice)
    return k
