"""Anatomical joint centres (Plug-in-Gait's chord, the Davis hip), the mirrored-trial
symmetry of the whole solver, and the per-joint provenance."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from vidcap.mocap.anatomical import DEFAULT_WIDTHS_MM, chord_centre, chord_offset_mm
from vidcap.mocap.c3d import read_c3d
from vidcap.mocap.hip import davis_hip_regression
from vidcap.mocap.skeleton import solve_joints


def _swap(label: str) -> str:
    if label[:1] in "LR":
        return {"L": "R", "R": "L"}[label[0]] + label[1:]
    if label[:2] in ("l_", "r_"):
        return {"l_": "r_", "r_": "l_"}[label[:2]] + label[2:]
    return label


def mirrored(trial):
    """The trial reflected through the lab's x = 0 plane with left and right swapped:
    labels, and the subject's measurements (a marker or measurement with no other-side
    partner keeps its name: Plug-in-Gait's RBAK marks the thorax's asymmetry)."""
    have = set(trial.labels)
    labels = tuple(_swap(k) if _swap(k) in have else k for k in trial.labels)
    subject = {(_swap(k) if _swap(k) in trial.subject else k): v
               for k, v in trial.subject.items()}
    return dataclasses.replace(trial, labels=labels, subject=subject,
                               positions=trial.positions * np.array([-1.0, 1.0, 1.0]))


@pytest.mark.parametrize("name", ["PiG_Motion3_FF.c3d", "kinematics_tennis_serve.c3d"])
def test_mirrored_trial_gives_mirrored_centres(shared_data, name):
    """Left and right are treated alike: every joint of the mirrored trial is the mirror
    of its other-side joint within 1 mm, placed by the same method."""
    trial = read_c3d(shared_data(f"c3d/{name}"))
    a, b = solve_joints(trial), solve_joints(mirrored(trial))
    assert a.markerset.name == b.markerset.name
    for j in a.joint_names:
        pa = a.position(j)
        pb = b.position(_swap(j)) * np.array([-1.0, 1.0, 1.0])
        d = np.linalg.norm(pa - pb, axis=1) * 1e3
        assert np.nanmax(d) < 1.0, (j, np.nanmax(d))
        assert a.report(j).method == b.report(_swap(j)).method, j


def test_chord_centre_known_answer_in_any_pose():
    """A knee 60 mm medial of its marker, the hip above it and the wand lateral: the
    chord puts the centre back at the knee, in any rotation and translation, and it
    is at the offset from the marker with a right angle hip-centre-marker."""
    rng = np.random.default_rng(5)
    rot = Rotation.random(50, random_state=rng)
    shift = rng.normal(size=(50, 3))
    knee = np.zeros(3)
    hip, marker, wand = np.array([0.02, 0.0, 0.42]), np.array([0.06, 0.0, 0.0]), \
        np.array([0.11, 0.0, 0.21])  # in the plane of hip, knee and marker
    # offset = |marker - knee| with knee on the Thales circle over marker-hip
    hip = hip - (hip @ marker) / (marker @ marker) * marker  # right angle at the knee
    got = chord_centre(rot.apply(wand) + shift, rot.apply(hip) + shift,
                       rot.apply(marker) + shift, 0.06)
    np.testing.assert_allclose(got, rot.apply(knee) + shift, atol=1e-12)
    # wider knee: farther from the marker by exactly the half-width change, still at
    # a right angle
    wide = chord_centre(rot.apply(wand) + shift, rot.apply(hip) + shift,
                        rot.apply(marker) + shift, 0.07)
    m, h = rot.apply(marker) + shift, rot.apply(hip) + shift
    np.testing.assert_allclose(np.linalg.norm(wide - m, axis=1), 0.07, atol=1e-12)
    np.testing.assert_allclose(np.sum((wide - m) * (wide - h), axis=1), 0.0, atol=1e-12)
    # a hip nearer the marker than the offset has no chord centre
    assert np.isnan(chord_centre(wand[None], marker[None] + 0.01, marker[None], 0.06)).all()


def test_chord_offset_reads_processing_widths_or_documented_defaults():
    off, src = chord_offset_mm("LKneeWidth", {"LKneeWidth": 102.0, "MarkerDiameter": 16.0})
    assert off == pytest.approx(59.0) and "102" in src and "default" not in src
    off, src = chord_offset_mm("RAnkleWidth", {})
    assert off == pytest.approx((DEFAULT_WIDTHS_MM["AnkleWidth"] + 14.0) / 2)
    assert src.count("default") == 2


def test_processing_knee_width_moves_the_knee_as_the_chord_rule_says(shared_data):
    """On a Plug-in-Gait walk: the knee centre is (LKneeWidth + MarkerDiameter)/2 from
    LKNE at a right angle to the hip, so widening the knee by 40 mm moves the centre
    20 mm farther from the marker, and the left knee only."""
    trial = read_c3d(shared_data("c3d/PiG_Motion3_FF.c3d"))
    base = solve_joints(trial)
    wide = solve_joints(dataclasses.replace(
        trial, subject={**trial.subject, "LKneeWidth": trial.subject["LKneeWidth"] + 40}))
    assert base.report("l_knee").method == "anatomical"
    for sol, width in ((base, trial.subject["LKneeWidth"]),
                       (wide, trial.subject["LKneeWidth"] + 40)):
        k, m, h = sol.position("l_knee"), trial.marker("LKNE"), sol.position("l_hip")
        d = np.linalg.norm(k - m, axis=1)
        ok = np.isfinite(d)
        np.testing.assert_allclose(d[ok], (width + 14.0) / 2e3, atol=1e-9)
        cos = np.sum((k - m) * (k - h), axis=1)[ok]
        np.testing.assert_allclose(cos, 0.0, atol=1e-9)
    np.testing.assert_array_equal(base.position("r_knee"), wide.position("r_knee"))
    assert "LKneeWidth 142" in wide.report("l_knee").note


def test_davis_hip_needs_leg_lengths_and_is_symmetric():
    # facing +y in a z-up lab: the left is -x
    la, ra = np.array([[-0.12, 0.1, 1.0]]), np.array([[0.12, 0.1, 1.0]])
    sacr = [np.array([[0.0, -0.06, 1.02]])]
    assert davis_hip_regression(la, ra, sacr, {}) is None
    left, right = davis_hip_regression(la, ra, sacr, {"LLegLength": 900.0,
                                                      "RLegLength": 900.0})
    np.testing.assert_allclose(left * [-1, 1, 1], right, atol=1e-12)
    # below and behind the ASIS, medial of them (C = 0.115 L - 15.3 mm)
    assert left[0, 2] < 1.0 and left[0, 1] < 0.1 and -0.12 < left[0, 0] < 0


def test_static_trial_hips_come_from_the_regression(shared_data):
    """A static trial: no thigh motion, so the hips are the pelvis regression whole
    (Plug-in-Gait's, from the file's leg lengths), not the fallback."""
    sol = solve_joints(read_c3d(shared_data("c3d/PiG_Calibration3_FF.c3d")))
    for j in ("l_hip", "r_hip"):
        rep = sol.report(j)
        assert rep.method == "regression" and not rep.flagged, rep
        assert "leg lengths" in rep.note


def test_cli_static_report_provenance_and_warnings(cli, shared_data, tmp_path):
    """`vidcap joints --static` calibrates the anatomical joints; the report gives each
    joint's provenance; a joint placed by rule or fallback gets one warning line."""
    mot, cal = shared_data("c3d/PiG_Motion3_FF.c3d"), shared_data("c3d/PiG_Calibration3_FF.c3d")
    r = cli("joints", mot, "--static", cal, "--report", tmp_path / "r.json", timeout=120)
    assert r.returncode == 0, r.stderr
    rep = {j["joint"]: j for j in json.loads((tmp_path / "r.json").read_text())["joints"]}
    for j in ("l_knee", "r_knee", "l_ankle", "r_ankle"):
        prov = rep[j]["provenance"]
        assert prov["method"] == "anatomical+static" and prov["warning"] == ""
        assert prov["range_of_motion_deg"] > 10 and prov["residual_mm"] > 0
        assert prov["condition"] >= 1
    assert "vidcap: warning" not in r.stderr and "0 poorly placed" in r.stdout
    # CMU's set has no anatomical definitions: its left ankle is a hinge placed by rule
    r = cli("joints", shared_data("c3d/07_01.c3d"), "--report", tmp_path / "c.json",
            timeout=120)
    warn = [ln for ln in r.stderr.splitlines() if ln.startswith("vidcap: warning: joint")]
    assert any("l_ankle" in ln and "by rule" in ln for ln in warn)
    assert len(warn) == len({ln.split(":")[2] for ln in warn})  # one line per joint
    # the static trial is an input: never overwritten
    before = cal.read_bytes()
    r = cli("joints", mot, "--static", cal, "--report", cal, timeout=60)
    assert r.returncode == 2 and cal.read_bytes() == before


def test_rejected_fit_between_named_landmarks_takes_their_midpoint(shared_data):
    """Qualisys's right wrist barely moves (its fit is rejected); its set names the
    styloids straddling it, so the centre is their midpoint in every frame."""
    trial = read_c3d(shared_data("c3d/Qualisys.c3d"))
    sol = solve_joints(trial)
    rep = sol.report("r_wrist")
    assert rep.method == "anatomical" and "R_RSP/R_UHE" in rep.note and not rep.warning()
    mid = (trial.marker("R_RSP") + trial.marker("R_UHE")) / 2
    ok = np.isfinite(mid).all(axis=1)
    np.testing.assert_allclose(sol.position("r_wrist")[ok], mid[ok], atol=1e-12)
