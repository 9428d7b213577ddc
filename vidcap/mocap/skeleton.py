"""Joint centres and a skeleton from marker trajectories (seed 000 §2.3-2.6, seed 001 §9).

The procedure, for a marker set (:mod:`vidcap.mocap.markerset`) and one or more trials:

1. The root segment's frame, per frame, from >= 3 of its markers.
2. Down the tree, for each child segment: its markers are expressed in the parent's
   frame over all frames (and all pooled trials); there they move on spheres about
   the joint centre, which MGDK (UGDK-corrected with ``noise_mm``) fits once
   (:func:`vidcap.mocap.spherefit.mgdk`). Planar motion is a hinge: the axis is
   reported. The per-frame centre is ``c_jk = x_jk + M_jk v_j`` (seed 000 §2.5),
   with ``x_jk``/``M_jk`` the parent's origin/axes and ``v_j`` the fitted centre.
3. The child's frame per frame from three points (seed 000 §2.5 case 3) - its own
   markers, the solved centre counting as a point (case 2) - or from one marker,
   the centre and the hinge axis (case 1).

Hips from a trial with little hip motion (a walk swings the thigh in one plane): the
fitted centre is then not observable across that plane and soft tissue pulls it 5-6
cm laterally (Plug-in-Gait and Qualisys gait trials in ``../shared``). Where the
marker set names the pelvis landmarks (``hip_regression``), the centre's components
along directions in which the thigh swung less than :data:`MIN_SWING_DEG` come from
the Harrington et al. (2007) regression (:func:`hip_regression`) instead.

Gaps: a frame where the primary three points of a segment are not all present is
filled by a least-squares rigid fit (Kabsch) of the segment's template (the median
local coordinates of all its points) to whichever >= 3 points are present. Samples
with a marker missing simply drop out of the sphere fit.

Everything is vectorised over frames; the only Python loops run over segments,
markers and trials.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from vidcap.errors import VidcapError
from vidcap.mocap.anatomical import chord_centre, chord_offset_mm
from vidcap.mocap.c3d import MarkerData
from vidcap.mocap.frames import (
    SegFrames,
    frame_from_axis,
    frame_from_three,
    frame_noise,
    frames_from_centre_axis,
    frames_from_points,
    kabsch,
    nanmean_points,
    nanmedian_rows,
    point_covariance,
    point_variance,
    rigid_residual_var,
    to_lab,
    to_local,
    unit,
)
from vidcap.mocap.hip import MIN_SWING_DEG, hip_regression, regress_hip
from vidcap.mocap.jointfit import fit_joint
from vidcap.mocap.markerset import MarkerSet, MarkerSetError, SegmentSpec, detect_markerset
from vidcap.mocap.score import refine_score, score
from vidcap.mocap.solution import JointReport, JointSolution
from vidcap.mocap.spherefit import PLANAR_COND
from vidcap.mocap.to_motion import lab_to_yup, solution_to_motion

__all__ = [
    "MIN_SWING_DEG", "JointReport", "JointSolution", "SolveOptions", "frame_from_axis",
    "frame_from_three", "hip_regression", "kabsch", "lab_to_yup", "point_covariance",
    "point_variance", "score", "solution_to_motion", "solve_joints",
]


#: A fitted centre farther than this (mm, in the parent's frame) from the set's
#: anatomical definition of the joint gives way to the definition: on real trials a
#: well-conditioned fit that far off reads soft-tissue motion as joint motion.
AGREE_MM = 20.0


@dataclass(frozen=True)
class SolveOptions:
    """The tuning of :func:`solve_joints` (its keyword arguments, documented there)."""

    noise_mm: float | None = None
    min_cap_deg: float = 10.0
    planar_cond: float = PLANAR_COND
    hinge_rule: bool = True
    max_axial_std_mm: float = 2.0
    hinge_ratio: float = 3.0
    score_refine: bool = True
    noise_correct: bool = True


@dataclass(frozen=True)
class ChildSamples:
    """A child segment's markers in its parent's frame, pooled over the trials.

    Attributes
    ----------
    sets : tuple of numpy.ndarray, each (N_k, 3)
        Per marker, its positions in the parent's frame over the frames where both are
        known, metres.
    fallback_local : numpy.ndarray, shape (3,)
        Median position of the fallback markers' centroid in the parent's frame.
    frames_used : int
        Frames with a parent frame and at least one of the child's markers.
    """

    sets: tuple[np.ndarray, ...]
    fallback_local: np.ndarray
    frames_used: int


@dataclass(frozen=True)
class HingeAnchor:
    """The point (parent frame, metres) a hinge centre is placed nearest, and what it is;
    ``point`` is None when the hinge rule does not apply to the joint."""

    point: np.ndarray | None
    what: str = ""


@dataclass(frozen=True)
class JointCentre:
    """One joint's constant centre, as the fit (and its refinements) placed it.

    Attributes
    ----------
    parent_local : numpy.ndarray, shape (3,)
        The centre in the parent segment's frame, metres.
    child_local : numpy.ndarray, shape (3,) or None
        The same centre in the child's own frame (SCoRE), when the child has frames of
        its own and both predictions are combined per frame.
    axis : numpy.ndarray, shape (3,) or None
        Hinge axis in the parent's frame (unit).
    report : JointReport
    own_frames : tuple of SegFrames or None
        The child's frames from its own >= 3 markers, per trial.
    mismatch_var : float
        SCoRE's residual variance per coordinate (m²) of the parent's and the child's
        predictions of the centre; 0 without SCoRE.
    marker_var : float
        Marker noise variance per coordinate (m²) used to weigh them.
    lab_centres : tuple of numpy.ndarray, each (F, 3), or None
        Per trial, the centre per frame in the lab when a per-frame definition placed
        it (:func:`anatomical_centre`) rather than a constant point of the parent.
    """

    parent_local: np.ndarray
    child_local: np.ndarray | None
    axis: np.ndarray | None
    report: JointReport
    own_frames: tuple[SegFrames, ...] | None = None
    mismatch_var: float = 0.0
    marker_var: float = 0.0
    lab_centres: tuple[np.ndarray, ...] | None = None


def _lab_up(trial: MarkerData) -> np.ndarray:
    up = getattr(trial, "up", None)
    return np.array([0.0, 0.0, 1.0]) if up is None else np.asarray(up, dtype=float)


def _pooled(arrays: Sequence[np.ndarray]) -> np.ndarray:
    """The trials' arrays one after the other (the one array itself for one trial)."""
    return arrays[0] if len(arrays) == 1 else np.concatenate(arrays)


def markers_of(trial: MarkerData, names) -> np.ndarray:
    """Positions of the named markers, (F, len(names), 3) metres (a copy)."""
    return np.take(trial.positions, [trial.index(m) for m in names], axis=1)


# --------------------------------------------------------------------------- steps
def root_frames(trials: Sequence[MarkerData], root: SegmentSpec) -> list[SegFrames]:
    """Step 1: the root segment's frames per trial, from its >= 3 markers (Kabsch-filled)."""
    return [frames_from_points(markers_of(t, root.markers)) for t in trials]


def child_samples(spec: SegmentSpec, trials: Sequence[MarkerData],
                  parent_frames: Sequence[SegFrames]) -> ChildSamples:
    """The child's markers in the parent's frame over all trials (the sphere fit's input),
    and its fallback point (the median centroid of ``spec.fallback``, else its markers)."""
    sets: list[list[np.ndarray]] = [[] for _ in spec.markers]
    fb: list[np.ndarray] = []
    used = 0
    for t, pf in zip(trials, parent_frames, strict=True):
        y = to_local(pf.r, pf.o, markers_of(t, spec.markers))  # (F, m, 3), NaN where missing
        ok = np.isfinite(y).all(axis=2)
        used += int(ok.any(axis=1).sum())
        for k in range(len(spec.markers)):
            sets[k].append(y[ok[:, k], k])
        fy = to_local(pf.r, pf.o, markers_of(t, spec.fallback)) if spec.fallback else y
        # (frames without any of them stay NaN)
        fb.append(nanmean_points(fy) if np.isfinite(fy).any() else fy[:, 0])
    return ChildSamples(tuple(np.concatenate(a) for a in sets),
                        nanmedian_rows(np.concatenate(fb)), used)


def hinge_anchor(spec: SegmentSpec, ms: MarkerSet, trial: MarkerData, parent_frame: SegFrames,
                 parent_joint_lab: np.ndarray | None, hinge_rule: bool) -> HingeAnchor:
    """Where the hinge rule places a centre along its axis (first trial, parent frame).

    The midpoint of landmarks straddling the joint (epicondyles, malleoli, styloids) when
    the set names them (``axis_anchor``); else, for a joint whose parent is a long bone
    (a non-root segment with this one child), the parent's proximal joint centre
    (``parent_joint_lab``, (F, 3) lab); else none.
    """
    if not hinge_rule:
        return HingeAnchor(None)
    pf = parent_frame
    if spec.axis_anchor:
        # their midpoint is the joint's anatomical centre along its axis
        point = nanmedian_rows(nanmean_points(
            to_local(pf.r, pf.o, markers_of(trial, spec.axis_anchor))))
        return HingeAnchor(point, f"the {'/'.join(spec.axis_anchor)} midpoint")
    pspec = ms.segment(spec.parent)
    n_siblings = sum(1 for q in ms.segments if q.parent == spec.parent)
    if pspec.parent is not None and n_siblings == 1 and parent_joint_lab is not None:
        point = nanmedian_rows(to_local(pf.r, pf.o, parent_joint_lab[:, None])[:, 0])
        return HingeAnchor(point, f"the {spec.parent} proximal joint")
    return HingeAnchor(None)


def parent_frame_cov(parent_frame: SegFrames, sets: Sequence[np.ndarray]) -> np.ndarray | None:
    """The noise the parent's frame adds to the child's markers in its coordinates: the
    mean over the markers of :func:`point_covariance` (3, 3), units of σ²; None when
    undetermined."""
    means = [y.mean(axis=0) for y in sets if len(y)]
    covs = (point_covariance(parent_frame.template, np.array(means), parent_frame.weights)
            if means else None)
    cov = np.mean(covs, axis=0) if means else None
    return None if cov is None or not np.isfinite(cov).all() else cov


def fit_segment_centre(spec: SegmentSpec, samples: ChildSamples, anchor: HingeAnchor,
                       frame_cov: np.ndarray | None, opts: SolveOptions) -> JointCentre:
    """Steps 2 and 3: the multi-sphere fit of one joint in its parent's frame, the hinge
    rule where the centre is not observable along an axis, the fallback when flagged."""
    v, axis, rep = fit_joint(
        spec, spec.parent, list(samples.sets), samples.fallback_local, samples.frames_used,
        noise_mm=opts.noise_mm, min_cap_deg=opts.min_cap_deg, planar_cond=opts.planar_cond,
        anchor=anchor.point, anchor_what=anchor.what, bone_guard=not spec.axis_anchor,
        max_axial_std_mm=opts.max_axial_std_mm, hinge_ratio=opts.hinge_ratio,
        frame_cov=frame_cov)
    return JointCentre(v, None, axis, rep)


def refine_symmetric(spec: SegmentSpec, trials: Sequence[MarkerData],
                     parent_frames: Sequence[SegFrames], fit: JointCentre,
                     anchor: HingeAnchor, samples: ChildSamples,
                     opts: SolveOptions) -> JointCentre:
    """With >= 3 markers the child has frames of its own: the symmetric two-frame fit
    (SCoRE; SARA and the hinge rule for hinges) replaces the sphere fit's centre, which
    still decides kind, flags and fallbacks (``opts.score_refine``)."""
    if len(spec.markers) < 3:
        return fit
    own = tuple(frames_from_points(markers_of(t, spec.markers)) for t in trials)
    fit = JointCentre(fit.parent_local, None, fit.axis, fit.report, own)
    if fit.report.flagged or not opts.score_refine:
        return fit
    # marker noise: a-priori, else from the child's rigid-fit residuals
    if opts.noise_mm is not None:
        sig2_m = (float(opts.noise_mm) * 1e-3) ** 2
    else:
        sig2_m = rigid_residual_var(list(own), [markers_of(t, spec.markers) for t in trials])
    pf0 = parent_frames[0]
    cen_p, inv_p = frame_noise(pf0.template, pf0.weights)
    cen_c, inv_c = frame_noise(own[0].template, None)
    kw = {}
    if opts.noise_correct and cen_p is not None and cen_c is not None:
        kw = dict(rot_cov_p=sig2_m * inv_p, rot_cov_c=sig2_m * inv_c,
                  centroid_p=cen_p, centroid_c=cen_c)
    sc = score(_pooled([f.r for f in parent_frames]), _pooled([f.o for f in parent_frames]),
               _pooled([f.r for f in own]), _pooled([f.o for f in own]), **kw)
    if sc["x"] is None:
        return fit
    v, v_child, axis, rep = refine_score(sc, fit.report, anchor.point, opts.max_axial_std_mm,
                                         np.concatenate(samples.sets), anchor.what,
                                         not spec.axis_anchor)
    return JointCentre(v, v_child, axis, rep, own, sc["s2"], sig2_m)


def regress_hip_centre(spec: SegmentSpec, root: SegmentSpec, trials: Sequence[MarkerData],
                       root_frames_: Sequence[SegFrames], fit: JointCentre,
                       samples: ChildSamples) -> JointCentre:
    """A hip's poorly swung components from the pelvis regression (:func:`regress_hip`),
    all of them when the fit was rejected; the other joints, and hips whose thigh swung
    enough, as they are. A moved centre keeps only the parent's prediction per frame."""
    if spec.parent != root.name or spec.joint not in root.hip_joints:
        return fit
    frames = [{root.name: f} for f in root_frames_]
    v, rep, moved = regress_hip(fit.parent_local, fit.report, spec, root, trials, frames,
                                list(samples.sets))
    if not moved:
        return fit
    return JointCentre(v, None, fit.axis, rep, fit.own_frames, fit.mismatch_var,
                       fit.marker_var)


def _combined_centre(spec: SegmentSpec, trial: MarkerData, pf: SegFrames, fit: JointCentre,
                     own: SegFrames) -> tuple[np.ndarray, SegFrames]:
    """Per frame, the inverse-variance mean of the parent's and the child's prediction of
    the centre; the parent's prediction is also a weighted point of the child's frame."""
    v, v_child = fit.parent_local, fit.child_local
    c = to_lab(pf.r, pf.o, v)
    var_p = point_variance(pf.template, v, pf.weights)
    var_c = point_variance(own.template, v_child)
    sig2_m = fit.marker_var
    # the parent's prediction as a point of the child's frame, weighted by its variance
    # relative to a marker's; the variance is scaled to the observed parent/child
    # mismatch (3 s² = σ²(var_p + var_c)), so a joint that is not a fixed point (a spine
    # standing for several joints) counts for little
    sig2_eff = max(3.0 * fit.mismatch_var / (var_p + var_c), sig2_m)
    w_pt = 3.0 * sig2_m / max(sig2_eff * var_p, 1e-300) if sig2_m > 0 else 0.0
    cc = to_lab(own.r, own.o, v_child)
    wp = np.where(np.isfinite(c).all(1), 1.0 / var_p, 0.0)[:, None]
    wc = np.where(np.isfinite(cc).all(1), 1.0 / var_c, 0.0)[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        both = (np.where(wp > 0, c, 0.0) * wp + np.where(wc > 0, cc, 0.0) * wc) / (wp + wc)
    centre = np.where(wp + wc > 0, both, np.nan)
    tmpl = np.concatenate([own.template, v_child[None]])
    wts = np.concatenate([np.ones(len(own.template)), [w_pt]])
    pts = np.concatenate([markers_of(trial, spec.markers), c[:, None]], axis=1)
    r2, o2 = kabsch(tmpl, pts, wts)
    return centre, SegFrames(r2, o2, tmpl, wts)


def per_frame_centre(spec: SegmentSpec, trial: MarkerData, pf: SegFrames, fit: JointCentre,
                     trial_index: int) -> tuple[np.ndarray, SegFrames]:
    """Step 4: the joint's centre per frame (lab, (F, 3) metres) and the child segment's
    frames in one trial (seed 000 §2.5 cases 3, 2 and 1 by its marker count)."""
    if fit.child_local is not None:
        return _combined_centre(spec, trial, pf, fit, fit.own_frames[trial_index])
    v = fit.parent_local
    c = to_lab(pf.r, pf.o, v)
    if fit.lab_centres is not None:  # per-frame definition; the constant point in its gaps
        own = fit.lab_centres[trial_index]
        c = np.where(np.isfinite(own).all(axis=1, keepdims=True), own, c)
    mk = markers_of(trial, spec.markers)
    if len(spec.markers) >= 3:
        own = fit.own_frames[trial_index] if fit.own_frames else frames_from_points(mk)
        return c, own
    if len(spec.markers) == 2:
        return c, frames_from_points(np.concatenate([mk, c[:, None]], 1))
    # case 1: one marker, the centre and an axis: the hinge axis if there is one, else
    # the parent's axis most perpendicular to the marker direction
    if fit.axis is not None:
        a_loc = fit.axis
    else:
        dloc = unit(nanmedian_rows(to_local(pf.r, pf.o, mk)[:, 0]) - v)
        a_loc = (np.eye(3)[int(np.argmin(np.abs(dloc)))] if np.isfinite(dloc).all()
                 else np.eye(3)[0])
    a_lab = np.einsum("fij,j->fi", pf.r, a_loc)
    return c, frames_from_centre_axis(c, mk[:, 0], a_lab)


def poor_fit_reason(report: JointReport, opts: SolveOptions) -> str:
    """Why the functional fit does not place this joint well ('' when it does): a
    fallback, a hinge whose centre along the axis a rule placed, or a worst-determined
    coordinate with a Cramér-Rao standard deviation above ``opts.max_axial_std_mm``."""
    if report.flagged:
        return "the fit was rejected"
    if "axis-rule" in report.method:
        return (f"a hinge (condition {report.condition:.3g}): its centre along the axis is "
                f"not observable (std {report.axial_std_mm:.0f} mm)")
    if not report.axial_std_mm <= opts.max_axial_std_mm:
        return (f"the centre's worst coordinate has a std of {report.axial_std_mm:.0f} mm "
                f"(condition {report.condition:.3g})")
    return ""


def anatomical_centre(spec: SegmentSpec, trials: Sequence[MarkerData],
                      parent_frames: Sequence[SegFrames],
                      parent_joint_lab: Sequence[np.ndarray] | None, fit: JointCentre,
                      opts: SolveOptions, parent_joint: str = "") -> JointCentre:
    """Plug-in-Gait's chord centre (:func:`vidcap.mocap.anatomical.chord_centre`) per
    frame where the set defines one (``spec.chord``) and the fit is poorly conditioned
    (:func:`poor_fit_reason`) or lies more than :data:`AGREE_MM` from it (soft tissue
    read as joint motion); the fit's report keeps its residual, condition and range of
    motion, its method becomes ``'anatomical'``. A joint whose set names the landmarks
    straddling it (``axis_anchor``: epicondyles, malleoli, styloids) and whose fit was
    rejected takes their midpoint per frame (:func:`landmark_midpoint_centre`).
    """
    if spec.axis_anchor and fit.report.flagged:
        return landmark_midpoint_centre(spec, trials, parent_frames, fit)
    if not spec.chord or parent_joint_lab is None:
        return fit
    wand, marker = spec.chord
    lab, local, sources = [], [], set()
    for t, pf, prox in zip(trials, parent_frames, parent_joint_lab, strict=True):
        off_mm, source = chord_offset_mm(spec.chord_width, getattr(t, "subject", {}) or {})
        sources.add(f"{off_mm:.0f} mm from {source}")
        c = chord_centre(t.marker(wand), prox, t.marker(marker), off_mm * 1e-3)
        lab.append(c)
        local.append(to_local(pf.r, pf.o, c[:, None])[:, 0])
    v = nanmedian_rows(np.concatenate(local))
    if not np.isfinite(v).all():
        return fit
    reason = poor_fit_reason(fit.report, opts)
    apart = float(np.linalg.norm(v - fit.parent_local)) * 1e3
    if not reason and apart > AGREE_MM:
        reason = (f"its centre lies {apart:.0f} mm from the anatomical one (over "
                  f"{AGREE_MM:g} mm: soft-tissue motion read as joint motion)")
    if not reason:
        return fit
    note = (f"Plug-in-Gait chord from {wand}, {marker} and the {parent_joint or spec.parent}"
            f" centre, offset {'; '.join(sorted(sources))}; the fit: {reason}")
    rep = replace(fit.report, method="anatomical", note=note, flagged=False,
                  center_local_m=[float(a) for a in v])
    return JointCentre(v, None, fit.axis, rep, fit.own_frames, lab_centres=tuple(lab))


def landmark_midpoint_centre(spec: SegmentSpec, trials: Sequence[MarkerData],
                             parent_frames: Sequence[SegFrames], fit: JointCentre
                             ) -> JointCentre:
    """The midpoint of the landmarks straddling the joint (``spec.axis_anchor``, e.g. the
    femoral epicondyles for the knee) per frame, for a joint whose fit was rejected."""
    lab = [np.mean(markers_of(t, spec.axis_anchor), axis=1) for t in trials]
    local = [to_local(pf.r, pf.o, c[:, None])[:, 0] for c, pf in zip(lab, parent_frames,
                                                                     strict=True)]
    v = nanmedian_rows(np.concatenate(local))
    if not np.isfinite(v).all():
        return fit
    note = (f"midpoint of {'/'.join(spec.axis_anchor)} per frame; the fit: "
            f"{fit.report.note.split(';')[0]}")
    rep = replace(fit.report, method="anatomical", note=note, flagged=False,
                  center_local_m=[float(a) for a in v])
    return JointCentre(v, None, None, rep, fit.own_frames, lab_centres=tuple(lab))


def static_offsets(static: MarkerData, ms: MarkerSet, opts: SolveOptions) -> dict:
    """The joints a static trial places by definition (``'anatomical'``, ``'regression'``),
    each as its constant point in the parent segment's frame (3,), metres."""
    sol = solve_joints(static, ms, **{k: getattr(opts, k) for k in (
        "noise_mm", "min_cap_deg", "planar_cond", "hinge_rule", "max_axial_std_mm",
        "hinge_ratio", "score_refine", "noise_correct")})
    out = {}
    for rep in sol.reports:
        if rep.method in ("anatomical", "regression") and rep.parent_segment:
            v = sol.local_points[rep.parent_segment][rep.joint]
            if np.isfinite(v).all():
                out[rep.joint] = np.asarray(v, dtype=float)
    return out


def calibrated_centre(fit: JointCentre, offset: np.ndarray | None, opts: SolveOptions,
                      static: MarkerData | None) -> JointCentre:
    """The static trial's offset (:func:`static_offsets`) in place of a joint the trial
    itself placed by definition or could not fit; a well-conditioned fit stands."""
    if offset is None:
        return fit
    rep = fit.report
    by_definition = rep.method == "anatomical" or "regression" in rep.method
    if not by_definition and not poor_fit_reason(rep, opts):
        return fit
    moved = float(np.linalg.norm(offset - fit.parent_local)) * 1e3
    note = (f"constant in the {rep.parent_segment} frame as the static trial "
            f"{getattr(static, 'path', '')} placed it ({moved:.0f} mm from this trial's "
            f"{rep.method} centre); {rep.note}")
    rep = replace(rep, method=f"{rep.method}+static", note=note, flagged=False,
                  center_local_m=[float(a) for a in offset])
    return JointCentre(offset, None, fit.axis, rep, fit.own_frames)


def root_joint(root: SegmentSpec, rf: SegFrames, parent_locals: dict
               ) -> tuple[np.ndarray, JointReport]:
    """Step 5: the root joint in the root's frame: the mean of its ``origin`` joints
    (hips) when solved, else its markers' centroid; with its report."""
    origin_j = [j for j in root.origin if j in parent_locals]
    if origin_j:
        v_root = np.mean([parent_locals[j] for j in origin_j], axis=0)
        how = f"mean of {', '.join(origin_j)}"
    else:
        v_root = np.nanmean(rf.template[: len(root.markers)], axis=0)
        how = f"centroid of {', '.join(root.markers)}"
    rep = JointReport(
        joint=root.joint, segment=root.name, parent_segment=None, kind="root",
        method="markers", frames_used=int(rf.valid.sum()), rms_residual_m=np.nan,
        condition=np.nan, cap_angle_deg=np.nan, axis=None,
        center_local_m=[float(a) for a in v_root], note=how)
    return v_root, rep


def end_joint(spec: SegmentSpec, sf: SegFrames, trial: MarkerData
              ) -> tuple[np.ndarray, JointReport]:
    """An end joint (head top, toe) in its segment's frame: the median centroid of its
    ``end_markers``; with its report."""
    valid = sf.valid
    loc = to_local(np.where(valid[:, None, None], sf.r, 0.0), np.where(valid[:, None], sf.o, 0.0),
                   markers_of(trial, spec.end_markers))
    loc[~valid] = np.nan
    v_end = nanmedian_rows(nanmean_points(loc) if np.isfinite(loc).any() else loc[:, 0])
    rep = JointReport(
        joint=spec.end_joint, segment=spec.name, parent_segment=spec.name, kind="end",
        method="markers", frames_used=int(valid.sum()), rms_residual_m=np.nan,
        condition=np.nan, cap_angle_deg=np.nan, axis=None,
        center_local_m=[float(a) for a in v_end],
        note=f"centroid of {', '.join(spec.end_markers)}")
    return v_end, rep


def joint_tree(ms: MarkerSet) -> tuple[list[str], list[int], list[str]]:
    """Joint names, parent indices (-1 for the root) and the segment each joint's rotation
    is, in the marker set's order, end joints last."""
    names, parents, jseg = [], [], []
    joint_of = {s.name: s.joint for s in ms.segments}
    for s in ms.segments:
        names.append(s.joint)
        parents.append(-1 if s.parent is None else names.index(joint_of[s.parent]))
        jseg.append(s.name)
    for s in ms.segments:
        if s.end_joint:
            names.append(s.end_joint)
            parents.append(names.index(s.joint))
            jseg.append(s.name)
    return names, parents, jseg


def _restricted_set(trials: Sequence[MarkerData], markerset: MarkerSet | None):
    """The marker set (detected when None) cut to the markers every trial has."""
    main = trials[0]
    if markerset is None:
        markerset = detect_markerset(main.labels, path=main.path)
    available = set(main.labels)
    for t in trials[1:]:
        available &= set(t.labels)
    ms, missing = markerset.restricted(available)
    if not ms.segments or ms.segments[0].name != markerset.root.name or len(ms.root.markers) < 3:
        raise MarkerSetError(
            f"marker set {markerset.name}: the root segment {markerset.root.name} needs >= 3 "
            f"of its markers {list(markerset.root.markers)}; missing: "
            f"{missing.get(markerset.root.name, [])}", main.path,
        )
    return ms, missing


def solve_segment(spec: SegmentSpec, ms: MarkerSet, trials: Sequence[MarkerData],
                  parent_frames: Sequence[SegFrames], parent_joint_lab: np.ndarray | None,
                  opts: SolveOptions) -> JointCentre:
    """One joint's constant centre from every step: samples, anchor, sphere fit and hinge
    rule, SCoRE refinement, hip regression."""
    samples = child_samples(spec, trials, parent_frames)
    anchor = hinge_anchor(spec, ms, trials[0], parent_frames[0], parent_joint_lab,
                          opts.hinge_rule)
    fit = fit_segment_centre(spec, samples, anchor,
                             parent_frame_cov(parent_frames[0], samples.sets), opts)
    fit = refine_symmetric(spec, trials, parent_frames, fit, anchor, samples, opts)
    root = ms.root
    if spec.parent == root.name:
        fit = regress_hip_centre(spec, root, trials, parent_frames, fit, samples)
    return fit


def solve_joints(
    trials: MarkerData | Sequence[MarkerData],
    markerset: MarkerSet | None = None,
    *,
    noise_mm: float | None = None,
    min_cap_deg: float = 10.0,
    planar_cond: float = PLANAR_COND,
    hinge_rule: bool = True,
    max_axial_std_mm: float = 2.0,
    hinge_ratio: float = 3.0,
    score_refine: bool = True,
    noise_correct: bool = True,
    static: MarkerData | None = None,
) -> JointSolution:
    """Joint centres of a marker-set skeleton (seed 000 §2.3-2.6).

    Parameters
    ----------
    trials : MarkerData or sequence of MarkerData
        The trial to solve first; any further trials (same subject and marker set)
        are pooled for the sphere fits only.
    markerset : MarkerSet, optional
        Detected from the first trial's labels when omitted.
    noise_mm : float, optional, keyword-only
        Marker noise standard deviation (mm, isotropic): the fits use UGDK's
        noise-corrected covariance C - σ² I. None: plain MGDK.
    min_cap_deg : float, keyword-only
        A joint whose markers sweep a cap smaller than this (degrees) about the fitted
        centre is flagged and falls back to its marker centroid: a sphere fit's error
        grows like σ/(r θ²) as the cap angle θ shrinks.
    planar_cond : float, keyword-only
        Condition number above which motion counts as planar (a hinge).
    hinge_rule : bool, keyword-only
        For a joint whose parent is a long bone (a non-root segment with this one
        child), when the motion is planar or the centre's worst coordinate has a
        Cramér-Rao standard deviation above ``max_axial_std_mm``, place the centre on
        the fitted axis at the point nearest the parent's proximal joint centre
        (reported as ``method='mgdk+axis-rule'``).
    max_axial_std_mm : float, keyword-only
        See ``hinge_rule``.
    hinge_ratio : float, keyword-only
        Motion counts as (nearly) planar for ``hinge_rule`` when the markers' spread
        across their plane of motion (√ of the smallest eigenvalue of the pooled
        within-marker covariance) is below ``hinge_ratio`` times the noise (σ from
        ``noise_mm``, else the RMS radial residual): out-of-plane scatter that noise
        alone explains.
    score_refine : bool, keyword-only
        For a child segment with >= 3 markers (frames of its own), replace the MGDK
        centre by the symmetric two-frame fit (:func:`score`, SCoRE; SARA's axis and
        the ``hinge_rule`` for hinges), and take each frame's centre as the
        inverse-variance mean of the parent's and the child's prediction
        (:func:`point_variance`); the parent's prediction also enters the child's
        least-squares frame as a weighted point (seed 000 §2.5: a solved centre counts
        as a point). MGDK's fit still decides the kind, flags and fallbacks.
    noise_correct : bool, keyword-only
        Remove the O(σ²) shrinkage bias of SCoRE due to noisy frames (see
        :func:`score`), with σ from ``noise_mm`` or else estimated from the child's
        rigid-fit residuals, and the frames' rotation noise predicted from their
        templates (:func:`point_covariance`).
    static : MarkerData, optional, keyword-only
        A static (standing) trial of the same subject: the joints it places by an
        anatomical definition or the pelvis regression (:func:`static_offsets`) keep
        that position in their parent segment's frame in the trials, wherever the
        trials' own fit is poorly conditioned (``method`` gains ``+static``).

    Returns
    -------
    JointSolution

    Raises
    ------
    MarkerSetError
        No marker set fits, or the root has fewer than 3 of its markers.
    """
    trials = [trials] if isinstance(trials, MarkerData) else list(trials)
    if not trials:
        raise VidcapError("no trials given")
    opts = SolveOptions(noise_mm, min_cap_deg, planar_cond, hinge_rule, max_axial_std_mm,
                        hinge_ratio, score_refine, noise_correct)
    main = trials[0]
    ms, missing = _restricted_set(trials, markerset)
    root = ms.root
    # per segment, its frames in every trial; per joint, its lab centre in every trial
    frames: dict[str, list[SegFrames]] = {root.name: root_frames(trials, root)}
    centres: dict[str, list[np.ndarray]] = {}
    fits: dict[str, JointCentre] = {}
    offsets = static_offsets(static, ms, opts) if static is not None else {}
    for s in ms.segments[1:]:
        pjoint = ms.segment(s.parent).joint
        fit = solve_segment(s, ms, trials, frames[s.parent],
                            centres.get(pjoint, [None])[0], opts)
        fit = anatomical_centre(s, trials, frames[s.parent], centres.get(pjoint), fit, opts,
                                pjoint)
        fit = calibrated_centre(fit, offsets.get(s.joint), opts, static)
        placed = [per_frame_centre(s, t, pf, fit, ti)
                  for ti, (t, pf) in enumerate(zip(trials, frames[s.parent], strict=True))]
        fits[s.joint] = fit
        centres[s.joint] = [c for c, _ in placed]
        frames[s.name] = [f for _, f in placed]

    return _assemble(ms, missing, main, frames, centres, fits)


def _assemble(ms: MarkerSet, missing: dict, main: MarkerData, frames: dict, centres: dict,
              fits: dict) -> JointSolution:
    """Step 5: the first trial's solution: constant local points per segment (its joints,
    the root joint, the end joints), the joint tree, positions and frames stacked."""
    root = ms.root
    # constant local points per segment (first trial): its joints, the root joint, ends
    f0 = {name: fr[0] for name, fr in frames.items()}
    c0 = {joint: c[0] for joint, c in centres.items()}
    reports = [fits[s.joint].report for s in ms.segments[1:]]
    local_points: dict[str, dict[str, np.ndarray]] = {s.name: {} for s in ms.segments}
    for s in ms.segments[1:]:
        local_points[s.parent][s.joint] = fits[s.joint].parent_local
        sf = f0[s.name]
        local_points[s.name][s.joint] = nanmedian_rows(
            to_local(sf.r, sf.o, c0[s.joint][:, None])[:, 0])
    rf = f0[root.name]
    v_root, rep = root_joint(root, rf, local_points[root.name])
    local_points[root.name][root.joint] = v_root
    c0[root.joint] = to_lab(rf.r, rf.o, v_root)
    reports.insert(0, rep)
    for s in ms.segments:
        if s.end_joint:
            v_end, rep = end_joint(s, f0[s.name], main)
            local_points[s.name][s.end_joint] = v_end
            c0[s.end_joint] = to_lab(f0[s.name].r, f0[s.name].o, v_end)
            reports.append(rep)

    names, parents, jseg = joint_tree(ms)
    seg_names = tuple(s.name for s in ms.segments)
    order = {r.joint: i for i, r in enumerate(reports)}
    reports.sort(key=lambda r: names.index(r.joint) if r.joint in names else order[r.joint])
    return JointSolution(
        markerset=ms, joint_names=tuple(names), joint_parents=tuple(parents),
        joint_segment=tuple(jseg), positions=np.stack([c0[n] for n in names], axis=1),
        segment_names=seg_names, rotations=np.stack([f0[n].r for n in seg_names], axis=1),
        origins=np.stack([f0[n].o for n in seg_names], axis=1), local_points=local_points,
        reports=tuple(reports), fps=main.fps, up=_lab_up(main), missing_markers=missing,
    )
