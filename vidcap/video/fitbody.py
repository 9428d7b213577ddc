"""The body the 2D fit draws for ``vidcap convert``'s options, and the one the 3D stage
gets: the proportions (``--proportions``), the ensemble's size (``--ensemble``) and the
camera's perspective (``--camera``: :mod:`vidcap.video.fit.perspective`).

A known body (the seed's, a real adult's) is drawn as the camera images it; an estimated
one is measured on the image, warped already, so the fit takes it as measured and the 3D
stage gets it un-warped.
"""

from __future__ import annotations

import dataclasses

from vidcap.video.fit.perspective import inverse_k, perspective_factors
from vidcap.video.fit.proportions import FOOT, fit_keywords, human_proportions

__all__ = ["ankle_share", "fit_keywords_for", "unwarped_estimate"]


def fit_keywords_for(proportions: str, ensemble: int = 1, perspective: float = 0.0,
                     seated: bool = False) -> dict:
    """The 2D fit's ``body`` and ``foot`` for a body known before the fit
    (``proportions='human'``: :func:`vidcap.video.fit.proportions.human_proportions`;
    none for the seed's, the fit's default, and for ``'auto'``, estimated after a first
    fit), and its ``ensemble`` when more than one fit (one: no key, as before ensembles;
    ``'auto'``: one, its first fit is replaced by the fit with the estimate). A camera's
    ``perspective`` (k, not 0) warps a known body as the camera images it
    (:func:`vidcap.video.fit.perspective.perspective_factors`). ``seated``: the body's
    scale probed where it sits or crouches for seconds (``low_body``,
    :mod:`vidcap.video.fit.lowbody`)."""
    kw = {} if ensemble == 1 or proportions == "auto" else {"ensemble": int(ensemble)}
    if seated:
        kw["low_body"] = True
    if proportions == "auto" or (proportions == "seed" and perspective == 0):
        return kw
    factors = human_proportions().factors if proportions == "human" else {}
    return {**fit_keywords(perspective_factors(factors, perspective)), **kw}


def unwarped_estimate(estimate, perspective: float):
    """``estimate`` (a :class:`vidcap.video.fit.proportions.ProportionEstimate` measured on
    the image) with its factors as the body's own for a camera's ``perspective`` k."""
    if not perspective:
        return estimate
    return dataclasses.replace(estimate, factors=perspective_factors(
        estimate.factors, inverse_k(perspective)))


def ankle_share(estimate) -> float:
    """The ankles' share of the standing height of the body ``estimate`` gives (None, the
    seed's body: 1)."""
    return 1.0 if estimate is None else float(estimate.factors.get(FOOT, 1.0))
