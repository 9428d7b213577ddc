"""Ground-truth clips: pose the body model with a motion, film it, keep the answers.

The renderer makes the test and benchmark inputs of the video path (seed 004): a
person made of the ten cylinders of :mod:`vidcap.body`, moved by a real motion
(BVH or ASF/AMC, retargeted onto our skeleton) or a built-in procedural one, seen
by a fixed scaled-orthographic camera over a textured background, with pixel noise
and optional slow lighting drift. Beside every clip we keep the truth: masks, 2D
and 3D joints, each segment's depth sign, the body orientation label and the camera.

Pipeline
--------
1. :func:`make_motion` -> a :class:`~vidcap.kinematics.Motion` on our skeleton
   (``'walk'``, ``'jacks'``, ``'arms'``, or a file retargeted by :func:`retarget`).
2. :func:`make_camera` -> an :class:`OrthoCamera` framing the whole clip.
3. :func:`render_frame` / :func:`iter_frames` -> BGR frames and body masks.
4. :func:`truth_arrays` -> the truth dictionary saved by :func:`synth_clip`.

Modules
-------
:mod:`~vidcap.synth.retarget` (joint maps, retargeting a source motion),
:mod:`~vidcap.synth.procedural` (the built-in motions), :mod:`~vidcap.synth.motions`
(:func:`make_motion`), :mod:`~vidcap.synth.camera` (the scaled orthographic camera and
its model), :mod:`~vidcap.synth.backdrop` (backgrounds), :mod:`~vidcap.synth.render`
(drawing the cylinders) and :mod:`~vidcap.synth.clip` (clips and their truth). Every
public name is importable from ``vidcap.synth`` itself.
"""

from __future__ import annotations

from vidcap.synth.backdrop import load_background, make_background
from vidcap.synth.camera import (
    OrthoCamera,
    body_forward,
    body_yaw,
    make_camera,
    mean_heading,
    project,
)
from vidcap.synth.clip import (
    Clip,
    depth_signs,
    iter_frames,
    prepare_clip,
    render_clip,
    render_frame,
    synth_clip,
    truth_arrays,
)
from vidcap.synth.motions import make_motion, parse_range
from vidcap.synth.procedural import (
    BUILTIN_MOTIONS,
    arms_motion,
    jacks_motion,
    sit_motion,
    walk_motion,
)
from vidcap.synth.render import SHIRT, SKIN, TROUSERS, finish_frame, lighting_gains, render_body
from vidcap.synth.retarget import (
    JOINT_MAPS,
    detect_joint_map,
    keep_arms_out_of_torso,
    retarget,
    source_joint_positions,
)

__all__ = ["BUILTIN_MOTIONS", "Clip", "JOINT_MAPS", "OrthoCamera", "SHIRT", "SKIN", "TROUSERS",
           "arms_motion", "body_forward", "body_yaw", "depth_signs", "detect_joint_map",
           "finish_frame", "iter_frames", "jacks_motion", "keep_arms_out_of_torso",
           "lighting_gains", "load_background", "make_background", "make_camera", "make_motion",
           "mean_heading", "parse_range", "prepare_clip", "project", "render_body", "render_clip",
           "render_frame", "retarget", "sit_motion", "source_joint_positions", "synth_clip",
           "truth_arrays", "walk_motion"]
