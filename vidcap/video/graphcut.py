"""The silhouette's uncertain band decided by a graph cut over space and time (issue 26,
Build 2).

The thresholded difference from the plate decides most pixels of a frame well; it
is unsure along the person's outline (mixed pixels, a limb the colour of the wall)
and wherever the plate itself is a guess (the never-seen area, inpainted). There
each pixel is re-decided by a minimum cut (Boykov and Jolly 2001; Rother et al.
2004) of an energy that sums, per pixel, evidence for "person":

* the **plate difference** ``log2(l1 / threshold)``, clipped to +-2 (weighted down
  where the plate was never seen: it is a guess there);
* **colour**: the person's colour model learned over the clip (:func:`clip_colours`,
  from the plate stage's samples) against the scene's, taken from the frame itself
  round the person (the crop outside the band; :data:`LOCAL_SCENE`): the
  log-likelihood ratio, clipped (the clip-wide scene model instead: jacks side
  0.884, the frame's own 0.923 median IoU);
* **time** (off by default, :data:`TIME_WEIGHT`): the previous frame's label;

and, between 4-neighbours, a contrast-sensitive cost for cutting them apart
(``exp(-beta * |I_p - I_q|^2)``): the outline follows the image's edges. Pixels
outside the band keep the threshold's decision; their links are folded into the
band pixels' terminal links, so the graph is the band (the outline and the
never-seen parts the person's crop touches), not the frame.

A frame is cut only when the colour models tell its scene from the person
(:data:`SCENE_KEPT_MIN`: on real footage the scene round the person often holds the
person's colours, and the cut then fills the never-seen area or the outline with
scene); else, and when the cut breaks the person up (:data:`LOST_MAX`), the frame
keeps the plain threshold's foreground. The cut trims the outline, and where a part of
the person hangs on the body by a thin or low-contrast strip it may split that part off
(a head whose inside the plate absorbed, held by its rim) or widen the gap between two
blobs the silhouette stage joins (a runner's torso and legs): the plain person's pieces
are reattached (:func:`keep_pieces`) and its joined blobs kept
(:func:`vidcap.video.silhouette._person_parts`). With them the 2D fit and the solve on
the cut's silhouettes are level with the plain threshold's (``benchmarks/cut_fit.py``:
the mean over perturbed runs; a single run's figures swing with a dozen pixels a frame).
On by default in ``vidcap convert`` and ``vidcap silhouettes`` (``--no-graph-cut``;
``extract_silhouettes(..., graph_cut=True)`` on a plate from
``estimate_background(colour_models=True)``; :data:`vidcap.video.pipeline.DEFAULT_GRAPH_CUT`).
Tuning clips, median IoU without ->
with (main f5880ab's silhouettes): jacks side 0.884 -> 0.917, jacks 3/4 0.902 ->
0.915, arms 3/4 0.890 -> 0.902, arms side 0.980 -> 0.987, arms front 0.920 -> 0.920,
ido_walk 0.921 -> 0.922, sports2d_walk_turn 0.846 -> 0.849 (vs MediaPipe), but
pose2sim cam1 (vs MediaPipe's masks) 0.347 -> 0.317: its never-seen area holds a
wall the colour of the subject's skin, which the colour term fills in.

Speed: the band, its data terms, the scene's histogram and the links are one compiled
pass over the crop each (:mod:`vidcap.video._graphcut_kernels`); as whole-array numpy
calls (some sixty a frame on crops of a few thousand pixels) the call overhead, not
the flow, was the cost: 3.4 -> 0.9 ms of CPU a frame on benchmarks/silhouette_speed.py's
walker at 640x480 (work 320x240), the same masks bit for bit. The links are made from
the band's pixels only (not every pair of the crop), the plate term read from a table,
the histogram's first two smoothing axes compiled: the cut adds ~1.0 ms a frame to the
silhouettes (1.4 before), of which the max-flow library's graph and flow are ~0.25 ms.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

__all__ = ["CutParams", "clip_colours", "cut_frame", "keep_pieces"]

#: Half-width of the band re-decided around the thresholded outline, work pixels.
BAND = 3
#: Weight of the plate difference term where the plate was never seen (a guess).
NEVER_WEIGHT = 0.25
#: Weight of the colour term where the plate is uncertain, and where it was seen;
#: the log-ratio is clipped to +- COLOUR_CLIP.
COLOUR_WEIGHT, SEEN_COLOUR, COLOUR_CLIP = 1.0, 0.3, 3.0
#: Pull towards the previous frame's label. Off: causal, it carries a part lost in
#: one frame into the next ones (arms front 0.937 without, 0.919 at 0.3; jacks 3/4
#: 0.916 / 0.914, ido_walk 0.931 / 0.927). (A cut over the plate stage's
#: samples, both neighbours, measured mixed and was not kept.)
TIME_WEIGHT = 0.0
#: The never-seen parts the person's crop touches are re-decided too (not only the
#: outline band).
WITH_NEVER = True
#: Share of the scene's colour model taken from the frame itself, round the person
#: (the crop outside the band), per frame; 0 = the clip's model only.
LOCAL_SCENE = 1.0
#: Share of the frame's scene model spread over every colour, as the person's model
#: has (:data:`vidcap.video.appearance.PRIOR_UNSEEN`). Without it a colour neither
#: model has seen (the scene inside the never-seen area, which the frame's scene model
#: leaves out) scores as the person's at the clip's limit. Chosen on the tuning rows, on
#: main 7ebb303's plates (the appearance pass's scene-beside gate): 0 / 0.3 / 0.5 /
#: 0.7, jacks side 0.872 / 0.905 / 0.923 / 0.930 (plain 0.918), 131_01 side 0.971 at
#: 0.3, 0.968 at 0.5, 0.964 at 0.7, 14_19 3/4 0.956 / 0.954 / 0.945; on the plates
#: before that gate office_stand's p10 0.002 at 0, 0.213 from 0.1 on.
SCENE_UNIFORM = 0.5
#: Weight of the pairwise (smoothness) term.
SMOOTH = 1.0
#: A frame whose cut leaves out more than this share of the plain foreground's largest
#: blob (where the plate was seen) keeps the plain foreground: the cut has broken the
#: person up (a dark waist taken for the hedge behind it, sports2d_run, which cut the
#: runner in two; then a false blob was followed, pose2sim cam4). Chosen on the tuning
#: rows (median IoU flat for 0.40-0.50 on all of them; the in-place renders' cut
#: legitimately drops up to 0.33 of it, 90th percentile, jacks side).
LOST_MAX = 0.45
#: A frame is cut only when the colour models tell its scene from the person: at
#: least this share of the sure scene round the person (the crop outside the dilated
#: foreground, seen) has a colour the models call scene. On real footage the scene
#: often holds the person's colours (a wall the colour of skin, a desk the colour of
#: trousers, pose2sim cam1 0.81, CDnet office 0.93, cam4 0.92 in the median frame), and
#: the cut then fills the never-seen area or the outline with scene; renders, where
#: the cut helps, keep 0.97-1.00. Chosen on the tuning rows (median IoU flat from 0.94
#: to 0.96; 0.97 costs the renders, under 0.94 office_enter loses more than 0.01).
SCENE_KEPT_MIN = 0.95
#: Pieces the cut splits off the plain person's blob are reattached
#: (:func:`keep_pieces`) when at least PIECE_MIN of the blob's area and the plain
#: foreground joins them to the body within PIECE_REACH band half-widths.
KEEP_PIECES, PIECE_MIN, PIECE_REACH = True, 0.005, 8
#: When a list, :func:`cut_frame` appends per frame cut (sure person kept as person,
#: sure scene kept as scene, their pixel counts, never-seen band pixels, band pixels):
#: a diagnostic, None otherwise.
TRACE = None



def clip_colours(model, frames: np.ndarray, gains: np.ndarray,
                 small: np.ndarray | None = None) -> np.ndarray | None:
    """The colour models of the person and of the scene over the clip.

    Parameters
    ----------
    model : vidcap.video.background.BackgroundModel
        The plate (final).
    frames : numpy.ndarray, shape (K, H, W, 3), uint8
        The samples it was estimated from.
    gains : numpy.ndarray, shape (K, 3)
        Their per-channel gains relative to the plate.
    small : numpy.ndarray, shape (K, h, w, 3), optional
        :func:`vidcap.video.appearance.small_samples` of ``frames``.

    Returns
    -------
    numpy.ndarray, shape (2, BINS**3), float32, or None
        log P(colour | person) and log P(colour | scene) per quantised colour
        (:func:`vidcap.video.appearance.colour_model`), colours divided by the
        frame's gain; None when the samples show too little of the person.
    """
    from vidcap.video.appearance import person_scene_models

    got = person_scene_models(model, frames, gains, small=small)
    return None if got is None else np.stack(got).astype(np.float32)


@dataclass
class CutParams:
    """What :func:`cut_frame` needs, at the silhouette stage's working resolution.

    Attributes
    ----------
    table : numpy.ndarray, shape (BINS**3,), float32
        Colour evidence per quantised colour with the clip's scene model (clipped
        log-ratio; used when :data:`LOCAL_SCENE` is 0).
    never : numpy.ndarray, shape (h, w), bool
        Never-seen pixels of the plate.
    band, never_weight, time_weight, smooth, colour_weight, seen_colour : float
        See the module's constants.
    prev : numpy.ndarray or None
        The previous frame's result (h, w) uint8, updated by :func:`cut_frame`.
    """

    table: np.ndarray
    never: np.ndarray
    band: int = BAND
    never_weight: float = NEVER_WEIGHT
    time_weight: float = TIME_WEIGHT
    smooth: float = SMOOTH
    colour_weight: float = COLOUR_WEIGHT
    seen_colour: float = SEEN_COLOUR
    prev: np.ndarray | None = field(default=None, repr=False)
    #: The clip's models, (2, BINS**3) log-probabilities (for :data:`LOCAL_SCENE`).
    colours: np.ndarray | None = field(default=None, repr=False)
    #: The never-seen area's 8-connected parts: labels (h, w) and boxes (n, 4)
    #: ``x0, y0, x1, y1`` (label 0, the rest, has an empty box).
    parts: tuple | None = field(default=None, repr=False)

    def __post_init__(self):
        n, lab, st, _ = cv2.connectedComponentsWithStats(self.never.view(np.uint8),
                                                         connectivity=8)
        boxes = np.column_stack([st[:, 0], st[:, 1], st[:, 0] + st[:, 2],
                                 st[:, 1] + st[:, 3]])
        boxes[0] = (1 << 30, 1 << 30, -1, -1)
        self.parts = (lab, boxes)

    @classmethod
    def make(cls, colours: np.ndarray, never: np.ndarray, **kw) -> CutParams:
        """From :func:`clip_colours`' models and the never-seen map (work size).
        (Plate pixels whose own colour is the person's were tried as uncertain
        too: pose2sim cam1 0.338 -> 0.275, the renders within 0.003.)"""
        llr = np.clip(colours[0] - colours[1], -COLOUR_CLIP, COLOUR_CLIP)
        never = np.asarray(never, bool)
        kw = {"band": BAND, "never_weight": NEVER_WEIGHT, "time_weight": TIME_WEIGHT,
              "smooth": SMOOTH, "colour_weight": COLOUR_WEIGHT,
              "seen_colour": SEEN_COLOUR, **kw}
        return cls(table=llr.astype(np.float32), never=never,
                   colours=np.asarray(colours, np.float32), **kw)


def cut_frame(frame: np.ndarray, l1: np.ndarray, tmap: np.ndarray, fg: np.ndarray,
              gain: np.ndarray, cp: CutParams) -> np.ndarray:
    """Re-decide one frame's uncertain band by a minimum cut.

    Parameters
    ----------
    frame : numpy.ndarray, shape (h, w, 3), uint8
        The frame at the working resolution, BGR.
    l1 : numpy.ndarray, shape (h, w), uint8
        Its L1 difference from the (gain-scaled) plate.
    tmap : numpy.ndarray, shape (h, w), uint8
        The per-pixel threshold.
    fg : numpy.ndarray, shape (h, w), uint8
        The thresholded, cleaned foreground (0 / 255).
    gain : numpy.ndarray, shape (3,)
        The frame's per-channel gain (the colour models are of gain-divided colours).
    cp : CutParams

    Returns
    -------
    numpy.ndarray, shape (h, w), uint8
        The foreground (0 / 255) with the band round its largest blob re-decided
        (``fg`` itself when it is empty, when the colours do not tell the sure scene
        from the person, :data:`SCENE_KEPT_MIN`, or when the cut breaks the person up,
        :data:`LOST_MAX`).
    """
    contours, _ = cv2.findContours(fg, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        cp.prev = None
        return fg
    biggest = max(contours, key=cv2.contourArea)
    x, y, w, h = cv2.boundingRect(biggest)
    H, W = fg.shape
    r = cp.band
    m = 2 * r + max(2, int(0.1 * max(w, h)))
    x0, y0, x1, y1 = max(0, x - m), max(0, y - m), min(W, x + w + m), min(H, y + h + m)
    # The crop takes in the whole of each never-seen part it touches (a static torso
    # beside the moving arm that is the largest blob).
    lab, boxes = cp.parts
    # (only parts whose box meets the crop can be in it; most frames meet none)
    meets = ((boxes[:, 0] < x1) & (boxes[:, 2] > x0) & (boxes[:, 1] < y1)
             & (boxes[:, 3] > y0))
    touched = np.flatnonzero(meets)
    if len(touched):
        touched = touched[_compiled(_kernels().labels_present, lab[y0:y1, x0:x1],
                                     len(boxes))[touched]]
    if len(touched):
        b = boxes[touched]
        x0, y0 = min(x0, int(b[:, 0].min())), min(y0, int(b[:, 1].min()))
        x1, y1 = max(x1, int(b[:, 2].max())), max(y1, int(b[:, 3].max()))
    f = fg[y0:y1, x0:x1]
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    inner = cv2.erode(f, disk)
    near = cv2.dilate(f, disk)
    never = cp.never[y0:y1, x0:x1]
    img = frame[y0:y1, x0:x1]
    band, qb, e, nv, hist, n_scene, hist_in, n_in = _compiled(
        _kernels().crop_terms, f, inner, near, never, img, np.asarray(gain, np.float32),
        _bins(), _plate_table(), l1[y0:y1, x0:x1], tmap[y0:y1, x0:x1], WITH_NEVER)
    if not len(qb):
        return fg
    # Evidence for the person (positive), per band pixel (row order).
    if LOCAL_SCENE > 0 and cp.colours is not None:
        table = _local_llr(hist, n_scene, cp.colours)
    else:
        table = cp.table
    scene_kept = float(hist @ (table <= 0)) / max(n_scene, 1)
    if TRACE is not None:
        TRACE.append((float(hist_in @ (table > 0)) / max(n_in, 1), scene_kept, n_in,
                      n_scene, int(nv.sum()), len(qb)))
    if scene_kept < SCENE_KEPT_MIN:
        cp.prev = fg  # colour does not tell this frame's person from its scene
        return fg
    col = table[qb]
    e = np.where(nv, cp.never_weight * e + cp.colour_weight * col, e + cp.seen_colour * col)
    if cp.prev is not None and cp.time_weight:
        e += np.where(cp.prev[y0:y1, x0:x1][band] > 0, cp.time_weight, -cp.time_weight)
    person = _band_cut(band, f, e, img, cp.smooth)
    out = fg.copy()
    _kernels().paint_band(out[y0:y1, x0:x1], band, person)
    blob = biggest - np.array([x0, y0], np.int32)
    # The plain person's blob, filled (keep_pieces and _lost_share both need it).
    inside = np.zeros(f.shape, np.uint8)
    cv2.drawContours(inside, [blob], 0, 255, cv2.FILLED)
    if KEEP_PIECES:
        keep_pieces(out[y0:y1, x0:x1], f, blob, r, inside)
    if _lost_share(biggest, out[y0:y1, x0:x1], never, (x0, y0), inside) > LOST_MAX:
        out = fg  # the cut broke the person up: the plain threshold's frame
    cp.prev = out
    return out


def keep_pieces(cut: np.ndarray, plain: np.ndarray, blob: np.ndarray, r: int,
                inside: np.ndarray | None = None) -> np.ndarray:
    """Reattach, in place, the pieces the cut splits off the plain foreground's person.

    The band is the outline's few pixels either side; where a part of the person
    joins the body only by a narrow or low-contrast strip (a head whose inside the
    plate absorbed, held by its rim; a hand at a thin wrist), the cut may drop that
    strip and leave the part a blob of its own, which the silhouette stage then leaves
    out (it keeps the largest blob and those of at least
    :data:`vidcap.video.silhouette.JOIN_SHARE` of it): on the arms sample the head went
    so in 21 of 75 frames. Every blob of the cut's result inside the plain person's
    outline ``blob``, other than the largest there and of at least :data:`PIECE_MIN` of
    the plain blob's area, is grown through the plain foreground,
    a pixel a step, until it touches the largest (at most :data:`PIECE_REACH` times
    ``r`` steps); what it grew through is given back: the strip the cut dropped, and
    the plain foreground as far from the piece as the strip is long.

    Parameters
    ----------
    cut : numpy.ndarray, shape (h, w), uint8
        The cut's foreground (0 / 255), changed in place.
    plain : numpy.ndarray, shape (h, w), uint8
        The plain threshold's (0 / 255), same crop.
    blob : numpy.ndarray
        The plain foreground's person blob: its outer contour (OpenCV points, crop
        coordinates).
    r : int
        The band's half-width, pixels (the steps' scale).
    inside : numpy.ndarray, shape (h, w), uint8, optional
        ``blob`` filled (255), when the caller has it.

    Returns
    -------
    numpy.ndarray
        ``cut``.
    """
    if inside is None:
        inside = np.zeros(cut.shape, np.uint8)
        cv2.drawContours(inside, [blob], 0, 255, cv2.FILLED)
    held = cv2.bitwise_and(cut, inside)
    least = PIECE_MIN * cv2.countNonZero(inside)
    # Most frames hold one blob (and specks): told by the outer contours (those inside
    # another blob's hole too; a blob's pixels are about its contour's area plus half its
    # perimeter), ~20 times as fast as labelling the pixels.
    contours, tree = cv2.findContours(held, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_SIMPLE)
    outer = [] if tree is None else [c for c, t in zip(contours, tree[0], strict=True)
                                     if t[3] < 0]
    if sum(cv2.contourArea(c) + 0.5 * cv2.arcLength(c, True) + 1 >= 0.5 * least
           for c in outer) < 2:
        return cut
    n, lab, st, _ = cv2.connectedComponentsWithStats(held, connectivity=8)
    area = st[1:, cv2.CC_STAT_AREA]
    main = int(np.argmax(area)) + 1
    pieces = np.flatnonzero(area >= least) + 1
    pieces = pieces[pieces != main]
    if not len(pieces):
        return cut
    target = cv2.dilate((lab == main).view(np.uint8), np.ones((3, 3), np.uint8))
    k3 = np.ones((3, 3), np.uint8)
    within = (plain > 0).view(np.uint8)
    for i in pieces:
        grown = (lab == i).view(np.uint8)
        for _ in range(PIECE_REACH * max(1, r)):
            if (grown & target).any():
                cut[grown > 0] = 255  # (plain pixels only: grown within ``plain``)
                break
            nxt = cv2.dilate(grown, k3) & within
            if np.array_equal(nxt, grown):
                break  # no plain path to the body
            grown = nxt
    return cut


def _lost_share(plain, cut, never, origin, inside=None) -> float:
    """Share of the plain foreground's largest blob (contour ``plain``, frame pixels),
    where the plate was seen, that the cut's largest blob in the crop (``cut``, 0 /
    255, at ``origin`` ``(x0, y0)``) leaves out; 0 when nothing of it was seen.
    ``inside``: ``plain`` filled in the crop (non-zero), when the caller has it."""
    h, w = cut.shape
    if inside is None:
        inside = np.zeros((h, w), np.uint8)
        cv2.drawContours(inside, [plain], 0, 1, cv2.FILLED,
                         offset=(-origin[0], -origin[1]))
    before = np.where(never, np.uint8(0), inside)
    n = cv2.countNonZero(before)
    if not n:
        return 0.0
    contours, _ = cv2.findContours(cut, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if contours:
        cv2.drawContours(before, [max(contours, key=cv2.contourArea)], 0, 0, cv2.FILLED)
    return cv2.countNonZero(before) / n


def _kernels():
    from vidcap.video import _graphcut_kernels

    return _graphcut_kernels


def _compiled(kernel, *args):
    """``kernel(*args)``, with a Ctrl-C or SIGTERM that lands while the compiled code
    runs raised as the ``KeyboardInterrupt`` it is: Python runs the signal handler as
    numba boxes the results, and reports it as a ``SystemError`` "returned a result with
    an exception set" caused by it (:mod:`vidcap.interrupt` expects the interrupt)."""
    try:
        return kernel(*args)
    except SystemError as exc:
        cause = exc.__cause__ or exc.__context__
        if isinstance(cause, BaseException) and not isinstance(cause, Exception):
            raise cause from None
        raise


def _bins() -> int:
    from vidcap.video.appearance import BINS

    return BINS


_PLATE_TABLE: list = []


def _plate_table() -> np.ndarray:
    """:func:`vidcap.video._graphcut_kernels.plate_table`, made once per process."""
    if not _PLATE_TABLE:
        _PLATE_TABLE.append(_compiled(_kernels().plate_table))
    return _PLATE_TABLE[0]


def _smoothing(bins: int, sigma: float = 1.0) -> np.ndarray:
    """(bins, bins) matrix of :func:`scipy.ndimage.gaussian_filter`'s 1-D kernel
    (truncate 4, ``mode='constant'``): the histogram smoothed axis by axis by three
    small products instead of a filter call."""
    r = int(4.0 * sigma + 0.5)
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    off = np.arange(bins)[:, None] - np.arange(bins)[None, :]
    return np.where(np.abs(off) <= r, k[np.clip(off + r, 0, 2 * r)], 0.0).astype(np.float32)


_SMOOTH_MATRIX: dict = {}


def _local_llr(hist: np.ndarray, n_scene: int, colours: np.ndarray) -> np.ndarray:
    """The colour log-ratio with the scene's model mixed with this frame's scene round
    the person (``hist``: the histogram of the quantised colours of the crop outside
    the band, ``n_scene`` pixels): :data:`LOCAL_SCENE` of it. The scene's model is
    :func:`vidcap.video.appearance.colour_model` of those pixels (smooth 1 bin)."""
    from vidcap.video.appearance import BINS

    if n_scene < 50:
        return np.clip(colours[0] - colours[1], -COLOUR_CLIP, COLOUR_CLIP)
    g = _SMOOTH_MATRIX.get(BINS)
    if g is None:
        g = _SMOOTH_MATRIX[BINS] = _smoothing(BINS)
    # The first two axes compiled (einsum's sums term by term); the last, along
    # memory, stays einsum's (its sums run in vector lanes).
    hist = _compiled(_kernels().smooth_first_two, g, hist.reshape((BINS,) * 3))
    hist = np.einsum("ck,abk->abc", g, hist).ravel()
    scene = np.log((1 - SCENE_UNIFORM) * hist / max(float(hist.sum()), 1.0)
                   + SCENE_UNIFORM / hist.size + 1e-7).astype(np.float32)
    if LOCAL_SCENE < 1:
        scene = np.logaddexp(np.log1p(-LOCAL_SCENE) + colours[1],
                             np.log(LOCAL_SCENE) + scene)
    return np.clip(colours[0] - scene, -COLOUR_CLIP, COLOUR_CLIP)


def _band_cut(band: np.ndarray, fixed: np.ndarray, e: np.ndarray, img: np.ndarray,
              smooth: float) -> np.ndarray:
    """The minimum cut over the band's pixels only.

    ``e``: evidence for the person per band pixel (row order); between
    4-neighbours a contrast-sensitive cost ``smooth * exp(-beta * |I_p - I_q|^2)``
    (``beta`` from the mean over the pairs touching the band, Rother et al. 2004).
    A link to a pixel outside the band (whose label ``fixed``, non-zero: person, is kept) is folded
    into the band pixel's terminal link: the graph is the band, not its bounding
    box, and the cost grows with the outline, not with the person's area. Returns
    (N,) bool, person, for the band's pixels in row order. The links come from one
    compiled pass (:func:`vidcap.video._graphcut_kernels.band_graph`)."""
    import maxflow

    n = len(e)
    ia, ib, wt, src, snk = _compiled(_kernels().band_graph, band, fixed,
                                     np.ascontiguousarray(img), float(smooth),
                                     np.asarray(e, np.float32))
    g = maxflow.Graph[float](n, len(wt))
    nodes = g.add_nodes(n)
    if len(wt):
        g.add_edges(ia, ib, wt, wt)
    g.add_grid_tedges(nodes, src, snk)
    g.maxflow()
    return ~g.get_grid_segments(nodes)  # (True = sink side = scene)
