"""The result of the marker path: per-joint reports and the solved skeleton's centres
and segment frames (:func:`vidcap.mocap.skeleton.solve_joints`)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from vidcap.mocap.markerset import MarkerSet

#: A fitted centre whose worst-determined coordinate has a Cramér-Rao standard
#: deviation above this (mm) is reported as poorly placed.
POOR_STD_MM = 10.0


@dataclass(frozen=True)
class JointReport:
    """Fit quality of one joint.

    Attributes
    ----------
    joint, segment : str
        The joint and the (child) segment whose markers located it.
    parent_segment : str or None
        The frame the centre is constant in (None for the root joint).
    kind : str
        ``'sphere'``, ``'hinge'``, ``'still'`` (from the fit), ``'root'`` or ``'end'``.
    method : str
        What placed the joint: ``'mgdk'``/``'mgdk+ugdk'`` (sphere or hinge fit),
        ``'score'`` (two-frame fit), ``'+axis-rule'`` (centre along a hinge axis by
        rule), ``'+regression'``/``'regression'`` (pelvis regression for some or all
        of a hip's coordinates), ``'anatomical'`` (the marker set's definition, e.g.
        Plug-in-Gait's chord), ``'+static'`` (from a static trial), ``'fallback'``
        (marker centroid), ``'markers'`` (root and end joints).
    frames_used : int
        Frames with a parent frame and at least one of the child's markers.
    rms_residual_m : float
        RMS of |y - c| - r over all samples (in-plane distance for a hinge), metres.
    condition : float
        Condition number of the pooled covariance (large: planar or little motion).
    cap_angle_deg : float
        Range of motion: the largest (98th percentile) angle of a marker's direction
        from the centre to its mean direction, over the child's markers, degrees.
    axis : list of float or None
        Hinge axis in the parent's frame (unit), for ``kind == 'hinge'``.
    center_local_m : list of float
        The centre in the parent segment's frame, metres.
    flagged : bool
        True when the fit was rejected and the fallback used.
    note : str
        Why it was flagged, and which fallback; or how a hinge centre was placed.
    axial_std_mm : float
        Standard deviation (Cramér-Rao, at the fitted centre and the residual noise)
        of the worst-determined coordinate of the centre, mm.
    """

    joint: str
    segment: str
    parent_segment: str | None
    kind: str
    method: str
    frames_used: int
    rms_residual_m: float
    condition: float
    cap_angle_deg: float
    axis: list | None
    center_local_m: list
    flagged: bool = False
    note: str = ""
    axial_std_mm: float = float("nan")

    def warning(self) -> str:
        """One line on why this joint's centre is not to be trusted ('' when it is): a
        fallback, a hinge centre put along its axis by the parent-joint rule (not seen
        in the data and no anatomical definition for it), or a fit whose worst-determined
        coordinate has a standard deviation over :data:`POOR_STD_MM`."""
        if self.kind in ("root", "end"):
            return ""
        if self.method == "fallback":
            return f"placed by its fallback: {self.note}"
        if "axis-rule" in self.method and "proximal joint" in self.note:
            return (f"a hinge: its centre along the axis is not observable (std "
                    f"{self.axial_std_mm:.0f} mm); placed on the axis nearest the parent's "
                    "joint by rule")
        if self.method.split("+")[0] in ("mgdk", "score") and "regression" not in self.method \
                and not self.axial_std_mm <= POOR_STD_MM:
            return (f"poorly conditioned fit (condition {self.condition:.3g}, worst coordinate "
                    f"std {self.axial_std_mm:.0f} mm, range of motion "
                    f"{self.cap_angle_deg:.0f} deg)")
        return ""

    def provenance(self) -> dict:
        """What placed the joint and how far to trust it: ``method``, range of motion
        (deg), RMS fit residual (mm), condition number, worst-coordinate std (mm) and the
        :meth:`warning` (JSON-ready)."""
        def num(x, scale=1.0):
            return float(x) * scale if x is not None and np.isfinite(x) else None

        return {"method": self.method, "range_of_motion_deg": num(self.cap_angle_deg),
                "residual_mm": num(self.rms_residual_m, 1e3), "condition": num(self.condition),
                "axial_std_mm": num(self.axial_std_mm), "warning": self.warning()}

    def as_dict(self) -> dict:
        """JSON-ready dict (NaN/inf become None), with :meth:`provenance`."""
        d = asdict(self)
        for k, v in d.items():
            if isinstance(v, float) and not np.isfinite(v):
                d[k] = None
        d["provenance"] = self.provenance()
        return d


@dataclass(frozen=True)
class JointSolution:
    """Joint centres of the first trial, plus what is needed to build a skeleton.

    Attributes
    ----------
    markerset : MarkerSet
        The (restricted) marker set used.
    joint_names : tuple of str, length J
    joint_parents : tuple of int, length J
        Parent joint index, -1 for the root.
    joint_segment : tuple of str, length J
        The segment whose frame a joint's own rotation is (its distal segment; ends:
        the segment they ride on).
    positions : numpy.ndarray, shape (F, J, 3)
        Joint centres in the C3D lab frame, metres, NaN where unknown.
    segment_names : tuple of str, length S
    rotations : numpy.ndarray, shape (F, S, 3, 3)
        Segment frames (columns = axes, lab frame), NaN where unknown.
    origins : numpy.ndarray, shape (F, S, 3)
        Segment frame origins, lab frame, metres.
    local_points : dict of str to dict of str to numpy.ndarray (3,)
        Per segment: constant positions of its joints (proximal, children, end) in
        its own frame, metres.
    reports : tuple of JointReport
    fps : float
    up : numpy.ndarray, shape (3,)
        The lab's up direction.
    missing_markers : dict of str to list of str
        Markers the set names that the file lacks, per segment.
    """

    markerset: MarkerSet
    joint_names: tuple[str, ...]
    joint_parents: tuple[int, ...]
    joint_segment: tuple[str, ...]
    positions: np.ndarray
    segment_names: tuple[str, ...]
    rotations: np.ndarray
    origins: np.ndarray
    local_points: dict
    reports: tuple[JointReport, ...]
    fps: float
    up: np.ndarray
    missing_markers: dict = field(default_factory=dict)

    def report(self, joint: str) -> JointReport:
        """The report of ``joint``."""
        for r in self.reports:
            if r.joint == joint:
                return r
        raise KeyError(joint)

    def position(self, joint: str) -> np.ndarray:
        """Trajectory of one joint, (F, 3) metres."""
        return self.positions[:, self.joint_names.index(joint)]

