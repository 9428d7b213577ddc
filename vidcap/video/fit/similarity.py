"""Similarity of model masks to a silhouette (seed 004 Eq. 3.1-3.3).

With ``I1`` the silhouette and ``I2`` the drawn model (the seed: p counts "pixels in
the silhouette but not in the human model"):

    p = |I1 and not I2| / |I1 or I2|        (3.1, positive error: silhouette missed)
    n = |I2 and not I1| / |I1 or I2|        (3.2, negative error: model overreach)
    S = exp(-p - n) (1 - p)                 (3.3)

S is 1 for a perfect cover and falls faster for missed silhouette than for
overreach (the extra factor ``1 - p``). Everything is computed from three integer
counts (silhouette pixels ``a``, model pixels ``m``, overlap ``i``):
``|I1 or I2| = a + m - i``, ``p = (a - i) / union``, ``n = (m - i) / union``.
"""

from __future__ import annotations

import numpy as np

_exp = np.exp


def similarity_from_counts(a, m, i) -> np.ndarray:
    """Eq. 3.3 from pixel counts (vectorised).

    Parameters
    ----------
    a : array_like of int
        Silhouette pixel count ``|I1|``.
    m : array_like of int
        Model pixel count ``|I2|``.
    i : array_like of int
        Overlap count ``|I1 and I2|``.

    Returns
    -------
    numpy.ndarray of float
        S in [0, 1]; 1 where both images are empty (nothing to disagree about).
        A Python float when ``a``, ``m`` and ``i`` are Python ints.

    Examples
    --------
    >>> float(similarity_from_counts(10, 10, 10))
    1.0
    >>> round(float(similarity_from_counts(4, 2, 2)), 4)  # p = 2/4, n = 0
    0.3033
    """
    if type(a) is int and type(m) is int and type(i) is int:
        # one model (the fitter's hot path): the same arithmetic on Python scalars,
        # without numpy's array set-up. The exponential stays numpy's: math.exp (the C
        # library's) differs from numpy's SIMD exp by an ulp on AVX-512 machines, and
        # the scalar and batch scores of one model must be equal bit for bit
        safe = max(a + m - i, 1)
        p = (a - i) / safe
        return float(_exp(-p - (m - i) / safe)) * (1.0 - p)
    a = np.asarray(a, dtype=np.int64)
    m = np.asarray(m, dtype=np.int64)
    i = np.asarray(i, dtype=np.int64)
    union = a + m - i
    safe = np.maximum(union, 1)
    p = (a - i) / safe
    n = (m - i) / safe
    return np.exp(-p - n) * (1.0 - p)


def similarity(silhouette: np.ndarray, models: np.ndarray) -> np.ndarray:
    """S(silhouette, model) of Eq. 3.3 for a batch of model masks.

    Parameters
    ----------
    silhouette : numpy.ndarray, shape (h, w), bool
        The silhouette ``I1``.
    models : numpy.ndarray, shape (B, h, w) or (h, w), bool
        Candidate model masks ``I2``.

    Returns
    -------
    numpy.ndarray, shape (B,) or ()
        Similarity of every candidate.
    """
    sil = np.asarray(silhouette, dtype=bool)
    models = np.asarray(models, dtype=bool)
    if models.shape[-2:] != sil.shape:
        raise ValueError(f"model masks {models.shape} do not match silhouette {sil.shape}")
    a = np.count_nonzero(sil)
    m = np.count_nonzero(models, axis=(-2, -1))
    i = np.count_nonzero(models & sil, axis=(-2, -1))
    return similarity_from_counts(a, m, i)


__all__ = ["similarity", "similarity_from_counts"]
