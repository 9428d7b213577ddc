"""Static other blobs are scene; moving ones are people (issue 26)."""

from __future__ import annotations

import numpy as np

from vidcap.video.staticblobs import static_rows


def test_a_blob_that_stays_put_is_static_a_walker_is_not():
    rng = np.random.default_rng(7)
    n = 40
    rows = []
    for f in range(n):
        j = rng.integers(-1, 2, 4)  # a lit wall: the same box, a pixel of jitter
        rows.append((f, 100 + j[0], 20 + j[1], 140 + j[2], 90 + j[3], 2500))
        x = 10 + 6 * f                 # a second person crossing the frame
        rows.append((f, x, 30, x + 25, 110, 1800))
    others = np.array(rows)
    static = static_rows(others, n)
    assert static[0::2].all()
    assert not static[1::2].any()
    assert not static_rows(others[:4], n).any()  # too few frames to tell: moving
