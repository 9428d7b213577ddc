"""Output rigs: our skeleton's motion renamed and re-jointed as retargeters expect it.

``--rig vidcap`` writes the body model's own 15 joints (:data:`vidcap.body.JOINT_NAMES`,
facing -Z). ``--rig mixamo`` and ``--rig humanik`` write the humanoid hierarchy that
Mixamo characters and MotionBuilder's HumanIK use, so that Blender's retargeting
add-ons, Unreal's IK Retargeter and MotionBuilder's characterisation map every bone
by name::

    Hips
    ├── Spine ── Spine1 ── Spine2 ─┬── Neck ── Head                  (End Site: HeadTop_End)
    │                              ├── LeftShoulder ── LeftArm ── LeftForeArm ── LeftHand
    │                              └── RightShoulder ── RightArm ── RightForeArm ── RightHand
    ├── LeftUpLeg ── LeftLeg ── LeftFoot ── LeftToeBase             (End Site: LeftToe_End)
    └── RightUpLeg ── RightLeg ── RightFoot ── RightToeBase

Mixamo's bones carry its ``mixamorig:`` namespace (``mixamorig:Hips``...), as a
character downloaded from Mixamo has them; HumanIK's names are bare (MotionBuilder's
naming template). Both rigs face +Z, as Mixamo and MotionBuilder characters do (our
own convention faces -Z); the rest pose is a T-pose with every joint frame aligned
with the world axes (identity rotations), Y up, metres.

Where the joints our model lacks are placed (our torso is one rigid cylinder, so the
spine joints do not bend: the whole torso turns at Hips):

* ``Spine``, ``Spine1``, ``Spine2``: a quarter, a half and three quarters of the way
  from the pelvis to the neck (the base of the neck, at shoulder height);
* ``LeftShoulder`` (the clavicle): at neck height, a quarter of the way from the neck to
  the shoulder joint; ``LeftArm`` is our shoulder joint;
* ``Head``: a third of the way from the neck to the top of the head (the skull's base);
  the top of the head is Head's End Site (``HeadTop_End``);
* ``LeftToeBase``: two thirds of our foot (:meth:`vidcap.body.BodyModel.end_site_offsets`:
  0.12 m at 1.75 m, forward along the floor) ahead of the ankle; the foot's tip
  (``LeftToe_End``) is its End Site. ``LeftHand`` is our wrist.

A marker skeleton (``vidcap joints``) is mapped the same way where it has our 15 joints
(the built-in full-body marker sets do); its own ``spine`` joint becomes ``Spine`` (with
``Spine1``/``Spine2`` at a third and two thirds of the way on to the neck), its ``l_toe``
``LeftToeBase`` and its ``l_hand_end`` the hand's End Site.

The mapped joints' names come from :data:`vidcap.io.jointmaps.JOINT_MAPS` (``"humanik"``), the
table by which :mod:`vidcap.synth` reads such files, so a file we write is read back
by name.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
from scipy.spatial.transform import Rotation

from vidcap.body import JOINT_NAMES
from vidcap.errors import UsageError
from vidcap.kinematics import Motion, Skeleton

#: The rigs ``--rig`` accepts.
RIGS: tuple[str, ...] = ("vidcap", "mixamo", "humanik")

#: Fractions of the pelvis -> neck line where the three spine joints sit.
SPINE_FRACTIONS = (0.25, 0.5, 0.75)
#: Fraction of the neck -> shoulder line where the clavicle joint sits.
CLAVICLE_FRACTION = 0.25
#: Fraction of the neck -> head top line where the Head joint (skull base) sits.
HEAD_FRACTION = 1.0 / 3.0
#: Fraction of our foot (the ankle's End Site) where the toe base sits.
TOE_FRACTION = 2.0 / 3.0


@dataclass(frozen=True)
class _RigJoint:
    """One joint of an output rig.

    ``place`` gives its rest position from our rest joint positions: ``(a, b, t)`` is
    ``a + t (b - a)``; ``b`` may be ``"<joint>@end"`` (that joint's End Site).
    ``anchor`` is our joint whose world rotation the rig joint takes.
    """

    name: str
    parent: str | None
    place: tuple[str, str, float]
    anchor: str


def _humanoid(side_names: dict[str, str], src: Skeleton) -> tuple[_RigJoint, ...]:
    """The rig's joints placed on ``src``: the video path's 15 joints, or a marker
    skeleton's, whose ``spine``, ``l_toe`` and ``l_hand_end`` joints are used where
    they exist (the torso then turns at the spine joint too)."""
    n = side_names  # our joint name -> the rig's name (HumanIK spelling, no namespace)
    have = set(src.joint_names)
    chest = src.joint_names[src.parents[src.index("neck")]]  # what the neck hangs from
    if "spine" in have:
        spine = [_RigJoint("Spine", n["pelvis"], ("spine", "spine", 0.0), "spine")]
        spine += [_RigJoint(name, parent, ("spine", "neck", f), chest) for name, parent, f in
                  (("Spine1", "Spine", 1 / 3), ("Spine2", "Spine1", 2 / 3))]
    else:
        spine = [_RigJoint(name, parent, ("pelvis", "neck", f), chest)
                 for name, parent, f in zip(("Spine", "Spine1", "Spine2"),
                                            (n["pelvis"], "Spine", "Spine1"), SPINE_FRACTIONS,
                                            strict=True)]
    joints = [
        _RigJoint(n["pelvis"], None, ("pelvis", "pelvis", 0.0), "pelvis"),
        *spine,
        _RigJoint(n["neck"], "Spine2", ("neck", "neck", 0.0), "neck"),
        _RigJoint("Head", n["neck"], ("neck", "head_top", HEAD_FRACTION), "neck"),
    ]
    for s, side in (("l", "Left"), ("r", "Right")):
        joints += [
            _RigJoint(f"{side}Shoulder", "Spine2",
                      ("neck", f"{s}_shoulder", CLAVICLE_FRACTION), chest),
            _RigJoint(n[f"{s}_shoulder"], f"{side}Shoulder",
                      (f"{s}_shoulder", f"{s}_shoulder", 0.0), f"{s}_shoulder"),
            _RigJoint(n[f"{s}_elbow"], n[f"{s}_shoulder"],
                      (f"{s}_elbow", f"{s}_elbow", 0.0), f"{s}_elbow"),
            _RigJoint(n[f"{s}_wrist"], n[f"{s}_elbow"],
                      (f"{s}_wrist", f"{s}_wrist", 0.0), f"{s}_wrist"),
        ]
    for s, side in (("l", "Left"), ("r", "Right")):
        toe = ((f"{s}_toe", f"{s}_toe", 0.0) if f"{s}_toe" in have
               else (f"{s}_ankle", f"{s}_ankle@end", TOE_FRACTION))
        joints += [
            _RigJoint(n[f"{s}_hip"], n["pelvis"], (f"{s}_hip", f"{s}_hip", 0.0), f"{s}_hip"),
            _RigJoint(n[f"{s}_knee"], n[f"{s}_hip"],
                      (f"{s}_knee", f"{s}_knee", 0.0), f"{s}_knee"),
            _RigJoint(n[f"{s}_ankle"], n[f"{s}_knee"],
                      (f"{s}_ankle", f"{s}_ankle", 0.0), f"{s}_ankle"),
            _RigJoint(f"{side}ToeBase", n[f"{s}_ankle"], toe, f"{s}_ankle"),
        ]
    return tuple(joints)


def _humanik_names() -> dict[str, str]:
    from vidcap.io.jointmaps import JOINT_MAPS

    table = JOINT_MAPS["humanik"]
    return {ours: (v if isinstance(v, str) else v[0]).split("@")[0] for ours, v in table.items()}


@dataclass(frozen=True)
class Rig:
    """An output rig: joint names, hierarchy, End Site names and facing.

    Attributes
    ----------
    name : str
        One of :data:`RIGS`.
    prefix : str
        Namespace put before every joint name (``"mixamorig:"`` for Mixamo).
    forward : {'-Z', '+Z'}
        Which way the rig's rest pose faces (Y is up in all of them).
    end_names : mapping of str to str
        Name of each leaf joint's End Site joint (glTF writes End Sites as joints),
        without the prefix.
    """

    name: str
    prefix: str
    forward: str
    end_names: MappingProxyType

    def joint_name(self, bare: str) -> str:
        """``bare`` with the rig's namespace prefix."""
        return self.prefix + bare

    def end_site_names(self) -> dict[str, str]:
        """Leaf joint name -> its End Site joint's name, both with the prefix."""
        return {self.prefix + k: self.prefix + v for k, v in self.end_names.items()}


def get_rig(name: str) -> Rig:
    """The :class:`Rig` called ``name``.

    Raises
    ------
    UsageError
        If ``name`` is not one of :data:`RIGS`.
    """
    if name == "vidcap":
        ends = {j: f"{j}_end" for j in ("head_top", "l_wrist", "r_wrist", "l_ankle", "r_ankle")}
        return Rig("vidcap", "", "-Z", MappingProxyType(ends))
    if name in ("mixamo", "humanik"):
        n = _humanik_names()
        ends = {"Head": n["head_top"], "LeftHand": "LeftHand_End",
                "RightHand": "RightHand_End", "LeftToeBase": "LeftToe_End",
                "RightToeBase": "RightToe_End"}
        prefix = "mixamorig:" if name == "mixamo" else ""
        return Rig(name, prefix, "+Z", MappingProxyType(ends))
    raise UsageError(f"unknown rig {name!r}; use one of {', '.join(RIGS)}")


def retarget(motion: Motion, rig: str | Rig = "vidcap") -> Motion:
    """``motion`` of the body model's skeleton as ``rig`` names and joints it.

    Parameters
    ----------
    motion : Motion
        A motion of a skeleton with our 15 joints, rooted at ``pelvis``, -Z forward
        (:meth:`vidcap.body.BodyModel.skeleton`, or a marker set's).
    rig : str or Rig
        One of :data:`RIGS`.

    Returns
    -------
    Motion
        The rig's skeleton (names with the rig's prefix, End Sites on its leaves) and
        local rotations that put every one of our joints where ``motion`` puts it,
        turned to face the rig's way (:func:`face_plus_z` for +Z rigs). For
        ``"vidcap"``, ``motion`` itself.

    Raises
    ------
    UsageError
        If ``motion`` lacks one of our 15 joints (a lower-body marker set, say) for a
        rig other than ``"vidcap"``.
    """
    rig = get_rig(rig) if isinstance(rig, str) else rig
    if rig.name == "vidcap":
        return motion
    sk = motion.skeleton
    missing = [n for n in JOINT_NAMES if n not in sk.joint_names]
    if missing or sk.joint_names[0] != "pelvis":
        missing = missing or ["pelvis as its root"]
        raise UsageError(f"--rig {rig.name} needs the 15 joints of our body model; this "
                         f"skeleton lacks {', '.join(missing)}")
    joints = _humanoid(_humanik_names(), sk)
    ours = {n: i for i, n in enumerate(sk.joint_names)}
    world_r, world_p = motion.world_transforms()
    rest = sk.rest_positions()
    ends = {n: rest[ours[n]] + off for n, off in sk.end_sites.items()}

    def point(spec: str) -> np.ndarray:
        name, _, end = spec.partition("@")
        if end and name not in ends:  # a leaf without an End Site: the bone continued
            return rest[ours[name]] + (rest[ours[name]] - rest[sk.parents[ours[name]]]) / 4
        return ends[name] if end else rest[ours[name]]

    def tip(joint: str, *after: str) -> np.ndarray:
        """Where the chain ends beyond ``joint``: the first of ``after`` that exists
        (a joint or an End Site, ``@end``)."""
        for spec in after:
            if spec.partition("@")[0] in ours and (not spec.endswith("@end")
                                                    or spec[:-4] in ends):
                return point(spec)
        return point(f"{joint}@end")

    pos = {j.name: point(j.place[0]) + j.place[2] * (point(j.place[1]) - point(j.place[0]))
           for j in joints}
    names = [j.name for j in joints]
    index = {n: i for i, n in enumerate(names)}
    parents = [-1 if j.parent is None else index[j.parent] for j in joints]
    offsets = np.array([pos[j.name] - (pos[j.parent] if j.parent else 0.0) for j in joints])
    end_sites = {"Head": rest[ours["head_top"]] - pos["Head"]}
    for side, s in (("Left", "l"), ("Right", "r")):
        end_sites[f"{side}Hand"] = tip(f"{s}_wrist", f"{s}_hand_end") - pos[f"{side}Hand"]
        end_sites[f"{side}ToeBase"] = (tip(f"{s}_ankle", f"{s}_toe@end", f"{s}_ankle@end")
                                       - pos[f"{side}ToeBase"])

    # world rotation of each rig joint = that of its anchor; local = parent^-1 @ world
    w_rig = world_r[:, [ours[j.anchor] for j in joints]]
    local = w_rig.copy()
    for k, p in enumerate(parents):
        if p >= 0:
            local[:, k] = np.swapaxes(w_rig[:, p], -1, -2) @ w_rig[:, k]
    F = motion.n_frames
    quats = Rotation.from_matrix(local.reshape(-1, 3, 3)).as_quat().reshape(F, len(joints), 4)
    skeleton = Skeleton(tuple(rig.joint_name(n) for n in names), tuple(parents), offsets,
                        {rig.joint_name(n): v for n, v in end_sites.items()})
    out = Motion(skeleton, motion.root_positions, quats, motion.fps)
    return face_plus_z(out) if rig.forward == "+Z" else out


#: Half a turn about +Y: our -Z-forward frame to a +Z-forward one (x, z negated).
TURN_TO_PLUS_Z = np.diag([-1.0, 1.0, -1.0])


def face_plus_z(motion: Motion) -> Motion:
    """``motion`` turned half a turn about the vertical, so its rest pose faces +Z.

    This is where our -Z-forward convention (``../shared/design.md``) becomes the +Z
    forward of glTF 2.0 and of Mixamo/HumanIK characters: every position and offset
    has its x and z negated, and every local rotation ``q`` becomes ``T q T^-1`` with
    ``T`` the half turn (quaternion ``(-x, y, -z, w)``), so the figure's left stays its
    left (left arm toward +X after the turn). Lengths and joint angles are unchanged.

    Parameters
    ----------
    motion : Motion

    Returns
    -------
    Motion
    """
    t = TURN_TO_PLUS_Z
    sk = motion.skeleton
    turned = Skeleton(sk.joint_names, sk.parents, sk.offsets @ t,
                      {n: v @ t for n, v in sk.end_sites.items()})
    q = motion.rotations * np.array([-1.0, 1.0, -1.0, 1.0])
    return Motion(turned, motion.root_positions @ t, q, motion.fps)


__all__ = ["RIGS", "Rig", "face_plus_z", "get_rig", "retarget"]
