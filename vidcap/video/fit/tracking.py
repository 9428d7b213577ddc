"""A clip's fit: tracking frame to frame, and the temporal priors over the clip.

:func:`fit_sequence` fits every frame (:func:`~vidcap.video.fit.frame.fit_frame`), warm
from the previous one while its pose still covers the silhouette; where a fresh fit
replaces the track, the frames before it are re-tracked backward from it
(:func:`_retrack_backward`). After the pass two priors refit frames that stand out
from their neighbours: the body's height (:func:`_refit_body_height`, a crouch or
raised arms) and the spread (:func:`_smooth_spread`, the body's yaw).
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Sequence

import numpy as np

from vidcap.body import JOINT_INDEX, JOINT_NAMES, SEGMENT_INDEX
from vidcap.video.fit.crossing import exchange_nearer, legs_heading
from vidcap.video.fit.cuecolours import learn_clip_colours
from vidcap.video.fit.cueframes import as_frame_crops
from vidcap.video.fit.cues import CUE_MODES, ColourModel
from vidcap.video.fit.frame import fit_frame, recross
from vidcap.video.fit.lowbody import refit_low_body
from vidcap.video.fit.normalise import NormalisedMask, normalise_mask
from vidcap.video.fit.options import FitOptions
from vidcap.video.fit.raster import image_angle
from vidcap.video.fit.result import FramePose, Pose2D
from vidcap.video.fit.temporal import arm_path, elbow_bend_signs, label_path
from vidcap.video.fit.temporal import relabel as temporal_relabel
from vidcap.video.masks import MaskStack, frames_with_pixels

#: Normalised silhouettes :func:`fit_sequence` keeps for backward re-tracking (frames)
_NORMS_KEPT = 64
#: Segments a warm start carries forward at their last frame-to-frame turn
#: (:func:`predicted_start`): the legs'. Where two legs meet in the image (the knees
#: passing in a step seen three-quarter on) the silhouette scores a leg that passes the
#: other and one that bounces back alike, and a search starting where the leg was
#: ends wherever the tie falls (half the time on the other knee: the leg then hangs
#: from the wrong hip for the rest of the step); started where the leg is heading, it
#: passes (``fit_sequence(predict=True)``). Arms measured no better (HISTORY.md).
PREDICTED_SEGMENTS = tuple(SEGMENT_INDEX[f"{s}_{p}_leg"] for s in "lr"
                           for p in ("upper", "lower"))
#: S a frame's refit at the body's height (:func:`_refit_body_height`) may lose to its fit
#: at the silhouette's height and still be kept, where the silhouette is the taller (a
#: hand above the head). The model stretched to the hand covers the raised arm about as
#: well as the model at the body's height does, so S tells the two apart by a few
#: boundary pixels: a mask one pixel wider, a gap closed, flips the choice (14_19 3/4,
#: a raise: 0.765 -> 0.700 for PCK 27 -> 80 %). On the tuning renders, true and vidcap's
#: masks, the refit of a taller frame that lost on S (all by under 0.1) was the better
#: by PCK on 59 of 71 frames, the worse on 8 (HISTORY.md). A shorter silhouette (a
#: crouch) keeps the plain comparison: there the refit was the worse more often.
TALLER_TIE = 0.1
#: :func:`fit_sequence`'s ``reinit_every``: a fresh fit challenges the track this many
#: frames after the last one. A track once formed is held until a fresh fit beats it, so
#: which of two nearly equal tracks a clip keeps hangs on single frames: the true masks
#: eroded or dilated by one pixel moved the fit's PCK@0.05 by up to 16 points on a tuning
#: render (``pose2d_accuracy.py --perturb``). Every 5 frames steadied the fit on the
#: renders (over 24 tuning and 26 validation renders of ``silhouettes_real.py`` the PCK
#: spread over the true masks and four one-pixel changes 6.3 -> 5.4 and 6.5 -> 5.7 points)
#: and lifted the held-out renders 88.28 -> 88.59 %, but lost on the real clips
#: (``pose2d_real.py --no-all``, the human body's validation clips 7.30 -> 7.67 % of the
#: height, mmskeleton_clean_jerk 13.7 -> 16.0) and cost ~0.6 ms a frame: 10 stays
#: (benchmarks/HISTORY.md).
REINIT_EVERY = 10


def predicted_start(prev: FramePose, before: FramePose | None,
                    segments=PREDICTED_SEGMENTS) -> FramePose:
    """The warm start for the frame after ``prev``: ``prev`` with ``segments``' angles
    turned on by their turn from ``before`` (the frame before it) to ``prev``.

    Parameters
    ----------
    prev : FramePose
        The last frame's fit.
    before : FramePose or None
        The fit of the frame before ``prev``, when ``prev`` was tracked from it (the
        same limbs under the same names); None: ``prev`` is returned unchanged.
    segments : sequence of int
        Segment indices (:data:`vidcap.body.SEGMENT_NAMES`) to carry forward.

    Returns
    -------
    FramePose
        ``prev`` with those angles ``prev + wrap(prev - before)``, radians in [0, 2 pi).

    Examples
    --------
    >>> import numpy as np
    >>> from vidcap.video.fit.result import FramePose
    >>> def pose(a):
    ...     return FramePose(np.zeros((15, 2)), np.full(10, a), np.ones(10), np.zeros(10),
    ...                      np.zeros(10), 0.5, False, 0.9, True, 100.0)
    >>> out = predicted_start(pose(6.2), pose(6.1), segments=[6])
    >>> round(float(out.angles[6]), 6), round(float(out.angles[0]), 6)
    (0.016815, 6.2)
    """
    if before is None or prev is None:
        return prev
    seg = list(segments)
    turn = np.angle(np.exp(1j * (prev.angles[seg] - before.angles[seg])))  # wrapped
    angles = np.array(prev.angles, dtype=float)
    angles[seg] = np.mod(angles[seg] + turn, 2 * np.pi)
    return dataclasses.replace(prev, angles=angles)


def fit_sequence(masks: np.ndarray | Sequence[np.ndarray], *, tracked: bool = True,
                 progress=None, reinit_every: int = REINIT_EVERY, spread_window: int = 31,
                 spread_jump: float = 0.25, spread_tie: float = 0.01,
                 back_tie: float | None = 0.002, body_window: int = 91,
                 body_tolerance: float = 0.05, body_backward: bool = True,
                 relabel: bool = False, frames=None, cues: str = "all", arm_solve: bool = True,
                 predict: bool = False, crossing: bool = True, colours: ColourModel | None = None,
                 low_body: bool = False, **kw) -> Pose2D:
    """Fit every frame of a silhouette sequence.

    Parameters
    ----------
    masks : numpy.ndarray, shape (F, H, W), bool (or a sequence of (H, W) masks)
        Silhouettes in original-frame pixels.
    tracked : bool
        Warm-start each frame from the previous one when its pose still fits
        (beyond the seed); ``False`` fits every frame independently (the seed).
    progress : callable, optional
        Wraps the frame iterator (e.g. :func:`vidcap.fileio.progress`); called as
        ``progress(iterable, total=F)``.
    reinit_every : int
        In tracked mode a frame this many frames after the last one fitted from
        scratch (a challenge, or a fresh fit that took over a slipping track) is also
        fitted from scratch and the better fit kept (0: never).
    back_tie : float or None
        Tracked mode: when a fresh fit replaces the track at a frame, the frames
        before it (back to where that track began) are refitted warm from the new
        pose, backward, while that improves their similarity by more than
        ``back_tie`` (None: off). A track that started in a wrong pose is thus
        corrected from the frame where the right one was found.
    spread_window, spread_jump, spread_tie
        Temporal prior on the spread (tracked mode, beyond the seed): the spread
        follows the body's yaw, which changes slowly, but a single silhouette
        barely shows it (the torso cylinder looks the same from every side), so
        per-frame estimates wander. After the pass, a frame whose spread is more
        than ``spread_jump`` from the running median over ``spread_window``
        frames (shifted inside the clip at its ends) is refitted with the spread
        fixed at that median (warm from its own pose, from scratch, and within
        a run of such frames warm from the one before), and the best refit
        kept unless its similarity is more than ``spread_tie`` lower. 0 window:
        off. A median passes a steady turn through unchanged (but within half a
        window of the clip's ends, where a turn reads as the first or last
        window's median and the similarity check decides), so the window (about
        1 s at 30 fps) only has to be longer than twice the runs of misread
        frames.
    body_window, body_tolerance
        The body's height in pixels (tracked mode, beyond the seed): the seed
        scales the model to each silhouette's height, which assumes an upright
        body; a crouch makes the silhouette shorter and raised arms make it
        taller. After the pass, the body's height is estimated per frame as the
        median silhouette height of the well-fitted frames (similarity at least
        the window's median; :func:`standing_heights`) within ``body_window`` frames; a frame whose
        silhouette height is more than ``body_tolerance`` (a fraction) from it is
        refitted at that height, warm from the frame before, and the refit kept
        if its similarity is higher (taller silhouettes: within :data:`TALLER_TIE`);
        ``body_backward``: then backward (:func:`_refit_body_backward`). 0 window: off.
    relabel : bool
        Tracked mode: after the priors, relabel the limb pairs over the clip by the
        solve over time (:func:`vidcap.video.fit.temporal.label_path`), so a fresh fit
        whose image-side names came out swapped against its neighbours is outvoted by
        them. Off by default: chunked fits (:mod:`vidcap.video.fit.parallel`) would be
        relabelled chunk by chunk, and held-out PCK with each pair's names matched once
        per clip measured lower with it (RESULTS.md).
    frames : numpy.ndarray, shape (F, H, W, 3), uint8, or FrameCrops, optional
        The colour frames (BGR) or their crops round the silhouettes (:class:`~vidcap.video.
        fit.cueframes.FrameCrops`): with ``cues="all"`` each frame's arms are also placed by
        the frame's cues inside the outline (:mod:`vidcap.video.fit.cues`: skin colour
        learned from this clip's heads, image edges along the limbs' borders).
    cues : {'all', 'outline'}
        ``'outline'``: the seed's silhouette-only score even with ``frames``.
    arm_solve : bool
        Tracked mode with cues: after the priors, each arm's placement per frame among
        the cue search's candidates by the solve over time (:func:`_choose_arms`), so a
        one-frame misplacement is outvoted by its neighbours.
    predict, crossing : bool
        Legs carried on by warm starts (:func:`predicted_start`); passing legs (:mod:`.crossing`).
    low_body : bool
        Tracked mode: a body seated or crouched for seconds probed at larger heights
        (:mod:`vidcap.video.fit.lowbody`; ``vidcap convert --seated``). Off by default.
    colours : ColourModel, optional
        The clip's colours for the cues (default: learned first, :func:`sequence_colours`).
    **kw
        The options of :func:`fit_pose` (``height``, ``refine``, ``spread``, ...), checked once
        here (:class:`~vidcap.video.fit.options.FitOptions`): a misspelling raises TypeError.

    Returns
    -------
    Pose2D
        Frames with an empty silhouette get NaN joints and angles and zero scores.

    Raises
    ------
    ValueError
        If ``masks`` is not a stack of 2-D silhouettes, or an option is out of range.
    TypeError
        If ``kw`` holds a name :func:`fit_pose` does not take.
    """
    options = FitOptions.from_keywords(kw)  # checked once, before any frame
    _check_masks(masks)
    if cues not in CUE_MODES:
        raise ValueError(f"cues must be one of {CUE_MODES}, got {cues!r}")
    n = len(masks)
    if frames is not None and len(frames) != n:
        raise ValueError(f"{len(frames)} frames for {n} silhouettes")
    out = _Frames(n)
    it = range(n) if progress is None else progress(range(n), total=n)
    normalised = _Normalised(masks, options, frames if cues == "all" else None, colours)
    _track(normalised, it, out, tracked=tracked, reinit_every=reinit_every, back_tie=back_tie,
           options=options, predict=predict, crossing=crossing)
    body = _height_passes(masks, out, options, normalised.cues, body_window if tracked else 0,
                          body_tolerance, body_backward, tracked and low_body)
    if tracked and spread_window > 1 and options.spread and n > 2:
        _smooth_spread(masks, spread_window, spread_jump, spread_tie, options, body, out,
                       normalised.cues)
    if tracked and arm_solve and any(c is not None for c in out.candidates):
        _choose_arms(out)
    if tracked and relabel:
        _relabel(out)
    return Pose2D(JOINT_NAMES, out.joints, out.angles, out.fore, out.scores, out.margins,
                  out.spread, out.sim, out.warm, bool(tracked), model_height=out.height)


def sequence_colours(masks, frames, *, n: int | None = None, **kw) -> ColourModel | None:
    """The clip's colour model as :func:`fit_sequence` (``masks``, ``frames=frames``, the
    options ``kw``) learns it (``kw['colours']`` if given; None without cues): what a
    chunked fit learns once and hands to every chunk.

    ``n``: the frames so far of a clip still coming in (a streamed fit; ``masks`` and
    ``frames`` hold at least ``n``): None until the frames the model is learned from
    are all in (:func:`vidcap.video.fit.cuecolours.colour_frames`)."""
    if kw.get("colours") is not None:
        return kw["colours"]
    if frames is None or kw.get("cues", "all") != "all":
        return None
    from vidcap.video.fit.cuecolours import colour_frames

    # ``ensemble`` is fit_ensemble's, which hands the rest on to fit_sequence
    own = (set(inspect.signature(fit_sequence).parameters) - {"kw"}) | {"ensemble"}
    options = FitOptions.from_keywords({k: v for k, v in kw.items() if k not in own})
    samples = colour_frames(frames_with_pixels(masks if n is None else masks[:n]),
                            final=n is None)
    if samples is None:
        return None
    return learn_clip_colours(masks, as_frame_crops(frames, masks, height=options.height),
                              options, frames=samples)


def _relabel(out: _Frames) -> None:
    """The limb pairs relabelled over the clip by :func:`label_path` (in place)."""
    swaps = label_path(out.joints, out.height, out.linked)
    temporal_relabel({"joints": out.joints, "angles": out.angles, "fore": out.fore,
                      "scores": out.scores, "margins": out.margins}, swaps)


def _choose_arms(out: _Frames) -> None:
    """Each arm's elbows and wrists as :func:`arm_path` chooses them, elbows held to
    the way the clip's knees say the body faces (:func:`elbow_bend_signs`), in place;
    the arms' angles follow, the foreshortening stays the frame's."""
    chosen = arm_path(out.joints, out.height, out.candidates,
                      bend_sign=elbow_bend_signs(out.joints, out.spread))
    for s, (elbow, wrist) in chosen.items():
        ie, iw = JOINT_INDEX[f"{s}_elbow"], JOINT_INDEX[f"{s}_wrist"]
        moved = np.flatnonzero((np.abs(out.joints[:, ie] - elbow) > 1e-9).any(-1)
                               | (np.abs(out.joints[:, iw] - wrist) > 1e-9).any(-1))
        if not moved.size:
            continue
        out.joints[moved, ie], out.joints[moved, iw] = elbow[moved], wrist[moved]
        shoulder = out.joints[moved, JOINT_INDEX[f"{s}_shoulder"]]
        up, lo = SEGMENT_INDEX[f"{s}_upper_arm"], SEGMENT_INDEX[f"{s}_lower_arm"]
        out.angles[moved, up] = image_angle(elbow[moved] - shoulder)
        out.angles[moved, lo] = image_angle(wrist[moved] - elbow[moved])


def _check_masks(masks) -> None:
    """A stack (F, H, W), a sequence of (H, W) masks or a MaskStack, else ValueError."""
    if isinstance(masks, MaskStack):
        return
    if isinstance(masks, np.ndarray):
        if masks.ndim != 3:
            raise ValueError(f"masks must be (F, H, W), got shape {masks.shape}")
        return
    for k, m in enumerate(masks):
        if np.ndim(m) != 2:
            raise ValueError(f"mask {k} must be (H, W), got shape {np.shape(m)}")


class _Normalised:
    """Frames' normalised silhouettes, the last ``_NORMS_KEPT`` kept for backward
    re-tracking (bounded memory)."""

    def __init__(self, masks, options: FitOptions, frames=None, colours=None):
        self.masks = masks
        self.size = dict(height=options.height, body_height=options.body_height)
        self.norms: dict[int, NormalisedMask] = {}
        # cut to the silhouettes' boxes, as the pipeline sends them to chunked fits
        self.frames = (None if frames is None
                       else as_frame_crops(frames, masks, height=options.height))
        # the colour model is learned from fits from scratch of a few frames, which the
        # main pass would make again where it challenges the track (the same frames)
        self.scratch: dict = {}
        if self.frames is not None and colours is None:
            colours = learn_clip_colours(masks, self.frames, options, scratch=self.scratch)
        self.colours = colours  # the clip's, the same for every frame

    def cues(self, k: int, norm: NormalisedMask):
        """``fit_frame``'s ``cues`` for frame ``k`` normalised as ``norm`` (None: no
        frames, the outline only)."""
        if self.frames is None:
            return None
        return self.frames.cue_image(k, norm), self.colours

    def __call__(self, k: int) -> NormalisedMask:
        norm = self.norms.get(k)
        if norm is None:
            norm = _normalise_frame(self.masks, k, **self.size)
            if len(self.norms) >= _NORMS_KEPT:
                del self.norms[min(self.norms)]
            self.norms[k] = norm
        return norm

    def has_pixels(self, k: int) -> bool:
        return _frame_has_pixels(self.masks, k)


def _track(normalised: _Normalised, frames, out: _Frames, *, tracked: bool, reinit_every: int,
           back_tie: float | None, options: FitOptions, predict: bool = False,
           crossing: bool = False) -> None:
    """The main pass of :func:`fit_sequence` over ``frames`` (in place into ``out``)."""
    prev = before = None
    start = 0  # first frame of the current track
    last_fresh = -reinit_every  # the last frame fitted from scratch (the first one is)
    for k in frames:
        if not normalised.has_pixels(k):
            prev = None
            start = k + 1
            continue
        # a fresh fit that took over (a slipping track) challenged the track as well
        challenge = bool(reinit_every) and k - last_fresh >= reinit_every
        norm = normalised(k)
        out.bottom[k] = norm.bottom / norm.scale_xy[1] + norm.offset[1]
        start_pose = predicted_start(prev, before) if predict else prev
        # the heading of two tracked frames (a fresh fit's legs may have jumped)
        heading = (legs_heading(prev.joints, before.joints)
                   if crossing and tracked and prev is not None and before is not None
                   and before.warm else None)
        fp = fit_frame(norm, previous=start_pose if tracked else None,
                       challenge=challenge, options=options, cues=normalised.cues(k, norm),
                       heading=heading, scratch=normalised.scratch.pop(k, None))
        if challenge or not fp.warm:
            last_fresh = k
        out.put(k, fp)
        out.linked[k] = fp.warm
        if tracked and prev is not None and not fp.warm and back_tie is not None:
            _retrack_backward(normalised, out, fp, range(k - 1, start - 1, -1), back_tie,
                              options)
            start = k
        # a fresh fit's names need not be prev's (unless its legs were chosen by where
        # they were heading)
        before = prev if fp.warm or heading is not None else None
        prev = fp
    if tracked and crossing and len(out.sim) > 2:
        _cross_backward(normalised, out, options)


def _cross_backward(normalised: _Normalised, out: _Frames, options: FitOptions) -> None:
    """The legs' crossing judged backward (in place): from the clip's end, each frame's
    legs against where the two frames after it say they came from
    (:func:`~vidcap.video.fit.frame.recross`). The forward pass has no heading at a
    track's first frames (a fresh fit hangs the legs from either hip); the frames
    after them have. Only within a track (frames linked by warm starts)."""
    for k in range(len(out.sim) - 3, -1, -1):
        if not (out.linked[k + 1] and out.linked[k + 2]):
            continue  # k, k + 1, k + 2 not one track (a fresh fit's legs may jump)
        heading = legs_heading(out.joints[k + 1], out.joints[k + 2])
        if heading is None or not exchange_nearer(out.joints[k], heading):
            continue  # nothing to try (the pixels are the same as the heading's units)
        fp = out.get(k, height_px=out.height[k])
        new = recross(normalised(k), fp, heading, options=options)
        if new is not fp:
            out.put(k, dataclasses.replace(new, arm_candidates=out.candidates[k]),
                    warm=False)


def _retrack_backward(normalised: _Normalised, out: _Frames, fp: FramePose, frames,
                      back_tie: float, options: FitOptions) -> None:
    """A fresh fit ``fp`` replaced the track: the frames before it were probably tracked
    in a wrong pose too. Carry the new pose backward over ``frames`` while it fits
    them better by more than ``back_tie`` (beyond the seed; in place into ``out``).

    Where the carried pose slips (below the fallback share of the S of the frame after
    it), the frame is fitted as the forward pass would (a fresh fit that beats the
    slipping one takes its place) and kept, and carried on, where that beats the
    stored fit: the frames before a second fresh fit are as wrong as those before
    the first (walk_three_quarter with the plate's never-seen flags: frames 3-13 kept
    crossed legs at S 0.81 where the fresh fit of frame 13 scored 0.93; HISTORY.md).
    """
    back = fp
    no_fallback = dataclasses.replace(options, fallback=0.0)
    for b in frames:
        nb = normalised(b)
        cb = normalised.cues(b, nb)
        fb = fit_frame(nb, previous=back, options=no_fallback, cues=cb)
        if not fb.warm or fb.similarity <= out.sim[b] + back_tie:
            break
        # fit_frame's fallback, only where its outcome matters: the frame fitted again
        # with it (a fresh fit that beats the slipping warm one takes its place, with
        # the track's names in a side view), kept where it beats the stored fit too
        if fb.similarity < options.fallback * back.similarity:
            fb = fit_frame(nb, previous=back, options=options, cues=cb)
            if fb.similarity <= out.sim[b] + back_tie:
                break
        out.put(b, fb)
        out.linked[b + 1], out.linked[b] = fb.warm, False  # b's labels came from b + 1's
        back = fb


class _Frames:
    """:func:`fit_sequence`'s per-frame results as arrays, filled frame by frame."""

    def __init__(self, n: int):
        self.joints = np.full((n, 15, 2), np.nan)
        self.angles = np.full((n, 10), np.nan)
        self.fore = np.full((n, 10), np.nan)
        self.scores = np.zeros((n, 10))
        self.margins = np.zeros((n, 10))
        self.spread = np.full(n, np.nan)
        self.sim = np.zeros(n)
        self.warm = np.zeros(n, dtype=bool)
        self.height = np.full(n, np.nan)  # the body height the model was drawn at, px
        self.bottom = np.full(n, np.nan)  # the silhouette's lowest row, original px
        self.linked = np.zeros(n, dtype=bool)  # labels carried from the frame before
        self.candidates: list = [None] * n  # the cue search's arm candidates

    def put(self, k: int, fp: FramePose, *, warm: bool = True) -> None:
        """Store frame k's fit (``warm``: its warm flag too)."""
        self.joints[k], self.angles[k], self.fore[k] = fp.joints, fp.angles, fp.foreshortening
        self.scores[k], self.margins[k], self.spread[k] = fp.scores, fp.margins, fp.spread
        self.sim[k] = fp.similarity
        self.height[k] = fp.height_px
        self.candidates[k] = fp.arm_candidates
        if warm:
            self.warm[k] = fp.warm

    def get(self, k: int, *, spread: float | None = None, height_px: float = 0.0) -> FramePose:
        """Frame k's stored fit as a :class:`FramePose` to warm-start from."""
        return FramePose(joints=self.joints[k], angles=self.angles[k],
                         foreshortening=self.fore[k], scores=self.scores[k],
                         margins=self.margins[k],
                         spread=float(self.spread[k] if spread is None else spread),
                         crossed=False, similarity=float(self.sim[k]),
                         warm=bool(self.warm[k]), height_px=float(height_px))


def body_heights(heights: np.ndarray, similarity: np.ndarray, window: int) -> np.ndarray:
    """The body's standing height per frame, from the silhouettes' heights.

    Parameters
    ----------
    heights : numpy.ndarray, shape (F,)
        Silhouette height per frame, pixels (NaN: no silhouette).
    similarity : numpy.ndarray, shape (F,)
        S of each frame's fit at that height.
    window : int
        Frames (centred; truncated at the clip's ends).

    Returns
    -------
    numpy.ndarray, shape (F,)
        The median height over the window's well-fitted frames (S at least the
        window's median S): a body whose silhouette is not as tall as it (a
        crouch, raised arms) fits worse at that height, so those frames drop out
        while they are fewer than half the window. NaN where the window has no
        frame.
    """
    h = np.asarray(heights, dtype=float)
    s = np.where(np.isfinite(h), np.asarray(similarity, dtype=float), np.nan)
    half = max(1, int(window) // 2)
    pad = np.full(half, np.nan)

    def windows(x):  # (F, 2 half + 1), NaN beyond the clip
        return np.lib.stride_tricks.sliding_window_view(np.concatenate([pad, x, pad]),
                                                        2 * half + 1)

    out = np.full(h.shape, np.nan)
    have = np.isfinite(windows(s)).any(axis=1)
    if not have.any():
        return out
    sw, hw = windows(s)[have], windows(h)[have]
    good = sw >= np.nanmedian(sw, axis=1, keepdims=True)
    out[have] = np.nanmedian(np.where(good, hw, np.nan), axis=1)
    return out


def _normalise_frame(masks, k: int, *, height: int = 80,
                     body_height: float | None = None) -> NormalisedMask:
    """Frame ``k`` of ``masks`` normalised: a :class:`MaskStack` frame from its crop
    (the same result as from the full frame, without building it)."""
    if isinstance(masks, MaskStack):
        crop, origin = masks.crop(k)
        return normalise_mask(crop, height=height, body_height=body_height, origin=origin)
    return normalise_mask(np.asarray(masks[k], dtype=bool), height=height,
                          body_height=body_height)


def _frame_has_pixels(masks, k: int) -> bool:
    if isinstance(masks, MaskStack):
        return bool(masks.bits[k].any())
    return bool(np.asarray(masks[k]).any())


def standing_heights(height: np.ndarray, joints: np.ndarray, bottom: np.ndarray,
                     window: int) -> np.ndarray:
    """How tall each frame says the body stands, px: the height the model was drawn at
    (the silhouette's), but from the fitted head top down to the silhouette's lowest row
    where a fitted wrist is above the head top (hands raised: the silhouette's top is
    a hand, not the head).

    A clip whose hands stay above the head (a side view of someone reaching up, arms
    crossed overhead) has no frame whose silhouette is as tall as the body, so the
    median of :func:`body_heights` alone takes the raised silhouettes' height and the
    model is drawn a tenth too tall in every frame (pelvis and neck 5-10 % of the
    height off; CMU 14_19 20-22 s seen from the side, a tuning render, HISTORY.md).
    The fit still lines its head up with the silhouette's head, and the head top to
    the floor is the standing height, whatever the arms do. Only silhouettes at least
    as tall as the clip's median are read so (a crouch's hands at its face leave its
    short silhouette as it is), and only where they are most of the window.

    Parameters
    ----------
    height : numpy.ndarray, shape (F,)
        Pixels, NaN without a silhouette.
    joints : numpy.ndarray, shape (F, 15, 2)
        The fitted joints, original pixels.
    bottom : numpy.ndarray, shape (F,)
        The silhouette's lowest row, original pixels.
    window : int
        :func:`body_heights`' window, frames: a raised frame is read so only where
        frames with a hand above the head are at least half of those with a
        silhouette within it (fewer, the median leaves them out already).

    Returns
    -------
    numpy.ndarray, shape (F,)
        ``height``, or ``bottom - head top`` where that is shorter in a raised frame.
    """
    top = joints[:, JOINT_INDEX["head_top"], 1]
    wrist = np.fmin(joints[:, JOINT_INDEX["l_wrist"], 1], joints[:, JOINT_INDEX["r_wrist"], 1])
    if not np.isfinite(height).any():
        return height
    with np.errstate(invalid="ignore"):
        above = wrist < top
        # a hand raised above the head makes the silhouette taller, never shorter: a
        # crouch's hands at its face (the silhouette short already) are left alone
        raised = above & (height >= np.nanmedian(height))
    # where hands are above the head in fewer than half the window's frames, the
    # median leaves those frames out anyway: only a window mostly raised is read so
    half = max(1, int(window)) // 2
    idx = np.arange(len(height))
    lo, hi = np.clip(idx - half, 0, len(height)), np.clip(idx + half + 1, 0, len(height))
    c_above = np.concatenate([[0], np.cumsum(above)])
    c_seen = np.concatenate([[0], np.cumsum(np.isfinite(height))])
    share = (c_above[hi] - c_above[lo]) / np.maximum(c_seen[hi] - c_seen[lo], 1)
    return np.where(raised & (share >= 0.5), np.fmin(height, bottom - top), height)


def _refit_body_height(masks, window, tolerance, options: FitOptions, height, out: _Frames,
                       cues_of=None, backward: bool = True):
    """Refit frames whose silhouette is not as tall as the body (in place); returns
    the body height (px) each refitted frame was fitted at, NaN elsewhere. The body's
    height from each frame's :func:`standing_heights`."""
    body = body_heights(standing_heights(height, out.joints, out.bottom, window), out.sim,
                        window)
    off = np.isfinite(height) & np.isfinite(body) & (np.abs(height / body - 1) > tolerance)
    used = np.full(len(height), np.nan)
    prev = None
    for k in range(len(height)):
        if not np.isfinite(height[k]):
            prev = None
            continue
        if off[k]:
            norm = _normalise_frame(masks, k, height=options.height,
                                    body_height=float(body[k]))
            fp = fit_frame(norm, previous=prev, options=options,
                           cues=None if cues_of is None else cues_of(k, norm))
            if fp.similarity > out.sim[k] - _height_tie(height[k], body[k]):
                out.put(k, fp)
                out.linked[k] = fp.warm
                used[k] = body[k]
                prev = fp
                continue
        prev = out.get(k, height_px=height[k])
    if backward:
        _refit_body_backward(masks, body, off, used, options, out, cues_of, height=height)
    return used


def _height_passes(masks, out: _Frames, options: FitOptions, cues_of, window: int,
                   tolerance: float, backward: bool, low_body: bool) -> np.ndarray:
    """The body-height pass (``window`` > 1, :func:`_refit_body_height`) and the seated
    body's (``low_body``, :func:`_refit_low_body`; off by default: on real clips of
    people standing, whose silhouettes carry shadow or scene, S can favour a larger model
    as much, Pose2Sim cam4) on the tracked fit ``out`` (in place); returns the body's
    height where a frame was refitted at it, px (NaN elsewhere)."""
    n = len(out.sim)
    body = np.full(n, np.nan)
    if window > 1 and n > 2:
        # the heights the main pass scaled the model to (the silhouettes', unless given)
        body = _refit_body_height(masks, window, tolerance, options, out.height.copy(), out,
                                  cues_of, backward=backward)
    if low_body and n > 2:
        low = _refit_low_body(masks, options, out, cues_of, anchored=np.isfinite(body))
        body = np.where(np.isfinite(low), low, body)
    return body


def _refit_low_body(masks, options: FitOptions, out: _Frames, cues_of=None,
                    anchored=None) -> np.ndarray:
    """:func:`vidcap.video.fit.lowbody.refit_low_body` on this clip's fit (in place);
    returns the heights (px) refitted frames were fitted at, NaN elsewhere."""
    def normalise(k, body_height):
        return _normalise_frame(masks, k, height=options.height, body_height=float(body_height))

    def fit(norm, previous, k):
        return fit_frame(norm, previous=previous, options=options,
                         cues=None if cues_of is None else cues_of(k, norm))

    def keep(k, fp):
        if fp is None:
            return out.get(k, height_px=float(out.height[k]))
        out.put(k, fp)
        out.linked[k] = fp.warm
        return fp

    return refit_low_body(len(out.sim), out.sim.copy(), out.height.copy(), normalise, fit, keep,
                          anchored=anchored)


def _refit_body_backward(masks, body, off, used, options: FitOptions, out: _Frames,
                         cues_of=None, height=None) -> None:
    """The body-height refit again, backward (in place): each frame off the body's
    height, warm from the frame after it where that one was fitted at the body's
    height, kept if its S is higher (within :data:`TALLER_TIE` where ``height``, the
    silhouettes' heights (px), shows the silhouette the taller and the forward pass left
    the frame at it). A run of frames whose silhouette is taller than
    the body (a hand raised above the head) is entered forward from a frame fitted at
    the silhouette's height, the model stretched to the hand (neck and shoulders
    high), and the warm refit from there can stay below that stretched fit; the run's
    far end, left at the body's height, carries the right scale back into it."""
    for k in range(len(off) - 2, -1, -1):
        if not (off[k] and np.isfinite(used[k + 1])):
            continue
        norm = _normalise_frame(masks, k, height=options.height, body_height=float(body[k]))
        fp = fit_frame(norm, previous=out.get(k + 1, height_px=float(out.height[k + 1])),
                       options=options, cues=None if cues_of is None else cues_of(k, norm))
        # a frame the forward pass refitted already: the plain comparison
        tie = 0.0 if np.isfinite(used[k]) or height is None else _height_tie(height[k], body[k])
        if fp.similarity > out.sim[k] - tie:
            out.put(k, fp)
            out.linked[k] = fp.warm
            used[k] = body[k]


def _height_tie(silhouette: float, body: float) -> float:
    """S the refit at the body's height may lose by and be kept: :data:`TALLER_TIE` where
    the silhouette (px) is the taller, else 0."""
    return TALLER_TIE if silhouette > body else 0.0


def _window_median(values: np.ndarray, window: int) -> np.ndarray:
    """Running median of ``values`` (N,) over ``window`` samples, the window shifted to
    stay inside the array near its ends rather than padded there: a clip whose first
    frames were misread is judged by the frames after them, not by copies of its own
    first value (as ``median_filter(mode="nearest")`` would). (N,)."""
    n = values.shape[0]
    w = max(1, min(int(window), n))
    first = np.clip(np.arange(n) - w // 2, 0, n - w)
    return np.median(values[first[:, None] + np.arange(w)], axis=1)


def _smooth_spread(masks, window, jump, tie, options: FitOptions, body, out: _Frames,
                   cues_of=None):
    """Refit frames whose spread jumps away from the running median (in place), each at
    the height it was fitted at (``body``: px, NaN for the silhouette's).

    Each such frame is fitted at the median's spread warm from its own pose, from
    scratch (its limbs were found for the other spread), and, inside a run of such
    frames, warm from the frame before once that was refitted (a run is tracked at
    the new spread, as the main pass would have); the best is kept unless it fits
    more than ``tie`` worse than the frame's fit.
    """
    spread = out.spread
    ok = np.isfinite(spread)
    if ok.sum() < 3:
        return
    idx = np.flatnonzero(ok)
    med = np.full_like(spread, np.nan)
    med[idx] = _window_median(spread[idx], window)
    refitted = -2
    for k in np.flatnonzero(ok & (np.abs(spread - med) > jump)):
        at = float(body[k]) if np.isfinite(body[k]) else None
        norm = _normalise_frame(masks, k, height=options.height, body_height=at)
        at_median = dataclasses.replace(options, spread_value=float(med[k]))
        cues = None if cues_of is None else cues_of(k, norm)
        # warm from its own pose, challenged by a fresh fit (which, in a side view,
        # takes the track's limb names, as in the main pass)
        fp = fit_frame(norm, previous=out.get(k, spread=med[k]), challenge=True,
                       options=at_median, cues=cues)
        if refitted == k - 1:
            chained = fit_frame(norm, previous=out.get(k - 1, spread=med[k]), options=at_median,
                                cues=cues)
            if chained.similarity > fp.similarity:
                fp = chained
        if fp.similarity >= out.sim[k] - tie:
            out.put(k, fp, warm=False)
            refitted = k


__all__ = ["PREDICTED_SEGMENTS", "REINIT_EVERY", "body_heights", "fit_sequence", "predicted_start",
           "sequence_colours", "standing_heights"]
