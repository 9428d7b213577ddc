"""Re-solving only the frames an annotation edit reaches (the annotate app, issue 33).

An edit (a depth sign, an orientation, a joint, the sides) changes what the user's
events say on a run of frames. Those frames, and ``pad`` frames either side, are
solved again (:func:`vidcap.video.solve.clip.solve_problem`) with the frames just outside
held at the clip's current solution, so the motion stays continuous across the
window's edges; a run longer than ``max_frames`` is re-solved from its start for
that many frames (the rest waits for the whole clip's solve, which the app runs in
the background).
"""

from __future__ import annotations

import numpy as np

from vidcap.body import BodyModel
from vidcap.video.solve.clip import (
    FITTED_CONTACT_FLOOR,
    FITTED_HEADING_WEIGHT,
    FITTED_NOISE_FLOOR,
    FITTED_SIGN_WEIGHT,
    make_problem,
    solve_problem,
    warm_start,
)
from vidcap.video.solve.residuals import segment_zeta

#: Frames held either side of a window (the second differences reach two frames).
_HOLD = 2


def edit_window(changed, *, pad: int = 10, max_frames: int = 60) -> tuple[int, int] | None:
    """Frames [start, stop) to re-solve for the frames (F,) bool an edit changed."""
    idx = np.flatnonzero(np.asarray(changed, bool))
    if not idx.size:
        return None
    F = len(changed)
    first = int(idx[0])
    last = min(int(idx[-1]), first + max_frames - 1)
    return max(0, first - pad - _HOLD), min(F, last + 1 + pad + _HOLD)


def resolve_window(params, joints3d, window, joints2d, *, scale, fps: float, body: BodyModel,
                   yaw, prior_signs, hard_signs, segment_scale=None, principal_point=None,
                   contact=None, yaw_sigma=0.5, confidence=None, max_iter: int = 8):
    """The clip's poses with ``window`` solved again.

    Parameters
    ----------
    params : numpy.ndarray, shape (F, 24)
        The clip's current solution (:attr:`vidcap.video.solve.ClipSolve.params`).
    joints3d : numpy.ndarray, shape (F, 15, 3)
        Its joints.
    window : (int, int)
        Frames [start, stop) (:func:`edit_window`).
    joints2d, scale, yaw, prior_signs, hard_signs, segment_scale, principal_point,
    contact, yaw_sigma, confidence :
        The whole clip's inputs, as :func:`vidcap.video.solve.solve_clip` takes them
        (``scale``/``segment_scale``/``yaw_sigma`` one value or per frame).

    Returns
    -------
    params : numpy.ndarray, shape (F, 24)
    joints3d : numpy.ndarray, shape (F, 15, 3)
    signs : numpy.ndarray of int8, shape (stop - start, 10)
        The window's solved depth signs.
    """
    a, b = window
    F = len(params)
    sl = slice(a, b)

    def cut(x):
        x = np.asarray(x) if x is not None else None
        return x[sl] if x is not None and x.ndim and len(x) == F else x

    pb = make_problem(joints2d[sl], scale=cut(scale), fps=fps, body=body, yaw=cut(yaw),
                      prior_signs=cut(prior_signs), hard_signs=cut(hard_signs),
                      yaw_sigma=cut(yaw_sigma), segment_scale=cut(segment_scale),
                      confidence=cut(confidence), noise_floor=FITTED_NOISE_FLOOR,
                      contact_floor=FITTED_CONTACT_FLOOR,
                      sign_weight=FITTED_SIGN_WEIGHT, heading_weight=FITTED_HEADING_WEIGHT,
                      principal_point=principal_point,
                      contact="off" if contact is None else cut(contact))
    p0 = np.array(params[sl], dtype=float)
    # where a hard sign now disagrees with the solution, start from the seed's lift
    zeta = segment_zeta(joints3d[sl], body.segment_lengths())
    against = ((pb.hard_signs != 0) & (pb.hard_signs * zeta < 0)).any(axis=1)
    if against.any():
        seg = warm_start(pb, joints2d[sl], scale=cut(scale), body=body,
                         segment_scale=cut(segment_scale), principal_point=principal_point)
        p0[against] = seg[against]
        p0[against, :3] = params[sl][against, :3]
    fixed = np.zeros(b - a, bool)
    if a > 0:
        fixed[:_HOLD] = True
    if b < F:
        fixed[-_HOLD:] = True
    sol = solve_problem(pb, p0, sweeps=1, max_iter=max_iter, fixed=fixed)
    out_p = np.array(params, dtype=float)
    out_j = np.array(joints3d, dtype=float)
    out_p[sl] = sol.params
    out_j[sl] = sol.joints3d
    return out_p, out_j, sol.signs
