"""The colour around the person, kept from the silhouettes' decode for the 3D stage's cues.

The 3D stage's colour cues (the front/back cue, :mod:`vidcap.video.frontback`, and the
limb order, :mod:`vidcap.video.legorder`) read pixels along the fitted limbs, known
only once the 2D fit is done. Decoding the clip again for them cost ~0.25 s of the
~3.5 s ``vidcap convert`` takes on 300 frames at 640x480, on one core while the other
waits. :class:`KeptFrames` instead keeps each frame's person box (with a margin) at
full resolution as the silhouettes are extracted, up to :data:`BUDGET_BYTES`; a longer
clip drops what it kept and the cues decode the video again, as before. So does a clip
where the cues would read a pixel outside a kept box (:meth:`KeptFrames.covers`: a
forearm searched far beyond the silhouette's box), so the cues are always those of
the whole frames, to the bit. On 8 clips (the 640x480 walk, the samples, ido_walk and
four real clips) 5 were covered at the 0.15 margin.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

#: Bytes the kept boxes may take (convert_speed.py's 640x480 walk: 18 KB a frame; a
#: dancer filling a 576x576 frame: 230 KB, so ~1,100 frames).
BUDGET_BYTES = 256 * 2**20
#: Margin kept round the person's box: this fraction of its height, at least
#: :data:`MARGIN_PX` pixels. The cues' search lines reach a limb's radius or two past
#: the fitted limb, and a fitted forearm may stick out of the silhouette a little.
MARGIN = 0.15
MARGIN_PX = 16
#: Frames after which the boxes kept so far project the whole clip's size.
_PROJECT_AFTER = 10


class KeptFrames:
    """Colour frames (F, H, W, 3) BGR uint8, each kept as its person's box.

    Parameters
    ----------
    budget : int
        Bytes the boxes may take; past it everything is dropped (:attr:`dropped`).
    n_frames : int, optional
        Frames the clip is expected to have: when the first boxes, so many times over,
        would pass the budget, nothing is kept from the start (no copies for nothing).
    """

    def __init__(self, budget: int = BUDGET_BYTES, n_frames: int | None = None):
        self.budget = int(budget)
        self.n_frames = n_frames
        self.frame_shape: tuple[int, int] | None = None
        self.boxes: list = []  # (h, w, 3) uint8 or None
        self.origins: list = []  # (y0, x0) of each box
        self.nbytes = 0
        self.dropped = False

    def append(self, frame: np.ndarray, box) -> None:
        """Keep ``frame`` (H, W, 3) uint8 inside the person's box ``(y0, y1, x0, x1)``
        px (empty, ``y0 == y1``, without a person)."""
        if self.dropped:
            return
        if self.frame_shape is None:
            self.frame_shape = tuple(frame.shape[:2])
        if tuple(frame.shape[:2]) != self.frame_shape:  # the cues' decode deals with it
            self.boxes, self.origins, self.dropped = [], [], True
            return
        y0, y1, x0, x1 = (int(v) for v in box)
        if y1 <= y0 or x1 <= x0:
            self.boxes.append(None)
            self.origins.append((0, 0))
            return
        H, W = self.frame_shape
        m = max(MARGIN_PX, int(np.ceil(MARGIN * (y1 - y0))))
        y0, y1, x0, x1 = max(y0 - m, 0), min(y1 + m, H), max(x0 - m, 0), min(x1 + m, W)
        kept = np.array(frame[y0:y1, x0:x1])
        self.nbytes += kept.nbytes
        seen = len(self.boxes) + 1
        expected = self.nbytes / seen * self.n_frames if self.n_frames and \
            seen >= _PROJECT_AFTER else 0.0
        if self.nbytes > self.budget or expected > self.budget:  # the cues decode again
            self.boxes, self.origins, self.dropped = [], [], True
            return
        self.boxes.append(kept)
        self.origins.append((y0, x0))

    def __len__(self) -> int:
        return len(self.boxes)

    def complete(self, n_frames: int) -> bool:
        """Whether every one of the clip's ``n_frames`` frames is kept."""
        return not self.dropped and len(self.boxes) == int(n_frames)

    def covers(self, bounds) -> bool:
        """Whether every frame's pixels read, inside ``bounds`` (F, 4) ``x_min, x_max,
        y_min, y_max`` px (inclusive; ``x_min > x_max`` where a frame reads none), are
        kept."""
        b = np.asarray(bounds, float).reshape(-1, 4)
        reads = b[:, 0] <= b[:, 1]
        if len(b) > len(self.boxes):
            return not reads[len(self.boxes):].any() and self.covers(b[:len(self.boxes)])
        size = np.array([(0, 0) if k is None else k.shape[:2] for k in self.boxes[:len(b)]],
                        float).reshape(-1, 2)
        y0, x0 = np.asarray(self.origins[:len(b)], float).reshape(-1, 2).T
        inside = (b[:, 0] >= x0) & (b[:, 1] < x0 + size[:, 1]) \
            & (b[:, 2] >= y0) & (b[:, 3] < y0 + size[:, 0])
        return bool(np.all(inside | ~reads))

    def frames(self, stop: int | None = None) -> Iterator[np.ndarray]:
        """The frames (H, W, 3) uint8 up to ``stop``, black outside the kept boxes (one
        buffer, refilled: a frame is valid until the next is asked for)."""
        if self.frame_shape is None:
            return
        buf = np.zeros((*self.frame_shape, 3), np.uint8)
        last = None
        for box, (y0, x0) in zip(self.boxes[:stop], self.origins[:stop], strict=True):
            if last is not None:
                buf[last] = 0
                last = None
            if box is not None:
                last = (slice(y0, y0 + box.shape[0]), slice(x0, x0 + box.shape[1]))
                buf[last] = box
            yield buf
