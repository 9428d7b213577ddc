"""A person who holds one pose for the whole clip (issue 26).

A plate estimated from the clip takes in a person who never moves: every sample
shows them, and nothing is left never seen, so :mod:`vidcap.video.personbox` (which
looks for an absorbed person only where the plate left part of the frame never
seen) does not run, and the silhouettes come out nearly empty
(:mod:`vidcap.video.stillcheck` warns after the fact). What gives the held pose away
before the silhouette stage is the same sign: the first-pass silhouettes of the
plate's samples (:func:`vidcap.video.platepass._person_masks`) are small in every
sample but one (:data:`MAX_SHOWN`: the one that caught them settling into the pose).
Then the person-box path runs anyway (the HOG detector and ``cv2.grabCut``,
:func:`vidcap.video.personbox.find_absorbed`, with all its tests: a person the
silhouettes show, boxes or cuts that move, leave the plate alone), searching each
sample also at half the height when the detector finds nobody at the usual one
(:data:`ROWS`), and the cut person becomes the plate's still parts as there.

On an ordinary clip the person shows in some sample and the gate stops at the
samples' first-pass silhouettes (a few milliseconds each); the detector never runs.
"""

from __future__ import annotations

import numpy as np

__all__ = ["absorbed_or_held", "nearly_empty"]

#: Look for a person who held one pose (off: only :mod:`vidcap.video.personbox`'s gate).
HELD_POSE = True
#: The samples' first-pass silhouettes cover less than this share of the frame in
#: every sample looked at but :data:`MAX_SHOWN`. The largest of them on the held
#: poses rendered over the real plates (``silhouettes_real.py``'s "held" rows,
#: tuning): 0.0-1.5 %; on every other tuning row 3.3 % or more (05_04 0-3 s front,
#: 1.3 %, is personbox's own: it leaves 0.5 % never seen).
MAX_AREA = 0.02
#: Samples allowed a larger silhouette than :data:`MAX_AREA`: a person settling into
#: the pose they then hold shows in the first sample (05_18 5.5-8.5 s 3/4: 3.0 % in
#: the first of eight, 0.3-1.5 % in the others). A person who passes through a clip
#: that is otherwise empty opens the gate too; the detector then finds them in a
#: sample or two and :func:`~vidcap.video.personbox.find_absorbed` leaves the plate
#: alone (not found again; a cost of up to ~0.6 s CPU at 640x480, nothing else).
MAX_SHOWN = 1
#: In frames under :data:`vidcap.video.personbox.ENLARGE_BELOW` rows (Weizmann's
#: 180x144), search for an absorbed person whatever the gates say: at that size the
#: plate's never-seen map can be too coarse to show a still body part (02_07 4-7 s
#: side: 0.03 % of the frame). Off: at 180x144 (``silhouettes_real.py --small``, session
#: 45) it took that tuning render 0.504 -> 0.936 median IoU, but two validation rows
#: lost (06_11 6-9 s front 0.873 -> 0.785, a real walker kept in place,
#: cdnet_pedestrians_coat, 0.931 -> 0.882) and no other row of 131 gained.
SMALL_FRAMES = False
#: Samples the gate looks at (evenly spread over the plate's samples).
N_GATE = 8
#: The heights (rows) the detector searches a sample at, the next only when the one
#: before found nobody. At 480 rows the HOG detector missed the held 05_02 3/4 and
#: 02_06 3/4 back mannequins in most samples; at 240 it found them in every one, and
#: found nothing on the three empty real plates at either.
ROWS = (480, 240)


def nearly_empty(model, frames: np.ndarray, gains: np.ndarray, *,
                 n_gate: int = N_GATE, max_area: float = MAX_AREA) -> bool:
    """Whether the first-pass silhouettes of the plate's samples are small in every
    sample looked at (:data:`MAX_AREA`) but at most :data:`MAX_SHOWN`: the plate holds
    whoever is there.

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The plate's samples.
    gains : numpy.ndarray, shape (K, 3)
    n_gate : int
        Samples looked at (evenly spread).
    max_area : float
        Share of the frame.

    Returns
    -------
    bool
    """
    from vidcap.video.platepass import _person_masks

    k = len(frames)
    if k < 2:
        return False
    pick = np.unique(np.linspace(0, k - 1, min(n_gate, k)).round().astype(int))
    masks = _person_masks(model, frames[pick], gains[pick])
    areas = masks.reshape(len(pick), -1).mean(axis=1)
    return bool((areas >= max_area).sum() <= MAX_SHOWN)


def absorbed_or_held(model, frames: np.ndarray, gains: np.ndarray):
    """:func:`vidcap.video.personbox.absorbed_person`, and when its gate kept the
    detector off (nothing never seen) but the samples' silhouettes are nearly empty
    (:func:`nearly_empty`), the same search without that gate at :data:`ROWS`.

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The plate's samples.
    gains : numpy.ndarray, shape (K, 3)

    Returns
    -------
    vidcap.video.background.BackgroundModel
        With the still person's parts (``still_person``) when one was found, else
        ``model``.
    """
    from vidcap.video import personbox

    found, why = personbox.find_absorbed(model, frames, gains)
    if why != personbox.SAW_ALL or not HELD_POSE or len(frames) < 2:
        return found
    small = SMALL_FRAMES and frames.shape[1] < personbox.ENLARGE_BELOW
    if not small and not nearly_empty(model, frames, gains):
        return model
    return personbox.find_absorbed(model, frames, gains, unseen_gate=False, rows=ROWS)[0]
