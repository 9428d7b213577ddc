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

# MediaPipe references (person masks + landmarks), with the reference tool's own python
# (set NO_MEDIAPIPE=1 to skip):
MP_PY=/root/.cache/vidcap-mediapipe-reference/bin/python
REF=/work/shared/tools/mediapipe-reference/reference.py
if [ -x "$MP_PY" ] && [ -z "${NO_MEDIAPIPE:-}" ]; then
    for v in onebyone_room pose2sim_balance_cam3 pose2sim_balance_cam4 pose2sim_balance_cam1; do
        [ -f "$DATA/$v.mp4" ] && [ ! -f "$DATA/$v.mediapipe.npz" ] && \
            "$MP_PY" "$REF" "$DATA/$v.mp4" "$DATA/$v.mediapipe.npz" --masks
    done
fi
exit 0
