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
