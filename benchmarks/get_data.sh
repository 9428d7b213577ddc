#!/usr/bin/env bash
# Reproduce the third-party real clips under $VIDCAP_DATA/video/ from the `fetch` mirrors.
# Not run by CI. Each repository must first be brought onto the machine with the search
# tool's `fetch github:<owner>/<name>` (it lands in /work/.mirror/<owner>+<name>/repo).
# Files are taken at the commit listed in benchmarks/DATA.md, so the bytes are the ones measured.
set -euo pipefail
DATA="${VIDCAP_DATA:-/work/data}/video"
MIRROR="${MIRROR:-/work/.mirror}"
mkdir -p "$DATA"

take() {  # take OWNER+NAME COMMIT PATH OUTFILE
    local git_dir="$MIRROR/$1/repo"
    if [ ! -d "$git_dir" ]; then
        echo "skip $4: $git_dir missing (fetch github:${1/+//} first)" >&2
        return 0
    fi
    git --git-dir="$git_dir" show "$2:$3" > "$DATA/$4"
    echo "$DATA/$4: $(stat -c %s "$DATA/$4") bytes"
}

# Intel IoT devkit sample videos (CC BY 4.0): people enter a room one at a time, stand at a
# table, leave; fixed camera, white wall.
take intel-iot-devkit+sample-videos 57978890822836f2b4743852f04f62fc511757e4 \
    one-by-one-person-detection.mp4 onebyone_room.mp4

# Pose2Sim demo (BSD 3-Clause): one barefoot participant balancing on one leg on a force
# plate in a motion-capture lab, filmed by four fixed cameras (100 frames, 60 fps each).
P2S=f7b39c747b361ce2cef2304bd7d42dddd15b3d36
take perfanalytics+pose2sim $P2S Pose2Sim/Demo_SinglePerson/videos/cam03.mp4 pose2sim_balance_cam3.mp4
take perfanalytics+pose2sim $P2S Pose2Sim/Demo_SinglePerson/videos/cam04.mp4 pose2sim_balance_cam4.mp4
take perfanalytics+pose2sim $P2S Pose2Sim/Demo_SinglePerson/videos/cam01.mp4 pose2sim_balance_cam1.mp4

# Validation clips added by the issue-26 realdata helper (nobody tuned on them). Clips
# longer than ~300 frames or larger than 1000 px are cut / scaled (H.264 crf 18, by
# vidcap's own reader and writer) so the benchmarks stay fast; the others are taken as is.
cut() {  # cut IN OUT FIRST STOP SCALE: frames FIRST..STOP-1 of IN, scaled by SCALE, to OUT
    [ -f "$DATA/$1" ] || return 0
    PYTHONPATH="${PYTHONPATH:-$(cd "$(dirname "$0")/.." && pwd)}" python - "$DATA/$1" "$DATA/$2" "$3" "$4" "$5" <<'PY'
import sys

import cv2

from vidcap.io.video import probe, read_frames, write_video

src, out, a, b, scale = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5])
frames = read_frames(src, start=a, stop=b)
if scale != 1.0:
    h, w = frames.shape[1:3]
    size = (round(w * scale / 2) * 2, round(h * scale / 2) * 2)
    frames = [cv2.resize(f, size, interpolation=cv2.INTER_AREA) for f in frames]
print(out, write_video(out, frames, probe(src).fps, crf=18), "frames")
PY
    rm -f "$DATA/$1"
}
# Sports2D demos (BSD 3-Clause): demo4, a woman walks across a white brick wall in side
# view, turns, walks back (fixed camera; frames 40-339 of 401, where MediaPipe finds her,
# 1280x720 -> 960x540); demo3, a woman runs past a chain-link fence and foliage outdoors
# (frames 0-32 of 47, where she is in view; 480x352).
S2D=4573cde7b1aa8ab3ccd1b0cf55c580ae9f5a9980
take davidpagnon+Sports2D $S2D Sports2D/Demo/demo4.mp4 sports2d_demo4_full.mp4
cut sports2d_demo4_full.mp4 sports2d_walk_turn.mp4 40 340 0.75
take davidpagnon+Sports2D $S2D Sports2D/Demo/demo3.mp4 sports2d_demo3_full.mp4
cut sports2d_demo3_full.mp4 sports2d_run.mp4 0 33 1.0
# TensorFlow.js models' pose-detection test videos (Apache 2.0): a woman doing squats with a
# resistance band in a studio (65 frames at 5 fps, 720x1280 -> 540x960), and a woman
# dancing in place in front of a still interior (120 frames, 576x576, taken as is).
TFJS=18a73420e555a3c1948209ebfa807c7086c7ff0c
take tensorflow+tfjs-models $TFJS pose-detection/test_data/pose_squats.mp4 tfjs_squats_full.mp4
cut tfjs_squats_full.mp4 tfjs_squats.mp4 0 65 0.75
take tensorflow+tfjs-models $TFJS pose-detection/test_data/pose_1.mp4 tfjs_dance.mp4

# Validation clips added by the issue-27 realpose helper (nobody tuned on them): the two
# single-person demo clips of OpenMMLab's mmskeleton (Apache 2.0; 340x256, 300 frames at
# 29.97 fps, letterboxed, taken as is): a man doing tai chi before a glass wall, a
# weightlifter's clean and jerk on a competition stage. Fixed cameras.
MMSK=b4c076baa9e02e69b5876c49fa7c509866d902c7
take open-mmlab+mmskeleton $MMSK resource/data_example/ta_chi.mp4 mmskeleton_taichi.mp4
take open-mmlab+mmskeleton $MMSK resource/data_example/clean_and_jerk.mp4 mmskeleton_clean_jerk.mp4

# CMU motion capture 14_19 (mocap.cs.cmu.edu, free for all uses; subject 14: arm raises,
# bending forward, stepping in place), the CMU site's own BVH as kept by lawrennd/mocap.
# silhouettes_real.py renders it (validation). Its joints are named the Poser way (hip,
# rShldr, rThigh, ...), which vidcap's readers do not map: 14_19_humanik.bvh is the same
# file with the 15 mapped joints renamed to HumanIK names and an end site 18 cm above the
# head joint (the head top; end sites carry no channels, so the motion data is unchanged).
LAW=7e192332050e0be6ccc5d45c3fb762b6f5da8fac
if [ -d "$MIRROR/lawrennd+mocap/repo" ]; then
    mkdir -p "$DATA/../mocap/cmu"
    git --git-dir="$MIRROR/lawrennd+mocap/repo" show "$LAW:python/files/14_19.bvh" \
        > "$DATA/../mocap/cmu/14_19.bvh"
    python - "$DATA/../mocap/cmu/14_19.bvh" "$DATA/../mocap/cmu/14_19_humanik.bvh" <<'PY'
import re
import sys

names = {"hip": "Hips", "neck": "Neck", "head": "Head",
         "rShldr": "RightArm", "rForeArm": "RightForeArm", "rHand": "RightHand",
         "lShldr": "LeftArm", "lForeArm": "LeftForeArm", "lHand": "LeftHand",
         "rThigh": "RightUpLeg", "rShin": "RightLeg", "rFoot": "RightFoot",
         "lThigh": "LeftUpLeg", "lShin": "LeftLeg", "lFoot": "LeftFoot"}
hierarchy, motion = open(sys.argv[1]).read().split("MOTION", 1)
hierarchy = re.sub(r"^(\s*(?:ROOT|JOINT) )(\w+)",
                   lambda m: m.group(1) + names.get(m.group(2), m.group(2)), hierarchy, flags=re.M)
hierarchy = re.sub(r"(JOINT Head\n(\s*)\{\n\s*OFFSET[^\n]*\n\s*CHANNELS[^\n]*\n)",
                   lambda m: (m.group(1) + f"{m.group(2)}  End Site\n{m.group(2)}  {{\n"
                              f"{m.group(2)}    OFFSET 0 18 0\n{m.group(2)}  }}\n"), hierarchy)
open(sys.argv[2], "w").write(hierarchy + "MOTION" + motion)
print(sys.argv[2])
PY
else
    echo "skip 14_19.bvh: $MIRROR/lawrennd+mocap/repo missing (fetch github:lawrennd/mocap first)" >&2
fi

# Real clips WITH TRUE PERSON MASKS (issue 26 validation rows of silhouettes_real.py), in
# $VIDCAP_DATA/masks/: <clip>.mp4 (the dataset's frames, H.264 crf 18 by vidcap's own writer,
# nominal 30 fps: neither dataset states a frame rate) and <clip>.truth.npz (masks (F,H,W)
# bool: ground-truth value 255, the moving person; ignore (F,H,W) bool: 85 outside the ROI,
# 170 unknown (blurred borders), every frame outside the sequence's temporalROI.txt if it has
# one, and the left-behind object of IGNORE_STATIC below; 50, hard shadow, and 0 are
# background; frames (F,) int: the dataset's frame numbers).
MASKS="$DATA/../masks"
masked() {  # masked OWNER+NAME COMMIT SEQ_PATH CLIP FIRST LAST [STATIC_FROM STATIC_TO [main]]
    # FIRST..LAST: the dataset's frame numbers (the digits ending the file names), inclusive.
    # STATIC_FROM..STATIC_TO: frames where an object the person put down lies alone; the
    # truth pixels common to all of them (the object, not a person), dilated by 5 px, are
    # ignored in every frame (the dataset marks it as foreground; it is not the person).
    # "main" (STATIC_FROM..STATIC_TO may be empty strings): the person is the largest blob of
    # each frame's truth; every other truth blob (a far-off passer-by), dilated by 5 px, is
    # ignored in that frame, so no method gains or loses by it.
    local git_dir="$MIRROR/$1/repo"
    if [ ! -d "$git_dir" ]; then
        echo "skip $4: $git_dir missing (fetch github:${1/+//} first)" >&2
        return 0
    fi
    [ -f "$MASKS/$4.truth.npz" ] && return 0
    mkdir -p "$MASKS"
    local tmp
    tmp=$(mktemp -d)
    git --git-dir="$git_dir" archive "$2" "$3" | tar -x -C "$tmp"
    PYTHONPATH="${PYTHONPATH:-$(cd "$(dirname "$0")/.." && pwd)}" python - "$tmp/$3" \
        "$MASKS/$4" "$5" "$6" "${7:-}" "${8:-}" "${9:-}" <<'PY'
import re
import sys
from pathlib import Path

import cv2
import numpy as np

from vidcap.io.video import write_video

seq, out, first, last = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3]), int(sys.argv[4])


def numbered(folder):
    return {int(re.search(r"(\d+)\.\w+$", p.name).group(1)): p
            for p in (seq / folder).iterdir() if p.suffix in (".jpg", ".png")}


inputs, gts = numbered("input"), numbered("groundtruth")
numbers = np.arange(first, last + 1)
frames = [cv2.imread(str(inputs[i]), cv2.IMREAD_COLOR) for i in numbers]
gt = np.stack([cv2.imread(str(gts[i]), cv2.IMREAD_GRAYSCALE) for i in numbers])
ignore = (gt == 85) | (gt == 170)
roi = seq / "temporalROI.txt"
if roi.exists():  # frames the dataset does not score
    roi_a, roi_b = (int(v) for v in roi.read_text().split()[:2])
    ignore[(numbers < roi_a) | (numbers > roi_b)] = True
if sys.argv[5]:
    a, b = int(sys.argv[5]), int(sys.argv[6])
    still = np.all(gt[(numbers >= a) & (numbers <= b)] == 255, axis=0).astype(np.uint8)
    ignore |= cv2.dilate(still, np.ones((11, 11), np.uint8)).astype(bool)[None]
if sys.argv[7] == "main":
    for k in range(len(gt)):
        n_blobs, labels, stats, _ = cv2.connectedComponentsWithStats((gt[k] == 255).astype(np.uint8))
        if n_blobs > 2:
            main = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
            others = ((labels > 0) & (labels != main)).astype(np.uint8)
            gt[k][others.astype(bool)] = 0
            ignore[k] |= cv2.dilate(others, np.ones((11, 11), np.uint8)).astype(bool)
n = write_video(out + ".mp4", frames, 30.0, crf=18)
np.savez_compressed(out + ".truth.npz", masks=gt == 255, ignore=ignore, frames=numbers)
print(out + ".mp4", n, "frames;", int((gt == 255).any((1, 2)).sum()), "with the person")
PY
    rm -rf "$tmp"
}
# CDnet 2014 (changedetection.net), as vendored in zhaochenqiu/UBgS_ADNNet (every frame).
# baseline/office (2050 frames, 360x240): an empty office; a man in a red T-shirt walks in
# (frame 582), stands reading a book by a bookcase for ~45 s (arms, head and a step now and
# then), turns and leaves (2041). Two cuts: 500-1099 (empty office, walk in, stand: the plate
# sees the empty scene) and 1100-1399 (he is in every frame, nearly still: never uncovered).
# baseline/pedestrians (1099 frames, 360x240, outdoors, bright path and lawn): 711-1099, the
# path empty, one woman walks across right to left (829-1051), empty again.
ADN=7131e056d39fbedbace68a3b38049539303e2572
masked zhaochenqiu+UBgS_ADNNet $ADN data/baseline/office cdnet_office_enter 500 1099
masked zhaochenqiu+UBgS_ADNNet $ADN data/baseline/office cdnet_office_stand 1100 1399
masked zhaochenqiu+UBgS_ADNNet $ADN data/baseline/pedestrians cdnet_pedestrians 711 1099
# SBI2015 (Maddalena & Petrosino) with the per-frame foreground masks of Wang, Luo & Jodoin
# (2017), as vendored in lim-anggun/FgSegNet. CaVignal (258 frames, 200x136, outdoors): a
# man stands still on the left for ~170 frames, then walks slowly to the right; he is in
# every frame. Candela_m1.10 (350 frames, 352x288, a lounge seen from high up, wide-angle):
# a man walks in with a bag, sits down on a sofa and stays seated (~230 frames), gets up and
# leaves without the bag; the truth marks the bag too, so the bag where it lies alone
# (frames 293-349) is ignored.
FGS=7aa31e2eba2bbe29f4725c040288e0090c453316
masked lim-anggun+FgSegNet $FGS SBI2015_dataset/CaVignal sbi_cavignal 0 257
masked lim-anggun+FgSegNet $FGS SBI2015_dataset/Candela_m1.10 sbi_candela 0 349 293 349
# Validation clips added by the issue-26 realsil helper (session 21), measured on main before
# any change. CAVIAR1 0-284 (384x256, a shopping-centre corridor, fixed camera, high view): a
# man walks in from the bottom right, crosses to a shop window on the left and stands there,
# nearly still, from about frame 220; far off at the top a passer-by (<= 250 px) is ignored
# ("main"); a second person walks in from the bottom at 285 (not used). CDnet pedestrians
# 596-832: a man in a dark coat walks across the sunlit path right to left (596-703, alone:
# the walkers before him have left), then the empty path (704-832).
masked lim-anggun+FgSegNet $FGS SBI2015_dataset/CAVIAR1 sbi_caviar1 0 284 "" "" main
masked zhaochenqiu+UBgS_ADNNet $ADN data/baseline/pedestrians cdnet_pedestrians_coat 596 832
# HallAndMonitor 243-295 (352x240, the MPEG "hall monitor" corridor, fixed camera): the
# second man, alone once the first has left, walks towards the camera carrying a monitor
# (the truth marks the monitor too) and turns into a doorway on the right; 53 frames.
masked lim-anggun+FgSegNet $FGS SBI2015_dataset/HallAndMonitor sbi_hallmonitor 243 295
# Validation clips added by the issue-26 realsil3 helper (session 22), measured on main
# (c2afe73) before any change. HallAndMonitor 0-74: the first man, alone, walks in from the
# left and away down the corridor carrying a briefcase (the second man appears at 75).
# IBMtest2 (320x240, a lobby seen from above, checkered carpet): 0-33, a man in a checked
# shirt walks towards the camera, alone (the woman enters at 34); 59-89, the woman in a
# white T-shirt walks towards the camera, alone (the man has left at the bottom).
# CAVIAR2 255-459 (384x256, a shop front seen from across a gallery, jpg): one shopper,
# alone, walks out of the shop and along the gallery (the others have left at 254).
masked lim-anggun+FgSegNet $FGS SBI2015_dataset/HallAndMonitor sbi_hallmonitor_away 0 74
masked lim-anggun+FgSegNet $FGS SBI2015_dataset/IBMtest2 sbi_ibmtest2_man 0 33
masked lim-anggun+FgSegNet $FGS SBI2015_dataset/IBMtest2 sbi_ibmtest2_woman 59 89
masked lim-anggun+FgSegNet $FGS SBI2015_dataset/CAVIAR2 sbi_caviar2 255 459

# A multi-view 3D reference for the Pose2Sim balance trial (issue 33): the four views and the
# Qualisys calibration in $VIDCAP_DATA/lift/pose2sim/; MediaPipe's 2D landmarks of each view
# (below) are triangulated by benchmarks/triangulate_pose2sim.py.
LIFT="$DATA/../lift/pose2sim"
if [ -d "$MIRROR/perfanalytics+pose2sim/repo" ]; then
    mkdir -p "$LIFT"
    for i in 1 2 3 4; do
        git --git-dir="$MIRROR/perfanalytics+pose2sim/repo" show \
            "$P2S:Pose2Sim/Demo_SinglePerson/videos/cam0$i.mp4" > "$LIFT/cam0$i.mp4"
    done
    git --git-dir="$MIRROR/perfanalytics+pose2sim/repo" show \
        "$P2S:Pose2Sim/Demo_SinglePerson/calibration/Calib.qca.txt" > "$LIFT/Calib.qca.txt"
fi

# The pose prior's CMU trials on the iClone rig (benchmarks/DATA.md, "The clip solve's pose
# prior"), and the renders' motions below: every file of subjects 001, 002, 003, 005 and 006
# in `DragonForgedTheArtist/IClone-CMU-Mocap`'s snapshot (49 trials; never subject 007).
ICLONE=79529f962ade3274163af53cd92179cee2ed9407
ICL_GIT="$MIRROR/DragonForgedTheArtist+IClone-CMU-Mocap/repo"
if [ -d "$ICL_GIT" ]; then
    mkdir -p "$DATA/../mocap/cmu_iclone"
    git --git-dir="$ICL_GIT" ls-tree -r --name-only "$ICLONE" -- All_BVH/subjects \
        | grep -E '^All_BVH/subjects/00[12356]/[0-9_]+\.bvh$' | while read -r f; do
        out="$DATA/../mocap/cmu_iclone/$(basename "$f")"
        [ -s "$out" ] || git --git-dir="$ICL_GIT" show "$ICLONE:$f" > "$out" 2>/dev/null \
            || rm -f "$out"  # (a path the snapshot lists without its blob)
    done
else
    echo "skip cmu_iclone: $ICL_GIT missing (fetch github:DragonForgedTheArtist/IClone-CMU-Mocap first)" >&2
fi

# pyCGM's sample trials for joints_accuracy.py (benchmarks/DATA.md, "Marker path"): each
# SampleData/<folder>/<file> as <folder>_<file>.
PYCGM=1750a62ccda8c60171ebe3d45f929c96e00a8300
PYCGM_GIT="$MIRROR/cadop+pyCGM/repo"
if [ -d "$PYCGM_GIT" ]; then
    mkdir -p "$DATA/../mocap/pycgm"
    for f in Test_Files/Movement_trial.c3d Test_Files/Static_trial.c3d Test_Files/Test.vsk \
             59993_Frame/59993_Frame_Static.c3d ROM/Sample_Static.c3d Sample_2/RoboStatic.c3d; do
        out="$DATA/../mocap/pycgm/${f//\//_}"
        [ -s "$out" ] || git --git-dir="$PYCGM_GIT" show "$PYCGM:SampleData/$f" > "$out"
    done
else
    echo "skip pycgm: $PYCGM_GIT missing (fetch github:cadop/pyCGM first)" >&2
fi

# CMU 02_05, 02_06, 02_07, 02_09, 02_10, 05_02, 05_09, 05_12, 05_18, 06_10, 06_11, 06_12,
# 01_08, 02_04, 02_08, 05_04, 05_05, 05_10, 05_13, 05_20, 06_15, and (session 34) 05_03,
# 05_06, 05_08, 05_14, 05_15, 05_16, 06_06, 06_08, 06_02, 06_03, 06_04, 06_05, 06_07, 06_09, 03_01
# (in place) for silhouettes_real.py's renders: the pose prior's iClone files ($VIDCAP_DATA/mocap/cmu_iclone, see benchmarks/DATA.md) with
# the 15 mapped joints renamed to HumanIK names and the face under the head replaced by
# an end site 18 cm up the head (the head top; the face's motion columns dropped).
ICL="$DATA/../mocap/cmu_iclone"
if [ -f "$ICL/002_05.bvh" ]; then
    mkdir -p "$DATA/../mocap/cmu_iclone_humanik"
    for t in 002_05 002_06 002_07 002_09 002_10 005_02 005_09 005_12 005_18 \
             006_10 006_11 006_12 001_08 002_04 002_08 005_04 005_05 005_10 005_13 \
             005_20 006_15 001_01 001_14 005_07 005_11 005_17 005_19 006_14 \
             005_03 005_06 005_08 005_14 005_15 005_16 006_06 006_08 006_02 006_03 006_04 \
             006_05 006_07 006_09 003_01; do
        python - "$ICL/$t.bvh" "$DATA/../mocap/cmu_iclone_humanik/${t}_humanik.bvh" <<'PY'
import re
import sys

NAMES = {"CC_Base_Hip": "Hips", "CC_Base_NeckTwist01": "Neck", "CC_Base_Head": "Head",
         "CC_Base_L_Upperarm": "LeftArm", "CC_Base_L_Forearm": "LeftForeArm",
         "CC_Base_L_Hand": "LeftHand", "CC_Base_R_Upperarm": "RightArm",
         "CC_Base_R_Forearm": "RightForeArm", "CC_Base_R_Hand": "RightHand",
         "CC_Base_L_Thigh": "LeftUpLeg", "CC_Base_L_Calf": "LeftLeg", "CC_Base_L_Foot": "LeftFoot",
         "CC_Base_R_Thigh": "RightUpLeg", "CC_Base_R_Calf": "RightLeg",
         "CC_Base_R_Foot": "RightFoot"}
src, dst = sys.argv[1], sys.argv[2]
hier, motion = open(src).read().split("MOTION", 1)
lines = hier.splitlines()
out, cols, col, skip_depth, depth = [], [], 0, None, 0
i = 0
while i < len(lines):
    ln = lines[i]
    s = ln.strip()
    if skip_depth is None and s.startswith("JOINT CC_Base_FacialBone"):
        # the face (jaw, tongue, eyes): replaced by the head top, 18 cm up the head
        ind = ln[:len(ln) - len(ln.lstrip())]
        out += [f"{ind}End Site", f"{ind}{{", f"{ind}    OFFSET 0.000000 18.000000 0.000000",
                f"{ind}}}"]
        skip_depth = depth
    if s.startswith("{"):
        depth += 1
    elif s.startswith("}"):
        depth -= 1
    if s.startswith("CHANNELS"):
        n = int(s.split()[1])
        if skip_depth is None:
            cols += list(range(col, col + n))
        col += n
    if skip_depth is not None:
        if s.startswith("}") and depth == skip_depth:
            skip_depth = None
        i += 1
        continue
    m = re.match(r"^(\s*(?:ROOT|JOINT) )(\w+)", ln)
    if m and m.group(2) in NAMES:
        ln = m.group(1) + NAMES[m.group(2)]
    out.append(ln)
    i += 1
mlines = motion.strip("\n").splitlines()
head, data = mlines[:2], mlines[2:]
rows = []
for r in data:
    v = r.split()
    assert len(v) == col, (len(v), col)
    rows.append(" ".join(v[c] for c in cols))
open(dst, "w").write("\n".join(out) + "\nMOTION\n" + "\n".join(head) + "\n" + "\n".join(rows) + "\n")
print(dst, len(rows), "frames,", len(cols), "of", col, "channels")
PY
    done
else
    echo "skip the 02_0x renders' motions: $ICL/002_05.bvh missing (see benchmarks/DATA.md)" >&2
fi

# MediaPipe references (person masks + landmarks), with the reference tool's own python
# (set NO_MEDIAPIPE=1 to skip):
MP_PY=/root/.cache/vidcap-mediapipe-reference/bin/python
REF=/work/shared/tools/mediapipe-reference/reference.py
if [ -x "$MP_PY" ] && [ -z "${NO_MEDIAPIPE:-}" ]; then
    for v in onebyone_room pose2sim_balance_cam3 pose2sim_balance_cam4 pose2sim_balance_cam1 \
             sports2d_walk_turn sports2d_run tfjs_squats tfjs_dance mmskeleton_taichi \
             mmskeleton_clean_jerk; do
        [ -f "$DATA/$v.mp4" ] && [ ! -f "$DATA/$v.mediapipe.npz" ] && \
            "$MP_PY" "$REF" "$DATA/$v.mp4" "$DATA/$v.mediapipe.npz" --masks
    done
    for v in cdnet_office_enter cdnet_office_stand cdnet_pedestrians sbi_cavignal sbi_candela \
             sbi_caviar1 cdnet_pedestrians_coat sbi_hallmonitor sbi_hallmonitor_away \
             sbi_ibmtest2_man sbi_ibmtest2_woman sbi_caviar2; do
        if [ -f "$MASKS/$v.mp4" ] && [ ! -f "$MASKS/$v.mediapipe.npz" ]; then
            "$MP_PY" "$REF" "$MASKS/$v.mp4" "$MASKS/$v.mediapipe.npz" --masks
        fi
    done
    # ido_walk's 2D and world landmarks for lift_accuracy.py --solve --real-only
    IDO="$(cd "$(dirname "$0")/.." && pwd)/../shared/data/video/ido_walk.avi"
    if [ -f "$IDO" ] && [ ! -f "$DATA/../lift/ido_walk_mediapipe.npz" ]; then
        "$MP_PY" "$REF" "$IDO" "$DATA/../lift/ido_walk_mediapipe.npz"
    fi
    for i in 1 2 3 4; do
        if [ -f "$LIFT/cam0$i.mp4" ] && [ ! -f "$LIFT/cam0$i.mediapipe.npz" ]; then
            "$MP_PY" "$REF" "$LIFT/cam0$i.mp4" "$LIFT/cam0$i.mediapipe.npz"
        fi
    done
fi
if [ -f "$LIFT/cam04.mediapipe.npz" ]; then
    VIDCAP_DATA="${VIDCAP_DATA:-/work/data}" \
        PYTHONPATH="${PYTHONPATH:-$(cd "$(dirname "$0")/.." && pwd)}" \
        python "$(dirname "$0")/triangulate_pose2sim.py"
fi
exit 0
