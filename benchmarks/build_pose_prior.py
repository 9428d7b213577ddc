"""Build vidcap/data/pose_prior.npz, the clip solve's pose prior (vidcap.video.solve.prior).

Training data: CMU Graphics Lab motion capture (mocap.cs.cmu.edu, NSF EIA-0196217),
as converted to BVH on the iClone/CC rig by the public repository
DragonForgedTheArtist/IClone-CMU-Mocap (commit 79529f9, All_BVH/subjects/), one file
per trial under $VIDCAP_DATA/mocap/cmu_iclone/ (benchmarks/DATA.md). Subjects 1, 2, 3, 5
and 6 only: never subject 7 (07_07 is a validation motion), 131 (131_01 is), 13 or 16
(reserved). Each trial's first frame (a T-pose the conversion prepended) is dropped,
the rest taken at 30 fps, at most MAX_FRAMES per trial (so long dance and playground
trials do not outweigh the walks), mirrored left/right too.

Each frame's 15 joints are read from the BVH, the solve's parameters fitted to their
directions (vidcap.video.solve.skeleton.params_from_joints), the body model posed with
them, and the features (segment directions in the torso frame) of that pose taken.

Run:  VIDCAP_DATA=/work/data python benchmarks/build_pose_prior.py
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vidcap.body import JOINT_NAMES, BodyModel  # noqa: E402
from vidcap.io.bvh import read_bvh  # noqa: E402
from vidcap.video.solve.prior import TABLE, features, fit_prior  # noqa: E402
from vidcap.video.solve.skeleton import forward_kinematics, params_from_joints  # noqa: E402

SOURCE = "DragonForgedTheArtist/IClone-CMU-Mocap@79529f962ade3274163af53cd92179cee2ed9407"
SUBJECTS = ("001", "002", "003", "005", "006")
MAX_FRAMES = 300
COMPONENTS = int(os.environ.get("PRIOR_COMPONENTS", "6"))
_MAP = {
    "pelvis": "CC_Base_Hip", "neck": "CC_Base_NeckTwist01", "head_top": "CC_Base_Head",
    "l_shoulder": "CC_Base_L_Upperarm", "l_elbow": "CC_Base_L_Forearm",
    "l_wrist": "CC_Base_L_Hand", "r_shoulder": "CC_Base_R_Upperarm",
    "r_elbow": "CC_Base_R_Forearm", "r_wrist": "CC_Base_R_Hand",
    "l_hip": "CC_Base_L_Thigh", "l_knee": "CC_Base_L_Calf", "l_ankle": "CC_Base_L_Foot",
    "r_hip": "CC_Base_R_Thigh", "r_knee": "CC_Base_R_Calf", "r_ankle": "CC_Base_R_Foot",
}
_MIRROR = [JOINT_NAMES.index(n.replace("l_", "x_").replace("r_", "l_").replace("x_", "r_"))
           for n in JOINT_NAMES]


def trial_joints(path: Path) -> np.ndarray:
    """(F, 15, 3) joints of a trial at 30 fps, first frame dropped, Y up."""
    m = read_bvh(path)
    names = list(m.skeleton.joint_names)
    pos = m.positions()
    step = max(1, int(round(m.fps / 30.0)))
    j = pos[1::step][:, [names.index(_MAP[n]) for n in JOINT_NAMES]]
    return j[:MAX_FRAMES]


def pose_features(joints, body) -> np.ndarray:
    p = params_from_joints(joints)
    posed, root, _ = forward_kinematics(p, body.rest_offsets())
    return features(posed, root, body.segment_lengths())


def main() -> int:
    data = Path(os.environ.get("VIDCAP_DATA", "/nonexistent")) / "mocap" / "cmu_iclone"
    body = BodyModel()
    files = sorted(f for f in data.glob("*.bvh") if f.name[:3] in SUBJECTS)
    if not files:
        print(f"no trials under {data} (benchmarks/DATA.md says how to fetch them)")
        return 2
    feats, used = [], []
    for f in files:
        j = trial_joints(f)
        mirrored = j[:, _MIRROR] * np.array([-1.0, 1.0, 1.0])
        feats += [pose_features(j, body), pose_features(mirrored, body)]
        used.append(f.stem)
    x = np.concatenate(feats)
    means, factors, consts = fit_prior(x, k=COMPONENTS)
    TABLE.parent.mkdir(exist_ok=True)
    np.savez_compressed(TABLE, means=means, factors=factors, consts=consts, trials=np.array(used),
                        source=np.array(SOURCE), frames=np.array(len(x)))
    print(f"{len(used)} trials, {len(x)} frames (with mirrored copies) -> {TABLE}")
    print("trials:", " ".join(used))
    return 0


if __name__ == "__main__":
    sys.exit(main())
