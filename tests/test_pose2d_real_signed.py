"""``benchmarks/pose2d_real.py``'s signed per-joint offsets against MediaPipe (issue 27),
known answers."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from vidcap.body import JOINT_NAMES, BodyModel

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from pose2d_real_pipeline import signed_offsets  # noqa: E402

LIMBS = tuple(f"{s}_{j}" for j in ("shoulder", "elbow", "wrist", "hip", "knee", "ankle")
              for s in "lr")
#: a reference's landmark names: the 15 joints in another order, and two it alone has
REF_NAMES = ["nose", *reversed(JOINT_NAMES), "l_heel"]


def _clip(frames=8, seed=0):
    """A reference (F, 17, 2) px whose box is 200 px tall, and vidcap's joints (F, 15, 2)
    on it."""
    rest = BodyModel().rest_positions()  # (15, 3) m, y up
    uv = np.c_[300 + 100 * rest[:, 0], 300 - 100 * rest[:, 1]]
    rng = np.random.default_rng(seed)
    joints = uv[None] + rng.normal(0.0, 0.3, (frames, 15, 2))
    ref = np.empty((frames, len(REF_NAMES), 2))
    for k, n in enumerate(REF_NAMES):
        ref[:, k] = joints[:, JOINT_NAMES.index(n)] if n in JOINT_NAMES else np.nan
    ref[:, 0] = joints[:, JOINT_NAMES.index("neck")]
    ref[:, -1] = joints[:, JOINT_NAMES.index("l_ankle")]
    # the box: 200 px tall, whatever the body's own height
    ref[:, 0, 1] = ref[:, :, 1].max(1) - 200.0
    return ref, joints


def _swapped(joints, frames):
    out = joints.copy()
    for side in ("shoulder", "elbow", "wrist"):
        li, ri = JOINT_NAMES.index("l_" + side), JOINT_NAMES.index("r_" + side)
        out[np.ix_(frames, [li, ri])] = joints[np.ix_(frames, [ri, li])]
    return out


def test_a_shift_is_read_in_per_cent_of_the_box_whatever_the_labels():
    ref, joints = _clip()
    pred = joints.copy()
    pred[..., 1] += 10.0  # every joint 10 px = 5 % of the 200 px box lower
    pred[:, JOINT_NAMES.index("l_ankle"), 0] -= 6.0  # one ankle 3 % to the left
    pred = _swapped(pred, [0, 1, 2, 4, 5])  # most frames: arms named the other way round
    out = signed_offsets(ref, REF_NAMES, pred, LIMBS)
    assert out.shape == (12, 2)
    assert np.allclose(out[:, 1], 0.05, atol=0.004)
    dx = np.delete(out[:, 0], LIMBS.index("l_ankle"))
    assert np.allclose(dx, 0.0, atol=0.004)
    assert abs(out[LIMBS.index("l_ankle"), 0] + 0.03) < 0.004


def test_frames_without_a_reference_or_joints_do_not_count():
    ref, joints = _clip()
    pred = joints.copy()
    pred[:, JOINT_NAMES.index("r_shoulder"), 1] -= 8.0  # 4 % higher
    ref[2] = np.nan  # nobody found
    pred[3] = np.nan  # vidcap gave no joints
    pred[6:, JOINT_NAMES.index("r_shoulder"), 1] += 100.0  # far off, but only 2 of 6 frames
    out = signed_offsets(ref, REF_NAMES, pred, LIMBS)
    assert abs(out[LIMBS.index("r_shoulder"), 1] + 0.04) < 0.004
    assert np.allclose(np.delete(out[:, 1], LIMBS.index("r_shoulder")), 0.0, atol=0.004)
    none = signed_offsets(ref, REF_NAMES, np.full_like(pred, np.nan), LIMBS)
    assert none.shape == (12, 2) and np.isnan(none).all()
