"""Foot contact from the 2D joints: which frames each foot is planted in.

A foot is planted where its ankle barely moves in the image (speed below
``max_speed`` metres per second at the frame's scale, after a light temporal
smoothing of the fitted joints) and is near the lower of the two ankles (within
``max_height`` metres of it in the image). Contact is only used on a clip that walks
or stands: the slower foot below ``still_speed`` in a quarter of the frames and at
least one foot planted in ``min_share`` of the frames; otherwise (a jump, jumping
jacks: both feet move together) no frame is taken as planted.

``min_share`` is 0.4: the thresholds find the middle of each stance, not its ends (the
ankle rolls over the heel and the toes there), and on the 2D fit's joints fewer frames
still: a foot was found planted in 0.48-0.57 of the frames of the side-view sample walk
(two fits), 0.52-0.92 of the other fitted tuning walks, 0.66-0.94 of the synth walk's true
2D plus 0-4 % noise. At 0.6 the side-view sample walk had no contact at all (foot sliding
end to end 8.1 mm/frame; 5.1 at 0.4, the contact weight as it was).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_closing, binary_opening, gaussian_filter1d

from vidcap.body import JOINT_INDEX

_ANKLES = (JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"])


def foot_contacts(joints2d, scale, fps: float, *, max_speed: float = 0.45,
                  max_height: float = 0.05, min_share: float = 0.4,
                  still_speed: float = 0.2, min_run: int = 3,
                  noise: float | None = None) -> np.ndarray:
    """Planted feet, (F, 2) bool (left, right ankle).

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Pixels, image y down.
    scale : float or array_like, shape (F,)
        Pixels per metre.
    fps : float
    max_speed : float
        Image speed (m/s) below which an ankle can be planted.
    max_height : float
        How far (m) above the lower ankle a planted one may be.
    min_share : float
        Share of frames with a planted foot for the clip to count as walking or
        standing; below it no contact is returned.
    still_speed : float
        The image speed (m/s) the slower foot stays below in a quarter of the
        frames of a clip that walks or
        stands.
    min_run : int
        Shortest run of planted frames kept (and gaps this short are closed).
    noise : float, optional
        The 2D joints' white noise, pixels (default
        :func:`vidcap.video.solve.noise.noise_sigma`). Noisy ankles are smoothed over
        more frames (``1 + noise / (1 % of the height)``), and the speed and height
        thresholds grow by twice what that noise leaves after the smoothing.
    """
    from vidcap.video.solve.noise import MOTION_FLOOR, noise_sigma

    j = np.asarray(joints2d, dtype=float)
    F = j.shape[0]
    s = np.broadcast_to(np.asarray(scale, dtype=float), (F,))[:, None]
    if F < 3:
        return np.zeros((F, 2), bool)
    sig = noise_sigma(j) if noise is None else float(noise)
    s_mid = float(np.median(s))
    frac = np.sqrt(max((sig / (s_mid * 1.75)) ** 2 - MOTION_FLOOR ** 2, 0.0))  # of 1.75 m
    width = 1.0 + frac / 0.01
    ank = gaussian_filter1d(j[:, _ANKLES], width, axis=0, mode="nearest")  # (F, 2, 2)
    d_speed, d_height = _noise_left(sig / s_mid, width, fps)
    speed = np.linalg.norm(np.gradient(ank, axis=0), axis=-1) * fps / s
    lowest = ank[:, :, 1].max(axis=1, keepdims=True)  # image y down: the larger is lower
    height = (lowest - ank[:, :, 1]) / s
    planted = (speed < max_speed + d_speed) & (height < max_height + d_height)
    still_speed = still_speed + d_speed
    structure = np.ones((max(1, int(min_run)), 1), bool)
    planted = binary_opening(binary_closing(planted, structure), structure)
    still = np.quantile(speed.min(axis=1), 0.25) < still_speed
    if not still or planted.any(axis=1).mean() < min_share:
        return np.zeros((F, 2), bool)
    return planted


def _noise_left(sigma_m: float, width: float, fps: float, n: int = 4000) -> tuple[float, float]:
    """Twice the spread (m/s, m) that white 2D noise of ``sigma_m`` metres leaves in an
    ankle's speed and in the height between two ankles after a Gaussian smoothing of
    ``width`` frames (measured on seeded noise: the filter's gain, no formula)."""
    if not sigma_m > 0:
        return 0.0, 0.0
    z = np.random.default_rng(0).normal(0.0, sigma_m, (n, 2, 2))
    zs = gaussian_filter1d(z, width, axis=0, mode="nearest")
    speed = np.linalg.norm(np.gradient(zs, axis=0), axis=-1) * fps
    height = zs[:, 0, 1] - zs[:, 1, 1]
    return 2.0 * float(np.median(speed)), 2.0 * float(np.std(height))
