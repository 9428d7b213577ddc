"""Automatic proposals for what the seed asks the user: depth signs and orientation.

Seed 004 (section 3.1.5, 4.3) leaves every segment's depth direction and the body
orientation to the user (60 inputs for an 82-frame walk). Here they are proposed
from three kinds of evidence, and the user only corrects what is wrong:

* **anatomy**: knees fold only backward and elbows only forward
  (:data:`vidcap.body.FLEXION_DIRECTION`), the elbow's "forward" turning with the
  upper arm (forward for an arm hanging or raised sideways, up for an arm raised
  forward: :func:`_elbow_fold`), the forearm preferably in the plane of that fold
  (the upper arm not rotated about its own axis; the same for the shin is a knob,
  off by default); thighs and upper arms rarely point far behind the body; limbs
  rarely cross the body's midline; the torso leans forward rather than backward;
* **walking direction**: the subject faces the way its silhouette moves;
* **temporal continuity**: a segment can only change its depth direction where it
  passes through the image plane (foreshortening ratio near 1). A flip between two
  frames costs in proportion to how far out of the image plane the segment is.

The signs of each limb (upper + lower segment: 4 states), of both legs jointly
(16 states, with a left/right lateral-symmetry cost), of both arms jointly (the same,
weight 0 by default) and of the torso and head
(2 states each) are chosen per frame by dynamic programming (min-sum over the
frames), which also gives min-marginals: how much worse the best solution with
the other sign is. That margin ranks the (frame, segment) pairs a user should check.
User signs enter as hard constraints, so one correction also repairs its
neighbours.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import median_filter, uniform_filter1d

from vidcap.body import JOINT_INDEX, SEGMENT_INDEX, SEGMENT_NAMES, BodyModel, segment_vectors
from vidcap.video.lift import body_axes, depth_magnitudes, torso_width_ratio

_BIG = 1e6
#: Chains of segments whose signs are chosen jointly: (segments, kind, side).
_CHAINS = (
    (("torso",), "torso", 0),
    (("head",), "head", 0),
    (("l_upper_arm", "l_lower_arm"), "arm", +1),
    (("r_upper_arm", "r_lower_arm"), "arm", -1),
    (("l_upper_leg", "l_lower_leg"), "leg", +1),
    (("r_upper_leg", "r_lower_leg"), "leg", -1),
)
#: Sign of each segment in each of the 4 states of a chain.
_STATES = np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]], dtype=float)


@dataclass(frozen=True)
class SignProposal:
    """Result of :func:`propose_signs`.

    Attributes
    ----------
    signs : numpy.ndarray of int8, shape (F, 10)
        Proposed depth signs (+1 distal joint nearer the camera), user constraints
        included.
    margin : numpy.ndarray, shape (F, 10)
        Cost of the best solution with the other sign minus the best cost (>= 0; big =
        confident, ``inf`` where the user fixed it).
    zeta : numpy.ndarray, shape (F, 10)
        |dZ| / length: how far out of the image plane the segment is (0-1); a wrong
        sign moves the distal joint by ``2 * zeta * length``.
    """

    signs: np.ndarray
    margin: np.ndarray
    zeta: np.ndarray

    def checks(self, body: BodyModel | None = None, *, limit: int = 20, tau: float = 0.2):
        """Ranked (frame, segment) pairs a user should check, most doubtful first.

        Runs of frames with the same proposed sign count once (at their least
        confident frame). Priority = expected displacement of the distal joint if
        the sign is wrong, ``2 zeta l * p_wrong`` with ``p_wrong = 1 / (1 + exp(margin /
        tau))``.

        Returns
        -------
        list of dict
            Keys ``frame``, ``segment``, ``sign``, ``margin``, ``priority`` (metres),
            ``run`` (first, last frame of the run).
        """
        body = body or BodyModel()
        L = body.segment_lengths()
        with np.errstate(over="ignore"):
            p_wrong = 1.0 / (1.0 + np.exp(np.minimum(self.margin / tau, 700.0)))
        prio = 2.0 * self.zeta * L * p_wrong
        out = []
        F = self.signs.shape[0]
        for k, name in enumerate(SEGMENT_NAMES):
            s = self.signs[:, k]
            starts = np.flatnonzero(np.r_[True, s[1:] != s[:-1]])
            stops = np.r_[starts[1:], F]
            for a, b in zip(starts, stops, strict=True):
                t = a + int(np.argmax(prio[a:b, k]))
                if prio[t, k] > 1e-6:
                    out.append({"frame": int(t), "segment": name, "sign": int(s[t]),
                                "margin": float(self.margin[t, k]),
                                "priority": float(prio[t, k]), "run": (int(a), int(b - 1))})
        out.sort(key=lambda d: -d["priority"])
        return out[:limit]


def _relu(x):
    return np.maximum(x, 0.0)


def _elbow_fold(upper, lower, fwd, *, fade: float = 0.3):
    """Cost of a forearm folding against the elbow's flexion direction, (...).

    The elbow's hinge turns with the upper arm: its flexion direction is the body's
    forward direction carried by the shortest rotation (the swing) that takes the
    hanging arm (down) to the upper arm's direction -- forward for an arm hanging or
    raised sideways (the forearm bends to the front), up for an arm raised forward
    (the hand comes to the face). The cost is how far the forearm points against it,
    ``relu(-lower . w)``. The humerus' own rotation (twist) turns the forearm out of
    the plane of the upper arm and ``w``; its cost is ``|lower . (upper x w)|``, the
    sine of that tilt (the forearm of a straight elbow follows the upper arm). The
    swing is undefined for an arm straight overhead, so both fade out as ``1 + down .
    upper`` falls below ``fade``.

    Parameters
    ----------
    upper, lower, fwd : numpy.ndarray, shape (..., 3)
        Unit directions of the upper arm, the forearm and the body's forward axis
        (Y up).

    Returns
    -------
    fold, twist : numpy.ndarray, shape (...)
    """
    down = np.array([0.0, -1.0, 0.0])
    c = np.cross(np.broadcast_to(down, upper.shape), upper)  # swing axis * sin
    d = 1.0 + upper @ down  # 1 + cos, 0 for an arm overhead
    cf = np.cross(c, fwd)
    w = fwd + cf + np.cross(c, cf) / np.maximum(d, 1e-6)[..., None]
    k = np.clip(d / fade, 0.0, 1.0)
    twist = np.abs(np.sum(lower * np.cross(upper, w), -1)) * k
    return _relu(-np.sum(lower * w, -1)) * k, twist


def _chain_costs(j2, yaw, *, scale, body, hinge_weight, range_weight, midline_weight,
                 lean_weight, torso_depth, twist_weight=0.0, leg_twist_weight=0.0):
    """Anatomical cost of every sign state of every chain, (C, F, 4), with the lateral
    offsets of the limbs' distal joints ({chain: (F, 4, 2)}) and zeta (F, 10)."""
    j2 = np.asarray(j2, dtype=float)
    F = j2.shape[0]
    yaw = np.broadcast_to(np.asarray(yaw, dtype=float), (F,))
    L = body.segment_lengths()
    dz, _ = depth_magnitudes(j2, scale, body)
    zeta = dz / L
    vec = segment_vectors(j2) / np.reshape(scale, (-1, 1, 1))  # one scale or one per frame
    vec[..., 1] *= -1.0
    fwd, left = body_axes(yaw)  # (F, 3)

    # the torso's axis (pelvis -> neck, unit, (F, 1, 3)) with its depth taken leaning
    # forward, the way bodies bend (its own sign is chosen with the torso's chain)
    kt = SEGMENT_INDEX["torso"]
    t_axis = np.concatenate([vec[:, kt], dz[:, kt, None]], -1)
    t_axis[:, 2] *= np.where(fwd[:, 2] < 0.0, -1.0, 1.0)
    t_axis = (t_axis / np.maximum(np.linalg.norm(t_axis, axis=-1, keepdims=True), 1e-12))[:, None]

    C, S = len(_CHAINS), 4
    unary = np.zeros((C, F, S))
    lateral = {}  # chain -> (F, S, 2): lateral offsets (body left) of its two distal joints
    for c, (segs, kind, side) in enumerate(_CHAINS):
        ks = [SEGMENT_INDEX[s] for s in segs]
        sig = _STATES[:, : len(ks)]  # (S, n)
        # 3D unit vectors of the chain's segments for every state: (F, S, n, 3)
        v3 = np.concatenate(
            [np.broadcast_to(vec[:, None, ks, :], (F, S, len(ks), 2)),
             (sig[None] * dz[:, None, ks])[..., None]], axis=-1) / L[ks][:, None]
        cost = np.zeros((F, S))
        f, lf = fwd[:, None, :], left[:, None, :]
        if kind in ("torso", "head"):
            cost += lean_weight * _relu(-np.sum(v3[:, :, 0] * f, -1))
        else:
            up, lo = v3[:, :, 0], v3[:, :, 1]
            if kind == "leg":  # the shin folds backward about the body's lateral axis
                fold = _relu(-np.sum(np.cross(up, lo) * lf, -1))
                # the same swing construction with the knee's backward fold direction
                _, twist = _elbow_fold(up, lo, -np.broadcast_to(f, up.shape))
                cost += leg_twist_weight * twist
            else:  # the forearm folds toward the swung forward direction
                fold, twist = _elbow_fold(up, lo, np.broadcast_to(f, up.shape))
                cost += twist_weight * twist
            back_limit = np.sin(np.deg2rad(25.0 if kind == "leg" else 45.0))
            behind = _relu(-np.sum(up * f, -1) - back_limit)
            w0 = body.hip_half_width if kind == "leg" else body.shoulder_half_width
            l_up, l_lo = L[ks[0]], L[ks[1]]
            lat1 = side * w0 + np.sum(up * lf, -1) * l_up
            lat2 = lat1 + np.sum(lo * lf, -1) * l_lo
            lateral[c] = np.stack([lat1, lat2], -1) / (l_up + l_lo)
            # knees, ankles and elbows stay on their own side (hands may cross in front)
            cross = _relu(-side * lat1) / l_up
            if kind == "leg":
                cross = cross + _relu(-side * lat2) / l_lo
            cost += hinge_weight * fold + range_weight * behind + midline_weight * cross
            if kind == "arm":  # elbow and wrist may not enter the torso (elliptic section)
                r = body.radius("torso")
                p1 = side * w0 * lf + up * l_up  # relative to the neck
                p2 = p1 + lo * l_lo
                Lt = L[SEGMENT_INDEX["torso"]]
                for p in (p1, p2):
                    # sections across the torso's own axis, not the vertical: a torso
                    # bent 30 degrees forward lies well behind the neck's vertical at the
                    # elbows' height, where an arm hanging from the shoulder is free
                    h = np.sum(p * t_axis, -1)  # along the axis, < 0 below the neck
                    q = p - h[..., None] * t_axis
                    e = (np.sum(q * lf, -1) / r) ** 2 + (np.sum(q * f, -1) / (torso_depth * r)) ** 2
                    below = (h > -Lt) & (h < 0.0)
                    cost += midline_weight * np.where(below, _relu(1.0 - e), 0.0)
        if len(ks) == 1:  # one segment: only the states whose (unused) second sign is +1
            cost[:, _STATES[:, 1] < 0] = _BIG
        unary[c] = cost
    return unary, lateral, zeta


def propose_signs(
    joints2d,
    yaw,
    *,
    scale,
    body: BodyModel | None = None,
    fixed=None,
    flip_cost: float = 3.0,
    flip_penalty: float = 0.05,
    hinge_weight: float = 2.0,
    range_weight: float = 1.0,
    midline_weight: float = 1.0,
    lean_weight: float = 0.5,
    torso_depth: float = 0.6,
    symmetry_weight: float = 0.5,
    arm_symmetry_weight: float = 0.0,
    symmetry_cap: float = 0.5,
    twist_weight: float = 0.3,
    leg_twist_weight: float = 0.0,
) -> SignProposal:
    """Propose a depth sign for every segment and frame.

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Image joints in pixels, named by the body's sides.
    yaw : array_like, shape (F,)
        Body yaw in radians (0 = facing the camera, +pi/2 = facing image right).
    scale : float or array_like, shape (F,)
        Pixels per metre (one, or per frame: :func:`vidcap.video.lift.estimate_scales`).
    body : BodyModel, optional
    fixed : array_like of int, shape (F, 10), optional
        User signs (+1/-1), 0 where free.
    flip_cost, flip_penalty : float
        A sign change between frames t-1 and t costs ``flip_cost * min(zeta(t-1),
        zeta(t)) + flip_penalty``.
    hinge_weight, range_weight, midline_weight, lean_weight : float
        Weights of the anatomical costs (knee/elbow fold direction, the elbow's
        carried by the upper arm's swing from hanging; thigh/upper arm
        pointing behind the body; limb crossing the midline or an arm entering the
        torso; torso/head leaning back).
    torso_depth : float
        Front-back half-depth of the torso as a fraction of the model cylinder's
        radius (real chests are flatter than the cylinder); elbows and wrists may not
        enter that elliptic section.
    symmetry_weight, arm_symmetry_weight : float
        Both legs (both arms) are chosen jointly (16 sign states per frame); a state
        costs this weight times the left/right lateral asymmetry of the pair: the sum
        of ``|lat_left + lat_right|`` over the knee and ankle (elbow and wrist), where
        ``lat`` is the joint's offset along the body's left axis from the midline, in
        units of the limb's length. Walking, standing and jumping keep the legs
        mirror-symmetric sideways (one leg's step sideways shows in the other); arms
        are off by default (one-arm gestures; weighted on the synth 'arms' motion it
        cost up to 1 point of MPJPE, while it fixed 'jacks' seen at 45 degrees).
    symmetry_cap : float
        Asymmetry above this (limb lengths) costs no more (robust to deliberate
        one-sided poses).
    twist_weight : float
        Weight of the forearm's tilt out of the plane of the upper arm and the elbow's
        flexion direction (the upper arm's rotation about its own axis away from
        neutral; see :func:`_elbow_fold`). The rotation has a wide range (about 90
        degrees each way), so this is a weak preference for the neutral one that
        decides where the other costs leave the forearm's sign open.
    leg_twist_weight : float
        The same for the shin and the thigh (the knee's flexion direction being
        backward carried by the thigh's swing), off by default: on the synth motions
        (true 2D joints) a weight of 1 was best (all pairs 82.7 -> 87.6 %), but in
        side views, where the legs lie near the image plane and the hip's rotation
        (toe-out) decides which way the shin leaves the plane, it flipped both shins
        for a whole clip (end to end walk_side 8.7 -> 9.6 % MPJPE).

    Returns
    -------
    SignProposal
    """
    body = body or BodyModel()
    j2 = np.asarray(joints2d, dtype=float)
    F = j2.shape[0]
    fixed = np.zeros((F, len(SEGMENT_NAMES)), int) if fixed is None else np.asarray(fixed)
    unary, lateral, zeta = _chain_costs(
        j2, yaw, scale=scale, body=body, hinge_weight=hinge_weight, range_weight=range_weight,
        midline_weight=midline_weight, lean_weight=lean_weight, torso_depth=torso_depth,
        twist_weight=twist_weight, leg_twist_weight=leg_twist_weight)
    trans = _chain_transitions(unary, zeta, fixed, flip_cost=flip_cost,
                               flip_penalty=flip_penalty)
    gu, gt = _group_costs(unary, trans, lateral, symmetry_weight=symmetry_weight,
                          arm_symmetry_weight=arm_symmetry_weight, symmetry_cap=symmetry_cap)
    signs, margin = _read_signs(_min_marginals(gu, gt), F)
    margin = np.where(fixed != 0, np.inf, np.minimum(margin, _BIG / 10))
    return SignProposal(signs=signs, margin=margin, zeta=zeta)


#: Chains solved jointly (indices into ``_CHAINS``): torso, head, both arms (16 states),
#: both legs (16 states).
_GROUPS = ((0, None), (1, None), (2, 3), (4, 5))


def _chain_transitions(unary, zeta, fixed, *, flip_cost: float, flip_penalty: float):
    """Per chain, the cost (F-1, 4, 4) of going from each sign state to each in the next
    frame: a sign change costs ``flip_cost * min(zeta(t-1), zeta(t)) + flip_penalty``.
    States against the user's ``fixed`` signs (F, 10) are made ``_BIG`` in ``unary``
    (changed in place)."""
    F = len(fixed)
    C, S = len(_CHAINS), 4
    trans = np.zeros((C, max(F - 1, 0), S, S))
    for c, (segs, _, _) in enumerate(_CHAINS):
        ks = [SEGMENT_INDEX[s] for s in segs]
        sig = _STATES[:, : len(ks)]
        for n, k in enumerate(ks):  # user constraints
            fx = fixed[:, k]
            bad = (fx[:, None] != 0) & (sig[None, :, n] != fx[:, None])
            unary[c][bad] += _BIG
        if F > 1:
            for n, k in enumerate(ks):
                flip = (sig[:, None, n] != sig[None, :, n]).astype(float)  # (S, S)
                z = np.minimum(zeta[:-1, k], zeta[1:, k])
                trans[c] += flip[None] * (flip_cost * z + flip_penalty)[:, None, None]
    return trans


def _group_costs(unary, trans, lateral, *, symmetry_weight: float,
                 arm_symmetry_weight: float, symmetry_cap: float):
    """Unary (G, F, 16) and transition (G, F-1, 16, 16) costs of the :data:`_GROUPS`:
    a pair's joint state costs both chains' plus the weight times its left/right
    lateral asymmetry (mirror symmetry about the body's sagittal plane, of
    elbows/wrists and knees/ankles); a single chain uses the first 4 states."""
    F, S = unary[0].shape[0], 4
    G, S2 = len(_GROUPS), S * S
    gu = np.full((G, F, S2), _BIG)
    gt = np.zeros((G, max(F - 1, 0), S2, S2))
    for g, (ca, cb) in enumerate(_GROUPS):
        if cb is None:
            gu[g, :, :S] = unary[ca]
            gt[g, :, :S, :S] = trans[ca]
            continue
        asym = np.abs(lateral[ca][:, :, None] + lateral[cb][:, None, :]).sum(-1)  # (F, S, S)
        w_sym = arm_symmetry_weight if _CHAINS[ca][1] == "arm" else symmetry_weight
        gu[g] = (unary[ca][:, :, None] + unary[cb][:, None, :]
                 + w_sym * np.minimum(asym, symmetry_cap)).reshape(F, S2)
        if F > 1:
            gt[g] = (trans[ca][:, :, None, :, None]
                     + trans[cb][:, None, :, None, :]).reshape(F - 1, S2, S2)
    return gu, gt


def _min_marginals(gu, gt) -> np.ndarray:
    """Min-sum forward / backward over frames, vectorised over groups and states: the
    cheapest whole-clip cost through each (group, frame, state), (G, F, 16)."""
    G, F, S2 = gu.shape
    alpha = np.empty((G, F, S2))
    beta = np.zeros((G, F, S2))
    alpha[:, 0] = gu[:, 0]
    for t in range(1, F):
        alpha[:, t] = gu[:, t] + np.min(alpha[:, t - 1, :, None] + gt[:, t - 1], axis=1)
    for t in range(F - 2, -1, -1):
        beta[:, t] = np.min(gt[:, t] + (gu[:, t + 1] + beta[:, t + 1])[:, None, :], axis=2)
    return np.minimum(alpha + beta, _BIG)


def _read_signs(marg, n_frames: int):
    """Each segment's sign (F, 10) int8, the cheaper of its + and - min-marginals, and
    the margin between them (F, 10)."""
    S = 4
    S2 = S * S
    signs = np.ones((n_frames, len(SEGMENT_NAMES)), dtype=np.int8)
    margin = np.zeros((n_frames, len(SEGMENT_NAMES)))
    st_a, st_b = np.divmod(np.arange(S2), S)
    for g, (ca, cb) in enumerate(_GROUPS):
        for c, st in ((ca, st_a if cb is not None else st_b), (cb, st_b)):
            if c is None:
                continue
            segs = _CHAINS[c][0]
            valid = (st_a == 0) & (_STATES[st_b, 1] > 0) if cb is None else np.ones(S2, bool)
            for n, s in enumerate(segs):
                k = SEGMENT_INDEX[s]
                plus = np.min(np.where(valid & (_STATES[st, n] > 0), marg[g], np.inf), -1)
                minus = np.min(np.where(valid & (_STATES[st, n] < 0), marg[g], np.inf), -1)
                signs[:, k] = np.where(plus <= minus, 1, -1)
                margin[:, k] = np.abs(plus - minus)
    return signs, margin


#: :func:`propose_front`: the averaging window (seconds) of
#: :func:`vidcap.video.frontback.near_side` and the averages that decide front and
#: back. Back needs more: the default is front, and a body read turned away when it
#: faces the camera is mirrored whole. Window chosen on the tuning renders and the
#: samples (``benchmarks/solve_fitted.py --front``): 1 / 4 / 8 s 104.4 / 107.6 / 107.3 mm
#: against 2 s at 0.03/0.03 (1 s: the fitted arms' errors decide; 4-8 s: the weak front
#: cue is averaged away at the side sector's edge). Thresholds: every tuning render and
#: sample keeps its PA-MPJPE for front 0.01-0.06 (``--front --legs``, 69.9 / 66.0 mm;
#: 0.07 loses walk yaw 60), and 0.03 sits in the middle of that range, so a clip's front
#: is read only where its arms say clearly more than the renders needed (on real
#: footage a weak average flipped clips with a few pixels of 2D change: HISTORY.md,
#: issue 33, "The face cue and a front threshold with a margin"). Back stays 0.05: the
#: rendered walk from behind at 320x240 (tests/test_frontback.py) reads -0.06 at yaw 120.
#: Built and off: :data:`NEAR_SIDE_MARGIN_FRONT` (0.03) as the front threshold took the
#: 13 real rows from 164.1 to 161.6 mm with the face cue on, but the held-out render
#: 131_01 2-4 s from 155.7 to 160.8 mm (> 5 mm: not kept); ``lift_accuracy.py
#: --front-margin``, ``solve_fitted.py --front-margin`` switch it on.
NEAR_SIDE_WINDOW_S = 2.0
NEAR_SIDE_MIN_FRONT = 0.01
NEAR_SIDE_MIN_BACK = 0.05
NEAR_SIDE_MARGIN_FRONT = 0.03
#: The face (:mod:`vidcap.video.facecue`), read over the same window: where at least
#: ``FACE_MIN_FOUND`` frontal faces were found, and in at least ``FACE_MIN_SHARE`` of
#: the frames searched, the body faces the camera whatever the arms say. A face not
#: found says nothing (too small, blurred, lit from behind, or turned a little away).
FACE_MIN_FOUND = 2
FACE_MIN_SHARE = 0.25


def _window_sum(x, window: int):
    """Sum of ``x`` (F,) over the ``window`` frames centred on each, cut at the clip's
    ends, and the number of frames summed (F,)."""
    c = np.r_[0.0, np.cumsum(x)]
    t = np.arange(len(x))
    lo = np.clip(t - window // 2, 0, len(x))
    hi = np.clip(t + window - window // 2, 0, len(x))
    return c[hi] - c[lo], hi - lo


def _window_mean(x, window: int) -> np.ndarray:
    """Mean of ``x`` (F,) over the ``window`` frames centred on each, cut at the clip's
    ends (not padded: a clip shorter than the window is not outvoted by its end frames
    repeated)."""
    total, n = _window_sum(x, window)
    return total / np.maximum(n, 1)


def face_front(face, window: int, *, min_found: int = FACE_MIN_FOUND,
               min_share: float = FACE_MIN_SHARE) -> np.ndarray:
    """Where the face says the body faces the camera, (F,) bool: at least ``min_found``
    faces found within the ``window`` frames centred on a frame, in at least
    ``min_share`` of the frames searched there.

    Parameters
    ----------
    face : array_like, shape (F,)
        :func:`vidcap.video.facecue.face_seen`: 1 face found, 0 none found, NaN not
        searched.
    window : int
        Frames.
    """
    f = np.asarray(face, dtype=float)
    found, _ = _window_sum(f == 1.0, window)
    looked, _ = _window_sum(np.isfinite(f), window)
    return (found >= min_found) & (found >= min_share * looked)


def propose_front(near_side, right, *, fps: float, min_front: float | None = None,
                  min_back: float | None = None,
                  window_s: float = NEAR_SIDE_WINDOW_S) -> np.ndarray:
    """Front or back per frame from the colour frame's near-side cue and, where it was
    read, the face.

    A body facing image right shows its right side to the camera: its right arm, the
    one in front of the body, is on the image's left when it faces the camera and on
    the image's right when it is turned away (mirrored for a body facing left). The
    cue is averaged over ``window_s`` (the body turns slowly, and the cue is sparse:
    arms swung clear of the body say nothing); where the average exceeds ``min_front``
    or falls below ``-min_back`` it decides, elsewhere the nearest frame it decided.
    Where the face was found over the window (:func:`face_front`) the body faces the
    camera, whatever the arms say; the face is not carried further (the head turns, and
    a profile or a face too small shows none).

    Parameters
    ----------
    near_side : array_like, shape (F,) or (F, 2)
        :func:`vidcap.video.frontback.near_side` (> 0: the image-left arm in front),
        and as a second column :func:`vidcap.video.facecue.face_seen`
        (:func:`vidcap.video.pipeline.colour_cues` with the face).
    right : array_like of bool, shape (F,)
        The body faces image right (the orientation proposal's side).
    fps : float
    min_front, min_back, window_s : float
        Thresholds (skin likelihood, 0-1; default :data:`NEAR_SIDE_MIN_FRONT`,
        :data:`NEAR_SIDE_MIN_BACK`, read at the call) and window (seconds).

    Returns
    -------
    numpy.ndarray of int8, shape (F,)
        +1 facing the camera, -1 turned away, 0 where nothing decides (everywhere when
        no frame does, beyond the face's windows when only it does).
    """
    min_front = NEAR_SIDE_MIN_FRONT if min_front is None else min_front
    min_back = NEAR_SIDE_MIN_BACK if min_back is None else min_back
    near = np.asarray(near_side, dtype=float)
    arm = near[:, 0] if near.ndim == 2 else near
    window = max(1, int(round(window_s * fps)))
    e = _window_mean(np.nan_to_num(arm) * np.where(right, 1.0, -1.0), window)
    vote = np.where(e > min_front, 1, np.where(e < -min_back, -1, 0))
    known = vote != 0
    if known.any():
        vote = vote[_nearest_known(known)]
    if near.ndim == 2:  # not carried beyond its window: the head turns, profiles show none
        vote = np.where(face_front(near[:, 1], window), 1, vote)
    return vote.astype(np.int8)


def _nearest_known(known: np.ndarray) -> np.ndarray:
    """Each frame's nearest frame (F,) int where ``known`` (F,) bool holds, the later of
    two as near; ``known`` must hold somewhere."""
    idx = np.flatnonzero(known)
    t = np.arange(len(known))
    pos = np.searchsorted(idx, t)
    after = idx[np.clip(pos, 0, len(idx) - 1)]
    before = idx[np.clip(pos - 1, 0, len(idx) - 1)]
    return np.where(np.abs(before - t) < np.abs(after - t), before, after)


#: The fold cue (:func:`propose_orientation`) that overrules the direction a moving
#: subject travels: three times the cue's own threshold (a clear fold of both knees).
FOLD_OVER_TRAVEL = 0.3


def _faces_image_right(cue, vel, moving, bent) -> np.ndarray:
    """Whether the body faces image right, (F,) bool, from the fold cue ``cue``, the
    horizontal velocity ``vel`` and where it moves and is bent (all (F,)); see
    :func:`propose_orientation`."""
    # A body that travels across the picture faces where it goes, unless its limbs'
    # fold says otherwise clearly: the travel reads from the whole silhouette's track,
    # the fold from four fitted limbs, and one arm fitted bent the wrong way tips a weak
    # fold (ido_walk frames 20-27: fold -0.1 to -0.2 while walking right).
    walking = moving & (np.abs(cue) < FOLD_OVER_TRAVEL)
    score = np.where(walking, np.sign(vel),
                     np.where(bent, np.sign(cue), np.where(moving, np.sign(vel), 0.0)))
    known = score != 0
    if known.any():
        return score[_nearest_known(known)] > 0
    return np.full(len(score), cue.sum() >= 0)


def propose_orientation(
    joints2d,
    *,
    scale,
    fps: float,
    body: BodyModel | None = None,
    sides_known: bool = False,
    track=None,
    min_speed: float = 0.15,
    min_fold: float = 0.1,
    window_s: float = 0.5,
    turn_window_s: float | None = 0.2,
    near_side=None,
    out: dict | None = None,
) -> np.ndarray:
    """Propose one of the six orientation labels per frame (seed 004 section 3.1.5).

    * image-right vs image-left (the sign of sin yaw): the sense in which the knees
      and elbows turn in the image. Both are hinges about the body's lateral axis
      (the shin folds backward, the forearm forward), so a flexed knee seen from
      the body's right turns clockwise whatever the thigh's direction (standing,
      kicking, sitting) and an elbow the other way; that sense is the sign of the
      image cross product of the upper and lower segments, ``sin`` of the image
      angle between them times their foreshortening ratios, summed (knees minus
      elbows) and averaged over ``window_s``. A subject that moves faster than
      ``min_speed`` body heights per second faces the direction it moves (``track``,
      e.g. the silhouette's centre) unless the cue exceeds :data:`FOLD_OVER_TRAVEL`;
      elsewhere the cue decides where it exceeds ``min_fold``; elsewhere the nearest
      such frame's;
    * side view vs front/back: the torso's horizontal foreshortening (< 0.5 = within
      30 degrees of a side view);
    * front vs back: with body-side named joints (``sides_known``), whether the
      body's left shoulder/hip appear on the image's right (facing the camera).
      A silhouette cannot tell (orthographic mirror images); with image-side names
      the colour frame's ``near_side`` decides (:func:`propose_front`: which arm is
      in front), else ``front``. One orientation event fixes a whole clip.

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        Image joints, pixels.
    scale : float or array_like, shape (F,)
        Pixels per metre (one, or per frame).
    fps : float
        Frames per second of the clip.
    body : BodyModel, optional
    sides_known : bool
        Whether ``joints2d`` is named by the body's true sides.
    track : array_like, shape (F,), optional
        Horizontal image position of the subject in pixels (default: the pelvis).
    min_speed : float
        Walking threshold in body heights per second.
    min_fold : float
        Threshold of the knee/elbow turning cue (a sum of sines, dimensionless).
    window_s : float
        Median-filter window in seconds for the walking direction and the knee/elbow
        cue (and the foreshortening when ``turn_window_s`` is None).
    turn_window_s : float, optional
        Median-filter window in seconds for the torso's foreshortening that decides
        side view vs front/back. A turning body passes through the 60-degree side
        sector quickly (at 180 degrees/s in a third of a second), so a window much
        longer than that labels the whole passage with the neighbouring sector.
    near_side : array_like, shape (F,) or (F, 2), optional
        :func:`vidcap.video.frontback.near_side` (image-side names only), with the face
        (:func:`vidcap.video.facecue.face_seen`) as a second column where it was read;
        read by :func:`propose_front` with its default thresholds.
    out : dict, optional
        Where ``near_side`` was read, set to ``{"front": propose_front(...), "right":
        right}`` ((F,) int8 and the (F,) bool facing it was read with), so that a caller
        who needs the front/back itself need not read it again.

    Returns
    -------
    numpy.ndarray of str, shape (F,)
    """
    body = body or BodyModel()
    j2 = np.asarray(joints2d, dtype=float)
    F = j2.shape[0]
    ji = JOINT_INDEX
    x = j2[:, ji["pelvis"], 0] if track is None else np.asarray(track, dtype=float)
    win = max(1, int(round(window_s * fps)) | 1)

    lengths = body.segment_lengths()

    def fold(a, b, c, upper, lower):
        """Image cross product (y down) of a->b and b->c over the model lengths: > 0
        where the limb turns clockwise on screen (a knee seen from the body's right)."""
        u, v = j2[:, ji[b]] - j2[:, ji[a]], j2[:, ji[c]] - j2[:, ji[b]]
        norm = scale**2 * lengths[SEGMENT_INDEX[upper]] * lengths[SEGMENT_INDEX[lower]]
        return (u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]) / norm

    cue = (fold("l_hip", "l_knee", "l_ankle", "l_upper_leg", "l_lower_leg")
           + fold("r_hip", "r_knee", "r_ankle", "r_upper_leg", "r_lower_leg")
           - fold("l_shoulder", "l_elbow", "l_wrist", "l_upper_arm", "l_lower_arm")
           - fold("r_shoulder", "r_elbow", "r_wrist", "r_upper_arm", "r_lower_arm"))
    cue = uniform_filter1d(cue, win, mode="nearest")
    xs = median_filter(x, size=win, mode="nearest") if F > 2 else x
    vel = np.gradient(xs) * fps if F > 1 else np.zeros(F)
    moving = np.abs(vel) > min_speed * body.height * scale
    bent = np.abs(cue) > min_fold
    twin = win if turn_window_s is None else max(1, int(round(turn_window_s * fps)) | 1)
    rho = median_filter(torso_width_ratio(j2, scale, body), size=twin, mode="nearest")
    right = _faces_image_right(cue, vel, moving, bent)
    if sides_known:
        d = (j2[:, ji["l_shoulder"], 0] - j2[:, ji["r_shoulder"], 0]
             + j2[:, ji["l_hip"], 0] - j2[:, ji["r_hip"], 0])
        front = median_filter(d, size=win, mode="nearest") >= 0
    elif near_side is not None:
        facing = propose_front(near_side, right, fps=fps)
        front = facing >= 0
        if out is not None:
            out.update(front=facing, right=right)
    else:
        front = np.ones(F, bool)
    side = np.where(right, "right", "left")
    label = np.where(rho < 0.5, side, np.char.add(np.where(front, "front_", "back_"), side))
    return label.astype(str)
