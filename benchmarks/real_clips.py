"""The real clips with a MediaPipe reference, shared by ``pose2d_real.py``,
``lift_accuracy.py --solve`` and ``silhouettes_real.py`` (issues 26, 27 and 33): the one
list of the real-footage benchmarks.

Every ``$VIDCAP_DATA/video/<clip>.mp4`` (or ``.avi``) with ``<clip>.mediapipe.npz`` beside
it (the mediapipe-reference tool's ``reference.py --masks`` output; listed in
``benchmarks/DATA.md`` and ``$VIDCAP_DATA/video/CLIPS.md``; ``benchmarks/get_data.sh``
rebuilds them). None has true masks or joints: MediaPipe is a reference, not the truth
(about 2.4 % of height off on lab footage). The real clips that DO have the dataset's own
person masks (CDnet 2014, SBI2015) are a separate list, :func:`masked_clips`
(``$VIDCAP_DATA/masks``), scored by silhouettes_real.py only. No threshold or weight of
vidcap was chosen on any of them (validation clips), except pose2sim_balance_cam1 for the
silhouettes (``silhouettes_real.REAL_TUNING``).

Each clip goes through vidcap's own pipeline, as ``vidcap convert`` runs it (plate and
silhouettes from the video, the tracked 2D fit; default options, ``cues`` as asked), on
the WHOLE video: the plate of ``onebyone_room`` then sees the empty room between visits
(a user would hand vidcap the whole file too). Scores are taken over the frame ranges in
:data:`STRETCHES` (one person present; the whole clip for the others), and the 3D lift is
run on each range's 2D joints alone, as if the video had been cut there.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: The pipeline's stage cache (plate, silhouettes, 2D fit; not in git): the two benchmarks
#: and the two ``cues`` share the plate and the silhouettes. Its keys name the video and
#: the options, not the code: delete it (``rm -r .vidcap-cache``) after changing the
#: silhouettes or the fit, or the benchmarks score the old code's output.
#: ``VIDCAP_BENCH_CACHE`` names another folder (two settings measured side by side, each
#: with its own cache).
CACHE = Path(os.environ.get("VIDCAP_BENCH_CACHE") or ROOT / ".vidcap-cache")
#: Scored frame ranges [start, stop) per clip, default the whole clip. onebyone_room: its six
#: visits (``lift_accuracy.ONEBYONE_VISITS``), each one person who walks in from the bottom
#: edge, stands at the table with their back to the camera and leaves to the right: the
#: first two scored since session 21 (233-445, 510-694 inclusive, the ones CLIPS.md named),
#: the other four added in session 28 as validation rows (other people and clothes: a grey
#: cardigan, black, grey, a grey shirt and jeans), measured on main before any change.
STRETCHES = {"onebyone_room": ((233, 446), (510, 695), (66, 195), (749, 866), (936, 1196),
                               (1242, 1358))}


@dataclass
class RealClip:
    """One scored stretch of a real clip."""

    name: str  # clip name, with the frame range when only part is scored
    video: Path
    reference: Path  # the mediapipe-reference npz
    start: int
    stop: int | None  # None: to the end


def real_clips(log=print) -> list[RealClip]:
    """The stretches of every real clip in ``$VIDCAP_DATA/video`` with a MediaPipe
    reference, sorted by clip name; ``log`` is told about videos skipped and why."""
    data = os.environ.get("VIDCAP_DATA")
    if not data:
        log("new real clips: skipped (VIDCAP_DATA is not set; see benchmarks/DATA.md)")
        return []
    folder = Path(data) / "video"
    if not folder.is_dir():
        log(f"new real clips: skipped (no folder {folder}; benchmarks/get_data.sh makes it)")
        return []
    out = []
    for video in sorted(p for p in folder.iterdir() if p.suffix in (".mp4", ".avi")):
        ref = video.with_suffix(".mediapipe.npz")
        if not ref.exists():
            log(f"{video.stem}: skipped (no MediaPipe reference {ref.name}: run "
                "../shared/tools/mediapipe-reference/reference.py VIDEO OUT.npz --masks)")
            continue
        for start, stop in STRETCHES.get(video.stem, ((0, None),)):
            name = video.stem if stop is None else f"{video.stem} {start}-{stop - 1}"
            out.append(RealClip(name, video, ref, start, stop))
    return out


#: Real clips WITH true person masks (issue 26): ``$VIDCAP_DATA/masks/<clip>.mp4`` with
#: ``<clip>.truth.npz`` beside it (made by ``benchmarks/get_data.sh`` from CDnet 2014
#: sequences; listed in ``benchmarks/DATA.md``) and, when made, ``<clip>.mediapipe.npz``.
#: The others are validation clips: no threshold or weight of vidcap was chosen on them. They are
#: not in :func:`real_clips` (pose2d_real.py and lift_accuracy.py keep their list).
#: Tuning since the issue-26 empty-scene helper chose vidcap.video.emptyscene.GHOST_RATIO
#: and vidcap.video.personbox.MAX_COVER on them; sbi_candela and sbi_cavignal since the
#: issue-26 realsil helper diagnosed them frame by frame (vidcap.video.emptyscene.
#: FROM_CLIP_ENDS was chosen on candela).
#: sbi_caviar1 since the issue-26 realsil3 helper (session 22) chose
#: vidcap.video.reflection.WEAK on it (its floor reflection), sbi_hallmonitor since that
#: helper diagnosed it frame by frame; the issue-26 hall helper (session 26) built and
#: chose vidcap.video.passedby on it (and checked it on candela and the office clips;
#: sbi_hallmonitor_away, validation, was looked at only through its score).
MASKED_TUNING: set[str] = {"cdnet_office_enter", "cdnet_office_stand", "sbi_candela",
                           "sbi_cavignal", "sbi_caviar1", "sbi_hallmonitor"}


@dataclass
class MaskedClip:
    """A real clip with the dataset's own person masks."""

    name: str
    video: Path
    truth: Path  # npz: masks (F,H,W) bool, ignore (F,H,W) bool, frames (F,) int
    reference: Path | None  # the mediapipe-reference npz, None when not made

    @property
    def use(self) -> str:
        return "tuning" if self.name in MASKED_TUNING else "validation"


def masked_clips(log=print) -> list[MaskedClip]:
    """Every ``$VIDCAP_DATA/masks/<clip>.mp4`` with its ``<clip>.truth.npz``, sorted by
    name; ``log`` is told about what is skipped and why."""
    data = os.environ.get("VIDCAP_DATA")
    if not data:
        log("real clips with true masks: skipped (VIDCAP_DATA is not set)")
        return []
    folder = Path(data) / "masks"
    if not folder.is_dir():
        log(f"real clips with true masks: skipped (no folder {folder}; "
            "benchmarks/get_data.sh makes it)")
        return []
    out = []
    for video in sorted(folder.glob("*.mp4")):
        truth = video.with_suffix(".truth.npz")
        if not truth.exists():
            log(f"{video.stem}: skipped (no {truth.name}: benchmarks/get_data.sh)")
            continue
        ref = video.with_suffix(".mediapipe.npz")
        out.append(MaskedClip(video.stem, video, truth, ref if ref.exists() else None))
    return out


def load_truth(clip: MaskedClip) -> tuple[np.ndarray, np.ndarray]:
    """The clip's true person masks and its ignore masks, both (F, H, W) bool: pixels the
    dataset leaves unscored (outside its region of interest, or unknown, such as blurred
    borders) are True in ``ignore``; shadows are background (False in both)."""
    with np.load(clip.truth) as z:
        return z["masks"].astype(bool), z["ignore"].astype(bool)


#: Frames of a real video that show its scene empty, as a user who looked would give them
#: to ``vidcap convert --background START:END`` (onebyone_room: the empty room between two
#: visitors, benchmarks/DATA.md; cdnet_office_enter: the office before the man walks in,
#: frame 82 of its truth the first with him).
EMPTY_FRAMES = {"onebyone_room": "35:65", "cdnet_office_enter": "0:80"}


def pipeline_result(video: Path, cues: str = "outline", height: float = 1.75,
                    proportions: str = "seed", hidden: str = "fit", camera=None,
                    background=None):
    """vidcap's :func:`vidcap.video.pipeline.run` on the whole ``video`` (default options but
    ``cues`` and ``proportions``; no smoothing, the per-segment lift: the 3D is re-run per
    stretch), cached by stage in :data:`CACHE`. ``hidden='solve'``: ``vidcap convert
    --hidden solve``, the clip solve as the lift and the joints the image cannot show
    taken from it (:mod:`vidcap.video.hidden`). ``camera``: ``vidcap convert --camera``'s
    (height, distance, pitch), as :func:`known_camera` gives it; ``background``: its
    ``--background``."""
    from vidcap.video.pipeline import run

    return run(video, height=height, smooth_sigma=0.0, progress=False, cache_dir=CACHE,
               lift="solve" if hidden == "solve" else "segment", cues=cues,
               proportions=proportions, hidden=hidden, camera=camera, background=background)


#: The clips whose camera stands where a calibration says: the Pose2Sim trial's Qualisys
#: calibration (``benchmarks/triangulate_pose2sim.py`` keeps each camera's pose in the
#: lab's frame, z up, the floor at z = 0).
_CALIBRATED = {"pose2sim_balance_cam1": 0, "pose2sim_balance_cam3": 2,
               "pose2sim_balance_cam4": 3}


def known_camera(name: str):
    """``vidcap convert --camera``'s values for clip ``name`` as a user who knows the
    lab would give them, from the calibration and the subject's triangulated position,
    with the subject's standing height: ``((height m, distance m, pitch deg), stature
    m)``; None for a clip whose camera is not known (every clip but the three calibrated
    pose2sim cameras)."""
    if name not in _CALIBRATED:
        return None
    path = Path(os.environ.get("VIDCAP_DATA", "/nonexistent")) / "lift" / \
        "pose2sim_balance_3d.npz"
    if not path.exists():
        return None
    with np.load(path, allow_pickle=True) as d:
        rot, t, joints = d["R"][_CALIBRATED[name]], d["t"][_CALIBRATED[name]], d["joints"]
        names = [str(n) for n in d["names"]]
    lens = -rot.T @ t  # the camera's centre in the lab, metres
    axis = rot[2]  # its optical axis in the lab (OpenCV camera: z forward)
    hips = np.nanmean(joints[:, [names.index("left_hip"), names.index("right_hip")]], axis=1)
    distance = float(np.nanmedian(np.hypot(*(hips[:, :2] - lens[:2]).T)))
    # the nose of a subject standing on one straight leg, and ~11 cm of head above it
    stature = float(np.nanmedian(joints[:, names.index("nose"), 2])) + 0.11
    pitch = float(np.degrees(np.arcsin(-axis[2])))
    return (float(lens[2]), distance, pitch), stature


def stretch(arr, clip: RealClip):
    """``arr`` (F, ...) cut to the clip's frame range."""
    return None if arr is None else np.asarray(arr)[clip.start:clip.stop]
