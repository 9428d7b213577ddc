"""Backgrounds for ground-truth clips: a procedurally textured room
(:func:`make_background`) or an image file scaled to the frame (:func:`load_background`)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from vidcap.errors import InputFileError


def make_background(
    size: tuple[int, int], rng: np.random.Generator, *, horizon: float = 0.8
) -> np.ndarray:
    """A procedurally textured room: a panelled, mottled wall over a planked floor.

    Parameters
    ----------
    size : (int, int)
        (width, height) pixels.
    rng : numpy.random.Generator
        Colours and texture.
    horizon : float
        Where the wall meets the floor, as a fraction of the height from the top.

    Returns
    -------
    numpy.ndarray, shape (H, W, 3) uint8
        BGR; muted greys/beiges/browns, far from the clothing colours.
    """
    import cv2

    W, H = int(size[0]), int(size[1])
    y = np.arange(H)[:, None]
    x = np.arange(W)[None, :]

    def smooth_noise(cells, amp, chroma=0.25):
        # mostly brightness (same in every channel), a little colour
        n = rng.standard_normal((cells[1], cells[0], 1)) + chroma * rng.standard_normal(
            (cells[1], cells[0], 3)
        )
        return amp * cv2.resize(n.astype(np.float32), (W, H), interpolation=cv2.INTER_CUBIC)

    wall = np.array([150, 165, 170], np.float32) + rng.uniform(-12, 12, 3).astype(np.float32)
    floor = np.array([105, 120, 135], np.float32) + rng.uniform(-10, 10, 3).astype(np.float32)
    img = np.where((y < horizon * H)[..., None], wall, floor).astype(np.float32)
    img = img + smooth_noise((6, 5), 8.0) + smooth_noise((W // 8 + 2, H // 8 + 2), 4.0)
    img += rng.normal(0.0, 3.0, (H, W, 1)).astype(np.float32)
    # wall panels: darker vertical seams every ~W/5 px; a skirting board at the horizon
    pitch = max(8, int(W / rng.uniform(4.0, 6.0)))
    seam = ((x + int(rng.integers(pitch))) % pitch) < max(1, W // 320)
    wall_rows = y < horizon * H
    img[np.broadcast_to(seam & wall_rows, (H, W))] -= 18.0
    skirt = (y >= horizon * H - max(2, H // 60)) & (y < horizon * H)
    img[np.broadcast_to(skirt, (H, W))] -= 25.0
    # floor planks: lines converging slightly, alternating tone
    band = ((y - horizon * H) // max(2, H // 24)) % 2 == 1
    img[np.broadcast_to(band & ~wall_rows, (H, W))] -= 6.0
    return np.clip(img, 0, 255).astype(np.uint8)


def load_background(path: str | os.PathLike, size: tuple[int, int]) -> np.ndarray:
    """Read an image file and resize it to ``size`` (width, height); BGR uint8 (H, W, 3)."""
    import cv2

    path = Path(path)
    if not path.is_file():
        raise InputFileError("background image not found", path)
    img = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if img is None:
        raise InputFileError("cannot read the background image (not an image file?)", path)
    return cv2.resize(img, (int(size[0]), int(size[1])), interpolation=cv2.INTER_AREA)
