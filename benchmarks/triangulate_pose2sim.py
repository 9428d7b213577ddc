"""A multi-view 3D reference for the Pose2Sim balance trial (issue 33's PA-MPJPE per real clip).

    VIDCAP_DATA=/work/data python benchmarks/triangulate_pose2sim.py

The Pose2Sim demo trial (one participant balancing on one leg, 100 frames at 60 fps) is
filmed by four synchronised, calibrated cameras (a Qualisys calibration, ``Calib.qca.txt``).
MediaPipe Pose's 2D landmarks of each view (the mediapipe-reference tool) are triangulated
here (linear DLT, each view weighted by MediaPipe's visibility, points undistorted first)
into one 3D skeleton per frame, in the lab's frame (metres). It is a multi-view reference,
not motion capture: it inherits MediaPipe's 2D errors (the median reprojection error is
printed; about 10-20 px on a participant 600-1200 px tall), but it has no monocular depth
ambiguity, so vidcap's 3D lift of cam1, cam3 or cam4 alone can be scored against it
(PA-MPJPE) independently of MediaPipe's own 3D guess.

Reads ``$VIDCAP_DATA/lift/pose2sim/`` (``cam0N.mp4``, ``cam0N.mediapipe.npz``,
``Calib.qca.txt``; made by benchmarks/get_data.sh) and writes
``$VIDCAP_DATA/lift/pose2sim_balance_3d.npz``:

* ``joints`` (F, 33, 3) float, metres, lab frame (Qualisys world; z up); NaN where fewer
  than two views saw the landmark;
* ``reproj_px`` (F, 33) float, the median reprojection error over the views, pixels;
* ``names`` (33,), ``names_vidcap_map`` (33,): MediaPipe's landmark names and the common
  joint names (``l_shoulder``, ...), as in the mediapipe-reference npz;
* ``R`` (4, 3, 3), ``t`` (4, 3), ``K`` (4, 3, 3), ``cameras`` (4,): world-to-camera
  rotation and translation (metres) and the intrinsics of each camera, so the joints can
  be put in a camera's frame (``R @ X + t``; x right, y down, z forward).

and, per camera, ``$VIDCAP_DATA/lift/pose2sim_balance_cam{1,2,3,4}_triangulated.npz``: the
same skeleton in that camera's frame, origin between the hips, in the mediapipe-reference
layout (``world``, ``names_vidcap_map``), a drop-in for ``<clip>.mediapipe.npz`` where a
benchmark scores 3D joints (lift_solve_tables.real_rows).
"""

from __future__ import annotations

import os
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import cv2
import numpy as np

CAMERAS = ("cam01", "cam02", "cam03", "cam04")


def read_qca(path: Path):
    """Cameras of a Qualisys ``.qca.txt`` calibration.

    Returns
    -------
    dict
        camera serial -> (K (3, 3), dist (4,) k1 k2 p1 p2, R (3, 3), t (3,)), with R, t the
        world-to-camera transform (metres) of an OpenCV camera (x right, y down, z forward).
        QTM stores sensor coordinates in 1/64 pixel and the camera's pose in the world with
        the camera looking down its -z; the conventions were checked by the reprojection
        error (median ~17 px with these, 95-320 px with the other three candidates).
    """
    out = {}
    for cam in ET.parse(path).getroot().findall("cameras/camera"):
        it, tr = cam.find("intrinsic").attrib, cam.find("transform").attrib
        k = np.array([[float(it["focalLengthU"]) / 64, 0, float(it["centerPointU"]) / 64],
                      [0, float(it["focalLengthV"]) / 64, float(it["centerPointV"]) / 64],
                      [0, 0, 1]])
        dist = np.array([float(it[n]) for n in ("radialDistortion1", "radialDistortion2",
                                                "tangentalDistortion1",
                                                "tangentalDistortion2")]) / 64
        rot = np.array([[float(tr[f"r{i}{j}"]) for j in (1, 2, 3)] for i in (1, 2, 3)])
        centre = np.array([float(tr[a]) for a in "xyz"]) / 1000
        flip = np.diag([1.0, -1.0, -1.0])  # QTM's camera looks down -z, OpenCV's down +z
        r_wc = flip @ rot
        out[cam.attrib["serial"]] = (k, dist, r_wc, -r_wc @ centre)
    return out


def triangulate(points: np.ndarray, weights: np.ndarray, projections: np.ndarray):
    """Weighted linear (DLT) triangulation, vectorised over frames and landmarks.

    Parameters
    ----------
    points : (V, F, J, 2) float
        Undistorted pixel coordinates in each of V views (NaN where unseen).
    weights : (V, F, J) float
        Weight of each view (0 where unseen).
    projections : (V, 3, 4) float
        Projection matrices ``K [R | t]``.

    Returns
    -------
    (F, J, 3) float
        World points; NaN where fewer than two views have a weight.
    """
    w = np.where(np.isfinite(points).all(-1), weights, 0.0)
    p = np.nan_to_num(points)
    # Rows x * P3 - P1 and y * P3 - P2 of each view: (V, F, J, 2, 4).
    rows = (p[..., None] * projections[:, None, None, 2:3, :]
            - projections[:, None, None, 0:2, :])
    rows = rows * w[..., None, None]
    a = np.moveaxis(rows, 0, 2).reshape(*points.shape[1:3], -1, 4)  # (F, J, 2V, 4)
    _, _, vt = np.linalg.svd(a)
    x = vt[..., -1, :]
    out = x[..., :3] / x[..., 3:4]
    out[(w > 0).sum(0) < 2] = np.nan
    return out


def main() -> int:
    data = os.environ.get("VIDCAP_DATA")
    folder = Path(data or "/nonexistent") / "lift" / "pose2sim"
    needed = [folder / "Calib.qca.txt"] + [folder / f"{c}.mediapipe.npz" for c in CAMERAS]
    missing = [p.name for p in needed if not p.exists()]
    if missing:
        print(f"skipped: {folder} lacks {', '.join(missing)} (benchmarks/get_data.sh)")
        return 0
    calib = read_qca(folder / "Calib.qca.txt")
    refs = [np.load(folder / f"{c}.mediapipe.npz") for c in CAMERAS]
    n = min(len(r["landmarks"]) for r in refs)
    pts, wts, proj = [], [], []
    for cam, ref in zip(CAMERAS, refs, strict=True):
        k, dist, r, t = calib[cam]
        lm = ref["landmarks"][:n].astype(np.float64)
        und = cv2.undistortPoints(np.nan_to_num(lm).reshape(-1, 1, 2), k, dist, P=k)
        und = und.reshape(lm.shape)
        und[~np.isfinite(lm)] = np.nan
        pts.append(und)
        wts.append(np.nan_to_num(ref["visibility"][:n]))
        proj.append(k @ np.hstack([r, t[:, None]]))
    pts, wts, proj = np.stack(pts), np.stack(wts), np.stack(proj)
    joints = triangulate(pts, wts, proj)
    hom = np.concatenate([joints, np.ones(joints.shape[:2] + (1,))], -1)
    q = np.einsum("vij,fkj->vfki", proj, hom)
    err = np.linalg.norm(q[..., :2] / q[..., 2:3] - pts, axis=-1)  # (V, F, J)
    reproj = np.nanmedian(err, axis=0)
    body = [i for i, m in enumerate(refs[0]["names_vidcap_map"]) if m and m != "nose"]
    print(f"{n} frames, 4 views: median reprojection error {np.nanmedian(reproj[:, body]):.1f} "
          f"px over the 12 limb joints; per view "
          + ", ".join(f"{c} {np.nanmedian(err[i][:, body]):.1f}" for i, c in enumerate(CAMERAS)))
    out = folder.parent / "pose2sim_balance_3d.npz"
    np.savez_compressed(
        out, joints=joints, reproj_px=reproj, names=refs[0]["names"],
        names_vidcap_map=refs[0]["names_vidcap_map"], cameras=np.array(CAMERAS),
        R=np.stack([calib[c][2] for c in CAMERAS]), t=np.stack([calib[c][3] for c in CAMERAS]),
        K=np.stack([calib[c][0] for c in CAMERAS]))
    print(f"wrote {out}")
    # The same skeleton in each camera's frame, in the mediapipe-reference layout (``world``
    # (F, 33, 3) m, x right, y down, z away from the camera; ``names_vidcap_map``), so the
    # benchmarks that score a clip against ``<clip>.mediapipe.npz`` can take it instead.
    for cam in CAMERAS:
        r, t = calib[cam][2], calib[cam][3]
        world = joints @ r.T + t
        world = world - 0.5 * (world[:, 23:24] + world[:, 24:25])  # origin between the hips
        path = folder.parent / f"pose2sim_balance_{cam.replace('0', '')}_triangulated.npz"
        np.savez_compressed(path, world=world.astype(np.float32), reproj_px=reproj,
                            names=refs[0]["names"],
                            names_vidcap_map=refs[0]["names_vidcap_map"])
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
