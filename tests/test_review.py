"""The review's 3D panel follows the pose it is given."""

import numpy as np

from vidcap.body import BodyModel
from vidcap.video.review import PoseRenderer


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


def test_small_videos_are_reviewed_enlarged_by_a_whole_factor():
    from vidcap.video.review import review_frames, review_scale

    assert review_scale(144, 360) == 3
    assert review_scale(360, 360) == 1
    assert review_scale(480, 360) == 1
    assert review_scale(100, 0) == 1
    h, w = 40, 30
    frame = np.zeros((h, w, 3), np.uint8)
    frame[10, 20] = 255  # one white pixel at (x=20, y=10)
    mask = np.zeros((1, h, w), bool)
    mask[0, 5:35, 10:20] = True
    joints2d = np.full((1, 15, 2), 15.0)
    joints3d = BodyModel().rest_positions()[None]
    (img,) = review_frames([frame], mask, joints2d, joints3d, min_height=100)
    k = 3  # ceil(100 / 40)
    assert img.shape == (k * h, 3 * k * w, 3)
    # the input panel repeats every pixel k x k times, at the scaled place
    assert (img[k * 10:k * 11, k * 20:k * 21] == 255).all()
    assert img[k * 10 - 1, k * 20].max() == 0
    # the silhouette panel is the scaled mask (grey inside, dark outside)
    mid = img[:, k * w:2 * k * w]
    assert mid[k * 30, k * 12, 0] == 110 and mid[k * 30, k * 25, 0] == 25
    (same,) = review_frames([frame], mask, joints2d, joints3d, min_height=0)
    assert same.shape == (h, 3 * w, 3)


def test_filled_frames_are_framed_in_orange():
    """A frame whose pose was filled from its neighbours gets the orange border on the
    silhouette panel; a fitted one does not."""
    from vidcap.video.review import review_frames

    h, w = 120, 90
    frames = [np.zeros((h, w, 3), np.uint8)] * 2
    masks = np.zeros((2, h, w), bool)
    masks[0, 20:100, 35:55] = True
    joints2d = np.full((2, 15, 2), 45.0)
    joints3d = np.repeat(BodyModel().rest_positions()[None], 2, axis=0)
    fitted, filled = review_frames(frames, masks, joints2d, joints3d, min_height=0,
                                   filled=np.array([False, True]))
    orange = np.array([0, 165, 255])
    assert (filled[h // 2, w] == orange).all()  # left edge of the middle panel
    assert not (fitted[h // 2, w] == orange).all()


def test_tall_videos_are_reviewed_shrunk():
    """A frame taller than max_height is shown shrunk (area averaging), silhouette and
    2D model with it, so a 4K video does not give an 11520 px wide review."""
    from vidcap.video.review import review_frames

    h, w = 800, 600
    frame = np.zeros((h, w, 3), np.uint8)
    frame[400:, :] = 200  # bottom half bright
    mask = np.zeros((1, h, w), bool)
    mask[0, 100:700, 250:350] = True
    joints2d = np.full((1, 15, 2), 300.0)
    joints3d = BodyModel().rest_positions()[None]
    (img,) = review_frames([frame], mask, joints2d, joints3d, max_height=200)
    assert img.shape == (200, 3 * 150, 3)
    assert img[150, 20].min() == 200 and img[50, 20].max() == 0  # the input, shrunk by 4
    mid = img[:, 150:300]
    # the silhouette shrunk with it: grey at the person's place, dark beside it
    assert mid[40, 75, 0] == 110 and mid[40, 20, 0] == 25  # (rows 25-175, cols 62-87)
    (same,) = review_frames([frame], mask, joints2d, joints3d, max_height=0)
    assert same.shape == (h, 3 * w, 3)
