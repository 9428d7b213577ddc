"""A draft marker set from the trial itself, for marker sets vidcap does not know.

Writing a marker-set TOML (:mod:`vidcap.mocap.markerset`) means knowing which marker
rides on which segment and which segment hangs from which. Both can be read from the
motion (after Kirk, O'Brien and Forsyth, "Skeletal parameter estimation from optical
motion capture data", CVPR 2005):

1. :func:`rigid_groups`: markers on one rigid segment keep their distances; markers
   across a joint that moves do not. The standard deviation over the trial of every
   pairwise distance, clustered with complete linkage below ``max_sd_mm``, gives the
   segments.
2. :func:`segment_tree`: a child segment's markers, seen in its parent's frame, move on
   spheres about the joint (seed 000): of all the ways to join the groups, the tree
   whose joints fit those spheres best (smallest RMS residual of an MGDK fit, attached
   greedily, as Prim's algorithm does) is the guess. The root is the group of three or
   more markers nearest the middle of all markers.
3. :func:`draft_markerset`: the TOML text, with the figures behind each guess in
   comments. Names and T-pose directions cannot be read from the motion: the draft
   calls them ``seg1``, ``seg1_seg2`` and ``rest = "-y"`` for the user to rename and
   check before using it with ``vidcap joints --markerset``.
"""

from __future__ import annotations

import warnings

import numpy as np

from vidcap.errors import FitError
from vidcap.mocap.c3d import MarkerData
from vidcap.mocap.markerset import MarkerSetError

#: Markers whose distance varies by less than this (standard deviation over the
#: trial, mm) can share a segment: skin markers on one segment move 0.5-5 mm against
#: each other (the Qualisys trial in ``../shared``), markers across a moving joint by
#: centimetres. In a walk some joints barely move (a shoulder, the neck): at 8 mm an
#: upper-arm marker of CMU's 07_01 joined the head's, at 5 mm a foot split in two.
MAX_SD_MM = 6.0


def distance_spread(positions: np.ndarray, *, chunk: int = 512) -> np.ndarray:
    """Standard deviation over frames of every pairwise marker distance.

    Parameters
    ----------
    positions : numpy.ndarray, shape (F, M, 3)
        Marker positions in metres, NaN where missing.
    chunk : int
        Frames per vectorised step (memory: chunk x M x M floats).

    Returns
    -------
    numpy.ndarray, shape (M, M)
        Metres; ``inf`` for pairs seen together in fewer than 2 frames; 0 on the
        diagonal.
    """
    p = np.asarray(positions, dtype=float)
    M = p.shape[1]
    n = np.zeros((M, M))
    s1 = np.zeros((M, M))
    s2 = np.zeros((M, M))
    for a in range(0, p.shape[0], chunk):
        x = p[a:a + chunk]
        d = np.linalg.norm(x[:, :, None] - x[:, None], axis=-1)  # (f, M, M), NaN if missing
        ok = np.isfinite(d)
        d = np.where(ok, d, 0.0)
        n += ok.sum(0)
        s1 += d.sum(0)
        s2 += (d * d).sum(0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = s1 / n
        sd = np.sqrt(np.maximum(s2 / n - mean * mean, 0.0) * n / np.maximum(n - 1, 1))
    sd = np.where(n >= 2, sd, np.inf)
    np.fill_diagonal(sd, 0.0)
    return sd


def rigid_groups(data: MarkerData, *, max_sd_mm: float = MAX_SD_MM,
                 min_present: float = 0.5) -> list[list[str]]:
    """Markers grouped into rigid segments (complete linkage on :func:`distance_spread`).

    Parameters
    ----------
    data : MarkerData
        The trial.
    max_sd_mm : float
        Largest distance spread (mm) between any two markers of one group.
    min_present : float
        Markers present in fewer than this share of frames are left out.

    Returns
    -------
    list of list of str
        Groups of marker labels, largest first (label order within a group).
    """
    return _grouped(data, max_sd_mm, min_present)[0]


def _grouped(data: MarkerData, max_sd_mm: float, min_present: float):
    """:func:`rigid_groups` and, per group, its largest distance spread (m)."""
    from scipy.cluster.hierarchy import fcluster, linkage
    from scipy.spatial.distance import squareform

    present = np.isfinite(data.positions).all(axis=2).mean(axis=0) >= min_present
    labels = [m for m, ok in zip(data.labels, present, strict=True) if ok]
    if len(labels) < 2:
        return ([labels], [0.0]) if labels else ([], [])
    sd = distance_spread(data.positions[:, present])
    sd = np.where(np.isfinite(sd), sd, 1e3)  # never seen together: never one segment
    z = linkage(squareform(sd, checks=False), method="complete")
    ids = fcluster(z, t=max_sd_mm * 1e-3, criterion="distance")
    order = sorted(np.unique(ids), key=lambda k: -int(np.count_nonzero(ids == k)))
    groups = [[m for m, g in zip(labels, ids, strict=True) if g == k] for k in order]
    spread = [float(sd[np.ix_(ids == k, ids == k)].max()) for k in order]
    return groups, spread


def _joint_residual(child: np.ndarray, frames) -> tuple[float, float]:
    """RMS residual (m) of one MGDK sphere about the child's markers (F, m, 3) seen in
    the parent's frames, and the mean radius (m); inf when it cannot be fitted."""
    from vidcap.mocap.frames import to_local as _to_local
    from vidcap.mocap.spherefit import mgdk

    y = _to_local(frames.r, frames.o, child)
    sets = [y[np.isfinite(y[:, k]).all(axis=1), k] for k in range(y.shape[1])]
    sets = [s for s in sets if len(s) >= 4]
    if not sets:
        return np.inf, np.nan
    try:
        fit = mgdk(sets)
    except FitError:
        return np.inf, np.nan
    c = np.asarray(fit.center, float)
    if not np.isfinite(c).all():
        return np.inf, np.nan
    res, radii = [], []
    for s in sets:
        r = np.linalg.norm(s - c, axis=1)
        res.append(r - r.mean())
        radii.append(r.mean())
    return float(np.sqrt(np.mean(np.concatenate(res) ** 2))), float(np.mean(radii))


def segment_tree(data: MarkerData, groups: list[list[str]]):
    """Parents of the rigid groups: the tree whose joints fit best.

    Returns
    -------
    root : int
        Index of the root group.
    links : list of (child, parent, rms_m, radius_m)
        In the order they were attached (parents before children); groups that
        could not be attached (no parent with three markers fits them) are absent.
    """
    from vidcap.mocap.frames import frames_from_points as _frames_from_points

    pos = [data.positions[:, [data.index(m) for m in g]] for g in groups]
    with warnings.catch_warnings():  # frames where a whole group is missing: NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        middle = np.nanmedian(np.nanmean(data.positions, axis=1), axis=0)
        centres = [np.nanmedian(np.nanmean(p, axis=1), axis=0) for p in pos]
    big = [k for k, g in enumerate(groups) if len(g) >= 3]
    if not big:
        raise MarkerSetError("no group of three or more rigid markers: no segment frame "
                             "to build a skeleton on", data.path)
    root = min(big, key=lambda k: float(np.linalg.norm(centres[k] - middle)))
    frames = {k: _frames_from_points(pos[k]) for k in big}
    score = {}
    for c in range(len(groups)):
        for p in big:
            if p != c:
                score[c, p] = _joint_residual(pos[c], frames[p])
    attached, links = {root}, []
    while True:
        options = [(score[c, p][0], c, p) for (c, p) in score
                   if c not in attached and p in attached and np.isfinite(score[c, p][0])]
        if not options:
            break
        rms, c, p = min(options)
        links.append((c, p, rms, score[c, p][1]))
        attached.add(c)
    return root, links


def draft_markerset(data: MarkerData, *, max_sd_mm: float = MAX_SD_MM) -> str:
    """The TOML text of a draft marker set for ``data`` (see the module docstring).

    Raises
    ------
    MarkerSetError
        No rigid group of three markers (no root frame).
    """
    groups, spread = _grouped(data, max_sd_mm, 0.5)
    root, links = segment_tree(data, groups)
    name = {root: "seg1"}
    for i, (c, _, _, _) in enumerate(links):
        name[c] = f"seg{i + 2}"

    def markers(k):
        return "[" + ", ".join(f'"{m}"' for m in groups[k]) + "]"

    children = {}
    for c, p, _, _ in links:
        children.setdefault(p, []).append(c)
    lines = [
        f"# Draft marker set made by `vidcap joints --draft-markerset` from {data.path}:",
        f"# {len(groups)} groups of markers whose distances vary by less than {max_sd_mm:g} mm",
        "# over the trial, joined where the child's markers turn about one point of the",
        "# parent's frame (RMS residual of the joint's sphere fit below). The names and",
        '# the T-pose directions ("rest", the direction from a joint to its "tip") are',
        "# not in the data: rename the joints (pelvis, l_hip, l_knee... as in",
        "# vidcap/mocap/markersets/*.toml), check every parent, set rest, then run",
        "# vidcap joints TRIAL.c3d --markerset THIS.toml.",
        'name = "draft"',
        f'description = "draft from {data.path}"',
        "",
    ]
    order = [root] + [c for c, _, _, _ in links]
    fit = {c: (p, rms, rad) for c, p, rms, rad in links}
    for k in order:
        lines.append(f"[segments.{name[k]}]")
        if k == root:
            lines.append(f'joint = "{name[k]}"')
        else:
            p, rms, rad = fit[k]
            lines.append(f'parent = "{name[p]}"')
            lines.append(f'joint = "{name[p]}_{name[k]}"  # sphere fit: RMS {rms * 1e3:.1f} mm, '
                         f"markers {rad * 1e3:.0f} mm from the centre")
        lines.append(f"markers = {markers(k)}  # rigid within {spread[k] * 1e3:.1f} mm")
        if children.get(k):
            lines.append(f'tip = "{name[k]}_{name[children[k][0]]}"')
        lines.append('rest = "-y"  # guess: the T-pose direction of the tip')
        lines.append("")
    left = [k for k in range(len(groups)) if k not in name]
    if left:
        lines.append("# Not joined to the tree (no group of three markers fits them as a parent):")
        for k in left:
            lines.append(f"#   {markers(k)}")
    return "\n".join(lines).rstrip() + "\n"
