"""A thigh pointing at the camera in a crouch (issue 27 item 4): drawn at 45 % of its
length, it is found by :func:`vidcap.video.fit.fold.fold_thighs` on a synthetic
silhouette with a known answer, and an upright figure is left as it is."""

import numpy as np

from vidcap.body import JOINT_INDEX, SEGMENT_INDEX
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.fold import crouching, fold_thighs
from vidcap.video.fit.normalise import normalise_mask
from vidcap.video.fit.raster import draw_pose, model_dimensions, pose_joints
from vidcap.video.fit.state import FitState

H = 240.0  # the figures' standing height, pixels
L, R, SH, HP = model_dimensions(H)
UP, LO = SEGMENT_INDEX["r_upper_leg"], SEGMENT_INDEX["r_lower_leg"]
KNEE = JOINT_INDEX["r_knee"]


def _figure(angles_deg, fore, shape=(320, 260)):
    root = np.array([shape[1] / 2, 30.0 + (77 / 175) * H])
    j = pose_joints(root, np.deg2rad(angles_deg), fore, 0.0, L, SH, HP)
    return draw_pose(j, R, shape, caps=False), j


def _engine_and_start(mask, joints, angles_deg, fore):
    """The engine on ``mask`` at the body's standing height (as a clip's body-height
    pass gives it), and the true pose in normalised pixels."""
    norm = normalise_mask(mask, height=80, body_height=H)
    eng = _MaskEngine(norm, caps=False)
    root = norm.to_normalised(joints[JOINT_INDEX["pelvis"]][None])[0]
    st = FitState.rest().replace(root=root, angles=np.deg2rad(np.asarray(angles_deg, float)),
                                 fore=np.asarray(fore, float), drawn=np.ones(10, bool))
    return norm, eng, st


# a crouch: left thigh forward (200 deg), right thigh toward the camera down-right
# (330 deg at 45 % of its length), both shins straight down
CROUCH = [90, 90, 270, 270, 270, 270, 200, 270, 330, 270]
CROUCH_FORE = np.array([1, 1, 1, 1, 1, 1, 1, 1, 0.45, 1])


def test_folded_thigh_found():
    mask, j = _figure(CROUCH, CROUCH_FORE)
    norm, eng, true = _engine_and_start(mask, j, CROUCH, CROUCH_FORE)
    assert crouching(eng)
    # a fit's leg: the thigh at its full length, where the outline lets it lie
    # (along the shin), the shin hung from its far knee
    wrong = true.with_entries(fore=(UP, 1.0), angles=([UP, LO], np.deg2rad([282.0, 300.0])))
    knee_true = norm.to_original(eng.joints(true))[KNEE]
    before = np.linalg.norm(norm.to_original(eng.joints(wrong))[KNEE] - knee_true)
    out = fold_thighs(eng, wrong, tie=0.01)
    after = np.linalg.norm(norm.to_original(eng.joints(out))[KNEE] - knee_true)
    # pixels of the 240 px figure: the full-length thigh puts the knee 49 px off, the
    # folded one 23 px (the outline of a short thigh and a shin under it is matched
    # about as well by a shorter thigh and a slanted shin: S 0.749 against the
    # truth's 0.748)
    assert before > 40.0
    assert after < 0.5 * before
    assert out.fore[UP] < 0.6
    assert eng.similarity(out) > eng.similarity(wrong) + 0.03


def test_upright_figure_not_folded():
    stand = [90, 90, 270, 270, 270, 270, 265, 270, 275, 270]
    mask, j = _figure(stand, np.ones(10))
    _, eng, st = _engine_and_start(mask, j, stand, np.ones(10))
    assert not crouching(eng)
    out = fold_thighs(eng, st, tie=0.01)
    np.testing.assert_array_equal(out.fore, st.fore)
    np.testing.assert_array_equal(out.angles, st.angles)
