"""The subject's own proportions, estimated from a clip's silhouettes (issue 27).

The seed's model has the Table 3.1/3.2 ratios; a real subject does not. Two kinds of
evidence measure this subject's, each where it is reliable (measured on renders of
bodies scaled away from the seed's ratios, ``benchmarks/pose2d_accuracy.py
--proportions``):

* **The fit's own score over a sample of frames** (:func:`_search`): a few windows of
  consecutive frames are fitted (tracked, as the clip is) with a body whose factor
  for one group is varied, and the factor with the best mean S (Eq. 3.3) kept,
  coordinate by coordinate. S peaks clearly for the legs' share of the height (the
  pelvis sits where the legs part), the shoulders' breadth and the limbs' widths.
  Left and right are one factor (one subject, one arm length).
* **Length profiles** (:mod:`vidcap.video.fit.lengthprofile`), with the sample's
  fitted poses held: each leg split between thigh and shin (the median over the
  frames whose knee and ankle the outline pins), and the arms' length (the median
  over the frames whose hand the outline pins of each whole arm's image length,
  the sample refitted twice with it and the two pooled, :data:`ARM_ROUNDS`). S
  alone reads the arms
  long: a longer arm fits as well or a little better (Algorithm 6 draws it shorter,
  and the slack lets the fit mend a shoulder or an elbow), ~10 % long on clips whose
  arms are raised or spread (jacks, 131_01, 07_07).

Everything is relative to the standing height (head top to ankles), which stays the
metric scale (``--height``): :meth:`ProportionEstimate.body` builds the
:class:`~vidcap.body.BodyModel` the second pass of the fit, the 3D lift and the BVH
skeleton use. The head's share of head + torso stays the seed's (nothing in a
silhouette marks the neck reliably).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from vidcap.body import (
    DEFAULT_HEIGHT_M,
    PROPORTION_ALIASES,
    PROPORTION_GROUPS,
    SEGMENT_INDEX,
    SHOULDER_DROP,
    BodyModel,
    body_with_proportions,
)
from vidcap.video.fit.lengthprofile import ARMS, arm_profiles, length_profiles
from vidcap.video.masks import frames_with_pixels, touches_border

#: The factors searched by the fit's S, in this order (a group's, or a width's). The
#: arms' length searched here is only the start of its measurement by length profiles
#: (``estimate_proportions(arms=True)``, :func:`_profiled`).
SEARCHED = ("legs", "shoulders", "leg_width", "arms", "arm_width")
#: Lengths a longer model fits as well as the right one (its segments foreshortened,
#: Algorithm 6): the shortest factor whose S is within ``PLATEAU_TIE`` of the best
#: (still ~10 % long where the arms are raised or spread: jacks, 131_01, 07_07).
PLATEAU = ("arms",)
PLATEAU_TIE = 0.0015
#: Factors a search may reach (beyond: the seed's ratios are kept for that group).
LIMITS = (0.7, 1.45)
#: Relative step and steps either side of each round of the search.
STEPS = ((0.05, 4), (0.025, 3))
#: The share of the standing height above the ankles (the feet below them: the fit's
#: ``foot`` option is one minus it), and the values its search may reach.
FOOT, FOOT_LIMITS = "above_feet", (0.8, 1.0)
#: A real adult's proportions as factors on the seed's ratios (``proportions='human'``):
#: the joint heights of Drillis & Contini's anthropometric table as a fraction of the
#: stature H (Winter, *Biomechanics and Motor Control of Human Movement*, 4th ed. 2009,
#: Fig. 4.1): shoulder 0.818, elbow 0.630, wrist 0.485, knee 0.285, ankle 0.039, the
#: head's top 1; the hips at 0.500, not the table's 0.530 (its greater trochanter):
#: where MediaPipe Pose and motion-capture hip centres put them, chosen on the tuning
#: clips of ``benchmarks/pose2d_real.py`` (pose2sim_balance cam1, whose hips it centres,
#: and onebyone_room 233-445; 0.530 / 0.515 / 0.500 / 0.485 gave median joint errors
#: 7.5 / 7.5 / 7.0 / 6.7 % and 9.8 / 9.4 / 8.9 / 8.8 % of height, 0.485 putting cam1's
#: hips below MediaPipe's). The seed's model (Table 3.1) puts the shoulders at the neck
#: (0.143 H below the top, not 0.182), the elbow 0.086 H too high, the hips at the waist
#: and the ankles on the floor; a silhouette does not show where a hanging arm's elbow
#: or a standing body's hips are, so the fit cannot correct that itself. Head = top to
#: shoulders, torso = shoulders to hips, upper arm = shoulder to elbow, lower arm =
#: elbow to wrist; the ankles 0.039 H above the soles (the model ends there). The
#: model's head top is the stature's (the table's eye height 0.936 is below it). The
#: table's shoulder is the acromion, the top of the shoulder's outline, which the torso's
#: top edge follows; the shoulder *joints* (the humerus' head, where the arm turns, and
#: where MediaPipe and motion-capture skeletons put the shoulders) sit
#: ``HUMAN_SHOULDER_DROP`` = 0.022 H lower (3.9 cm at 1.75 m; the low end of published
#: offsets: Rab et al. 2002 put the joint 17 % of the biacromial breadth, ~0.038 H, below
#: an acromion skin marker), chosen a priori, not on any clip, with the upper arm
#: 0.188 - 0.022 so that a hanging elbow stays at the table's 0.630 (benchmarks/HISTORY.md,
#: session 36: against MediaPipe, 2D 7.81 -> 7.71 % of the height on the 16 real clips,
#: 3D PA-MPJPE 162.7 -> 148.2 mm).
HUMAN_SHOULDER_DROP = 0.022
HUMAN = {"head": 0.182 / (25 / 175), "torso": 0.318 / (52 / 175),
         "upper_legs": 0.215 / (46 / 175), "lower_legs": 0.246 / (52 / 175),
         "upper_arms": (0.188 - HUMAN_SHOULDER_DROP) / (25 / 175),
         "lower_arms": 0.145 / (35 / 175), FOOT: 0.961, SHOULDER_DROP: HUMAN_SHOULDER_DROP}
#: What ``proportions=`` may be: the seed's ratios, the subject's estimated from the
#: clip (:func:`estimate_proportions`), or a real adult's (:func:`human_proportions`).
PROPORTION_CHOICES = ("seed", "auto", "human")
#: Frames per window and windows per clip fitted for each candidate body.
WINDOW, WINDOWS = 30, 3
#: The arms' length is measured (:func:`_profiled`) ``ARM_ROUNDS`` times, each with the
#: model's arms at the last measurement; the median of the measurements of every round
#: but the first is kept. A model whose arms are much too long misfits them (07_07
#: 120 deg, body A: arms 1.2 / 1.3 x the truth read 1.11 / 1.10 x, 1.0 / 1.1 x read
#: 1.04 / 1.02 x), and one round's median moves by a few per cent with a small change
#: of the model (07_07: +5.8 % at arms x 0.917, +1.7 % at x 0.922): two rounds pooled.
ARM_ROUNDS = 3
#: How far (radians) from the image's vertical both segments of an arm may be for its
#: measurement to count (:func:`_profiled`).
VERTICAL = np.deg2rad(30.0)
#: The percentile of a window's model heights taken as its standing height.
STANDING = 90
#: Fewest frames that must pin a knee for the thigh/shin split to be measured.
MIN_FRAMES = 10


@dataclass(frozen=True)
class ProportionEstimate:
    """A subject's proportions as factors on the seed's ratios.

    Attributes
    ----------
    factors : dict
        Factor per name :func:`vidcap.body.body_with_proportions` takes (``legs``,
        ``upper_legs``, ``lower_legs``, ``arms``, ``shoulders``, ``leg_width``,
        ``arm_width``), applied before the lengths are rescaled to the standing height.
    evidence : dict
        Per factor, what measured it: frames fitted for a searched factor, frames
        with a determined length for a profiled one (0: kept at 1, the seed's).
    similarity : tuple of float
        Mean S of the sample windows fitted with the seed's proportions (or the
        search's ``base``) and with these
        (the parabola's vertex is kept even where a single fit there scores a little
        lower than a grid point: the fit's noise is of that size).
    """

    factors: dict = field(default_factory=dict)
    evidence: dict = field(default_factory=dict)
    similarity: tuple = (float("nan"), float("nan"))

    @property
    def foot(self) -> float:
        """The share of the standing height below the ankles (0: the seed's body)."""
        return 1.0 - self.factors.get(FOOT, 1.0)

    def body(self, height: float = DEFAULT_HEIGHT_M) -> BodyModel:
        """The body with these proportions for a subject ``height`` metres tall
        standing: its head top to ankles is ``height`` less the feet (:attr:`foot`,
        not part of the model)."""
        return body_with_proportions(height * (1.0 - self.foot),
                                     {k: v for k, v in self.factors.items() if k != FOOT})

    def ratios(self) -> dict[str, float]:
        """Length per group (pooled left/right) as a fraction of the standing height,
        and ``shoulders`` (the torso's width) likewise."""
        b = self.body(1.0)
        out = {g: b.length(segs[0]) for g, segs in PROPORTION_GROUPS.items()}
        out["shoulders"] = 2.0 * b.radius("torso")
        return out

    def summary(self) -> str:
        """One line: each length and the shoulders as % of height, and the change
        from the seed's ratio."""
        seed = ProportionEstimate().ratios()
        cells = [f"{k.replace('_', ' ')} {100 * v:.1f}% ({100 * (v / seed[k] - 1):+.0f}%)"
                 for k, v in self.ratios().items()]
        return "body proportions (of height, vs the seed's): " + ", ".join(cells)


def human_proportions() -> ProportionEstimate:
    """A real adult's proportions (:data:`HUMAN`: an anthropometric table's, nothing
    measured from the clip), for ``proportions='human'``."""
    return ProportionEstimate(factors=dict(HUMAN), evidence=dict.fromkeys(HUMAN, 0))


def sample_windows(masks, *, window: int = WINDOW, windows: int = WINDOWS) -> list[slice]:
    """Up to ``windows`` runs of ``window`` consecutive frames spread over the clip,
    each with the person wholly in the picture in every frame (the whole clip when it
    is shorter than the windows together)."""
    ok = frames_with_pixels(masks) & ~touches_border(masks)
    n = len(ok)
    if n <= window * windows:
        return [slice(0, n)] if ok.any() else []
    # runs of usable frames at least a window long; windows spread over their frames
    good = np.flatnonzero(np.convolve(ok.astype(int), np.ones(window, int), "valid")
                          == window)
    if not good.size:
        return [slice(0, n)] if ok.any() else []
    picks = good[np.unique(np.round(np.linspace(0, good.size - 1, windows)).astype(int))]
    out, last = [], -window
    for p in picks:
        if p >= last + window:  # no overlap
            out.append(slice(int(p), int(p) + window))
            last = p
    return out


def estimate_proportions(masks, *, height: int = 80, window: int = WINDOW,
                         windows: int = WINDOWS, searched=SEARCHED, steps=STEPS,
                         base: dict | None = None, arms: bool = True,
                         **fit_kw) -> ProportionEstimate:
    """Estimate the subject's proportions from a clip's silhouettes.

    Parameters
    ----------
    masks : numpy.ndarray, shape (F, H, W), bool, or MaskStack
        The clip's silhouettes.
    height : int
        The fit's normalised silhouette height (px).
    window, windows : int
        Frames per sample window and windows (:func:`sample_windows`).
    searched : sequence of str
        The factors searched by S (:data:`SEARCHED`), in order.
    steps : sequence of (float, int)
        Relative step and steps either side of the current factor, per round.
    base : dict, optional
        Factors the search starts from and multiplies (e.g. :data:`HUMAN`); the
        thigh/shin split is then the base's (not profiled). Default: the seed's.
    arms : bool
        Measure the arms' length after the search from the fitted frames' arm
        profiles (:func:`_profiled`, :data:`ARM_ROUNDS`); False: the search's
        (``'arms'`` in ``searched``) or the base's.
    **fit_kw
        Other options of :func:`vidcap.video.fit.tracking.fit_sequence`.

    Returns
    -------
    ProportionEstimate
        The seed's (all factors 1) when the clip has no usable frame.
    """
    from vidcap.video.fit.tracking import fit_sequence

    wins = sample_windows(masks, window=window, windows=windows)
    if not wins:
        return ProportionEstimate()
    n_frames = sum(len(range(len(masks))[w]) for w in wins)

    def score(factors):
        kw = fit_keywords(compose(base, factors))
        sims = [fit_sequence(masks[w], height=height, **kw, **fit_kw).similarity
                for w in wins]
        s = np.concatenate(sims)
        return float(np.mean(s[s > 0])) if (s > 0).any() else 0.0

    factors: dict[str, float] = {}
    seed_s = score(factors)
    for step, reach in steps:
        for name in searched:
            factors = _search(score, factors, name, step, reach)
    evidence = dict.fromkeys(searched, n_frames)
    split, n_split, pooled = None, 0, []
    for r in range(ARM_ROUNDS if arms else 1):
        upper, n_split, measured = _profiled(masks, wins, compose(base, factors), height,
                                             fit_kw, legs=not base, arms=arms)
        if upper is not None:
            split = _leg_split(factors, upper)
        if len(measured) < MIN_FRAMES:
            break
        values = factors.get("arms", 1.0) * np.asarray(measured)
        if r:  # the first round's model (the search's arms) may be far off: not pooled
            pooled.extend(values.tolist())
        factors["arms"] = float(np.clip(np.median(pooled if pooled else values), *LIMITS))
        evidence["arms"] = len(pooled if pooled else values)
    if split is not None:
        factors.update(split)
    evidence["upper_legs"] = evidence["lower_legs"] = n_split
    return ProportionEstimate(factors=compose(base, factors), evidence=evidence,
                              similarity=(seed_s, score(factors)))


def compose(base: dict | None, factors: dict) -> dict:
    """``factors`` applied on top of ``base`` (None: ``factors``): every group's, width's
    and the feet's factor the product of the two, aliases (``legs``, ``arms``)
    resolved to their groups (a group's own factor wins over its alias's)."""
    if not base:
        return dict(factors)

    def resolved(f: dict) -> dict:
        out = {}
        for alias, groups in PROPORTION_ALIASES.items():
            if alias in f:
                out.update(dict.fromkeys(groups, f[alias]))
        out.update({k: v for k, v in f.items() if k not in PROPORTION_ALIASES})
        return out

    b, f = resolved(base), resolved(factors)
    out = {k: b.get(k, 1.0) * f.get(k, 1.0) for k in sorted(set(b) | set(f))}
    if SHOULDER_DROP in out:  # a share of the height, not a factor: the later one's
        out[SHOULDER_DROP] = f.get(SHOULDER_DROP, b.get(SHOULDER_DROP))
    return out


def fit_keywords(factors: dict) -> dict:
    """The fit's options (``body``, ``foot``) for ``factors`` (1.70 m standing: only the
    ratios matter to a 2D fit)."""
    lengths = {k: v for k, v in factors.items() if k != FOOT}
    out = {"body": body_with_proportions(DEFAULT_HEIGHT_M, lengths)}
    if FOOT in factors:
        out["foot"] = 1.0 - factors[FOOT]
    return out


def to_ankles(model_height, fit_kw: dict | None = None):
    """The fitted model's height cut to head top → ankles, as the 3D stage takes it.

    Parameters
    ----------
    model_height : array_like, shape (F,)
        The fit's model height per frame (head top to soles), pixels.
    fit_kw : dict, optional
        The fit's options (:func:`fit_keywords`); their ``foot`` (the share of the
        height below the ankles) is left out. Without one (the seed's body, no feet)
        the height is returned as it is.

    Returns
    -------
    numpy.ndarray, shape (F,)
        Pixels.
    """
    return np.asarray(model_height) * (1.0 - (fit_kw or {}).get("foot", 0.0))


def _search(score, factors: dict, name: str, step: float, reach: int):
    """One coordinate: S at ``factors[name]`` times ``1 + k step`` for ``|k| <= reach``
    (within :data:`LIMITS`), then the vertex of a parabola fitted (least squares) to
    the best and the points within two steps of it, which steadies the choice against
    the fit's own noise (a small change of the model moves a search by a pixel here
    and there). Returns the factors with ``name``'s chosen."""
    cur = factors.get(name, 1.0)
    values = np.unique(np.clip(cur * (1 + step * np.arange(-reach, reach + 1)),
                               *(FOOT_LIMITS if name == FOOT else LIMITS)))
    s = np.array([score({**factors, name: float(v)}) for v in values])
    i = int(np.argmax(s))
    if name in PLATEAU:  # longer than the subject's fits as well, foreshortened
        i = int(np.flatnonzero(s >= s[i] - PLATEAU_TIE)[0])
        return {**factors, name: float(values[i])}
    near = np.abs(values - values[i]) <= 2.01 * step * cur
    v_best = float(values[i])
    if near.sum() >= 3:
        c = np.polyfit(values[near] - values[i], s[near], 2)
        if c[0] < 0:
            v_best = float(np.clip(values[i] - c[1] / (2 * c[0]), values[near].min(),
                                   values[near].max()))
    return {**factors, name: v_best}


def _profiled(masks, wins, factors, height, fit_kw, *, legs: bool = True,
              arms: bool = True):
    """Length profiles of the sample's frames fitted with ``factors`` (the model's
    own, base included): the thigh's share of the leg (median over the measured
    frames and legs; None below :data:`MIN_FRAMES` measurements or when not asked
    for) and how many measured it, and each measurement of an arm's length as a
    ratio to the model's (a list, empty when not asked for).

    An arm's measurement is its image length (upper arm + forearm,
    :func:`~vidcap.video.fit.lengthprofile.arm_profiles`) against the model's arm drawn
    at the window's standing height: the :data:`STANDING` percentile of the heights
    the model was drawn at (a walking silhouette is shorter than the standing body,
    and the fit draws the model at its height: 07_07 120 deg, body A, median 0.974 x
    the standing height, 90th percentile 0.996 x). Only arms whose two segments are
    within :data:`VERTICAL` of the image's vertical count, where there are
    :data:`MIN_FRAMES` of them: for a level camera an arm hanging or raised lies near
    the image plane, one held out sideways or forward may point toward the camera and
    read short (jacks 45 deg, body A, arms profiled with the true body: median of all
    0.906 x the truth, of the upright ones 0.959 x; on the other tuning clips the two
    agree within 1.3 %).

    The search's S cannot give the arms' length: a longer arm than the subject's fits
    as well or a little better (Algorithm 6 draws it shorter, and the freedom lets the
    fit correct a shoulder or an elbow), so the search's arms are long by ~10 % on
    clips where the arms are raised or spread (jacks, 131_01, 07_07); the fit with
    those long arms draws them at the image's length, which the profile reads where
    the hand's end is pinned by the outline. An arm out of the image plane reads
    short, a misfit either way: the median, not a high percentile (the determined
    frames' top decile read 1.04-1.65 x the truth on the tuning clips, their median
    1.00-1.04 x)."""
    from vidcap.video.fit.tracking import fit_sequence

    kw = fit_keywords(factors)
    body, above = kw["body"], 1.0 - kw.get("foot", fit_kw.get("foot", 0.0))
    ul = [SEGMENT_INDEX["l_upper_leg"], SEGMENT_INDEX["r_upper_leg"]]
    ll = [SEGMENT_INDEX["l_lower_leg"], SEGMENT_INDEX["r_lower_leg"]]
    ratios, arm, upright = [], [], []
    for w in wins:
        sub = masks[w]
        pose = fit_sequence(sub, height=height, **kw, **fit_kw)
        fitted = pose.similarity > 0
        standing = (float(np.percentile(pose.model_height[fitted], STANDING))
                    if fitted.any() else 0.0)
        for k in range(len(sub)):
            if not pose.similarity[k] > 0:
                continue
            args = (np.asarray(sub[k]), pose.joints2d[k], pose.angles[k],
                    pose.foreshortening[k], float(pose.spread[k]),
                    above * float(pose.model_height[k]))
            if legs:
                lengths, _ = length_profiles(*args, body=body)
                r = lengths[ul] / (lengths[ul] + lengths[ll])  # NaN where either is unknown
                ratios.extend(r[np.isfinite(r)].tolist())
            if arms:
                a = arm_profiles(*args, body=body) * float(pose.model_height[k]) / standing
                up = np.abs(np.sin(pose.angles[k][ARMS])).min(axis=1) >= np.cos(VERTICAL)
                arm.extend(a[np.isfinite(a)].tolist())
                upright.extend(up[np.isfinite(a)].tolist())
    upper = float(np.median(ratios)) if len(ratios) >= MIN_FRAMES else None
    if sum(upright) >= MIN_FRAMES:  # the arms near the image's vertical, where there are
        arm = [a for a, u in zip(arm, upright, strict=True) if u]
    return upper, len(ratios), arm


def _leg_split(factors: dict, upper: float) -> dict:
    """Thigh and shin factors splitting the legs' searched length (``factors['legs']``)
    with the thigh's share ``upper`` of it."""
    seed = BodyModel(height=1.0)
    u0, l0 = seed.length("l_upper_leg"), seed.length("l_lower_leg")
    total = factors.get("legs", 1.0) * (u0 + l0)
    return {"upper_legs": upper * total / u0, "lower_legs": (1 - upper) * total / l0}


__all__ = ["FOOT", "HUMAN", "LIMITS", "PROPORTION_CHOICES", "SEARCHED", "ProportionEstimate",
           "estimate_proportions", "fit_keywords", "human_proportions", "sample_windows",
           "to_ankles"]
