"""Retargeting a source motion (BVH, ASF/AMC) onto our fifteen-joint skeleton.

The source's joints are mapped onto our fifteen by :data:`JOINT_MAPS`. The torso
(root) rotation comes from the source's torso frame (up = pelvis -> neck, lateral
= left -> right hips plus left -> right shoulders), every other joint gets the
minimal rotation (no twist added) that turns our rest bone onto the source's bone
direction, expressed in its parent's frame. The root translation is the source's
pelvis scaled by our leg length over the source's leg length, shifted so that the
lowest ankle over the clip stands on the floor (y = 0).

Our torso is a 40 cm cylinder with the shoulders on its surface; the performer's is
narrower and flatter. A hand resting on the belly, or an elbow against the flank,
lands inside our torso: a pose no body can take, whose arm no camera can see and
whose depth direction means nothing. :func:`keep_arms_out_of_torso` turns such an
arm out to the cylinder's surface (the smallest rotation at the shoulder, then at
the elbow), so the truth is a pose of the model itself.
"""

from __future__ import annotations

import os

import numpy as np
from scipy.spatial.transform import Rotation

from vidcap.body import (
    JOINT_INDEX,
    JOINT_NAMES,
    BodyModel,
)
from vidcap.errors import MotionFileError
from vidcap.io.jointmaps import JOINT_MAPS
from vidcap.kinematics import Motion, Skeleton
from vidcap.synth._geometry import unit
from vidcap.video.motion import joints_to_motion, minimal_rotation


def _norm_name(name: str) -> str:
    return name.rsplit(":", 1)[-1].strip().lower()


def _alternatives(spec) -> tuple[str, ...]:
    """A :data:`JOINT_MAPS` value as its tuple of alternative source names."""
    return (spec,) if isinstance(spec, str) else tuple(spec)


def _missing_names(skeleton: Skeleton, table) -> list[str]:
    have = {_norm_name(n) for n in skeleton.joint_names}
    return [_alternatives(s)[0] for s in table.values()
            if not any(_norm_name(a.split("@")[0]) in have for a in _alternatives(s))]


def detect_joint_map(skeleton: Skeleton, *, source: str | os.PathLike | None = None) -> str:
    """Name of the :data:`JOINT_MAPS` scheme that fits ``skeleton``'s joint names.

    Parameters
    ----------
    skeleton : Skeleton
        The source motion's skeleton.
    source : str or path-like, optional
        The motion file, named in the error message.

    Raises
    ------
    MotionFileError
        If no scheme fits; the message lists what the closest scheme misses.
    """
    best, best_missing = None, None
    for key, table in JOINT_MAPS.items():
        missing = _missing_names(skeleton, table)
        if not missing:
            return key
        if best_missing is None or len(missing) < len(best_missing):
            best, best_missing = key, missing
    raise MotionFileError(
        f"cannot map this skeleton onto the body model: closest naming scheme {best!r} "
        f"lacks joints {', '.join(m.split('@')[0] for m in best_missing)}"
        f" (known schemes: {', '.join(JOINT_MAPS)})",
        source,
    )


def source_joint_positions(
    motion: Motion, table, *, source: str | os.PathLike | None = None
) -> np.ndarray:
    """World positions of our 15 joints found in a source motion.

    Parameters
    ----------
    motion : Motion
        The source motion (any skeleton), metres.
    table : mapping of str to str or tuple of str
        One of :data:`JOINT_MAPS` (ours -> source names).

    Returns
    -------
    numpy.ndarray, shape (F, 15, 3)
        Metres, in :data:`vidcap.body.JOINT_NAMES` order.
    """
    sk = motion.skeleton
    index = {_norm_name(n): i for i, n in enumerate(sk.joint_names)}
    world_r, world_p = motion.world_transforms()
    out = np.empty((motion.n_frames, len(JOINT_NAMES), 3))
    for j, ours in enumerate(JOINT_NAMES):
        names = _alternatives(table[ours])
        spec = next((a for a in names if _norm_name(a.split("@")[0]) in index), names[0])
        name, _, end = spec.partition("@")
        k = index.get(_norm_name(name))
        if k is None:
            raise MotionFileError(f"no joint {name!r} to map onto {ours!r}", source)
        if not end:
            out[:, j] = world_p[:, k]
            continue
        site = sk.end_sites.get(sk.joint_names[k])
        if site is not None and np.linalg.norm(site) > 0:
            out[:, j] = world_p[:, k] + world_r[:, k] @ site
        else:
            kids = sk.children(k)
            if not kids:
                raise MotionFileError(f"joint {name!r} has no End Site or child", source)
            out[:, j] = world_p[:, kids[0]]
    return out


def _floor_motion(motion: Motion) -> Motion:
    """Shift ``motion`` vertically so its lowest ankle over the clip is at y = 0."""
    pos = motion.positions()
    ank = pos[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]], 1]
    root = motion.root_positions.copy()
    root[:, 1] -= ank.min()
    return Motion(motion.skeleton, root, motion.rotations, motion.fps)


def _up_fix(pts: np.ndarray) -> np.ndarray:
    """Rotate ``pts`` so the source's up axis (the dominant axis of pelvis -> neck) is +Y."""
    up = np.mean(pts[:, JOINT_INDEX["neck"]] - pts[:, JOINT_INDEX["pelvis"]], axis=0)
    k = int(np.argmax(np.abs(up)))
    if k == 1 and up[1] > 0:
        return pts
    axis = np.zeros(3)
    axis[k] = np.sign(up[k])
    rot = Rotation.from_quat(minimal_rotation(axis, np.array([0.0, 1.0, 0.0])))
    return pts @ rot.as_matrix().T


def retarget(
    motion: Motion,
    body: BodyModel | None = None,
    *,
    source: str | os.PathLike | None = None,
    solid_torso: bool = True,
) -> Motion:
    """Retarget a motion on any mappable skeleton onto our body by bone directions.

    Parameters
    ----------
    motion : Motion
        Source motion (metres; Y up, or Z up which is detected and turned to Y up).
    body : BodyModel, optional
        Target body (default: 1.75 m).
    source : str or path-like, optional
        The motion's file, named in errors.
    solid_torso : bool
        Turn arms that would pass through our (wider) torso out to its surface
        (:func:`keep_arms_out_of_torso`); False keeps every bone direction exactly.

    Returns
    -------
    Motion
        F frames on ``body.skeleton()``, same fps; root translation scaled by our
        leg length / the source's leg length; lowest ankle of the clip at y = 0.

    Raises
    ------
    MotionFileError
        If the skeleton's joints cannot be mapped (see :data:`JOINT_MAPS`).
    """
    body = body or BodyModel()
    table = JOINT_MAPS[detect_joint_map(motion.skeleton, source=source)]
    pts = _up_fix(source_joint_positions(motion, table, source=source))
    J = JOINT_INDEX
    legs = []
    for s in "lr":
        legs.append(
            np.linalg.norm(pts[:, J[f"{s}_knee"]] - pts[:, J[f"{s}_hip"]], axis=-1)
            + np.linalg.norm(pts[:, J[f"{s}_ankle"]] - pts[:, J[f"{s}_knee"]], axis=-1)
        )
    src_leg = float(np.median(np.concatenate(legs)))
    if not src_leg > 0:
        raise MotionFileError("the source's legs have zero length", source)
    out = joints_to_motion(pts, motion.fps, body=body)
    if solid_torso:
        out = joints_to_motion(keep_arms_out_of_torso(out.positions(), body), motion.fps,
                               body=body)
    scaled = Motion(out.skeleton, out.root_positions * (body.pelvis_height / src_leg),
                    out.rotations, out.fps)
    return _floor_motion(scaled)


def keep_arms_out_of_torso(joints3d, body: BodyModel | None = None, *,
                           iterations: int = 8) -> np.ndarray:
    """Turn elbows and wrists that lie inside the torso cylinder out to its surface.

    A point is inside when it is nearer the pelvis-neck axis than the torso's radius,
    between the pelvis and the neck. The upper arm turns about the shoulder toward
    the nearest surface point (the forearm moving with it), then the forearm about
    the elbow; bone lengths are kept, so a few passes settle a point that the first
    turn left just short of the surface.

    Parameters
    ----------
    joints3d : array_like, shape (F, 15, 3)
        Joints of ``body``'s skeleton, metres (bone lengths the model's).
    body : BodyModel, optional
    iterations : int
        Passes of the turn per joint.

    Returns
    -------
    numpy.ndarray, shape (F, 15, 3)
        A copy with the arms moved where needed; every other joint as given.
    """
    body = body or BodyModel()
    j = np.array(joints3d, dtype=float)
    J = JOINT_INDEX
    pel, neck = j[:, J["pelvis"]], j[:, J["neck"]]
    axis = neck - pel
    length = np.linalg.norm(axis, axis=-1)
    axis = axis / np.maximum(length, 1e-12)[:, None]
    r = body.radius("torso")

    def radial(x):
        d = x - pel
        h = np.sum(d * axis, -1)
        q = d - h[:, None] * axis
        return h, q, np.linalg.norm(q, axis=-1)

    for side in "lr":
        sh, el, wr = J[f"{side}_shoulder"], J[f"{side}_elbow"], J[f"{side}_wrist"]
        _, q_sh, rho_sh = radial(j[:, sh])
        outward = q_sh / np.maximum(rho_sh, 1e-12)[:, None]  # the arm's own side
        for pivot, point in ((sh, el), (el, wr)):
            bone = np.linalg.norm(j[:, point] - j[:, pivot], axis=-1)
            for _ in range(iterations):
                h, q, rho = radial(j[:, point])
                inside = (h > 0.0) & (h < length) & (rho < r)
                if not inside.any():
                    break
                away = np.where((rho > 1e-9)[:, None], q / np.maximum(rho, 1e-12)[:, None],
                                outward)
                # aimed a hair outside: the turned bone, shorter than the way to the
                # aim, falls a little short of it
                surface = pel + h[:, None] * axis + (r * (1.0 + 1e-3)) * away
                turned = j[:, pivot] + bone[:, None] * unit(surface - j[:, pivot])
                moved = np.where(inside[:, None], turned - j[:, point], 0.0)
                j[:, point] += moved
                if point == el:  # the forearm keeps its direction
                    j[:, wr] += moved
    return j
