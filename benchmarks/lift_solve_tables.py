"""The tables of ``benchmarks/lift_accuracy.py --solve`` (issue 33): the seed's
per-segment lift against the clip solve.

* **Noisy true 2D**: each motion filmed by vidcap.synth's orthographic camera at yaw 90
  and 45 degrees, its true 2D joints plus Gaussian noise of 0, 1, 2 and 4 % of the
  body height (seeded), lifted with the proposed signs and with the true ones
  (orientation proposed from the noisy joints, scale from the image height as the 3D
  stage reads it: :func:`vidcap.video.lifting.frame_scales`, noise bias removed).
* **End to end**: the sample clips and held-out renders through the 2D fit, then
  both lifts on the fitted joints, no annotations.

Columns: MPJPE (12 limb joints, pelvis-aligned) and PA-MPJPE (per frame similarity
alignment without reflection) in mm; foot sliding in mm per frame while the *true*
foot is planted (true ankle slower than 0.25 m/s and within 5 cm of the lower
ankle), in the lift's own world; jitter (mean joint acceleration, m/s^2); the solve's
largest bone-length deviation in the BVH it writes (read back), and its speed.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from vidcap.body import JOINT_INDEX, SEGMENT_JOINTS
from vidcap.video.lift import estimate_scale, lift, torso_width_ratio, yaw_from_orientation
from vidcap.video.lifting import frame_scales
from vidcap.video.motion import jitter
from vidcap.video.proposals import propose_orientation, propose_signs

LIMB_JOINTS = np.array([JOINT_INDEX[f"{s}_{j}"] for s in "lr" for j in
                        ("shoulder", "elbow", "wrist", "hip", "knee", "ankle")])
ANKLES = np.array([JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]])
NOISE = (0.0, 0.01, 0.02, 0.04)


def mpjpe_mm(pred, true) -> float:
    """Mean error of the 12 limb joints after aligning the pelvis, mm."""
    a = pred - pred[:, :1]
    b = true - true[:, :1]
    return float(np.linalg.norm(a[:, LIMB_JOINTS] - b[:, LIMB_JOINTS], axis=-1).mean() * 1e3)


def pa_mpjpe_mm(pred, true) -> float:
    """Mean error of the 12 limb joints after a per-frame similarity alignment (rotation
    without reflection, scale, translation; Umeyama), mm."""
    return float(pa_joint_errors(pred, true).mean() * 1e3)


def pa_joint_errors(pred, true) -> np.ndarray:
    """Error (..., F, 12) of each of the 12 limb joints, metres, after each frame's
    similarity alignment of ``pred`` (..., F, 15, 3) on ``true`` (F, 15, 3) (rotation
    without reflection, scale, translation; Umeyama); leading axes of ``pred`` are
    alternatives of the same frames."""
    a = pred[..., LIMB_JOINTS, :] - pred[..., LIMB_JOINTS, :].mean(-2, keepdims=True)
    b = true[..., LIMB_JOINTS, :] - true[..., LIMB_JOINTS, :].mean(-2, keepdims=True)
    b = np.broadcast_to(b, a.shape)
    u, s, vt = np.linalg.svd(np.swapaxes(a, -1, -2) @ b)
    d = np.sign(np.linalg.det(u @ vt))
    fix = np.ones(d.shape + (3,))
    fix[..., 2] = d
    rot = u @ (fix[..., :, None] * vt)
    scale = (s * fix).sum(-1) / (a ** 2).sum(axis=(-1, -2))
    aligned = scale[..., None, None] * a @ rot
    return np.linalg.norm(aligned - b, axis=-1)


def true_planted(true3, fps) -> np.ndarray:
    """(F, 2) bool: the true ankle is planted (slow and near the lower ankle)."""
    ank = true3[:, ANKLES]
    speed = np.linalg.norm(np.gradient(ank, axis=0), axis=-1) * fps
    height = ank[:, :, 1] - ank[:, :, 1].min(axis=1, keepdims=True)
    return (speed < 0.25) & (height < 0.05)


def sliding_mm(pred, planted) -> float:
    """Mean frame-to-frame motion of an ankle planted in both frames, mm (nan: none)."""
    both = planted[1:] & planted[:-1]
    if not both.any():
        return float("nan")
    step = np.linalg.norm(np.diff(pred[:, ANKLES], axis=0), axis=-1)
    return float(step[both].mean() * 1e3)


def bvh_bone_deviation(params, body, fps) -> float:
    """Largest |bone length - its mean| (m) over the frames of the BVH written from the
    solve's rotations and read back."""
    from vidcap.io.bvh import read_bvh, write_bvh
    from vidcap.video.solve.stage import solved_motion

    m = solved_motion(params, fps, body=body).motion
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "solve.bvh"
        write_bvh(path, m)
        pos = read_bvh(path).positions()
    seg = np.linalg.norm(pos[:, SEGMENT_JOINTS[:, 1]] - pos[:, SEGMENT_JOINTS[:, 0]], axis=-1)
    return float(np.abs(seg - seg.mean(0)).max())


def _row(label, pred, true3, fps, planted):
    return (label, mpjpe_mm(pred, true3), pa_mpjpe_mm(pred, true3), sliding_mm(pred, planted),
            jitter(pred, fps))


def noisy_rows(name, truth, true3, body, *, seed=0):
    """Rows (clip, noise, lift, signs, MPJPE, PA, sliding, jitter, s) for every noise level."""
    from vidcap.video.solve import solve_clip

    fps = float(truth["fps"])
    planted = true_planted(true3, fps)
    rows, bones, speed = [], [], []
    for noise in NOISE:
        rng = np.random.default_rng(seed)
        s_true = estimate_scale(truth["joints2d"], body)
        j2 = truth["joints2d"] + rng.normal(0.0, noise * body.height * s_true,
                                            truth["joints2d"].shape)
        s = frame_scales(j2, fps, body)  # the 3D stage's scale (noise bias removed)
        orient = propose_orientation(j2, scale=s, fps=fps, body=body, sides_known=True)
        yaw = yaw_from_orientation(orient, torso_width_ratio(j2, s, body))
        prop = propose_signs(j2, yaw, scale=s, body=body).signs
        for sign_name, signs in (("proposed", prop), ("true", truth["depth_signs"])):
            seg = lift(j2, signs, yaw, body=body, scale=s).joints3d
            rows.append((name, noise, "segment", sign_name,
                         *_row("", seg, true3, fps, planted)[1:], 0.0))
            t0 = time.perf_counter()
            sol = solve_clip(j2, scale=s, fps=fps, body=body, yaw=yaw, prior_signs=signs)
            secs = time.perf_counter() - t0
            speed.append(len(j2) / secs)
            rows.append((name, noise, "solve", sign_name,
                         *_row("", sol.joints3d, true3, fps, planted)[1:], secs))
            if sign_name == "proposed":
                bones.append(bvh_bone_deviation(sol.params, body, fps))
    return rows, max(bones), speed


def print_noisy(rows):
    print("clip | 2D noise % of height | lift | signs | MPJPE mm | PA-MPJPE mm | "
          "foot sliding mm/frame | jitter m/s^2 | s")
    print("--- | --- | --- | --- | --- | --- | --- | --- | ---")
    for r in rows:
        print(f"{r[0]} | {r[1] * 100:.0f} | {r[2]} | {r[3]} | {r[4]:.0f} | {r[5]:.0f} | "
              f"{r[6]:.1f} | {r[7]:.1f} | {r[8]:.2f}")


def end_to_end_rows(clips, body):
    """Rows (clip, frames, lift, MPJPE, PA, sliding, jitter, 2D error % of height) for
    (name, pose2d-like dict, truth, true3) clips."""
    from vidcap.video.lifting import lift_pose
    from vidcap.video.solve import solve_clip  # noqa: F401 - imported before timing

    rows = []
    for name, fit, truth, true3, size in clips:
        fps = float(truth["fps"])
        planted = true_planted(true3, fps)
        for method in LIFTS:
            t0 = time.perf_counter()
            lr = lift_pose(fit["joints2d"], fps=fps, body=body, image_sides=True,
                           spread=fit["spread"], track=fit.get("track"), frame_size=size,
                           model_height=fit["model_height"], method=method.split()[0],
                           near_side=fit.get("near_side") if method in (FRONT, LEGS) else None,
                           limb_order=fit.get("limb_order") if method == LEGS else None)
            secs = time.perf_counter() - t0
            e2 = np.linalg.norm(lr.joints2d - truth["joints2d"], axis=-1).mean()
            h_px = np.mean(lr.scale) * body.height
            rows.append((name, len(lr.joints3d), method,
                         *_row("", lr.joints3d, true3, fps, planted)[1:], e2 / h_px * 100, secs))
    return rows


def add_front_options(ap) -> None:
    """The front/back cue's switches of ``lift_accuracy.py --solve`` and
    ``solve_fitted.py --front``: ``--no-face`` (the arms alone, as before the face cue,
    ``vidcap.video.pipeline.FACE_CUE``) and ``--front-margin`` (the front threshold with a
    margin, ``vidcap.video.proposals.NEAR_SIDE_MARGIN_FRONT``; built, off)."""
    ap.add_argument("--no-face", action="store_true",
                    help="the front/back cue without the face (vidcap.video.facecue)")
    ap.add_argument("--front-margin", action="store_true",
                    help="the front/back cue's front threshold with a margin "
                         "(vidcap.video.proposals.NEAR_SIDE_MARGIN_FRONT; off by default)")


def apply_front_options(args) -> None:
    """Set the switches of :func:`add_front_options` for this process."""
    import vidcap.video.pipeline as pipeline
    import vidcap.video.proposals as proposals

    if args.no_face:
        pipeline.FACE_CUE = False
    if args.front_margin:
        proposals.NEAR_SIDE_MIN_FRONT = proposals.NEAR_SIDE_MARGIN_FRONT


#: The lifts of the end-to-end and real tables: the per-segment lift, the solve without
#: and with the colour frame's front/back cue (:mod:`vidcap.video.frontback`; the
#: pipeline's default since issue 33's front/back work), and with the leg order too
#: (:mod:`vidcap.video.legorder`: arms and legs), same 2D, same run.
FRONT = "solve + front cue"
LEGS = "solve + front + limb cues"
LIFTS = ("segment", "solve", FRONT, LEGS)


def print_end_to_end(rows):
    print("clip | frames | lift | MPJPE mm | PA-MPJPE mm | foot sliding mm/frame | "
          "jitter m/s^2 | 2D error % of height (body sides) | s")
    print("--- | --- | --- | --- | --- | --- | --- | --- | ---")
    for r in rows:
        print(f"{r[0]} | {r[1]} | {r[2]} | {r[3]:.0f} | {r[4]:.0f} | {r[5]:.1f} | {r[6]:.1f} | "
              f"{r[7]:.1f} | {r[8]:.2f}")


def mediapipe_world(path, joint_names) -> np.ndarray:
    """MediaPipe's world landmarks of ``path`` (the mediapipe-reference tool's npz) as
    (F, 15, 3) in the lift's frame (X right, Y up, Z toward the camera), NaN for the
    joints it has no landmark for (pelvis = mid-hips; neck = mid-shoulders)."""
    ref = np.load(path)
    world = ref["world"].astype(float)
    world = world * np.array([1.0, -1.0, -1.0])  # y down, z away -> Y up, Z toward
    common = [str(n) for n in ref["names_vidcap_map"]]
    out = np.full((len(world), len(joint_names), 3), np.nan)
    for j, name in enumerate(joint_names):
        if name in common:
            out[:, j] = world[:, common.index(name)]
    i = {n: k for k, n in enumerate(joint_names)}
    out[:, i["pelvis"]] = 0.5 * (out[:, i["l_hip"]] + out[:, i["r_hip"]])
    out[:, i["neck"]] = 0.5 * (out[:, i["l_shoulder"]] + out[:, i["r_shoulder"]])
    return out


def mediapipe_image_joints(path, joint_names, fitted) -> np.ndarray:
    """MediaPipe's 2D landmarks of ``path`` (pixels, its own left and right) as (F, 15, 2)
    joints: the limb joints as they are, pelvis = mid-hips, neck = mid-shoulders, and
    the head top (no MediaPipe landmark) the ``fitted`` (F, 15, 2) joints' neck-to-head
    vector set on that neck; NaN frames where a landmark is missing."""
    ref = np.load(path)
    common = [str(n) for n in ref["names_vidcap_map"]]
    marks = ref["landmarks"].astype(float)
    n = min(len(marks), len(fitted))
    i = {name: k for k, name in enumerate(joint_names)}
    out = np.full((n, len(joint_names), 2), np.nan)
    for j, name in enumerate(joint_names):
        if name in common:
            out[:, j] = marks[:n, common.index(name)]
    out[:, i["pelvis"]] = 0.5 * (out[:, i["l_hip"]] + out[:, i["r_hip"]])
    out[:, i["neck"]] = 0.5 * (out[:, i["l_shoulder"]] + out[:, i["r_shoulder"]])
    out[:, i["head_top"]] = (fitted[:n, i["head_top"]] - fitted[:n, i["neck"]]
                             + out[:, i["neck"]])
    out[~np.isfinite(out).all(axis=(1, 2))] = np.nan
    return out


#: The row of :func:`real_rows` that lifts MediaPipe's own 2D (a reference for the lift).
MEDIAPIPE_2D = "solve on MediaPipe's 2D"


def real_rows(video, reference, proportions="human", frames=None, label=None):
    """PA-MPJPE (mm) of both lifts on a real clip against MediaPipe's world landmarks, on
    the frames where MediaPipe has every limb joint (and within ``frames``, (F,) bool,
    when given: the stretches a person is in the picture), of a fixed standing pose
    (:func:`standing_baseline_mm`) and of the solve given MediaPipe's own 2D landmarks
    and sides (:data:`MEDIAPIPE_2D`: what the lift makes of better 2D; optimistic, as
    MediaPipe's 2D and world landmarks come from one network) on the same frames. The
    pipeline runs on the whole clip (``real_clips.pipeline_result``: default options but
    ``proportions``, as ``vidcap convert --proportions``; stage cache), the lifts too,
    with the pipeline's body. Rows: (label, default the video's name; frames; lift; mm)."""
    from real_clips import pipeline_result

    from vidcap.body import JOINT_NAMES
    from vidcap.io.video import iter_frames
    from vidcap.video.lifting import lift_pose
    from vidcap.video.pipeline import colour_cues

    res = pipeline_result(Path(video), proportions=proportions)
    body = res.body
    ref = mediapipe_world(reference, JOINT_NAMES)
    size = (res.masks.shape[2], res.masks.shape[1])
    theirs = mediapipe_image_joints(reference, JOINT_NAMES, res.image_joints2d)
    n = min(len(ref), len(theirs))
    ok = np.isfinite(ref[:n, LIMB_JOINTS]).all(axis=(1, 2))
    ok &= np.isfinite(res.image_joints2d[:n]).all(axis=(1, 2))
    ok &= np.isfinite(theirs[:n]).all(axis=(1, 2))
    if frames is not None:
        ok &= np.asarray(frames, bool)[:n]
    label = label or Path(video).name
    rows = []
    near, limbs = colour_cues(iter_frames(video, stop=len(res.image_joints2d)),
                             res.image_joints2d, res.model_height, res.body, front=True,
                             limbs=True, fps=res.fps)
    for method in LIFTS:
        lr = lift_pose(res.image_joints2d, fps=res.fps, body=body, image_sides=True,
                       spread=res.spread, track=res.track, frame_size=size,
                       model_height=res.model_height, method=method.split()[0],
                       near_side=near if method in (FRONT, LEGS) else None,
                       limb_order=limbs if method == LEGS else None)
        rows.append((label, int(ok.sum()), method,
                     pa_mpjpe_mm(lr.joints3d[:n][ok], ref[:n][ok])))
    rows.append((label, int(ok.sum()), "standing pose", standing_baseline_mm(ref[:n][ok], body)))
    lr = lift_pose(theirs[:n], fps=res.fps, body=body, image_sides=False, track=res.track[:n],
                   frame_size=size, model_height=res.model_height[:n], method="solve")
    rows.append((label, int(ok.sum()), MEDIAPIPE_2D, pa_mpjpe_mm(lr.joints3d[ok], ref[:n][ok])))
    return rows


def standing_baseline_mm(ref, body) -> float:
    """PA-MPJPE (mm) of one fixed pose for every frame of ``ref`` (F, 15, 3): the body
    model standing with its arms hanging down (no video read). A lift that does not beat
    it has not yet read the pose from the image."""
    from vidcap.body import JOINT_INDEX as J

    pose = body.rest_positions().copy()
    for side in "lr":
        shoulder = pose[J[f"{side}_shoulder"]]
        upper = np.linalg.norm(pose[J[f"{side}_elbow"]] - shoulder)
        fore = np.linalg.norm(pose[J[f"{side}_wrist"]] - pose[J[f"{side}_elbow"]])
        pose[J[f"{side}_elbow"]] = shoulder - [0.0, upper, 0.0]
        pose[J[f"{side}_wrist"]] = shoulder - [0.0, upper + fore, 0.0]
    return pa_mpjpe_mm(np.broadcast_to(pose, ref.shape), ref)
