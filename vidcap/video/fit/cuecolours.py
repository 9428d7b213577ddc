"""The clip's skin and clothing colours for the cues, learned once before the fit.

The cues' skin likelihood (:class:`vidcap.video.fit.cues.ColourModel`) is learned from
the person's head (skin) and torso core (clothing). Learned frame by frame as the fit
went (the model of frame k holding frames 0..k), every frame of a chunked fit
(:mod:`vidcap.video.fit.parallel`) read another model than in one serial pass (a chunk
knew only its own frames), and the fits differed on half of the frames. Here the model
is one for the whole clip, learned before any frame is fitted from a few frames of the
clip's start (:func:`colour_frames`: frames with a silhouette, the first
:data:`COLOUR_SPAN` of them, every :data:`COLOUR_STEP`-th), each fitted from scratch (a
fit that depends on that frame and the frames sampled before it only), and handed to
every chunk. Those are the frames where a tracked fit challenges its track with a fit
from scratch (:data:`vidcap.video.fit.tracking.REINIT_EVERY` apart from the first), so
one serial fit makes those fits once (:func:`learn_clip_colours`' ``scratch``). The
start of the clip, so a streamed fit (the pipeline's, chunks sent while later frames
are still being extracted) has it as soon as its first chunk is ready (chunks hold at
least 60 frames).
"""

from __future__ import annotations

import numpy as np

from vidcap.video.fit.cues import (
    ColourModel,
    chroma_bins,
    cue_maps,
    learn_colours,
    refine_arms_with_cues,
)
from vidcap.video.fit.engine import _MaskEngine
from vidcap.video.fit.frame import fit_normalised
from vidcap.video.fit.normalise import normalise_mask
from vidcap.video.fit.options import FitOptions
from vidcap.video.masks import frames_with_pixels

#: The model is learned from the clip's first this many frames with a silhouette.
COLOUR_SPAN = 60
#: ... every this many of them (each costs a fit from scratch, ~5 ms, which the main
#: pass of a serial fit takes on where it challenges the track, and a cue search over
#: every arm angle, ~3 ms): tracking.REINIT_EVERY, the challenges' spacing. (Ten frames
#: evenly spread, none shared with the main pass, cost the 60-frame walk of
#: ``pose2d_speed.py`` 1.5 ms a frame.)
COLOUR_STEP = 10
#: The most frames the model is learned from.
COLOUR_SAMPLES = -(-COLOUR_SPAN // COLOUR_STEP)


def colour_frames(has_pixels: np.ndarray, *, final: bool = True) -> np.ndarray | None:
    """The frames the clip's colour model is learned from.

    Parameters
    ----------
    has_pixels : numpy.ndarray, shape (N,), bool
        Which of the clip's frames so far have a silhouette
        (:func:`vidcap.video.masks.frames_with_pixels`).
    final : bool
        ``has_pixels`` covers the whole clip. Otherwise (a streamed fit, frames still to
        come) None is returned until :data:`COLOUR_SPAN` frames with a silhouette are in.

    Returns
    -------
    numpy.ndarray of int or None
        Up to :data:`COLOUR_SAMPLES` frame indices, ascending: every
        :data:`COLOUR_STEP`-th of the first :data:`COLOUR_SPAN` frames with a silhouette,
        from the first (empty: none has one).
    """
    idx = np.flatnonzero(np.asarray(has_pixels, bool))[:COLOUR_SPAN]
    if len(idx) < COLOUR_SPAN and not final:
        return None
    return idx[::COLOUR_STEP]


def learn_clip_colours(masks, crops, options: FitOptions, frames=None,
                       scratch: dict | None = None) -> ColourModel:
    """The clip's :class:`~vidcap.video.fit.cues.ColourModel`.

    Parameters
    ----------
    masks : numpy.ndarray, shape (F, H, W), bool, or MaskStack
        The clip's silhouettes (or its first frames, at least up to the last of
        ``frames``).
    crops : FrameCrops
        Their colour crops (:class:`vidcap.video.fit.cueframes.FrameCrops`).
    options : FitOptions
        The fit's (normalised height, body).
    frames : sequence of int, optional
        The frames to learn from (default :func:`colour_frames` of the whole clip).
    scratch : dict, optional
        Filled with each of those frames' fit from scratch, ``{k: (state, crossed)}``
        (:func:`vidcap.video.fit.frame.fit_normalised`'s), for the fit of the clip to
        use again (:func:`vidcap.video.fit.frame.fit_frame`'s ``scratch``).

    Returns
    -------
    ColourModel
        Learned from each frame's fit from scratch, its arms placed by the cues with
        the model of the frames before it: its head's and torso's cores, the arms left
        out (:func:`vidcap.video.fit.cues.learn_colours`). Not learned (no skin cue)
        if no frame has a silhouette.
    """
    if frames is None:
        frames = colour_frames(frames_with_pixels(masks))
    model = ColourModel()
    for k in frames:  # in clip order, each placed by the model of those before it
        # a MaskStack frame from its crop, as the fit normalises it
        mask, origin = (masks.crop(int(k)) if hasattr(masks, "crop")
                        else (np.asarray(masks[k]), (0, 0)))
        norm = normalise_mask(np.asarray(mask, bool), height=options.height,
                              body_height=options.body_height, origin=origin)
        eng = _MaskEngine(norm, caps=options.caps, body=options.body, foot=options.foot)
        st, crossed, _ = fit_normalised(eng, options=options)
        if scratch is not None:
            scratch[int(k)] = (st, crossed)
        image = crops.cue_image(int(k), norm)
        bins = chroma_bins(image)
        # the arms placed by the cues first: an arm across the torso, which the outline
        # does not show, is then left out of the clothing (the first frame: by a model of
        # its own colours alone)
        placed_by = model
        if not model.learned:
            placed_by = ColourModel()
            learn_colours(placed_by, bins, eng, st)
        st = refine_arms_with_cues(eng, st, cue_maps(image, eng.sil, placed_by))
        learn_colours(model, bins, eng, st)
    return model


__all__ = ["COLOUR_SAMPLES", "COLOUR_SPAN", "COLOUR_STEP", "colour_frames",
           "learn_clip_colours"]
