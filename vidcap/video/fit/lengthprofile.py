"""A limb segment's length measured in one frame: the similarity S along its length.

With a frame's fitted pose held, each limb segment is drawn at a range of image
lengths (its descendants moving with its end) and S (Eq. 3.3) read at each: where
the segment's end stands clear of the rest of the body, S peaks at the length the
image shows; where its end lies inside the silhouette (an arm hanging in front of
the torso) S is flat over many lengths, and the frame says nothing of that segment.
:func:`length_profiles` returns the measured image lengths and which of them are
determined; :mod:`vidcap.video.fit.proportions` pools them over a clip.
"""

from __future__ import annotations

import numpy as np

from vidcap.body import JOINT_INDEX, BodyModel
from vidcap.video.fit.normalise import normalise_mask
from vidcap.video.fit.raster import (
    _DIST,
    _PROX,
    model_dimensions,
    pose_joints_batch,
    span_counts,
)
from vidcap.video.fit.similarity import similarity_from_counts

#: The limb segments measured (all but torso and head).
LIMB_SEGMENTS = np.arange(2, 10)
#: Image lengths tried, as fractions of the model segment's full length.
GRID = np.linspace(0.4, 1.6, 61)
#: A length is determined when every length whose S is within ``TIE_PIXELS`` pixels'
#: worth of the best lies within ``SPREAD`` (fraction of the model length) of it: the
#: end pinned by the outline.
TIE_PIXELS = 4.0
SPREAD = 0.06
#: Height (px) the silhouette is normalised to for the profiles: finer than the fit's
#: 80 px, where one pixel is 6 % of a forearm.
PROFILE_HEIGHT = 200


def length_profiles(mask: np.ndarray, joints: np.ndarray, angles: np.ndarray,
                    fore: np.ndarray, spread: float, model_height: float, *,
                    body: BodyModel | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Image length of every limb segment of one fitted frame, where S determines it.

    Parameters
    ----------
    mask : numpy.ndarray, shape (H, W), bool
        The frame's silhouette.
    joints : numpy.ndarray, shape (15, 2)
        The fitted joints, original pixels (their pelvis places the model).
    angles, fore : numpy.ndarray, shape (10,)
        The fitted image-plane angles (radians) and foreshortening ratios.
    spread : float
        The fitted spread.
    model_height : float
        The body height (px) the frame was fitted at.
    body : BodyModel, optional
        The proportions it was fitted with (default: the seed's).

    Returns
    -------
    lengths : numpy.ndarray, shape (10,)
        Measured image length / body height per segment (NaN: torso, head, or not
        determined in this frame).
    peak : numpy.ndarray, shape (10,)
        The best S per segment (NaN for torso and head).
    """
    out = np.full(10, np.nan)
    peak = np.full(10, np.nan)
    if not (np.isfinite(joints).all() and np.isfinite(angles).all() and model_height > 0):
        return out, peak
    norm = normalise_mask(mask, height=PROFILE_HEIGHT, body_height=float(model_height))
    h_px = norm.body_height
    L, R, shoulder, hip = model_dimensions(h_px, body)
    root = norm.to_normalised(joints[JOINT_INDEX["pelvis"]])
    n_g, n_s = GRID.size, LIMB_SEGMENTS.size
    f = np.repeat(np.asarray(fore, float)[None], n_g * n_s, axis=0).reshape(n_s, n_g, 10)
    f[np.arange(n_s), :, LIMB_SEGMENTS] = GRID[None, :]
    f = f.reshape(-1, 10)
    b = f.shape[0]
    j = pose_joints_batch(np.repeat(root[None], b, axis=0),
                          np.repeat(np.asarray(angles, float)[None], b, axis=0), f,
                          np.full(b, float(spread)), L, shoulder, hip)
    _, cum = norm.count_tables
    counts = span_counts(j[:, _PROX], j[:, _DIST], R, cum, caps=False)
    a = int(norm.count_tables[0][-1])
    s = np.asarray(similarity_from_counts(a, counts[:, 0], counts[:, 1]), float)
    s = s.reshape(n_s, n_g)
    best = s.max(axis=1)
    near = s >= best[:, None] * (1.0 - TIE_PIXELS / max(a, 1))  # dS/S = d(pixels)/a
    lo = np.where(near, GRID[None, :], np.inf).min(axis=1)
    hi = np.where(near, GRID[None, :], -np.inf).max(axis=1)
    ok = (hi - lo <= SPREAD) & (lo > GRID[0]) & (hi < GRID[-1])
    at = GRID[np.argmax(s, axis=1)]
    out[LIMB_SEGMENTS] = np.where(ok, at * L[LIMB_SEGMENTS] / h_px, np.nan)
    peak[LIMB_SEGMENTS] = best
    return out, peak


__all__ = ["GRID", "LIMB_SEGMENTS", "PROFILE_HEIGHT", "length_profiles"]
