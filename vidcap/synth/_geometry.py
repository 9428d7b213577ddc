"""Small vector helpers shared by the ground-truth renderer's modules."""

from __future__ import annotations

import numpy as np


def unit(v: np.ndarray, axis: int = -1) -> np.ndarray:
    """``v`` scaled to unit length along ``axis`` (zero vectors are left as they are)."""
    n = np.linalg.norm(v, axis=axis, keepdims=True)
    return v / np.where(n > 1e-12, n, 1.0)
