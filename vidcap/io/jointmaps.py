"""Joint-name tables: how each of our 15 joints is named in other skeletons.

Shared by the readers of foreign motion (:mod:`vidcap.synth.retarget`) and the output rigs
(:mod:`vidcap.io.rigs`), so that a file we write is read back by the same table.
"""

from types import MappingProxyType

from vidcap.body import JOINT_NAMES

#: How each of our 15 joints is found in a source skeleton, per naming scheme.
#: Each entry maps our joint name to a source joint name, or to a tuple of names of
#: which the first present is used; ``"<name>@end"`` means the End Site of that joint
#: (or its first child when it has none). Source names are matched
#: case-insensitively, ignoring a namespace prefix such as ``mixamorig:``. The first
#: scheme whose joints are all present is used (:func:`detect_joint_map`).
#:
#: =========== ============== ============== ==========================
#: ours        CMU BVH        CMU ASF/AMC    HumanIK
#: =========== ============== ============== ==========================
#: pelvis      Hips           root           Hips
#: neck        Neck           upperneck      Neck
#: head_top    Head@end       head@end       HeadTop_End or Head@end
#: l_shoulder  LeftShoulder   lhumerus       LeftArm
#: l_elbow     LeftElbow      lradius        LeftForeArm
#: l_wrist     LeftWrist      lwrist         LeftHand
#: l_hip       LeftHip        lfemur         LeftUpLeg
#: l_knee      LeftKnee       ltibia         LeftLeg
#: l_ankle     LeftAnkle      lfoot          LeftFoot
#: (right side likewise: Right*, r*)
#: =========== ============== ============== ==========================
#:
#: CMU BVH's ``Neck`` joint and ASF's ``upperneck`` (the near end of the bone) sit at
#: shoulder height, where our neck joint is (the top of the torso cylinder). The
#: HumanIK names (MotionBuilder's) are those of Mixamo, of the widely shared CMU
#: conversion (``LHipJoint``, ``LeftUpLeg``, ``Spine1``, ``Neck1``...) and of many
#: capture suits' BVH exports; their ``Neck`` is the base of the neck too.
JOINT_MAPS = MappingProxyType(
    {
        "vidcap": MappingProxyType({n: n for n in JOINT_NAMES}),
        "cmu_bvh": MappingProxyType(
            {
                "pelvis": "Hips", "neck": "Neck", "head_top": "Head@end",
                "l_shoulder": "LeftShoulder", "l_elbow": "LeftElbow", "l_wrist": "LeftWrist",
                "r_shoulder": "RightShoulder", "r_elbow": "RightElbow",
                "r_wrist": "RightWrist",
                "l_hip": "LeftHip", "l_knee": "LeftKnee", "l_ankle": "LeftAnkle",
                "r_hip": "RightHip", "r_knee": "RightKnee", "r_ankle": "RightAnkle",
            }
        ),
        "cmu_asf": MappingProxyType(
            {
                "pelvis": "root", "neck": "upperneck", "head_top": "head@end",
                "l_shoulder": "lhumerus", "l_elbow": "lradius", "l_wrist": "lwrist",
                "r_shoulder": "rhumerus", "r_elbow": "rradius", "r_wrist": "rwrist",
                "l_hip": "lfemur", "l_knee": "ltibia", "l_ankle": "lfoot",
                "r_hip": "rfemur", "r_knee": "rtibia", "r_ankle": "rfoot",
            }
        ),
        "humanik": MappingProxyType(
            {
                "pelvis": "Hips", "neck": "Neck", "head_top": ("HeadTop_End", "Head@end"),
                "l_shoulder": "LeftArm", "l_elbow": "LeftForeArm", "l_wrist": "LeftHand",
                "r_shoulder": "RightArm", "r_elbow": "RightForeArm", "r_wrist": "RightHand",
                "l_hip": "LeftUpLeg", "l_knee": "LeftLeg", "l_ankle": "LeftFoot",
                "r_hip": "RightUpLeg", "r_knee": "RightLeg", "r_ankle": "RightFoot",
            }
        ),
    }
)
