"""A limb segment's length measured in one frame: the similarity S along its length.

With a frame's fitted pose held, each limb segment is drawn at a range of image
lengths (its descendants moving with its end) and S (Eq. 3.3) read at each: where
the segment's end stands clear of the rest of the body, S peaks at the length the
image shows; where its end lies inside the silhouette (an arm hanging in front of
the torso) S is flat over many lengths, and the frame says nothing of that segment.
:func:`length_profiles` returns the measured image lengths and which of them are
determined; :mod:`vidcap.video.fit.proportions` pools them over a clip.

:func:`arm_profiles` measures each whole arm the same way, scaled about its shoulder
(upper arm and forearm together, the fitted elbow angle kept): where the hand stands
clear, S peaks where the hand's end meets the outline's, and the arm's image length
(upper arm plus forearm, each as drawn) there is the arm's length when the arm lies
in the image plane (shorter otherwise). A misplaced elbow moves that sum much less
than it moves either segment's own profile.
"""

from __future__ import annotations

import numpy as np

from vidcap.body import JOINT_INDEX, SEGMENT_INDEX, BodyModel
from vidcap.video.fit.normalise import normalise_mask
from vidcap.video.fit.raster import (
    _DIST,
    _PROX,
    model_dimensions,
    model_shoulder,
    pose_joints_batch,
    span_counts,
)
from vidcap.video.fit.similarity import similarity_from_counts

#: The limb segments measured (all but torso and head).
LIMB_SEGMENTS = np.arange(2, 10)
#: Each arm's segments (upper arm, forearm), image-left arm first.
ARMS = np.array([[SEGMENT_INDEX["l_upper_arm"], SEGMENT_INDEX["l_lower_arm"]],
                 [SEGMENT_INDEX["r_upper_arm"], SEGMENT_INDEX["r_lower_arm"]]])
#: Image lengths tried, as fractions of the model segment's full length.
GRID = np.linspace(0.4, 1.6, 61)
#: The same for a whole arm (:func:`arm_profiles`), finer: the clip's median of it is
#: the arm's length, and 2 % steps would quantise it.
ARM_GRID = np.linspace(0.4, 1.6, 121)
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
    n_s = LIMB_SEGMENTS.size
    f = np.repeat(np.asarray(fore, float)[None], GRID.size * n_s, axis=0)
    f = f.reshape(n_s, GRID.size, 10)
    f[np.arange(n_s), :, LIMB_SEGMENTS] = GRID[None, :]
    at, ok, best, L, h_px = _profiles(mask, joints, angles, f, GRID, spread, model_height,
                                      body)
    out[LIMB_SEGMENTS] = np.where(ok, at * L[LIMB_SEGMENTS] / h_px, np.nan)
    peak[LIMB_SEGMENTS] = best
    return out, peak


def arm_profiles(mask: np.ndarray, joints: np.ndarray, angles: np.ndarray,
                 fore: np.ndarray, spread: float, model_height: float, *,
                 body: BodyModel | None = None) -> np.ndarray:
    """Image length of each whole arm of one fitted frame, where S determines it.

    Each arm is scaled about its shoulder (both segments' drawn lengths times the
    same factor, the fitted angles held); the arm's image length is the sum of its
    two segments' drawn lengths at the best factor.

    Parameters
    ----------
    mask, joints, angles, fore, spread, model_height, body
        As :func:`length_profiles`.

    Returns
    -------
    numpy.ndarray, shape (2,)
        Image length (upper arm + forearm) / the model's arm length (upper arm +
        forearm at full length) for the image's left and right arm: 1 where the
        image shows an arm as long as the model's lying in the image plane (NaN: not
        determined in this frame).
    """
    out = np.full(2, np.nan)
    if not (np.isfinite(joints).all() and np.isfinite(angles).all() and model_height > 0):
        return out
    fore = np.asarray(fore, float)
    f = np.repeat(fore[None], 2 * ARM_GRID.size, axis=0).reshape(2, ARM_GRID.size, 10)
    for k, segs in enumerate(ARMS):
        f[k][:, segs] = fore[segs][None, :] * ARM_GRID[:, None]  # both segments scaled
    at, ok, _, L, _ = _profiles(mask, joints, angles, f, ARM_GRID, spread, model_height,
                                body)
    for k, segs in enumerate(ARMS):
        if ok[k]:
            out[k] = at[k] * float(fore[segs] @ L[segs]) / float(L[segs].sum())
    return out


def _profiles(mask, joints, angles, fore_grid, grid, spread, model_height, body):
    """S of the pose with each row of ``fore_grid`` (shape (P, G, 10): P profiles of
    ``grid``'s G values): the best grid value per profile, whether it is
    determined (the end pinned), the best S, and the model's lengths (px) at the
    profile height ``h_px``."""
    norm = normalise_mask(mask, height=PROFILE_HEIGHT, body_height=float(model_height))
    h_px = norm.body_height
    L, R, lateral, hip = model_dimensions(h_px, body)
    shoulder = model_shoulder(lateral, h_px, body)
    root = norm.to_normalised(joints[JOINT_INDEX["pelvis"]])
    n_p, n_g = fore_grid.shape[:2]
    f = fore_grid.reshape(-1, 10)
    b = f.shape[0]
    j = pose_joints_batch(np.repeat(root[None], b, axis=0),
                          np.repeat(np.asarray(angles, float)[None], b, axis=0), f,
                          np.full(b, float(spread)), L, shoulder, hip)
    _, cum = norm.count_tables
    counts = span_counts(j[:, _PROX], j[:, _DIST], R, cum, caps=False)
    a = int(norm.count_tables[0][-1])
    s = np.asarray(similarity_from_counts(a, counts[:, 0], counts[:, 1]), float)
    s = s.reshape(n_p, n_g)
    best = s.max(axis=1)
    near = s >= best[:, None] * (1.0 - TIE_PIXELS / max(a, 1))  # dS/S = d(pixels)/a
    lo = np.where(near, grid[None, :], np.inf).min(axis=1)
    hi = np.where(near, grid[None, :], -np.inf).max(axis=1)
    ok = (hi - lo <= SPREAD) & (lo > grid[0]) & (hi < grid[-1])
    return grid[np.argmax(s, axis=1)], ok, best, L, h_px


__all__ = ["ARMS", "ARM_GRID", "GRID", "LIMB_SEGMENTS", "PROFILE_HEIGHT", "arm_profiles",
           "length_profiles"]
