"""The ground-truth camera: scaled orthographic, framing the whole clip.

Camera model (scaled orthographic, seed 004 Eq. 2.2)
----------------------------------------------------
``uv = camera[:, :3] @ X + camera[:, 3]`` with ``camera[0, :3] = s * right`` and
``camera[1, :3] = s * down`` (image x right, y down, pixels), ``s`` in pixels per
metre; ``view_dir`` is the unit direction the camera looks along (depth grows along
it), so a point is nearer the camera when ``view_dir @ X`` is smaller.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from vidcap.body import (
    JOINT_INDEX,
)
from vidcap.errors import UsageError
from vidcap.synth._geometry import unit


@dataclass(frozen=True)
class OrthoCamera:
    """A scaled orthographic camera.

    Attributes
    ----------
    matrix : numpy.ndarray, shape (2, 4)
        ``uv = matrix[:, :3] @ X + matrix[:, 3]``, pixels (x right, y down).
    view_dir : numpy.ndarray, shape (3,)
        Unit direction the camera looks along; depth = ``view_dir @ X`` (metres).
    size : (int, int)
        Image width and height, pixels.
    """

    matrix: np.ndarray
    view_dir: np.ndarray
    size: tuple[int, int]

    @property
    def pixels_per_metre(self) -> float:
        """Scale s of the projection, pixels per metre."""
        return float(np.linalg.norm(self.matrix[0, :3]))

    def project(self, X: np.ndarray) -> np.ndarray:
        """Project points (..., 3) metres to pixels (..., 2)."""
        X = np.asarray(X, dtype=float)
        return X @ self.matrix[:, :3].T + self.matrix[:, 3]

    def depth(self, X: np.ndarray) -> np.ndarray:
        """Depth (...,) metres along the view direction (larger = farther)."""
        return np.asarray(X, dtype=float) @ self.view_dir


def project(camera: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Project points (..., 3) with a (2, 4) camera matrix to pixels (..., 2)."""
    camera = np.asarray(camera, dtype=float)
    return np.asarray(X, dtype=float) @ camera[:, :3].T + camera[:, 3]


def body_forward(joints3d: np.ndarray) -> np.ndarray:
    """Horizontal unit facing direction of the body per frame, (F, 3), from joints (F, 15, 3)."""
    J = JOINT_INDEX
    lat = (joints3d[:, J["r_hip"]] - joints3d[:, J["l_hip"]]) + (
        joints3d[:, J["r_shoulder"]] - joints3d[:, J["l_shoulder"]]
    )
    fwd = np.cross(np.array([0.0, 1.0, 0.0]), lat)  # up x right = forward (-Z at rest)
    fwd[:, 1] = 0.0
    return unit(fwd)


def mean_heading(joints3d: np.ndarray) -> np.ndarray:
    """The clip's mean horizontal facing direction (3,), a circular mean of :func:`body_forward`."""
    fwd = body_forward(joints3d)
    m = fwd.sum(axis=0)
    if np.linalg.norm(m) < 1e-6 * len(fwd):
        m = fwd[0]
    return unit(m)


def body_yaw(joints3d: np.ndarray, view_dir: np.ndarray) -> np.ndarray:
    """Per-frame yaw (F,) radians of the body relative to the camera.

    0 = facing the camera, +pi/2 = facing image-right, pi = facing away (the
    convention of :func:`vidcap.body.orientation_from_yaw`).
    """
    v = np.asarray(view_dir, float).copy()
    v[1] = 0.0
    v = unit(v)
    right = unit(np.cross(v, [0.0, 1.0, 0.0]))
    f = body_forward(joints3d)
    return np.arctan2(f @ right, -(f @ v))


def make_camera(
    joints3d: np.ndarray,
    *,
    size: tuple[int, int] = (640, 480),
    yaw_deg: float = 90.0,
    elevation_deg: float = 0.0,
    pixels_per_metre: float | None = None,
    height: float = 1.75,
    fill: float = 0.75,
    margin: float = 0.04,
    floor_frac: float | None = None,
    radius: float = 0.2,
) -> OrthoCamera:
    """A fixed scaled-orthographic camera framing the whole clip.

    Parameters
    ----------
    joints3d : numpy.ndarray, shape (F, 15, 3)
        The body's joints over the clip, metres, Y up.
    size : (int, int)
        Image (width, height), pixels.
    yaw_deg : float
        Yaw of the body relative to the camera, degrees, measured from the clip's
        mean heading: 0 = facing the camera, 90 = side view facing image-right,
        180 = back view, -90 = facing image-left.
    elevation_deg : float
        Downward tilt of the camera, degrees (0 = horizontal view).
    pixels_per_metre : float, optional
        Scale; default: the figure's ``height`` fills ``fill`` of the image height,
        reduced if needed so the whole clip (joints plus ``radius``) stays within
        ``margin`` of the borders.
    height : float
        Standing height of the figure, metres (for the default scale).
    floor_frac : float, optional
        Where the floor under the clip's mean position appears, as a fraction of
        the image height from the top; default: centre the clip's extent vertically.
    radius : float
        Body half-width allowance around the joints for framing, metres.

    Returns
    -------
    OrthoCamera
    """
    W, H = int(size[0]), int(size[1])
    if W < 8 or H < 8:
        raise UsageError(f"image size must be at least 8x8 pixels, got {W}x{H}")
    joints3d = np.asarray(joints3d, dtype=float)
    f = mean_heading(joints3d)
    psi = np.deg2rad(yaw_deg)
    # In the body frame (forward = -Z) the camera looks along (-sin psi, 0, cos psi);
    # rotate that frame about Y so -Z goes to the mean heading f.
    theta = np.arctan2(-f[0], -f[2])  # rotation about Y taking -Z to f
    heading = Rotation.from_rotvec([0.0, theta, 0.0])
    v_h = heading.apply([-np.sin(psi), 0.0, np.cos(psi)])
    el = np.deg2rad(elevation_deg)
    view = unit(np.cos(el) * v_h - np.sin(el) * np.array([0.0, 1.0, 0.0]))
    right = unit(np.cross(v_h, [0.0, 1.0, 0.0]))
    down = np.cross(view, right)
    A = np.stack([right, down])  # (2, 3), unit scale
    uv = joints3d.reshape(-1, 3) @ A.T
    lo, hi = uv.min(0) - radius, uv.max(0) + radius
    span = hi - lo
    if pixels_per_metre is None:
        s = fill * H / height
        s = min(s, (1 - 2 * margin) * W / span[0], (1 - 2 * margin) * H / span[1])
    else:
        s = float(pixels_per_metre)
        if not s > 0:
            raise UsageError(f"pixels per metre must be positive, got {pixels_per_metre}")
    tx = W / 2 - s * 0.5 * (lo[0] + hi[0])
    if floor_frac is None:
        ty = H / 2 - s * 0.5 * (lo[1] + hi[1])
    else:
        centre = joints3d[:, JOINT_INDEX["pelvis"]].mean(0)
        centre[1] = 0.0
        ty = floor_frac * H - s * (down @ centre)
    matrix = np.concatenate([s * A, [[tx], [ty]]], axis=1)
    return OrthoCamera(matrix, view, (W, H))
