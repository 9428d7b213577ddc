"""``pose2d_real.py``'s second part: every real clip through vidcap's own pipeline
(silhouettes from the video, the tracked 2D fit) against MediaPipe's landmarks (issue 27).

See ``real_clips.py`` for the clips, the frame ranges and the pipeline options. Per clip and
``cues``: frames scored (MediaPipe found a person in the range), the share of those where
vidcap gave joints, the median of the 12 limb joints' median distances (per cent of the
height: the larger side of the box around MediaPipe's 33 landmarks, about 0.9 of
stature), the share of (frame, joint) pairs more than 10 % apart, and the worst joint by
that share; ``mp-masks``: the same fit to MediaPipe's masks instead of vidcap's own
silhouettes (which part of the error is the silhouettes'); ``human`` and ``mp-human``: the
same two with ``proportions='human'`` (an anthropometric table's body, the ankles above
the soles); ``all-human``: ``--cues all`` with the human body (``vidcap convert``'s
default body); any of them with ``+solve``: the joints the image cannot show (shoulders, arms
inside the torso's outline) from the 3D clip solve (``--hidden solve``: the pipeline rows
through ``vidcap convert``'s own path with the clip solve, the ``mp-`` rows as ``vidcap pose2d``
does it); ``human-eN`` / ``outline-eN``: the ``human`` / ``outline`` row's silhouettes fitted
again as the pipeline fits them (the whole video, its chunks) but each chunk as
:func:`vidcap.video.fit.ensemble.fit_ensemble` of N members (``pose2d_real.py --ensemble N``;
``-e1`` repeats the plain row's fit, a check; with ``+solve`` the hidden joints from
:func:`vidcap.video.hidden.solve_hidden` as for the ``mp-`` rows, not convert's own path:
compare ``-eN+solve`` with ``-e1+solve``); ``human-empty``: the ``human`` row with the
plate taken from frames that show the scene empty where a user would know them
(``vidcap convert --background START:END``, :data:`real_clips.EMPTY_FRAMES`; the
``human`` row elsewhere).
Then per row kind, over the tuning clips, the validation clips and all, the mean of the
clips' medians and of their shares > 10 % apart, and how many clips meet issue 27's 5 % of
the height; per joint (each row kind): median / share > 10 %; and where vidcap's joint sits against
MediaPipe's, the median signed offset down / right (:func:`signed_offsets`: a high camera's
perspective reads as shoulders and hips up and ankles down, a silhouette reaching below the
soles as every joint down).
"""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path

import numpy as np
from real_clips import (
    EMPTY_FRAMES,
    RealClip,
    known_camera,
    pipeline_result,
    real_clips,
    stretch,
)

from vidcap.body import JOINT_NAMES

#: Clips something of the fit or the plate was chosen or diagnosed on (the rest are
#: validation): the human body's hips and feet on cam1 and onebyone 233-445 (wt-human);
#: cam4 and cam3 since wt-cam diagnosed their pipeline losses on them (the appearance
#: pass's scene-beside gate, vidcap.video.appearance.MIN_BETWEEN, and the lean fit's
#: head row, vidcap.video.fit.torso.HEAD_ROW_WIDTH, measured on cam4; cam3's frames
#: looked at). The three pose2sim cameras are one trial: cam1's figures are tuning too.
#: wt-real2d chose the fit's below-threshold track (vidcap.video.fit.frame.
#: track_below_threshold) among its variants on these four (frames looked at: cam1, cam3;
#: the validation clips' frames were looked at for the diagnosis only, nothing chosen).
TUNING = ("onebyone_room 233-445", "pose2sim_balance_cam1", "pose2sim_balance_cam3",
          "pose2sim_balance_cam4", "mmskeleton_taichi",
          # the came-stayed-went plate pass (vidcap.video.stayed) was tuned on these two
          "onebyone_room 66-194", "onebyone_room 1242-1357")


def _score(clip: RealClip, joints, compare, limb_joints) -> tuple[dict, float, np.ndarray]:
    """compare.py's joint scores of ``joints`` (F, 15, 2) px, the whole video's or the
    range's, over ``clip``'s range, the share of the reference's frames where vidcap
    gave joints, and :func:`signed_offsets` of ``limb_joints``."""
    with np.load(clip.reference) as d:
        landmarks = stretch(d["landmarks"], clip)
        names = d["names_vidcap_map"]
    if len(joints) != len(landmarks):
        joints = stretch(joints, clip)
    seen = np.isfinite(landmarks).all(axis=(1, 2))
    covered = float(np.isfinite(joints[seen]).all(axis=(1, 2)).mean()) if seen.any() else 0.0
    signed = signed_offsets(landmarks, [str(n) for n in names], joints, limb_joints)
    with tempfile.TemporaryDirectory() as tmp:
        ref, pred = Path(tmp) / "ref.npz", Path(tmp) / "pred.npz"
        np.savez(ref, landmarks=landmarks, names_vidcap_map=names)
        np.savez(pred, joints2d=joints, joint_names=np.array(JOINT_NAMES))
        return compare(ref, pred), covered, signed


def signed_offsets(landmarks, names, joints, limb_joints) -> np.ndarray:
    """Where vidcap's joints sit against MediaPipe's: the median over frames of
    ``joints`` less the reference's, per joint of ``limb_joints``, as a fraction of the
    height (compare.py's: the larger side of the box around the reference's landmarks).

    Parameters
    ----------
    landmarks : numpy.ndarray, shape (F, K, 2)
        The reference's landmarks, px (NaN: no person found).
    names : list of str
        vidcap's name of each landmark (the reference's ``names_vidcap_map``; other
        landmarks named otherwise).
    joints : numpy.ndarray, shape (F, 15, 2)
        vidcap's joints, px, in :data:`vidcap.body.JOINT_NAMES` order.
    limb_joints : sequence of str
        ``l_``/``r_`` joints of the arms (shoulder, elbow, wrist) and legs (hip, knee,
        ankle) to report.

    Returns
    -------
    numpy.ndarray, shape (J, 2)
        Median (x, y) offset per joint: +x vidcap's joint to the right, +y below
        MediaPipe's (a high camera's perspective shows as shoulders and hips above,
        negative, ankles below; a silhouette reaching below the soles as every joint
        below). Each frame's arms and legs are matched either way round where that
        is nearer, as compare.py's "swap" does (vidcap's labels are image sides).
    """
    ref = np.asarray(landmarks, float)
    height = np.maximum(*(ref.max(1) - ref.min(1)).T)  # NaN where it found nobody
    pred = np.asarray(joints, float)[:, [JOINT_NAMES.index(n) for n in limb_joints]].copy()
    ref = ref[:, [names.index(n) for n in limb_joints]]
    for parts in (("shoulder", "elbow", "wrist"), ("hip", "knee", "ankle")):
        left = [i for i, n in enumerate(limb_joints) if n[2:] in parts and n[0] == "l"]
        right = [limb_joints.index("r_" + limb_joints[i][2:]) for i in left]
        if not left:
            continue
        keep = np.linalg.norm(pred[:, left + right] - ref[:, left + right], axis=2).mean(1)
        swap = np.linalg.norm(pred[:, right + left] - ref[:, left + right], axis=2).mean(1)
        use = swap < keep  # NaN compares False: kept as given
        pred[np.ix_(use, left + right)] = pred[np.ix_(use, right + left)]
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = (pred - ref) / height[:, None, None]
    rel[~np.isfinite(rel).all(axis=2)] = np.nan
    out = np.full((len(limb_joints), 2), np.nan)
    has = np.isfinite(rel[..., 0]).any(axis=0)
    out[has] = np.nanmedian(rel[:, has], axis=0)
    return out


def _has_masks(path: Path) -> bool:
    with np.load(path) as d:
        return "masks" in d.files


def _fit_reference_masks(clip: RealClip, proportions: str = "seed", cues: str = "outline"):
    """The tracked fit (outline) to MediaPipe's masks over ``clip``'s range, a
    :class:`vidcap.video.fit.result.Pose2D`: what the fit does with silhouettes better
    than vidcap's own (cues column ``mp-masks``; ``mp-human``: with
    ``proportions='human'``; ``mp-all-human``: and ``cues='all'``, the clip's colour
    frames over the range as the cues' frames: the cues apart from the silhouettes)."""
    from vidcap.io.video import iter_frames
    from vidcap.video.fit.cueframes import FrameCrops
    from vidcap.video.fit.proportions import fit_keywords, human_proportions
    from vidcap.video.fit.tracking import fit_sequence

    with np.load(clip.reference) as d:
        masks = stretch(d["masks"], clip).astype(bool)
    kw = fit_keywords(human_proportions().factors) if proportions == "human" else {}
    frames = None
    if cues == "all":
        frames = FrameCrops.from_frames(
            iter_frames(clip.video, start=clip.start, stop=clip.start + len(masks)), masks)
    return fit_sequence(masks, cues=cues, frames=frames, **kw)


def _joints(clip: RealClip, row: str):
    """The 2D joints of one row kind (see the module's docstring); a row ending in
    ``+solve``: that row's with the joints the image cannot show taken from the 3D clip
    solve (pipeline rows: ``vidcap convert --hidden solve``'s own path,
    :func:`vidcap.video.pipeline.run` with ``lift='solve', hidden='solve'``; the
    ``mp-`` rows and the ensemble rows ``human-eN`` / ``outline-eN``:
    :func:`vidcap.video.hidden.solve_hidden`, ``vidcap pose2d --hidden solve``)."""
    from vidcap.io.video import probe
    from vidcap.video.fit.proportions import human_proportions, to_ankles
    from vidcap.video.hidden import solve_hidden

    base = row.removesuffix("+solve")
    hidden = "fit" if base == row else "solve"
    if base in ("human-erode", "human-dilate"):
        return _fit_ensemble(clip.video, "human", 1, base.removeprefix("human-"))[0]
    if base == "human-empty":  # vidcap convert --background START:END where it is known
        return pipeline_result(clip.video, "outline", proportions="human", hidden=hidden,
                               background=EMPTY_FRAMES.get(clip.video.stem)).image_joints2d
    if base.startswith(("human-e", "outline-e")):
        body, members = base.split("-e")
        return _ensemble_joints(clip.video, body, int(members), hidden)
    if base.startswith("human-k"):
        return _fit_with_perspective(clip, float(base.removeprefix("human-k")))
    if base in ("human-cam", "mp-human-cam"):
        return _with_known_camera(clip, base, hidden)
    if base == "human-auto":  # vidcap convert --camera auto
        return pipeline_result(clip.video, "outline", proportions="human", hidden=hidden,
                               camera="auto").image_joints2d
    human = base in ("human", "all-human", "mp-human", "mp-all-human")
    cues = "all" if base in ("all", "all-human", "mp-all-human") else "outline"
    if not base.startswith("mp-"):
        return pipeline_result(clip.video, cues, proportions="human" if human else "seed",
                               hidden=hidden).image_joints2d
    pose = _fit_reference_masks(clip, "human" if human else "seed", cues)
    if hidden == "fit":
        return pose.joints2d
    info = probe(clip.video)
    body = human_proportions() if human else None
    # head top to ankles, as convert's 3D stage reads it (a body with feet leaves them out)
    return solve_hidden(pose.joints2d, fps=info.fps, body=None if body is None else body.body(),
                        spread=pose.spread, frame_size=(info.width, info.height),
                        model_height=to_ankles(pose.model_height,
                                               None if body is None else {"foot": body.foot}))


def _fit_with_perspective(clip: RealClip, k: float) -> np.ndarray:
    """Row ``human-kK``: the pipeline's silhouettes over ``clip``'s range fitted again
    (tracked, outline, one process) with the ``human`` body as a camera of perspective
    ``K`` draws it (:func:`vidcap.video.fit.perspective.perspective_factors`; ``human-k0``:
    the same serial fit without the warp, the fair comparison). (F, 15, 2) joints."""
    from vidcap.video.fit.perspective import perspective_factors
    from vidcap.video.fit.proportions import fit_keywords, human_proportions
    from vidcap.video.fit.tracking import fit_sequence

    masks = stretch(np.asarray(pipeline_result(clip.video, "outline", proportions="human").masks),
                    clip)
    factors = perspective_factors(human_proportions().factors, k)
    return fit_sequence(masks, cues="outline", **fit_keywords(factors)).joints2d


def _with_known_camera(clip: RealClip, base: str, hidden: str):
    """Rows ``human-cam`` (``vidcap convert --camera`` with the calibration's values,
    :func:`real_clips.known_camera`, and the subject's stature as ``--height``) and
    ``mp-human-cam`` (the fit to MediaPipe's masks with the body warped alike)."""
    from vidcap.video.fit.perspective import camera_perspective, perspective_factors
    from vidcap.video.fit.proportions import fit_keywords, human_proportions
    from vidcap.video.fit.tracking import fit_sequence

    camera, stature = known_camera(clip.name)
    if base == "human-cam":
        return pipeline_result(clip.video, "outline", height=stature, proportions="human",
                               hidden=hidden, camera=camera).image_joints2d
    with np.load(clip.reference) as d:
        masks = stretch(d["masks"], clip).astype(bool)
    k = camera_perspective(camera, stature)
    return fit_sequence(masks, cues="outline", **fit_keywords(
        perspective_factors(human_proportions().factors, k))).joints2d


@functools.cache  # onebyone_room's six stretches share one fit and solve of the video
def _ensemble_joints(video: Path, body: str, members: int, hidden: str) -> np.ndarray:
    """Rows ``human-eN`` and ``outline-eN`` (:func:`_fit_ensemble`), (F, 15, 2) px over
    the whole video; ``hidden='solve'``: the joints the image cannot show from
    :func:`vidcap.video.hidden.solve_hidden` (``vidcap pose2d --hidden solve``)."""
    from vidcap.io.video import probe
    from vidcap.video.fit.proportions import human_proportions
    from vidcap.video.hidden import solve_hidden

    joints, spread, model_height = _fit_ensemble(video, body, members)
    if hidden == "fit":
        return joints
    info = probe(video)
    return solve_hidden(joints, fps=info.fps,
                        body=human_proportions().body() if body == "human" else None,
                        spread=spread, model_height=model_height,
                        frame_size=(info.width, info.height))


@functools.cache
def _fit_ensemble(video: Path, body: str, members: int, change: str = "as_given"):
    """Rows ``human-eN`` and ``outline-eN``: the pipeline's silhouettes (``body`` 'human'
    or 'outline', the seed's) of the whole ``video`` fitted again in the chunks the pipeline
    plans (:data:`vidcap.video.pipeline._PLAN_JOBS`, ``_CHUNKS_PER_JOB``; one process,
    the same result) with the outline, each chunk as
    :func:`vidcap.video.fit.ensemble.fit_ensemble` of ``members`` fits, and the frames
    where the person is mostly outside the picture left out as the pipeline leaves
    them. Over the whole video: the joints (F, 15, 2) px, the torso's spread (F,) and
    the model's height head top to ankles (F,) px (as the pipeline keeps it: the
    :func:`vidcap.video.hidden.solve_hidden` of a ``+solve`` row reads both). ``change``:
    the silhouettes first changed at the outline as an ensemble's member changes them
    (:func:`vidcap.video.fit.ensemble.changed_masks`; rows ``human-erode`` and
    ``human-dilate``, one fit each)."""
    from vidcap.video import pipeline
    from vidcap.video.fit.parallel import fit_sequence_chunked
    from vidcap.video.fit.proportions import fit_keywords, human_proportions, to_ankles
    from vidcap.video.person import partly_outside

    human = body == "human"
    masks = pipeline_result(video, "outline", proportions="human" if human else "seed").masks
    kw = fit_keywords(human_proportions().factors) if human else {}
    if change != "as_given":
        from vidcap.video.fit.ensemble import changed_masks

        masks = changed_masks(masks, change)
    pose = fit_sequence_chunked(masks, jobs=pipeline._PLAN_JOBS, per_job=pipeline._CHUNKS_PER_JOB,
                                workers=1, cues="outline", ensemble=members, **kw)
    joints, model_height = pose.joints2d.copy(), to_ankles(pose.model_height, kw)
    outside = partly_outside(masks)
    joints[outside], model_height[outside] = np.nan, np.nan
    return joints, pose.spread, model_height


#: Issue 27's bar: the median of the 12 joints' medians at most this share of the height.
GOAL = 0.05


def _summary(per_joint, cues) -> None:
    """Per row kind: over the tuning clips, the validation clips and all, the mean of the
    clips' 12-joint medians and of their shares of (frame, joint) pairs more than 10 %
    apart; and how many clips meet :data:`GOAL`. ``per_joint``: (clip name, row, 12 joint
    medians, 12 shares > 10 %, offsets)."""
    print(f"\nMeans over the clips of the 12-joint median / the share > 10 % apart (% of "
          f"height; clips), and the clips whose median is within {GOAL * 100:.0f} % of the height")
    print(f"{'row':16} {'tuning':>19} {'validation':>19} {'all':>19} {'<= goal':>9}")
    for c in cues:
        got = [(name in TUNING, float(np.median(m)), float(np.nanmean(sh)))
               for name, row, m, sh, _ in per_joint if row == c]
        if not got:
            continue
        cells = []
        for part in ([g for g in got if g[0]], [g for g in got if not g[0]], got):
            cells.append(f"{np.mean([g[1] for g in part]) * 100:5.2f} / "
                         f"{np.mean([g[2] for g in part]) * 100:4.1f} ({len(part):2d})"
                         if part else f"{'-':>19}")
        met = sum(g[1] <= GOAL for g in got)
        print(f"{c:16} {' '.join(cells)} {met:3d} of {len(got):2d}")


def pipeline_tables(ido, reference, compare, limb_joints, *,
                    cues=("outline", "all", "mp-masks", "human", "mp-human"), only=None,
                    use=None):
    """Print the tables. ``ido``: (name, video) of ido_walk; ``reference(name, video)``:
    its MediaPipe npz or None; ``compare(ref, pred)``: compare.py's joint scores.
    ``cues``: ``vidcap convert --cues`` values, ``mp-masks``: the fit (outline) to
    MediaPipe's masks instead of vidcap's silhouettes (clips whose reference has masks),
    ``human`` / ``mp-human``: the same with ``proportions='human'``, ``mp-all-human``:
    ``mp-human`` with ``cues='all'``. ``only``: just the clips whose name contains it;
    ``use``: just the ``'tuning'`` or the ``'validation'`` clips (None: both)."""
    print("\nThrough vidcap's own pipeline (silhouettes from the video, tracked fit; the seed's "
          "body (proportions='seed') in the outline, all and mp-masks rows, a real adult's "
          "(proportions='human', the default since wt-human) in the human rows; 'use': "
          "tuning clips chose or diagnosed something (TUNING), the others are "
          "validation). MediaPipe is a reference, "
          "not the truth (~2.4 % of height off on lab footage).")
    clips = real_clips()
    name, video = ido
    ref = reference(name, video) if video.exists() else None
    if ref is not None:
        clips.insert(0, RealClip(name, video, ref, 0, None))
    clips = [c for c in clips if (not only or only in c.name)
             and (use is None or (c.name in TUNING) == (use == "tuning"))]
    if not clips:
        print("  no real clip found")
        return
    print(f"{'clip':26} {'use':10} {'cues':12} {'frames':>6} {'vidcap':>6} {'median':>7} "
          f"{'>10 %':>6}  worst joint (>10 %)")
    per_joint = []
    for clip in clips:
        for c in cues:
            if c.startswith("mp-") and not _has_masks(clip.reference):
                continue
            if "-cam" in c and known_camera(clip.name) is None:
                continue  # no camera geometry known for this clip
            joints = _joints(clip, c)
            res, covered, signed = _score(clip, joints, compare, limb_joints)
            shares = [1 - res["joints"][j]["swap"]["pck10"] for j in limb_joints]
            medians = [res["joints"][j]["swap"]["median"] for j in limb_joints]
            worst = int(np.nanargmax(shares))
            clip_use = "tuning" if clip.name in TUNING else "validation"
            print(f"{clip.name:26} {clip_use:10} {c:12} {res['frames_with_reference']:6d} "
                  f"{covered:6.1%} "
                  f"{np.median(medians):7.1%} {np.nanmean(shares):6.0%}  "
                  f"{limb_joints[worst]} ({shares[worst]:.0%})")
            per_joint.append((clip.name, c, medians, shares, signed))
    _summary(per_joint, cues)
    print("\nPer joint: median % of height / share of frames > 10 % apart")
    print(f"{'clip':26} {'row':12} " + " ".join(f"{j.replace('shoulder', 'shld'):>9}"
                                               for j in limb_joints))
    rows = sorted(per_joint, key=lambda r: cues.index(r[1]))
    for name, c, medians, shares, _ in rows:
        print(f"{name:26} {c:12} " + " ".join(f"{m * 100:5.1f}/{s * 100:3.0f}"
                                             for m, s in zip(medians, shares, strict=True)))
    print("\nPer joint, where vidcap's joint sits: median offset from MediaPipe's, % of height, "
          "down / right (+: vidcap's lower / to the right; a high camera shows as shoulders "
          "and hips up, ankles down)")
    print(f"{'clip':26} {'row':12} " + " ".join(f"{j.replace('shoulder', 'shld'):>9}"
                                               for j in limb_joints))
    for name, c, _, _, signed in rows:
        print(f"{name:26} {c:12} " + " ".join(f"{dy * 100:5.1f}/{dx * 100:3.0f}"
                                             for dx, dy in signed))
