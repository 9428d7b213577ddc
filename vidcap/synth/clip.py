"""A ground-truth clip: the motion, camera and background it is rendered from
(:class:`Clip`, :func:`prepare_clip`), its frames (:func:`render_frame`,
:func:`iter_frames`), its truth (:func:`truth_arrays`, :func:`depth_signs`) and the
files :func:`synth_clip` writes."""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from vidcap.body import (
    JOINT_INDEX,
    JOINT_NAMES,
    SEGMENT_JOINTS,
    SEGMENT_NAMES,
    BodyModel,
    orientation_from_yaw,
)
from vidcap.errors import UsageError
from vidcap.kinematics import Motion
from vidcap.synth.backdrop import load_background, make_background
from vidcap.synth.camera import (
    OrthoCamera,
    body_yaw,
    make_camera,
)
from vidcap.synth.motions import make_motion
from vidcap.synth.render import finish_frame, lighting_gains, render_body


@dataclass(frozen=True)
class Clip:
    """Everything needed to render a clip, and its geometric truth.

    Attributes
    ----------
    motion : Motion
        The motion on our skeleton.
    body : BodyModel
    camera : OrthoCamera
    joints3d : numpy.ndarray, shape (F, 15, 3)
        Metres, Y up.
    background : numpy.ndarray, shape (H, W, 3) uint8
    gains : numpy.ndarray, shape (F, 3)
        Lighting gain per frame and channel.
    noise : float
        Gaussian pixel noise sigma, grey levels.
    foot : float
        Share of the standing height (head top to soles) below the ankles, drawn as
        feet (0: none, the seed's body standing on its ankles).
    """

    motion: Motion
    body: BodyModel
    camera: OrthoCamera
    joints3d: np.ndarray
    background: np.ndarray
    gains: np.ndarray
    noise: float
    foot: float = 0.0

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return self.joints3d.shape[0]


def prepare_clip(
    motion: Motion,
    *,
    body: BodyModel | None = None,
    size: tuple[int, int] = (640, 480),
    yaw_deg: float = 90.0,
    elevation_deg: float = 0.0,
    pixels_per_metre: float | None = None,
    floor_frac: float | None = None,
    background: np.ndarray | str | os.PathLike | None = None,
    noise: float = 2.0,
    lighting_drift: float = 0.0,
    rng: np.random.Generator | None = None,
    foot: float = 0.0,
) -> Clip:
    """Set up camera, background and lighting for ``motion`` (on our skeleton).

    ``body`` gives the cylinder radii (default: a body as tall as the motion's
    skeleton). See :func:`make_camera` for the camera options. ``background`` is an
    image array (resized if needed), an image file, or ``None`` for
    :func:`make_background`. ``rng`` (default ``default_rng(0)``) drives the
    background texture and the lighting phase. ``noise`` is the Gaussian pixel noise
    sigma (grey levels); ``lighting_drift`` the relative amplitude of a slow global
    brightness/colour change (:func:`lighting_gains`). ``foot`` is the share of the
    standing height below the ankles, drawn as feet (:func:`vidcap.synth.render.foot_segments`;
    0: none, the seed's body; e.g. :data:`vidcap.video.fit.proportions.HUMAN`'s
    ``1 - above_feet`` with that body), ``body.height`` then head top to ankles.
    """
    import cv2

    rng = rng if rng is not None else np.random.default_rng(0)
    if tuple(motion.skeleton.joint_names) != JOINT_NAMES:
        raise UsageError("render needs a motion on our skeleton (use retarget())")
    if body is None:  # the body whose skeleton the motion uses (its standing height)
        off = np.linalg.norm(motion.skeleton.offsets, axis=1)
        J = JOINT_INDEX
        body = BodyModel(height=float(off[J["neck"]] + off[J["head_top"]] + off[J["l_knee"]]
                                      + off[J["l_ankle"]]))
    if noise < 0 or lighting_drift < 0:
        raise UsageError("noise and lighting drift must not be negative")
    if not 0.0 <= foot < 0.3:
        raise UsageError(f"foot must be in [0, 0.3), got {foot!r}")
    joints3d = motion.positions()
    camera = make_camera(
        joints3d, size=size, yaw_deg=yaw_deg, elevation_deg=elevation_deg,
        pixels_per_metre=pixels_per_metre, height=body.height, floor_frac=floor_frac,
        radius=body.radius("torso"),
    )
    W, H = camera.size
    if background is None:
        ank = joints3d[:, [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]].reshape(-1, 3)
        floor_v = float(np.median(camera.project(ank)[:, 1]))
        horizon = float(np.clip(floor_v / H - 0.08, 0.3, 0.95))
        bg = make_background((W, H), rng, horizon=horizon)
    elif isinstance(background, np.ndarray):
        bg = background
        if bg.ndim != 3 or bg.shape[2] != 3:
            raise UsageError(f"background must be (H, W, 3) BGR, got {bg.shape}")
        if bg.shape[:2] != (H, W):
            bg = cv2.resize(bg, (W, H), interpolation=cv2.INTER_AREA)
        bg = bg.astype(np.uint8)
    else:
        bg = load_background(background, (W, H))
    gains = lighting_gains(motion.n_frames, motion.fps, lighting_drift, rng)
    return Clip(motion, body, camera, joints3d, bg, gains.astype(np.float32), float(noise),
                float(foot))


def render_frame(clip: Clip, i: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Frame ``i`` of ``clip``: BGR uint8 (H, W, 3) with noise, and its mask (H, W) bool."""
    img, mask = render_body(clip.joints3d[i], clip.camera, clip.body, clip.background,
                            foot=clip.foot)
    return finish_frame(img, rng, noise=clip.noise, gain=clip.gains[i]), mask


def iter_frames(
    clip: Clip, rng: np.random.Generator, *, show_progress: bool | None = None
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Yield ``(frame, mask)`` for every frame of ``clip`` (see :func:`render_frame`)."""
    from vidcap.fileio import progress

    for i in progress(range(clip.n_frames), desc="rendering", unit="frame",
                      enabled=show_progress):
        yield render_frame(clip, i, rng)


def depth_signs(joints3d: np.ndarray, view_dir: np.ndarray) -> np.ndarray:
    """+1 where a segment's distal end is nearer the camera than its proximal end, else -1.

    Parameters
    ----------
    joints3d : numpy.ndarray, shape (F, 15, 3)
    view_dir : numpy.ndarray, shape (3,)

    Returns
    -------
    numpy.ndarray, shape (F, 10) int8
    """
    dz = (joints3d[:, SEGMENT_JOINTS[:, 1]] - joints3d[:, SEGMENT_JOINTS[:, 0]]) @ view_dir
    return np.where(dz < 0, 1, -1).astype(np.int8)


def truth_arrays(clip: Clip, masks: np.ndarray) -> dict[str, np.ndarray]:
    """The truth of ``clip`` as the arrays saved by :func:`synth_clip`.

    Keys: ``joint_names`` (15,), ``masks`` (F, H, W) bool, ``joints2d`` (F, 15, 2) px,
    ``joints3d`` (F, 15, 3) m, ``depth_signs`` (F, 10) int8, ``segment_names`` (10,),
    ``orientation`` (F,) str, ``yaw_deg`` (F,), ``camera`` (2, 4), ``view_dir`` (3,),
    ``fps`` ().
    """
    cam = clip.camera
    yaw = body_yaw(clip.joints3d, cam.view_dir)
    return {
        "joint_names": np.array(JOINT_NAMES),
        "masks": np.asarray(masks, dtype=bool),
        "joints2d": cam.project(clip.joints3d),
        "joints3d": clip.joints3d,
        "depth_signs": depth_signs(clip.joints3d, cam.view_dir),
        "segment_names": np.array(SEGMENT_NAMES),
        "orientation": np.asarray(orientation_from_yaw(yaw)).astype(str).reshape(-1),
        "yaw_deg": np.rad2deg(yaw),
        "camera": cam.matrix,
        "view_dir": cam.view_dir,
        "fps": np.float64(clip.motion.fps),
    }


def render_clip(
    motion: Motion,
    *,
    rng: np.random.Generator | None = None,
    show_progress: bool | None = False,
    **options,
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Render ``motion`` (on our skeleton) in memory.

    Parameters
    ----------
    motion : Motion
        On ``BodyModel(...).skeleton()`` (see :func:`make_motion`).
    rng : numpy.random.Generator, optional
        Background, lighting and noise (default ``default_rng(0)``).
    **options
        :func:`prepare_clip` options (``body``, ``size``, ``yaw_deg``,
        ``elevation_deg``, ``pixels_per_metre``, ``floor_frac``, ``background``,
        ``noise``, ``lighting_drift``).

    Returns
    -------
    frames : numpy.ndarray, shape (F, H, W, 3) uint8
        BGR.
    truth : dict
        :func:`truth_arrays`.
    """
    rng = rng if rng is not None else np.random.default_rng(0)
    clip = prepare_clip(motion, rng=rng, **options)
    W, H = clip.camera.size
    frames = np.empty((clip.n_frames, H, W, 3), np.uint8)
    masks = np.empty((clip.n_frames, H, W), bool)
    for i, (frame, mask) in enumerate(iter_frames(clip, rng, show_progress=show_progress)):
        frames[i], masks[i] = frame, mask
    return frames, truth_arrays(clip, masks)


def synth_clip(
    out_video: str | os.PathLike,
    truth_path: str | os.PathLike,
    motion: Motion | str | os.PathLike = "walk",
    *,
    bvh_path: str | os.PathLike | None = None,
    rng: np.random.Generator | None = None,
    show_progress: bool | None = None,
    crf: int = 18,
    **options,
) -> dict[str, np.ndarray]:
    """Render a clip to a video file and save its truth (both atomically).

    Parameters
    ----------
    out_video : str or path-like
        H.264 video to write (via :class:`vidcap.io.video.VideoWriter`).
    truth_path : str or path-like
        ``.npz`` truth (:func:`truth_arrays` keys), via
        :func:`vidcap.fileio.savez_atomic`.
    motion : Motion or str or path-like
        A motion on our skeleton, or anything :func:`make_motion` takes (then built
        with ``body`` and ``rng``).
    bvh_path : str or path-like, optional
        Also write the motion (on our skeleton) as BVH.
    rng : numpy.random.Generator, optional
        Default ``default_rng(0)``.
    **options
        :func:`prepare_clip` options.

    Returns
    -------
    dict
        The saved truth arrays.
    """
    from vidcap.fileio import savez_atomic
    from vidcap.io.video import VideoWriter

    rng = rng if rng is not None else np.random.default_rng(0)
    if not isinstance(motion, Motion):
        motion = make_motion(motion, body=options.get("body"), rng=rng)
    clip = prepare_clip(motion, rng=rng, **options)
    W, H = clip.camera.size
    if W % 2 or H % 2:
        raise UsageError(f"H.264 needs an even image size, got {W}x{H}", out_video)
    masks = np.empty((clip.n_frames, H, W), bool)
    with VideoWriter(out_video, motion.fps, crf=crf) as writer:
        for i, (frame, mask) in enumerate(iter_frames(clip, rng, show_progress=show_progress)):
            writer.write(frame)
            masks[i] = mask
    truth = truth_arrays(clip, masks)
    savez_atomic(truth_path, **truth)
    if bvh_path is not None:
        from vidcap.io.bvh import write_bvh

        write_bvh(bvh_path, motion)
    return truth
