"""Arms that only explain hair (vidcap.video.fit.headzone) on a synthetic side view."""

import cv2
import numpy as np

from vidcap.body import JOINT_INDEX
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.frame import fit_frame
from vidcap.video.fit.headzone import (
    MIN_HAIR,
    clear_head_zone,
    hair_pixels,
    head_zone,
    zone_engine,
)
from vidcap.video.fit.limits import REST_DEG
from vidcap.video.fit.normalise import normalise_mask
from vidcap.video.fit.options import FitOptions
from vidcap.video.fit.raster import draw_pose, model_dimensions, pose_joints
from vidcap.video.fit.state import FitState
from vidcap.video.fit.torso import place_torso

H = 240.0  # body height of the synthetic figure, pixels
L, R, SH, HP = model_dimensions(H)


def _side_figure_with_hair(shape=(320, 240)):
    """A side view (spread 0.1) standing with both arms hanging inside the torso's
    outline, a head of hair and a ponytail behind the head as pose2d_run.py draws
    them: (mask, joints)."""
    root = np.array([shape[1] / 2, 30.0 + (77 / 175) * H])
    j = pose_joints(root, np.deg2rad(np.array(REST_DEG, dtype=float)), np.ones(10), 0.1, L,
                    SH, HP)
    mask = draw_pose(j, R, shape, caps=False).astype(np.uint8)
    top, neck = j[JOINT_INDEX["head_top"]], j[JOINT_INDEX["neck"]]
    c = top + 0.35 * (neck - top)
    cv2.circle(mask, (int(c[0] - 0.02 * H), int(c[1])), int(0.065 * H), 1, -1)
    cv2.ellipse(mask, (int(c[0] - 0.10 * H), int(c[1])), (int(0.06 * H), int(0.035 * H)), 0, 0,
                360, 1, -1)
    return mask.astype(bool), j


def test_head_zone_is_round_the_head_above_the_neck():
    j = np.zeros((15, 2))
    j[JOINT_INDEX["neck"]] = (100.0, 100.0)
    j[JOINT_INDEX["head_top"]] = (100.0, 60.0)  # head length 40, centre (100, 80)
    points = np.array([[100.0, 80.0],   # the head's centre
                       [140.0, 70.0],   # beside the head, 41 from the centre
                       [130.0, 105.0],  # within reach of the centre but below the neck
                       [100.0, 52.0],   # 0.2 head lengths above the head top
                       [100.0, 40.0],   # 0.5 head lengths above it: out of the band
                       [170.0, 80.0]])  # 70 from the centre
    assert head_zone(j, points).tolist() == [True, True, False, True, False, False]
    assert head_zone(j, points, heads=1.0).tolist() == [True, False, False, True, False,
                                                        False]


def test_hair_is_no_arm():
    # both arms hang inside the torso's outline, where any pose of theirs covers the
    # same pixels; without the head zone one folds up into the ponytail (its wrist
    # above the neck), with it both wrists hang (the true ones 0.36 of the height below
    # the neck) and one, the one that had folded, within 3 % of the height
    mask, j = _side_figure_with_hair()
    neck_y = j[JOINT_INDEX["neck"], 1]
    norm = normalise_mask(mask, height=80)
    off = fit_frame(norm, options=FitOptions(head_zone=0.0))
    assert min(off.joints[JOINT_INDEX[f"{s}_wrist"], 1] for s in "lr") < neck_y
    on = fit_frame(norm, options=FitOptions(head_zone=1.25))
    errors = []
    for s in "lr":
        fitted = on.joints[JOINT_INDEX[f"{s}_wrist"]]
        assert fitted[1] > neck_y + 0.2 * H, s
        errors.append(min(np.linalg.norm(fitted - j[JOINT_INDEX[f"{t}_wrist"]]) for t in "lr"))
    assert min(errors) <= 0.03 * H


def test_off_by_default():
    assert FitOptions().head_zone == 0.0


def test_no_arm_in_the_zone_leaves_the_state():
    mask, _ = _side_figure_with_hair()
    eng = _MaskEngine(normalise_mask(mask, height=80), caps=False)
    st = FitState.rest(spread=0.1)
    assert clear_head_zone(eng, st) is st


def test_zone_engine_leaves_out_the_hair():
    mask, j = _side_figure_with_hair()
    eng = _MaskEngine(normalise_mask(mask, height=80), caps=False)
    st = place_torso(eng, FitState.rest(spread=0.1))
    hair = hair_pixels(eng, st)
    assert hair.sum() >= MIN_HAIR * eng.sil.sum()
    # all of it round the head: above the neck
    ys = np.nonzero(hair)[0]
    assert ys.max() < eng.joints(st)[JOINT_INDEX["neck"], 1]
    zeng = zone_engine(eng, hair)
    assert np.array_equal(zeng.sil, eng.sil & ~hair)
