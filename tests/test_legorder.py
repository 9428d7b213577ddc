"""Which leg is nearer the camera, from the colour frame (vidcap.video.legorder).

Known answers: two shaded bars, one drawn over the other, are told apart by which one's
borders cross the other; a rendered side-view walk whose 2D names are the wrong way
round (as the 2D fit often has them) is named right through the 3D stage.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX, BodyModel
from vidcap.video.legorder import (
    frame_limb_edges,
    limb_edges,
    limb_radii,
    near_limb,
    side_limb_names,
)

R = 10.0  # the bars' radius, px


def _bar(img, zbuf, a, b, depth, colour, R=R):
    """Draw a shaded band of radius ``R`` about a -> b into ``img`` (H, W, 3) where it is
    nearer than ``zbuf``: a cylinder's shading, brighter toward its middle."""
    H, W = zbuf.shape
    y, x = np.mgrid[0:H, 0:W].astype(float)
    d = np.subtract(b, a, dtype=float)
    L = np.hypot(*d)
    u = d / L
    along = (x - a[0]) * u[0] + (y - a[1]) * u[1]
    across = (x - a[0]) * u[1] - (y - a[1]) * u[0]
    on = (np.abs(across) < R) & (along >= 0) & (along <= L) & (depth > zbuf)
    shade = np.sqrt(np.clip(1 - (across / R) ** 2, 0, 1))
    img[on] = (np.asarray(colour)[None] * (0.35 + 0.65 * shade[on, None])).astype(np.uint8)
    zbuf[on] = depth


def _crossed_legs(l_in_front: bool):
    """A frame with two crossing legs of the same colour and the 2D joints naming the
    vertical one ``l_`` and the slanted one ``r_``."""
    H, W = 240, 200
    img = np.full((H, W, 3), 200, np.uint8)
    zbuf = np.full((H, W), -np.inf)
    j = np.full((15, 2), np.nan)
    legs = {"l": ((100, 20), (100, 120), (100, 220)), "r": ((50, 20), (100, 120), (150, 220))}
    for side, (hip, knee, ankle) in legs.items():
        j[JOINT_INDEX[f"{side}_hip"]] = hip
        j[JOINT_INDEX[f"{side}_knee"]] = knee
        j[JOINT_INDEX[f"{side}_ankle"]] = ankle
    depth = {"l": 1.0 if l_in_front else 0.0, "r": 0.0 if l_in_front else 1.0}
    for side in sorted(legs, key=lambda s: depth[s]):  # the farther first
        hip, _, ankle = legs[side]
        _bar(img, zbuf, hip, ankle, depth[side], (90, 50, 30))
    return img, j


@pytest.mark.parametrize("l_in_front", [True, False])
def test_the_leg_whose_borders_cross_the_other_is_the_near_one(l_in_front):
    img, j = _crossed_legs(l_in_front)
    strength, count = frame_limb_edges(img, j, np.full(5, R))
    assert (count[1] > 0).all()
    assert (count[0] == 0).all()  # no torso, no arms
    order = near_limb(strength, count)[1]
    assert order > 0.5 if l_in_front else order < -0.5


def test_an_arm_in_front_of_the_torso_shows_its_borders_across_it():
    img = np.full((240, 200, 3), 200, np.uint8)
    zbuf = np.full((240, 200), -np.inf)
    j = np.full((15, 2), np.nan)
    j[JOINT_INDEX["pelvis"]], j[JOINT_INDEX["neck"]] = (100, 200), (100, 40)
    # the l arm hangs in front of the torso, the r arm behind it (the fit puts both there)
    for side, dx in (("l", -1.0), ("r", 1.0)):
        for k, name in enumerate(("shoulder", "elbow", "wrist")):
            j[JOINT_INDEX[f"{side}_{name}"]] = (100 + dx * (6 + 8 * k), 50 + 60 * k)
    arm = j[[JOINT_INDEX[f"{s}_{n}"] for s in "lr" for n in ("shoulder", "wrist")]]
    shirt = (40, 45, 190)
    _bar(img, zbuf, arm[2], arm[3], 0.0, shirt, R=0.5 * R)
    _bar(img, zbuf, (100, 40), (100, 200), 0.5, shirt, R=3 * R)  # the torso
    _bar(img, zbuf, arm[0], arm[1], 1.0, shirt, R=0.5 * R)
    strength, count = frame_limb_edges(img, j, np.array([0.5, 0.5, 3, 1, 1]) * R)
    assert near_limb(strength, count, min_count=1)[0] > 0.5


def test_legs_apart_give_no_score():
    img = np.full((240, 200, 3), 200, np.uint8)
    j = np.zeros((15, 2))
    for side, x in (("l", 40.0), ("r", 160.0)):
        for k, name in enumerate(("hip", "knee", "ankle")):
            j[JOINT_INDEX[f"{side}_{name}"]] = [x, 20.0 + 100 * k]
    s, n = limb_edges([img, None], np.stack([j, j]), np.full((2, 5), R))
    assert np.isnan(near_limb(s, n)).all()


def test_side_limb_names_name_the_near_track_the_side_the_body_turns_to_the_camera():
    F = 10
    order = np.full(F, 0.5)  # the fit's l leg nearer throughout
    edge = np.ones(F, bool)
    link = np.zeros(F, bool)
    # facing image right, the right leg is the near one: the fit's l is the right leg
    assert side_limb_names(order, edge, np.ones(F, bool), link).all()
    assert not side_limb_names(order, edge, np.zeros(F, bool), link).any()
    # the fit's names jump for frames 4-6 (linked back): the cue there reads the other
    # leg's, and the run is still named as one
    jumped = order.copy()
    jumped[4:7] *= -1
    link[4:7] = True
    out = side_limb_names(jumped, edge, np.ones(F, bool), link)
    assert out[:4].all() and not out[4:7].any() and out[7:].all()
    # too little evidence: the fit's names stay
    sparse = np.full(F, np.nan)
    sparse[:3] = 0.5
    assert not side_limb_names(sparse, edge, np.ones(F, bool), np.zeros(F, bool)).any()
    # frames outside the runs are left alone
    assert not side_limb_names(order, np.zeros(F, bool), np.ones(F, bool), link).any()


def _crossing_arms(F=20):
    """(F, 15, 2) joints whose two forearms pass through each other at frame 10 at a
    constant velocity (no acceleration as named), the rest still."""
    j = np.zeros((F, 15, 2))
    j[:, :, 0] = 100.0 + np.arange(15) * 3.0
    j[:, :, 1] = 50.0
    t = np.arange(F) - 10.0
    for side, sign in (("l", 1.0), ("r", -1.0)):
        for k, name in enumerate(("elbow", "wrist")):
            j[:, JOINT_INDEX[f"{side}_{name}"]] = np.stack(
                [100.0 + sign * 4.0 * t, np.full(F, 80.0 + 20.0 * k)], -1)
    return j


def test_arms_named_frame_by_frame_where_the_cue_outweighs_a_smooth_crossing():
    from vidcap.video.lifting import cued_links

    F = 20
    j2 = _crossing_arms(F)
    order = np.full((F, 2), np.nan)  # the legs: no cue
    order[:10, 0], order[10:, 0] = -0.5, 0.5  # the fit's r arm near, then its l arm
    edge, right, swap = np.ones(F, bool), np.ones(F, bool), np.zeros(F, bool)
    # facing right the near arm is the right one: the fit's names hold to frame 9, from
    # frame 10 its l arm is the right one (a bounce in 2D, outweighed by 10 cued frames)
    out = cued_links(j2, 1.0, order, edge, right, swap)
    assert not out[:10, 0].any() and out[10:, 0].all()
    assert not out[:, 1].any()
    # a weak cue does not outweigh the crossing's smoothness: the names stay (but at
    # frame 10, where both namings are the same points)
    weak = cued_links(j2, 1.0, 0.05 * np.sign(order), edge, right, swap)
    assert not np.delete(weak[:, 0], 10).any()
    # facing left, or outside the edge frames, the cue reads the other way / not at all
    left = cued_links(j2, 1.0, order, edge, ~right, swap)
    assert left[:10, 0].all() and not left[10:, 0].any()
    assert not cued_links(j2, 1.0, order, ~edge, right, swap).any()



def test_turned_frames_names_three_quarter_frames_as_side_ones():
    from vidcap.video.lifting import near_limb_names

    F = 12
    j2 = np.zeros((F, 15, 2))
    j2[:, :, 0] = 100.0 + np.arange(15) * 3.0  # still joints: the linking keeps the names
    j2[:, :, 1] = 50.0 + np.arange(15) * 7.0
    order = np.full((F, 2), np.nan)
    order[:, 1] = 0.5  # the fit's l leg nearer throughout
    # a body facing front-right, turned 53 degrees (spread 0.6), then nearly frontal
    # (spread 0.95)
    orient = np.full(F, "front_right")
    rho = np.r_[np.full(6, 0.6), np.full(6, 0.95)]
    user = np.full(F, "")

    def named(frames):
        out = near_limb_names(j2, order, orient, user, rho, 1.0, frames=frames)
        return np.zeros((F, 2), bool) if out is None else out

    # 'side' names only side labels: none here
    assert not named("side").any()
    # 'turned' names the turned frames: facing image right its right leg is the near one,
    # and facing the camera the image-side names swap (the fit's l is the body's right
    # already), so the fit's names stay there: no exchange; the frontal frames are left
    # alone either way
    assert not named("turned").any()
    flipped = order.copy()
    flipped[:, 1] = -0.5  # the fit's r leg nearer: named the other way in turned frames
    out = near_limb_names(j2, flipped, orient, user, rho, 1.0, frames="turned")
    assert out is not None and out[:6, 1].all() and not out[6:].any()

@functools.cache
def _side_walk():
    from vidcap.synth import make_motion, render_clip

    m = make_motion("walk", body=BodyModel(), fps=30.0, n_frames=40,
                    rng=np.random.default_rng(0))
    return render_clip(m, yaw_deg=90.0, size=(320, 240), noise=0.0,
                       rng=np.random.default_rng(0))


def test_a_side_view_walk_named_the_wrong_way_round_is_named_right():
    from vidcap.video.lift import swap_sides
    from vidcap.video.lifting import lift_pose

    frames, truth = _side_walk()
    body = BodyModel()
    true2 = truth["joints2d"]
    wrong = swap_sides(true2)  # every limb named the wrong way round
    height = np.full(len(wrong), float(np.linalg.norm(truth["camera"][0, :3])) * body.height)
    order = near_limb(*limb_edges(frames, wrong, limb_radii(height, body)))
    assert (np.isfinite(order).sum(0) >= 10).all()
    args = dict(fps=30.0, body=body, image_sides=True, frame_size=(320, 240),
                model_height=height, method="segment")
    limbs = [JOINT_INDEX[f"{s}_{n}"] for s in "lr" for n in ("knee", "ankle", "elbow", "wrist")]
    as_fit = lift_pose(wrong, **args)
    named = lift_pose(wrong, limb_order=order, **args)
    assert np.allclose(as_fit.joints2d[:, limbs], wrong[:, limbs])  # a side view keeps names
    # named as the truth, but where the arms pass each other (frame 12: 1 px apart, a
    # weak cue there), where either naming is the same points
    assert np.abs(named.joints2d[:, limbs] - true2[:, limbs]).max() < 2.0


def test_colour_cues_read_both_cues_in_one_pass_over_the_frames():
    from vidcap.video.pipeline import colour_cues

    frames, truth = _side_walk()
    body = BodyModel()
    j2 = truth["joints2d"]
    height = np.full(len(j2), float(np.linalg.norm(truth["camera"][0, :3])) * body.height)
    seen = []

    def decoded():
        for f in list(frames) + [frames[0]]:  # one frame more than there are joints
            seen.append(1)
            yield f

    near, order = colour_cues(decoded(), j2, height, body, front=True, limbs=True)
    assert len(seen) == len(j2) + 1  # consumed to the end
    # the front/back cue with the face (vidcap.video.facecue): none on a render
    assert near.shape == (len(j2), 2) and order.shape == (len(j2), 2)
    assert np.isfinite(near[:, 1]).any() and np.nansum(near[:, 1]) == 0
    assert colour_cues(iter(frames), j2, height, body, front=True, limbs=False,
                       face=False)[0].shape == (len(j2),)
    alone = near_limb(*limb_edges(frames, j2, limb_radii(height, body)))
    assert np.array_equal(np.isnan(order), np.isnan(alone))
    assert np.allclose(order[np.isfinite(order)], alone[np.isfinite(alone)])
    assert colour_cues(iter(frames), j2, height, body, front=False, limbs=False) == (None, None)
    assert colour_cues(iter(frames), j2, None, body, front=True, limbs=True)[1] is None
