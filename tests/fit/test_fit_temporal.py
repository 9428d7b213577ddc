"""The solve over time: Viterbi against brute force, and limb labels over a clip."""

import itertools

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX, LIMB_PAIR_JOINTS
from vidcap.video.fit.temporal import best_path, label_path, relabel

LEFT_LEG, RIGHT_LEG = (list(x) for x in LIMB_PAIR_JOINTS["legs"])


def test_best_path_is_the_brute_force_minimum():
    rng = np.random.default_rng(0)
    for _ in range(20):
        n, k = rng.integers(1, 6), rng.integers(1, 4)
        unary, move = rng.random((n, k)), rng.random((n - 1, k, k))
        path, cost = best_path(unary, move)

        def total(p, unary=unary, move=move):
            return unary[np.arange(len(p)), p].sum() + sum(move[f, p[f], p[f + 1]]
                                                           for f in range(len(p) - 1))

        brute = min(itertools.product(range(k), repeat=n), key=lambda p: total(np.array(p)))
        assert cost == pytest.approx(total(np.array(brute)))
        assert total(path) == pytest.approx(cost)


def test_best_path_refuses_bad_shapes_and_costs():
    with pytest.raises(ValueError, match="transition"):
        best_path(np.zeros((3, 2)), np.zeros((3, 2, 2)))
    with pytest.raises(ValueError, match="finite"):
        best_path(np.array([[0.0, np.nan]]), np.zeros((0, 2, 2)))
    assert best_path(np.zeros((0, 2)), np.zeros((0, 2, 2)))[0].shape == (0,)


def _walk(n=40, spread=1.0):
    """Joints (n, 15, 2) of a figure 100 px tall whose legs swing in antiphase, hips
    ``spread`` * 20 px apart."""
    t = np.arange(n)
    j = np.zeros((n, 15, 2))
    j[:, :, 0] = 100.0
    j[:, :, 1] = 50.0
    swing = 12.0 * np.sin(2 * np.pi * t / 30)
    for joints, side, sign in ((LEFT_LEG, -1, 1), (RIGHT_LEG, 1, -1)):
        hip, knee, ankle = joints
        j[:, hip] = np.c_[100 + side * 10 * spread + 0 * t, np.full(n, 100.0)]
        j[:, knee] = np.c_[j[:, hip, 0] + sign * swing / 2, np.full(n, 125.0)]
        j[:, ankle] = np.c_[j[:, hip, 0] + sign * swing, np.full(n, 150.0)]
    return j


def _swapped(j, frames):
    out = j.copy()
    out[np.ix_(frames, LEFT_LEG + RIGHT_LEG)] = j[np.ix_(frames, RIGHT_LEG + LEFT_LEG)]
    return out


@pytest.mark.parametrize("linked", [False, True])
def test_a_single_frame_leg_swap_is_outvoted_by_its_neighbours(linked):
    truth = _walk()
    planted = _swapped(truth, [17])
    swaps = label_path(planted, np.full(len(truth), 100.0), np.full(len(truth), linked))
    assert np.flatnonzero(swaps["legs"]).tolist() == [17]
    assert not swaps["arms"].any()
    arrays = {"joints": planted, "angles": np.zeros((len(truth), 10))}
    relabel(arrays, swaps)
    np.testing.assert_array_equal(arrays["joints"], truth)


def test_labels_swapped_from_a_fresh_fit_on_follow_the_frames_before():
    truth = _walk()
    planted = _swapped(truth, list(range(25, 40)))
    linked = np.ones(40, bool)
    linked[[0, 25]] = False  # a fresh fit took over at frame 25, tracked from there
    swaps = label_path(planted, np.full(40, 100.0), linked)
    assert np.flatnonzero(swaps["legs"]).tolist() == list(range(25, 40))


def test_legs_crossing_in_a_side_view_keep_their_tracked_labels():
    # side view: the legs pass each other every half cycle; at those frames the
    # swapped labels are as close as the tracked ones, and the track's link stands
    truth = _walk(spread=0.0)
    swaps = label_path(truth, np.full(40, 100.0), np.ones(40, bool))
    assert not swaps["legs"].any()
    knee = JOINT_INDEX["l_knee"]
    assert np.ptp(truth[:, knee, 0]) > 10  # the legs did swing past each other


def _side_view_legs(n: int, knee_dx: float) -> np.ndarray:
    """(n, 15, 2) joints: a body seen from the side with both knees bent, the shins
    turning back towards ``-knee_dx`` (pixels, y down)."""
    j = np.zeros((n, 15, 2))
    for s in "lr":
        j[:, JOINT_INDEX[f"{s}_hip"]] = (100.0, 100.0)
        j[:, JOINT_INDEX[f"{s}_knee"]] = (100.0 + knee_dx, 140.0)
        j[:, JOINT_INDEX[f"{s}_ankle"]] = (100.0, 180.0)
    return j


def test_elbows_bend_against_the_knees_in_a_side_view_only():
    from vidcap.video.fit.temporal import elbow_bend_signs, turn

    # knees forward at +x: thigh down-right, shin down-left = a clockwise turn (y up)
    j = _side_view_legs(8, 15.0)
    knee = turn(j[0, JOINT_INDEX["l_knee"]] - j[0, JOINT_INDEX["l_hip"]],
                j[0, JOINT_INDEX["l_ankle"]] - j[0, JOINT_INDEX["l_knee"]])
    assert knee < 0
    spread = np.array([0.1] * 6 + [0.9, np.nan])
    signs = elbow_bend_signs(j, spread)
    assert signs.tolist() == [1.0] * 6 + [0.0, 0.0]  # elbows counter-clockwise; front: 0
    assert elbow_bend_signs(_side_view_legs(8, -15.0), spread)[0] == -1.0  # mirrored
    assert not elbow_bend_signs(_side_view_legs(8, 2.0), spread).any()  # straight legs
    assert not elbow_bend_signs(_side_view_legs(4, 15.0), spread[:4]).any()  # too few


def test_the_arm_solve_prefers_the_elbow_bent_the_way_the_body_faces():
    from vidcap.video.fit.temporal import arm_path

    n = 6
    joints = _side_view_legs(n, 15.0)  # facing +x: elbows bend counter-clockwise
    sh, ie, iw = (JOINT_INDEX[f"l_{k}"] for k in ("shoulder", "elbow", "wrist"))
    joints[:, sh] = (100.0, 40.0)
    joints[:, ie] = (100.0, 70.0)  # upper arm hanging
    forward, back = np.array([125.0, 85.0]), np.array([75.0, 85.0])  # forearm 60 deg
    joints[:, iw] = back  # the fit bent it backwards (inside the torso: a tie)
    cands = [{"l": (np.array([joints[f, ie]] * 2), np.array([back, forward]),
                    np.array([0.0, 0.001]))} for f in range(n)]
    spread = np.full(n, 0.1)
    from vidcap.video.fit.temporal import elbow_bend_signs

    sign = elbow_bend_signs(joints, spread)
    _, wrist = arm_path(joints, np.full(n, 175.0), cands, bend_sign=sign)["l"]
    np.testing.assert_allclose(wrist, np.tile(forward, (n, 1)))
    _, wrist = arm_path(joints, np.full(n, 175.0), cands)["l"]  # without: as fitted
    np.testing.assert_allclose(wrist, np.tile(back, (n, 1)))
    # a backward bend the image clearly prefers (0.5 of S) stays
    cands = [{"l": (c["l"][0], c["l"][1], np.array([0.0, 0.5]))} for c in cands]
    _, wrist = arm_path(joints, np.full(n, 175.0), cands, bend_sign=sign)["l"]
    np.testing.assert_allclose(wrist, np.tile(back, (n, 1)))
