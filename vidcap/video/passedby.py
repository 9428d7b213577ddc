"""The plate re-taken where it holds a colour that only passed by (issue 26, Build 1, 4).

The plate's vote (:mod:`vidcap.video.background`) takes, per pixel, the colour of the
most *stable region*: a Felzenszwalb region whose colour many samples share. A person who
walks along the camera's line of sight keeps a large, evenly coloured region (a white
shirt) over the same pixels for most of the clip, and the vote can take it over scenery
the samples show less often. On sbi_hallmonitor (tuning) the plate held the man's shirt
over a brown chair and cabinet he walks in front of, and over the corridor where he
stood at the start: a false blob in every frame where the chair is, the man's torso
absorbed (median IoU 0.31). The empty-scene pass (:mod:`vidcap.video.emptyscene`) did
not help: the chair has edges of its own where the plate holds the shirt, so its ghost
test never fired, and the corridor is uncovered for the last 0.3 s only.

Motion tells the two apart. Every frame of the clip is looked at, at the plate's working
size (the thumbnails :mod:`vidcap.video.timecover` decodes anyway, brought to the plate's
exposure: :func:`plate_levels`), and in each the *moving blob* is found
(:func:`moving_blobs`): the pixels that differ from the frames a short time before *and*
after (a double difference: a frame difference alone marks where the person was as well
as where they are), at a few lags (:data:`LAGS_S`), closed and filled into a solid shape
(:data:`CLOSE`: the inside of a shirt does not change from frame to frame, its outline
does). Then, per pixel (:func:`passed_by`):

* the plate's colour is seen mostly in frames in which the pixel lies inside the blob
  (at most :data:`MAX_OUTSIDE` of them outside): it passed by;
* the scene is what the pixel shows in its *quiet ends*, the frames before the blob
  first covers it and after it last does (less the frames that show the plate's colour
  without a break from the blob's: a slow walker's shirt before the blob's outline took
  it in), when they agree on another colour for :data:`MIN_AWAY_S` and hardly show the
  plate's. A person who came and stood still is bracketed by their own coming and going,
  so their still frames are not the scene; the scene is what the pixel showed before the
  first passer-by and after the last (but a person standing still is outside the moving
  blob, so the first test keeps their colour: :mod:`vidcap.video.stayed` handles them);
* and between the first and the last frame showing the plate's colour, the scene's
  hardly shows (the passer-by hid it while passing; where the scene keeps showing between
  the plate colour's appearances, the plate's colour is the scene seen between a limb's
  passes, which the double difference takes for the moving thing).

The quiet ends are read only in frames whose blob holds the person whole
(:func:`whole_blob_frames`): against the plate the pass would give, the blob holds most of
what differs from it near the blob. A dancer who stands still at the clip's first frames
while one arm moves gets a blob round the arm only, and her still torso beside it, outside
the blob, would otherwise be taken for the scene her later dancing uncovers (the render
05_19 3/4 back lost 0.974 -> 0.938 median IoU so); a walker's blob holds the walker.

There the plate is re-taken from the sampled trusted frames that show the scene's colour
outside the blob (their median, each divided by its gain). Pixels flagged never seen (a guess by
design) and self-lit pixels are left alone. The pass runs after the empty-scene pass,
whose ghosts and re-take it would otherwise move.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np

from vidcap.video.timecover import channel_max_diff, coarse_step, inverse_gains

__all__ = ["ClipMotion", "clip_motion", "moving_blobs", "passed_by", "plate_levels",
           "retake_from_samples", "retake_passed_by", "whole_blob_frames"]

#: Re-take the plate where it holds a colour that only passed by (called by
#: :func:`vidcap.video.background.estimate_background` when the thumbnails exist,
#: :data:`vidcap.video.timecover.TIME_COVER`). **Off.** With the whole-blob gate
#: (:func:`whole_blob_frames`; wt-pass, one sitting, ``silhouettes_real.py --quick --pck
#: --no-mediapipe`` with and without ``--passed-by``) it is safe for the silhouettes: no
#: render loses more than 0.01 median IoU (05_19 3/4 back 0.974 -> 0.974, was 0.938
#: without the gate; 05_18 side 0.957 -> 0.949, was 0.945; 05_02 front 0.897 -> 0.897,
#: was 0.887; all tuning), the real clips keep their gains (hallmonitor 0.314 -> 0.667,
#: candela 0.885 -> 0.933, tuning; hallmonitor_away 0.819 -> 0.863, ibmtest2_woman
#: 0.957 -> 0.962, validation) and the silhouettes rise against MediaPipe's masks on
#: cam1, cam3 and taichi. But the 2D fit through the pipeline gets worse on the in-place
#: clips whose plate it changes (``pose2d_real.py --no-all --rows human``, % of height:
#: pose2sim cam1 12.3 -> 17.9, cam3 8.1 -> 9.0, cam4 4.9 -> 5.5, tuning; taichi 10.6 ->
#: 11.8, tfjs_dance 4.9 -> 5.6, validation; clean_jerk 13.7 -> 12.2), also as the mean
#: of 4 runs with 1 % of the outline flipped (cam1 15.2 -> 18.3, taichi 11.5 -> 12.2),
#: though there the silhouettes it gives are nearer MediaPipe's masks (cam1's absorbed
#: torso back, cam3's false blob gone): so not on by default (benchmarks/RESULTS.md).
PASSED_BY = False
#: The double difference's lags, seconds (each at least one thumbnail).
LAGS_S = (0.1, 0.2, 0.4)
#: The moving pixels closed into a blob with an ellipse this share of the thumbnail's
#: long side across (then holes filled).
CLOSE = 0.08
#: The plate's colour counts as passed by where at most this share of its frames lie
#: outside the moving blob ...
MAX_OUTSIDE = 0.35
#: ... and the frames outside the blob agree on another colour for at least this long,
#: seconds (at least 3 thumbnails).
MIN_AWAY_S = 0.1
#: The scene's colour is seen inside the blob in at most this share of the times it is
#: seen outside it.
SCENE_INSIDE = 0.35
#: A frame shows the scene outside the blob only when the blob holds at least this share
#: of what differs from the re-taken plate near it (:func:`whole_blob_frames`) ... Chosen
#: on the tuning clips' re-taken thumbnail pixels, scored against their true masks:
#: 05_19 3/4 back kept 74 of its 93 wrong ones at 0.4, 1 at 0.55; 05_02 front 18 at
#: 0.4, 2 at 0.55; sbi_hallmonitor kept 163 of its 164 right ones at 0.55, 161 at 0.7;
#: sbi_candela all 59 at 0.4-0.7.
MIN_HELD = 0.55
#: ... within this share of the thumbnail's long side of it.
NEAR = 0.08
#: A frame without a blob shows the scene when what differs from the re-taken plate is
#: at most this share of the clip's median blob.
EMPTY = 0.25


def plate_levels(thumbs: np.ndarray, plate: np.ndarray) -> np.ndarray:
    """The thumbnails (N, h, w, 3) uint8, each 3x3 blurred and brought to the exposure of
    ``plate`` (h, w, 3) (divided by its per-channel gain against it: the median ratio
    over a coarse grid), rounded and clipped to uint8: a channel the camera clipped in a
    darker frame is the plate's clipped 255, not more."""
    step = coarse_step(*thumbs.shape[1:3])
    inv = inverse_gains(thumbs, plate[::step, ::step].astype(np.float32) + 1.0)
    out = np.empty_like(thumbs)
    for t in range(len(thumbs)):
        # (uint8 in, uint8 out: cv2 rounds and saturates)
        cv2.multiply(cv2.GaussianBlur(thumbs[t], (3, 3), 0),
                     (*(float(g) for g in inv[t]), 0.0), dst=out[t])
    return out


def moving_blobs(levels: np.ndarray, tau: float, lags: list[int], close: int) -> np.ndarray:
    """Per frame, the solid shape of what moves in it.

    Parameters
    ----------
    levels : numpy.ndarray, shape (n, h, w, 3), uint8
        The frames (:func:`plate_levels`).
    tau : float
        A pixel differs between two frames when a channel does by more than ``tau``.
    lags : list of int
        Frame lags, ascending. A pixel moves in frame t when, at some lag L, it differs
        from both frames t - L and t + L; at the clip's ends, where one of them does not
        exist, only the smallest lag is used, one-sided.
    close : int
        Diameter, pixels, of the ellipse the moving pixels are closed with.

    Returns
    -------
    numpy.ndarray, shape (n, h, w), bool
        The moving pixels closed, their holes filled, dilated by one pixel.
    """
    n, h, w = levels.shape[:3]
    moving = np.zeros((n, h, w), bool)
    for i, lag in enumerate(lags):
        if lag >= n:
            break
        # d[j]: frame j + lag differs from frame j (each pair once; the whole stack in
        # one absdiff, the channels' max as three planes)
        a = cv2.absdiff(levels[lag:].reshape(n - lag, -1), levels[:n - lag].reshape(n - lag, -1))
        a = a.reshape(n - lag, h, w, 3)
        d = np.maximum(np.maximum(a[..., 0], a[..., 1]), a[..., 2]) > tau
        if n > 2 * lag:  # frames with both neighbours (none in a clip shorter than 2 lags)
            moving[lag:n - lag] |= d[:n - 2 * lag] & d[lag:]
        if i == 0:  # the ends, one-sided
            ends = min(lag, n - lag)
            moving[:ends] |= d[:ends]
            moving[n - ends:] |= d[n - lag - ends:n - lag]
    ker = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (close, close))
    one = np.ones((3, 3), np.uint8)
    out = np.zeros((n, h, w), bool)
    seed = np.zeros((h + 4, w + 4), np.uint8)
    framed = np.zeros((h + 2, w + 2), np.uint8)
    for t in range(n):
        if not moving[t].any():
            continue
        m = cv2.morphologyEx(moving[t].view(np.uint8), cv2.MORPH_CLOSE, ker)
        # holes: what the frame's border cannot reach round the blob (a one-pixel frame
        # of background round it: the blob may touch the border)
        framed[:] = 0
        framed[1:-1, 1:-1] = m
        seed[:] = 0
        cv2.floodFill(framed, seed, (0, 0), 1)
        out[t] = cv2.dilate(m | (1 - framed[1:-1, 1:-1]), one) > 0
    return out


def whole_blob_frames(levels: np.ndarray, blobs: np.ndarray, plate: np.ndarray, tau: float,
                      reach: int) -> np.ndarray:
    """Frames in which the moving blob holds the person whole, (n,) bool.

    A person who stands still while a limb moves (a dancer at the clip's first frames)
    gets a blob round the limb only, and their still torso beside it is outside the
    blob: not the scene, though it is what the pixel shows there. Against the plate the
    pass would give (the scene where :func:`passed_by` flags), a frame is trusted when
    the blob holds at least :data:`MIN_HELD` of what differs from it within ``reach``
    pixels of the blob (a walker's blob holds the walker: 0.7-0.85 on sbi_hallmonitor;
    a still dancer's 0.02-0.2), or, without a blob, when what differs from it is at most
    :data:`EMPTY` of the clip's median blob.

    Parameters
    ----------
    levels : numpy.ndarray, shape (n, h, w, 3), uint8
    blobs : numpy.ndarray, shape (n, h, w), bool
    plate : numpy.ndarray, shape (h, w, 3), uint8
    tau : float
    reach : int
        Pixels round the blob looked at.
    """
    n = len(levels)
    ker = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * reach + 1, 2 * reach + 1))
    area = blobs.reshape(n, -1).sum(axis=1)
    typical = float(np.median(area[area > 0])) if area.any() else 0.0
    out = np.zeros(n, bool)
    for t in range(n):
        fg = channel_max_diff(levels[t], plate) > tau
        if area[t] == 0:
            out[t] = fg.sum() <= EMPTY * typical
            continue
        near = fg & (cv2.dilate(blobs[t].view(np.uint8), ker) > 0)
        out[t] = (near & blobs[t]).sum() >= MIN_HELD * near.sum()
    return out


def passed_by(levels: np.ndarray, blobs: np.ndarray, plate: np.ndarray, tau: float,
              min_away: int, left_alone: np.ndarray, trusted: np.ndarray | None = None):
    """Pixels whose plate colour only passed by, and the scene's colour there.

    Parameters
    ----------
    levels : numpy.ndarray, shape (n, h, w, 3), uint8
        The frames (:func:`plate_levels`).
    blobs : numpy.ndarray, shape (n, h, w), bool
        :func:`moving_blobs`.
    plate : numpy.ndarray, shape (h, w, 3), uint8
        The plate at the frames' size and blur.
    tau : float
        Colours within ``tau`` (max over the channels) are the same.
    min_away : int
        Frames that must agree on the scene's colour.
    left_alone : numpy.ndarray, shape (h, w), bool
        Pixels not to look at.
    trusted : numpy.ndarray, shape (n,), bool, optional
        The frames that may show the scene (:func:`whole_blob_frames`; default all).

    Returns
    -------
    flag : numpy.ndarray, shape (h, w), bool
        The plate's colour is seen outside the blob in at most :data:`MAX_OUTSIDE` of
        the frames it is seen in; the pixel's quiet ends (the frames outside the blob
        before it first covers the pixel and after it last does, less those showing the
        plate's colour without a break from the blob's) agree on another colour (their
        median) in at least ``min_away`` frames and show the plate's in at most
        :data:`MAX_OUTSIDE` as many; and between the first and the last frame showing
        the plate's colour, that colour shows in at most :data:`MAX_OUTSIDE` as many
        frames as the plate's.
    scene : numpy.ndarray, shape (h, w, 3), float32
        That median where ``flag`` (0 elsewhere).
    """
    n, h, w = levels.shape[:3]
    shown = np.zeros((h, w), np.int32)
    shown_out = np.zeros((h, w), np.int32)
    on_all = np.empty((n, h, w), bool)  # frame t shows the plate's colour
    for t in range(n):
        on = np.less(channel_max_diff(levels[t], plate), tau, out=on_all[t])
        shown += on
        shown_out += on & ~blobs[t]
    # The quiet ends: the frames before the blob first covers the pixel and after it
    # last does.
    first = np.full((h, w), n, np.int32)
    last = np.full((h, w), n, np.int32)
    for t in range(n):
        np.copyto(first, t, where=blobs[t] & (first == n))
        np.copyto(last, t, where=blobs[t])
    ever = first < n
    quiet = first + np.where(ever, n - 1 - last, 0)
    cand = ((shown_out <= MAX_OUTSIDE * shown) & (shown - shown_out >= min_away)
            & (quiet >= min_away) & ~left_alone)
    flag = np.zeros((h, w), bool)
    scene = np.zeros((h, w, 3), np.float32)
    if not cand.any():
        return flag, scene
    vals = levels[:, cand].astype(np.float32)  # (n, P, 3)
    t = np.arange(n)[:, None]
    first, last = first[cand][None], last[cand][None]
    on = on_all[:, cand]  # (n, P)
    # The plate's colour in frames next to the blob's, without a break, is the
    # passer-by's still (a slow walker's shirt before the blob's outline took it in).
    inside = blobs[:, cand]
    passer = on & inside
    for i in range(1, n):
        passer[i] |= on[i] & passer[i - 1]
    for i in range(n - 2, -1, -1):
        passer[i] |= on[i] & passer[i + 1]
    ends = ~inside & ~passer & ((t < first) | (t > last))  # (n, P)
    if trusted is not None:
        ends &= trusted[:, None]
    from vidcap.video.emptyscene import _nanmedian0

    med = _nanmedian0(np.where(ends[..., None], vals, np.nan))
    is_scene = np.abs(vals - med[None]).max(axis=-1) < tau
    agree = (is_scene & ends).sum(axis=0)
    # The passer-by hid the scene while it passed: between the first and the last frame
    # that show the plate's colour, the scene's hardly shows (where it does, the plate's
    # colour came and went in front of it again and again: the scene seen between a
    # limb's passes, which the double difference takes for the moving thing).
    first_p = on.argmax(axis=0)
    last_p = n - 1 - on[::-1].argmax(axis=0)
    between = is_scene & (t > first_p[None]) & (t < last_p[None])
    # ... and the scene's colour is seen mostly outside the blob (a person who stays in
    # view shows their own colours inside it as they move: their still torso at the
    # clip's ends, where the blob is thin, is not the scene).
    seen_in = (is_scene & inside).sum(axis=0)
    ok = ((agree >= min_away) & ((on & ends).sum(axis=0) <= MAX_OUTSIDE * agree)
          & (seen_in <= SCENE_INSIDE * (is_scene & ~inside).sum(axis=0))
          & (between.sum(axis=0) <= MAX_OUTSIDE * on.sum(axis=0))
          & (np.abs(med - plate[cand]).max(axis=-1) >= tau))
    flag[cand] = ok
    scene[cand] = np.where(ok[:, None], med, 0)
    return flag, scene


def retake_passed_by(model, frames: np.ndarray, gains: np.ndarray, thumbs: np.ndarray, *,
                     step: int, fps: float):
    """Re-take the plate where it holds a colour that only passed by (module docstring).

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The samples the plate was estimated from (``model.sample_indices``).
    gains : numpy.ndarray, shape (K, 3)
        Their per-channel gains relative to the plate.
    thumbs : numpy.ndarray, shape (N, h, w, 3), uint8
        Every ``step``-th frame of the clip (frame ``i * step``), at low resolution.
    step : int
    fps : float
        The clip's frame rate.

    Returns
    -------
    vidcap.video.background.BackgroundModel
        With the plate, its confidence and noise map replaced there from the samples in
        which the pixel lies outside the moving blob (their median, each divided by its
        gain); ``model`` itself when nothing changes.
    """
    got = clip_motion(model, frames, thumbs, step=step, fps=fps)
    if got is None:
        return model
    left_alone = model.never_seen if model.self_lit is None else (
        model.never_seen | model.self_lit)
    left_small = cv2.resize(left_alone.view(np.uint8), got.levels.shape[2:0:-1],
                            interpolation=cv2.INTER_AREA) > 0
    min_away = max(3, int(np.ceil(MIN_AWAY_S / got.dt)))
    flag, scene = passed_by(got.levels, got.blobs, got.plate, got.tau, min_away, left_small)
    if not flag.any():
        return model
    # Again with only the frames whose blob holds the person whole against the plate
    # re-taken so (a still person beside a moving limb is not the scene).
    trusted = got.trusted(flag, scene)
    if not trusted.all():
        flag, scene = passed_by(got.levels, got.blobs, got.plate, got.tau, min_away,
                                left_small, trusted)
        if not flag.any():
            return model
    return retake_from_samples(model, frames, gains, got, flag, scene, trusted,
                               left_alone=left_alone)


@dataclass(frozen=True)
class ClipMotion:
    """The whole clip at the plate's working size, for the passes that read every frame
    (:func:`clip_motion`).

    Attributes
    ----------
    levels : numpy.ndarray, shape (n, h, w, 3), uint8
        The thumbnails at the plate's exposure (:func:`plate_levels`).
    blobs : numpy.ndarray, shape (n, h, w), bool
        Their moving blobs (:func:`moving_blobs`).
    plate : numpy.ndarray, shape (h, w, 3), uint8
        The plate at the thumbnails' size and blur.
    tau : float
        Colours within ``tau`` (max over the channels) are the same.
    dt : float
        Seconds between two thumbnails.
    step : int
        Thumbnail ``i`` is frame ``i * step``.
    """

    levels: np.ndarray
    blobs: np.ndarray
    plate: np.ndarray
    tau: float
    dt: float
    step: int

    def plate_with(self, flag: np.ndarray, scene: np.ndarray) -> np.ndarray:
        """The plate (h, w, 3) uint8 with ``scene`` (h, w, 3) put in where ``flag``."""
        retaken = self.plate.copy()
        retaken[flag] = np.clip(np.round(scene[flag]), 0, 255).astype(np.uint8)
        return retaken

    def trusted(self, flag: np.ndarray, scene: np.ndarray) -> np.ndarray:
        """:func:`whole_blob_frames` against the plate with ``scene`` (h, w, 3) put in
        where ``flag`` (h, w): the frames that may show the scene, (n,) bool."""
        h, w = self.plate.shape[:2]
        return whole_blob_frames(self.levels, self.blobs, self.plate_with(flag, scene),
                                 self.tau, max(1, int(round(NEAR * max(h, w)))))


def clip_motion(model, frames: np.ndarray, thumbs: np.ndarray, *, step: int,
                fps: float) -> ClipMotion | None:
    """The thumbnails brought to the plate's exposure, their noise level and moving
    blobs (:class:`ClipMotion`); None for fewer than 3 thumbnails or samples that are
    not ``model.sample_indices``."""
    n, h, w = thumbs.shape[:3]
    if n < 3 or len(np.asarray(model.sample_indices)) != len(frames):
        return None
    dt = step / float(fps)
    plate_small = cv2.GaussianBlur(
        cv2.resize(model.plate, (w, h), interpolation=cv2.INTER_AREA), (3, 3), 0)
    levels = plate_levels(thumbs, plate_small)
    # (most pixels show the plate most of the time: a robust spread of the noise)
    pick = np.unique(np.linspace(0, n - 1, min(n, 48)).round().astype(int))
    dev = np.stack([channel_max_diff(levels[t, ::2, ::2], plate_small[::2, ::2]) for t in pick])
    tau = max(8.0, 5.0 * 1.4826 * float(np.median(dev)))
    lags = sorted({max(1, round(s / dt)) for s in LAGS_S})
    close = max(3, int(round(CLOSE * max(h, w))) | 1)
    return ClipMotion(levels, moving_blobs(levels, tau, lags, close), plate_small, tau, dt,
                      int(step))


def retake_from_samples(model, frames: np.ndarray, gains: np.ndarray, got: ClipMotion,
                        flag: np.ndarray, scene: np.ndarray, trusted: np.ndarray, *,
                        left_alone: np.ndarray | None = None, unflag: bool = False):
    """The plate re-taken at full resolution where ``flag`` (h, w) from the samples whose
    nearest thumbnail shows ``scene`` (h, w, 3) there, outside the moving blob, in a
    ``trusted`` (n,) frame (their median, each divided by its gain); pixels
    ``left_alone`` (H, W) and pixels no such sample shows are not touched. Its
    confidence and noise map follow; with ``unflag`` the pixels re-taken are no longer
    never seen (nor still person). ``model`` itself when nothing changes."""
    levels, blobs, tau = got.levels, got.blobs, got.tau
    n, h, w = levels.shape[:3]
    k, hh, ww = frames.shape[:3]
    idx = np.asarray(model.sample_indices)
    size = (ww, hh)
    redo = cv2.resize(flag.view(np.uint8), size, interpolation=cv2.INTER_NEAREST) > 0
    if left_alone is not None:
        redo &= ~left_alone
    # The samples that show the scene's colour there, outside the moving blob (in the
    # nearest thumbnail).
    near = np.clip(np.round(idx / got.step).astype(int), 0, n - 1)
    shows = np.stack([~blobs[i] & (np.abs(levels[i] - scene).max(axis=-1) < tau) & flag
                      & trusted[i] for i in near])
    away = np.stack([cv2.resize(m.view(np.uint8), size, interpolation=cv2.INTER_NEAREST)[redo]
                     > 0 for m in shows])
    have = away.any(axis=0)
    if not have.any():
        return model
    ids = np.flatnonzero(redo.ravel())
    redo.ravel()[ids[~have]] = False
    away = away[:, have]
    vals = frames[:, redo].astype(np.float32) / gains[:, None, :]  # (K, P, 3)
    vals[~away] = np.nan
    from vidcap.video.emptyscene import _nanmedian0

    new = np.clip(_nanmedian0(vals), 0, 255)
    plate = model.plate.copy()
    plate[redo] = new.astype(np.uint8)
    # The noise about the new plate in those samples (clipped as the plate's first
    # estimate clips it: a stray frame must not inflate it).
    l1 = np.minimum(np.abs(vals - new[None]).sum(axis=-1) * gains.mean(axis=1)[:, None],
                    2.0 * model.threshold)
    noise_map = model.noise_map.copy()
    noise_map[redo] = np.nanmean(np.where(away, l1, np.nan), axis=0)
    conf = model.confidence.copy()
    conf[redo] = away.sum(axis=0) / k
    out = replace(model, plate=plate, confidence=conf.astype(np.float32),
                  noise_map=noise_map.astype(np.float32))
    if unflag:
        still = None if model.still_person is None else model.still_person & ~redo
        out = replace(out, never_seen=model.never_seen & ~redo, still_person=still)
    return out
