"""The plate where a person came, stayed and went (issue 26, Build 1).

A person who walks in, stands in one place for most of the clip and walks out (the
onebyone_room visits: in from the bottom edge, 10-25 s at a table, out to the right)
covers the pixels where they stand in most frames. The plate's vote
(:mod:`vidcap.video.background`) takes their colours there, and the passes after it
flag what they cover never seen and guess it; worse, the passes made for a person who
never leaves (:mod:`vidcap.video.appearance`, :func:`vidcap.video.absorbed.flag_unseen`,
the footprint's static parts in :func:`vidcap.video.regionvote._footprint_plate`) take
scenery near the still person, which the clip shows nearly all the time, for never seen
(a grey pillar beside a woman in a grey cardigan, the skirting board along the walk, the
table's foot) and inpaint it: a false blob in every frame. The scene there is seen in
the frames before the person arrives and after they leave, but few of the plate's
samples fall in them; the empty-scene pass (:mod:`vidcap.video.emptyscene`) asks a second
of them and an outline that is the plate's edge, and the passed-by pass
(:mod:`vidcap.video.passedby`) asks the plate's colour to be seen inside the moving blob,
which a person standing still is not.

Every frame is looked at instead, at the plate's working size (the thumbnails
:mod:`vidcap.video.timecover` decodes anyway, :func:`vidcap.video.passedby.clip_motion`).
A pixel's clip *ends* (its first and last :data:`END_S`) show the scene where at least
:data:`MIN_END` of their frames show it in one colour, outside the moving blob, in
frames whose blob holds what moves against the plate re-taken so
(:func:`vidcap.video.passedby.whole_blob_frames`) and :data:`APART` from everything that
differs from that plate (a limb at rest, a still body beside a moving arm, is not the
scene). Then (:func:`bracketed`):

* **stayed**: both ends show the pixel in one colour, and in between it shows something
  else for at least :data:`MIN_STAY` of the clip, in one run (from the first to the last
  frame showing something else the ends' colour shows in at most :data:`MAX_BETWEEN` of
  them: a limb that keeps coming back, as in jumping jacks, is not a stay);
* **came and went** (:data:`SEEN`): when the pixels that stayed so are at least
  :data:`MIN_AREA` of the frame (someone stood there and was gone at both ends: in-place
  renders reach 0.1 %, the onebyone visits and the arriving renders 2-7 %), one end is
  enough where the stay reaches the other (the woman already in front of the table's
  foot in the first frame), and so is a colour the ends show that the clip shows in at
  least :data:`SEEN_MOST` of its frames (the pillar, the skirting board).

Where the plate differs from that colour it is re-taken from the samples whose nearest
thumbnail shows it outside the moving blob
(:func:`vidcap.video.passedby.retake_from_samples`), and those pixels are no longer never
seen. A person in view from the first frame to the last (an in-place performer) has no
ends that show the scene where they are, and no area that stayed while they were gone.
"""

from __future__ import annotations

import cv2
import numpy as np

from vidcap.video.passedby import clip_motion, retake_from_samples
from vidcap.video.timecover import channel_max_diff

__all__ = ["bracketed", "retake_stayed"]

#: Re-take the plate where a person came, stayed and went
#: (:func:`vidcap.video.background.estimate_background`, after every other pass, with the
#: still-person passes, when the thumbnails exist). On: ``silhouettes_real.py --quick
#: --no-mediapipe`` (wt-arrive, one sitting, against main f939fdf) onebyone_room 233-445
#: and 749-865 (validation) 0.746 -> 0.881 and 0.584 -> 0.855 median IoU against
#: MediaPipe's masks, 66-194 and 1242-1357 (tuning) 0.524 -> 0.898 and 0.468 -> 0.718,
#: sbi_candela (tuning) 0.885 -> 0.975, the arriving render side / room (tuning) 0.717 ->
#: 0.983; no other row of the 80 moved by more than 0.005. With ``--seed 1`` onebyone
#: 936-1195 (validation) lost 0.752 -> 0.610 (benchmarks/RESULTS.md, Silhouettes).
STAYED = True
#: The clip's ends looked at, seconds (at least :data:`MIN_END_FRAMES` thumbnails).
END_S = 0.5
#: ... at least this many thumbnails.
MIN_END_FRAMES = 3
#: Share of an end's frames that must show the pixel in its colour, usable (module
#: docstring).
MIN_END = 0.5
#: Share of the clip's frames the pixel must show something else in (someone stayed:
#: where the scene's colour shows most of the time the vote took it).
MIN_STAY = 0.5
#: From the first to the last frame showing something else, the ends' colour shows in at
#: most this share of the frames.
MAX_BETWEEN = 0.1
#: In the clip's ends, a pixel shows the scene only this share of the thumbnail's long
#: side or more away from what differs from the re-taken plate.
APART = 0.03
#: With someone who came and went, also one end where the stay reaches the other, and
#: a colour the clip shows most of the time (module docstring).
SEEN = True
#: ... when the pixels that stayed between two ends showing the scene are at least this
#: share of the frame (chosen on the tuning rows: the arriving renders 5.0 / 7.1 %,
#: onebyone 66-194 and 1242-1357 2.3 / 2.0 %, sbi_candela 3.4 %; 02_06 4-7 s 3/4, in
#: place, 1.1 %; every other render of silhouettes_real.py at most 0.2 %) ...
MIN_AREA = 0.015
#: ... and "most of the time" is this share of the clip's frames.
SEEN_MOST = 0.5


def bracketed(levels: np.ndarray, usable: np.ndarray, plate: np.ndarray, tau: float,
              end: int, left_alone: np.ndarray, seen: bool = False):
    """Pixels a person covered for a long time, and the scene the clip's ends show there.

    Parameters
    ----------
    levels : numpy.ndarray, shape (n, h, w, 3), uint8
        Every frame at the plate's exposure (:func:`vidcap.video.passedby.plate_levels`).
    usable : numpy.ndarray, shape (n, h, w), bool
        Where a frame may show the scene (outside the moving blob, away from the person).
    plate : numpy.ndarray, shape (h, w, 3), uint8
        The plate at the frames' size and blur.
    tau : float
        Colours within ``tau`` (max over the channels) are the same.
    end : int
        Frames at each end of the clip looked at.
    left_alone : numpy.ndarray, shape (h, w), bool
        Pixels not to look at.
    seen : bool
        Someone came and went: also the module docstring's one-ended stays and colours
        shown most of the time.

    Returns
    -------
    flag : numpy.ndarray, shape (h, w), bool
        The pixel stayed (module docstring; with ``seen``, came and went) and the ends'
        colour is not the plate's.
    scene : numpy.ndarray, shape (h, w, 3), float32
        The ends' colour (the median of their usable frames) where ``flag``, 0 elsewhere.
    share : float
        Share of the frame that stayed between two ends showing the scene, whatever the
        plate holds there (the test of :data:`MIN_AREA`).
    """
    n, h, w = levels.shape[:3]
    flag = np.zeros((h, w), bool)
    scene = np.zeros((h, w, 3), np.float32)
    if n < 2 * end + 1:
        return flag, scene, 0.0
    from vidcap.video.emptyscene import _nanmedian0

    ends = np.concatenate([np.arange(end), np.arange(n - end, n)])
    vals = np.where(usable[ends][..., None], levels[ends].astype(np.float32), np.nan)
    # An end shows the scene where enough of its frames are usable and agree (with their
    # median); the colour is the median of both ends where both do.
    shown = []
    for v in (vals[:end], vals[end:]):
        has = np.isfinite(v[..., 0]).sum(axis=0) >= MIN_END * end
        med = np.full((h, w, 3), np.nan, np.float32)
        if has.any():
            med[has] = _nanmedian0(v[:, has])
        steady = (np.abs(v - med[None]).max(axis=-1) < tau).sum(axis=0) >= MIN_END * end
        shown.append((has & steady, med))
    (at0, med0), (at1, med1) = shown
    cand = (at0 | at1) & ~left_alone
    if not cand.any():
        return flag, scene, 0.0
    c = np.where(at0[..., None], med0, med1)
    c = np.where((at0 & at1)[..., None], (med0 + med1) / 2, c)
    agree = ~(at0 & at1) | (np.abs(med0 - med1).max(axis=-1) < tau)
    ids = np.flatnonzero((cand & agree).ravel())
    if not len(ids):
        return flag, scene, 0.0
    col = c.reshape(-1, 3)[ids]
    # |series - col| in uint8 (the larger less the smaller) and the channels' max as two
    # elementwise maxima: the whole frame may be looked at, over up to 600 thumbnails,
    # where an int16 copy and a reduction over a 3-long axis cost several times more
    series = levels.reshape(n, -1, 3)[:, ids]  # (n, P, 3)
    col8 = np.round(col).astype(np.uint8)
    d = np.maximum(series, col8) - np.minimum(series, col8)
    shows = np.maximum(np.maximum(d[..., 0], d[..., 1]), d[..., 2]) < tau
    other = ~shows
    first = other.argmax(axis=0)
    last = n - 1 - other[::-1].argmax(axis=0)
    t = np.arange(n)[:, None]
    between = (shows & (t > first) & (t < last)).sum(axis=0)
    stay = ((other.sum(axis=0) >= MIN_STAY * n)
            & (between <= MAX_BETWEEN * (last - first + 1))
            # an end that does not show the scene is covered by the stay
            & (at0.ravel()[ids] | (first < end)) & (at1.ravel()[ids] | (last >= n - end)))
    both = stay & at0.ravel()[ids] & at1.ravel()[ids]
    good = both.copy()
    if seen:
        # Someone came, stayed and went: one end is enough where the stay reaches the
        # other, and what the ends show, away from the person, is the scene wherever the
        # clip shows it most of the time too.
        good = stay | (shows.sum(axis=0) >= SEEN_MOST * n)
    good &= np.abs(col - plate.reshape(-1, 3)[ids]).max(axis=-1) >= tau
    flag.ravel()[ids[good]] = True
    scene.reshape(-1, 3)[ids[good]] = col[good]
    return flag, scene, float(both.sum()) / (h * w)


def _usable(got, flag: np.ndarray, scene: np.ndarray, end: int) -> np.ndarray:
    """(n, h, w) bool: where a frame may show the scene, against the plate with ``scene``
    put in where ``flag``: outside the moving blob, in frames whose blob holds what
    moves (:meth:`vidcap.video.passedby.ClipMotion.trusted`), and, in the clip's first
    and last ``end`` frames, at least :data:`APART` of the long side from what differs
    from that plate (the person, still or not)."""
    n, h, w = got.levels.shape[:3]
    usable = ~got.blobs & got.trusted(flag, scene)[:, None, None]
    retaken = got.plate_with(flag, scene)
    r = max(1, int(round(APART * max(h, w))))
    reach = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    box = np.ones((3, 3), np.uint8)
    for t in np.concatenate([np.arange(end), np.arange(n - end, n)]):
        fg = (channel_max_diff(got.levels[t], retaken) > got.tau).view(np.uint8)
        fg = cv2.morphologyEx(fg, cv2.MORPH_OPEN, box)
        usable[t] &= cv2.dilate(fg, reach) == 0
    return usable


def retake_stayed(model, frames: np.ndarray, gains: np.ndarray, thumbs: np.ndarray, *,
                  step: int, fps: float):
    """Re-take the plate where a person came, stayed and went (module docstring).

    Parameters
    ----------
    model, frames, gains, thumbs, step, fps
        As :func:`vidcap.video.passedby.retake_passed_by`'s: the plate, the samples it was
        estimated from and their gains, every ``step``-th frame's thumbnail, the clip's
        frame rate.

    Returns
    -------
    vidcap.video.background.BackgroundModel
        With the plate re-taken there from the samples that show the ends' colour
        (those pixels no longer never seen); ``model`` itself when nothing changes.
    """
    got = clip_motion(model, frames, thumbs, step=step, fps=fps)
    if got is None:
        return model
    n, h, w = got.levels.shape[:3]
    end = max(MIN_END_FRAMES, int(round(END_S / got.dt)))
    lit = np.zeros((h, w), bool) if model.self_lit is None else cv2.resize(
        model.self_lit.view(np.uint8), (w, h), interpolation=cv2.INTER_AREA) > 0
    flag, scene, share = bracketed(got.levels, ~got.blobs, got.plate, got.tau, end, lit)
    if not flag.any() and share < MIN_AREA:
        return model
    # Again with only what the ends show away from the person against the plate re-taken
    # so (a still person beside a moving limb, a limb at rest, is not the scene).
    usable = _usable(got, flag, scene, end)
    flag, scene, share = bracketed(got.levels, usable, got.plate, got.tau, end, lit)
    if SEEN and share >= MIN_AREA:
        # Someone came and went: the same with the colour the clip shows most of the time
        # too, first to find the frames and pixels away from the person against it.
        seen, scene, _ = bracketed(got.levels, ~got.blobs, got.plate, got.tau, end, lit,
                                   seen=True)
        usable = _usable(got, seen, scene, end)
        flag, scene, _ = bracketed(got.levels, usable, got.plate, got.tau, end, lit, seen=True)
    if not flag.any():
        return model
    return retake_from_samples(model, frames, gains, got, flag, scene, usable.any(axis=(1, 2)),
                               left_alone=model.self_lit, unflag=True)
