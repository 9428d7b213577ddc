"""Front or back from the colour frame (vidcap.video.frontback, proposals.propose_front).

Known answers: a rendered walk seen from behind (yaw 120) and from the front (yaw 60)
with the true 2D joints; a walk whose front/back the silhouette-only proposal gets
wrong (it always says front) is turned the right way by the cue, through the clip solve.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from vidcap.body import BodyModel
from vidcap.video.frontback import arm_visibility, near_side, sample_points
from vidcap.video.proposals import propose_front, propose_orientation


@functools.cache
def _walk(yaw: float):
    """Frames and truth of the synth walk (30 frames, 320x240) at ``yaw`` degrees."""
    from vidcap.synth import make_motion, render_clip

    m = make_motion("walk", body=BodyModel(), fps=30.0, n_frames=30,
                    rng=np.random.default_rng(0))
    return render_clip(m, yaw_deg=yaw, size=(320, 240), noise=0.0,
                       rng=np.random.default_rng(0))


def test_propose_front_reads_the_near_arm_against_the_facing_side():
    F = 40
    right = np.ones(F, bool)
    assert (propose_front(np.full(F, 0.2), right, fps=30.0) == 1).all()
    assert (propose_front(np.full(F, -0.2), right, fps=30.0) == -1).all()
    # a body facing image left shows its near (left) arm on the image's right
    assert (propose_front(np.full(F, 0.2), ~right, fps=30.0) == -1).all()
    assert (propose_front(np.zeros(F), right, fps=30.0) == 0).all()


def test_propose_front_carries_a_decision_over_frames_without_evidence():
    F = 90
    near = np.zeros(F)
    near[:20] = -0.3  # the arm swung clear of the body from frame 20 on: no evidence
    out = propose_front(near, np.ones(F, bool), fps=30.0)
    assert (out == -1).all()


def test_sample_points_tell_the_arms_by_their_shoulders_not_their_names():
    j = np.zeros((1, 15, 2))
    j[0, 3] = [10.0, 0.0]  # l_shoulder on the image's right
    j[0, 4], j[0, 5] = [10.0, 10.0], [10.0, 20.0]
    j[0, 6] = [0.0, 0.0]  # r_shoulder on the image's left
    j[0, 7], j[0, 8] = [0.0, 10.0], [0.0, 20.0]
    pts = sample_points(j, search=np.zeros(1))
    assert np.allclose(pts["arm_left"][0, :, 0], 0.0)
    assert np.allclose(pts["arm_right"][0, :, 0], 10.0)


@pytest.mark.parametrize("yaw, sign", [(135.0, -1), (120.0, -1), (60.0, 1), (45.0, 1)])
def test_the_near_arm_of_a_rendered_walk(yaw, sign):
    frames, truth = _walk(yaw)
    near = near_side(arm_visibility(frames, truth["joints2d"]))
    # facing image right: the image-left arm in front means facing the camera
    assert sign * near.mean() > 0.02
    if yaw in (135.0, 45.0):  # 30 degrees from the side sector's edges: decided throughout
        assert (propose_front(near, np.ones(len(near), bool), fps=30.0) == sign).all()


def test_missing_frames_give_no_evidence():
    frames, truth = _walk(120.0)
    vis = arm_visibility([frames[0], frames[1], None], truth["joints2d"][:4])
    assert np.isfinite(vis[:2]).all() and np.isnan(vis[2:]).all()
    assert (near_side(vis)[2:] == 0).all()


def test_orientation_proposal_takes_front_or_back_from_the_cue():
    frames, truth = _walk(120.0)
    j2 = truth["joints2d"]
    body = BodyModel()
    scale = float(np.linalg.norm(truth["camera"][0, :3]))
    plain = propose_orientation(j2, scale=scale, fps=30.0, body=body)
    assert not any(lab.startswith("back") for lab in plain)  # silhouettes cannot tell
    near = near_side(arm_visibility(frames, j2))
    read = {}
    cued = propose_orientation(j2, scale=scale, fps=30.0, body=body, near_side=near, out=read)
    assert all(lab.startswith("back") or lab in ("left", "right") for lab in cued)
    # the front/back it read, handed out with the facing it was read with
    assert (read["right"] == np.char.endswith(cued, "right")).all()
    np.testing.assert_array_equal(read["front"], propose_front(near, read["right"], fps=30.0))
    assert (read["front"] == -1).all()


def test_a_walk_planted_front_for_back_is_turned_round_by_the_cue():
    from vidcap.video.lifting import lift_pose
    from vidcap.video.solve.skeleton import YAW

    frames, truth = _walk(135.0)
    j2 = truth["joints2d"]  # seen from behind, body names = image sides
    near = near_side(arm_visibility(frames, j2))
    args = dict(fps=30.0, body=BodyModel(), image_sides=True, frame_size=(320, 240))
    wrong = lift_pose(j2, **args)
    right = lift_pose(j2, near_side=near, **args)
    assert (np.cos(wrong.solve_params[:, YAW]) > 0).mean() >= 0.9  # facing the camera
    assert (np.cos(right.solve_params[:, YAW]) < 0).mean() >= 0.9  # turned away, as rendered
    assert (right.facing == -1).all()
    assert wrong.facing is None
