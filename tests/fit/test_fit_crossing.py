"""Legs passing each other in a track (vidcap.video.fit.crossing): the exchanged legs keep
their knees and ankles, the heading decides, and a three-quarter walk keeps its hips."""

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX
from vidcap.video.fit.crossing import (
    choose_crossing,
    exchange_ankles,
    exchange_knees,
    exchange_legs,
    leg_distance,
    legs_heading,
)
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.normalise import normalise_mask
from vidcap.video.fit.state import FitState
from vidcap.video.fit.torso import place_torso

LK, LA, RK, RA = (JOINT_INDEX[n] for n in ("l_knee", "l_ankle", "r_knee", "r_ankle"))
LH, RH = JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]


def _engine_and_pose(upper=(285.0, 255.0), lower=(285.0, 255.0), spread=1.0, fore=1.0):
    """An engine on a bar, and a pose on it whose legs form an X (thighs and shins
    crossing; the legs drawn at ``fore`` of their length)."""
    bar = np.zeros((160, 80), bool)
    bar[10:150, 30:50] = True
    eng0 = _MaskEngine(normalise_mask(bar), caps=False)
    st = place_torso(eng0, FitState.rest(spread=spread))
    angles = st.angles.copy()
    angles[[6, 8]] = np.deg2rad(upper)  # l, r upper leg
    angles[[7, 9]] = np.deg2rad(lower)  # l, r lower leg
    st = st.replace(angles=angles, fore=np.r_[np.ones(6), np.full(4, fore)],
                    drawn=np.ones(10, dtype=bool))
    return eng0, st


def test_exchanges_keep_the_knees_and_ankles_and_hips():
    # legs drawn short: each thigh can reach the other knee (a knee beyond a thigh's
    # length is reached as far as the thigh goes)
    eng, st = _engine_and_pose(upper=(280.0, 262.0), lower=(290.0, 250.0), fore=0.85)
    j = eng.joints(st)
    for exchange, order in ((exchange_legs, [RK, RA, LK, LA]),
                            (exchange_ankles, [LK, RA, RK, LA]),
                            (exchange_knees, [RK, LA, LK, RA])):
        x = eng.joints(exchange(eng, st))
        np.testing.assert_allclose(x[[LK, LA, RK, RA]], j[order], atol=1e-6)
        np.testing.assert_allclose(x[[LH, RH]], j[[LH, RH]], atol=1e-9)  # hips stay
        assert x.shape == (15, 2)


def test_choose_crossing_follows_the_heading_and_costs_nothing_without_a_bounce():
    # the truth: legs crossing in an X; the track bounced them (each ankle on the other
    # leg: two legs bent toward each other, the same pixels give or take the overlap)
    eng, truth = _engine_and_pose()
    drawn = eng.model(truth)
    eng = _MaskEngine(normalise_mask(drawn), caps=False)
    norm = eng.norm
    scale = norm.to_normalised(np.array([[1.0, 1.0]])) - norm.to_normalised(np.zeros((1, 2)))
    assert scale[0, 0] == pytest.approx(1.0, abs=0.35)
    _, guess = _engine_and_pose()
    guess = place_torso(eng, guess.replace(root=np.zeros(2)))
    bounced = exchange_ankles(eng, guess)
    target = eng.joints(guess)[[LK, LA, RK, RA]]
    chosen = choose_crossing(eng, bounced, target, interval=np.deg2rad(16))
    assert chosen is not bounced
    assert leg_distance(eng, chosen, target) * eng.H < 3.0  # px
    # heading where the legs are: no exchange tried, the same state back
    here = eng.joints(bounced)[[LK, LA, RK, RA]]
    assert choose_crossing(eng, bounced, here, interval=np.deg2rad(16)) is bounced
    assert choose_crossing(eng, bounced, np.full((4, 2), np.nan),
                           interval=np.deg2rad(16)) is bounced


def test_legs_heading_carries_the_last_step_on():
    before, prev = np.zeros((15, 2)), np.zeros((15, 2))
    prev[[LK, LA, RK, RA]] = [[1, 2], [3, 4], [5, 6], [7, 8]]
    out = legs_heading(prev, before)
    np.testing.assert_allclose(out, 2 * prev[[LK, LA, RK, RA]])
    assert legs_heading(prev, None) is None
    before[LK] = np.nan
    assert legs_heading(prev, before) is None


def test_a_three_quarter_walk_keeps_its_hips_where_the_legs_pass():
    # the built-in walk seen three-quarter on from behind: the knees pass in the image
    # once a step; tracked without the crossing hypothesis the legs bounce back there
    # and hang from the wrong hips for the rest of the step (tests/fit/test_fit_predict)
    from tests.fit.test_fit_predict import _hip_misses
    from vidcap.synth import make_motion, render_clip
    from vidcap.video.fit.tracking import fit_sequence

    _, truth = render_clip(make_motion("walk", n_frames=36), size=(320, 240), yaw_deg=135.0,
                           noise=0.0, rng=np.random.default_rng(0))
    crossing = fit_sequence(truth["masks"], crossing=True).joints2d
    without = fit_sequence(truth["masks"], crossing=False).joints2d
    assert _hip_misses(crossing, truth["joints2d"]) <= 2
    assert _hip_misses(without, truth["joints2d"]) >= 10
