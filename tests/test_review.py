"""The review's 3D panel follows the pose it is given."""

import numpy as np

from vidcap.body import BodyModel
from vidcap.review import PoseRenderer


def test_pose_renderer_draws_each_new_pose():
    rest = BodyModel().rest_positions()
    moved = rest.copy()
    moved[[4, 5]] = rest[3] + np.array([[0.0, -0.25, 0.0], [0.0, -0.6, 0.0]])  # left arm down
    renderer = PoseRenderer((160, 120))
    try:
        first = renderer.render(rest).astype(int)
        second = renderer.render(moved).astype(int)
        again = renderer.render(rest).astype(int)
    finally:
        renderer.close()
    assert np.abs(first - second).mean() > 0.5  # a different pose, a different image
    assert np.abs(first - again).mean() < 0.05  # the same pose, the same image
