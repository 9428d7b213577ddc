"""The pipeline's proportions stage (``vidcap convert --proportions auto``, issue 27).

After the 2D fit with the seed's proportions, the subject's own are estimated from
the silhouettes (:func:`vidcap.video.fit.proportions.estimate_proportions`) and the
clip fitted again with them; both are cached as one stage, keyed on the silhouettes.
"""

from __future__ import annotations

import numpy as np

from vidcap.video.fit.proportions import (
    ProportionEstimate,
    estimate_proportions,
    fit_keywords,
    to_ankles,
)
from vidcap.video.stagecache import StageCache, stage_key

#: Bumped when the estimator's results change for the same silhouettes.
_VERSION = 3  # 3: the arms measured by length profiles (issue 27)


def proportions_stage(cache: StageCache, k_sil: str, masks, *, jobs: int, per_job: int,
                      progress, fixed: ProportionEstimate | None = None,
                      workers: int | None = None, ensemble: int = 1,
                      seated: bool = False) -> tuple[dict, ProportionEstimate]:
    """The subject's proportions and the 2D pose fitted with them, cached or computed.

    ``fixed``: these proportions (e.g. :data:`vidcap.video.fit.proportions.HUMAN`'s)
    instead of an estimate from the clip. The pose's ``model_height`` is the model's
    (head top to ankles: the feet, :attr:`ProportionEstimate.foot`, left out), which
    the lift reads against the body's height. ``jobs`` and ``per_job`` plan the fit's
    chunks, ``workers`` (default ``jobs``) fit them
    (:func:`vidcap.video.fit.parallel.fit_sequence_chunked`); ``ensemble``: that many fits
    on the silhouettes changed at the outline, joined (:mod:`vidcap.video.fit.ensemble`);
    ``seated``: the fit with the estimate probes a seated body's scale as the first fit
    did (``low_body``, :mod:`vidcap.video.fit.lowbody`).

    Returns
    -------
    pose : dict
        As :func:`vidcap.video.pipeline._pose_stage` returns it.
    estimate : ProportionEstimate
    """
    from vidcap.fileio import progress as bar
    from vidcap.video.fit.parallel import chunk_bounds, fit_sequence_chunked

    key = stage_key("proportions", _VERSION, k_sil,
                    chunk_bounds(len(masks), jobs, per_job=per_job),
                    None if fixed is None else sorted(fixed.factors.items()),
                    # one fit (and not seated) keeps the key it had before the options
                    *(() if ensemble == 1 else (f"ensemble={int(ensemble)}",)),
                    *(("low_body",) if seated else ()))
    names = ("factor_names", "factor_values", "evidence", "seed_similarity")
    hit = cache.load("proportions", key, required=names + ("model_height",))
    if hit is not None:
        factors = dict(zip(hit["factor_names"].astype(str).tolist(),
                           hit["factor_values"].tolist(), strict=True))
        evidence = dict(zip(hit["factor_names"].astype(str).tolist(),
                            hit["evidence"].astype(int).tolist(), strict=True))
        est = ProportionEstimate(factors, evidence, (float(hit["seed_similarity"][0]),
                                                     float(hit["seed_similarity"][1])))
        return {k: v for k, v in hit.items() if k not in names}, est
    est = estimate_proportions(masks) if fixed is None else fixed

    def wrap(it, total):
        return bar(it, total=total, desc="2D pose (own proportions)", unit="frame",
                   enabled=progress)

    pose = fit_sequence_chunked(masks, jobs=jobs, progress=wrap, per_job=per_job,
                                workers=workers, **fit_keywords(est.factors),
                                **({} if ensemble == 1 else {"ensemble": int(ensemble)}),
                                **({"low_body": True} if seated else {}))
    out = {"joints2d": pose.joints2d, "scores": pose.scores, "spread": pose.spread,
           "similarity": pose.similarity,
           "model_height": to_ankles(pose.model_height, {"foot": est.foot})}
    names_in = sorted(est.factors)
    cache.save("proportions", key, **out, factor_names=np.array(names_in, dtype=str),
               factor_values=np.array([est.factors[n] for n in names_in], float),
               evidence=np.array([est.evidence.get(n, 0) for n in names_in], int),
               seed_similarity=np.array(est.similarity, float))
    return out, est


__all__ = ["proportions_stage"]
