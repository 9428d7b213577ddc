"""Test helper: pose the body model with forward kinematics and project it.

Independent of the synth branch: a walking-like motion made of sinusoidal joint
angles (hips/knees/shoulders/elbows), seen by an orthographic camera at a yaw.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from vidcap.body import JOINT_INDEX, JOINT_NAMES, BodyModel, segment_vectors
from vidcap.kinematics import Motion


def walk_motion(n_frames=60, fps=30.0, *, body=None, rng=None, speed=1.2, lean_deg=5.0):
    """A simple walk in the body's forward direction (-Z), as a Motion."""
    body = body or BodyModel()
    rng = rng or np.random.default_rng(0)
    sk = body.skeleton()
    t = np.arange(n_frames) / fps
    ph = 2 * np.pi * 1.0 * t + rng.uniform(0, 2 * np.pi)
    rot = np.zeros((n_frames, len(JOINT_NAMES), 4))
    rot[..., 3] = 1.0
    i = JOINT_INDEX

    def rx(deg):  # rotation about X: positive tips a -Y bone toward -Z (forward)
        return Rotation.from_euler("x", np.deg2rad(np.asarray(deg, float))[:, None]).as_quat()

    rot[:, i["pelvis"]] = rx(np.full(n_frames, -lean_deg))  # torso leans forward
    hip = 25 * np.sin(ph)
    rot[:, i["l_hip"]] = rx(-hip + 5)
    rot[:, i["r_hip"]] = rx(hip + 5)
    knee_l = 10 + 25 * (1 + np.sin(ph + 1.2))
    knee_r = 10 + 25 * (1 + np.sin(ph + np.pi + 1.2))
    rot[:, i["l_knee"]] = rx(-knee_l)  # shin folds backward (+Z)
    rot[:, i["r_knee"]] = rx(-knee_r)
    # arms hang down (from T-pose rotate about Z), swing fore/aft, elbows bent forward
    sw = 20 * np.sin(ph)
    down_l = Rotation.from_euler("z", np.full((n_frames, 1), np.deg2rad(80)))
    down_r = Rotation.from_euler("z", np.full((n_frames, 1), np.deg2rad(-80)))
    swing = np.deg2rad(sw)[:, None]
    rot[:, i["l_shoulder"]] = (Rotation.from_euler("x", swing) * down_l).as_quat()
    rot[:, i["r_shoulder"]] = (Rotation.from_euler("x", -swing) * down_r).as_quat()
    # elbow flexion: forearm (along -X for left arm in its frame) folds toward -Z world
    el_l = np.deg2rad(-(30 + 15 * np.sin(ph)))[:, None]
    el_r = np.deg2rad(30 - 15 * np.sin(ph))[:, None]
    rot[:, i["l_elbow"]] = Rotation.from_euler("y", el_l).as_quat()
    rot[:, i["r_elbow"]] = Rotation.from_euler("y", el_r).as_quat()
    root = np.zeros((n_frames, 3))
    root[:, 1] = body.pelvis_height - 0.03
    root[:, 2] = -speed * t
    return Motion(sk, root, rot, fps)


def to_camera(joints_world, yaw_deg):
    """World joints (body faces -Z) -> camera frame (X right, Y up, Z toward camera)
    for a body with yaw ``yaw_deg`` (0 = facing the camera, 90 = facing image right)."""
    R = Rotation.from_euler("y", np.deg2rad(yaw_deg) + np.pi)
    p = np.asarray(joints_world)
    return R.apply(p.reshape(-1, 3)).reshape(p.shape)


def project(joints_cam, scale=200.0, origin=(320.0, 400.0)):
    """Orthographic projection to pixels (x right, y down)."""
    j = np.asarray(joints_cam)
    return np.stack([origin[0] + scale * j[..., 0], origin[1] - scale * j[..., 1]], -1)


def true_signs(joints_cam):
    """+1 where a segment's distal joint is nearer the camera (larger Z)."""
    dz = segment_vectors(joints_cam)[..., 2]
    return np.where(dz >= 0, 1, -1).astype(np.int8)


def posed_clip(yaw_deg=90.0, n_frames=60, fps=30.0, *, body=None, scale=200.0, rng=None):
    """(joints2d px, joints3d camera-frame m, true signs, fps) of a walk at a yaw."""
    body = body or BodyModel()
    m = walk_motion(n_frames, fps, body=body, rng=rng)
    cam = to_camera(m.positions(), yaw_deg)
    return project(cam, scale), cam, true_signs(cam), fps
