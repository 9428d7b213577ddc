"""The challenger refined before it meets the track (:func:`vidcap.video.fit.frame.polished`),
the challenge period (:data:`vidcap.video.fit.tracking.REINIT_EVERY`) and the one-pixel mask
changes of ``benchmarks/pose2d_accuracy.py --perturb``, known answers."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from vidcap.body import JOINT_INDEX, SEGMENT_INDEX
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.options import FitOptions
from vidcap.video.fit.raster import draw_pose, model_dimensions, normalise_mask, pose_joints
from vidcap.video.fit.state import FitState

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import pose2d_accuracy as pa  # noqa: E402

H = 240.0
L, R, SH, HP = model_dimensions(H)
POSE = [92, 90, 250, 230, 290, 300, 265, 272, 280, 268]  # arms out, legs apart


def _figure(angles_deg, spread=0.5, shape=(320, 240), top=30.0):
    root = np.array([shape[1] / 2, top + (77 / 175) * H])
    j = pose_joints(root, np.deg2rad(angles_deg), np.ones(10), spread, L, SH, HP)
    return draw_pose(j, R, shape, caps=False), j


def _state(mask, joints, angles_deg, spread=0.5):
    norm = normalise_mask(mask)
    o = FitOptions()
    eng = _MaskEngine(norm, caps=o.caps, body=o.body, foot=o.foot)
    st = replace(FitState.rest(spread=spread),
                 root=norm.to_normalised(joints[JOINT_INDEX["pelvis"]]),
                 angles=np.deg2rad(np.asarray(angles_deg, float))).drawing(slice(None))
    return eng, st, o


def _off_deg(a, b):
    return abs(np.rad2deg(np.angle(np.exp(1j * (a - b)))))


def test_polished_challenger_climbs_to_the_pose_the_track_would_reach():
    from vidcap.video.fit.frame import polished

    mask, joints = _figure(POSE)
    # a fresh fit 7 degrees off on an upper arm and a thigh (within the warm searches'
    # +-8 degrees): refined, it fits better and sits on the drawn pose
    off = list(POSE)
    for seg in ("l_upper_arm", "r_upper_leg"):
        off[SEGMENT_INDEX[seg]] += 7
    eng, fresh, o = _state(mask, joints, off)
    out = polished(eng, fresh, o)
    assert eng.similarity(out) > eng.similarity(fresh) + 0.1
    for seg in ("l_upper_arm", "r_upper_leg"):
        k = SEGMENT_INDEX[seg]
        assert _off_deg(out.angles[k], np.deg2rad(POSE[k])) < 3.0


def test_polished_keeps_the_fresh_fit_when_refining_loses(monkeypatch):
    import vidcap.video.fit.frame as frame

    mask, joints = _figure(POSE)
    eng, fresh, o = _state(mask, joints, POSE)
    worse = fresh.with_entries(angles=(SEGMENT_INDEX["torso"], np.deg2rad(60.0)))
    assert eng.similarity(worse) < eng.similarity(fresh)
    monkeypatch.setattr(frame, "_fit_warm", lambda *a, **k: worse)
    assert frame.polished(eng, fresh, o) is fresh


def test_challenger_is_polished_only_with_the_option(monkeypatch):
    import vidcap.video.fit.frame as frame
    from vidcap.video.fit.pose2d import fit_pose

    mask, _ = _figure(POSE)
    calls = []
    real = frame.polished
    monkeypatch.setattr(frame, "polished", lambda *a: calls.append(1) or real(*a))
    previous = fit_pose(mask)
    frame.fit_frame(normalise_mask(mask), previous=previous, challenge=True,
                    options=FitOptions())  # off by default
    assert calls == []
    frame.fit_frame(normalise_mask(mask), previous=previous, challenge=True,
                    options=FitOptions(polish=True))
    assert calls == [1]


def test_default_challenge_period(monkeypatch):
    import vidcap.video.fit.tracking as tracking
    from vidcap.video.fit.pose2d import fit_sequence

    mask, _ = _figure(POSE)
    masks = np.stack([mask] * 22)
    challenged = []
    real = tracking.fit_frame

    def spy(norm, **kw):
        challenged.append(bool(kw.get("challenge")))
        return real(norm, **kw)

    monkeypatch.setattr(tracking, "fit_frame", spy)
    fit_sequence(masks, back_tie=None, body_window=0, spread_window=0)
    # a still figure never slips: challenged at 0 (cold) and every REINIT_EVERY frames
    assert tracking.REINIT_EVERY == 10
    assert [k for k, c in enumerate(challenged) if c] == [0, 10, 20]


@pytest.mark.parametrize("how", ["true", "erode", "dilate", "edge3"])
def test_perturbed_masks_change_only_the_outline(how):
    mask = np.zeros((1, 40, 30), bool)
    mask[0, 10:30, 8:20] = True  # a 20 x 12 box
    out = pa.perturb_masks(mask, how)
    inner = np.zeros_like(mask)
    inner[0, 11:29, 9:19] = True
    ring = np.zeros_like(mask)
    ring[0, 9:31, 7:21] = True
    ring[0, [9, 9, 30, 30], [7, 20, 7, 20]] = False  # a cross does not reach the corners
    changed = out ^ mask
    assert not (changed & ~(ring & ~inner)).any()  # only within a pixel of the outline
    if how == "true":
        assert not changed.any()
    elif how == "erode":
        assert np.array_equal(out, inner)
    elif how == "dilate":
        assert np.array_equal(out, ring)
    else:  # a quarter of the 2 * 64 - 4 ring pixels either side, drawn, seeded
        assert 15 < changed.sum() < 50
        assert np.array_equal(out, pa.perturb_masks(mask, how))
