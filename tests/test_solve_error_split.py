"""``benchmarks/solve_error_split.py``'s per-frame split of the 3D error (issue 33), known
answers."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from vidcap.body import JOINT_INDEX, BodyModel

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from lift_solve_tables import pa_joint_errors, pa_mpjpe_mm  # noqa: E402
from solve_error_split import (  # noqa: E402
    band_of,
    best_reflection_errors,
    limb_reflections,
)


def _poses(frames=6, seed=0):
    """(F, 15, 3) rest poses with every joint jittered by 3 cm in 3D (no two limbs
    alike, so no reflection of one is the other)."""
    rest = BodyModel().rest_positions()
    rng = np.random.default_rng(seed)
    return rest[None] + rng.normal(0.0, 0.03, (frames, 15, 3))


def _reflect_forearm(p, side="l"):
    q = p.copy()
    e, w = JOINT_INDEX[f"{side}_elbow"], JOINT_INDEX[f"{side}_wrist"]
    q[:, w, 2] = 2.0 * q[:, e, 2] - q[:, w, 2]
    return q


def test_pa_joint_errors_ignore_a_similarity_and_match_the_mean():
    p = _poses()
    c, s = np.cos(0.7), np.sin(0.7)
    rot = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    moved = 1.3 * p @ rot.T + np.array([0.4, -0.2, 2.0])
    assert np.abs(pa_joint_errors(moved, p)).max() < 1e-9
    q = _reflect_forearm(p)
    e = pa_joint_errors(q, p)
    assert e.shape == (6, 12) and e.max() > 0.01
    assert abs(pa_mpjpe_mm(q, p) - e.mean() * 1e3) < 1e-9
    # alternatives on a leading axis are aligned each on its own
    both = pa_joint_errors(np.stack([moved, q]), p)
    assert np.allclose(both[1], e) and np.abs(both[0]).max() < 1e-9


def test_limb_reflections_code_zero_is_the_pose_and_every_one_keeps_the_bones():
    p = _poses()
    r = limb_reflections(p)
    assert r.shape == (512, 6, 15, 3)
    assert np.array_equal(r[0], p)
    bones = [(JOINT_INDEX[a], JOINT_INDEX[b]) for a, b in (
        ("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"), ("r_hip", "r_knee"),
        ("r_knee", "r_ankle"))]
    for a, b in bones:
        length = np.linalg.norm(p[:, b] - p[:, a], axis=-1)
        # the unmirrored half (the mirrored one renames the sides)
        assert np.allclose(np.linalg.norm(r[:256, :, b] - r[:256, :, a], axis=-1), length)
    # there only depths change
    assert np.array_equal(r[:256, ..., :2], np.broadcast_to(p[..., :2], r[:256, ..., :2].shape))


def test_best_reflection_finds_a_reflected_forearm_and_a_mirrored_body():
    truth = _poses(seed=1)
    wrong = _reflect_forearm(truth, "r")
    assert pa_joint_errors(wrong, truth).mean() > 0.005
    assert best_reflection_errors(wrong, truth).max() < 1e-9
    from vidcap.video.lift import swap_sides

    root = truth[:, :1]
    mirrored = swap_sides((truth - root) * np.array([1.0, 1.0, -1.0])) + root
    assert pa_joint_errors(mirrored, truth).mean() > 0.005
    assert best_reflection_errors(mirrored, truth).max() < 1e-9


def test_band_of_counts_the_upper_bounds_into_the_band_above():
    assert band_of([0.0, 0.049, 0.05, 0.099, 0.10, 0.5]).tolist() == [0, 0, 1, 1, 2, 2]
