"""``benchmarks/lift_solve_tables.mediapipe_image_joints``: MediaPipe's 2D landmarks as the
lift's 15 joints (issue 33's reference row), known answers."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from vidcap.body import JOINT_INDEX as J
from vidcap.body import JOINT_NAMES

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from lift_solve_tables import mediapipe_image_joints  # noqa: E402

#: MediaPipe Pose's 33 landmark slots as the reference tool maps them ('' = not a joint).
_MAP = ["nose"] + [""] * 10 + ["l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist",
                               "r_wrist"] + [""] * 6 + ["l_hip", "r_hip", "l_knee", "r_knee",
                                                        "l_ankle", "r_ankle"] + [""] * 4


def _reference(tmp_path, marks):
    path = tmp_path / "clip.mediapipe.npz"
    np.savez(path, landmarks=marks.astype(np.float32), names_vidcap_map=np.array(_MAP))
    return path


def test_limb_joints_are_the_landmarks_and_the_trunk_their_midpoints(tmp_path):
    rng = np.random.default_rng(0)
    marks = rng.uniform(0, 500, (4, 33, 2))
    fitted = rng.uniform(0, 500, (4, 15, 2))
    out = mediapipe_image_joints(_reference(tmp_path, marks), JOINT_NAMES, fitted)
    assert out.shape == (4, 15, 2)
    for name in ("l_wrist", "r_knee", "l_shoulder", "r_ankle"):
        np.testing.assert_allclose(out[:, J[name]], marks[:, _MAP.index(name)], rtol=1e-6)
    hips = 0.5 * (marks[:, _MAP.index("l_hip")] + marks[:, _MAP.index("r_hip")])
    np.testing.assert_allclose(out[:, J["pelvis"]], hips, rtol=1e-6)
    # the head top keeps the fit's neck-to-head vector, set on MediaPipe's neck
    np.testing.assert_allclose(out[:, J["head_top"]] - out[:, J["neck"]],
                               fitted[:, J["head_top"]] - fitted[:, J["neck"]], rtol=1e-6)


def test_a_frame_with_a_missing_landmark_is_missing_whole(tmp_path):
    marks = np.ones((3, 33, 2))
    marks[1, _MAP.index("r_wrist")] = np.nan
    out = mediapipe_image_joints(_reference(tmp_path, marks), JOINT_NAMES, np.zeros((5, 15, 2)))
    assert len(out) == 3  # as long as the shorter of the two
    assert np.isnan(out[1]).all()
    assert np.isfinite(out[[0, 2]]).all()
