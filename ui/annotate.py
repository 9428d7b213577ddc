"""The annotate web app (trame + vuetify 3 + pyvista): depth directions, orientation and
occluded joints for one clip, with a live 3D pose, and a Review tab; regions that are not
the person and boxes around the person, with the silhouette over the frame
(:mod:`vidcap.ui.regionedit`).

Start it with ``vidcap annotate VIDEO`` (or :func:`serve`). Everything the page
shows comes from an :class:`vidcap.ui.session.AnnotateSession`; every edit goes through it,
is re-lifted at once and saved atomically.

Keyboard: Left/Right step a frame, Space plays/pauses, N jumps to the next frame
that needs attention.
"""

from __future__ import annotations

import asyncio
import sys

import cv2
import numpy as np
from vidcap.ui import render
from vidcap.ui.session import MAX_DISPLAY_WIDTH, AnnotateSession

from vidcap.body import JOINT_NAMES, ORIENTATIONS, SEGMENT_JOINTS

#: Width in pixels of the frame picture on the page (small clips are scaled up).
DISPLAY_WIDTH = 640
#: Radius in display pixels within which a mouse press picks a joint up.
PICK_RADIUS = 14
#: What dragging the mouse over the frame does (state ``draw_mode``): move a joint,
#: or draw a region (:mod:`vidcap.ui.regionedit`).
DRAW_MODES = (("joints", "move joints"), ("scene_region", "not the person: box"),
              ("scene_area", "not the person: outline"),
              ("person_box", "person is here (this frame)"))

_KEYS_JS = """
if (!window.__vidcapKeys) {
  window.__vidcapKeys = true;
  window.addEventListener('keydown', function (e) {
    var t = e.target;
    if (t && (t.tagName === 'INPUT' || t.tagName === 'TEXTAREA' || t.isContentEditable ||
              (t.getAttribute && t.getAttribute('role') === 'slider'))) { return; }
    var map = {ArrowRight: 'next', ArrowLeft: 'prev', ' ': 'play', n: 'attention',
               N: 'attention'};
    var action = map[e.key];
    if (action && window.trame) { e.preventDefault(); window.trame.trigger('key', [action]); }
  });
}
"""


def _image_xy(axis: str) -> str:
    """JS for the mouse position in the picture's own pixels."""
    if axis == "x":
        return "$event.offsetX * $event.target.naturalWidth / $event.target.clientWidth"
    return "$event.offsetY * $event.target.naturalHeight / $event.target.clientHeight"


class AnnotateApp:
    """The page for one :class:`AnnotateSession`.

    Parameters
    ----------
    session : AnnotateSession
        The clip and its annotations.
    server : trame server, optional
        Default: a new one (``trame.app.get_server`` with a unique name).
    """

    def __init__(self, session: AnnotateSession, *, server=None):
        import pyvista as pv
        from trame.app import get_server
        from vidcap.ui.view import Points3D, Scene

        from vidcap.video.review import quiet_vtk

        self.session = session
        session.defer_refresh = True  # edits answer at once; re-proposals run in a worker
        self.server = server or get_server(f"vidcap-annotate-{id(self)}", client_type="vue3")
        self.state, self.ctrl = self.server.state, self.server.controller
        w, h = session.clip.size
        self.display_scale = (DISPLAY_WIDTH / w if w < DISPLAY_WIDTH
                              else min(1.0, MAX_DISPLAY_WIDTH / w))
        self._drag: str | None = None
        self._rect_start: tuple[float, float] | None = None  # a region being drawn
        self._reseg_task = None
        self._reseg_progress = ("", 0, 0)
        self._play_task = None

        # live 3D pose: the whole clip frames the camera and the floor
        j3 = self._floor(session.joints3d)
        self._points3d = Points3D(JOINT_NAMES, j3, np.asarray(SEGMENT_JOINTS), session.clip.fps, 1)
        quiet_vtk()
        self.plotter = pv.Plotter(off_screen=True, window_size=[420, 320])
        self.scene = Scene(self._points3d, plotter=self.plotter, view_direction=(0.6, 0.3, 1.0),
                           follow=True)
        self.scene.bone_rgb = self._bone_rgb()

        self._init_state()
        self._build_ui()
        self.state.change("frame")(self._on_frame)
        self.state.change("show_sil")(self._on_frame)
        self._register_triggers()
        self._update_frame()

    # ------------------------------------------------------------------ state
    @staticmethod
    def _floor(joints3d: np.ndarray) -> np.ndarray:
        j = np.array(joints3d, dtype=float)
        j[..., 1] -= np.nanmin(j[..., 1])
        return j

    def _bone_rgb(self) -> np.ndarray:
        """Bone colours (F, 10, 3) RGB by depth sign, as in the 2D picture."""
        toward = np.array(render.TOWARD_BGR[::-1], np.uint8)
        away = np.array(render.AWAY_BGR[::-1], np.uint8)
        return np.where(self.session.signs[..., None] >= 0, toward, away)

    def _init_state(self) -> None:
        s, st = self.session, self.state
        st.frame = 0
        st.n_frames = s.n_frames
        st.tab = "annotate"
        st.playing = False
        st.orientations = list(ORIENTATIONS)
        st.orientation = ""
        st.sides_swapped = []
        st.segments = []
        st.n_inputs = s.n_user_inputs
        st.load_error = s.load_error or ""
        st.backup = str(s.backup) if s.backup else ""
        st.save_status = "no edits yet" if not s.load_error else "not saved: fix or edit"
        st.edit_ms = 0.0
        st.refreshing = False
        st.flagged = []
        st.message = ""
        st.drag_joint = ""
        st.drag_pos = [0, 0]
        st.frame_src = st.sil_src = st.review_frame_src = st.review_sil_src = ""
        st.review_side_src = ""
        st.fit_score = 0.0
        st.filled = False
        st.video_name = s.clip.video.name
        st.joint_names = list(JOINT_NAMES)
        st.joints_display = []
        st.annotations_path = str(s.path)
        # regions (issue 26): what the mouse draws, the silhouette over the frame
        st.draw_mode = "joints"
        st.show_sil = True
        st.band = []
        st.regions = s.region_items()
        st.resegmenting = False
        st.reseg_status = ""
        st.sil_area = 0
        st.can_resegment = s.clip.resegment is not None

    def _update_flagged(self) -> None:
        items = self.session.flagged()
        self.state.flagged = [{"frame": it["frame"], "reason": it["reason"],
                               "key": f"{it['frame']}-{it['segment']}"} for it in items[:60]]

    def _update_frame(self) -> None:
        """Recompute every picture and control of the current frame."""
        s, st = self.session, self.state
        f = int(np.clip(int(st.frame), 0, s.n_frames - 1))
        info = s.frame_info(f)
        signs = s.signs[f]
        low = s.low_confidence(f)
        user_signs = s.user_signs[f] != 0
        user_joints = np.isfinite(s.user_joints[f]).all(-1)
        frame = s.clip.read_frame(f)
        scale = self.display_scale
        big = render.fit_width(frame, round(s.clip.size[0] * scale))  # frames may come shrunk
        j2 = s.joints2d[f] * scale
        mask = None if s.clip.masks is None else s.clip.masks[f]
        shown = render.draw_regions(
            render.overlay_silhouette(big, mask) if st.show_sil else big,
            s.regions_at(f), scale)
        overlay = render.draw_model(shown, j2, signs, low_confidence=low, user_signs=user_signs,
                                    user_joints=user_joints)
        sil = render.silhouette_image(mask, frame.shape[:2])
        sil_big = render.fit_width(sil, big.shape[1])
        sil_model = render.draw_model(sil_big, j2, signs, low_confidence=low,
                                      user_signs=user_signs, user_joints=user_joints)
        side = render.side_view(self._points3d_frame(f), signs, size=(240, big.shape[0]))
        with st:
            st.frame_src = render.data_url(overlay)
            st.sil_src = render.data_url(render.fit_width(sil_model, 320))
            st.review_frame_src = render.data_url(render.fit_width(big, 320))
            st.review_sil_src = st.sil_src
            st.review_side_src = render.data_url(render.fit_width(side, 160))
            st.segments = info["segments"]
            st.orientation = info["orientation"]
            st.orientation_user = info["orientation_user"]
            st.sides_swapped = info["sides_swapped"]
            st.fit_score = info["fit_score"]
            st.filled = info["filled"]
            st.user_joints = info["user_joints"]
            st.joints_display = np.round(j2, 1).tolist()  # page pixels, for tests and tools
            st.n_inputs = s.n_user_inputs
            st.sil_area = 0 if mask is None else int(np.count_nonzero(mask))
        self.scene.set_frame(f)
        self._update_3d_view()

    def _points3d_frame(self, f: int) -> np.ndarray:
        return self._points3d.positions[f]

    def _update_3d_view(self) -> None:
        view = getattr(self, "view3d", None)
        if view is not None:
            view.update()

    def _after_edit(self, ms: float) -> None:
        s, st = self.session, self.state
        from vidcap.ui.view import Points3D

        st.regions = s.region_items()
        self._points3d = Points3D(JOINT_NAMES, self._floor(s.joints3d), self._points3d.bones,
                                  s.clip.fps, 1)
        self.scene.data = self._points3d
        self.scene.bone_rgb = self._bone_rgb()
        with st:
            st.edit_ms = round(ms, 1)
            st.save_status = f"saved {s.path.name}" if s.saved else "not saved"
            st.message = ""
        self._update_flagged()
        self._update_frame()

    def _on_frame(self, frame=None, **_):
        self._update_frame()

    # ------------------------------------------------------------------ triggers
    def _register_triggers(self) -> None:
        server = self.server

        @server.trigger("set_depth")
        def set_depth(segment, sign):
            self._edit(self.session.set_depth, int(self.state.frame), segment, int(sign))

        @server.trigger("flip_depth")
        def flip_depth(segment):
            self._edit(self.session.flip_depth, int(self.state.frame), segment)

        @server.trigger("set_orientation")
        def set_orientation(label):
            # choosing the proposed label also counts: it confirms it from this frame on
            if label and (label != self.state.orientation or not self.state.orientation_user):
                self._edit(self.session.set_orientation, int(self.state.frame), label)

        @server.trigger("flip_sides")
        def flip_sides(pair):
            self._edit(self.session.flip_sides, int(self.state.frame), pair)

        @server.trigger("drag_start")
        def drag_start(x, y):
            if self.state.draw_mode != "joints":  # a region: its first corner
                self._rect_start = (x / self.display_scale, y / self.display_scale)
                return
            f = int(self.state.frame)
            u, v = x / self.display_scale, y / self.display_scale
            self._drag = self.session.nearest_joint(f, u, v,
                                                    radius=PICK_RADIUS / self.display_scale)
            self.state.drag_joint = self._drag or ""

        @server.trigger("drag_end")
        def drag_end(x, y):
            mode, start, self._rect_start = self.state.draw_mode, self._rect_start, None
            if mode in ("scene_region", "person_box") and start is not None:
                box = (*start, x / self.display_scale, y / self.display_scale)
                f = int(self.state.frame)
                if mode == "scene_region":
                    self._region_edit(lambda: self.session.add_scene_region(f, box=box))
                else:
                    self._region_edit(lambda: self.session.add_person_box(f, box))
                return
            joint, self._drag = self._drag, None
            self.state.drag_joint = ""
            if joint is None:
                return
            f = int(self.state.frame)
            u, v = x / self.display_scale, y / self.display_scale
            old = self.session.joints2d[f, JOINT_NAMES.index(joint)]
            if np.hypot(u - old[0], v - old[1]) * self.display_scale < 2:  # a click, not a drag
                return
            self._edit(self.session.set_joint, f, joint, u, v)

        @server.trigger("lasso_end")
        def lasso_end(points):
            self._rect_start = None
            if self.state.draw_mode != "scene_area" or not points:
                return
            pts = np.asarray(points, np.float32).reshape(-1, 1, 2) / self.display_scale
            if len(pts) > 3:  # the mouse's path to within a pixel: fewer points to keep
                pts = cv2.approxPolyDP(pts, 1.0, True)
            poly = pts.reshape(-1, 2).tolist()
            f = int(self.state.frame)
            self._region_edit(lambda: self.session.add_scene_region(f, polygon=poly))

        @server.trigger("delete_region")
        def delete_region(ident):
            type_, frame, key = str(ident).split("|", 2)
            self._region_edit(lambda: self.session.remove_region(int(frame), type_, key))

        @server.trigger("clear_joint")
        def clear_joint(joint):
            self._edit(self.session.clear_joint, int(self.state.frame), joint)

        @server.trigger("step")
        def step(delta):
            self._goto(int(self.state.frame) + int(delta))

        @server.trigger("goto")
        def goto(frame):
            self._goto(int(frame))

        @server.trigger("attention")
        def attention():
            item = self.session.next_attention(int(self.state.frame))
            if item is None:
                self.state.message = "nothing flagged"
            else:
                self.state.message = f"frame {item['frame']}: {item['reason']}"
                self._goto(item["frame"])

        @server.trigger("play")
        def play():
            self._toggle_play()

        @server.trigger("key")
        def key(action):
            {"next": lambda: step(1), "prev": lambda: step(-1), "play": self._toggle_play,
             "attention": attention}.get(action, lambda: None)()

    def _edit(self, fn, *args) -> None:
        try:
            ms = fn(*args)
        except (ValueError, OSError) as exc:
            self.state.message = f"edit refused: {exc}"
            print(f"vidcap annotate: edit refused: {exc}", file=sys.stderr, flush=True)
            return
        self._after_edit(ms)
        if self.session.stale:
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError:  # no server loop (used from a script or a test): do it now
                if self.session.refresh():
                    self._after_edit(ms)
            else:
                self.state.refreshing = True
                loop.create_task(self._refresh())

    def _region_edit(self, fn) -> None:
        """A region edit: saved at once, then the silhouettes and fit are redone (in the
        background when the server runs)."""
        try:
            ms = fn()
        except (ValueError, OSError) as exc:
            self.state.message = f"region refused: {exc}"
            return
        self._after_edit(ms)
        if not self.session.regions_stale:
            if self.session.clip.resegment is None:
                self.state.reseg_status = "saved; vidcap convert applies it"
            return
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:  # no server loop (a script or a test): do it now
            self._resegmented(self.session.resegment())
            return
        if self._reseg_task is None or self._reseg_task.done():
            self._reseg_task = loop.create_task(self._resegment_loop())

    def _on_reseg_progress(self, stage: str, done: int, total: int) -> None:
        self._reseg_progress = (stage, done, total)  # (a worker thread: read by the loop)

    async def _resegment_loop(self) -> None:
        """Redo the silhouettes (and refit what changed) in a worker thread while the
        page stays live, showing progress; again if a region was edited meanwhile."""
        loop = asyncio.get_running_loop()
        st = self.state
        while self.session.regions_stale:
            self._reseg_progress = ("silhouettes", 0, self.session.n_frames)
            with st:
                st.resegmenting = True
            job = loop.run_in_executor(None, self.session.resegment, self._on_reseg_progress)
            while not job.done():
                stage, done, total = self._reseg_progress
                with st:
                    st.reseg_status = f"recomputing {stage}: {done}/{total} frames"
                await asyncio.wait({job}, timeout=0.25)
            try:
                result = job.result()
            except Exception as exc:  # noqa: BLE001 - shown, the page stays up
                with st:
                    st.resegmenting = False
                    st.reseg_status = f"recompute failed: {exc}"
                print(f"vidcap annotate: recompute failed: {exc}", file=sys.stderr, flush=True)
                return
            with st:
                self._resegmented(result)

    def _resegmented(self, result) -> None:
        """Show the clip's new silhouettes and pose."""
        st = self.state
        st.resegmenting = False
        if result is None:
            return
        st.reseg_status = (f"silhouettes recomputed: {result['changed']} frame(s) changed"
                           f" ({result['seconds']:.1f} s)")
        self._update_flagged()
        self._after_edit(self.session.last_edit_ms)

    async def _refresh(self) -> None:
        """Re-propose the other depth signs in a worker thread, then redraw."""
        loop = asyncio.get_running_loop()
        kept = await loop.run_in_executor(None, self.session.refresh)
        if kept:
            with self.state:
                self.state.refreshing = False
                self._after_edit(self.session.last_edit_ms)

    def _goto(self, frame: int) -> None:
        self.state.frame = int(np.clip(frame, 0, self.session.n_frames - 1))

    def _toggle_play(self) -> None:
        st = self.state
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:  # playing needs the server's event loop
            return
        st.playing = not st.playing
        if st.playing and (self._play_task is None or self._play_task.done()):
            self._play_task = loop.create_task(self._play_loop())

    async def _play_loop(self) -> None:
        st = self.state
        delay = 1.0 / min(self.session.clip.fps, 12.0)
        while st.playing:
            await asyncio.sleep(delay)
            with st:
                st.frame = (int(st.frame) + 1) % self.session.n_frames

    # ------------------------------------------------------------------ layout
    def _build_ui(self) -> None:
        from trame.ui.vuetify3 import SinglePageLayout
        from trame.widgets import client, html
        from trame.widgets import vuetify3 as v3
        from trame_pyvista.ui import plotter_ui

        with SinglePageLayout(self.server) as layout:
            self.layout = layout
            layout.title.set_text("vidcap annotate: {{ video_name }}")
            with layout.toolbar:
                v3.VSpacer()
                v3.VChip("inputs: {{ n_inputs }}", id="inputs-count", classes="mx-1",
                         color="primary", variant="tonal")
                v3.VChip("re-lift {{ edit_ms }} ms{{ refreshing ? ', re-proposing' : '' }}",
                         classes="mx-1", variant="tonal", id="edit-time")
                v3.VChip("{{ save_status }}", id="save-status", classes="mx-1", variant="tonal")
            with layout.content:
                client.Script(_KEYS_JS)
                with v3.VContainer(fluid=True, classes="pa-2"):
                    v3.VAlert(
                        "{{ load_error }}", v_if="load_error", id="load-error", type="error",
                        title="The annotations file could not be read",
                        text=("'Starting with no annotations. Your file is kept unchanged; a copy"
                              " is in ' + backup + '. It is written only after your first edit.'",),
                        classes="mb-2", density="compact")
                    with v3.VTabs(v_model=("tab",), density="compact"):
                        v3.VTab("Annotate", value="annotate", id="tab-annotate")
                        v3.VTab("Review", value="review", id="tab-review")
                    with v3.VWindow(v_model=("tab",)):
                        with v3.VWindowItem(value="annotate"):
                            self._annotate_tab(v3, html, plotter_ui)
                        with v3.VWindowItem(value="review"):
                            self._review_tab(v3, html)

    def _frame_controls(self, v3, html, prefix: str) -> None:
        with v3.VRow(classes="align-center ma-0", dense=True):
            v3.VBtn(icon="mdi-chevron-left", id=f"{prefix}btn-prev", size="small",
                    click="trigger('step', [-1])", title="previous frame (Left)")
            v3.VBtn(icon=("playing ? 'mdi-pause' : 'mdi-play'",), id=f"{prefix}btn-play",
                    size="small", click="trigger('play')", title="play/pause (Space)")
            v3.VBtn(icon="mdi-chevron-right", id=f"{prefix}btn-next", size="small",
                    click="trigger('step', [1])", title="next frame (Right)")
            v3.VSlider(v_model_number=("frame",), min=0, max=("n_frames - 1",), step=1,
                       hide_details=True, classes="mx-3", id=f"{prefix}frame-slider")
            html.Span("frame {{ frame }} / {{ n_frames - 1 }}", id=f"{prefix}frame-label",
                      classes="text-no-wrap")

    def _annotate_tab(self, v3, html, plotter_ui) -> None:
        drag_x, drag_y = _image_xy("x"), _image_xy("y")
        with v3.VRow(dense=True):
            with v3.VCol(cols=12, md=7):
                with html.Div(style="position: relative; display: inline-block; line-height: 0",
                              id="frame-box"):
                    html.Img(
                        src=("frame_src",), id="frame-img",
                        style=f"max-width: 100%; width: {DISPLAY_WIDTH}px; cursor: crosshair;"
                              " user-select: none",
                        raw_attrs=[
                            'draggable="false"',
                            f'@mousedown.prevent="trigger(\'drag_start\', [{drag_x}, {drag_y}]);'
                            ' drag_pos = [$event.offsetX, $event.offsetY];'
                            " draw_mode != 'joints' && (band = [$event.offsetX, $event.offsetY,"
                            f' $event.offsetX, $event.offsetY], $event.target.__pts = [[{drag_x},'
                            f' {drag_y}]])"',
                            '@mousemove="drag_joint && (drag_pos = [$event.offsetX,'
                            ' $event.offsetY]); band.length && (band = [band[0], band[1],'
                            " $event.offsetX, $event.offsetY]); band.length && draw_mode =="
                            " 'scene_area' && $event.target.__pts &&"
                            f' $event.target.__pts.push([{drag_x}, {drag_y}])"',
                            f'@mouseup="trigger(\'drag_end\', [{drag_x}, {drag_y}]);'
                            " band.length && draw_mode == 'scene_area' &&"
                            " trigger('lasso_end', [$event.target.__pts || []]); band = []\"",
                        ])
                    html.Div(
                        v_if="band.length", id="draw-band",
                        style=("'position: absolute; pointer-events: none; border: 2px dashed '"
                               " + (draw_mode == 'person_box' ? 'rgb(60,220,60)' :"
                               " 'rgb(230,60,60)') + '; left: ' + Math.min(band[0], band[2])"
                               " + 'px; top: ' + Math.min(band[1], band[3]) + 'px; width: '"
                               " + Math.abs(band[2] - band[0]) + 'px; height: '"
                               " + Math.abs(band[3] - band[1]) + 'px'",))
                    v3.VChip(
                        "FILLED: not fitted (no person, or mostly outside the picture); "
                        "pose from the frames around", v_if="filled", id="filled-badge",
                        color="orange", variant="elevated", size="small",
                        style="position: absolute; left: 8px; top: 8px; line-height: normal")
                    html.Div(
                        v_if="drag_joint", id="drag-dot",
                        style=("'position: absolute; pointer-events: none; width: 14px;"
                               " height: 14px; margin: -7px 0 0 -7px; border-radius: 7px;"
                               " background: rgb(60,220,60); left: ' + drag_pos[0] + 'px; top: '"
                               " + drag_pos[1] + 'px'",))
                self._frame_controls(v3, html, "")
                self._region_controls(v3, html)
                with v3.VRow(classes="align-center ma-0", dense=True):
                    v3.VBtn("next needing attention (N)", id="btn-attention", size="small",
                            prepend_icon="mdi-alert-circle-outline", click="trigger('attention')",
                            classes="mr-2")
                    html.Span("{{ message }}", id="message", classes="text-caption")
                with html.Div(classes="text-caption mt-1"):
                    html.Span("toward the camera", style=f"color: {render.TOWARD_CSS};"
                              " font-weight: bold")
                    html.Span(" / ")
                    html.Span("away", style=f"color: {render.AWAY_CSS}; font-weight: bold")
                    html.Span(" (thicker = set by you); ")
                    html.Span("red ring", style=f"color: {render.LOW_CSS}; font-weight: bold")
                    html.Span(" = doubtful; ")
                    html.Span("green joint", style=f"color: {render.USER_CSS}; font-weight: bold")
                    html.Span(" = placed by you. Drag a joint to move it. Fit score"
                              " {{ fit_score }}.")
            with v3.VCol(cols=12, md=5):
                with html.Div(style="height: 300px; position: relative", id="view3d"):
                    self.view3d = plotter_ui(self.plotter, mode="server", add_menu=False,
                                             server=self.server)
                with v3.VRow(dense=True, classes="ma-0 mt-1 align-center"):
                    html.Img(src=("sil_src",), id="sil-img",
                             style="width: 45%; margin-right: 8px")
                    with html.Div(style="width: 50%"):
                        v3.VSelect(
                            label="orientation (from this frame on)", items=("orientations",),
                            model_value=("orientation",), density="compact", hide_details=True,
                            id="orientation-select",
                            update_modelValue="trigger('set_orientation', [$event])")
                        html.Div("{{ orientation_user ? 'set by you' : 'proposed' }}",
                                 classes="text-caption")
                        # in a side view no silhouette tells the near limb from the far
                        # one: which leg (arm) is the left is the 2D stage's guess
                        with html.Div(classes="mt-1 text-no-wrap"):
                            for pair in ("legs", "arms"):
                                v3.VBtn(f"swap {pair}", size="x-small", classes="mr-1",
                                        id=f"swap-{pair}",
                                        variant=(f"sides_swapped.includes('{pair}') ? 'flat'"
                                                 " : 'outlined'",),
                                        title=f"left and right {pair} exchanged from this "
                                              "frame on (click again to undo)",
                                        click=f"trigger('flip_sides', ['{pair}'])")
                with v3.VTable(density="compact", id="segments-table"):
                    with html.Tbody():
                        with html.Tr(v_for="s in segments", key="s.name"):
                            html.Td("{{ s.label }}", classes="text-no-wrap")
                            with html.Td():
                                v3.VIcon("mdi-alert-circle", v_if="s.low", color="error",
                                         size="small",
                                         title=("'doubtful: ' + s.doubt_cm + ' cm if wrong'",))
                            with html.Td(classes="text-no-wrap"):
                                v3.VBtn("toward", size="x-small", classes="mr-1",
                                        id=("'toward-' + s.name",),
                                        variant=("s.sign > 0 ? 'flat' : 'outlined'",),
                                        color=("s.sign > 0 ? 'orange' : 'grey'",),
                                        click="trigger('set_depth', [s.name, 1])")
                                v3.VBtn("away", size="x-small", classes="mr-1",
                                        id=("'away-' + s.name",),
                                        variant=("s.sign < 0 ? 'flat' : 'outlined'",),
                                        color=("s.sign < 0 ? 'blue' : 'grey'",),
                                        click="trigger('set_depth', [s.name, -1])")
                                v3.VBtn("flip", size="x-small", id=("'flip-' + s.name",),
                                        variant="text",
                                        click="trigger('flip_depth', [s.name])")
                            html.Td("{{ s.user ? 'you' : 'auto' }}", classes="text-caption")

    def _region_controls(self, v3, html) -> None:
        """What the mouse draws on the frame, the silhouette over it, the regions drawn."""
        with v3.VRow(classes="align-center ma-0", dense=True):
            html.Span("mouse:", classes="text-caption mr-1")
            with v3.VBtnToggle(v_model=("draw_mode",), mandatory=True, density="compact",
                               divided=True, variant="outlined", id="draw-mode"):
                for value, title in DRAW_MODES:
                    v3.VBtn(title, value=value, size="small", id=f"mode-{value}",
                            classes="text-none")
        with v3.VRow(classes="align-center ma-0", dense=True):
            v3.VSwitch(v_model=("show_sil",), label="silhouette over the frame",
                       density="compact", hide_details=True, color="info", id="show-sil",
                       classes="mr-3", style="flex: 0 0 auto")
            v3.VChip("{{ reseg_status }}", v_if="reseg_status", id="reseg-status", size="small",
                     color=("resegmenting ? 'warning' : 'success'",), variant="tonal",
                     prepend_icon=("resegmenting ? 'mdi-progress-clock' : 'mdi-check'",))
        with html.Div(id="region-list", classes="text-caption"):
            with html.Div(v_for="r in regions", key="r.id", classes="d-flex align-center"):
                v3.VIcon("mdi-square-outline", size="x-small", classes="mr-1",
                         color=(f"r.type == 'scene_region' ? '{render.SCENE_REGION_CSS}'"
                                f" : '{render.PERSON_BOX_CSS}'",))
                html.Span("{{ r.label }}")
                v3.VBtn(icon="mdi-delete", size="x-small", variant="text",
                        id=("'delete-' + r.id",), title="delete this region",
                        click="trigger('delete_region', [r.id])")

    def _review_tab(self, v3, html) -> None:
        with v3.VRow(dense=True):
            for title, src, ident in (("frame", "review_frame_src", "review-frame"),
                                      ("silhouette + model", "review_sil_src", "review-sil"),
                                      ("3D pose (side view)", "review_side_src", "review-side")):
                with v3.VCol(cols="auto"):
                    html.Div(title, classes="text-subtitle-2")
                    html.Img(src=(src,), id=ident, style="height: 260px")
        self._frame_controls(v3, html, "review-")
        html.Div("Flagged frames (click to open):", classes="text-subtitle-2 mt-2")
        with html.Div(id="flagged-list", style="max-height: 200px; overflow-y: auto"):
            v3.VChip("{{ item.frame }}: {{ item.reason }}", v_for="item in flagged",
                     key="item.key", size="small", classes="ma-1",
                     color=("item.frame == frame ? 'primary' : ''",),
                     click="trigger('goto', [item.frame])")

    # ------------------------------------------------------------------ running
    def start(self, *, token: str, port: int = 0, **kwargs):
        """Serve the page on 127.0.0.1 to requests holding ``token`` (blocks until stopped).

        See :mod:`vidcap.ui.access` for what is refused.
        """
        from vidcap.ui import access, closedpages

        self._update_flagged()
        access.protect(self.server, token)
        self.ctrl.on_server_ready.add(lambda **_: closedpages.quiet_closed_pages())
        return self.server.start(host=access.LOOPBACK, port=port, open_browser=False,
                                 timeout=0, show_connection_info=False, **kwargs)


def serve(session: AnnotateSession, *, port: int = 0, open_browser: bool = True) -> None:
    """Build the page for ``session`` and serve it on 127.0.0.1 until interrupted.

    The address printed (and opened) carries a fresh random token; requests without it,
    or from another ``Host`` or ``Origin``, are refused (:mod:`vidcap.ui.access`).

    Parameters
    ----------
    session : AnnotateSession
    port : int
        TCP port (0 = a free one).
    open_browser : bool
        Open the system's browser on the page.
    """
    import webbrowser

    import pyvista as pv
    from vidcap.ui import access

    pv.OFF_SCREEN = True
    app = AnnotateApp(session)
    token = access.new_token()

    @app.ctrl.on_server_ready.add
    def _ready(**_):
        url = access.page_url(app.server.port, token)
        print(f"vidcap annotate: {url}  (annotations: {session.path}; Ctrl+C to stop)",
              flush=True)
        if open_browser:
            webbrowser.open(url)

    if session.load_error:
        print(f"vidcap annotate: error: {session.load_error}; your file is kept, a copy is in"
              f" {session.backup}", file=sys.stderr, flush=True)
    argv, sys.argv = sys.argv, sys.argv[:1]  # trame parses sys.argv too: give it nothing
    try:
        app.start(token=token, port=port)
    finally:
        sys.argv = argv
