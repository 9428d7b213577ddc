"""The face cue (vidcap.video.facecue) and how propose_front weighs it against the arms.

Known answers: the cascade finds no face on renders of the cylinder model (no faces),
so with the face read the proposal is the arms' alone; a face found over a window says
front whatever a weaker or contrary arm cue says; a face not found says nothing; the
boxes searched sit on the fitted head and scale with it.
"""

from __future__ import annotations

import numpy as np

from tests.test_frontback import _walk
from vidcap.body import JOINT_INDEX
from vidcap.video.facecue import face_seen, head_boxes, read_bounds, search_frames
from vidcap.video.frontback import arm_visibility, near_side
from vidcap.video.proposals import face_front, propose_front


def _faces(F: int, found) -> np.ndarray:
    """A face_seen-like (F,) array searched every 5th frame, ``found`` at those listed."""
    out = np.full(F, np.nan)
    out[::5] = 0.0
    out[list(found)] = 1.0
    return out


def test_a_face_found_over_the_window_overrules_the_arms():
    F = 90
    right = np.ones(F, bool)
    arms_back = np.full(F, -0.2)  # the arm cue says turned away, clearly
    faces = _faces(F, range(0, F, 5))  # a face in every frame searched
    assert (propose_front(arms_back, right, fps=30.0) == -1).all()
    assert (propose_front(np.c_[arms_back, faces], right, fps=30.0) == 1).all()


def test_no_face_found_is_no_evidence():
    F = 90
    right = np.ones(F, bool)
    none_found = _faces(F, ())
    for arms in (np.full(F, -0.2), np.full(F, 0.2), np.zeros(F)):
        np.testing.assert_array_equal(propose_front(np.c_[arms, none_found], right, fps=30.0),
                                      propose_front(arms, right, fps=30.0))


def test_a_face_decides_its_window_only_where_the_arms_say_nothing():
    F = 150
    faces = _faces(F, (0, 5, 10))  # a face at the start, then the head turns away
    out = propose_front(np.c_[np.zeros(F), faces], np.ones(F, bool), fps=30.0)
    assert (out[:30] == 1).all()
    # not carried on: a profile or a face too small shows none, so the rest abstains
    assert (out[60:] == 0).all()


def test_an_arm_cue_below_the_threshold_abstains():
    F = 90
    right = np.ones(F, bool)
    weak = np.full(F, 0.02)  # the front side, but no more than a few pixels of 2D make
    assert (propose_front(weak, right, fps=30.0, min_front=0.03) == 0).all()
    assert (propose_front(weak, right, fps=30.0, min_front=0.01) == 1).all()


def test_a_single_stray_detection_does_not_decide():
    F = 120
    right = np.ones(F, bool)
    one = _faces(F, (60,))  # one false positive among 24 searches
    assert not face_front(one, 60).any()
    np.testing.assert_array_equal(propose_front(np.c_[np.full(F, -0.2), one], right, fps=30.0),
                                  np.full(F, -1))
    # two faces among many searches without one: below the share
    sparse = _faces(F, (0, 115))
    assert not face_front(sparse, 60).any()


def test_face_front_counts_faces_found_against_frames_searched():
    f = _faces(60, (20, 25, 30))
    inside = face_front(f, 30)
    assert inside[25] and not inside[0] and not inside[59]


def test_the_cascade_finds_no_face_on_renders_so_the_arms_decide_alone():
    for yaw in (60.0, 120.0):
        frames, truth = _walk(yaw)
        j2 = truth["joints2d"]
        seen = face_seen(frames, j2, fps=30.0, step_s=0.1)
        assert np.isfinite(seen).sum() >= 9  # searched, every third frame
        assert np.nansum(seen) == 0
        near = near_side(arm_visibility(frames, j2))
        right = np.ones(len(j2), bool)
        np.testing.assert_array_equal(propose_front(np.c_[near, seen], right, fps=30.0),
                                      propose_front(near, right, fps=30.0))


def test_head_boxes_sit_on_the_head_and_scale_with_it():
    j2 = np.zeros((2, 15, 2))
    j2[:, JOINT_INDEX["neck"]] = [100.0, 100.0]
    j2[0, JOINT_INDEX["head_top"]] = [100.0, 80.0]
    j2[1, JOINT_INDEX["head_top"]] = [100.0, 60.0]
    box = head_boxes(j2, box_heads=2.0)
    np.testing.assert_allclose(box, [[100.0, 90.0, 20.0], [100.0, 80.0, 40.0]])
    half = head_boxes(j2)[:, 2]
    b = read_bounds(j2, (480, 640), fps=1.0, step_s=1.0)
    np.testing.assert_allclose(b[:, 1] - b[:, 0], np.floor(100 + half) - np.floor(100 - half))
    assert (b[:, 2] <= box[:, 1] - half).all() and (b[:, 3] >= box[:, 1] + half - 1).all()


def test_search_frames_are_sparse_and_a_tiny_head_is_not_searched():
    assert search_frames(10, 30.0, 0.1).nonzero()[0].tolist() == [0, 3, 6, 9]
    j2 = np.zeros((4, 15, 2))
    j2[:, JOINT_INDEX["neck"]] = [50.0, 50.0]
    j2[:, JOINT_INDEX["head_top"]] = [50.0, 45.0]  # a 5 px head
    seen = face_seen([np.zeros((100, 100, 3), np.uint8)] * 4, j2, fps=30.0)
    assert np.isnan(seen).all()
