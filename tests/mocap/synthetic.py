"""Virtual markers rigidly attached to the bones of a real motion (ground truth for tests)."""

from __future__ import annotations

import numpy as np

from vidcap.mocap.c3d import MarkerData
from vidcap.mocap.markerset import parse_markerset

# segment -> (parent segment, joint at the near end, bone joint, far-end joint) per source
BVH_131 = {
    "pelvis": (None, "pelvis", "Hips", ("LeftHip", "RightHip")),
    "thorax": ("pelvis", "spine", "Chest2", ("LeftShoulder", "RightShoulder", "Neck")),
    "l_upper_arm": ("thorax", "l_shoulder", "LeftShoulder", ("LeftElbow",)),
    "l_lower_arm": ("l_upper_arm", "l_elbow", "LeftElbow", ("LeftWrist",)),
    "r_upper_arm": ("thorax", "r_shoulder", "RightShoulder", ("RightElbow",)),
    "r_lower_arm": ("r_upper_arm", "r_elbow", "RightElbow", ("RightWrist",)),
    "l_upper_leg": ("pelvis", "l_hip", "LeftHip", ("LeftKnee",)),
    "l_lower_leg": ("l_upper_leg", "l_knee", "LeftKnee", ("LeftAnkle",)),
    "r_upper_leg": ("pelvis", "r_hip", "RightHip", ("RightKnee",)),
    "r_lower_leg": ("r_upper_leg", "r_knee", "RightKnee", ("RightAnkle",)),
}
ASF_07 = {
    "pelvis": (None, "pelvis", "root", ("lfemur", "rfemur")),
    "thorax": ("pelvis", "spine", "thorax", ("lhumerus", "rhumerus", "upperneck")),
    "l_upper_arm": ("thorax", "l_shoulder", "lhumerus", ("lradius",)),
    "l_lower_arm": ("l_upper_arm", "l_elbow", "lradius", ("lwrist",)),
    "r_upper_arm": ("thorax", "r_shoulder", "rhumerus", ("rradius",)),
    "r_lower_arm": ("r_upper_arm", "r_elbow", "rradius", ("rwrist",)),
    "l_upper_leg": ("pelvis", "l_hip", "lfemur", ("ltibia",)),
    "l_lower_leg": ("l_upper_leg", "l_knee", "ltibia", ("lfoot",)),
    "r_upper_leg": ("pelvis", "r_hip", "rfemur", ("rtibia",)),
    "r_lower_leg": ("r_upper_leg", "r_knee", "rtibia", ("rfoot",)),
}
#: joints whose rotation would move a shoulder or hip relative to the thorax/pelvis
#: frame (clavicles, hip "joints"): held still so that the truth is a rigid-body joint.
RIGID = {"LeftCollar", "RightCollar", "LHipJoint", "RHipJoint",
         "lclavicle", "rclavicle", "lhipjoint", "rhipjoint"}


def attach_markers(motion, layout, rng, *, noise_m=0.001, per_segment=3):
    """Markers 5-15 cm from the joints, rigid on each segment of ``motion``.

    Returns
    -------
    data : MarkerData
        Noisy markers (F, M, 3), metres, Y up.
    markerset : MarkerSet
    truth : dict of str to (F, 3)
        True joint centres by vidcap joint name.
    """
    from vidcap.kinematics import Motion

    sk = motion.skeleton
    rot = motion.rotations.copy()
    for j, n in enumerate(sk.joint_names):
        if n in RIGID:
            rot[:, j] = (0, 0, 0, 1)
    motion = Motion(sk, motion.root_positions, rot, motion.fps)
    world_r, world_p = motion.world_transforms()
    truth, labels, cols, toml = {}, [], [], ["name = 'synthetic'"]
    for seg, (parent, joint, bone, ends) in layout.items():
        b = sk.index(bone)
        truth[joint] = world_p[:, b]
        # the segment's joints in its own (bone) frame
        local_joints = [np.zeros(3)] if parent else []
        local_joints += [world_r[0, b].T @ (world_p[0, sk.index(e)] - world_p[0, b]) for e in ends]
        local_joints = np.array(local_joints)
        names = []
        while len(names) < per_segment:
            if len(local_joints) > 2 or not parent:  # around the segment's joints
                along = local_joints[rng.integers(len(local_joints))]
            elif parent:  # along the bone with a sideways offset
                t = rng.uniform(0.2, 0.8)
                along = local_joints[0] + t * (local_joints[1] - local_joints[0])
            off = rng.normal(size=3)
            cand = along + off / np.linalg.norm(off) * rng.uniform(0.04, 0.09)
            d = np.linalg.norm(local_joints - cand, axis=1).min()
            if 0.05 <= d <= 0.15:
                name = f"{seg.upper()}{len(names)}"
                names.append(name)
                labels.append(name)
                cols.append(world_p[:, b] + world_r[:, b] @ cand)
        toml.append(f"[segments.{seg}]")
        toml.append(f"joint = '{joint}'")
        if parent:
            toml.append(f"parent = '{parent}'")
        toml.append(f"markers = {names!r}")
    truth["pelvis"] = 0.5 * (truth["l_hip"] + truth["r_hip"])  # unused by the tests
    pos = np.stack(cols, axis=1)
    pos = pos + rng.normal(scale=noise_m, size=pos.shape)
    data = MarkerData(tuple(labels), pos, motion.fps, up=(0.0, 1.0, 0.0), path="<synthetic>")
    return data, parse_markerset("\n".join(toml)), truth
