#!/bin/sh
# Regenerate the sample clips (the README demo input) and their ground truth.
# Run from the repository root:  sh sample_videos/make_samples.sh
# Needs the reference motions in ../shared/data/motion/ (CMU mocap database).
set -e
PY=${PYTHON:-python}
M=../shared/data/motion
OUT=sample_videos

# 1. side view of a real walk (CMU subject 07, trial 07: 1.7 s of it), walking to the right
$PY -m vidcap synth --motion $M/07.asf --amc $M/07_07.amc --range 100:300 --fps 25 --yaw 90 \
    --size 480x360 --noise 2 --seed 1 --proportions seed \
    -o $OUT/walk_side.mp4 --truth $OUT/walk_side_truth.npz

# 2. three-quarter (front-right) view of another real walk (CMU 131_01, before the turn),
#    camera tilted down 8 degrees
$PY -m vidcap synth --motion $M/131_01.bvh --range 0:280 --fps 25 --yaw 45 --elevation 8 \
    --size 480x360 --noise 2 --seed 2 --proportions seed \
    -o $OUT/walk_three_quarter.mp4 --truth $OUT/walk_three_quarter_truth.npz

# 3. a figure raising and bending its arms, slow lighting drift
$PY -m vidcap synth --motion arms --frames 75 --fps 25 --yaw 20 \
    --size 480x360 --noise 2 --lighting-drift 0.05 --seed 3 --proportions seed \
    -o $OUT/arms.mp4 --truth $OUT/arms_truth.npz
