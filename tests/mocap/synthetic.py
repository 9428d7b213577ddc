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


def _place(local_joints, long_bone, per_segment, rng, *, min_width=0.03):
    """Marker positions (per_segment, 3) in a segment's frame, 5-15 cm from its joints.

    As a marker set would place them: spread over the segment and around it, never
    (nearly) in a line, since three collinear markers do not define a frame.

    * A long bone (proximal and distal joint): the markers alternate between the
      proximal and the distal end (10-45 % of the bone from that end), 4-9 cm off
      the bone axis, at azimuths about 120 degrees apart (±20 degrees) around it.
    * Other segments (pelvis, thorax): each marker 4-9 cm in a random direction from
      a different joint of the segment (in random order).

    Every marker is 5-15 cm from the nearest joint of the segment, and a layout is
    redrawn until the markers' second principal extent (√ of the second eigenvalue
    of their scatter) is at least ``min_width`` m.
    """
    while True:
        out = []
        phi0 = rng.uniform(0, 2 * np.pi)
        order = rng.permutation(len(local_joints))
        while len(out) < per_segment:
            i = len(out)
            if long_bone and len(local_joints) == 2:
                a, b = local_joints
                axis = (b - a) / np.linalg.norm(b - a)
                t = rng.uniform(0.10, 0.45)
                end = i % 2 if i < 2 else rng.integers(2)
                along = a + (t if end == 0 else 1 - t) * (b - a)
                ref = np.eye(3)[int(np.argmin(np.abs(axis)))]
                e1 = np.cross(axis, ref)
                e1 /= np.linalg.norm(e1)
                e2 = np.cross(axis, e1)
                phi = phi0 + 2 * np.pi * i / per_segment + np.radians(rng.uniform(-20, 20))
                cand = along + rng.uniform(0.04, 0.09) * (np.cos(phi) * e1 + np.sin(phi) * e2)
            else:
                along = local_joints[order[i % len(order)]]
                off = rng.normal(size=3)
                cand = along + off / np.linalg.norm(off) * rng.uniform(0.04, 0.09)
            d = np.linalg.norm(local_joints - cand, axis=1).min()
            if 0.05 <= d <= 0.15:
                out.append(cand)
        out = np.array(out)
        sv = np.linalg.svd(out - out.mean(0), compute_uv=False)
        if sv[1] / np.sqrt(len(out)) >= min_width:
            return out


def attach_markers(motion, layout, rng, *, noise_m=0.001, per_segment=3):
    """Markers 5-15 cm from the joints, rigid on each segment of ``motion``.

    Clavicles and hip "joints" are held still (so shoulders and hips are ball joints
    of the thorax and pelvis); marker layout by :func:`_place`; noise i.i.d. Gaussian
    per coordinate, ``noise_m`` standard deviation, drawn from ``rng``; every frame of
    the motion is used.

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
        cands = _place(local_joints, bool(parent), per_segment, rng)
        names = []
        for cand in cands:
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
