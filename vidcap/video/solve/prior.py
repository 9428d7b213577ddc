"""A pose prior learned from motion capture: which limb directions people take.

Where the image says little (a segment near the image plane under 2D noise, a limb
whose two reflections fit the 2D equally), the solve's other terms leave the pose
free within the joint limits; this prior pulls it toward poses people take. The
features of a pose are the unit directions of the nine non-torso segments (head,
upper and lower arms and legs) in the torso's frame (:func:`features`, 27 numbers,
independent of where the body faces); the prior is a Gaussian on them per chain
(head; each arm; each leg: 3 and 6 numbers), its residual ``W (f - mean)`` with
``W^T W`` the chain's precision, so it adds 27 rows to each frame's residuals
(:mod:`vidcap.video.solve.residuals`) with a Jacobian read from the kinematic one.

The table (``vidcap/data/pose_prior.npz``: mean, factor and the list of trials it was
learned from) is built by ``benchmarks/build_pose_prior.py`` from CMU motion capture
trials (subjects 1, 2, 3, 5 and 6; never the trials or subjects the benchmarks
validate on), mirrored left/right so the prior has no side.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from vidcap.body import SEGMENT_JOINTS

#: The segments whose direction is a feature (all but the torso), and the chains the
#: prior couples: (start, stop) columns of the 27 features.
PRIOR_SEGMENTS = np.arange(1, 10)
CHAINS = ((0, 3), (3, 9), (9, 15), (15, 21), (21, 27))
N_FEATURES = 27
TABLE = Path(__file__).resolve().parents[2] / "data" / "pose_prior.npz"


def _directions(joints, root, lengths):
    seg = SEGMENT_JOINTS[PRIOR_SEGMENTS]
    vec = (joints[..., seg[:, 1], :] - joints[..., seg[:, 0], :]) / lengths[PRIOR_SEGMENTS, None]
    return vec @ root  # R^T v for each segment, (..., 9, 3)


def features(joints, root, lengths) -> np.ndarray:
    """Unit directions (..., 27) of the segments :data:`PRIOR_SEGMENTS` in the torso frame.

    Parameters
    ----------
    joints : (..., 15, 3) world joints, metres.
    root : (..., 3, 3) the torso's world rotation.
    lengths : (10,) segment lengths, metres (the solve's bones are rigid, so dividing
        by the length gives unit vectors).
    """
    local = _directions(joints, root, lengths)
    return local.reshape(local.shape[:-2] + (N_FEATURES,))


def feature_jacobian(jac_joints, root, lengths) -> np.ndarray:
    """d(features)/d(params) (F, 27, 24) from the kinematic Jacobian (F, 15, 3, 24).

    A turn of the torso moves every segment with it, so only the swings change the
    features: ``R^T dv / length`` with the torso columns (position, yaw, pitch, roll)
    zero."""
    seg = SEGMENT_JOINTS[PRIOR_SEGMENTS]
    dv = (jac_joints[:, seg[:, 1]] - jac_joints[:, seg[:, 0]]) / lengths[PRIOR_SEGMENTS, None, None]
    out = np.swapaxes(root, 1, 2)[:, None] @ dv  # R^T dv, (F, 9, 3, 24)
    out[..., :6] = 0.0
    return out.reshape(out.shape[0], N_FEATURES, -1)


@lru_cache(maxsize=1)
def load_prior() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The shipped prior, a mixture of K Gaussians per chain: means (K, 27), factors
    (K, 27, 27) (block diagonal by :data:`CHAINS`, ``W^T W`` the precision) and
    constants (K, 5) (``-2 log weight + log det cov`` of each chain's component, less
    the chain's smallest)."""
    with np.load(TABLE) as t:
        return t["means"].copy(), t["factors"].copy(), t["consts"].copy()


#: Residual rows of the prior per frame: the 27 whitened features and one per chain
#: for the chosen component's constant.
N_ROWS = N_FEATURES + len(CHAINS)


#: Cauchy scale of the prior, in squared whitened distance (None: Gaussian): a pose far
#: from every component the training poses took (a jumping jack's spread legs) is
#: pulled less than a Gaussian would. 9 of 4, 9 and none on the tuning clips.
ROBUST_TAU2 = 9.0


def _robust(z, tau2):
    """Scale s (...) of whitened misfits z (..., n) so |s z|^2 = tau2 log(1 + |z|^2 / tau2),
    and ds/d(|z|^2) / s."""
    x = np.sum(z * z, -1)
    xs = np.maximum(x, 1e-12)
    rho = tau2 * np.log1p(xs / tau2)
    s = np.sqrt(rho / xs)
    # d log s / dx = 0.5 (rho'/rho - 1/x), rho' = 1 / (1 + x / tau2)
    g = 0.5 * (1.0 / (1.0 + xs / tau2) / np.maximum(rho, 1e-300) - 1.0 / xs)
    return np.where(x > 1e-12, s, 1.0), np.where(x > 1e-12, g, -0.5 / tau2)


def prior_residuals(feats, means, factors, consts, *, jacobian=None, out=None):
    """Residuals (..., 32) of features (..., 27) under the mixture: per chain the
    component nearest in cost (``|W (f - mean)|^2 + const``), its whitened misfit and
    sqrt(const). With ``jacobian`` (F, 27, 24) d(features)/d(params), also returns
    the residuals' Jacobian (F, 32, 24) (the component held), written into ``out``
    (F, 32, 24) when given, whose constants' rows must hold zeros."""
    res = np.empty(feats.shape[:-1] + (N_ROWS,))
    jac = None
    if jacobian is not None:
        jac = np.zeros((jacobian.shape[0], N_ROWS, jacobian.shape[-1])) if out is None else out
    K = len(means)
    for c, (a, b) in enumerate(CHAINS):
        w = factors[:, a:b, a:b]  # (K, n, n)
        # W (f - mean) for every component at once: one product with the stacked
        # factors (the per-component einsum over the frames was 5x slower)
        wm = np.einsum("kij,kj->ki", w, means[:, a:b])
        z = (feats[..., a:b] @ w.reshape(K * (b - a), b - a).T).reshape(
            feats.shape[:-1] + (K, b - a)) - wm  # (..., K, n)
        best = np.argmin(np.sum(z * z, -1) + consts[:, c], axis=-1)  # (...)
        zb = np.take_along_axis(z, best[..., None, None], axis=-2)[..., 0, :]
        res[..., N_FEATURES + c] = np.sqrt(consts[best, c])
        jz = None if jac is None else w[best] @ jacobian[:, a:b]
        if ROBUST_TAU2:
            sc, g = _robust(zb, ROBUST_TAU2)
            if jz is not None:  # d(s z) = s dz + z s g 2 z^T dz
                jz = sc[:, None, None] * (jz + 2.0 * g[:, None, None] * zb[:, :, None]
                                          * (zb[:, None, :] @ jz))
            zb = zb * sc[..., None]
        res[..., a:b] = zb
        if jac is not None:
            jac[:, a:b] = jz
    return res if jac is None else (res, jac)


def _chain_gmm(x, k, rng, iters=60, reg=1e-6):
    """EM for a k-component Gaussian mixture of x (N, n) from k random points: weights,
    means, covs and the mean log-likelihood."""
    n_pts, n = x.shape
    means = x[rng.choice(n_pts, k, replace=False)]
    covs = np.repeat(np.cov(x, rowvar=False)[None], k, axis=0)
    w = np.full(k, 1.0 / k)
    ll = -np.inf
    for _ in range(iters):
        inv = np.linalg.inv(covs)
        d = x[:, None] - means
        maha = np.einsum("nki,kij,nkj->nk", d, inv, d)
        logp = np.log(w) - 0.5 * (maha + np.linalg.slogdet(covs)[1] + n * np.log(2 * np.pi))
        top = logp.max(axis=1, keepdims=True)
        r = np.exp(logp - top)
        tot = r.sum(axis=1, keepdims=True)
        ll = float(np.mean(np.log(tot) + top))
        r /= tot
        nk = r.sum(axis=0) + 1e-9
        w = nk / n_pts
        means = (r.T @ x) / nk[:, None]
        d = x[:, None] - means
        covs = np.einsum("nk,nki,nkj->kij", r, d, d) / nk[:, None, None] + reg * np.eye(n)
    return w, means, covs, ll


def fit_prior(feats, *, k: int = 1, floor: float = 0.05, seed: int = 0, restarts: int = 1):
    """Means (k, 27), factors (k, 27, 27), constants (k, 5) of a k-component Gaussian
    mixture of features (N, 27) per chain (EM; k = 1 a single Gaussian).

    ``floor`` (unit-vector components) bounds every standard deviation from below, so
    directions the training poses never took are unlikely, not impossible. EM runs from
    ``restarts`` seedings; the most likely fit is kept."""
    f = np.asarray(feats, float)
    rng = np.random.default_rng(seed)
    means = np.zeros((k, N_FEATURES))
    factors = np.zeros((k, N_FEATURES, N_FEATURES))
    consts = np.zeros((k, len(CHAINS)))
    for c, (a, b) in enumerate(CHAINS):
        if k == 1:
            w, mu, cov = np.ones(1), f[None, :, a:b].mean(1), np.cov(f[:, a:b], rowvar=False)[None]
        else:
            fits = [_chain_gmm(f[:, a:b], k, rng) for _ in range(restarts)]
            w, mu, cov, _ = max(fits, key=lambda fit: fit[3])
        cov = cov + floor ** 2 * np.eye(b - a)
        means[:, a:b] = mu
        # W = L^-1 with cov = L L^T: |W x|^2 = x^T cov^-1 x
        factors[:, a:b, a:b] = np.linalg.inv(np.linalg.cholesky(cov))
        const = -2.0 * np.log(w) + np.linalg.slogdet(cov)[1]
        consts[:, c] = const - const.min()
    return means, factors, consts
