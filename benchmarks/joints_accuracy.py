"""Accuracy of marker-derived joint centres (RESULTS.md, "Marker path: joint centres").

Run: /work/venv/bin/python benchmarks/joints_accuracy.py

1. Real trials vs vendor centres: every trial carrying Vicon Plug-in-Gait's joint
   centres (../shared/data's PiG_Motion3_FF / PiG_Calibration3_FF, and the pyCGM
   sample trials under $VIDCAP_DATA/mocap/pycgm), with and without ``--static``.
2. 07_01.c3d: bone lengths vs the subject's skeleton ../shared/data/motion/07.asf.
3. kinematics_tennis_serve.c3d (full-body Plug-in-Gait, no reference skeleton): left
   against right bone lengths, and which joints fell back.
4. Qualisys.c3d (anatomical landmark names): hinge centres against the midpoints of the
   landmark pairs that define them anatomically (femoral epicondyles for the knee,
   malleoli for the ankle, humeral epicondyles for the elbow, styloids for the wrist).
5. Synthetic truth: markers rigidly on 131_01.bvh / 07_07.amc, 1 mm and 5 mm noise.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "mocap"))

from synthetic import ASF_07, BVH_131, attach_markers  # noqa: E402

from vidcap.io.asf import read_asf_amc  # noqa: E402
from vidcap.io.bvh import read_bvh  # noqa: E402
from vidcap.mocap.c3d import read_c3d  # noqa: E402
from vidcap.mocap.skeleton import solve_joints  # noqa: E402

DATA = ROOT.parent / "shared" / "data"


def dist_mm(a, b):
    d = np.linalg.norm(a - b, axis=1) * 1e3
    return d[np.isfinite(d)]


#: Vicon Plug-in-Gait's joint-centre outputs: segment origins and proximal points
#: (FEP hip, FEO knee, TIO ankle; CLO shoulder, HUO elbow, RAO wrist).
PIG_REFS = [("hip", "FEP"), ("knee", "FEO"), ("ankle", "TIO"), ("shoulder", "CLO"),
            ("elbow", "HUO"), ("wrist", "RAO")]


def real_trial_list():
    """(name, trial path, static path or None) of every trial with vendor joint centres:
    ../shared/data's Plug-in-Gait pair, then $VIDCAP_DATA/mocap/pycgm (benchmarks/DATA.md)."""
    out = [("PiG_Motion3_FF", DATA / "c3d/PiG_Motion3_FF.c3d", None),
           ("PiG_Motion3_FF --static", DATA / "c3d/PiG_Motion3_FF.c3d",
            DATA / "c3d/PiG_Calibration3_FF.c3d"),
           ("PiG_Calibration3_FF (static)", DATA / "c3d/PiG_Calibration3_FF.c3d", None)]
    extra = os.environ.get("VIDCAP_DATA")
    folder = Path(extra) / "mocap" / "pycgm" if extra else None
    if folder is None or not folder.is_dir():
        print("(VIDCAP_DATA/mocap/pycgm absent: the pyCGM sample trials are skipped; "
              "see benchmarks/DATA.md)")
        return out
    move, still = folder / "Test_Files_Movement_trial.c3d", folder / "Test_Files_Static_trial.c3d"
    out += [("pyCGM Movement_trial", move, None),
            ("pyCGM Movement_trial --static", move, still)]
    for f in sorted(folder.glob("*Static*.c3d")):
        out.append((f"pyCGM {f.stem.split('_', 1)[1]} (static)", f, None))
    return out


def real_trials():
    """Every trial with vendor joint centres: per joint median/p90 distance (mm) to the
    vendor's centres and the method that placed it; the hip/knee/ankle targets."""
    print("\n## Real trials vs vendor centres (Vicon Plug-in-Gait outputs; mm per frame)")
    print(f"{'trial':34s} {'joint':10s} {'ref':5s} {'median':>7s} {'p90':>7s} method")
    worst, worst_lr = 0.0, 0.0
    for name, path, static in real_trial_list():
        trial = read_c3d(path)
        sol = solve_joints(trial, static=None if static is None else read_c3d(static))
        for joint, suffix in PIG_REFS:
            meds = []
            for side in "lr":
                jn, ref = f"{side}_{joint}", f"{side.upper()}{suffix}"
                if jn not in sol.joint_names or ref not in trial.labels:
                    continue
                d = dist_mm(sol.position(jn), trial.marker(ref))
                if not len(d):
                    continue
                meds.append(np.median(d))
                print(f"{name:34s} {jn:10s} {ref:5s} {np.median(d):7.1f} "
                      f"{np.percentile(d, 90):7.1f} {sol.report(jn).method}")
            if joint in ("hip", "knee", "ankle") and meds:
                worst = max(worst, max(meds))
                if len(meds) == 2:
                    worst_lr = max(worst_lr, abs(meds[0] - meds[1]))
    print(f"targets: every hip/knee/ankle median <= 20 mm: worst {worst:.1f} mm "
          f"{'PASS' if worst <= 20 else 'FAIL'}; left and right within 10 mm: worst "
          f"{worst_lr:.1f} mm {'PASS' if worst_lr <= 10 else 'FAIL'}")


def bones():
    sol = solve_joints(read_c3d(DATA / "c3d/07_01.c3d"))
    asf = read_asf_amc(DATA / "motion/07.asf", DATA / "motion/07_07.amc").skeleton
    pairs = [("l_hip", "l_knee", "lfemur", "ltibia"), ("r_hip", "r_knee", "rfemur", "rtibia"),
             ("l_knee", "l_ankle", "ltibia", "lfoot"), ("r_knee", "r_ankle", "rtibia", "rfoot"),
             ("l_shoulder", "l_elbow", "lhumerus", "lradius"),
             ("r_shoulder", "r_elbow", "rhumerus", "rradius"),
             ("l_elbow", "l_wrist", "lradius", "lwrist"),
             ("r_elbow", "r_wrist", "rradius", "rwrist"),
             ("l_hip", "r_hip", "lfemur", "rfemur")]
    print("\n## 07_01.c3d bone lengths vs 07.asf (mm)")
    print(f"{'bone':22s} {'ours':>7s} {'07.asf':>7s} {'diff':>7s}")
    rest = asf.rest_positions()
    for a, b, ja, jb in pairs:
        ours = np.median(np.linalg.norm(sol.position(a) - sol.position(b), axis=1)) * 1e3
        ref = np.linalg.norm(rest[asf.index(ja)] - rest[asf.index(jb)]) * 1e3
        print(f"{a + '-' + b:22s} {ours:7.0f} {ref:7.0f} {ours - ref:+7.0f}")


def symmetry():
    sol = solve_joints(read_c3d(DATA / "c3d/kinematics_tennis_serve.c3d"))
    print(f"\n## kinematics_tennis_serve.c3d ({sol.markerset.name}): left vs right bone "
          "lengths (mm)")
    print(f"{'bone':16s} {'left':>7s} {'right':>7s} {'diff':>7s}")
    for a, b in [("hip", "knee"), ("knee", "ankle"), ("shoulder", "elbow"),
                 ("elbow", "wrist")]:
        lr = [np.median(np.linalg.norm(sol.position(f"{s}_{a}") - sol.position(f"{s}_{b}"),
                                       axis=1)) * 1e3 for s in "lr"]
        print(f"{a + '-' + b:16s} {lr[0]:7.0f} {lr[1]:7.0f} {lr[0] - lr[1]:+7.0f}")
    for rep in sol.reports:
        if rep.warning():
            print(f"poorly placed: {rep.joint}: {rep.warning()}")


def landmarks():
    trial = read_c3d(DATA / "c3d/Qualisys.c3d")
    sol = solve_joints(trial)
    print(f"\n## Qualisys.c3d ({sol.markerset.name}): centres vs landmark midpoints (mm, per "
          "frame); the offset split along / across the landmark line")
    print(f"{'joint':8s} {'landmarks':16s} {'median':>7s} {'p90':>7s} {'along':>6s} "
          f"{'across':>6s} {'width':>6s} method")
    pairs = {"knee": ("FLE", "FME"), "ankle": ("FAL", "TAM"), "elbow": ("HLE", "HME"),
             "wrist": ("RSP", "UHE")}
    for name, (a, b) in pairs.items():
        for s, p in (("l", "L"), ("r", "R")):
            pa, pb = trial.marker(f"{p}_{a}"), trial.marker(f"{p}_{b}")
            line = (pa - pb) / np.linalg.norm(pa - pb, axis=1, keepdims=True)
            off = sol.position(f"{s}_{name}") - (pa + pb) / 2
            along = np.abs(np.sum(off * line, 1))
            across = np.linalg.norm(off - along[:, None] * line * np.sign(
                np.sum(off * line, 1))[:, None], axis=1)
            d = np.linalg.norm(off, axis=1) * 1e3
            rep = sol.report(f"{s}_{name}")
            print(f"{s + '_' + name:8s} {p + '_' + a + '/' + b:16s} {np.median(d):7.1f} "
                  f"{np.percentile(d, 90):7.1f} {np.median(along) * 1e3:6.0f} "
                  f"{np.median(across) * 1e3:6.0f} "
                  f"{np.median(np.linalg.norm(pa - pb, axis=1)) * 1e3:6.0f} {rep.method}")


def synthetic():
    motions = {"131_01.bvh": (read_bvh(DATA / "motion/131_01.bvh"), BVH_131),
               "07_07.amc": (read_asf_amc(DATA / "motion/07.asf", DATA / "motion/07_07.amc"),
                             ASF_07)}
    joints = ["l_hip", "r_hip", "l_knee", "r_knee", "l_shoulder", "r_shoulder", "l_elbow",
              "r_elbow"]
    print("\n## Synthetic truth: RMS joint-centre error (mm), median over 5 marker layouts")
    print(f"{'motion':11s} {'noise':>5s} " + " ".join(f"{j:>10s}" for j in joints))
    for name, (m, lay) in motions.items():
        for noise, nmm in [(0.0, None), (0.001, None), (0.005, 5.0)]:
            errs = []
            for seed in range(5):
                d, ms, truth = attach_markers(m, lay, np.random.default_rng(seed), noise_m=noise)
                s = solve_joints(d, ms, noise_mm=nmm)
                errs.append([np.sqrt(np.mean(np.sum((s.position(j) - truth[j]) ** 2, 1))) * 1e3
                             for j in joints])
            med = np.median(errs, axis=0)
            print(f"{name:11s} {noise * 1e3:5.0f} " + " ".join(f"{e:10.1f}" for e in med))


if __name__ == "__main__":
    real_trials()
    bones()
    symmetry()
    landmarks()
    synthetic()
