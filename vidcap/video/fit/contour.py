"""Contour analysis of seed 004 section 3.1.4.3: limb curves, elbow corner, knee crossing.

* :func:`row_runs` - the horizontal scan lines: runs of silhouette pixels per row.
* :func:`fit_angle` / :func:`split_angles` - "FindAngle": the image-plane angle of a
  least-squares (principal-axis) line through a curve, oriented from its first point
  to its last; :func:`split_angles` fits both halves for every split point at once
  from prefix sums (Algorithm 4's loop without a Python loop).
* :func:`elbow_corner` (Algorithm 4) and :func:`arm_angles` (Algorithm 3).
* :func:`leg_curves` and :func:`knees_crossed` (Algorithms 2 and 5).
* :func:`limb_curve` - an ordered curve from scattered limb pixels.

Angles are image-plane angles in radians (counter-clockwise from +x, y up; see
:mod:`vidcap.video.fit.raster`). Points are ``(x, y)`` pixels, y down.

Deviations from the pseudo-code (the text's meaning is followed):

* Algorithm 4 tests ``listOfPossibleCorners.Length >= 0``, which is always true and
  would look for a maximum in an empty list; it must be ``> 0`` (no candidate means
  no elbow, index -1, as Algorithm 3 expects).
* Algorithm 4 tries corners from ``minimumCornerDistance`` to ``Length - 1``, so the
  lower part can be a single point whose "angle" is undefined; the minimum distance
  is applied at both ends.
* Algorithm 2 names the knee scan lists ``LLKLineList``/``RLKLineList`` and then
  passes ``LeftLowerKneeLineList``/``RightLowerKneeLineList``; they are the same
  lists. Section 3.1.4.3's first sentence lists the "upper right leg" among the
  contour segments; Algorithm 2 (and the rest of the text) means the lower right leg.
* Algorithm 5 says "LLLLineList[i] intersects RLLLineList[i]": on scan line i the
  left and right lower-leg runs are one and the same run (the legs overlap). Legs
  are crossed when, going down from the knees, the scan lines first show one merged
  run and then two separate runs to the end.
"""

from __future__ import annotations

import numpy as np

from vidcap.video.fit.raster import image_angle


def row_runs(mask: np.ndarray):
    """Runs of ``True`` along every row (the horizontal scan lines).

    Parameters
    ----------
    mask : numpy.ndarray, shape (h, w), bool

    Returns
    -------
    rows, starts, ends : numpy.ndarray of int, shape (R,)
        Row of each run, its first column and its last column (inclusive), sorted by
        row then column.
    """
    m = np.asarray(mask, dtype=bool)
    padded = np.zeros((m.shape[0], m.shape[1] + 2), dtype=np.int8)
    padded[:, 1:-1] = m
    d = np.diff(padded, axis=1)
    r0, c0 = np.nonzero(d == 1)
    r1, c1 = np.nonzero(d == -1)
    return r0, c0, c1 - 1


def _fit_from_sums(n, sx, sy, sxx, syy, sxy, first, last):
    mx, my = sx / n, sy / n
    cxx = sxx / n - mx * mx
    cyy = syy / n - my * my
    cxy = sxy / n - mx * my
    theta = 0.5 * np.arctan2(2 * cxy, cxx - cyy)  # principal axis in pixel coords
    d = np.stack([np.cos(theta), np.sin(theta)], axis=-1)
    flip = ((last - first) * d).sum(-1) < 0
    return image_angle(d * np.where(flip, -1.0, 1.0)[..., None])


def fit_angle(points: np.ndarray) -> float:
    """Angle of the principal-axis line through ``points``, oriented first -> last.

    Parameters
    ----------
    points : numpy.ndarray, shape (N, 2)
        An ordered curve, ``(x, y)`` pixels, N >= 2.

    Returns
    -------
    float
        Image-plane angle in radians in [0, 2 pi).
    """
    p = np.asarray(points, dtype=float)
    if len(p) < 2:
        raise ValueError("need at least two points to fit a line")
    x, y = p[:, 0], p[:, 1]
    return float(
        _fit_from_sums(len(p), x.sum(), y.sum(), (x * x).sum(), (y * y).sum(), (x * y).sum(),
                       p[0], p[-1])
    )


def split_angles(points: np.ndarray, splits: np.ndarray):
    """Line angles of ``points[:i+1]`` and ``points[i:]`` for every split ``i``.

    Parameters
    ----------
    points : numpy.ndarray, shape (N, 2)
        Ordered curve.
    splits : numpy.ndarray of int, shape (K,)
        Split indices, each in [1, N-2].

    Returns
    -------
    upper, lower : numpy.ndarray, shape (K,)
        Angles (radians) of the part before (including) and after (including) the
        split point.
    """
    p = np.asarray(points, dtype=float)
    i = np.asarray(splits, dtype=int)
    x, y = p[:, 0], p[:, 1]
    cs = np.cumsum(np.stack([np.ones_like(x), x, y, x * x, y * y, x * y]), axis=1)
    cs = np.concatenate([np.zeros((6, 1)), cs], axis=1)  # cs[:, k] = sum of first k
    head = cs[:, i + 1]
    tail = cs[:, -1][:, None] - cs[:, i]
    upper = _fit_from_sums(*head, p[0][None], p[i])
    lower = _fit_from_sums(*tail, p[i], p[-1][None])
    return upper, lower


def elbow_corner(points: np.ndarray, *, min_distance: int = 4,
                 min_angle_difference: float = np.deg2rad(10.0)) -> int:
    """Algorithm 4: the index of the elbow corner on an arm curve, or -1.

    Every point at least ``min_distance`` from both ends is tried as the corner;
    those where the upper and lower line angles differ by more than
    ``min_angle_difference`` are candidates, and the one with the largest difference
    wins.

    Parameters
    ----------
    points : numpy.ndarray, shape (N, 2)
        The arm curve ordered from the shoulder outward.
    min_distance : int
        ``minimumCornerDistance`` (4 in the seed), in points.
    min_angle_difference : float
        ``minimumCornerAngleDifference`` (10 degrees in the seed), radians.

    Returns
    -------
    int
        Index into ``points``, or -1 when there is no corner.
    """
    n = len(points)
    splits = np.arange(min_distance, n - min_distance)
    if splits.size == 0:
        return -1
    upper, lower = split_angles(points, splits)
    diff = np.abs(np.angle(np.exp(1j * (upper - lower))))
    ok = diff > min_angle_difference
    if not ok.any():  # the seed's ">= 0" test; see the module docstring
        return -1
    return int(splits[np.flatnonzero(ok)[np.argmax(diff[ok])]])


def arm_angles(points: np.ndarray, **corner_kw):
    """Algorithm 3: lower and upper arm angles from an arm curve.

    Parameters
    ----------
    points : numpy.ndarray, shape (N, 2)
        Arm curve ordered from the shoulder outward, N >= 2.
    **corner_kw
        Passed to :func:`elbow_corner`.

    Returns
    -------
    lower, upper : float
        Angles of the lower and upper arm in radians (equal when no elbow is found).
    corner : int
        The elbow corner's index, or -1.
    """
    corner = elbow_corner(points, **corner_kw)
    if corner < 0:
        a = fit_angle(points)
        return a, a, -1
    return fit_angle(points[corner:]), fit_angle(points[: corner + 1]), corner


def knees_crossed(intersects: np.ndarray) -> bool:
    """Algorithm 5: do the lower legs cross?

    Parameters
    ----------
    intersects : numpy.ndarray, shape (R,), bool
        For every scan line from the knees down, whether the left and right
        lower-leg runs are one and the same (the legs overlap there).

    Returns
    -------
    bool
        True when the scan lines start with merged runs and then stay separate to
        the end (one line, then two lines) - the seed's Figure 3.7.
    """
    v = np.asarray(intersects, dtype=bool)
    if v.size == 0 or not v[0]:
        return False  # starts with two lines
    first_two = np.argmin(v)  # first False
    if v[first_two]:
        return False  # never became two lines ("TwoKneeStarted is false")
    return not v[first_two:].any()  # merged again after separating: not crossed


def leg_curves(mask: np.ndarray, top: int, bottom: int, radius: float, *,
               split: float | None = None):
    """Scan-line curves of the left and right lower legs (Algorithm 2's inputs).

    On every row from ``top`` to ``bottom`` the image-left leg's centre is taken
    ``radius`` inside the left edge of the leftmost run and the image-right leg's
    ``radius`` inside the right edge of the rightmost run. Where there is a single
    run narrower than ``split`` both legs share it ("intersect"): its centre is
    used for both.

    Parameters
    ----------
    mask : numpy.ndarray, shape (h, w), bool
    top, bottom : int
        Row range (inclusive) of the lower legs.
    radius : float
        Half-width of a lower leg, pixels.
    split : float, optional
        Width below which a single run is one merged leg (default ``3 * radius``).

    Returns
    -------
    left, right : numpy.ndarray, shape (R, 2)
        Curve points ``(x, y)`` ordered top to bottom (rows with no pixel skipped).
    intersects : numpy.ndarray, shape (R,), bool
        Rows where the legs share a single run.
    """
    split = 3.0 * radius if split is None else split
    top, bottom = max(int(top), 0), min(int(bottom), mask.shape[0] - 1)
    rows, starts, ends = row_runs(mask[top : bottom + 1])
    if rows.size == 0:
        empty = np.zeros((0, 2))
        return empty, empty, np.zeros(0, dtype=bool)
    uniq, first, counts = np.unique(rows, return_index=True, return_counts=True)
    last = first + counts - 1
    lx = starts[first].astype(float)
    rx = ends[last].astype(float)
    single = counts == 1
    width = rx - lx + 1
    merged = single & (width < split)
    centre = 0.5 * (lx + rx)
    left_x = np.where(merged, centre, np.minimum(lx + radius - 0.5, centre))
    right_x = np.where(merged, centre, np.maximum(rx - radius + 0.5, centre))
    y = (uniq + top).astype(float)
    return np.stack([left_x, y], 1), np.stack([right_x, y], 1), merged


def limb_curve(pixels: np.ndarray, origin: np.ndarray, *, step: float = 1.0) -> np.ndarray:
    """Order scattered limb pixels into a curve running away from ``origin``.

    The pixels are binned by their distance from ``origin`` (rings ``step`` wide,
    the scan lines of a limb that may point anywhere) and each ring's mean point
    becomes one curve point.

    Parameters
    ----------
    pixels : numpy.ndarray, shape (N, 2)
        ``(x, y)`` of the limb's pixels.
    origin : numpy.ndarray, shape (2,)
        The limb's root (a shoulder).
    step : float
        Ring width in pixels.

    Returns
    -------
    numpy.ndarray, shape (M, 2)
        Curve points ordered by increasing distance (empty rings skipped).
    """
    p = np.asarray(pixels, dtype=float)
    if len(p) == 0:
        return np.zeros((0, 2))
    d = np.hypot(*(p - origin).T)
    b = np.floor(d / step).astype(int)
    n = np.bincount(b)
    sx = np.bincount(b, weights=p[:, 0])
    sy = np.bincount(b, weights=p[:, 1])
    keep = n > 0
    return np.stack([sx[keep] / n[keep], sy[keep] / n[keep]], 1)


__all__ = [
    "arm_angles",
    "elbow_corner",
    "fit_angle",
    "knees_crossed",
    "leg_curves",
    "limb_curve",
    "row_runs",
    "split_angles",
]
