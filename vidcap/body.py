"""The 10-cylinder human body model of seed 004 (Demir 2006, section 3.1.1).

Ten cylinders (head, torso, two upper arms, two lower arms, two upper legs, two
lower legs) joined at fifteen named joints. Every stage of the video path uses this
one model: the renderer that makes ground truth, the 2D fitter, the 3D lifting and
the BVH writer.

Geometry
--------
Lengths are the ratios of Table 3.1 times the subject's height (default 1.75 m).
Head + torso + upper leg + lower leg = (25 + 52 + 46 + 52) / 175 = 1, so the pelvis
sits at (46 + 52) / 175 of the height and the ankles are on the floor.

Table 3.2 lists "radii" of 40/175 for the torso and 20/175 for the head, i.e.
0.40 m and 0.20 m for a 1.75 m person. Read literally that is an 80 cm wide torso;
read as the full width (diameter) it is 40 cm (shoulder width) and a 20 cm head,
which matches human proportions and the silhouettes of the seed's Figure 3.3. We
therefore take the tabulated value as the cylinder's *diameter*
(:attr:`Segment.width_ratio`); :meth:`BodyModel.radius` is half of it.

Where the joints sit that the seed does not place: shoulders at the top corners of
the torso cylinder (half the torso width to each side, at neck height), hip joints
a quarter of the torso width to each side of the pelvis (0.20 m apart at 1.75 m,
an adult's inter-hip distance).

Degrees of freedom (seed 004 section 3.1.1): 3 global position, 3 torso, 1 head,
2 per upper and lower limb segment (8 x 2): 23 in all (:data:`DOF`).

Orientation convention: Y up, the body faces -Z in its rest pose, so its left is -X
and its right is +X (see ``../shared/design.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

#: Height of the seed's model in its own units (Table 3.1 denominators).
TABLE_HEIGHT = 175.0
#: Default subject height in metres.
DEFAULT_HEIGHT_M = 1.75

#: The 15 joint names, in a fixed order used by every (F, J, ...) array.
JOINT_NAMES: tuple[str, ...] = (
    "pelvis",
    "neck",
    "head_top",
    "l_shoulder",
    "l_elbow",
    "l_wrist",
    "r_shoulder",
    "r_elbow",
    "r_wrist",
    "l_hip",
    "l_knee",
    "l_ankle",
    "r_hip",
    "r_knee",
    "r_ankle",
)
JOINT_INDEX = MappingProxyType({name: i for i, name in enumerate(JOINT_NAMES)})

#: Parent of every joint in the kinematic tree (the root's parent is None).
#: The torso is one rigid cylinder (seed 004: 3 DOF, no spine), so the shoulders and
#: hips hang from the pelvis: the pelvis' rotation is the torso's rotation.
JOINT_PARENT = MappingProxyType(
    {
        "pelvis": None,
        "neck": "pelvis",
        "head_top": "neck",
        "l_shoulder": "pelvis",
        "l_elbow": "l_shoulder",
        "l_wrist": "l_elbow",
        "r_shoulder": "pelvis",
        "r_elbow": "r_shoulder",
        "r_wrist": "r_elbow",
        "l_hip": "pelvis",
        "l_knee": "l_hip",
        "l_ankle": "l_knee",
        "r_hip": "pelvis",
        "r_knee": "r_hip",
        "r_ankle": "r_knee",
    }
)
PARENT_INDEX: tuple[int, ...] = tuple(
    -1 if JOINT_PARENT[n] is None else JOINT_INDEX[JOINT_PARENT[n]] for n in JOINT_NAMES
)


@dataclass(frozen=True)
class Segment:
    """One cylinder of the body model.

    Attributes
    ----------
    name : str
        ``torso``, ``head``, ``l_upper_arm`` ...
    proximal, distal : str
        The joints it joins (the proximal one is nearer the root).
    length_ratio : float
        Length / body height (seed 004 Table 3.1).
    width_ratio : float
        Diameter / body height (seed 004 Table 3.2, read as a diameter; see module doc).
    """

    name: str
    proximal: str
    distal: str
    length_ratio: float
    width_ratio: float


#: The ten cylinders, Table 3.1 lengths and Table 3.2 widths.
SEGMENTS: tuple[Segment, ...] = (
    Segment("torso", "pelvis", "neck", 52 / 175, 40 / 175),
    Segment("head", "neck", "head_top", 25 / 175, 20 / 175),
    Segment("l_upper_arm", "l_shoulder", "l_elbow", 25 / 175, 10 / 175),
    Segment("l_lower_arm", "l_elbow", "l_wrist", 35 / 175, 10 / 175),
    Segment("r_upper_arm", "r_shoulder", "r_elbow", 25 / 175, 10 / 175),
    Segment("r_lower_arm", "r_elbow", "r_wrist", 35 / 175, 10 / 175),
    Segment("l_upper_leg", "l_hip", "l_knee", 46 / 175, 20 / 175),
    Segment("l_lower_leg", "l_knee", "l_ankle", 52 / 175, 20 / 175),
    Segment("r_upper_leg", "r_hip", "r_knee", 46 / 175, 20 / 175),
    Segment("r_lower_leg", "r_knee", "r_ankle", 52 / 175, 20 / 175),
)
SEGMENT_NAMES: tuple[str, ...] = tuple(s.name for s in SEGMENTS)
SEGMENT_INDEX = MappingProxyType({s.name: i for i, s in enumerate(SEGMENTS)})
#: Joints (proximal first) of the left and of the right member of each limb pair.
LIMB_PAIR_JOINTS = MappingProxyType({
    pair: tuple([JOINT_INDEX[f"{side}_{j}"] for j in joints] for side in "lr")
    for pair, joints in (("arms", ("shoulder", "elbow", "wrist")),
                         ("legs", ("hip", "knee", "ankle")))
})
#: (S, 2) joint indices (proximal, distal) of every segment.
SEGMENT_JOINTS = np.array(
    [(JOINT_INDEX[s.proximal], JOINT_INDEX[s.distal]) for s in SEGMENTS], dtype=np.intp
)
SEGMENT_JOINTS.setflags(write=False)

#: Degrees of freedom of the model (seed 004 section 3.1.1).
DOF = 3 + 3 + 1 + 8 * 2

#: Image-plane direction limits in degrees for Algorithm 1 (seed 004 Table 3.3). The
#: angle of a segment is that of the vector proximal -> distal, counter-clockwise
#: from the image's +x axis with image y pointing *up* (so 90 = straight up,
#: 270 = straight down). Table 3.3 gives the neck (head), waist (torso) and hips
#: (upper legs). The rest are not in the table; the values here are ours:
#: arms may point anywhere in the image (shoulders have a full circle of 2D
#: directions once the arm can swing toward/away from the camera), lower legs
#: within 90 degrees of straight down (a knee can bend 150 degrees, but a
#: standing/walking figure seen in the image keeps the shin below the knee; seen
#: in 2D, a shin above horizontal would mean a kneeling or kicking figure, which
#: the seed's upright-performer assumption excludes).
IMAGE_ANGLE_LIMITS_DEG = MappingProxyType(
    {
        "torso": (45.0, 135.0),  # Table 3.3 "Waist"
        "head": (45.0, 135.0),  # Table 3.3 "Neck"
        "l_upper_leg": (240.0, 300.0),  # Table 3.3 "Left hip"
        "r_upper_leg": (240.0, 300.0),  # Table 3.3 "Right hip"
        "l_lower_leg": (180.0, 360.0),  # ours, see above
        "r_lower_leg": (180.0, 360.0),
        "l_upper_arm": (0.0, 360.0),  # ours: unconstrained in 2D
        "r_upper_arm": (0.0, 360.0),
        "l_lower_arm": (0.0, 360.0),
        "r_lower_arm": (0.0, 360.0),
    }
)

#: Anatomical (3D) flexion limits in degrees for the joints Table 3.3 omits. Sources:
#: American Academy of Orthopaedic Surgeons normal ranges of motion (Greene &
#: Heckman, 1994): elbow flexion 0-150, knee flexion 0-135 (we allow 150 for deep
#: knee bends, as Norkin & White, 2016, report up to 150 passive). The elbow bends
#: only *forward* (the forearm folds toward the front of the upper arm) and the knee
#: only *backward* (the shin folds toward the back of the thigh); 0 is straight.
#: A few degrees of hyperextension (-5) are tolerated for measurement noise.
FLEXION_LIMITS_DEG = MappingProxyType(
    {
        "l_elbow": (-5.0, 150.0),
        "r_elbow": (-5.0, 150.0),
        "l_knee": (-5.0, 150.0),
        "r_knee": (-5.0, 150.0),
    }
)
#: Which way each hinge folds, as the direction (in the body's rest frame: -Z
#: forward) the distal segment moves toward when the joint flexes from straight.
FLEXION_DIRECTION = MappingProxyType(
    {
        "l_elbow": np.array([0.0, 0.0, -1.0]),  # forearm comes forward
        "r_elbow": np.array([0.0, 0.0, -1.0]),
        "l_knee": np.array([0.0, 0.0, 1.0]),  # shin goes backward
        "r_knee": np.array([0.0, 0.0, 1.0]),
    }
)

#: The six body orientations of seed 004 section 3.1.5 (which way the performer
#: faces as seen by the camera).
ORIENTATIONS: tuple[str, ...] = (
    "left",
    "right",
    "back_left",
    "back_right",
    "front_left",
    "front_right",
)


def orientation_from_yaw(yaw_rad):
    """Map a body yaw to the six orientation labels of seed 004 section 3.1.5.

    Parameters
    ----------
    yaw_rad : float or array_like, shape (...)
        Yaw of the body relative to the camera in radians: 0 = facing the camera,
        +pi/2 = facing image-right (a side view walking to the right), pi = facing
        away from the camera.

    Returns
    -------
    str or numpy.ndarray of str, shape (...)
        ``right``/``left`` within 30 degrees of a pure side view; otherwise
        ``front_*`` when the body faces the camera (|yaw| < 90 degrees) and
        ``back_*`` when it faces away, ``*_right`` when it faces image-right
        (sin(yaw) >= 0).
    """
    yaw = np.asarray(yaw_rad, dtype=float)
    s, c = np.sin(yaw), np.cos(yaw)
    side = np.where(s >= 0, "right", "left")
    depth = np.where(c >= 0, "front", "back")
    label = np.where(np.abs(c) < np.sin(np.deg2rad(30.0)), side, np.char.add(depth + "_", side))
    return str(label) if label.ndim == 0 else label.astype(object).astype(str)


@dataclass(frozen=True)
class BodyModel:
    """The body model at a given height, with optional per-subject segment lengths.

    Parameters
    ----------
    height : float
        Standing height in metres (head top to floor).
    lengths : mapping of str to float, optional
        Segment lengths in metres overriding the Table 3.1 ratios for this subject,
        keyed by segment name (e.g. ``{"l_upper_arm": 0.31}``).
    widths : mapping of str to float, optional
        Segment widths (diameters) in metres overriding the Table 3.2 ratios, keyed
        by segment name. The torso's width is the shoulders' breadth (the shoulder
        joints sit at its corners, the hips a quarter of it from the pelvis).
    shoulder_drop : float
        How far below the torso's top corners the shoulder joints sit, metres (0, the
        seed's: at the corners). A real shoulder's joint centre (the humerus' head) lies
        a few centimetres below the top of the shoulder's outline, which the torso's
        top edge follows.

    A subject's own proportions (:mod:`vidcap.video.fit.proportions` estimates them
    from a clip) are built with :func:`body_with_proportions`, which keeps ``height``
    the standing height.

    Examples
    --------
    >>> body = BodyModel(height=1.75)
    >>> round(body.length("torso"), 3)
    0.52
    >>> body.rest_positions().shape
    (15, 3)
    """

    height: float = DEFAULT_HEIGHT_M
    lengths: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    widths: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    shoulder_drop: float = 0.0

    def __post_init__(self):
        if not np.isfinite(self.height) or self.height <= 0:
            raise ValueError(f"height must be a positive number of metres, got {self.height!r}")
        drop = float(self.shoulder_drop)
        if not (np.isfinite(drop) and 0.0 <= drop < 0.1 * self.height):
            raise ValueError(f"shoulder_drop must be in [0, 0.1 x height) metres, got "
                             f"{self.shoulder_drop!r}")
        object.__setattr__(self, "shoulder_drop", drop)
        for name in ("lengths", "widths"):
            values = {k: float(v) for k, v in dict(getattr(self, name)).items()}
            unknown = set(values) - set(SEGMENT_NAMES)
            if unknown:
                raise ValueError(f"unknown segment(s) in {name}: {sorted(unknown)}")
            bad = {k: v for k, v in values.items() if not (np.isfinite(v) and v > 0)}
            if bad:
                raise ValueError(f"segment {name} must be positive metres, got {bad}")
            object.__setattr__(self, name, MappingProxyType(values))

    def __reduce__(self):
        # a MappingProxyType does not pickle: rebuild from plain dicts (fit workers)
        return (type(self), (self.height, dict(self.lengths), dict(self.widths),
                             self.shoulder_drop))

    @property
    def custom(self) -> bool:
        """True when any length or width is this subject's own (not the seed's ratios)."""
        return bool(self.lengths) or bool(self.widths) or bool(self.shoulder_drop)

    def length(self, segment: str) -> float:
        """Length of ``segment`` in metres."""
        if segment in self.lengths:
            return float(self.lengths[segment])
        return SEGMENTS[SEGMENT_INDEX[segment]].length_ratio * self.height

    def segment_lengths(self) -> np.ndarray:
        """Lengths of all segments in :data:`SEGMENT_NAMES` order, shape (10,), metres."""
        return np.array([self.length(s) for s in SEGMENT_NAMES])

    def radius(self, segment: str) -> float:
        """Cylinder radius of ``segment`` in metres (half its width: Table 3.2's value
        unless ``widths`` gives this subject's)."""
        if segment in self.widths:
            return 0.5 * float(self.widths[segment])
        return 0.5 * SEGMENTS[SEGMENT_INDEX[segment]].width_ratio * self.height

    def segment_radii(self) -> np.ndarray:
        """Radii of all segments in :data:`SEGMENT_NAMES` order, shape (10,), metres."""
        return np.array([self.radius(s) for s in SEGMENT_NAMES])

    @property
    def shoulder_half_width(self) -> float:
        """Lateral distance from the torso axis to each shoulder joint, metres."""
        return self.radius("torso")

    @property
    def hip_half_width(self) -> float:
        """Lateral distance from the pelvis to each hip joint, metres."""
        return 0.5 * self.radius("torso")

    def rest_offsets(self) -> np.ndarray:
        """Offsets of every joint from its parent in the T-pose, shape (15, 3), metres.

        T-pose: standing upright (+Y), facing -Z, arms straight out to the sides
        (left arm toward -X, right arm toward +X), legs straight down.
        """
        L = self.length
        sw, hw = self.shoulder_half_width, self.hip_half_width
        top = L("torso") - self.shoulder_drop  # the shoulder joints' height on the torso
        off = {
            "pelvis": (0.0, 0.0, 0.0),
            "neck": (0.0, L("torso"), 0.0),
            "head_top": (0.0, L("head"), 0.0),
            "l_shoulder": (-sw, top, 0.0),
            "l_elbow": (-L("l_upper_arm"), 0.0, 0.0),
            "l_wrist": (-L("l_lower_arm"), 0.0, 0.0),
            "r_shoulder": (sw, top, 0.0),
            "r_elbow": (L("r_upper_arm"), 0.0, 0.0),
            "r_wrist": (L("r_lower_arm"), 0.0, 0.0),
            "l_hip": (-hw, 0.0, 0.0),
            "l_knee": (0.0, -L("l_upper_leg"), 0.0),
            "l_ankle": (0.0, -L("l_lower_leg"), 0.0),
            "r_hip": (hw, 0.0, 0.0),
            "r_knee": (0.0, -L("r_upper_leg"), 0.0),
            "r_ankle": (0.0, -L("r_lower_leg"), 0.0),
        }
        return np.array([off[n] for n in JOINT_NAMES], dtype=float)

    def end_site_offsets(self) -> dict[str, np.ndarray]:
        """Non-zero End Site offsets of the leaf joints for BVH, metres.

        The head gets a short continuation upward, the hands a short continuation of
        the forearm, and each ankle a foot pointing forward (-Z) along the floor, so
        an animator sees which way the figure faces.
        """
        h = self.height / DEFAULT_HEIGHT_M
        return {
            "head_top": np.array([0.0, 0.03 * h, 0.0]),
            "l_wrist": np.array([-0.05 * h, 0.0, 0.0]),
            "r_wrist": np.array([0.05 * h, 0.0, 0.0]),
            "l_ankle": np.array([0.0, 0.0, -0.12 * h]),
            "r_ankle": np.array([0.0, 0.0, -0.12 * h]),
        }

    @property
    def standing_height(self) -> float:
        """Head top to floor when standing straight (head + torso + the longer leg),
        metres; ``height`` unless the lengths are a subject's own that do not add up to
        it."""
        return self.pelvis_height + self.length("torso") + self.length("head")

    @property
    def pelvis_height(self) -> float:
        """Height of the pelvis above the floor when standing straight, metres."""
        return max(
            self.length("l_upper_leg") + self.length("l_lower_leg"),
            self.length("r_upper_leg") + self.length("r_lower_leg"),
        )

    def rest_positions(self) -> np.ndarray:
        """World positions of the joints in the T-pose, feet on the floor, shape (15, 3)."""
        off = self.rest_offsets()
        pos = np.zeros_like(off)
        for j, p in enumerate(PARENT_INDEX):
            pos[j] = off[j] if p < 0 else pos[p] + off[j]
        pos[:, 1] += self.pelvis_height
        return pos

    def skeleton(self):
        """This body as a :class:`vidcap.kinematics.Skeleton` (the BVH hierarchy)."""
        from vidcap.kinematics import Skeleton

        return Skeleton(
            joint_names=JOINT_NAMES,
            parents=PARENT_INDEX,
            offsets=self.rest_offsets(),
            end_sites=self.end_site_offsets(),
        )


#: The groups of segments :func:`body_with_proportions` scales together (left and right
#: pooled: one subject has one arm length).
PROPORTION_GROUPS = MappingProxyType({
    "head": ("head",),
    "torso": ("torso",),
    "upper_arms": ("l_upper_arm", "r_upper_arm"),
    "lower_arms": ("l_lower_arm", "r_lower_arm"),
    "upper_legs": ("l_upper_leg", "r_upper_leg"),
    "lower_legs": ("l_lower_leg", "r_lower_leg"),
})
#: Shorthands of :func:`body_with_proportions`: several groups at once.
PROPORTION_ALIASES = MappingProxyType({
    "arms": ("upper_arms", "lower_arms"),
    "legs": ("upper_legs", "lower_legs"),
})
#: The key of :func:`body_with_proportions`' ``factors`` that is not a factor: the shoulder
#: joints' drop below the torso's top corners as a share of the standing height
#: (:attr:`BodyModel.shoulder_drop`).
SHOULDER_DROP = "shoulder_drop"
#: Width factors :func:`body_with_proportions` takes (``shoulders``: the torso's width).
WIDTH_GROUPS = MappingProxyType({
    "shoulders": ("torso",),
    "head_width": ("head",),
    "arm_width": ("l_upper_arm", "r_upper_arm", "l_lower_arm", "r_lower_arm"),
    "leg_width": ("l_upper_leg", "r_upper_leg", "l_lower_leg", "r_lower_leg"),
})


def body_with_proportions(height: float = DEFAULT_HEIGHT_M, factors=None, *,
                          keep_height: bool = True) -> BodyModel:
    """A body whose segments are the seed's ratios times per-group factors.

    Parameters
    ----------
    height : float
        Standing height in metres.
    factors : mapping of str to float, optional
        Length factors by :data:`PROPORTION_GROUPS` name (or an alias of
        :data:`PROPORTION_ALIASES`: ``legs``, ``arms``) and width factors by
        :data:`WIDTH_GROUPS` name, e.g. ``{"legs": 1.15, "arms": 0.9, "shoulders": 1.2}``;
        and :data:`SHOULDER_DROP`, the shoulder joints' drop below the torso's top
        corners as a share of ``height`` (in [0, 0.1); default 0), rescaled with the
        lengths (so it stays the share it is of head + torso + leg).
    keep_height : bool
        Rescale every length and width together so head + torso + leg stays
        ``height`` (the subject's standing height is the metric scale); False keeps
        the factors as given (a body taller than ``height`` when the legs are longer).

    Returns
    -------
    BodyModel

    Raises
    ------
    ValueError
        On an unknown name or a factor that is not positive.

    Examples
    --------
    >>> b = body_with_proportions(1.75, {"legs": 1.15})
    >>> round(b.standing_height, 6), b.length("l_upper_leg") > BodyModel().length("l_upper_leg")
    (1.75, True)
    """
    f_len = dict.fromkeys(SEGMENT_NAMES, 1.0)
    f_wid = dict.fromkeys(SEGMENT_NAMES, 1.0)
    # aliases first, so a group's own factor (``upper_legs``) wins over ``legs``
    factors = dict(factors or {})
    drop = float(factors.pop(SHOULDER_DROP, 0.0))
    if not (np.isfinite(drop) and 0.0 <= drop < 0.1):
        raise ValueError(f"{SHOULDER_DROP} must be a share of the height in [0, 0.1), got "
                         f"{drop!r}")
    items = sorted(factors.items(), key=lambda kv: kv[0] not in PROPORTION_ALIASES)
    for name, value in items:
        value = float(value)
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"proportion {name!r} must be a positive factor, got {value!r}")
        if name in WIDTH_GROUPS:
            for seg in WIDTH_GROUPS[name]:
                f_wid[seg] = value
            continue
        groups = PROPORTION_ALIASES.get(name, (name,))
        if any(g not in PROPORTION_GROUPS for g in groups):
            known = sorted([*PROPORTION_GROUPS, *PROPORTION_ALIASES, *WIDTH_GROUPS])
            raise ValueError(f"unknown proportion {name!r} (known: {', '.join(known)})")
        for g in groups:
            for seg in PROPORTION_GROUPS[g]:
                f_len[seg] = value
    seed = BodyModel(height=height)
    lengths = {s: seed.length(s) * f_len[s] for s in SEGMENT_NAMES}
    widths = {s: 2.0 * seed.radius(s) * f_wid[s] for s in SEGMENT_NAMES}
    k = 1.0
    if keep_height:
        legs = max(lengths["l_upper_leg"] + lengths["l_lower_leg"],
                   lengths["r_upper_leg"] + lengths["r_lower_leg"])
        k = height / (legs + lengths["torso"] + lengths["head"])
    return BodyModel(height=height, lengths={s: v * k for s, v in lengths.items()},
                     widths={s: v * k for s, v in widths.items()},
                     shoulder_drop=drop * height * k)


def segment_vectors(joints: np.ndarray) -> np.ndarray:
    """Vectors proximal -> distal of every segment.

    Parameters
    ----------
    joints : numpy.ndarray, shape (..., 15, D)
        Joint positions in :data:`JOINT_NAMES` order (D = 2 or 3).

    Returns
    -------
    numpy.ndarray, shape (..., 10, D)
        ``joints[..., distal] - joints[..., proximal]`` per segment.
    """
    joints = np.asarray(joints)
    return joints[..., SEGMENT_JOINTS[:, 1], :] - joints[..., SEGMENT_JOINTS[:, 0], :]
