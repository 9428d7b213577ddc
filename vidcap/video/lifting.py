"""The 3D stage of the video path: from 2D joints to 3D joints, with the user's events.

:func:`lift_pose` runs the stage's steps in order: gaps filled (:func:`fill_gaps`), the
scale per frame (:func:`frame_scales`, :func:`model_scales`), the body's orientation
proposed and constrained to what the user said of the view
(:func:`constrain_orientation`), the user's orientation, sides and joints applied
(:func:`apply_user_view`, :func:`swap_pairs`; with :data:`CONSISTENT_NAMES`, off, the fit's
limb names are first repaired where they jump from one limb to the other, :func:`consistent_names`),
the depth signs proposed and fixed where the user set them (held until the segment next
passes through the image plane, :func:`plane_passages`), then the scaled orthographic lift
itself (:func:`vidcap.video.lift.lift`). The stage is cheap (milliseconds per clip) and is rerun
after every annotation edit (``ui/session.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d, median_filter

from vidcap.body import LIMB_PAIR_JOINTS, ORIENTATIONS, BodyModel
from vidcap.errors import VidcapError
from vidcap.video.annotations import PAIRS, Annotations
from vidcap.video.lift import (
    assign_sides,
    estimate_scales,
    faces_camera,
    lift,
    torso_width_ratio,
    yaw_from_orientation,
)
from vidcap.video.proposals import propose_front, propose_orientation, propose_signs
from vidcap.video.solve.labels import consistent_labels, exchange_distal
from vidcap.video.solve.stage import check_method, solve_lift

#: Foreshortening |dZ|/length below which a segment counts as "in the image plane"
#: (a depth annotation is carried forward until the segment next enters it).
NEAR_PLANE = 0.15

def plane_passages(zeta, *, near: float = NEAR_PLANE, window: int = 5) -> np.ndarray:
    """Frames where each segment passes through the image plane.

    A passage is a frame where ``zeta = |dZ| / length`` is below ``near`` and is the
    smallest within ``window`` frames (a run of equal minima, e.g. clamped zeros,
    counts as a whole). Given to :meth:`vidcap.video.annotations.Annotations.resolve` as
    ``near_plane``, a depth event then holds until its segment next passes through
    the plane, also when the segment never leaves the near-plane zone (a side-view
    walk), where "until it next enters the zone" would hold across a sign change.

    Parameters
    ----------
    zeta : array_like, shape (F, 10)
        Out-of-plane fraction of every segment (:attr:`SignProposal.zeta`).
    near : float
        Only minima below this count.
    window : int
        Frames over which a minimum must be the smallest (odd).

    Returns
    -------
    numpy.ndarray of bool, shape (F, 10)
    """
    from scipy.ndimage import minimum_filter1d

    z = np.asarray(zeta, dtype=float)
    if z.shape[0] == 0:
        return np.zeros(z.shape, bool)
    low = minimum_filter1d(z, size=max(1, int(window)), axis=0, mode="nearest")
    return (z <= low + 1e-12) & (z < near)


@dataclass(frozen=True)
class LiftResult:
    """The 3D stage's output (:func:`lift_pose`).

    Attributes
    ----------
    joints2d : (F, 15, 2) px, body-side named, user joint fixes applied, gaps filled.
    joints3d : (F, 15, 3) m, camera-aligned world (X right, Y up, Z toward camera).
    proposed_signs, signs : (F, 10) int8, proposed and final (user events applied).
    proposed_orientation, orientation : (F,) str.
    yaw : (F,) rad. scale : px per metre, one number or (F,) (the subject's distance
    changes): where the root is. segment_scale : (F,) px per metre the segments were
    read at (:func:`model_scales`), or None (``scale``). clamped : (F, 10) bool;
    excess : (F, 10) how much longer than the model a clamped segment was (0 elsewhere).
    checks : ranked list of (frame, segment) pairs to check (see
        :meth:`vidcap.video.proposals.SignProposal.checks`).
    margin, zeta : (F, 10) sign confidence and out-of-plane amount.
    """

    joints2d: np.ndarray
    joints3d: np.ndarray
    proposed_signs: np.ndarray
    signs: np.ndarray
    proposed_orientation: np.ndarray
    orientation: np.ndarray
    yaw: np.ndarray
    scale: float | np.ndarray
    clamped: np.ndarray
    checks: list
    margin: np.ndarray
    zeta: np.ndarray
    segment_scale: np.ndarray | None = None
    excess: np.ndarray | None = None
    #: The clip solve's poses (:mod:`vidcap.video.solve.skeleton`), (F, 24), and planted
    #: ankles (F, 2) bool; None with the per-segment lift.
    solve_params: np.ndarray | None = None
    contact: np.ndarray | None = None
    #: The arms' (column 0) and legs' (1) distal joints the 3D stage exchanged against
    #: the 2D fit's names (:func:`consistent_names`), None where it did not run.
    names_swapped: np.ndarray | None = None
    #: Front (+1) or back (-1) per frame from the colour frame's cue
    #: (:func:`vidcap.video.proposals.propose_front`), 0 where none; None without the cue.
    facing: np.ndarray | None = None


def fill_gaps(joints2d) -> np.ndarray:
    """Linearly interpolate frames with NaN joints (no silhouette), (F, 15, 2).

    Raises
    ------
    VidcapError
        No frame has joints.
    """
    j = np.array(joints2d, float)
    ok = np.isfinite(j).all(axis=(1, 2))
    if not ok.any():
        raise VidcapError("no person was found in any frame")
    if ok.all():
        return j
    t = np.arange(len(j))
    flat = j.reshape(len(j), -1)
    for c in range(flat.shape[1]):  # 30 coordinate series, vectorised over frames
        flat[:, c] = np.interp(t, t[ok], flat[ok, c])
    return flat.reshape(j.shape)


#: What ``view`` (``vidcap convert --view``) accepts: how the camera sees the subject
#: for the whole clip. ``auto`` proposes the orientation per frame; ``side``,
#: ``front`` and ``back`` fix the sector and leave which way the subject faces (image
#: left or right) to the proposal; one of the six labels fixes the orientation.
VIEWS: tuple[str, ...] = ("auto", "side", "front", "back", *ORIENTATIONS)

def check_view(view: str) -> None:
    """Raise ValueError unless ``view`` is one of :data:`VIEWS`."""
    if view not in VIEWS:
        raise ValueError(f"unknown view {view!r}; expected one of {list(VIEWS)}")


def constrain_orientation(labels, view: str = "auto") -> np.ndarray:
    """The orientation labels within what the user said of the view.

    Parameters
    ----------
    labels : array_like of str, shape (F,)
        Proposed labels (:data:`vidcap.body.ORIENTATIONS`).
    view : str
        One of :data:`VIEWS`. ``side`` keeps each label's facing (``front_right``
        becomes ``right``), ``front``/``back`` put it in that half (``right`` becomes
        ``front_right``), a label replaces every frame's.

    Returns
    -------
    numpy.ndarray of str, shape (F,)

    Raises
    ------
    ValueError
        ``view`` is not one of :data:`VIEWS`.
    """
    labels = np.asarray(labels).astype(str)
    check_view(view)
    if view == "auto":
        return labels
    if view in ORIENTATIONS:
        return np.full(labels.shape, view)
    facing = np.where(np.char.endswith(labels, "left"), "left", "right")
    return facing if view == "side" else np.char.add(f"{view}_", facing)


#: How far (radians) a side view's yaw is turned toward the front or back the colour
#: frame says (``facing``): the side labels carry no front/back, and the side
#: sector spans 60 to 120 degrees. The names carry it already: 0 / 8 / 15 / 25 degrees
#: gave 85.1 / 85.9 / 86.4 / 85.3 mm on the tuning renders (samples 95.8 each;
#: ``benchmarks/solve_fitted.py --front``).
SIDE_TILT = 0.0


#: The torso's foreshortening above which a side view is named by the colour frame's
#: front/back (``facing``): about 12 degrees or more from a pure side view. Nearer, the
#: torso is edge-on, a body and its mirror differ only in which arm and leg is which
#: (a coin toss the front/back cue does not decide: the samples' walk_side went 160 ->
#: 91 mm with it, the held-out 07_07 end 57 -> 211), so the fit's names are kept. The
#: tuning walks at yaw 60 and 120 have their side frames at 0.32-0.45, the pure side
#: views (walk_side; arms raised sideways at yaw 120) at 0-0.1.
SIDE_FACING_SPREAD = 0.2


def apply_user_view(joints2d, proposed_orientation, spread, user_orientation, user_joints,
                    *, image_sides: bool = True, user_sides=None, facing=None,
                    names_swapped=None):
    """Orientation, yaw and side-named 2D joints once the user's events are applied.

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, 2)
        Gap-filled 2D joints, pixels.
    proposed_orientation : array_like of str, shape (F,)
        The automatic orientation proposal.
    spread : array_like, shape (F,)
        Torso horizontal foreshortening (0 side view, 1 front view).
    user_orientation : array_like of str, shape (F,)
        The user's orientation per frame, ``""`` where none.
    user_joints : numpy.ndarray, shape (F, 15, 2)
        The user's joint positions, NaN where none.
    image_sides : bool
        ``joints2d`` names limbs by image side (the 2D fitter's naming).
    user_sides : array_like of bool, shape (F, 2), optional
        :meth:`vidcap.video.annotations.Annotations.sides`: frames where the user swapped
        the arms' (column 0) or legs' (column 1) left and right.
    facing : array_like of int, shape (F,), optional
        Front (+1) or back (-1) from the colour frame (:attr:`LiftResult.facing`), 0
        where unknown: where the orientation is a side label (``left``, ``right``), not
        the user's, and ``spread`` exceeds :data:`SIDE_FACING_SPREAD`, the yaw is turned
        :data:`SIDE_TILT` that way and image-side names are read as that view's (its
        left on the image's right when it faces the camera).
    names_swapped : array_like of bool, shape (F, 2), optional
        Frames whose arms' (column 0), legs' (1) elbows and wrists, knees and ankles are
        exchanged in ``joints2d`` before it is named (:func:`consistent_names`).

    Returns
    -------
    orientation : numpy.ndarray of str, shape (F,)
    yaw : numpy.ndarray, shape (F,), radians
    joints2d : numpy.ndarray, shape (F, 15, 2)
        Named by the body's true sides, with the user's joints in place.
    """
    orientation, yaw, swap = view_names(proposed_orientation, spread, user_orientation,
                                        facing)
    if names_swapped is not None:
        joints2d = exchange_distal(joints2d, names_swapped)
    j2 = assign_sides(joints2d, yaw, swap=swap) if image_sides else joints2d
    if user_sides is not None:
        j2 = swap_pairs(j2, user_sides)
    j2 = np.where(np.isfinite(user_joints), user_joints, j2)
    return orientation, yaw, j2


def view_names(proposed_orientation, spread, user_orientation, facing=None):
    """The orientation (F,) str, the yaw (F,) rad and the frames whose image-side names
    :func:`vidcap.video.lift.assign_sides` swaps (F,) bool, from the proposed and the
    user's orientation and the colour frame's ``facing`` (:func:`apply_user_view`)."""
    orientation = np.where(np.asarray(user_orientation) != "", user_orientation,
                           proposed_orientation).astype(str)
    yaw = yaw_from_orientation(orientation, spread)
    if facing is None:
        return orientation, yaw, faces_camera(yaw)
    f = np.asarray(facing, dtype=float)
    tilt = ((orientation == "left") | (orientation == "right")) & (f != 0)
    tilt &= np.asarray(user_orientation) == ""  # the user's side view stays one
    tilt &= np.asarray(spread, float) > SIDE_FACING_SPREAD
    yaw = np.where(tilt, np.sign(yaw) * (0.5 * np.pi - SIDE_TILT * f), yaw)
    return orientation, yaw, np.where(tilt, f > 0, faces_camera(yaw))


def swap_pairs(joints2d, swapped) -> np.ndarray:
    """Exchange the left and right arms and/or legs where ``swapped`` says so.

    Parameters
    ----------
    joints2d : numpy.ndarray, shape (F, 15, D)
    swapped : array_like of bool, shape (F, 2)
        Per frame: swap the arms (column 0), the legs (column 1)
        (:data:`vidcap.video.annotations.PAIRS`).

    Returns
    -------
    numpy.ndarray, shape (F, 15, D)
        A copy.
    """
    j = np.array(joints2d, dtype=float)
    sw = np.asarray(swapped, dtype=bool)
    if sw.shape != (len(j), len(PAIRS)):
        raise ValueError(f"swapped must be ({len(j)}, {len(PAIRS)}), got {sw.shape}")
    for col, pair in enumerate(PAIRS):
        left, right = LIMB_PAIR_JOINTS[pair]
        rows = np.flatnonzero(sw[:, col])
        j[np.ix_(rows, left + right)] = j[np.ix_(rows, right + left)]
    return j


#: Whether the clip solve's 3D stage re-names the limbs where the 2D fit's names jump
#: from one limb to the other and back (:func:`consistent_names`). Off: on renders it
#: helps (``benchmarks/solve_fitted.py --front --consistent-names``: tuning renders 86.9
#: -> 67.1 mm, held-out renders 127.4 -> 122.9, samples 118.8 -> 116.1), but real footage
#: loses against MediaPipe's world landmarks (sum over the 11 rows 1663 -> 1701 mm:
#: ido_walk 118 -> 139, pose2sim cam1 196 -> 212, cam4 183 -> 192): with the real fit's
#: noisier joints and front/back, the smoothest naming is often the mirror
#: (benchmarks/HISTORY.md, issue 33).
CONSISTENT_NAMES = False


def consistent_names(j2, rho, unit) -> np.ndarray:
    """(F, 2) bool: the frames whose arms' (column 0), legs' (1) distal joints
    :func:`vidcap.video.solve.labels.consistent_labels` exchanges in the 2D joints ``j2``
    (F, 15, 2) as the fit names them (before :func:`vidcap.video.lift.assign_sides`: the
    fit's tracking is repaired, the view's front/back stays the orientation's), ``unit``
    pixels per 1 % of the height. Frames whose torso is edge-on (``rho`` at most
    :data:`SIDE_FACING_SPREAD`) keep the fit's names: there a body and its mirror differ
    only in which limb is which, and the smoothest naming is as likely the mirror (the
    samples' walk_side 160 -> 205 mm without this hold; the samples were tuning for it)."""
    held = np.repeat((np.asarray(rho, float) <= SIDE_FACING_SPREAD)[:, None], 2, axis=1)
    return consistent_labels(j2, unit, held=held)


#: Which frames the colour frame's limb order names (:func:`near_limb_names`): ``edge``
#: the edge-on side views only (a side label, the torso's spread at most
#: :data:`SIDE_FACING_SPREAD`), ``side`` every side label (the body turned 60 degrees or
#: more from the camera: its near hip and shoulder then 17 cm or more nearer, more than a
#: limb's swing moves it), ``all`` every frame. ``benchmarks/solve_fitted.py --front
#: --legs``, tuning renders / samples / held-out renders, mm: edge 84.9 / 81.6 / 127.2,
#: side 69.2 / 81.6 / 127.2, all 62.6 / 78.9 / 120.8; real footage against MediaPipe
#: (sum over 11 rows, 1560 mm without the cue; looked at to choose, see
#: benchmarks/HISTORY.md): edge 1554, side 1544, all 1617 (frontal clips lose: a limb's
#: own swing outweighs the side's depth there). ``turned``: the side labels and the
#: three-quarter frames whose spread is at most :data:`LIMB_ORDER_TURNED_RHO` (session 20,
#: same cached 2D, with a legs-coupled pose prior that was not kept either): tuning
#: renders 67.7 -> 53.7 mm (walk yaw 60 80 -> 50, yaw 120 60 -> 47, arms yaw 120 92 -> 77),
#: but the validation renders gain nothing (samples 68.2 both, held out 106.0 -> 106.7)
#: and real footage loses (sum 1617 -> 1631, sports2d_walk_turn 108 -> 118; 1625 at a
#: spread of 0.6), so ``side`` stays.
LIMB_ORDER_FRAMES = "side"
#: ``turned`` (:data:`LIMB_ORDER_FRAMES`): the torso's spread (cos of the yaw, about) at
#: or below which a three-quarter frame is named too.
LIMB_ORDER_TURNED_RHO = 0.75
#: The limb pairs (arms, legs: :data:`vidcap.video.annotations.PAIRS` columns) it names
#: (legs only: tuning renders 68.5 mm with ``all``; real sum 1556 with ``side``).
LIMB_ORDER_PAIRS = (True, True)


#: How each limb pair's (arms, legs) side-view names follow the limb order: ``runs``
#: each linked run named as a whole (:func:`vidcap.video.legorder.side_limb_names`),
#: ``frames`` the linking and each frame's cue in one min-sum (:func:`cued_links`). The
#: arms per frame: in a side view the fit's arm names jump where the arms pass each
#: other, and the linking (no 2D jump there) does not see it, while the cue does (walk_side
#: arms scored right in 88 % of frames, linked into runs 69 %). ``benchmarks/solve_fitted.py
#: --front --legs``, tuning renders / samples / held-out renders, mm: runs 69.2 / 81.6 /
#: 127.2, arms per frame 69.2 / **75.7** / **121.7** (walk_side 48 -> 31, 07_07 end 53
#: -> 30; arms named right 0.69 -> 0.90, 0.63 -> 0.90); legs per frame too 69.2 / 77.9
#: (walk_side 37). Real footage sum over 11 rows (validation, same run): 1624 -> 1623.
LIMB_ORDER_LINK = ("frames", "runs")
#: :func:`cued_links`: cost of a frame's naming against its limb-order score, per unit
#: of |score| (a frame's jump in the linking costs up to 200). Tuning renders and samples,
#: mm: 3 / 30 / 50 as runs (walk_side 48), 70 / 100 / 300 walk_side 31, 1000 tuning 69.2
#: -> 78.0 (arms yaw 120 95 -> 133: weak scores then outweigh the linking).
LIMB_ORDER_WEIGHT = 150.0


def cued_links(j2, unit, order, edge, facing_right, swap, *,
               weight: float | None = None) -> np.ndarray:
    """(F, 2) bool: the exchanges of each pair's distal joints that make the named joints
    move smoothly (:func:`vidcap.video.solve.labels.consistent_labels`) and, in the
    ``edge`` frames, name the limb the colour frame shows nearer (``order`` (F, 2),
    :func:`vidcap.video.legorder.near_limb`) as the side facing the camera: each
    frame's score is a cost of ``weight`` x |score| for the naming it contradicts,
    in place of the linking's bias for the fit's names (a side view's names are a coin
    toss)."""
    w = LIMB_ORDER_WEIGHT if weight is None else weight
    d = np.asarray(order, float)
    want = ((d > 0) == np.asarray(facing_right, bool)[:, None]) ^ np.asarray(swap, bool)[:, None]
    prior = np.where(want, -1.0, 1.0) * w * np.abs(d)
    prior = np.where(np.asarray(edge, bool)[:, None] & np.isfinite(d), prior, np.nan)
    return consistent_labels(j2, unit, prior=prior)


def near_limb_names(j2, limb_order, proposed_orientation, user_orientation, rho, unit,
                    names=None, facing=None, *, frames: str | None = None,
                    pairs=None) -> np.ndarray | None:
    """``names`` (F, 2) bool (:func:`consistent_names`, or None: none exchanged) with
    the arms' and legs' columns set, in the runs of frames :data:`LIMB_ORDER_FRAMES`
    names (not the user's orientation), so that the arm and the leg the colour frame
    shows nearer the camera (``limb_order`` (F, 2), :func:`vidcap.video.legorder.near_limb`)
    are of the side the body turns to it (:func:`vidcap.video.legorder.side_limb_names`:
    a body facing image right turns its right side to the camera, whether it faces the
    camera or away); ``unit`` pixels per 1 % of the height. None when ``names`` is None
    and nothing is exchanged."""
    from vidcap.video.legorder import side_limb_names

    frames = LIMB_ORDER_FRAMES if frames is None else frames
    pairs = LIMB_ORDER_PAIRS if pairs is None else pairs
    orient, yaw, swap = view_names(proposed_orientation, rho, user_orientation, facing)
    edge = np.asarray(user_orientation) == ""
    side = (orient == "left") | (orient == "right")
    if frames == "turned":  # a side label, or turned at least LIMB_ORDER_TURNED_RHO
        edge &= side | (np.asarray(rho, float) <= LIMB_ORDER_TURNED_RHO)
    elif frames != "all":
        edge &= side
    if frames == "edge":
        edge &= np.asarray(rho, float) <= SIDE_FACING_SPREAD
    if not edge.any() or not any(pairs):
        return names
    order = np.asarray(limb_order, float)
    out = np.zeros((len(j2), 2), bool) if names is None else np.array(names, bool)
    link = consistent_labels(j2, unit) if "runs" in LIMB_ORDER_LINK else None
    per_frame = cued_links(j2, unit, order, edge, yaw > 0, swap) \
        if "frames" in LIMB_ORDER_LINK else None
    for c in range(2):
        if not pairs[c]:
            continue
        if LIMB_ORDER_LINK[c] == "frames":
            named = per_frame[:, c]
        else:
            named = side_limb_names(order[:, c], edge, yaw > 0, link[:, c], swap)
        out[:, c] = np.where(edge, named, out[:, c])
    return None if names is None and not out.any() else out


#: Knot spacing (seconds) of the per-frame scale (:func:`vidcap.video.lift.estimate_scales`).
SCALE_WINDOW_S = 3.0


def frame_scales(joints2d, fps: float, body: BodyModel | None = None, *,
                 window_s: float = SCALE_WINDOW_S, debias: bool = True):
    """:func:`vidcap.video.lift.estimate_scales` with its window in seconds: pixels per metre,
    one number or (F,) for gap-filled (F, 15, 2) joints.

    With ``debias`` the scale is corrected for the bias noise in the joints gives it
    (:func:`vidcap.video.solve.noise.robust_scale`: 2-5 % too large at 2 % of the height
    of noise, which puts every segment in the image plane out of it).
    """
    s = estimate_scales(joints2d, body, window=max(3, int(round(window_s * fps)) | 1))
    if debias:
        from vidcap.video.lift import estimate_scale
        from vidcap.video.solve.noise import robust_scale

        s = s * (robust_scale(joints2d, body) / estimate_scale(joints2d, body))
    return s


def model_scales(model_height, n_frames: int, body: BodyModel | None = None):
    """Pixels per metre at which the 2D fit drew its model in each frame.

    The fitter scales its model to each frame's silhouette (seed 004 section 4.2),
    and a walker's silhouette is a few per cent shorter with the feet apart than in
    mid-stance, so every drawn segment is that much shorter there. Read against one
    scale for the clip, Eq. 2.2 turns that into depth in every segment (sqrt(1 -
    0.96^2) = 0.28 of its length); read against the frame's own model scale, a
    segment's ratio is the foreshortening the fit found.

    Parameters
    ----------
    model_height : array_like, shape (F,), or None
        :attr:`vidcap.video.fit.pose2d.Pose2D.model_height`: body height in pixels per
        frame, NaN where there was no fit (interpolated here).
    n_frames : int
    body : BodyModel, optional
        The subject (its height in metres).

    Returns
    -------
    numpy.ndarray, shape (F,), or None
        None when ``model_height`` is None or has no usable value.
    """
    if model_height is None:
        return None
    body = body or BodyModel()
    h = np.asarray(model_height, dtype=float).reshape(-1)
    if h.shape != (n_frames,):
        raise ValueError(f"model_height must be ({n_frames},), got shape {h.shape}")
    ok = np.isfinite(h) & (h > 0)
    if not ok.any():
        return None
    t = np.arange(n_frames)
    return np.interp(t, t[ok], h[ok]) / body.height


def _torso_spread(j2, spread, geometry, body, window: int) -> np.ndarray:
    """The torso's horizontal foreshortening per frame: the 2D fit's ``spread`` where
    given, else from the 2D shoulders and hips, then a running median over ``window``
    frames (the body turns slowly: it removes single-frame misfits)."""
    rho = torso_width_ratio(j2, geometry, body)
    if spread is not None:
        rho = np.where(np.isfinite(spread), np.asarray(spread, float), rho)
    return median_filter(rho, size=window, mode="nearest")


def _fit_names(j2, rho, body, geometry, method, limb_order, image_sides, proposed, facing,
               annotations):
    """The frames whose arms' and legs' distal joints the 3D stage exchanges against the
    2D fit's names (F, 2) bool, or None: the fit's jumps repaired
    (:func:`consistent_names`, with the solve and :data:`CONSISTENT_NAMES`), then the
    colour frame's limb order (:func:`near_limb_names`, given ``limb_order`` and
    ``image_sides``); and the
    user's orientation (F,) and joints (F, 15, 2) (``annotations.resolve``)."""
    _, user_orient, user_joints = annotations.resolve(len(j2))
    unit = 0.01 * body.height * np.asarray(geometry)  # px per 1 % of the height
    names = consistent_names(j2, rho, unit) if method == "solve" and CONSISTENT_NAMES \
        else None
    if limb_order is not None and image_sides:
        names = near_limb_names(j2, limb_order, proposed, user_orient, rho, unit, names,
                                facing)
    return names, user_orient, user_joints


def _propose_view(j2, geometry, fps, body, *, image_sides, track, window_s, view, near_side):
    """The proposed orientation labels (F,) within ``view``, and the colour frame's
    front/back (:func:`vidcap.video.proposals.propose_front`, (F,) int8, or None without
    ``near_side`` or with body-side names)."""
    near = near_side if image_sides else None
    read = {}
    labels = propose_orientation(j2, scale=geometry, fps=fps, body=body,
                                 sides_known=not image_sides, track=track, window_s=window_s,
                                 turn_window_s=window_s, near_side=near, out=read)
    labels = constrain_orientation(labels, view)
    if near is None:
        return labels, None
    right = np.char.endswith(labels, "right")
    if np.array_equal(right, read["right"]):
        return labels, read["front"]  # the facing as proposed: read already
    # a view naming the facing (e.g. --view front_left) turned some frames
    return labels, propose_front(near, right, fps=fps)


def lift_pose(
    joints2d,
    *,
    fps: float,
    body: BodyModel | None = None, annotations: Annotations | None = None,
    image_sides: bool = True,
    spread=None, track=None,
    smooth_2d: float = 0.0,
    yaw_window_s: float = 1.0,
    scale_window_s: float = SCALE_WINDOW_S,
    frame_size: tuple[int, int] | None = None,
    model_height=None,
    view: str = "auto", method: str = "solve",
    near_side=None, limb_order=None, jobs: int = 1,
) -> LiftResult:
    """The 3D stage: orientation, sides, depth signs (proposed + user) and lifting.

    Parameters
    ----------
    joints2d : array_like, shape (F, 15, 2)
        2D joints in pixels; NaN frames are interpolated.
    fps : float
    body : BodyModel, optional
    annotations : Annotations, optional
        User events (orientation, depth, joint positions), true-side names.
    image_sides : bool
        ``l_*`` is the image's left limb (the 2D fitter's naming), not the body's left.
    spread : array_like, shape (F,), optional
        Torso horizontal foreshortening (0 side view, 1 front view), e.g.
        :attr:`vidcap.video.fit.pose2d.Pose2D.spread`; default from the 2D shoulders/hips.
    track : array_like, shape (F,), optional
        Horizontal image position of the subject (walking direction).
    smooth_2d : float
        Gaussian smoothing of the 2D joints over time before lifting, frames (0 = none).
    yaw_window_s : float
        Running-median window (seconds) of the torso's horizontal foreshortening.
    scale_window_s : float
        Window (seconds) of the per-frame scale (:func:`vidcap.video.lift.estimate_scales`).
    frame_size : (int, int), optional
        (width, height) in pixels: the centre is the camera's axis (per-frame scales).
    model_height : array_like, shape (F,), optional
        The height in pixels the 2D model was drawn at per frame
        (:attr:`vidcap.video.fit.pose2d.Pose2D.model_height`): segments are then read at
        that frame's scale (:func:`model_scales`), the root at the clip's.
    view : str
        The user's view of the whole clip (:data:`VIEWS`), applied to the proposed
        orientation (:func:`constrain_orientation`); orientation events override it.
    near_side, limb_order : array_like, shapes (F,) or (F, 2), and (F, 2), optional
        The colour frame's cues (:func:`vidcap.video.pipeline.colour_cues`): front or back
        (near side and face), the nearer arm, leg (:func:`near_limb_names`).
    method : {'solve', 'segment'}
        The clip solve (:func:`vidcap.video.solve.stage.solve_lift`) or the seed's
        per-segment lift (:func:`vidcap.video.lift.lift`).
    jobs : int
        Processes for the clip solve (2: a long clip in halves, :mod:`~vidcap.video.solve.split`).

    Returns
    -------
    LiftResult

    Examples
    --------
    The model's rest pose, seen from the front at 200 px per metre for 30 frames,
    comes back at its own size (within 0.11 m: the solve's pose prior bends straight knees
    out of the image plane by up to 10 cm; ``method="segment"`` returns it exactly):

    >>> import numpy as np
    >>> from vidcap.body import BodyModel
    >>> rest = BodyModel().rest_positions()  # (15, 3) m, Y up
    >>> uv = np.c_[320 + 200 * rest[:, 0], 400 - 200 * rest[:, 1]]  # px, y down
    >>> res = lift_pose(np.repeat(uv[None], 30, axis=0), fps=30.0, image_sides=False)
    >>> res.joints3d.shape, float(res.scale), bool(np.allclose(
    ...     res.joints3d[0] - res.joints3d[0, 0], rest - rest[0], atol=0.11))
    ((30, 15, 3), 200.0, True)
    >>> seg = lift_pose(np.repeat(uv[None], 30, axis=0), fps=30.0, image_sides=False,
    ...                 method="segment")
    >>> bool(np.allclose(seg.joints3d[0] - seg.joints3d[0, 0], rest - rest[0], atol=1e-6))
    True
    """
    check_method(method)
    body = body or BodyModel()
    annotations = annotations or Annotations()
    j2 = fill_gaps(joints2d)
    F = len(j2)
    scale = frame_scales(j2, fps, body, window_s=scale_window_s)  # (F,): the distance changes
    seg_scale = model_scales(model_height, F, body)
    geometry = scale if seg_scale is None else seg_scale  # what segments are read at
    if smooth_2d > 0 and F > 2:
        j2 = gaussian_filter1d(j2, smooth_2d, axis=0, mode="nearest")
    rho = _torso_spread(j2, spread, geometry, body, max(1, int(round(yaw_window_s * fps)) | 1))
    proposed_orient, facing = _propose_view(j2, geometry, fps, body, image_sides=image_sides,
                                            track=track, window_s=yaw_window_s, view=view,
                                            near_side=near_side)
    names, user_orient, user_joints = _fit_names(j2, rho, body, geometry, method, limb_order,
                                                 image_sides, proposed_orient, facing, annotations)
    orient, yaw, j2 = apply_user_view(j2, proposed_orient, rho, user_orient, user_joints,
                                      image_sides=image_sides, user_sides=annotations.sides(F),
                                      facing=facing, names_swapped=names)
    free = propose_signs(j2, yaw, scale=geometry, body=body)
    user_signs, _, _ = annotations.resolve(F, near_plane=plane_passages(free.zeta))
    final = propose_signs(j2, yaw, scale=geometry, body=body, fixed=user_signs) \
        if (user_signs != 0).any() else free
    centre = None if frame_size is None else (0.5 * frame_size[0], 0.5 * frame_size[1])
    out = lift(j2, final.signs, yaw, body=body, scale=scale, principal_point=centre,
               segment_scale=seg_scale)
    joints3d, params, contact = out.joints3d, None, None
    if method == "solve":
        sol, final = solve_lift(
            j2, fps=fps, body=body, scale=scale, segment_scale=seg_scale, yaw=yaw, jobs=jobs,
            proposal=final, user_signs=user_signs, user_orientation=user_orient,
            principal_point=centre, user_joints=user_joints,
            user_sides_set=annotations.sides_set(F))
        joints3d, params, contact = sol.joints3d, sol.params, sol.contact
        j2 = swap_pairs(j2, sol.swapped)
    return LiftResult(
        joints2d=j2, joints3d=joints3d, proposed_signs=free.signs, signs=final.signs,
        proposed_orientation=proposed_orient, orientation=orient, yaw=yaw, scale=scale,
        clamped=out.clamped, checks=final.checks(body), margin=final.margin, zeta=final.zeta,
        segment_scale=seg_scale, excess=out.excess, solve_params=params, contact=contact,
        facing=facing, names_swapped=names)


__all__ = ["CONSISTENT_NAMES", "LIMB_ORDER_FRAMES", "LIMB_ORDER_PAIRS", "NEAR_PLANE",
           "SCALE_WINDOW_S", "VIEWS", "LiftResult", "apply_user_view", "check_view",
           "consistent_names", "near_limb_names", "view_names", "constrain_orientation",
           "fill_gaps", "frame_scales", "lift_pose", "model_scales", "plane_passages",
           "swap_pairs"]
