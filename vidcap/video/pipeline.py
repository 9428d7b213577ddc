"""Video -> BVH: the stages in sequence, with caching and progress.

Stages (``docs/architecture.md``)::

    frames -> background plate -> silhouettes -> 2D pose -> 3D lift -> motion -> BVH

:func:`run` calls one function per stage (:func:`_plate_stage`,
:func:`_silhouette_stage`, :func:`_pose_stage`, :func:`_lift_and_motion`), each owning
its cache key and its test for stale entries. The expensive image stages (plate,
silhouettes, 2D pose) are cached as ``.npz`` files (:class:`vidcap.video.stagecache.StageCache`,
default folder ``.vidcap-cache`` beside the output), each keyed by the video's identity,
the stage's parameters and the key of the stage before it, so changing an option or the
video redoes exactly the stages that depend on it. The 3D stage
(:func:`vidcap.video.lifting.lift_pose`) is cheap and always rerun, since it depends on the
user's annotations.

The stages themselves live in their own modules; the names this module used to define
are imported here too, so ``from vidcap.video.pipeline import lift_pose`` keeps working.
"""

from __future__ import annotations

import os
import time
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vidcap.body import BodyModel
from vidcap.errors import AnnotationError
from vidcap.video.annotations import Annotations, default_path
from vidcap.video.emptyframes import given_plate_identity
from vidcap.video.fit.perspective import camera_perspective, unwarp_joints, warp_joints
from vidcap.video.fitbody import ankle_share, fit_keywords_for, unwarped_estimate
from vidcap.video.flatview import flat_view
from vidcap.video.hidden import DEFAULT_HIDDEN, check_hidden, fill_hidden
from vidcap.video.keptframes import KeptFrames
from vidcap.video.lifting import (
    NEAR_PLANE,
    SCALE_WINDOW_S,
    VIEWS,
    LiftResult,
    apply_user_view,
    check_view,
    constrain_orientation,
    fill_gaps,
    frame_scales,
    lift_pose,
    model_scales,
    plane_passages,
    swap_pairs,
)
from vidcap.video.masks import MaskStack
from vidcap.video.motion import MotionResult, build_motion, keyframes_by_confidence
from vidcap.video.person import partly_outside, person_track
from vidcap.video.result import MIXED_VIEW, POOR_FIT, ConvertResult, frame_runs, true_runs
from vidcap.video.stagecache import StageCache, stage_key, video_identity
from vidcap.video.userregions import region_cache_part
from vidcap.video.vanishing import scene_k_for

#: Chunks per fitting process in ``run``: the fit of each chunk starts as soon as its
#: silhouettes are out, so shorter chunks leave less of the fit to wait for after the
#: last frame is extracted (each chunk after the first costs ``overlap`` extra frames).
_CHUNKS_PER_JOB = 2
#: The processes ``run`` plans the 2D fit's chunks for, whatever its ``jobs``
#: (:func:`vidcap.video.fit.parallel.chunk_bounds`): a tracked chunk's fit depends on
#: where the chunk starts, so chunks planned by ``jobs`` gave another fit on one process
#: than on two (frames differed on 1 % of a 300-frame walk with the outline, on 34 % with
#: the cues: a side view's arms named the other way round from a chunk on). Planned
#: alike, one process fits the same chunks one after another (the same result); more
#: than ``_PLAN_JOBS * _CHUNKS_PER_JOB`` processes leave the extra ones idle in the fit.
_PLAN_JOBS = 2

#: The fit's cues by default (``run``'s ``cues``; ``vidcap convert --cues``).
DEFAULT_CUES = "outline"
#: The body's proportions by default (``run``'s ``proportions``; ``vidcap convert`` and
#: ``vidcap pose2d --proportions``): a real adult's (an anthropometric table's, the
#: ankles above the soles). On real footage it is nearer MediaPipe's joints than the
#: seed's Table 3.1/3.2 body in 9 of 10 clips, and on renders each body is fitted best
#: with its own proportions (``benchmarks/RESULTS.md``, "the default body"); ``'seed'``
#: keeps the seed's.
DEFAULT_PROPORTIONS = "human"


#: Bumped when the silhouette stage's results change for the same video and options
#: (2: no shadow test on grey video; 3: the person followed, not the largest blob; 5: the
#: graph cut keeps the plain person's pieces and blobs, ``graphcut.keep_pieces``,
#: ``silhouette._person_parts``), so caches written by older versions are redone.
_SILHOUETTE_VERSION = 5
#: Bumped when the estimated plate changes (issue 26: self-lit pixels, still parts; 3:
#: absorbed parts no sample uncovers flagged never seen, ``absorbed.flag_unseen``; 4: scene
#: colours round the footprint, ``regionvote.SCENE_RING``; 5: the scene where a person
#: came, stood and went, ``stayed.retake_stayed``; 6: a plate colour no steady stretch
#: shows gives way to one that stayed, ``steadyscene.UNSTEADY_PLATE``; 7: a guessed
#: plate colour no sample shows gives way to the one most samples show,
#: ``platepass.MODE_RETAKE``; 8: a person who held one pose, found by the person box
#: when the samples' first-pass silhouettes are nearly empty, ``heldpose.HELD_POSE``; 9:
#: a footprint hole the moving body does not touch in every sample is scene,
#: ``regionvote.MIN_ATTACHED``; 10: a lamp a person crosses still found self-lit,
#: ``stillparts.self_lit``; 11: ``heldpose.MAX_SHOWN``; 12: the person box searched for
#: in frames under 240 rows enlarged, ``personbox.ENLARGE_BELOW``, and a second, side-on
#: people detector, ``personbox.SECOND_DETECTOR``; 13: ``personbox.STILL_CORE``,
#: ``appearance.SURE_MARGIN_PX``).
_PLATE_VERSION = 13
#: Bumped when the 2D fit's results change (1: a tracked frame never ends below the
#: previous pose, ``fit.frame.kept_or_better``; 2: a tracked body bending or crouching
#: follows the bend, ``fit.bend``), so a cache written by an older fit is redone rather
#: than handed back as the new fit's. (``--seated`` fits are keyed apart by
#: :func:`_pose_key`; the default fit did not change with them.)
_POSE_VERSION = 3

#: The silhouettes' graph cut (:mod:`vidcap.video.graphcut`) by default (``run``'s
#: ``graph_cut``; ``vidcap convert --graph-cut / --no-graph-cut``). On: it decides only
#: frames whose colour models tell the person from the scene
#: (:data:`vidcap.video.graphcut.SCENE_KEPT_MIN`), so no real clip with true or MediaPipe
#: masks loses more than 0.01 median IoU, and the in-place renders gain (15 of 17 at
#: >= 0.92, 11 plain). Through the 2D fit and the solve it is level once the pieces and
#: blobs it split off the plain person are kept (``graphcut.keep_pieces``,
#: ``silhouette._person_parts``), measured as the mean over perturbed runs
#: (benchmarks/cut_fit.py): a single run's figures on the samples and ido_walk swing
#: with a dozen pixels a frame (walk_side's PA-MPJPE 160 mm on the plain masks, 204 on
#: the cut's and on the true masks), which made the cut look worse (RESULTS.md,
#: Silhouettes).
DEFAULT_GRAPH_CUT = True


def default_still_person() -> bool:
    """The still-person passes of the plate by default (``run``'s ``still_person``;
    ``vidcap convert --still-person / --no-still-person``): on when both
    :data:`vidcap.video.background.EMPTY_SCENE` and
    :data:`vidcap.video.background.PERSON_BOX` are (read at call time)."""
    from vidcap.video import background

    return bool(background.EMPTY_SCENE and background.PERSON_BOX)


def run(
    video: str | os.PathLike,
    *,
    annotations: str | os.PathLike | Annotations | None = None,
    background: str | os.PathLike | None = None,
    height: float = 1.75, smooth_sigma: float = 1.0, keyframe_score: float | None = None,
    cache_dir: str | os.PathLike | None = None, progress: bool | None = None, log=None,
    jobs: int | None = None, view: str = "auto",
    lift: str = "solve", proportions: str = DEFAULT_PROPORTIONS, cues: str = DEFAULT_CUES,
    graph_cut: bool | None = None, still_person: bool | None = None,
    hidden: str = DEFAULT_HIDDEN, ensemble: int = 1,
    camera: tuple[float, ...] | str | None = None, seated: bool = False,
) -> ConvertResult:
    """Run the whole video path on ``video``.

    Parameters
    ----------
    video : str or path-like
    annotations : path or Annotations, optional
        Default: ``VIDEO_STEM.vidcap.json`` beside the video when it exists.
    background : path or str, optional
        An image of the empty scene or ``'START:END'`` (frames showing it); default: estimated.
    height : float
        Subject's height in metres.
    smooth_sigma : float
        Gaussian smoothing of the motion in frames (0 = none).
    keyframe_score : float, optional
        Key only the frames whose 2D fit similarity is at least this (and enough to leave
        no gap over 10 frames), Slerp between (seed 004 3.1.5); default: every frame.
    cache_dir : path, optional
        Stage cache folder (None = no caching).
    progress : bool, optional
        Progress bars (default: when stderr is a terminal).
    log : callable, optional
        Called with one-line status messages.
    jobs : int, optional
        Worker processes for the 2D fit (default: the usable CPUs, at most ``MAX_JOBS``; 1
        or under 120 frames: here, :mod:`vidcap.video.fit.parallel`), started while the
        silhouettes are extracted; 2 or more also solve a long clip's 3D in two
        halves at once (:mod:`vidcap.video.solve.split`).
    view : str
        How the camera sees the subject for the whole clip (:data:`~vidcap.video.lifting.VIEWS`;
        ``auto``: proposed per frame; :func:`~vidcap.video.lifting.constrain_orientation`).
    lift : {'solve', 'segment'}
        One kinematic solve over the clip (:mod:`vidcap.video.solve`) or the seed's lift.
    proportions : {'human', 'seed', 'auto'}
        A real adult's (:data:`DEFAULT_PROPORTIONS`), the seed's, the subject's (``_fit_stage``).
    cues : {'outline', 'all'}
        The 2D fit reads the silhouette only, or the frame's cues inside it too.
    graph_cut, still_person : bool, optional
        The silhouettes' graph cut (:mod:`vidcap.video.graphcut`) and the plate's
        still-person passes: see :func:`_graph_cut_option`, :func:`_still_person_option`.
    hidden : {'fit', 'solve'}
        The 2D joints as fitted, or with the shoulders, hips and arms the torso hides
        from the 3D (:func:`vidcap.video.hidden.fill_hidden`; ``lift='solve'``).
    ensemble : int
        Fits joined per joint (:func:`vidcap.video.fit.ensemble.fit_ensemble`, 1 to 5).
    camera : (height m, distance m[, pitch deg]) or 'auto', optional
        Where it stands (:mod:`vidcap.video.fitbody`), or read (:mod:`vidcap.video.vanishing`).
    seated : bool
        The body's scale probed where it sits for seconds (:mod:`vidcap.video.fit.lowbody`).

    Returns
    -------
    ConvertResult
    """
    from vidcap.io.video import frame_times, probe
    from vidcap.video.background import load_plate
    from vidcap.video.fit.parallel import default_jobs

    log = log or (lambda msg: None)
    ensemble, k = _check_options(view, lift, proportions, cues, hidden, ensemble,  # before
                                 camera, height)  # any work; k: the camera's perspective
    video, body, timings = Path(video), BodyModel(height=height), {}
    info, cache = probe(video), StageCache(cache_dir, log=log)
    ann, ann_source = _load_annotations(annotations, video, log, (info.width, info.height))

    # a given plate is read first: a bad file is reported before any worker starts
    with _timed(timings, "plate"):
        plate = load_plate(background, video) if background is not None else None
    graph_cut, still, k_plate, k_sil = _stage_keys(video, background, ann, graph_cut, log,
                                                   still_person)
    jobs = default_jobs() if jobs is None else max(1, int(jobs))
    plan, per_job = _PLAN_JOBS, _CHUNKS_PER_JOB  # the chunks alike for any jobs
    fit_kw = fit_keywords_for(proportions, ensemble, k, seated)
    pool = _start_fit_workers(cache, k_sil, info.n_frames, plan, per_job, cues, fit_kw, jobs,
                              stream=camera != "auto")  # auto: the fit waits for the scene's k
    # the pool is closed after the fit; on an error or Ctrl-C its running chunks are
    # nobody's, and it is killed (FitPool.__exit__)
    with pool if pool is not None else nullcontext():
        with _timed(timings, "plate"):
            plate = _plate_stage(cache, k_plate, video, plate, progress=progress, log=log,
                                 colour_models=graph_cut, still_person=still, notice=True)
        with _timed(timings, "silhouettes"):
            streamed, crops = _streamed_fit(pool, info.n_frames, plan, per_job, cues, fit_kw)
            sil = _silhouette_stage(cache, k_sil, video, plate, streamed=streamed, crops=crops,
                                    progress=progress, regions=_regions(ann, plate),
                                    graph_cut=graph_cut, log=log, n_frames=info.n_frames)
        _report_silhouettes(sil, info.n_frames, log)
        k = scene_k_for(camera, k, plate.plate, sil.masks, log)
        pose, body, estimate = _fit_stage(cache, k_sil, sil.masks, body, proportions, jobs=plan,
                                          per_job=per_job, streamed=streamed, log=log, workers=jobs,
                                          progress=progress, timings=timings, perspective=k,
                                          cues=(cues, crops, video), ensemble=ensemble,
                                          seated=seated)

    with _timed(timings, "lift+motion"):
        out = _lift_and_motion(pose, sil, fps=info.fps, frame_size=(info.width, info.height),
                               body=body, annotations=ann, ann_source=ann_source, view=view,
                               smooth_sigma=smooth_sigma, keyframe_score=keyframe_score,
                               log=log, lift_method=lift, video=video, hidden=hidden,
                               jobs=jobs, perspective=(k, ankle_share(estimate)))
    return ConvertResult(
        video=str(video), fps=info.fps, masks=sil.masks, bbox=np.asarray(sil.bbox),
        scores=pose["scores"], similarity=pose["similarity"], lifted=out.lifted,
        motion=out.motion.motion, jitter_before=out.motion.jitter_before, timings=timings,
        jitter_after=out.motion.jitter_after, image_joints2d=out.joints2d, track=out.track,
        spread=pose["spread"], model_height=out.model_height, outside=out.outside, view=view,
        frame_times=frame_times(video), body=body, proportions=estimate,
        plate_estimated=background is None, perspective=(k, ankle_share(estimate)))


# --------------------------------------------------------------------------- helpers
def _check_choice(name: str, value: str, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ValueError(f"unknown {name} {value!r}; expected "
                         + " or ".join(repr(c) for c in choices))


def _fit_stage(cache, k_sil, masks, body, proportions: str, *, jobs, per_job, streamed,
               progress, timings, log, cues=(DEFAULT_CUES, None, None), workers=None,
               ensemble: int = 1, perspective: float = 0.0, seated: bool = False):
    """The 2D pose (:func:`_pose_stage`) fitted with the body's proportions: the seed's,
    a real adult's (``'human'``, :func:`vidcap.video.fit.proportions.human_proportions`,
    one fit with them), or with ``'auto'`` the subject's own estimated from a first fit
    with the seed's and the clip fitted again with them
    (:func:`vidcap.video.bodystage.proportions_stage`, the outline only): the 3D lift
    and the motion's skeleton then use them, ``body``'s height still the standing
    height. Returns (pose, body, estimate or None). ``cues``: ``(cues, crops, video)``
    of :func:`_pose_stage`; ``jobs`` and ``per_job`` plan the chunks, ``workers``
    (default ``jobs``) fit them; ``ensemble``: fits joined per chunk (:func:`fit_keywords_for`).
    ``perspective``: the camera's k; the fit draws the body warped by it, and the
    estimate, measured on the image, is un-warped for the 3D lift.
    """
    with _timed(timings, "pose2d"):
        pose = _pose_stage(cache, k_sil, masks, jobs=jobs, per_job=per_job,
                           streamed=streamed, progress=progress, cues=cues[0],
                           crops=cues[1], video=cues[2], workers=workers,
                           fit_kw=fit_keywords_for(proportions, ensemble, perspective, seated))
    if proportions == "seed":
        return pose, body, None
    from vidcap.video.fit.proportions import human_proportions

    if proportions == "human":
        estimate = human_proportions()
    else:
        from vidcap.video.bodystage import proportions_stage

        with _timed(timings, "proportions"):
            pose, estimate = proportions_stage(cache, k_sil, masks, jobs=jobs,
                                               per_job=per_job, progress=progress,
                                               workers=workers, ensemble=ensemble,
                                               seated=seated)
        estimate = unwarped_estimate(estimate, perspective)
    log(estimate.summary())
    return pose, estimate.body(body.height), estimate


def _check_options(view: str, lift: str, proportions: str, cues: str,
                   hidden: str = DEFAULT_HIDDEN, ensemble: int = 1, camera=None,
                   height: float = 1.75) -> tuple[int, float]:
    """ValueError for an option ``run`` cannot take; returns ``ensemble`` as an int and
    the ``camera``'s perspective k for a subject ``height`` metres tall."""
    check_view(view)
    _check_choice("lift", lift, ("solve", "segment"))
    from vidcap.video.fit.cues import CUE_MODES
    from vidcap.video.fit.proportions import PROPORTION_CHOICES

    _check_choice("proportions", proportions, PROPORTION_CHOICES)
    _check_choice("cues", cues, tuple(CUE_MODES))
    check_hidden(hidden)
    from vidcap.video.fit.ensemble import member_count

    # 'auto': k is read from the scene once the silhouettes exist (vidcap.video.vanishing)
    k = 0.0 if camera == "auto" else camera_perspective(camera, height)
    return member_count(ensemble), k


def _streamed_fit(pool, n_frames: int | None, jobs: int, per_job: int, cues: str,
                  fit_kw: dict | None = None):
    """The :class:`vidcap.video.fit.parallel.StreamedFit` that fits each chunk of frames as
    soon as its silhouettes are there (None without ``pool``), and the
    :class:`vidcap.video.fit.cueframes.FrameCrops` to fill with the colour crops the cues
    read as the silhouettes are extracted (None for ``cues='outline'``). ``fit_kw``: the
    fit's body and ensemble (:func:`fit_keywords_for`); ``n_frames`` None: 0 (not known)."""
    from vidcap.video.fit.cueframes import FrameCrops
    from vidcap.video.fit.parallel import StreamedFit

    streamed = (None if pool is None
                else StreamedFit(pool, n_frames or 0, jobs=jobs, per_job=per_job, cues=cues,
                                 **(fit_kw or {})))
    return streamed, (FrameCrops() if cues == "all" else None)


@contextmanager
def _timed(timings: dict, name: str):
    """Add the seconds the ``with`` block takes to ``timings[name]``."""
    t0 = time.perf_counter()
    try:
        yield
    finally:
        timings[name] = timings.get(name, 0.0) + time.perf_counter() - t0


def _load_annotations(annotations, video: Path, log,
                      frame_size) -> tuple[Annotations, object]:
    """The user's events (given, a file, or ``VIDEO_STEM.vidcap.json`` beside the
    video when it exists) and the file named in errors about them; a region beyond the
    ``frame_size`` (width, height) is refused here, before any work."""
    if annotations is None and default_path(video).exists():
        annotations = default_path(video)
    source = video
    if isinstance(annotations, (str, os.PathLike)):
        log(f"annotations: {annotations}")
        source = annotations
        annotations = Annotations.load(annotations)  # frames are checked once decoded
    annotations = annotations or Annotations()
    annotations.check_frame_size(*frame_size, source)
    return annotations, source


def _check_events(ann: Annotations, n_frames: int, source) -> None:
    late = [e for e in ann.events if e.frame >= n_frames]
    if late:
        e = late[0]
        raise AnnotationError(
            f"{e.type} event at frame {e.frame} is beyond the video's {n_frames} frames "
            f"(frames count from 0)", source)


def _start_fit_workers(cache: StageCache, k_sil: str, n_frames: int | None, jobs: int,
                       per_job: int, cues: str = DEFAULT_CUES, fit_kw: dict | None = None,
                       workers: int | None = None, *, stream: bool = True):
    """The 2D fit's worker processes (a :class:`vidcap.video.fit.parallel.FitPool`), started
    first so that they load their compiled kernels while this process estimates the
    plate and extracts the silhouettes; None when the fit is one chunk, on one process
    (``workers``, default ``jobs``; the chunks planned for ``jobs`` are then fitted here)
    or cached, or not to ``stream`` (the body the fit draws is known only after the
    silhouettes). ``fit_kw``: the fit's body and ensemble (:func:`fit_keywords_for`)."""
    from vidcap.video.fit.parallel import FitPool, chunk_bounds

    expected = chunk_bounds(n_frames or 0, jobs, per_job=per_job)
    workers = jobs if workers is None else workers
    if len(expected) < 2 or workers < 2 or not stream:
        return None
    pose_path = cache.path("pose2d", _pose_key(k_sil, expected, cues, fit_kw))
    if pose_path and pose_path.exists():
        return None
    # the silhouettes need numba here anyway: loaded before the fork, the workers'
    # zygote inherits numba's import and LLVM's start-up (~0.25 s less CPU on 2 cores)
    from vidcap.video.silhouette import load_kernels

    load_kernels()
    return FitPool(min(workers, len(expected)))


# --------------------------------------------------------------------------- 1. plate
def _plate_key(video_id: dict, background, colour_models: bool = False,
               still_person: bool = False) -> str:
    if background is not None:  # an image, or frames of the video (emptyframes)
        return stage_key("plate-file", *given_plate_identity(background, video_id))
    # the colour models and the still-person passes join the key only when asked for:
    # entries without them stay valid
    extra = (("colours",) if colour_models else ()) + (
        ("still-person",) if still_person else ())
    return stage_key("plate", _PLATE_VERSION, video_id, *extra)


def _stage_keys(video: Path, background, ann: Annotations, graph_cut: bool | None, log,
                still_person: bool | None = None):
    """``(graph_cut, still_person, plate key, silhouette key)``: whether the cut runs
    (:func:`_graph_cut_option`), whether the plate's still-person passes do
    (:func:`_still_person_option`) and the keys of the two image stages."""
    ident = video_identity(video)
    graph_cut = _graph_cut_option(graph_cut, background, log)
    still = _still_person_option(still_person, background, log)
    k_plate = _plate_key(ident, background, graph_cut, still)
    return graph_cut, still, k_plate, _silhouette_key(ident, k_plate, region_cache_part(ann),
                                                      graph_cut)


def _still_person_option(still_person: bool | None, background, log) -> bool:
    """Whether the plate stage runs the still-person passes: ``still_person``, or
    :func:`default_still_person` when None; never with a given ``background`` plate
    (nothing is estimated; a notice through ``log`` when they were asked for)."""
    use = default_still_person() if still_person is None else bool(still_person)
    if use and background is not None:
        if still_person:
            log("notice: --still-person works on the estimated plate, not a given one: "
                "the given plate is used as it is")
        use = False
    return use


def _graph_cut_option(graph_cut: bool | None, background, log) -> bool:
    """Whether the silhouette stage runs the graph cut: ``graph_cut``, or
    :data:`DEFAULT_GRAPH_CUT` when None; never with a given ``background`` plate (it has
    no colour models: the plain threshold decides, with a notice through ``log`` when the
    cut was asked for explicitly)."""
    use = DEFAULT_GRAPH_CUT if graph_cut is None else bool(graph_cut)
    if use and background is not None:
        if graph_cut:
            log("notice: the graph cut needs the estimated plate (its colour models), not "
                "a given one: the plain threshold decides")
        use = False
    return use


def _plate_stage(cache: StageCache, key: str, video: Path, plate, *, progress, log,
                 colour_models: bool = False, still_person: bool = False,
                 notice: bool = False):
    """The background plate (:class:`vidcap.video.background.BackgroundModel`): ``plate``
    when the user gave one, else the cached one, else estimated from the video (with
    the clip's colour models for the graph cut when ``colour_models``, with the
    still-person passes when ``still_person``; ``key`` must say so, :func:`_plate_key`).
    ``notice``: log the plate's notice (:func:`vidcap.video.inputchecks.plate_notice`),
    if any."""
    plate = _plate_of(cache, key, video, plate, progress=progress, log=log,
                      colour_models=colour_models, still_person=still_person)
    if notice:
        from vidcap.video.inputchecks import plate_notice

        if plate_notice(plate):
            log(plate_notice(plate))
    return plate


def _plate_of(cache: StageCache, key: str, video: Path, plate, *, progress, log,
              colour_models: bool, still_person: bool = False):
    from vidcap.video.background import estimate_plate

    if plate is not None:
        return plate
    required = _PLATE_FIELDS + (("colours",) if colour_models else ())
    hit = cache.load("plate", key, required=required)
    if hit is not None:
        return _plate_from_cache(hit)
    log("estimating the background plate")
    plate = estimate_plate(video, colour_models=colour_models, still_person=still_person,
                           progress=progress)
    h, w = plate.plate.shape[:2]
    # (no colour models: an empty array, read back as None)
    extra = ({"colours": np.zeros(0, np.float32) if plate.colours is None else plate.colours}
             if colour_models else {})
    cache.save("plate", key, plate=plate.plate, never_seen=plate.never_seen,
               noise_map=plate.noise_map, noise_sigma=plate.noise_sigma,
               threshold=np.float64(plate.threshold),
               self_lit=np.zeros((h, w), bool) if plate.self_lit is None else plate.self_lit,
               still_person=(np.zeros((h, w), bool) if plate.still_person is None
                             else plate.still_person),
               # the still parts' own colour (the plate is inpainted there)
               person_plate=(np.zeros(0, np.uint8) if plate.person_plate is None
                             else plate.person_plate), **extra)
    return plate


#: What a cached plate holds besides the image: the silhouette stage needs them all.
_PLATE_FIELDS = ("plate", "never_seen", "noise_map", "noise_sigma", "threshold", "self_lit",
                 "still_person", "person_plate")


def _plate_from_cache(hit: dict):
    from vidcap.video.background import BackgroundModel

    never = hit["never_seen"].astype(bool)
    return BackgroundModel(
        plate=hit["plate"], confidence=(~never).astype(np.float32), never_seen=never,
        noise_sigma=hit["noise_sigma"], noise_map=hit["noise_map"],
        threshold=float(hit["threshold"]), method="felzenszwalb",
        self_lit=hit["self_lit"].astype(bool) if hit["self_lit"].any() else None,
        still_person=(hit["still_person"].astype(bool) if hit["still_person"].any()
                      else None),
        person_plate=hit["person_plate"] if hit["person_plate"].size else None,
        colours=hit["colours"] if "colours" in hit and hit["colours"].size else None)


# --------------------------------------------------------------------------- 2. silhouettes
@dataclass(frozen=True)
class _Silhouettes:
    """The silhouette stage's output: ``masks`` (F frames, original pixels), ``bbox``
    (F, 4) ``x0, y0, x1, y1`` px of the followed person, ``n_other`` (F,) other
    person-sized blobs per frame."""

    masks: MaskStack
    bbox: np.ndarray
    n_other: np.ndarray
    kept: KeptFrames | None = None  # the colour round the person, when extracted here


def _silhouette_key(video_id: dict, k_plate: str, regions: list | None = None,
                    graph_cut: bool = False) -> str:
    # the user's regions join the key only when there are some: the entries of clips
    # without any stay valid, and no other event ever touches it (the graph cut alike)
    extra = ((regions,) if regions else ()) + (("graph-cut",) if graph_cut else ())
    return stage_key("silhouettes", _SILHOUETTE_VERSION, video_id, k_plate, *extra)


def _regions(ann: Annotations, plate):
    """The user's regions (:class:`vidcap.video.userregions.UserRegions`), None if none."""
    from vidcap.video.userregions import UserRegions

    regions = UserRegions(ann, plate.plate.shape[:2])
    return regions if regions else None


class _Both:
    """Two keepers of the extraction's colour frames (``append(frame, box)``) as one."""

    def __init__(self, first, second):
        self.first, self.second = first, second

    def append(self, frame, box) -> None:
        self.first.append(frame, box)
        self.second.append(frame, box)


class _MaskFeed:
    """``on_masks`` of :func:`vidcap.video.silhouette.extract_silhouettes`: gathers the chunks
    of silhouettes so far and hands them to the streamed 2D fit."""

    def __init__(self, streamed, crops=None):
        self.streamed = streamed
        self.so_far = None  # MaskStack of the frames so far
        self.crops = crops  # FrameCrops of the frames so far (filled by the extraction)

    def __call__(self, _start, chunk_masks) -> None:
        if self.so_far is None:
            self.so_far = MaskStack(chunk_masks.frame_shape)
        self.so_far.extend(chunk_masks)
        self.streamed.feed(self.so_far, self.crops)


def _silhouette_stage(cache: StageCache, key: str, video: Path, plate, *, streamed,
                      progress, regions=None, on_masks=None, crops=None,
                      graph_cut: bool = False, log=None,
                      n_frames: int | None = None) -> _Silhouettes:
    """The person's silhouettes, cached or extracted; while they are extracted, each
    chunk of frames goes to ``streamed`` (a :class:`vidcap.video.fit.parallel.StreamedFit`,
    or None) as soon as it is complete, or to ``on_masks`` (as ``on_masks(start, masks)``
    of :func:`vidcap.video.silhouette.extract_silhouettes`). ``regions``: the user's
    (:class:`vidcap.video.userregions.UserRegions`), which ``key`` must include.
    ``crops``: a :class:`vidcap.video.fit.cueframes.FrameCrops` filled with each frame's
    colour crop (None: none; left empty when the silhouettes come from the cache).
    Extracted, the stage keeps the colour round the person for the 3D stage's cues
    (:class:`vidcap.video.keptframes.KeptFrames`, as ``kept``; ``n_frames``: the
    frames expected, if known, to tell early that they will not fit). ``graph_cut``:
    the band's graph cut, on ``plate``'s colour models (none: the clip's samples showed
    too little of the person; the plain threshold decides, with a notice through
    ``log``)."""
    from vidcap.video.silhouette import extract_silhouettes

    # entries written before the masks were stored cropped lack mask_boxes: extract again
    hit = cache.load("silhouettes", key, required=("mask_boxes",))
    if hit is not None:
        masks = MaskStack.from_arrays(hit["mask_shape"], hit["mask_boxes"],
                                      hit["mask_bits"], hit["mask_sizes"])
        n_other = hit["n_other"] if "n_other" in hit else np.zeros(len(masks), np.int64)
        return _Silhouettes(masks, hit["bbox"], n_other)
    if streamed is not None:
        on_masks = _MaskFeed(streamed, crops)
    if graph_cut and getattr(plate, "colours", None) is None:
        (log or (lambda msg: None))(
            "notice: the graph cut is skipped: the plate's samples show too little of the "
            "person to learn their colours")
        graph_cut = False
    kept = KeptFrames(n_frames=n_frames) if FRONT_CUE or LIMB_CUE else None
    keep = crops if kept is None else kept if crops is None else _Both(crops, kept)
    sil = extract_silhouettes(video, plate, progress=progress, on_masks=on_masks,
                              regions=regions, crops=keep, graph_cut=graph_cut)
    out = _Silhouettes(sil.masks, sil.bbox, sil.n_other_blobs, kept)
    cache.save("silhouettes", key, bbox=out.bbox, n_other=out.n_other, **out.masks.to_arrays())
    return out


def silhouettes_only(video: str | os.PathLike, annotations: Annotations, *,
                     cache_dir: str | os.PathLike | None = None, on_masks=None,
                     log=None, graph_cut: bool | None = None,
                     still_person: bool | None = None) -> _Silhouettes:
    """The first two stages of :func:`run` only (plate, silhouettes with the user's
    regions), cached as :func:`run` caches them: what the annotate page redoes when
    the user draws a region.

    Parameters
    ----------
    video : str or path-like
    annotations : Annotations
        Only the region events count (:mod:`vidcap.video.userregions`).
    cache_dir : path, optional
        The stage cache (None = no caching).
    on_masks : callable, optional
        ``on_masks(start, masks)`` after each chunk of frames (progress).
    log : callable, optional
    graph_cut : bool, optional
        As :func:`run`'s (default :data:`DEFAULT_GRAPH_CUT`).
    still_person : bool, optional
        As :func:`run`'s (default :func:`default_still_person`).

    Returns
    -------
    object
        ``masks`` (:class:`vidcap.video.masks.MaskStack`), ``bbox`` (F, 4) and
        ``n_other`` (F,), as the silhouette stage gives them.
    """
    from vidcap.io.video import probe

    log = log or (lambda msg: None)
    video = Path(video)
    info = probe(video)
    annotations.check_frame_size(info.width, info.height, video)
    cache = StageCache(cache_dir, log=log)
    ident = video_identity(video)
    graph_cut = DEFAULT_GRAPH_CUT if graph_cut is None else bool(graph_cut)
    still = _still_person_option(still_person, None, log)
    k_plate = _plate_key(ident, None, graph_cut, still)
    plate = _plate_stage(cache, k_plate, video, None, progress=False, log=log,
                         colour_models=graph_cut, still_person=still)
    key = _silhouette_key(ident, k_plate, region_cache_part(annotations), graph_cut)
    return _silhouette_stage(cache, key, video, plate, streamed=None, progress=False,
                             regions=_regions(annotations, plate), on_masks=on_masks,
                             graph_cut=graph_cut, log=log)


def _report_silhouettes(sil: _Silhouettes, n_expected: int | None, log) -> None:
    """Tell the user of other people in view and of a frame count the container got wrong."""
    masks, n_other = sil.masks, sil.n_other
    crowded = int(np.count_nonzero(n_other))
    if crowded >= max(3, 0.05 * len(masks)):
        # vidcap follows one person: say so rather than silently mixing people (an
        # extra blob in a frame or two is a plate artefact, not a person, and is not
        # told)
        log(f"more than one person-sized blob in {crowded} of {len(masks)} frames "
            f"(up to {int(n_other.max()) + 1} at once); one is followed from frame to frame "
            "(the largest at first)")
    if len(masks) != n_expected and n_expected:
        log(f"decoded {len(masks)} frames (container says {n_expected})")


# --------------------------------------------------------------------------- 3. 2D pose
def _pose_key(k_sil: str, chunks, cues: str = DEFAULT_CUES, fit_kw: dict | None = None) -> str:
    # chunked fits may differ from a serial one (rarely, see fit.parallel): keyed apart
    parts = ("pose2d", _POSE_VERSION, k_sil) if len(chunks) < 2 else (
        "pose2d", _POSE_VERSION, k_sil, chunks)
    fit_kw = fit_kw or {}
    if fit_kw.get("body") is not None:  # a body other than the seed's (the seed's keeps its key)
        body = fit_kw["body"]
        parts += (f"body={body.segment_lengths().round(6).tolist()}"
                  f"{body.segment_radii().round(6).tolist()}", f"foot={fit_kw.get('foot', 0):.6f}")
        if body.shoulder_drop:  # (a body without one keeps the key it had before)
            parts += (f"shoulder_drop={body.shoulder_drop / body.height:.6f}",)
    if fit_kw.get("ensemble", 1) != 1:  # one fit keeps the key it had before ensembles
        parts += (f"ensemble={int(fit_kw['ensemble'])}",)
    if fit_kw.get("low_body"):
        parts += ("low_body",)
    return stage_key(*parts) if cues == "outline" else stage_key(*parts, f"cues={cues}")


def _pose_stage(cache: StageCache, k_sil: str, masks: MaskStack, *, jobs: int, per_job: int,
                streamed, progress, cues: str = DEFAULT_CUES, crops=None,
                video=None, fit_kw: dict | None = None, workers: int | None = None) -> dict:
    """The 2D pose, cached or fitted (by ``streamed`` when it was fed the silhouettes,
    else by :func:`vidcap.video.fit.parallel.fit_sequence_chunked`), with the colour
    frames' cues (``cues='all'``: ``crops``, filled while the silhouettes were
    extracted, else cut now from ``video``, decoded again) or the outline only.

    Returns
    -------
    dict
        ``joints2d`` (F, 15, 2) px, image-side limb names, NaN where no fit;
        ``scores`` and ``similarity`` (F,); ``spread`` (F,) torso foreshortening
        (0 side view, 1 front view); ``model_height`` (F,) px.
    """
    from vidcap.fileio import progress as bar
    from vidcap.video.fit.parallel import chunk_bounds, fit_sequence_chunked
    from vidcap.video.fit.proportions import to_ankles

    fit_kw = fit_kw or {}
    key = _pose_key(k_sil, chunk_bounds(len(masks), jobs, per_job=per_job), cues, fit_kw)
    # entries written before the model's height was kept lack it: fit again
    hit = cache.load("pose2d", key, required=("model_height",))
    if hit is not None:
        return hit

    def wrap(it, total):
        return bar(it, total=total, desc="2D pose", unit="frame", enabled=progress)

    frames = None
    if cues == "all":
        frames = crops if crops is not None and len(crops) == len(masks) else None
        if frames is None:  # the silhouettes came from the cache: cut the crops now
            frames = _colour_crops(video, masks, progress=progress)
    if streamed is not None:
        pose = streamed.finish(masks, frames=frames, progress=wrap)
    else:
        pose = fit_sequence_chunked(masks, jobs=jobs, progress=wrap, per_job=per_job,
                                    frames=frames, cues=cues, workers=workers, **fit_kw)
    # the model's height is head top to ankles: a body with feet leaves them out
    hit = {"joints2d": pose.joints2d, "scores": pose.scores, "spread": pose.spread,
           "similarity": pose.similarity,
           "model_height": to_ankles(pose.model_height, fit_kw)}
    cache.save("pose2d", key, **hit)
    return hit


def _colour_crops(video, masks: MaskStack, *, progress):
    """The colour crops (:class:`vidcap.video.fit.cueframes.FrameCrops`) of ``video``'s
    frames around ``masks`` (decoded again)."""
    from vidcap.fileio import progress as bar
    from vidcap.video.fit.cueframes import crops_from_video

    return crops_from_video(video, masks, progress=lambda it, total: bar(
        it, total=total, desc="colour", unit="frame", enabled=progress))


# --------------------------------------------------------------------------- 4. lift, 5. motion
@dataclass(frozen=True)
class _Lifted:
    """The 3D stage's and the motion's output, with the 2D joints they were read from."""

    lifted: LiftResult
    motion: MotionResult
    joints2d: np.ndarray  # (F, 15, 2) px, image-side names, NaN where left out
    model_height: np.ndarray  # (F,) px, NaN where left out
    outside: np.ndarray  # (F,) bool, the person mostly outside the picture
    track: np.ndarray | None  # (F,) px, horizontal centre of the person


def _image_joints(pose: dict, masks: MaskStack):
    """The 2D fit's joints and model heights with the frames where the person is mostly
    outside the picture left out (NaN: filled from the neighbouring frames, like frames
    without a fit), and those frames (F,) bool."""
    outside = partly_outside(masks)
    joints2d, model_height = pose["joints2d"], pose["model_height"]
    if outside.any():
        joints2d, model_height = joints2d.copy(), np.array(model_height, float)
        joints2d[outside] = np.nan
        model_height[outside] = np.nan
    return joints2d, model_height, outside


#: Whether the 3D stage reads front and back from the colour frames
#: (:mod:`vidcap.video.frontback`: which arm is in front of the body). On: on the tuning
#: renders and samples the share of frames solved facing the right way rose and
#: PA-MPJPE fell (benchmarks/HISTORY.md, issue 33, the front/back cue).
FRONT_CUE = True


#: Whether the front/back cue reads the face too (:mod:`vidcap.video.facecue`: a frontal
#: face found where the fit put the head says the body faces the camera, whatever the
#: arms say; no face says nothing).
FACE_CUE = True


#: Whether the 3D stage names the arms and legs by which one the colour frame shows
#: nearer the camera (:mod:`vidcap.video.legorder`: the nearer leg's borders cross the
#: farther one, the nearer arm's the torso).
LIMB_CUE = True


def colour_cues(frames, joints2d, model_height=None, body=None, *, front: bool | None = None,
                limbs: bool | None = None, lines=None, face: bool | None = None,
                fps: float | None = None):
    """The colour frames' cues in one pass over ``frames`` (an iterable of (H, W, 3) BGR
    frames, consumed to its end) for the image-side named 2D joints (F, 15, 2): the
    front/back cue (:func:`vidcap.video.frontback.near_side`, with ``front``, default
    :data:`FRONT_CUE`), (F,) or None, and the limb order
    (:func:`vidcap.video.legorder.near_limb`, with ``limbs``, default :data:`LIMB_CUE`,
    and the fit's ``model_height`` (F,) px), (F, 2) or None. ``lines``: the limb order's
    search lines, planned already (:func:`vidcap.video.legorder.plan_lines`). With
    ``face`` (default :data:`FACE_CUE`) the front/back cue is (F, 2): the near side and
    :func:`vidcap.video.facecue.face_seen` (one frame searched every
    :data:`vidcap.video.facecue.FACE_STEP_S` at ``fps``, default 30), as
    :func:`vidcap.video.proposals.propose_front` reads them."""
    from vidcap.video.facecue import tap_faces
    from vidcap.video.frontback import arm_visibility, near_side
    from vidcap.video.legorder import limb_radii, near_limb, tap_limb_edges

    front = FRONT_CUE if front is None else front
    limbs = LIMB_CUE if limbs is None else limbs
    face = (FACE_CUE if face is None else face) and front
    F = len(joints2d)
    strength, count = np.full((F, 2, 2), np.nan), np.zeros((F, 2, 2))
    if limbs and model_height is not None:
        frames = tap_limb_edges(frames, joints2d, limb_radii(model_height, body), strength,
                                count, lines)
    else:
        limbs = False
    seen = np.full(F, np.nan)
    if face:
        frames = tap_faces(frames, joints2d, seen, fps=fps or 30.0)
    frames = iter(frames)
    near = near_side(arm_visibility(frames, joints2d)) if front else None
    for _ in frames:  # the rest (all of them without the front cue)
        pass
    if face:
        near = np.column_stack([near, seen])
    return near, near_limb(strength, count) if limbs else None


def _kept_covers(kept, joints2d, model_height, body, fps: float = 30.0):
    """Whether ``kept`` (a :class:`vidcap.video.keptframes.KeptFrames`, or None) holds every
    pixel :func:`colour_cues` reads for the 2D joints (F, 15, 2): then the cues read it
    and give what a second decode would, to the bit. Returns (bool, the limb order's
    search lines planned for it or None: :func:`colour_cues` reads along them)."""
    from vidcap.video.facecue import read_bounds as face_bounds
    from vidcap.video.frontback import read_bounds as arm_bounds
    from vidcap.video.legorder import limb_radii, plan_lines
    from vidcap.video.legorder import read_bounds as limb_bounds

    F = len(joints2d)
    if kept is None or not kept.complete(F):
        return False, None
    if FRONT_CUE and not kept.covers(arm_bounds(joints2d, kept.frame_shape)):
        return False, None
    if FRONT_CUE and FACE_CUE and not kept.covers(face_bounds(joints2d, kept.frame_shape,
                                                              fps=fps)):
        return False, None
    if LIMB_CUE and model_height is not None:
        lines = plan_lines(joints2d, limb_radii(model_height, body), kept.frame_shape)
        return kept.covers(limb_bounds(lines)), lines
    return True, None


def front_cue(video, joints2d, fps: float | None = None) -> np.ndarray:
    """The front/back cue of ``video``'s frames (decoded again, one at a time) for
    the image-side named 2D joints (F, 15, 2): :func:`vidcap.video.frontback.near_side`
    (F,), with the face (F, 2) where :data:`FACE_CUE` (one frame searched every
    :data:`vidcap.video.facecue.FACE_STEP_S` at ``fps``, default 30), as
    :func:`colour_cues` reads them (``vidcap convert`` reads them with the limb order).

    Decoded again: ``vidcap convert`` reads the colour its silhouette stage kept round
    the person instead (:class:`vidcap.video.keptframes.KeptFrames`, up to a memory
    budget: a whole clip's colour is 0.2-1.4 GB for ten minutes at 30 fps), where this
    decode holds one frame at a time, for 0.3-0.45 s CPU per 300 frames (640x480 to
    960x540).
    """
    from vidcap.io.video import iter_frames

    return colour_cues(iter_frames(video, stop=len(joints2d)), joints2d, front=True,
                       limbs=False, fps=fps)[0]


def _lift_and_motion(pose: dict, sil: _Silhouettes, *, fps: float, frame_size, body,
                     annotations: Annotations, ann_source, view: str, smooth_sigma: float,
                     keyframe_score: float | None, log, lift_method: str = "solve",
                     video=None, hidden: str = DEFAULT_HIDDEN, jobs: int = 1,
                     perspective: tuple[float, float] = (0.0, 1.0)) -> _Lifted:
    """The 3D lift (:func:`vidcap.video.lifting.lift_pose`) with the user's events, then the
    motion (:func:`vidcap.video.motion.build_motion`), keyed on the best-fitting frames when
    ``keyframe_score`` is given. With ``video`` its frames are decoded again for the
    front/back cue and the limb order (:func:`colour_cues`), unless the silhouette
    stage kept all of them (``sil.kept``). ``hidden='solve'`` with the
    clip solve: the 2D joints with the ones the torso hides from it (:func:`_with_hidden`).
    ``jobs`` processes solve the clip (:mod:`vidcap.video.solve.split`). ``perspective``:
    the camera's k and the body's ankle height share; the 3D stage reads the fitted
    joints and the user's placed ones un-warped (:func:`vidcap.video.flatview.flat_view`),
    the colour cues and the returned image joints stay as fitted."""
    joints2d, model_height, outside = _image_joints(pose, sil.masks)
    track = person_track(sil.bbox, sil.masks, exclude=outside)
    _check_events(annotations, len(sil.masks), ann_source)
    near = limbs = None
    if video is not None and (FRONT_CUE or LIMB_CUE):
        from vidcap.io.video import iter_frames

        F = len(joints2d)
        kept = sil.kept
        covered, lines = _kept_covers(kept, joints2d, model_height, body, fps)
        frames = kept.frames(F) if covered else iter_frames(video, stop=F)
        near, limbs = colour_cues(frames, joints2d, model_height, body, lines=lines, fps=fps)
    flat2d, flat_height, flat_events = flat_view(joints2d, model_height, annotations, perspective)
    lifted = lift_pose(flat2d, fps=fps, body=body, annotations=flat_events,
                       image_sides=True, spread=pose["spread"], track=track,
                       frame_size=frame_size, model_height=flat_height, view=view,
                       method=lift_method, near_side=near, limb_order=limbs, jobs=jobs)
    keys = None
    if keyframe_score is not None:
        keys = keyframes_by_confidence(pose["similarity"], min_score=keyframe_score)
        log(f"{len(keys)} keyframes of {len(sil.masks)}")
    if lifted.solve_params is not None:  # the solve's rotations go to the BVH as they are
        from vidcap.video.solve.stage import solved_motion

        motion = solved_motion(lifted.solve_params, fps, body=body, keys=keys,
                               smooth_sigma=smooth_sigma)
    else:
        motion = build_motion(lifted.joints3d, fps, body=body, smooth_sigma=smooth_sigma,
                              keys=keys)
    out = _Lifted(lifted, motion, joints2d, model_height, outside, track)
    if hidden == "solve" and lift_method == "solve":
        return _with_hidden(out, perspective)
    return out


def _with_hidden(out: _Lifted, perspective: tuple[float, float] = (0.0, 1.0)) -> _Lifted:
    """``out`` with its 2D joints (the fit's image-side ones and the lift's body-side
    ones) taking the shoulders, the hips and the arms inside the torso's outline from
    the 3D (:func:`vidcap.video.hidden.fill_hidden`); the image-side ones filled
    un-warped and warped back for a camera's perspective ``(k, above_feet)``."""
    import dataclasses

    lifted = dataclasses.replace(out.lifted,
                                 joints2d=fill_hidden(out.lifted.joints2d, out.lifted.joints3d))
    flat2d, flat_height = unwarp_joints(out.joints2d, out.model_height, *perspective)
    image2d = warp_joints(fill_hidden(flat2d, out.lifted.joints3d), flat_height, *perspective)[0]
    return dataclasses.replace(out, lifted=lifted, joints2d=image2d)


# --------------------------------------------------------------------------- convert
def convert(
    video: str | os.PathLike,
    out_bvh: str | os.PathLike,
    *,
    save: str | os.PathLike | None = None,
    cache_dir: str | os.PathLike | None | bool = True,
    rig: str = "vidcap",
    **options,
) -> ConvertResult:
    """:func:`run` and write the motion (atomically) and optionally the ``--save`` npz.

    ``out_bvh`` ending in ``.glb``/``.gltf`` gives glTF 2.0, sampled at the video's own
    frame times; any other name gives BVH (:func:`vidcap.io.motionfile.write_motion`), on
    ``rig``'s joints. ``cache_dir=True`` puts the cache in ``.vidcap-cache`` beside
    ``out_bvh``; ``False``/``None`` disables it.
    """
    from vidcap.io.motionfile import write_motion
    from vidcap.io.rigs import get_rig

    get_rig(rig)  # an unknown rig fails before any work

    out_bvh = Path(out_bvh)
    if cache_dir is True:
        cache_dir = out_bvh.parent / ".vidcap-cache"
    elif cache_dir is False:
        cache_dir = None
    from vidcap.video.hugepages import small_pages

    with small_pages():  # (the video stages' large temporaries: vidcap.video.hugepages)
        result = run(video, cache_dir=cache_dir, **options)
    motion, times = result.motion_and_times(out_bvh)
    write_motion(out_bvh, motion, rig=rig, times=times)
    if save is not None:
        result.save_npz(save)
    return result



# the stages' names, defined in their own modules since issue 31 and imported from
# here by existing callers
__all__ = ["DEFAULT_GRAPH_CUT", "MIXED_VIEW", "NEAR_PLANE", "POOR_FIT", "SCALE_WINDOW_S",
           "VIEWS", "ConvertResult", "LiftResult", "StageCache", "apply_user_view",
           "constrain_orientation", "convert", "default_still_person",
           "fill_gaps", "frame_runs", "frame_scales", "lift_pose", "model_scales",
           "partly_outside", "person_track", "plane_passages", "run", "swap_pairs",
           "true_runs"]
