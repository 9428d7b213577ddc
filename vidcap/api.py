"""The Python entry points: :func:`convert` (a video) and :func:`joints` (a C3D trial).

They do what ``vidcap convert`` and ``vidcap joints`` do, return the results as arrays
and write files only when asked (``.save``). Errors a user can cause are the CLI's
:class:`vidcap.errors.VidcapError` subclasses (a bad file: ``InputFileError``; a bad
option: ``UsageError``).

>>> import vidcap                                           # doctest: +SKIP
>>> r = vidcap.convert("walk.mp4", height=1.80)             # doctest: +SKIP
>>> r.joints3d.shape, r.fps                                 # doctest: +SKIP
((42, 15, 3), 25.0)
>>> r.save("walk.glb", rig="mixamo")                        # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vidcap.errors import UsageError


def check_convert_options(*, height: float, jobs: int | None, view: str = "auto",
                          smooth: float = 1.0, keyframes: float | None = None,
                          cues: str = "outline", proportions: str = "human",
                          ensemble: int | str = 1) -> None:
    """Raise :class:`UsageError` for an option of ``convert`` that cannot work.

    Shared by :func:`convert` and ``vidcap convert``, so both refuse the same values.
    """
    from vidcap.video.lifting import VIEWS

    if not (height > 0):
        raise UsageError(f"--height must be positive metres, got {height}")
    if smooth < 0:
        raise UsageError(f"--smooth must not be negative, got {smooth}")
    if keyframes is not None and not 0.0 <= keyframes <= 1.0:
        raise UsageError(f"--keyframes is a fit similarity between 0 and 1, got {keyframes}")
    if jobs is not None and jobs < 1:
        raise UsageError(f"--jobs must be at least 1, got {jobs}")
    if view not in VIEWS:
        raise UsageError(f"unknown view {view!r}; use one of {', '.join(VIEWS)}")
    check_cues_option(cues)
    check_ensemble_option(ensemble)
    from vidcap.video.fit.proportions import PROPORTION_CHOICES

    if proportions not in PROPORTION_CHOICES:
        raise UsageError(f"unknown proportions {proportions!r}; use one of "
                         + ", ".join(PROPORTION_CHOICES))


def check_camera_option(camera, height: float = 1.75) -> tuple[float, ...] | str | None:
    """``camera`` (``--camera``'s text ``HEIGHT,DISTANCE[,PITCH]`` or ``auto``, or a tuple;
    None: no camera given) as :func:`vidcap.video.pipeline.run` takes it: a tuple of
    floats, or ``'auto'`` (the perspective read from the scene,
    :mod:`vidcap.video.vanishing`); :class:`UsageError` unless it is ``auto`` or two or
    three numbers of a camera that sees a subject ``height`` metres tall (a positive
    distance, a pitch within ±89 degrees)."""
    if camera is None:
        return None
    if isinstance(camera, str) and camera.strip().lower() == "auto":
        return "auto"
    from vidcap.video.fit.perspective import camera_perspective

    try:
        parts = camera.split(",") if isinstance(camera, str) else list(camera)
        values = tuple(float(p) for p in parts)
    except (TypeError, ValueError):
        values = ()
    if len(values) not in (2, 3):
        raise UsageError(f"--camera takes HEIGHT,DISTANCE[,PITCH] (metres, metres, degrees "
                         f"down) or auto, got {camera!r}")
    try:
        camera_perspective(values, height)
    except ValueError as exc:
        raise UsageError(f"--camera {','.join(f'{v:g}' for v in values)}: {exc}") from None
    return values


def check_cues_option(cues: str) -> None:
    """:class:`UsageError` unless ``cues`` is a ``--cues`` value
    (:data:`vidcap.video.fit.cues.CUE_MODES`)."""
    from vidcap.video.fit.cues import CUE_MODES

    if cues not in CUE_MODES:
        raise UsageError(f"unknown --cues {cues!r}; use one of {', '.join(CUE_MODES)}")


def check_ensemble_option(ensemble: int | str) -> int:
    """``ensemble`` (``--ensemble``'s text, or an int) as the number of fits
    (:func:`vidcap.video.fit.ensemble.fit_ensemble`); :class:`UsageError` unless it is a
    whole number from 1 to ``len(MEMBERS)``."""
    from vidcap.video.fit.ensemble import member_count

    try:
        return member_count(ensemble)
    except ValueError as exc:
        raise UsageError(f"--{exc}") from None


@dataclass(frozen=True)
class VideoMotion:
    """The motion :func:`convert` read from a video.

    Attributes
    ----------
    joints3d : numpy.ndarray, shape (F, 15, 3)
        World joint positions per video frame, metres, Y up, the body facing -Z in
        its rest pose: the written motion's joints (``--save``'s ``bvh_joints3d``).
    joint_names : tuple of str, length 15
        :data:`vidcap.body.JOINT_NAMES`.
    fps : float
        The video's frame rate.
    frame_times : numpy.ndarray, shape (F,)
        When each frame was shown, seconds from the first.
    notices : list of str
        What the CLI prints after converting (frames without a person, a poor fit,
        a variable frame rate...), one sentence each.
    result : vidcap.video.result.ConvertResult
        Everything the pipeline computed (masks, 2D joints, depth signs...).
    """

    joints3d: np.ndarray
    joint_names: tuple[str, ...]
    fps: float
    frame_times: np.ndarray
    notices: list[str]
    result: object = field(repr=False)

    def save(self, path: str | os.PathLike, *, rig: str = "vidcap") -> list[Path]:
        """Write the motion: glTF 2.0 for ``.glb``/``.gltf``, the ``--save`` arrays
        for ``.npz``, BVH otherwise.

        Parameters
        ----------
        path : str or path-like
        rig : {'vidcap', 'mixamo', 'humanik'}
            Joint names and hierarchy (:mod:`vidcap.io.rigs`); not for ``.npz``.

        Returns
        -------
        list of Path
            The files written (a ``.gltf`` brings its ``.bin``).
        """
        from vidcap.io.motionfile import output_files, write_motion
        from vidcap.outputguard import check_outputs

        check_outputs({"output": output_files(path)}, {"video": [self.result.video]})
        if Path(path).suffix.lower() == ".npz":
            self.result.save_npz(path)
            return [Path(path)]
        motion, times = self.result.motion_and_times(path)
        return write_motion(path, motion, rig=rig, times=times)


def convert(video: str | os.PathLike, *, annotations: str | os.PathLike | None = None,
            height: float = 1.75, view: str = "auto", jobs: int | None = None,
            progress: bool = False, cues: str | None = None,
            proportions: str | None = None,
            graph_cut: bool | None = None,
            still_person: bool | None = None, ensemble: int = 1,
            camera: tuple[float, ...] | str | None = None,
            seated: bool = False) -> VideoMotion:
    """3D motion of the one person in a single-camera video (``vidcap convert``).

    Parameters
    ----------
    video : str or path-like
        The video (static camera, one person).
    annotations : str or path-like, optional
        Depth/orientation/joint annotations (JSON); default ``VIDEO_STEM.vidcap.json``
        beside the video when it exists.
    height : float
        The subject's height, metres.
    view : str
        How the camera sees the subject (``"auto"``, ``"side"``, ``"front"``,
        ``"back"`` or one orientation; see ``vidcap convert --help``).
    jobs : int, optional
        Processes fitting the 2D pose (default: the CPUs, at most 8).
    progress : bool
        Show progress bars on stderr.
    cues : {'all', 'outline'}, optional
        What places the 2D model: the silhouette's outline and the colour frame's cues
        inside it (``'all'``: skin colour and edges place the arms), or the outline
        only (the seed); default :data:`vidcap.video.pipeline.DEFAULT_CUES`.
    proportions : {'human', 'seed', 'auto'}, optional
        The body fitted, lifted and written: a real adult's (``'human'``), the seed's
        Table 3.1/3.2 ratios, or the subject's estimated from the clip; default
        :data:`vidcap.video.pipeline.DEFAULT_PROPORTIONS`.
    graph_cut : bool, optional
        Re-decide a band round the person by a graph cut on the clip's colours
        (``vidcap convert --graph-cut``); default
        :data:`vidcap.video.pipeline.DEFAULT_GRAPH_CUT`.
    still_person : bool, optional
        The plate also from frames that show the empty scene, and a person who never
        moves looked for by a person detector (``vidcap convert --still-person``);
        default :func:`vidcap.video.pipeline.default_still_person`.
    ensemble : int
        The 2D fit on this many versions of the silhouettes changed by one pixel at the
        outline, joined per joint by the median (``vidcap convert --ensemble``, 1 to 5;
        :func:`vidcap.video.fit.ensemble.fit_ensemble`); costs that many fits.
    camera : (height, distance[, pitch]) or str, optional
        The camera's height above the floor and horizontal distance from the subject,
        metres, and its downward tilt, degrees (``vidcap convert --camera``; default
        aimed at the subject's middle): the 2D fit draws the body as such a camera's
        perspective images it (:mod:`vidcap.video.fit.perspective`); ``"auto"``: the
        perspective read from the scene's vertical lines and the person standing
        (:mod:`vidcap.video.vanishing`). Default: none.
    seated : bool
        The subject sits or crouches for seconds at a time (``vidcap convert --seated``):
        the 2D fit probes the body's scale there (:mod:`vidcap.video.fit.lowbody`).

    Returns
    -------
    VideoMotion
        ``joints3d`` (F, 15, 3) metres, ``joint_names``, ``fps``, ``frame_times``,
        ``notices``; ``.save(path, rig=...)`` writes BVH or glTF.

    Raises
    ------
    vidcap.errors.VideoError
        If the video cannot be decoded.
    vidcap.errors.AnnotationError
        If the annotations are malformed.
    vidcap.errors.UsageError
        If an option is invalid.
    """
    from vidcap.video.pipeline import DEFAULT_CUES, DEFAULT_PROPORTIONS, run

    cues = DEFAULT_CUES if cues is None else cues
    proportions = DEFAULT_PROPORTIONS if proportions is None else proportions
    check_convert_options(height=height, jobs=jobs, view=view, cues=cues,
                          proportions=proportions)
    res = run(video, annotations=annotations, height=height, view=view, jobs=jobs,
              progress=progress, cues=cues, proportions=proportions,
              graph_cut=graph_cut, still_person=still_person,
              ensemble=check_ensemble_option(ensemble),
              camera=check_camera_option(camera, height), seated=bool(seated))
    F = res.n_frames
    times = (np.arange(F) / res.fps if res.frame_times is None
             else np.asarray(res.frame_times, dtype=float))
    return VideoMotion(res.motion.positions(), tuple(res.motion.skeleton.joint_names),
                       float(res.fps), times, res.notices(), res)


@dataclass(frozen=True)
class JointCentres:
    """Joint centres :func:`joints` found in a marker trial.

    Attributes
    ----------
    centres : numpy.ndarray, shape (F, J, 3)
        Joint centres in the C3D's lab frame, metres, NaN where unknown (as
        ``--centres`` writes them).
    joint_names : tuple of str, length J
        As the marker set names them.
    fps : float
        The trial's frame rate.
    notices : list of str
        Markers the file lacks and joints whose fits are flagged, one sentence each.
    solution : vidcap.mocap.solution.JointSolution
        Everything the solve computed (segment frames, fit reports...).
    """

    centres: np.ndarray
    joint_names: tuple[str, ...]
    fps: float
    notices: list[str]
    solution: object = field(repr=False)
    inputs: tuple[str, ...] = field(default=(), repr=False)

    def save(self, path: str | os.PathLike, *, rig: str = "vidcap") -> list[Path]:
        """Write the skeleton's motion (Y up, T-pose rest): glTF 2.0 for ``.glb``/``.gltf``,
        BVH otherwise; ``rig`` as :meth:`VideoMotion.save` (``mixamo``/``humanik`` need
        a marker set with the body model's 15 joints). Returns the files written."""
        from vidcap.io.motionfile import output_files, write_motion
        from vidcap.mocap.skeleton import solution_to_motion
        from vidcap.outputguard import check_outputs

        check_outputs({"output": output_files(path)}, {"trial": list(self.inputs)})
        return write_motion(path, solution_to_motion(self.solution), rig=rig)


def joints(c3d: str | os.PathLike, *, markerset: str | os.PathLike | None = None,
           also: Sequence[str | os.PathLike] = (),
           static: str | os.PathLike | None = None) -> JointCentres:
    """Joint centres by sphere fits from C3D marker trajectories (``vidcap joints``).

    Parameters
    ----------
    c3d : str or path-like
        The trial whose frames the centres are given for.
    markerset : str or path-like, optional
        A built-in marker set's name or a TOML file; default: detected.
    also : sequence of str or path-like
        More trials of the same subject and marker set, pooled for the fits.
    static : str or path-like, optional
        A static trial of the subject (``--static``): calibrates the joints placed by
        definition once, as constant points of their parent segments.

    Returns
    -------
    JointCentres
        ``centres`` (F, J, 3) metres, ``joint_names``, ``fps``, ``notices``;
        ``.save(path)`` writes BVH or glTF.

    Raises
    ------
    vidcap.errors.C3DError
        If a trial cannot be read or lacks what is needed.
    vidcap.errors.FitError
        If a joint cannot be fitted from the data.
    """
    from vidcap.mocap.c3d import read_c3d
    from vidcap.mocap.markerset import load_markerset
    from vidcap.mocap.skeleton import solve_joints

    trials = [read_c3d(p) for p in (c3d, *also)]
    ms = load_markerset(markerset) if markerset is not None else None
    sol = solve_joints(trials, ms, static=read_c3d(static) if static is not None else None)
    return JointCentres(np.asarray(sol.positions), tuple(sol.joint_names), float(sol.fps),
                        solution_notices(sol, trials[0].path), sol,
                        tuple(str(p) for p in (c3d, *also, *([static] if static else []))))


def solution_notices(sol, trial_path) -> list[str]:
    """What ``vidcap joints`` warns of: markers absent from the trial, flagged fits."""
    notices = [f"{trial_path}: marker set {sol.markerset.name}: segment {seg}: markers "
               f"absent from the file: {', '.join(gone)}"
               for seg, gone in sol.missing_markers.items()]
    return notices + [f"joint {r.joint}: {r.warning()}" for r in sol.reports if r.warning()]


__all__ = ["JointCentres", "VideoMotion", "check_camera_option", "check_convert_options",
           "check_ensemble_option",
           "convert", "joints"]
