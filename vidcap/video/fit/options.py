"""The options of a fit (:class:`FitOptions`), checked once at the door.

:func:`~vidcap.video.fit.pose2d.fit_pose` builds one from its keywords and
:func:`~vidcap.video.fit.pose2d.fit_sequence` from its ``**kw`` (a misspelled option fails
there, before any frame is fitted); nothing inside the fit checks them again.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from vidcap.body import BodyModel

#: fit_pose's default: a warm fit below this share of the last S slipped
FALLBACK = 0.97


@dataclass(frozen=True)
class FitOptions:
    """How each frame is fitted (the keywords of :func:`~vidcap.video.fit.pose2d.fit_pose`).

    Attributes
    ----------
    height : int
        Height in pixels the silhouette is normalised to before fitting.
    refine, spread, verify_crossing, caps, arm_grid, leg_grid : bool
        As :func:`~vidcap.video.fit.pose2d.fit_pose` describes them.
    arm_pairs : bool
        With ``refine`` and ``arm_grid``, fresh fits also search both arms together
        (:func:`vidcap.video.fit.armpairs.search_arm_pairs`: a three-quarter view's far
        arm no longer folds across the chest to cover the near arm's elbow).
    arm_track : bool
        In tracked frames, search each whole arm over every angle pair at full length
        and keep it when it fits clearly better than the tracked arm
        (:func:`vidcap.video.fit.grids.search_arm_track`: a forearm swinging faster
        than the track's +-16 degrees a frame).
    head_zone : float
        Where an arm's elbow and wrist lie within this many head lengths of the head's
        centre (above the neck), both arms are searched again without the silhouette's
        pieces round the head that may be hair (:func:`vidcap.video.fit.headzone.
        clear_head_zone`); 0 (the default): off. Not the default: it mends arms folded
        up into a ponytail but mistakes raised arms beside the head for hair
        (benchmarks/HISTORY.md, session 32, wt-runarms).
    track_bend : bool
        Tracked frames of a body bending or crouching also move the model up and down
        and turn the torso about the pelvis (:func:`vidcap.video.fit.bend.track_bend`).
    warm_threshold : float
        Similarity of the previous pose needed to warm-start, in [0, 1].
    fallback : float
        A warm fit below ``fallback`` times the previous frame's S is redone fresh.
    warm_step_deg : float
        First step of a warm angle search, degrees (> 0).
    polish : bool
        A fresh fit that challenges a track is first refined by the tracked frame's
        searches started from it (:func:`vidcap.video.fit.frame.polished`), so it meets
        the track refined as the track is. Off by default: it steadied the fit on
        one-pixel mask changes and lifted the held-out side views 83.7 -> 85.3 %, but
        lost the three-quarter views 87.6 -> 86.6 and the mean (benchmarks/HISTORY.md).
    spread_value : float or None
        Fix the spread at this value in [0, 1] (no search).
    body_height : float or None
        The body's standing height in original pixels, when known apart from the
        silhouette's (> 0).
    tie : float
        S within which a fresh fit's alternatives (crossed legs, untangled thighs)
        count as tied (>= 0).
    body : BodyModel or None
        The subject's proportions the model is drawn with (its lengths and widths
        relative to its standing height; None: the seed's Table 3.1/3.2 ratios).
    foot : float
        The share of the standing height (head top to soles) below the ankles, where the
        model ends: a real person's feet (0: the seed's body, whose ankles are on the
        floor; in [0, 0.3)).
    """

    height: int = 80
    refine: bool = True
    spread: bool = True
    verify_crossing: bool = True
    caps: bool = False
    warm_threshold: float = 0.55
    fallback: float = FALLBACK
    warm_step_deg: float = 2.0
    polish: bool = False
    arm_grid: bool = True
    arm_pairs: bool = True
    leg_grid: bool = True
    fold_legs: bool = False
    track_bend: bool = True
    arm_track: bool = False
    head_zone: float = 0.0
    spread_value: float | None = None
    body_height: float | None = None
    tie: float = 0.01
    body: BodyModel | None = None
    foot: float = 0.0

    def __post_init__(self):
        if not (isinstance(self.height, int) or float(self.height).is_integer()) \
                or not self.height >= 1:
            raise ValueError(f"height must be a positive whole number of pixels, got "
                             f"{self.height!r}")
        for name in ("warm_threshold", "fallback", "tie", "head_zone"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")
        if not self.warm_step_deg > 0:
            raise ValueError(f"warm_step_deg must be > 0, got {self.warm_step_deg!r}")
        if self.spread_value is not None and not 0.0 <= self.spread_value <= 1.0:
            raise ValueError(f"spread_value must be in [0, 1], got {self.spread_value!r}")
        if self.body_height is not None and not self.body_height > 0:
            raise ValueError(f"body_height must be positive, got {self.body_height}")
        if not 0.0 <= self.foot < 0.3:
            raise ValueError(f"foot must be in [0, 0.3), got {self.foot!r}")
        if self.body is not None and not isinstance(self.body, BodyModel):
            raise ValueError(f"body must be a BodyModel, got {type(self.body).__name__}")

    @property
    def spread_searched(self) -> bool:
        """Whether the fit searches the torso's spread (``spread`` on, no
        ``spread_value`` fixing it)."""
        return bool(self.spread) and self.spread_value is None

    @classmethod
    def from_keywords(cls, kw: dict, *, caller: str = "fit_sequence") -> FitOptions:
        """Options from keywords such as ``fit_sequence``'s ``**kw``; unknown names
        raise TypeError (as a function's keywords do)."""
        names = {f.name for f in dataclasses.fields(cls)} - {"tie"}
        unknown = sorted(set(kw) - names)
        if unknown:
            raise TypeError(f"{caller}() got an unexpected keyword argument {unknown[0]!r}")
        return cls(**kw)


__all__ = ["FALLBACK", "FitOptions"]
