"""Both arms searched together (vidcap.video.fit.armpairs) on synthetic three-quarter figures."""

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX, SEGMENT_INDEX
from vidcap.video.fit.armpairs import search_arm_pairs
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.limits import REST_DEG
from vidcap.video.fit.normalise import normalise_mask
from vidcap.video.fit.pose2d import fit_pose
from vidcap.video.fit.raster import draw_pose, model_dimensions, pose_joints
from vidcap.video.fit.state import FitState

H = 240.0  # body height of the synthetic figures, pixels
L, R, SH, HP = model_dimensions(H)


def _figure(arms_deg, spread, shape=(320, 240)):
    """A standing figure, its image-left arm at ``arms_deg[:2]`` and its image-right
    one at ``arms_deg[2:]`` (upper, lower; degrees), the rest hanging: (mask, joints)."""
    a = np.array(REST_DEG, dtype=float)
    for name, v in zip(("l_upper_arm", "l_lower_arm", "r_upper_arm", "r_lower_arm"), arms_deg,
                       strict=True):
        a[SEGMENT_INDEX[name]] = v
    root = np.array([shape[1] / 2, 30.0 + (77 / 175) * H])
    j = pose_joints(root, np.deg2rad(a), np.ones(10), spread, L, SH, HP)
    return draw_pose(j, R, shape, caps=False), j


def _err(fp, j, name):
    return float(np.linalg.norm(fp.joints[JOINT_INDEX[name]] - j[JOINT_INDEX[name]]))


def test_near_arm_takes_its_own_elbow_the_far_arm_hangs():
    # a three-quarter view: the near (image-left) arm swung forward, its elbow out past
    # the chest and its forearm raised; the far arm hangs inside the torso's outline.
    # Arm by arm, the far arm folded across the chest to the near elbow scores as well
    # (its wrist was 38 % of the height off); searched in pairs, each arm is its own
    mask, j = _figure((240, 180, 275, 275), spread=0.6)
    fp = fit_pose(mask)
    tol = 0.03 * H
    for name in ("l_elbow", "l_wrist", "r_elbow", "r_wrist"):
        assert _err(fp, j, name) <= tol, name


def test_arm_seen_across_the_torso_is_kept():
    # the prior acts only where the silhouette cannot see an arm: a forearm reaching
    # past the torso's far edge stays where the silhouette shows it
    mask, j = _figure((300, 340, 270, 270), spread=0.7)
    fp = fit_pose(mask)
    assert _err(fp, j, "l_wrist") <= 0.03 * H


@pytest.mark.parametrize("prior_px", [0.0, 15.0, 40.0])
def test_pairs_keep_a_visible_arm(prior_px):
    # started from the true pose, the pair search leaves the near arm, which the
    # silhouette shows outside the torso, where it is, whatever the prior's weight
    mask, j = _figure((235, 200, 270, 270), spread=0.7)
    norm = normalise_mask(mask, height=80)
    eng = _MaskEngine(norm, caps=False)
    a = np.array(REST_DEG, dtype=float)
    a[[SEGMENT_INDEX[n] for n in ("l_upper_arm", "l_lower_arm")]] = (235, 200)
    st = FitState(norm.to_normalised(j[JOINT_INDEX["pelvis"]]), np.deg2rad(a), np.ones(10),
                  0.7, np.zeros(10), np.zeros(10), np.ones(10, dtype=bool))
    out = search_arm_pairs(eng, st, prior_px=prior_px)
    moved = eng.joints(out)[JOINT_INDEX["l_wrist"]] - eng.joints(st)[JOINT_INDEX["l_wrist"]]
    assert np.linalg.norm(moved) <= 0.03 * 80


def test_angle_gap_wraps_to_half_a_turn():
    from vidcap.video.fit.limits import angle_gap

    a = np.array([0.1, 3.0, -3.0, 2 * np.pi + 0.5])
    b = np.array([2 * np.pi - 0.1, -3.0, 3.0, 0.25])
    want = np.abs(np.angle(np.exp(1j * (a - b))))
    np.testing.assert_allclose(angle_gap(a, b), want, atol=1e-12)
    np.testing.assert_allclose(angle_gap(a, b), [0.2, 2 * np.pi - 6.0, 2 * np.pi - 6.0, 0.25],
                               atol=1e-12)


def test_apart_on_the_orders_prefix_picks_what_the_whole_grid_picks():
    # the pair search reads only the first top * 25 + 1 of a grid's order: each pick
    # puts at most its 5 x 5 neighbours out of the running, so the picks are the same
    from vidcap.video.fit.armpairs import _apart
    from vidcap.video.fit.grids import pair_grid

    ua, la = pair_grid(15.0)[:2]
    rng = np.random.default_rng(0)
    for _ in range(20):
        order = rng.permutation(len(ua))
        full = _apart(ua[order], la[order], 6, 15.0)
        head = _apart(ua[order[:151]], la[order[:151]], 6, 15.0)
        assert head == full and len(full) == 6
    # clustered orders (the best pairs next to each other, as real scores are) too
    centre = np.argmin(np.abs(ua - np.pi) + np.abs(la - np.pi))
    near = np.argsort(np.abs(np.angle(np.exp(1j * (ua - ua[centre]))))
                      + np.abs(np.angle(np.exp(1j * (la - la[centre])))), kind="stable")
    assert _apart(ua[near[:151]], la[near[:151]], 6, 15.0) == _apart(ua[near], la[near], 6, 15.0)
