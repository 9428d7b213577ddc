"""The result of the marker path: per-joint reports and the solved skeleton's centres
and segment frames (:func:`vidcap.mocap.skeleton.solve_joints`)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from vidcap.mocap.markerset import MarkerSet


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
        ``'mgdk'``, ``'mgdk+ugdk'``, ``'fallback'`` (marker centroid), ``'markers'``.
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

    def as_dict(self) -> dict:
        """JSON-ready dict (NaN/inf become None)."""
        d = asdict(self)
        for k, v in d.items():
            if isinstance(v, float) and not np.isfinite(v):
                d[k] = None
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

