"""The person in the plate stage's samples by one graph cut over space and time
(issue 26, Build 2).

The appearance pass (:mod:`vidcap.video.appearance`) labels, per sample, the person
in the area where the plate is a guess from a colour log-likelihood ratio. Here
that labelling is one minimum cut over all samples at once: the ratio (clipped) is
the unary term, a contrast-sensitive cost joins 4-neighbours within a sample and a
fixed one joins a pixel's labels in neighbouring samples (a limb that is person in
sample k is likely person in k +- 1). Used when
``vidcap.video.appearance.SAMPLE_CUT`` is set (off by default: measured mixed, see
there).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["cut_samples"]

#: The pull between a pixel's labels in neighbouring samples, and the smoothness
#: within a sample.
SAMPLE_TIME, SAMPLE_SMOOTH = 0.5, 1.0
#: The log-ratio is clipped to +- this.
COLOUR_CLIP = 3.0


def _contrast_weights(img: np.ndarray, smooth: float):
    """Contrast-sensitive weights to the right and below, (..., h, w) each, of images
    (..., h, w, 3): ``smooth * exp(-beta * |I_p - I_q|^2)``, ``beta`` from the
    mean squared difference (Rother et al. 2004)."""
    fi = img.astype(np.float32)
    dx = np.square(fi[..., :, 1:, :] - fi[..., :, :-1, :]).sum(axis=-1)
    dy = np.square(fi[..., 1:, :, :] - fi[..., :-1, :, :]).sum(axis=-1)
    beta = 1.0 / max(float(dx.mean() + dy.mean()), 1e-6)
    wx = np.zeros(fi.shape[:-1], np.float64)
    wy = np.zeros(fi.shape[:-1], np.float64)
    wx[..., :, :-1] = smooth * np.exp(-beta * dx)
    wy[..., :-1, :] = smooth * np.exp(-beta * dy)
    return wx, wy


def cut_samples(small: np.ndarray, llr: np.ndarray, uncertain: np.ndarray, *,
                clip: float = COLOUR_CLIP) -> np.ndarray:
    """The person in the samples by one minimum cut over space and time.

    Parameters
    ----------
    small : numpy.ndarray, shape (K, h, w, 3)
        The samples (gain-divided colours) in time order.
    llr : numpy.ndarray, shape (K, h, w), float32
        Log-likelihood ratio person / scene per pixel (clipped to +- ``clip``).
    uncertain : numpy.ndarray, shape (h, w), bool
        Where the labels are wanted; the cut runs over its bounding box (and a
        margin), elsewhere the sign of ``llr`` is returned.

    Returns
    -------
    numpy.ndarray, shape (K, h, w), bool
        Person.
    """
    import maxflow

    out = llr > 0
    if not uncertain.any():
        return out
    k, h, w = llr.shape
    x, y, bw, bh = cv2.boundingRect(uncertain.view(np.uint8))
    m = 3
    x0, y0, x1, y1 = max(0, x - m), max(0, y - m), min(w, x + bw + m), min(h, y + bh + m)
    e = np.clip(llr[:, y0:y1, x0:x1], -clip, clip).astype(np.float64)
    wx, wy = _contrast_weights(small[:, y0:y1, x0:x1], SAMPLE_SMOOTH)
    g = maxflow.Graph[float]()
    ids = g.add_grid_nodes(e.shape)
    g.add_grid_edges(ids, weights=wx, structure=_T_RIGHT, symmetric=True)
    g.add_grid_edges(ids, weights=wy, structure=_T_DOWN, symmetric=True)
    if k > 1 and SAMPLE_TIME > 0:
        g.add_grid_edges(ids, weights=SAMPLE_TIME, structure=_T_NEXT, symmetric=True)
    g.add_grid_tedges(ids, np.maximum(e, 0), np.maximum(-e, 0))
    g.maxflow()
    out[:, y0:y1, x0:x1] = ~g.get_grid_segments(ids)
    return out


_T_RIGHT = np.zeros((3, 3, 3))
_T_RIGHT[1, 1, 2] = 1
_T_DOWN = np.zeros((3, 3, 3))
_T_DOWN[1, 2, 1] = 1
_T_NEXT = np.zeros((3, 3, 3))
_T_NEXT[2, 1, 1] = 1
