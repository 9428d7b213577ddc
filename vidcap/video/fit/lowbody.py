"""A body lower than it stands: the scale of a person seated or crouched for seconds.

The tracked fit draws the model at the body's height, which :func:`~vidcap.video.fit.
tracking.body_heights` reads as the median silhouette height over about three seconds.
That holds while the person stands for part of the window; a person seated (an office
chair, a sofa, at a desk eating or on the phone) or crouched for longer has a
silhouette about 0.8 of the standing height in every frame, and the model is drawn that
much too small: thighs and shins too short, the shoulders at the chin. On renders of a
seated figure (true silhouettes) PCK@0.05 was 30-53 % at the silhouettes' height and
55-84 % at the true one.

On clean silhouettes the silhouette itself says which is right: fitted afresh at larger
heights, a seated body's S rises from 0.64 at its silhouette's height to 0.87 at 1.3 times
it (true 1.25), while a standing one scores best at 1.0 (walks, jacks, arm raises, every
view). So, per window of :data:`WINDOW` frames whose fits are middling (median S in
[:data:`FLOOR`, :data:`GATE`)), a few frames are fitted afresh at :data:`FACTORS`; where
enough of them score clearly better at a larger one, the window's frames are refitted,
tracked, at the factor their S peaks at (interpolated between the probed ones), each kept
only where its S is higher. Frames the body-height pass refitted at a height read from
standing frames nearby (a crouch between upright frames) are left alone: that height is
already the standing one.

On real silhouettes, which carry shadow and scene, S also favours a larger model where
the person stands (Pose2Sim cam4: 5.2 -> 6.3 % of the height against MediaPipe), so
:func:`~vidcap.video.fit.tracking.fit_sequence` runs this only when asked (``low_body``;
``vidcap convert --seated``). Figures: benchmarks/RESULTS.md, "A person seated for
seconds".
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["FACTORS", "FLOOR", "GAIN", "GATE", "SAMPLES", "SHARE", "WINDOW", "refit_low_body",
           "window_factor"]

#: The heights probed, as factors on the height the track drew each frame at: close
#: together near 1, where a stance a little lower than standing (a basketball player's,
#: 1.08) must not be read as the next step up.
FACTORS = (1.0, 1.06, 1.12, 1.2, 1.3, 1.42)
#: Frames per window probed and refitted together (about three seconds at 30 fps).
WINDOW = 90
#: Frames of a window fitted afresh at every factor.
SAMPLES = 6
#: The window's median S under which it is probed: upright bodies at their height score
#: 0.90-0.95 on clean silhouettes, a seated one 0.64.
GATE = 0.85
#: ... and at or above which: a silhouette the model covers this poorly at any height (a
#: shadow or the scene in it: 0.2-0.4 on two real clips) scores a larger model higher
#: only because it covers more of the blob.
FLOOR = 0.5
#: S by which a sample frame's best larger factor must beat its fresh fit at 1.0 for the
#: frame to call the body larger (a seated body: 0.2; real upright clips mostly under
#: 0.07, but Pose2Sim cam4 0.12-0.19 in four frames of six).
GAIN = 0.1
#: Share of the sample frames that must call the body larger for the window's refit.
SHARE = 0.5


def _peak(factors: np.ndarray, scores: np.ndarray) -> float:
    """The factor where a parabola through the best score and its neighbours peaks,
    kept between those neighbours (the best factor itself at either end)."""
    j = int(np.argmax(scores))
    if j == 0 or j == len(factors) - 1:
        return float(factors[j])
    (xa, xb, xc), (ya, yb, yc) = factors[j - 1:j + 2], scores[j - 1:j + 2]
    den = (xb - xa) * (yb - yc) - (xb - xc) * (yb - ya)
    if den <= 0:  # flat or not a peak: the probed factor itself
        return float(factors[j])
    num = (xb - xa) ** 2 * (yb - yc) - (xb - xc) ** 2 * (yb - ya)
    return float(np.clip(xb - 0.5 * num / den, xa, xc))


def window_factor(similarity: np.ndarray) -> float | None:
    """The height factor a window's sample calls for, or None.

    Parameters
    ----------
    similarity : numpy.ndarray, shape (N, len(FACTORS))
        S of each sample frame fitted afresh at each factor.

    Returns
    -------
    float or None
        The median, over the frames that score better at a larger factor by
        :data:`GAIN`, of the factor their S peaks at; None unless those frames are at
        least :data:`SHARE` of the sample.
    """
    s = np.asarray(similarity, float)
    factors = np.asarray(FACTORS, float)
    best = s.argmax(axis=1)
    larger = (best > 0) & (s[np.arange(len(s)), best] - s[:, 0] > GAIN)
    if not len(s) or larger.mean() < SHARE:
        return None
    return float(np.median([_peak(factors, row) for row in s[larger]]))


def refit_low_body(n: int, sim: np.ndarray, height: np.ndarray,
                   normalise: Callable, fit: Callable, keep: Callable,
                   anchored: np.ndarray | None = None) -> np.ndarray:
    """Refit the windows whose silhouettes show a body larger than it was drawn.

    Parameters
    ----------
    n : int
        Frames in the clip.
    sim, height : numpy.ndarray, shape (n,)
        Each frame's S and the body height its model was drawn at, px (NaN: not fitted).
    normalise : callable
        ``normalise(k, body_height_px)``: frame ``k``'s silhouette normalised for a body
        that tall.
    fit : callable
        ``fit(norm, previous, k) -> FramePose``: a fresh (``previous`` None) or warm fit.
    keep : callable
        ``keep(k, fitted_pose_or_None) -> FramePose``: stores a better refit of frame
        ``k`` (given) and returns the pose frame ``k`` now has (the warm start of the
        next frame).
    anchored : numpy.ndarray of bool, shape (n,), optional
        Frames the body-height pass already refitted at a height read from upright
        frames nearby: left as they are, neither probed nor refitted. In a crouch
        between standing frames that height is right, and S, which a larger model with
        folded legs can raise too, would move them off it (131_01's crouch: PCK 72 ->
        64 % before they were left out).

    Returns
    -------
    numpy.ndarray, shape (n,)
        The body height each refitted frame was fitted at, px; NaN elsewhere.
    """
    sim = np.asarray(sim, float)
    height = np.asarray(height, float).copy()
    used = np.full(n, np.nan)
    fitted = np.isfinite(height)
    if anchored is not None:
        fitted &= ~np.asarray(anchored, bool)
    for start in range(0, n, WINDOW):
        idx = start + np.flatnonzero(fitted[start:start + WINDOW])
        if len(idx) < 3 or not FLOOR <= np.median(sim[idx]) < GATE:
            continue
        pick = idx[np.unique(np.linspace(0, len(idx) - 1, min(SAMPLES, len(idx)))
                             .round().astype(int))]
        probe = np.array([[fit(normalise(k, f * height[k]), None, k).similarity
                           for f in FACTORS] for k in pick])
        factor = window_factor(probe)
        if factor is None:
            continue
        prev = None
        for k in range(start, min(n, start + WINDOW)):
            if not fitted[k]:
                prev = None if not np.isfinite(height[k]) else keep(k, None)
                continue
            fp = fit(normalise(k, factor * height[k]), prev, k)
            better = fp.similarity > sim[k]
            if better:
                used[k] = factor * height[k]
            prev = keep(k, fp if better else None)
    return used
