"""The 2D joints' noise level, and an image scale that noise does not bias.

Noise lengthens every 2D segment on average, and the scale estimate takes a high
quantile over frames of the subject's image height
(:func:`vidcap.video.lift.estimate_scale`), which noise raises further: at 2 % of the
height of white noise the scale comes out 2-5 % too large (benchmarks, validation
clips). Read at that scale every segment in the image plane is "too short" by as
much, and the lift gives it sqrt(1 - 0.96^2) = 0.28 of its length in depth on a side
of the image plane nothing in the image decides: on a side-view walk that turns the
legs out of their plane and doubles the error (PA-MPJPE 42 -> 99 mm at 1 % noise).

:func:`noise_sigma` measures the noise from the joints' second differences over
time (median absolute deviation: the motion's own accelerations are brief);
:func:`robust_scale` removes the scale's noise bias by a parametric bootstrap: the
estimate of the joints with as much noise again added, ``s(x + n)``, is biased about
as much from ``s(x)`` as ``s(x)`` from the truth, so ``2 s(x) - mean s(x + n)``.
"""

from __future__ import annotations

import numpy as np

from vidcap.body import BodyModel

#: :func:`noise_sigma` of noise-free joints (the motion's own second differences), as
#: a fraction of the body height: 0.0-0.25 % on the synth and mocap renders.
MOTION_FLOOR = 0.003


def noise_sigma(joints2d) -> float:
    """Standard deviation (pixels) of white noise on the 2D joints (F, 15, 2).

    From the second differences over frames, whose spread is sqrt(6) sigma for white
    noise; median absolute deviation, so the motion's brief accelerations do not
    count. 0 for fewer than 3 frames. Temporally correlated errors (a 2D fit that
    stays off for a run of frames) read smaller than they are.
    """
    j = np.asarray(joints2d, dtype=float)
    if j.shape[0] < 3:
        return 0.0
    d2 = j[2:] - 2.0 * j[1:-1] + j[:-2]
    d2 = d2[np.isfinite(d2)]
    if not d2.size:
        return 0.0
    return float(np.median(np.abs(d2)) / 0.6745 / np.sqrt(6.0))


def noise_fraction(joints2d, scale, body: BodyModel | None = None) -> float:
    """The 2D joints' noise beyond what their motion reads as (:data:`MOTION_FLOOR`), as
    a fraction of the body height; ``scale`` pixels per metre (one or (F,): the median
    is used)."""
    body = body or BodyModel()
    s = float(np.median(np.asarray(scale, dtype=float)))
    sig = noise_sigma(joints2d) / (s * body.height)
    return float(np.sqrt(max(sig ** 2 - MOTION_FLOOR ** 2, 0.0)))


def robust_scale(joints2d, body: BodyModel | None = None, *, sigma: float | None = None,
                 draws: int = 8, seed: int = 0) -> float:
    """:func:`vidcap.video.lift.estimate_scale` without the bias 2D noise gives it.

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Image joints in pixels.
    body : BodyModel, optional
    sigma : float, optional
        The noise (pixels); default :func:`noise_sigma`.
    draws : int
        Bootstrap draws of the noise.
    seed : int
        Seed of the draws (the result is deterministic).

    Returns
    -------
    float
        Pixels per metre.
    """
    from vidcap.video.lift import estimate_scale

    body = body or BodyModel()
    j = np.asarray(joints2d, dtype=float)
    s = estimate_scale(j, body)
    sig = noise_sigma(j) if sigma is None else float(sigma)
    # what a clip's own motion reads as noise (noise-free renders: up to 0.25 % of the
    # height) is not corrected for: there the correction only moves segments in the
    # image plane off it
    sig = np.sqrt(max(sig ** 2 - (MOTION_FLOOR * body.height * s) ** 2, 0.0))
    if not sig > 0:
        return s
    rng = np.random.default_rng(seed)
    again = np.mean([estimate_scale(j + rng.normal(0.0, sig, j.shape), body)
                     for _ in range(max(1, int(draws)))])
    out = 2.0 * s - again
    return float(out) if out > 0 else s
