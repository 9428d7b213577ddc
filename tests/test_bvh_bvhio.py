"""Our BVH files read by an independent reader (bvhio) give our joint positions."""

from __future__ import annotations

import numpy as np
import pytest

from vidcap.body import BodyModel
from vidcap.io.bvh import write_bvh
from vidcap.kinematics import Motion
from vidcap.synth import make_motion

bvhio = pytest.importorskip("bvhio")


def _bvhio_positions(path, n_frames, names):
    root = bvhio.readAsHierarchy(str(path))
    out = np.empty((n_frames, len(names), 3))
    lengths = []
    for f in range(n_frames):
        root.loadPose(f)
        pos = {j.Name: np.array(list(j.PositionWorld), float) for j, _, _ in root.layout()}
        out[f] = [pos[n] for n in names]
    root.loadRestPose()
    for joint, _, depth in root.layout():
        if depth > 0:
            lengths.append((joint.Name, float(np.linalg.norm(list(joint.Position)))))
    return out, lengths


@pytest.mark.parametrize("which", ["rest", "walk", "jacks"])
def test_bvhio_reads_our_positions(tmp_path, which):
    body = BodyModel(height=1.7)
    if which == "rest":
        m = Motion.rest(body.skeleton(), 2)
    else:
        m = make_motion(which, body=body, n_frames=8, rng=np.random.default_rng(4))
    path = tmp_path / f"{which}.bvh"
    write_bvh(path, m)
    theirs, lengths = _bvhio_positions(path, m.n_frames, m.skeleton.joint_names)
    np.testing.assert_allclose(theirs, m.positions(), atol=1e-4)
    assert len(lengths) >= len(m.skeleton.joint_names) - 1
    short = [(n, v) for n, v in lengths if v < 1e-3]
    assert not short, f"zero-length bones: {short}"
