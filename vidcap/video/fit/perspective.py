"""A high (or low) camera's perspective on a standing body, as one number k.

The 2D fit draws the body model by a scaled orthographic projection: every height of the
body is shrunk alike. A camera above the subject, looking down, is nearer the head than
the feet, so the upper body comes out larger than the lower: on onebyone_room (a camera
~2.5 m up) the fit with a real adult's proportions put the shoulders and hips 6-10 % of
the height above MediaPipe's and the ankles below (benchmarks/RESULTS.md, 2D pose, Real
video).

A vertical body whose point at height fraction u (0 at the head's top, 1 at the soles)
lies at depth ``Z(u)`` along the optical axis, linear in u, is imaged at

    g(u) = u (1 + k) / (1 + k u),    1 + k = Z(1) / Z(0),

of its image height (both ends fixed): k is the feet's depth over the head's, less one
(0 for a level camera, > 0 for a camera above, < 0 below). For a camera at height h_c,
the subject at horizontal distance D, pitched down by theta,
``k = H sin(theta) / (D cos(theta) + (h_c - H) sin(theta))``.

:func:`perspective_factors` warps a body's segment lengths by g (what the fit should draw
for such a camera); :func:`perspective_k` gives k from the camera's height and distance
(``vidcap convert --camera HEIGHT,DISTANCE[,PITCH]``); :func:`unwarp_joints` maps the
fitted joints' rows back by g's inverse, so the 3D stage (scaled orthography) reads a body
whose heights are shrunk alike, and :func:`warp_joints` maps them forward again.
``benchmarks/pose2d_real.py --rows human-cam`` measures it on cameras of known geometry.
"""

from __future__ import annotations

import math

import numpy as np

from vidcap.body import PROPORTION_GROUPS, SEGMENT_INDEX, SEGMENTS
from vidcap.video.fit.proportions import FOOT

__all__ = ["camera_perspective", "inverse_k", "perspective_factors", "perspective_k",
           "unwarp_joints", "unwarp_points", "warp_height", "warp_joints"]

#: Length groups along the standing body, head to feet, and along a hanging arm.
_TRUNK = ("head", "torso", "upper_legs", "lower_legs")
_ARM = ("upper_arms", "lower_arms")


def perspective_k(camera_height: float, distance: float, subject_height: float = 1.75,
                  pitch_deg: float | None = None) -> float:
    """k of a camera at ``camera_height`` metres, ``distance`` metres from the subject.

    Parameters
    ----------
    camera_height : float
        The lens above the floor, metres.
    distance : float
        Horizontal distance from the camera to the subject, metres (> 0).
    subject_height : float
        The subject's standing height H, metres.
    pitch_deg : float, optional
        The camera's downward tilt, degrees; default: aimed at the subject's middle
        (``atan((camera_height - H / 2) / distance)``).

    Returns
    -------
    float
        k (dimensionless), 0 for a camera at mid-height looking level.

    Raises
    ------
    ValueError
        When the head or the feet would be behind the camera.

    Examples
    --------
    >>> round(perspective_k(0.875, 3.0), 6)  # at mid-height, level
    0.0
    >>> round(perspective_k(2.5, 3.0, pitch_deg=35.0), 3)  # onebyone_room's room
    0.348
    """
    if not (distance > 0 and subject_height > 0):
        raise ValueError("distance and subject_height must be positive metres")
    if pitch_deg is None:
        theta = math.atan2(camera_height - subject_height / 2, distance)
    else:
        theta = math.radians(pitch_deg)
    z_head = distance * math.cos(theta) + (camera_height - subject_height) * math.sin(theta)
    z_feet = distance * math.cos(theta) + camera_height * math.sin(theta)
    if z_head <= 0 or z_feet <= 0:
        raise ValueError("the subject is not in front of the camera at this height, "
                         "distance and tilt")
    return z_feet / z_head - 1.0


#: The most the feet's depth may differ from the head's (1 + k, either way) for
#: :func:`camera_perspective`: nearer, the body's widths and the arms' lengths change along
#: it too much for one number (a camera at head height 1 cm away gives k = 15,000).
MAX_DEPTH_RATIO = 3.0


def camera_perspective(camera, height: float) -> float:
    """k for ``vidcap convert --camera``'s values and a subject ``height`` metres tall.

    Parameters
    ----------
    camera : sequence of 2 or 3 floats, or None
        The lens's height above the floor and its horizontal distance from the subject,
        metres, and optionally its downward tilt, degrees (default: aimed at the
        subject's middle). None: no camera given.
    height : float
        The subject's standing height, metres.

    Returns
    -------
    float
        k (:func:`perspective_k`); 0 for None.

    Raises
    ------
    ValueError
        For a camera that is not two or three finite numbers, a tilt beyond ±89 degrees,
        one that cannot see the subject or one nearer than :data:`MAX_DEPTH_RATIO` allows.
    """
    if camera is None:
        return 0.0
    if len(camera) not in (2, 3) or not all(math.isfinite(c) for c in camera):
        raise ValueError(f"camera is (height, distance[, pitch]) in metres and degrees, "
                         f"got {camera!r}")
    if len(camera) == 3 and not -89.0 <= camera[2] <= 89.0:
        raise ValueError(f"camera pitch must be within ±89 degrees, got {camera[2]}")
    k = perspective_k(float(camera[0]), float(camera[1]), float(height),
                      None if len(camera) == 2 else float(camera[2]))
    if not 1.0 / MAX_DEPTH_RATIO <= 1.0 + k <= MAX_DEPTH_RATIO:
        raise ValueError(f"the camera is too near the subject: the feet would be "
                         f"{1.0 + k:.3g} times as far as the head (one perspective number "
                         f"holds to {MAX_DEPTH_RATIO:g} times either way)")
    return k


def warp_height(u, k: float):
    """g(u) = u (1 + k) / (1 + k u): where height fraction ``u`` (0 head top, 1 soles;
    scalar or array) is imaged, as a fraction of the body's image height."""
    return u * (1.0 + k) / (1.0 + k * u)


def perspective_factors(factors: dict, k: float) -> dict:
    """The length factors of a body (:func:`vidcap.body.body_with_proportions`' groups, and
    the ankles' height ``above_feet`` when given) as a camera with perspective ``k`` draws
    them: each segment of the standing body, arms hanging, stretched or shrunk by the
    mean slope of g over its span. Widths and other keys are kept.

    Parameters
    ----------
    factors : dict
        Length factors on the seed's ratios by group (``head``, ``torso``, ``upper_legs``,
        ``lower_legs``, ``upper_arms``, ``lower_arms``; missing: 1) and, optionally,
        ``above_feet`` (the share of the stature above the ankles; missing: 1).
    k : float
        The perspective (:func:`perspective_k`); 0 returns the factors unchanged.

    Returns
    -------
    dict
        The warped factors (``above_feet`` present when it was).

    Examples
    --------
    >>> f = perspective_factors({"head": 1.0, "lower_legs": 1.0}, 0.35)
    >>> f["head"] > 1.0 > f["lower_legs"]
    True
    """
    out = dict(factors)
    if k == 0:
        return out
    length = {g: factors.get(g, 1.0) * SEGMENTS[SEGMENT_INDEX[PROPORTION_GROUPS[g][0]]].length_ratio
              for g in (*_TRUNK, *_ARM)}
    stature = sum(length[g] for g in _TRUNK) / factors.get(FOOT, 1.0)
    # each chain's joints as height fractions from the head's top: head top to ankles,
    # and a hanging arm from the shoulder (the head's lower end)
    for chain, top in ((_TRUNK, 0.0), (_ARM, length["head"] / stature)):
        ends = top + np.cumsum([length[g] / stature for g in chain])
        starts = np.concatenate(([top], ends[:-1]))
        for g, u0, u1 in zip(chain, starts, ends, strict=True):
            slope = (warp_height(u1, k) - warp_height(u0, k)) / (u1 - u0)
            out[g] = factors.get(g, 1.0) * float(slope)
    if FOOT in factors:
        out[FOOT] = float(warp_height(factors[FOOT], k))
    return out


def inverse_k(k: float) -> float:
    """The k of g's inverse: ``warp_height(warp_height(u, k), inverse_k(k)) == u``."""
    return -k / (1.0 + k)


def _remap_rows(joints2d, model_height, k: float, ankle_from: float, top=None):
    """Rows of ``joints2d`` (F, J, 2) moved by g (parameter ``k``) along the body's
    height, head top fixed; ``model_height`` (F,) spans head top to ankles, which sit at
    ``ankle_from`` of the height to the soles; ``top`` (F,): the head top's rows (default:
    ``joints2d``'s own ``head_top``). Returns (joints, model_height)."""
    from vidcap.body import JOINT_INDEX

    joints = np.array(joints2d, dtype=float, copy=True)
    height = np.asarray(model_height, float)
    if k == 0:  # no perspective: as they are, to the bit
        return joints, height.copy()
    stature = height / ankle_from  # head top to soles, px
    top = (joints[:, JOINT_INDEX["head_top"], 1] if top is None
           else np.asarray(top, float))[:, None]
    v = (joints[..., 1] - top) / stature[:, None]
    # g is a projective map of the line: finite while 1 + k v > 0, which holds for any
    # row above 1 / |k| statures below the head (k > -1 for a camera that sees the subject)
    joints[..., 1] = top + stature[:, None] * warp_height(v, k)
    return joints, stature * warp_height(ankle_from, k)


def unwarp_joints(joints2d, model_height, k: float, above_feet: float = 1.0):
    """Fitted 2D joints as a camera without perspective would image them.

    Each joint's row, as a fraction v of the body's image height from the head's top,
    goes to g⁻¹(v) (:func:`inverse_k`), the head top fixed: the body the fit drew warped
    by g (:func:`perspective_factors`) comes back to the body's own proportions, which the
    3D stage's scaled orthography expects. Columns are kept (the horizontal
    magnification's change along the body is left out, as the fit's widths leave it).

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Image joints (x right, y down), pixels, with ``head_top`` among them.
    model_height : array_like, shape (F,)
        The fitted body's image height from the head's top to the ankles, pixels.
    k : float
        The camera's perspective (:func:`perspective_k`); 0 changes nothing.
    above_feet : float
        The ankles' height as a share of the standing height (the body's ``above_feet``,
        1 for the seed's body).

    Returns
    -------
    joints : numpy.ndarray, shape (F, 15, 2)
    model_height : numpy.ndarray, shape (F,)
        Head top to ankles after the change, pixels.

    Examples
    --------
    >>> import numpy as np
    >>> j = np.zeros((1, 15, 2)); j[0, :, 1] = np.linspace(0.0, 100.0, 15)
    >>> back, h = warp_joints(*unwarp_joints(j, [100.0], 0.3), 0.3)
    >>> bool(np.allclose(back, j)) and bool(np.allclose(h, 100.0))
    True
    """
    return _remap_rows(joints2d, model_height, inverse_k(k), float(warp_height(above_feet, k)))


def warp_joints(joints2d, model_height, k: float, above_feet: float = 1.0):
    """The inverse of :func:`unwarp_joints`: joints of a body with its own proportions
    as the camera of perspective ``k`` images them (same arguments and returns;
    ``model_height`` the unwarped body's head top to ankles)."""
    return _remap_rows(joints2d, model_height, k, above_feet)


def unwarp_points(points, joints2d, model_height, k: float, above_feet: float = 1.0):
    """Other image points of each frame moved as :func:`unwarp_joints` moves that
    frame's fitted joints: the joints the user placed by hand, say, for a 3D stage that
    reads the fitted joints un-warped.

    Parameters
    ----------
    points : array_like, shape (F, N, 2)
        Image points (x right, y down), pixels; NaN stays NaN, and a frame without a
        fitted head top or height keeps its points as they are.
    joints2d : array_like, shape (F, 15, 2)
        The fitted joints whose ``head_top`` row stays fixed.
    model_height, k, above_feet
        As :func:`unwarp_joints`.

    Returns
    -------
    numpy.ndarray, shape (F, N, 2)
    """
    from vidcap.body import JOINT_INDEX

    top = np.asarray(joints2d, float)[:, JOINT_INDEX["head_top"], 1]
    moved = _remap_rows(points, model_height, inverse_k(k), float(warp_height(above_feet, k)),
                        top=top)[0]
    return np.where(np.isfinite(moved), moved, points)
