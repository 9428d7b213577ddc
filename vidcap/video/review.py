"""Review frames: input | silhouette with the 2D model | 3D pose (seed 004 Figures 4.1-4.2).

The 3D panel is rendered off screen with pyvista (VTK falls back to OSMesa/EGL
without a display); the figure is seen from 40 degrees to the camera's side so
depth is visible, with a floor grid.
"""

from __future__ import annotations

import os

import numpy as np

from vidcap.body import JOINT_INDEX, SEGMENT_JOINTS, SEGMENT_NAMES

_LEFT = (255, 128, 0)  # BGR: blue-ish for the body's left
_RIGHT = (0, 96, 255)  # orange-red for the right
_MID = (0, 200, 0)


def _segment_colours():
    return [_LEFT if n.startswith("l_") else _RIGHT if n.startswith("r_") else _MID
            for n in SEGMENT_NAMES]


def draw_2d(mask, joints2d, *, low=None) -> np.ndarray:
    """The silhouette (grey) with the 2D model's segments drawn over it, (H, W, 3) uint8.

    ``low`` (10,) bool marks low-confidence segments, drawn thin and dashed-looking
    (white ends).
    """
    import cv2

    img = np.where(np.asarray(mask, bool)[..., None], 110, 25).astype(np.uint8).repeat(3, -1)
    h = img.shape[0]
    thick = max(2, h // 120)
    for k, (a, b) in enumerate(SEGMENT_JOINTS):
        pa = tuple(int(round(x)) for x in joints2d[a])
        pb = tuple(int(round(x)) for x in joints2d[b])
        weak = low is not None and low[k]
        cv2.line(img, pa, pb, _segment_colours()[k], 1 if weak else thick, cv2.LINE_AA)
        if weak:
            cv2.circle(img, pb, thick + 2, (255, 255, 255), 1, cv2.LINE_AA)
    for p in joints2d:
        cv2.circle(img, tuple(int(round(x)) for x in p), thick, (240, 240, 240), -1, cv2.LINE_AA)
    return img


def quiet_vtk() -> None:
    """Without an X display, hide VTK's harmless "bad X server connection" warning
    before it falls back to EGL (with one, VTK's warnings stay)."""
    if os.environ.get("DISPLAY"):
        return
    try:
        from vtkmodules.vtkCommonCore import vtkLogger

        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
    except ImportError:  # pragma: no cover - older VTK
        pass


class PoseRenderer:
    """Off-screen pyvista renderer of the 3D skeleton, one (H, W, 3) BGR image per pose."""

    def __init__(self, size: tuple[int, int], *, azimuth_deg: float = 40.0, height: float = 1.75):
        import pyvista as pv

        quiet_vtk()
        pv.OFF_SCREEN = True
        w, h = size
        self.pl = pv.Plotter(off_screen=True, window_size=(w + (w % 2), h + (h % 2)))
        self.pl.set_background("white")
        n = len(SEGMENT_JOINTS)
        self.points = np.zeros((len(JOINT_INDEX), 3))
        lines = np.hstack([np.full((n, 1), 2), SEGMENT_JOINTS]).ravel()
        self.mesh = pv.PolyData(self.points.copy(), lines=lines)
        cols = np.array([c[::-1] for c in _segment_colours()], np.uint8)
        self.mesh.cell_data["rgb"] = cols
        self.pl.add_mesh(self.mesh, scalars="rgb", rgb=True, line_width=6,
                         render_lines_as_tubes=True)
        self.joints = pv.PolyData(self.points.copy())
        self.pl.add_mesh(self.joints, color="black", point_size=9,
                         render_points_as_spheres=True)
        floor = pv.Plane(center=(0, 0, 0), direction=(0, 1, 0), i_size=4 * height,
                         j_size=4 * height, i_resolution=8, j_resolution=8)
        self.floor = floor
        self.floor_actor = self.pl.add_mesh(floor, style="wireframe", color="grey", opacity=0.5)
        self.az = np.deg2rad(azimuth_deg)
        self.height = height
        self.size = (w, h)

    def render(self, joints3d) -> np.ndarray:
        """Render one pose (15, 3) metres (Y up); returns (H, W, 3) uint8 BGR."""
        p = np.asarray(joints3d, float)
        self.mesh.points = p
        self.joints.points = p
        c = p[JOINT_INDEX["pelvis"]].copy()
        self.floor_actor.position = (c[0], 0.0, c[2])
        focus = (c[0], 0.5 * self.height, c[2])
        d = 3.2 * self.height
        eye = (focus[0] + d * np.sin(self.az), focus[1] + 0.25 * d, focus[2] + d * np.cos(self.az))
        self.pl.camera_position = [eye, focus, (0, 1, 0)]
        # screenshot() reuses the last rendered image; new points need a fresh render.
        self.pl.render()
        img = self.pl.screenshot(return_img=True)
        w, h = self.size
        return np.ascontiguousarray(img[:h, :w, ::-1])

    def close(self):
        self.pl.close()


def review_scale(frame_height: int, min_height: int) -> int:
    """Whole-number factor that brings a panel ``frame_height`` px tall to at least
    ``min_height`` px (1 when it is already tall enough)."""
    return max(1, -(-int(min_height) // max(int(frame_height), 1)))


def review_frames(frames, masks, joints2d, joints3d, *, scores=None, similarity=None,
                  low_score: float = 0.5, height: float = 1.75, min_height: int = 360,
                  filled=None, max_height: int = 720):
    """Yield the three-panel review images, (k H, 3 k W, 3) uint8 BGR each (H, W
    shrunk to ``max_height`` for a tall video).

    Parameters
    ----------
    frames : iterable of (H, W, 3) uint8
    masks : (F, H, W) bool
    joints2d : (F, 15, 2) px; joints3d : (F, 15, 3) m (Y up)
    scores : (F, 10), optional
        Per-segment 2D fit scores; below ``low_score`` a segment is marked.
    similarity : (F,), optional
        Whole-model fit; below ``low_score`` the frame is marked "LOW".
    filled : (F,) bool, optional
        Frames whose pose was not fitted but filled from the neighbouring frames (no
        person, or mostly outside the picture): marked "FILLED" instead.
    min_height : int
        Panels of a smaller video are enlarged by the whole-number factor
        ``k = ceil(min_height / H)`` (:func:`review_scale`; pixels repeated, so the
        input is shown as it is), so a 180x144 clip is not reviewed at thumbnail
        size. 0 or a frame at least this tall: ``k = 1``.
    max_height : int
        Panels of a taller video are shrunk to this height (area averaging), so a
        1080p or 4K video gives a review a player can show (a 4K one was 11520 px
        wide). 0: never shrunk.
    """
    import cv2

    renderer = None
    k = 1
    try:
        for f, frame in enumerate(frames):
            if renderer is None:
                fh, fw = frame.shape[:2]
                k = review_scale(fh, min_height)
                shrink = bool(max_height) and fh > max_height
                # (even sizes: the video encoder's 4:2:0 chroma needs them)
                size = ((2 * round(fw * max_height / fh / 2), max_height) if shrink
                        else (k * fw, k * fh))
                renderer = PoseRenderer(size, height=height)
            mask = np.asarray(masks[f], bool)
            j2 = np.asarray(joints2d[f], float)
            if shrink:
                sx, sy = size[0] / fw, size[1] / fh
                frame = cv2.resize(frame, size, interpolation=cv2.INTER_AREA)
                mask = cv2.resize(mask.view(np.uint8), size, interpolation=cv2.INTER_AREA) > 0
                j2 = (j2 + 0.5) * (sx, sy) - 0.5  # pixel centres
            elif k > 1:
                frame = cv2.resize(frame, None, fx=k, fy=k, interpolation=cv2.INTER_NEAREST)
                mask = mask.repeat(k, 0).repeat(k, 1)
                j2 = k * j2 + (k - 1) / 2  # pixel centres: (x, y) -> k x + (k - 1) / 2
            h, w = frame.shape[:2]
            low = None if scores is None else np.asarray(scores[f]) < low_score
            left = frame.copy()
            mid = draw_2d(mask, j2, low=low)
            right = renderer.render(joints3d[f])
            img = np.concatenate([left, mid, right], axis=1)
            fs = max(0.4, h / 600)
            cv2.putText(img, f"{f}", (8, int(24 * fs * 1.6)), cv2.FONT_HERSHEY_SIMPLEX, fs,
                        (255, 255, 255), 2, cv2.LINE_AA)
            if filled is not None and filled[f]:
                cv2.putText(img, "FILLED", (w + 8, int(24 * fs * 1.6)),
                            cv2.FONT_HERSHEY_SIMPLEX, fs, (0, 165, 255), 2, cv2.LINE_AA)
                cv2.rectangle(img, (w, 0), (2 * w - 1, h - 1), (0, 165, 255), 2)
            elif similarity is not None and similarity[f] < low_score:
                cv2.putText(img, "LOW", (w + 8, int(24 * fs * 1.6)), cv2.FONT_HERSHEY_SIMPLEX,
                            fs, (0, 0, 255), 2, cv2.LINE_AA)
                cv2.rectangle(img, (w, 0), (2 * w - 1, h - 1), (0, 0, 255), 2)
            yield img
    finally:
        if renderer is not None:
            renderer.close()
