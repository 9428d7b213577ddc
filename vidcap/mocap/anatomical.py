"""Joint centres from anatomical definitions, for joints a functional fit cannot place.

A gait trial flexes the knee by ~60 degrees and the ankle by ~30 about one axis: the
hinge fit finds the axis but not where along it the centre lies. Where the marker set
says how its protocol defines the joint, that definition places it instead.

Plug-in-Gait's chord construction (Vicon's Plug-in-Gait manual; Davis et al. 1991):
the knee centre K lies in the plane of the hip centre H, the thigh wand W and the
lateral knee marker M, at the distance ``d = (KneeWidth + MarkerDiameter) / 2`` from
M, with the angle H-K-M a right angle (M's offset is medial, across the thigh). The
ankle centre follows from the knee centre, the tibial wand and the ankle marker with
``AnkleWidth``. With ``L = |H - M|``, ``u = (H - M)/L`` and ``n`` the unit component of
``W - M`` perpendicular to ``u``::

    K = M + d (d/L u - sqrt(1 - (d/L)^2) n)

(the point on the circle over the chord M-H at the distance d from M, on the side
away from the wand).

The widths come from the C3D's ``PROCESSING`` group (``LKneeWidth``, ``RAnkleWidth``,
``MarkerDiameter``, mm), read into :attr:`vidcap.mocap.c3d.MarkerData.subject`; when
the file has none, the defaults below stand in and the report says so.
"""

from __future__ import annotations

import numpy as np

#: Marker diameter (mm) when PROCESSING:MarkerDiameter is absent: Vicon's 14 mm
#: markers, the size the Plug-in-Gait protocol is usually captured with.
MARKER_DIAMETER_MM = 14.0

#: Joint widths (mm) when the PROCESSING group lacks them: adult medians (knee
#: width across the femoral epicondyles ~100 mm, ankle across the malleoli ~70 mm).
DEFAULT_WIDTHS_MM = {"KneeWidth": 100.0, "AnkleWidth": 70.0, "ElbowWidth": 70.0,
                     "WristWidth": 50.0}


def chord_centre(wand: np.ndarray, proximal: np.ndarray, marker: np.ndarray,
                 offset: float) -> np.ndarray:
    """Plug-in-Gait's chord joint centre, per frame (see the module docstring).

    Parameters
    ----------
    wand : numpy.ndarray, shape (F, 3)
        The segment's wand marker (thigh wand for the knee, tibial wand for the ankle).
    proximal : numpy.ndarray, shape (F, 3)
        The proximal joint centre (hip for the knee, knee for the ankle).
    marker : numpy.ndarray, shape (F, 3)
        The lateral joint marker (KNE, ANK).
    offset : float
        Distance of the centre from the marker, same units (half the joint width plus
        the marker radius).

    Returns
    -------
    numpy.ndarray, shape (F, 3)
        NaN where a point is missing, the three are collinear, or the proximal joint is
        nearer the marker than ``offset``.

    Examples
    --------
    A knee marker 60 mm lateral (+x) of a knee at the origin, the hip 40 cm above the
    knee, the wand on the lateral thigh:

    >>> import numpy as np
    >>> k = chord_centre(np.array([[0.1, 0.0, 0.2]]), np.array([[0.0, 0.0, 0.4]]),
    ...                  np.array([[0.06, 0.0, 0.0]]), 0.06)
    >>> np.abs(np.round(k, 9))
    array([[0., 0., 0.]])
    """
    w, h, m = (np.asarray(a, dtype=float) for a in (wand, proximal, marker))
    d = h - m
    length = np.linalg.norm(d, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = d / length
        side = w - m
        side = side - np.sum(side * u, axis=-1, keepdims=True) * u
        n = side / np.linalg.norm(side, axis=-1, keepdims=True)
        cos = offset / length
        sin = np.sqrt(1.0 - cos ** 2)
    centre = m + offset * (cos * u - sin * n)
    bad = ~(np.isfinite(centre).all(axis=-1) & (cos[..., 0] <= 1.0))
    centre[bad] = np.nan
    return centre


def chord_offset_mm(width_name: str, subject: dict) -> tuple[float, str]:
    """The chord's offset ``(width + marker diameter) / 2`` (mm) and where it came from.

    Parameters
    ----------
    width_name : str
        The PROCESSING parameter, e.g. ``'LKneeWidth'``; its side-free suffix picks the
        default (:data:`DEFAULT_WIDTHS_MM`) when ``subject`` lacks it.
    subject : dict
        :attr:`vidcap.mocap.c3d.MarkerData.subject`.

    Returns
    -------
    offset_mm : float
    source : str
        e.g. ``'LKneeWidth 102 mm + MarkerDiameter 14 mm (default)'``.
    """
    suffix = width_name[1:] if width_name[:1] in "LR" else width_name
    width = subject.get(width_name)
    w_src = "file"
    if width is None or not width > 0:
        width, w_src = DEFAULT_WIDTHS_MM.get(suffix, 100.0), "default"
    marker = subject.get("MarkerDiameter")
    m_src = "file"
    if marker is None or not marker > 0:
        marker, m_src = MARKER_DIAMETER_MM, "default"
    source = (f"{width_name} {width:g} mm ({w_src}) + MarkerDiameter {marker:g} mm "
              f"({m_src})")
    return (float(width) + float(marker)) / 2.0, source
