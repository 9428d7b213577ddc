"""Small synthetic clips with known silhouettes, for the background/silhouette tests.

A textured static background (smooth noise, a few flat shapes) and a stick
figure drawn as thick lines: a torso that bobs a little and limbs that swing, so
some background pixels are covered in most frames (the jumping-jacks case), plus
optional camera noise and slow lighting drift. Used only by tests and benchmarks.
"""

from __future__ import annotations

import cv2
import numpy as np


def background(h: int, w: int, rng: np.random.Generator) -> np.ndarray:
    """A textured BGR background (H, W, 3) uint8."""
    coarse = rng.uniform(60, 200, (max(2, h // 24), max(2, w // 24), 3)).astype(np.float32)
    img = cv2.resize(coarse, (w, h), interpolation=cv2.INTER_CUBIC)
    img += rng.normal(0, 6, (h, w, 3)).astype(np.float32)  # fine texture
    for _ in range(6):
        c = tuple(float(v) for v in rng.uniform(40, 220, 3))
        x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
        cv2.rectangle(img, (x, y), (x + w // 6, y + h // 8), c, -1)
    return np.clip(img, 0, 255).astype(np.uint8)


def figure_mask(h: int, w: int, phase: float, *, cx: float | None = None) -> np.ndarray:
    """A jumping-jacks stick figure at ``phase`` (radians), (H, W) uint8 0/1."""
    m = np.zeros((h, w), np.uint8)
    s = h / 240
    cx = w / 2 if cx is None else cx
    open_ = 0.5 - 0.5 * np.cos(phase)          # 0 closed .. 1 open
    top = 50 * s - 8 * s * open_                # a small jump
    hip = np.array([cx, top + 100 * s])
    neck = np.array([cx, top + 25 * s])
    th = max(2, int(10 * s))
    cv2.circle(m, (int(cx), int(top + 12 * s)), int(12 * s), 1, -1)
    cv2.line(m, tuple(neck.astype(int)), tuple(hip.astype(int)), 1, int(30 * s))
    for side in (-1, 1):
        a = np.deg2rad(-80 + 150 * open_)      # arm angle from straight down
        hand = neck + 70 * s * np.array([side * np.sin(np.deg2rad(10) + a), np.cos(a)])
        cv2.line(m, tuple((neck + [side * 12 * s, 4 * s]).astype(int)),
                 tuple(hand.astype(int)), 1, th)
        b = np.deg2rad(5 + 25 * open_)
        foot = hip + 95 * s * np.array([side * np.sin(b), np.cos(b)])
        cv2.line(m, tuple((hip + [side * 8 * s, 0]).astype(int)), tuple(foot.astype(int)), 1,
                 int(1.4 * th))
    return m


def clip(
    n: int = 60, h: int = 240, w: int = 320, *, rng: np.random.Generator,
    noise: float = 2.0, drift: float = 0.0, walk: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Frames (F, H, W, 3) uint8 and true masks (F, H, W) bool.

    ``drift``: the light's gain goes linearly from ``1 - drift`` to ``1 + drift``.
    ``walk``: the figure crosses the frame instead of staying in place.
    """
    bg = background(h, w, rng).astype(np.float32)
    colours = np.array([[40, 50, 160], [150, 90, 30], [30, 30, 30]], np.float32)
    frames = np.empty((n, h, w, 3), np.uint8)
    masks = np.empty((n, h, w), bool)
    for i in range(n):
        cx = (0.1 + 0.8 * i / max(1, n - 1)) * w if walk else None
        m = figure_mask(h, w, 2 * np.pi * i / 15, cx=cx)
        img = bg.copy()
        # shirt, trousers (lower half), skin-ish head by rows
        rows = np.arange(h)[:, None]
        part = np.where(rows < h * 0.25, 0, np.where(rows < h * 0.6, 1, 2))
        col = colours[np.broadcast_to(part, (h, w))]
        img = np.where(m[..., None] > 0, col, img)
        gain = 1 - drift + 2 * drift * i / max(1, n - 1)
        img = img * gain + rng.normal(0, noise, img.shape)
        frames[i] = np.clip(img, 0, 255).astype(np.uint8)
        masks[i] = m > 0
    return frames, masks


def room_with_verticals(h: int, w: int, vanishing_y: float, rng: np.random.Generator
                        ) -> np.ndarray:
    """A light BGR plate (H, W, 3) uint8 with dark lines from its top edge toward the point
    ``(w / 2, vanishing_y)`` far below the frame: a room's door frames and shelves seen by
    a camera looking down (:mod:`vidcap.video.vanishing`)."""
    room = np.clip(rng.normal(190, 4, (h, w, 3)), 0, 255).astype(np.uint8)
    for x in np.arange(10, w, 30):
        d = np.array([w / 2 - x, vanishing_y - 5.0])
        end = np.array([x, 5.0]) + d / np.linalg.norm(d) * 0.45 * h
        cv2.line(room, (int(x), 5), tuple(np.int32(end)), (70, 70, 70), 2)
    return room
