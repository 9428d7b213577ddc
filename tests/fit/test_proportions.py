"""The subject's own proportions from a clip (issue 27): known answers on renders of
bodies scaled away from the seed's ratios."""

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX, SEGMENT_INDEX, body_with_proportions
from vidcap.video.fit.lengthprofile import arm_profiles, length_profiles
from vidcap.video.fit.proportions import (
    FOOT,
    ProportionEstimate,
    compose,
    estimate_proportions,
    fit_keywords,
    human_proportions,
    sample_windows,
    to_ankles,
)
from vidcap.video.fit.raster import draw_pose, model_dimensions, pose_joints

SCALED = {"legs": 1.15, "arms": 0.9, "shoulders": 1.2}


def test_length_profile_measures_clear_limbs():
    """Arms bent up beside the head and legs apart, drawn with the subject's
    proportions; a seed-proportioned model in the same pose (its ratios stretched to the
    subject's joints) reads each limb segment's own length from the outline."""
    from vidcap.body import BodyModel

    true, seed = body_with_proportions(1.0, SCALED), BodyModel(height=1.0)
    h = 200.0
    L, R, sh, hip = model_dimensions(h, true)
    angles = np.deg2rad([90, 90, 180, 90, 0, 90, 250, 265, 290, 275]).astype(float)
    joints = pose_joints(np.array([170.0, 160.0]), angles, np.ones(10), 1.0, L, sh, hip)
    mask = draw_pose(joints, R, (320, 340), caps=False)
    fore = true.segment_lengths() / seed.segment_lengths()
    spread = true.shoulder_half_width / seed.shoulder_half_width
    lengths, _ = length_profiles(mask, joints, angles, fore, spread, h)
    for seg in ("l_upper_arm", "l_lower_arm", "r_upper_arm", "r_lower_arm", "l_lower_leg",
                "r_lower_leg"):
        assert lengths[SEGMENT_INDEX[seg]] == pytest.approx(true.length(seg), rel=0.04), seg
    assert np.isnan(lengths[:2]).all()  # torso and head are not profiled


@pytest.mark.parametrize("arms_deg", [(180, 90, 0, 90), (200, 160, 340, 20), (250, 290, 290, 250)])
@pytest.mark.parametrize("scale", [1.0, 0.8, 1.15])
def test_arm_profile_reads_the_whole_arm_whatever_the_model_draws(arms_deg, scale):
    """Arms standing clear (bent up, spread, hanging out to the sides), drawn with the
    subject's proportions; a seed-proportioned model in the same pose whose arms are
    drawn at the subject's length, 20 % shorter or 15 % longer (its elbow misplaced
    with them) reads each whole arm as the subject's within 2 %; arms hanging over the
    torso in a side view read nothing."""
    from vidcap.body import BodyModel

    true, seed = body_with_proportions(1.0, SCALED), BodyModel(height=1.0)
    h = 200.0
    L, R, sh, hip = model_dimensions(h, true)
    want = ((true.length("l_upper_arm") + true.length("l_lower_arm"))
            / (seed.length("l_upper_arm") + seed.length("l_lower_arm")))
    fore = true.segment_lengths() / seed.segment_lengths()
    fore[2:6] *= scale
    for arms, spread, clear in ((arms_deg, 1.0, True), ((270, 270, 270, 270), 0.0, False)):
        angles = np.deg2rad([90, 90, *arms, 265, 290, 275, 250]).astype(float)
        joints = pose_joints(np.array([170.0, 160.0]), angles, np.ones(10), spread, L, sh,
                             hip)
        mask = draw_pose(joints, R, (320, 340), caps=False)
        sp = spread * true.shoulder_half_width / seed.shoulder_half_width
        got = arm_profiles(mask, joints, angles, fore, sp, h)
        if clear:
            np.testing.assert_allclose(got, want, rtol=0.02)
        else:
            assert np.isnan(got).all()


def test_sample_windows_avoid_empty_frames():
    masks = np.zeros((200, 20, 20), bool)
    masks[:, 5:15, 8:12] = True
    masks[95:105] = False  # a gap
    wins = sample_windows(masks, window=30, windows=3)
    assert len(wins) == 3
    for w in wins:
        assert masks[w].any(axis=(1, 2)).all() and w.stop - w.start == 30
    assert sample_windows(np.zeros((5, 8, 8), bool)) == []


def test_seed_estimate_reports_the_seed():
    est = ProportionEstimate()
    assert "(+0%)" in est.summary()
    assert est.body(1.75) == body_with_proportions(1.75)


@pytest.mark.parametrize("factors", [SCALED, {}])
def test_legs_and_shoulders_recovered_within_5_percent(factors):
    """A side-view walk of a body with known proportions: the legs' share of the
    height and the shoulders' breadth come back within 5 %."""
    from vidcap.synth import make_motion, render_clip

    truth = ProportionEstimate(factors=factors)
    body = truth.body(1.75)
    motion = make_motion("walk", body=body, n_frames=30)
    _, t = render_clip(motion, body=body, yaw_deg=90, size=(320, 240), noise=0.0,
                       rng=np.random.default_rng(0))
    est = estimate_proportions(t["masks"], searched=("legs", "shoulders"),
                               steps=((0.05, 4),))
    got, want = est.ratios(), truth.ratios()
    for group in ("upper_legs", "lower_legs", "torso", "shoulders"):
        assert got[group] == pytest.approx(want[group], rel=0.05), group
    assert np.isfinite(est.similarity).all()


@pytest.mark.parametrize("factors", [SCALED, {"legs": 0.9, "arms": 1.1, "shoulders": 0.85}])
def test_arms_recovered_within_5_percent(factors):
    """Jumping jacks seen from the front (arms raised and spread, where the search's S
    reads them ~10 % long): the arms' share of the height comes back within 5 % from
    their length profiles, for arms shorter and longer than the seed's."""
    from vidcap.synth import make_motion, render_clip

    truth = ProportionEstimate(factors=factors)
    body = truth.body(1.75)
    motion = make_motion("jacks", body=body, n_frames=30)
    _, t = render_clip(motion, body=body, yaw_deg=0, size=(320, 240), noise=0.0,
                       rng=np.random.default_rng(0))
    est = estimate_proportions(t["masks"], searched=("legs", "shoulders", "arms"),
                               steps=((0.05, 4),))
    got, want = est.ratios(), truth.ratios()
    for group in ("upper_arms", "lower_arms"):
        assert got[group] == pytest.approx(want[group], rel=0.05), group
    assert est.evidence["arms"] >= 10


def _standing_with_feet(body, foot_px: float, h: float = 200.0):
    """A standing model (legs a little apart, arms down) ``h`` px head top to ankles,
    with a foot block ``foot_px`` tall under each ankle; its true joints."""
    L, R, sh, hip = model_dimensions(h, body)
    angles = np.deg2rad([90, 90, 265, 270, 275, 270, 265, 270, 275, 270]).astype(float)
    joints = pose_joints(np.array([160.0, 40.0 + L[0] + L[1]]), angles, np.ones(10), 1.0,
                         L, sh, hip)
    mask = draw_pose(joints, R, (320, 320), caps=False)
    for name in ("l_ankle", "r_ankle"):
        x, y = joints[JOINT_INDEX[name]]
        r = R[SEGMENT_INDEX["l_lower_leg"]]
        mask[int(round(y)): int(round(y + foot_px)), int(round(x - r)): int(round(x + r))] = True
    return mask, joints


def test_the_feet_below_the_ankles_are_left_out():
    """A body drawn with feet under its ankles (6 % of its standing height): fitted
    with ``foot=0.06`` its ankles are found within 2 px; with the seed's body (ankles on
    the floor) they sit at the soles."""
    from vidcap.video.fit.tracking import fit_sequence

    body = human_proportions().body(1.0)
    foot_px = 0.06 / 0.94 * 200.0  # 6 % of head top to soles
    mask, truth = _standing_with_feet(body, foot_px)
    masks = np.repeat(mask[None], 3, axis=0)
    ankles = [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]
    with_feet = fit_sequence(masks, cues="outline", body=body, foot=0.06).joints2d[-1]
    without = fit_sequence(masks, cues="outline", body=body).joints2d[-1]
    err = np.abs(with_feet[ankles, 1] - truth[ankles, 1])
    assert err.max() < 2.0
    assert (without[ankles, 1] - truth[ankles, 1]).min() > 0.6 * foot_px  # at the soles
    knees = [JOINT_INDEX["l_knee"], JOINT_INDEX["r_knee"]]
    assert np.abs(with_feet[knees] - truth[knees]).max() < 3.0


def test_model_height_cut_to_the_ankles():
    """The 3D stage takes the model's height head top to ankles: a body with feet (6 %
    of its standing height) fitted to a figure 200 px head top to ankles gives about
    213 px to the soles and 200 px once cut; the seed's body (no ``foot``) is kept."""
    from vidcap.video.fit.tracking import fit_sequence

    body = human_proportions().body(1.0)
    mask, _ = _standing_with_feet(body, 0.06 / 0.94 * 200.0)
    fit_kw = {"body": body, "foot": 0.06}
    height = fit_sequence(np.repeat(mask[None], 3, axis=0), cues="outline",
                          **fit_kw).model_height
    assert np.abs(height / (200.0 / 0.94) - 1.0).max() < 0.03
    assert np.abs(to_ankles(height, fit_kw) / 200.0 - 1.0).max() < 0.03
    np.testing.assert_array_equal(to_ankles(height, {"body": body}), height)
    np.testing.assert_array_equal(to_ankles(height), height)


def test_human_proportions_put_the_joints_of_the_table():
    """The human body's joints standing (arms down), as fractions of the stature, are
    the anthropometric table's: the top of the shoulders 0.818 (the torso's top
    corners), elbow 0.630, wrist 0.485, knee 0.285, ankle 0.039 (the feet below the
    model); the hips at 0.500 (chosen on real clips); the shoulder joints, where the
    arms turn, 0.022 below the top of the shoulders (0.796)."""
    est = human_proportions()
    assert est.foot == pytest.approx(0.039)
    body = est.body(1.0)  # stature 1: head top to ankles 0.961
    assert body.standing_height == pytest.approx(0.961)
    top = 1.0
    shoulder = top - body.length("head")
    assert shoulder == pytest.approx(0.818, abs=1e-3)
    joint = shoulder - body.shoulder_drop
    assert joint == pytest.approx(0.796, abs=1e-3)
    assert joint - body.length("l_upper_arm") == pytest.approx(0.630, abs=1e-3)
    assert joint - body.length("l_upper_arm") - body.length("l_lower_arm") \
        == pytest.approx(0.485, abs=1e-3)
    # the rest pose (arms out) puts the shoulder joints there too, 1 m tall
    rest = body.rest_positions() / body.standing_height * 0.961 + [0, 0.039, 0]
    assert rest[JOINT_INDEX["l_shoulder"], 1] == pytest.approx(0.796, abs=1e-3)
    hip = shoulder - body.length("torso")
    assert hip == pytest.approx(0.500, abs=1e-3)
    assert hip - body.length("l_upper_leg") == pytest.approx(0.285, abs=1e-3)
    assert hip - body.length("l_upper_leg") - body.length("l_lower_leg") \
        == pytest.approx(0.039, abs=1e-3)
    assert "above feet" not in est.summary()


def test_foot_option_checked():
    from vidcap.video.fit.options import FitOptions

    with pytest.raises(ValueError, match="foot"):
        FitOptions(foot=0.5)
    with pytest.raises(ValueError, match="foot"):
        FitOptions(foot=-0.1)
    assert fit_keywords({"legs": 1.1})["body"].custom and "foot" not in fit_keywords({})
    assert fit_keywords({FOOT: 0.95})["foot"] == pytest.approx(0.05)


def test_rows_below_the_image_are_none():
    """A search's rows starting below the normalised image (a pelvis placed under a tiny
    silhouette's bottom) are empty, not an index past the row table."""
    from vidcap.video.fit.engine import _MaskEngine
    from vidcap.video.fit.normalise import normalise_mask

    mask = np.zeros((40, 40), bool)
    mask[10:30, 15:25] = True
    eng = _MaskEngine(normalise_mask(mask, height=20), caps=False)
    assert eng.rows((eng.h + 5, eng.h + 50)) == (eng.h, eng.h)
    assert eng.pixels(*eng.rows((eng.h + 5, eng.h + 50))) == 0
    assert eng.rows((-3, 4)) == (0, 4)
    assert eng.pixels(*eng.rows(None)) == int(eng.sil.sum())


def test_proportions_stage_with_fixed_human_body(tmp_path):
    """The pipeline's proportions stage with ``fixed`` proportions: no estimate, the clip
    fitted with them, the pose's model height the model's (the feet left out), cached."""
    from vidcap.synth import make_motion, render_clip
    from vidcap.video.bodystage import proportions_stage
    from vidcap.video.fit.ensemble import fit_ensemble
    from vidcap.video.fit.tracking import fit_sequence
    from vidcap.video.stagecache import StageCache

    motion = make_motion("walk", n_frames=6)
    _, t = render_clip(motion, yaw_deg=90, size=(160, 120), noise=0.0,
                       rng=np.random.default_rng(0))
    cache = StageCache(tmp_path)
    human = human_proportions()
    pose, est = proportions_stage(cache, "k", t["masks"], jobs=1, per_job=1, progress=False,
                                  fixed=human)
    assert est.factors == human.factors
    direct = fit_sequence(t["masks"], **fit_keywords(human.factors))
    np.testing.assert_allclose(pose["joints2d"], direct.joints2d)
    np.testing.assert_allclose(pose["model_height"], direct.model_height * 0.961)
    again, est2 = proportions_stage(cache, "k", t["masks"], jobs=1, per_job=1,
                                    progress=False, fixed=human)
    assert est2.factors == pytest.approx(human.factors)
    np.testing.assert_allclose(again["joints2d"], pose["joints2d"])
    # an ensemble of fits (vidcap convert --ensemble) is its own entry, not the one fit's
    two, _ = proportions_stage(cache, "k", t["masks"], jobs=1, per_job=1, progress=False,
                               fixed=human, ensemble=2)
    assert len(list(tmp_path.glob("proportions-*.npz"))) == 2
    np.testing.assert_allclose(two["joints2d"], fit_ensemble(
        t["masks"], ensemble=2, **fit_keywords(human.factors)).joints2d)
    # --seated: the fit with the proportions probes the seated scale too, its own entry
    seated, _ = proportions_stage(cache, "k", t["masks"], jobs=1, per_job=1,
                                  progress=False, fixed=human, seated=True)
    assert len(list(tmp_path.glob("proportions-*.npz"))) == 3
    np.testing.assert_allclose(seated["joints2d"], fit_sequence(
        t["masks"], low_body=True, **fit_keywords(human.factors)).joints2d)


def test_proportions_stage_hands_the_seated_probe_to_its_fit(tmp_path, monkeypatch):
    """``vidcap convert --proportions auto --seated``: the refit with the estimate gets
    ``low_body`` as the first fit did (it used to be dropped there)."""
    import vidcap.video.fit.parallel as parallel
    from vidcap.video.bodystage import proportions_stage
    from vidcap.video.stagecache import StageCache

    seen = []

    class _Pose:
        joints2d = scores = spread = similarity = model_height = np.zeros((2, 15, 2))

    def fake(masks, **kw):
        seen.append(kw.get("low_body", False))
        return _Pose()

    monkeypatch.setattr(parallel, "fit_sequence_chunked", fake)
    masks = np.zeros((2, 8, 8), bool)
    for seated in (False, True):
        proportions_stage(StageCache(tmp_path / str(seated)), "k", masks, jobs=1, per_job=1,
                          progress=False, fixed=human_proportions(), seated=seated)
    assert seen == [False, True]


def test_compose_multiplies_groups_and_resolves_aliases():
    base = {"legs": 0.8, "upper_arms": 1.3, FOOT: 0.96}
    out = compose(base, {"legs": 1.1, "arms": 0.5, "upper_legs": 2.0, "shoulders": 1.2})
    assert out == pytest.approx({"upper_legs": 1.6, "lower_legs": 0.88, "upper_arms": 0.65,
                                 "lower_arms": 0.5, "shoulders": 1.2, FOOT: 0.96})
    assert compose(None, {"legs": 1.1}) == {"legs": 1.1}
