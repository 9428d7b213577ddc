"""3D viewer for results: a BVH skeleton over a ground grid, or a C3D marker cloud.

Used by ``vidcap view``. Every scene is an ordinary :class:`pyvista.Plotter`, so the
same code draws an interactive window, an offscreen PNG (``--screenshot``) and the
test images (``pyvista.OFF_SCREEN = True``).
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vidcap.errors import InputFileError, UsageError
from vidcap.video.review import quiet_vtk

#: Colours of the scene (RGB 0-1).
BONE_COLOUR = (0.16, 0.42, 0.80)
JOINT_COLOUR = (0.95, 0.55, 0.10)
MARKER_COLOUR = (0.55, 0.55, 0.58)
CENTRE_COLOUR = (0.85, 0.12, 0.15)
GRID_COLOUR = (0.62, 0.62, 0.62)
BACKGROUND = (1.0, 1.0, 1.0)

#: Bones drawn between joint centres (``--centres``): each joint's parent is the first of
#: its candidates present in the file, so the optional ``spine`` of the marker path slots in
#: between pelvis and neck, and the shoulders hang from the neck (a clavicle line) rather
#: than from the pelvis as in the rigid-torso body model.
CENTRE_PARENTS = {
    "spine": ("pelvis",), "chest": ("spine", "pelvis"), "neck": ("chest", "spine", "pelvis"),
    "head_top": ("neck",), "head": ("neck",),
    "l_shoulder": ("neck", "chest", "spine", "pelvis"),
    "r_shoulder": ("neck", "chest", "spine", "pelvis"),
    "l_elbow": ("l_shoulder",), "l_wrist": ("l_elbow",), "r_elbow": ("r_shoulder",),
    "r_wrist": ("r_elbow",), "l_hip": ("pelvis",), "r_hip": ("pelvis",),
    "l_knee": ("l_hip",), "l_ankle": ("l_knee",), "r_knee": ("r_hip",), "r_ankle": ("r_knee",),
    "l_toe": ("l_ankle",), "r_toe": ("r_ankle",), "l_heel": ("l_ankle",),
    "r_heel": ("r_ankle",), "l_hand": ("l_wrist",), "r_hand": ("r_wrist",),
    "l_hand_end": ("l_hand", "l_wrist"), "r_hand_end": ("r_hand", "r_wrist"),
}


# --------------------------------------------------------------------------- data
@dataclass(frozen=True)
class Points3D:
    """Points moving over F frames, with optional bones between them.

    Parameters
    ----------
    names : tuple of str
        One name per point (length P).
    positions : numpy.ndarray, shape (F, P, 3)
        Positions in metres; NaN where a point is missing in a frame.
    bones : numpy.ndarray, shape (B, 2) int
        Index pairs (parent, child) to draw as lines.
    fps : float
        Frames per second.
    up : int
        Index of the vertical axis (1 = Y up as in BVH, 2 = Z up as in most C3D files).
    """

    names: tuple
    positions: np.ndarray
    bones: np.ndarray
    fps: float
    up: int = 1

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return self.positions.shape[0]


def motion_points(motion) -> Points3D:
    """Joint positions and bones of a :class:`vidcap.kinematics.Motion`.

    End sites become extra points (named ``<joint>_end``) so that the last bone of
    every chain (head, hands, feet) is drawn too.
    """
    pos = motion.positions()
    names = list(motion.skeleton.joint_names)
    bones = [(p, j) for j, p in enumerate(motion.skeleton.parents) if p >= 0]
    ends = motion.end_site_positions()
    extra = []
    for name, p in ends.items():
        extra.append(p)
        bones.append((motion.skeleton.index(name), len(names)))
        names.append(f"{name}_end")
    if extra:
        pos = np.concatenate([pos, np.stack(extra, axis=1)], axis=1)
    return Points3D(tuple(names), pos, np.asarray(bones, dtype=int).reshape(-1, 2), motion.fps, 1)


def read_c3d_points(path: str | os.PathLike) -> Points3D:
    """The markers of a C3D file (:func:`vidcap.mocap.c3d.read_c3d`): metres, gaps as NaN.

    Raises
    ------
    vidcap.errors.C3DError
        If the file is missing or cannot be parsed.
    """
    from vidcap.mocap.c3d import read_c3d

    data = read_c3d(path)
    up = int(np.argmax(np.abs(data.up)))
    return Points3D(tuple(data.labels), data.positions, np.zeros((0, 2), int), data.fps, up)


def read_centres_csv(path: str | os.PathLike) -> Points3D:
    """Joint centres from a CSV with header ``frame,time_s,joint,x_m,y_m,z_m``.

    Bones join each joint to its parent (:data:`CENTRE_PARENTS`) where both are present.

    Raises
    ------
    InputFileError
        If the file is missing, lacks a column, or holds a non-numeric value.
    """
    path = Path(path)
    need = ["frame", "joint", "x_m", "y_m", "z_m"]
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
    except OSError as exc:
        raise InputFileError(f"cannot read joint-centre CSV: {exc.strerror or exc}", path) from None
    if not rows or any(k not in rows[0] for k in need):
        raise InputFileError(
            "not a joint-centre CSV (needs the header frame,time_s,joint,x_m,y_m,z_m)", path)
    names = list(dict.fromkeys(r["joint"] for r in rows))
    try:
        frames = np.array([int(r["frame"]) for r in rows])
        xyz = np.array([[float(r["x_m"] or "nan"), float(r["y_m"] or "nan"),
                         float(r["z_m"] or "nan")] for r in rows])
        times = [float(r["time_s"]) for r in rows] if "time_s" in rows[0] else []
    except (TypeError, ValueError) as exc:
        raise InputFileError(f"non-numeric value in joint-centre CSV ({exc})", path) from None
    f0 = frames.min()
    pos = np.full((frames.max() - f0 + 1, len(names), 3), np.nan)
    index = {n: i for i, n in enumerate(names)}
    pos[frames - f0, [index[r["joint"]] for r in rows]] = xyz
    bones = []
    for n in names:
        parent = next((p for p in CENTRE_PARENTS.get(n, ()) if p in index), None)
        if parent is not None:
            bones.append((index[parent], index[n]))
    fps = 100.0
    if len(times) > 1 and len(set(frames.tolist())) > 1:
        t = np.asarray(times)
        span = frames.max() - f0
        if t.max() > t.min():
            fps = float(span / (t.max() - t.min()))
    return Points3D(tuple(names), pos, np.asarray(bones, int).reshape(-1, 2), fps, 2)


def load_points(path: str | os.PathLike) -> Points3D:
    """Read a BVH (skeleton) or C3D (markers) file for viewing.

    Raises
    ------
    UsageError
        If the extension is neither ``.bvh`` nor ``.c3d``.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext == ".bvh":
        from vidcap.io.bvh import read_bvh

        if not path.is_file():
            raise InputFileError("no such BVH file", path)
        return motion_points(read_bvh(path))
    if ext == ".c3d":
        return read_c3d_points(path)
    raise UsageError(f"cannot view '{ext or path.name}' files (a .bvh or .c3d file is needed)",
                     path)


# --------------------------------------------------------------------------- scene
def _bone_polydata(points: np.ndarray, bones: np.ndarray):
    import pyvista as pv

    lines = np.column_stack([np.full(len(bones), 2), bones]).ravel()
    return pv.PolyData(np.nan_to_num(points).astype(float), lines=lines)


def _frame_points(points: np.ndarray):
    """Points of one frame without the missing ones (keeps at least one, for VTK)."""
    ok = np.isfinite(points).all(axis=1)
    return points[ok] if ok.any() else np.zeros((1, 3))


def _bones_of_frame(points: np.ndarray, bones: np.ndarray) -> np.ndarray:
    ok = np.isfinite(points).all(axis=1)
    return bones[ok[bones].all(axis=1)] if len(bones) else bones


def ground_grid(extent_min: np.ndarray, extent_max: np.ndarray, *, up: int = 1,
                spacing: float = 0.5):
    """A wireframe floor (at 0 on the ``up`` axis) covering the given horizontal extent.

    Parameters
    ----------
    extent_min, extent_max : numpy.ndarray, shape (3,)
        Bounding box of what stands on the floor, metres.
    up : int
        Index of the vertical axis.
    spacing : float
        Cell size, metres.
    """
    import pyvista as pv

    h = [a for a in range(3) if a != up]
    lo = np.floor(extent_min[h] / spacing - 1) * spacing
    hi = np.ceil(extent_max[h] / spacing + 1) * spacing
    ticks = [np.linspace(lo[k], hi[k], int(round((hi[k] - lo[k]) / spacing)) + 1) for k in (0, 1)]
    ends = []
    for k in (0, 1):  # lines along the other horizontal axis, one per tick of this one
        t = ticks[k]
        a = np.zeros((len(t), 3))
        a[:, h[k]] = t
        b = a.copy()
        a[:, h[1 - k]], b[:, h[1 - k]] = lo[1 - k], hi[1 - k]
        ends.append(np.stack([a, b], axis=1))
    seg = np.concatenate(ends).reshape(-1, 3)
    n = len(seg) // 2
    lines = np.column_stack([np.full(n, 2), 2 * np.arange(n), 2 * np.arange(n) + 1]).ravel()
    return pv.PolyData(seg, lines=lines)


class Scene:
    """A plotter showing :class:`Points3D` data at one frame, able to change frame.

    Parameters
    ----------
    data : Points3D
        The main data (skeleton or markers).
    overlay : Points3D, optional
        Joint centres drawn over markers (frames aligned with ``data``).
    window_size : tuple of int
        Width and height in pixels.
    off_screen : bool, optional
        Render without a window (default: ``pyvista.OFF_SCREEN``).
    plotter : pyvista.Plotter, optional
        Draw into this plotter (e.g. one shown in a web page) instead of a new one.
    follow : bool
        Frame the camera on the current frame's points (for single-frame pictures);
        otherwise on the whole clip (for playing it).
    view_direction : array_like, shape (3,), optional
        From where the camera looks at the scene's centre (default: front-right,
        a little above).
    """

    def __init__(self, data: Points3D, *, overlay: Points3D | None = None,
                 window_size=(800, 600), off_screen=None, plotter=None, follow=False,
                 view_direction=None):
        import pyvista as pv

        self.data = data
        self.overlay = overlay
        self.follow = follow
        self.view_direction = view_direction
        #: Optional per-frame bone colours (F, B, 3) uint8 RGB for the main data.
        self.bone_rgb = None
        self.frame = 0
        if off_screen or pv.OFF_SCREEN:
            quiet_vtk()
        self.plotter = plotter if plotter is not None else pv.Plotter(
            off_screen=pv.OFF_SCREEN if off_screen is None else off_screen,
            window_size=list(window_size))
        pl = self.plotter
        pl.set_background(BACKGROUND)
        all_pts = data.positions.reshape(-1, 3)
        if overlay is not None:
            all_pts = np.concatenate([all_pts, overlay.positions.reshape(-1, 3)])
        all_pts = all_pts[np.isfinite(all_pts).all(axis=1)]
        if not len(all_pts):
            all_pts = np.zeros((1, 3))
        lo, hi = all_pts.min(axis=0), all_pts.max(axis=0)
        # a robust box: ignore a few far outliers (stray markers) when framing the camera
        if len(all_pts) > 50:
            lo, hi = np.percentile(all_pts, 0.5, axis=0), np.percentile(all_pts, 99.5, axis=0)
        self.bounds = (lo, hi)
        pl.add_mesh(ground_grid(lo, hi, up=data.up), style="wireframe", color=GRID_COLOUR,
                    line_width=1, lighting=False, name="grid")
        self._actors = {}
        self._draw()
        self._set_camera(*self._camera_box())

    def _camera_box(self):
        if not self.follow:
            return self.bounds
        pts = self.data.positions[self.frame]
        if self.overlay is not None:
            pts = np.concatenate([pts, self.overlay.positions[
                min(self.frame, self.overlay.n_frames - 1)]])
        pts = pts[np.isfinite(pts).all(axis=1)]
        if not len(pts):
            return self.bounds
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        lo[self.data.up] = min(lo[self.data.up], 0.0)  # keep the floor in view
        return lo, hi

    def _layer(self, key, pts3d: Points3D, *, colour, point_size, line_width, bone_colour):
        import pyvista as pv

        f = min(self.frame, pts3d.n_frames - 1)
        pts = pts3d.positions[f]
        ok = np.isfinite(pts).all(axis=1)
        keep = ok[pts3d.bones].all(axis=1) if len(pts3d.bones) else np.zeros(0, bool)
        bones = pts3d.bones[keep]
        self.plotter.add_mesh(pv.PolyData(_frame_points(pts)), color=colour, point_size=point_size,
                              render_points_as_spheres=True, name=f"{key}_points",
                              reset_camera=False)
        rgb = None if key != "data" or self.bone_rgb is None else self.bone_rgb[f][keep]
        if len(bones):
            poly = _bone_polydata(pts, bones)
            style = dict(line_width=line_width, render_lines_as_tubes=True, name=f"{key}_bones",
                         reset_camera=False)
            if rgb is None:
                self.plotter.add_mesh(poly, color=bone_colour, **style)
            else:
                poly.cell_data["rgb"] = np.asarray(rgb, np.uint8)
                self.plotter.add_mesh(poly, scalars="rgb", rgb=True, **style)
        else:
            self.plotter.remove_actor(f"{key}_bones")

    def _draw(self):
        is_markers = len(self.data.bones) == 0
        self._layer("data", self.data, colour=MARKER_COLOUR if is_markers else JOINT_COLOUR,
                    point_size=8 if is_markers else 10, line_width=5, bone_colour=BONE_COLOUR)
        if self.overlay is not None:
            self._layer("overlay", self.overlay, colour=CENTRE_COLOUR, point_size=12,
                        line_width=4, bone_colour=CENTRE_COLOUR)

    def _set_camera(self, lo, hi):
        centre = (lo + hi) / 2
        size = float(np.max(hi - lo)) or 1.0
        up = np.zeros(3)
        up[self.data.up] = 1.0
        if self.view_direction is not None:
            direction = np.array(self.view_direction, dtype=float)
        elif self.data.up == 1:  # Y up, -Z forward: look from front-right, a little above
            direction = np.array([0.7, 0.3, -1.0])
        else:  # Z up: look from +X,-Y, a little above
            direction = np.array([0.7, -1.0, 0.3])
        direction /= np.linalg.norm(direction)
        cam = self.plotter.camera
        cam.focal_point = centre
        cam.position = centre + direction * size * 2.3
        cam.up = up
        self.plotter.reset_camera_clipping_range()

    def set_frame(self, frame: int) -> None:
        """Show frame ``frame`` (0-based; clipped to the clip)."""
        self.frame = int(np.clip(frame, 0, self.data.n_frames - 1))
        self._draw()
        if self.follow:
            self._set_camera(*self._camera_box())

    def screenshot(self, path: str | os.PathLike | None = None) -> np.ndarray:
        """Render and return the image (H, W, 3) uint8 RGB; also save it to ``path``.

        The PNG is written atomically.
        """
        from vidcap.fileio import atomic_path

        img = self.plotter.screenshot(None, return_img=True)
        if path is not None:
            with atomic_path(path, suffix=".png") as tmp:
                _save_png(img, tmp)
        return img

    def add_player(self) -> None:
        """Add a frame slider and a play/pause key (space) for interactive windows."""
        self.playing = False
        self._slider = None
        n = self.data.n_frames
        if n <= 1:
            return

        def on_slider(value):
            self.set_frame(int(round(value)))

        self._slider = self.plotter.add_slider_widget(
            on_slider, [0, n - 1], value=self.frame, title="frame", fmt="%.0f",
            pointa=(0.1, 0.08), pointb=(0.9, 0.08), style="modern")
        self.plotter.add_key_event("space", self.toggle_play)
        self.plotter.add_text("space: play/pause", position="upper_left", font_size=9,
                              color="black")

    def toggle_play(self) -> None:
        """Start or stop playing (in real time, from the current frame)."""
        import time

        self.playing = not getattr(self, "playing", False)
        self._play_t0 = time.monotonic() - self.frame / self.data.fps

    def tick(self, now: float | None = None) -> None:
        """While playing, show the frame due at time ``now`` (``time.monotonic()``)."""
        import time

        if not getattr(self, "playing", False):
            return
        now = time.monotonic() if now is None else now
        nxt = int((now - self._play_t0) * self.data.fps) % self.data.n_frames
        if nxt != self.frame:
            if self._slider is not None:
                self._slider.GetRepresentation().SetValue(nxt)
            self.set_frame(nxt)

    def show(self) -> None:
        """Open the interactive window (blocks until closed)."""
        import time

        if getattr(self, "_slider", None) is None:
            self.plotter.show()
            return
        self.plotter.show(interactive_update=True, auto_close=False)
        try:
            while not getattr(self.plotter, "_closed", False) and self.plotter.ren_win:
                self.tick()
                self.plotter.update(stime=1)
                time.sleep(1.0 / 60.0)
        finally:
            self.plotter.close()


def _save_png(img: np.ndarray, path) -> None:
    import cv2

    if not cv2.imwrite(str(path), np.ascontiguousarray(img[..., ::-1]),
                       [cv2.IMWRITE_PNG_COMPRESSION, 9]):
        raise InputFileError("cannot write the PNG", path)


def view(path: str | os.PathLike, *, screenshot: str | os.PathLike | None = None,
         frame: int | None = None, centres: str | os.PathLike | None = None,
         window_size=(800, 600)) -> np.ndarray | None:
    """Show a BVH or C3D file; with ``screenshot``, render offscreen to that PNG instead.

    Parameters
    ----------
    path : str or path-like
        A ``.bvh`` (skeleton over a ground grid) or ``.c3d`` file (marker cloud).
    screenshot : str or path-like, optional
        Write a PNG of ``frame`` and return the image instead of opening a window.
    frame : int, optional
        Frame to show (0-based; default 0, negative counts from the end).
    centres : str or path-like, optional
        Joint-centre CSV (``frame,time_s,joint,x_m,y_m,z_m``) drawn over a C3D's markers.
    window_size : tuple of int
        Width and height in pixels.

    Returns
    -------
    numpy.ndarray or None
        The screenshot (H, W, 3) uint8 RGB, or None after an interactive window closes.
    """
    data = load_points(path)
    overlay = None
    if centres is not None:
        if Path(path).suffix.lower() != ".c3d":
            raise UsageError("--centres goes with a C3D file", centres)
        overlay = read_centres_csv(centres)
        overlay = Points3D(overlay.names, overlay.positions, overlay.bones, overlay.fps, data.up)
    f = 0 if frame is None else int(frame)
    if f < 0:
        f += data.n_frames
    if not 0 <= f < data.n_frames:
        raise UsageError(f"frame {frame} is outside the file's 0..{data.n_frames - 1}", path)
    scene = Scene(data, overlay=overlay, window_size=window_size,
                  off_screen=True if screenshot is not None else None,
                  follow=screenshot is not None)
    scene.set_frame(f)
    if screenshot is not None:
        try:
            return scene.screenshot(screenshot)
        finally:
            scene.plotter.close()
    scene.add_player()
    scene.show()
    return None
