"""Refitting the 2D pose of the frames whose silhouettes changed (issue 26, item 5).

When the user draws a region in the annotate page, the silhouettes are extracted
again (a couple of milliseconds a frame) but only some frames come out different: a
lamp the person never touched changes nothing, a person box in one frame changes that
frame and the few after it until the person's blob is followed as before. The 2D fit
(tens of milliseconds a frame) is redone only around those frames.

The tracked fit carries each frame's pose into the next and challenges it with a fresh
fit every ``reinit_every`` (10) frames, so a window is refitted as the chunked fit
does (:mod:`vidcap.video.fit.parallel`): it starts ``overlap`` frames early at a
multiple of 10, from scratch, and runs ``settle`` frames past the last changed frame
so the track is back where the old one was; its limb labels are matched to the old
fit's over the unchanged frames it covers (:func:`vidcap.video.fit.parallel.reconcile_labels`).
The result is close to, not always identical with, a fit of the whole clip (which
``vidcap convert`` does when the silhouettes change): when the windows would cover
most of the clip, the whole clip is refitted instead.
"""

from __future__ import annotations

import numpy as np

from vidcap.video.masks import MaskStack

#: The per-frame arrays of the pipeline's 2D pose (``pose2d`` stage cache entry).
POSE_KEYS = ("joints2d", "scores", "similarity", "spread", "model_height")
#: Windows covering more than this share of the clip: refit the whole clip.
WHOLE_CLIP_SHARE = 0.5


def changed_frames(old: MaskStack, new: MaskStack) -> np.ndarray:
    """(F,) bool: the frames whose masks differ (a different frame count: all)."""
    n = len(new)
    if len(old) != n or old.frame_shape != new.frame_shape:
        return np.ones(n, bool)
    same_box = (old.boxes == new.boxes).all(axis=1)
    out = ~same_box
    for k in np.flatnonzero(same_box):
        out[k] = not np.array_equal(old.bits[k], new.bits[k])
    return out


def refit_windows(changed, *, align: int = 10, overlap: int = 10,
                  settle: int = 10) -> list[tuple[int, int, int]]:
    """The windows to refit around the ``changed`` frames (F,) bool.

    Returns
    -------
    list of (start, begin, end)
        Fit frames ``start:end``, keep frames ``begin:end`` (``begin`` a multiple of
        ``align``, ``start = begin - overlap`` clipped at 0, ``end`` ``settle``
        frames past the last changed frame of the window, clipped at F); windows
        that would touch are merged.
    """
    changed = np.asarray(changed, bool)
    n = len(changed)
    out: list[list[int]] = []
    for k in np.flatnonzero(changed):
        begin = (int(k) // align) * align
        end = min(n, int(k) + 1 + settle)
        if out and begin <= out[-1][2] + overlap:
            out[-1][2] = max(out[-1][2], end)
        else:
            out.append([max(0, begin - overlap), begin, end])
    return [tuple(w) for w in out]


def _swap(arrays: dict, swaps: dict) -> dict:
    """``arrays`` (POSE_KEYS) with the limb pairs ``swaps`` names relabelled."""
    from vidcap.video.fit.labels import LIMB_PAIRS

    out = {k: np.array(v, copy=True) for k, v in arrays.items()}
    for name, ((jl, sl), (jr, sr)) in LIMB_PAIRS.items():
        if swaps.get(name):
            out["joints2d"][:, jl + jr] = arrays["joints2d"][:, jr + jl]
            out["scores"][:, sl + sr] = arrays["scores"][:, sr + sl]
    return out


def refit_changed(masks: MaskStack, pose: dict, changed, *, progress=None,
                  whole_share: float = WHOLE_CLIP_SHARE, fit_kw: dict | None = None) -> dict:
    """The 2D pose ``pose`` refitted (in this process) where the silhouettes changed.

    Parameters
    ----------
    masks : MaskStack, shape (F, H, W)
        The new silhouettes.
    pose : dict
        The old fit: :data:`POSE_KEYS` arrays of F frames (``joints2d`` (F, 15, 2)
        pixels, image-side limb names; ``scores`` (F, 10); ``similarity``, ``spread``,
        ``model_height`` (F,)).
    changed : array_like of bool, shape (F,)
        Frames whose silhouettes changed (:func:`changed_frames`).
    progress : callable, optional
        ``progress(done, total)`` in frames as the fit goes.
    whole_share : float
        When the refit windows would cover more than this share of the clip, the
        whole clip is refitted (as ``vidcap convert`` would).
    fit_kw : dict, optional
        The body the old fit used (``body`` and ``foot`` of :func:`fit_sequence`, e.g.
        :func:`vidcap.video.fit.proportions.fit_keywords` of the run's proportions;
        default: the seed's); ``model_height`` is then head top to ankles, as the
        pipeline keeps it.

    Returns
    -------
    dict
        The new fit (same keys and shapes; new arrays, ``pose`` is not modified).
    """
    from vidcap.video.fit.parallel import reconcile_labels
    from vidcap.video.fit.proportions import to_ankles
    from vidcap.video.fit.tracking import fit_sequence

    changed = np.asarray(changed, bool)
    n = len(masks)
    out = {k: np.array(pose[k], copy=True) for k in POSE_KEYS}
    windows = refit_windows(changed)
    total = sum(e - s for s, _b, e in windows)
    if total > whole_share * n:
        windows, total = [(0, 0, n)], n
    done = 0
    for start, begin, end in windows:
        def report(it, total=None, base=done, grand=total):  # noqa: ARG001 - fit_sequence's
            for i, k in enumerate(it):
                yield k
                if progress is not None:
                    progress(base + i + 1, grand)

        new = fit_sequence(masks[start:end], progress=report, **(fit_kw or {})).arrays()
        new = {k: np.asarray(new[k]) for k in POSE_KEYS}
        new["model_height"] = to_ankles(new["model_height"], fit_kw)
        same = ~changed[start:end]  # frames the old fit saw the same silhouette in
        if same.any() and (start, end) != (0, n):
            new = _swap(new, reconcile_labels({"joints2d": out["joints2d"][start:end][same]},
                                              {"joints2d": new["joints2d"][same]}))
        for k in POSE_KEYS:
            out[k][begin:end] = new[k][begin - start:]
        done += end - start
    return out


__all__ = ["POSE_KEYS", "changed_frames", "refit_changed", "refit_windows"]
