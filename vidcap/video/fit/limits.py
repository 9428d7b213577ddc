"""Segment indices, angle limits and angle helpers shared by the fit's moves.

Angles are image-plane angles in radians, counter-clockwise from the image's +x axis
with y up (``pi/2`` straight up, ``3 pi/2`` straight down), of the vector from a
segment's proximal to its distal joint (:data:`vidcap.body.IMAGE_ANGLE_LIMITS_DEG`,
in degrees there). Lengths are normalised pixels (:mod:`vidcap.video.fit.normalise`).
"""

from __future__ import annotations

import numpy as np

from vidcap.body import IMAGE_ANGLE_LIMITS_DEG, JOINT_INDEX, SEGMENT_NAMES
from vidcap.video.fit.raster import _DIST, _PROX, DESCENDANTS

S = {name: i for i, name in enumerate(SEGMENT_NAMES)}
J = JOINT_INDEX
TWO_PI = 2 * np.pi
LIMITS = {k: np.deg2rad(v) for k, v in IMAGE_ANGLE_LIMITS_DEG.items()}
ONE_DEGREE = np.deg2rad(1.0)
THIRTY_DEGREES = np.deg2rad(30.0)
#: Largest image-plane bend at an elbow or knee (the 150 degree flexion limit of
#: vidcap.body.FLEXION_LIMITS_DEG): a lower limb does not fold back over its parent.
MAX_BEND = np.deg2rad(150.0)
#: Thigh directions allowed when refining and tracking: Table 3.3's hip limits
#: (240-300 degrees) keep the seed's first estimate upright, but a knee lifted to
#: hip height (a high step, a kick) points the thigh nearly horizontal (beyond the
#: seed).
THIGH_WIDE = (np.deg2rad(180.0), np.deg2rad(360.0))
#: The rest pose a fresh fit starts from: torso and head up, every limb down (degrees).
REST_DEG = np.array([90, 90, 270, 270, 270, 270, 270, 270, 270, 270], dtype=float)
PROX64, DIST64 = _PROX.astype(np.int64), _DIST.astype(np.int64)  # as the kernels take them
#: each segment's child limb segment (-1: none)
CHILD = tuple(DESCENDANTS[s][1] if len(DESCENDANTS[s]) > 1 else -1 for s in range(10))
#: DESCENDANT_OF[s, d]: segment d moves with segment s (s itself included)
DESCENDANT_OF = np.array([[d in DESCENDANTS[s] for d in range(10)] for s in range(10)])


def angle_gap(a, b):
    """``|a - b|`` wrapped to ``[0, pi]``, radians, elementwise (arrays broadcast).

    Real arithmetic, several times cheaper than ``abs(angle(exp(1j * (a - b))))`` (the
    same value to rounding), for the fit's hot loops over candidate grids.
    """
    return np.abs(np.mod(np.asarray(a) - b + np.pi, TWO_PI) - np.pi)


def into_range(angle, lo, hi):
    """The representative of ``angle`` (mod 2 pi) in ``[lo, hi]``, or the nearer bound."""
    if np.ndim(angle) == 0 and np.ndim(lo) == 0 and np.ndim(hi) == 0:
        # scalars: Python's float % is numpy's np.mod (the same remainder), cheaper
        lo, hi = float(lo), float(hi)
        x = lo + (float(angle) - lo) % TWO_PI
        if x > hi:
            return lo if (lo + TWO_PI - x) < (x - hi) else hi
        return x
    x = lo + np.mod(np.asarray(angle, dtype=float) - lo, TWO_PI)
    beyond = x > hi
    nearer_lo = (lo + TWO_PI - x) < (x - hi)
    out = np.where(beyond, np.where(nearer_lo, lo, hi), x)
    return float(out) if np.ndim(out) == 0 else out


def median(values: np.ndarray) -> float:
    """``np.median`` of a short 1-D array (the same value, without its set-up cost)."""
    v = np.sort(values)
    mid = v.size // 2
    return float(v[mid] if v.size % 2 else (v[mid - 1] + v[mid]) / 2)
