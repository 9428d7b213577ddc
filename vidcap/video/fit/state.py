"""The state of one frame's fit: a frozen :class:`FitState`, and :func:`keep_if_better`.

Every move of the fit (:mod:`vidcap.video.fit.moves`, :mod:`vidcap.video.fit.torso`, ...) takes a
:class:`FitState` and returns a new one; nothing changes a state in place, so a move
that turns out worse is undone by keeping the state it started from
(:func:`keep_if_better`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from vidcap.video.fit.limits import REST_DEG, TWO_PI, S


@dataclass(frozen=True)
class FitState:
    """One pose of the 2D model and what its searches measured (normalised pixels).

    Attributes
    ----------
    root : numpy.ndarray, shape (2,)
        The pelvis ``(x, y)``, normalised pixels, y down.
    angles : numpy.ndarray, shape (10,)
        Image-plane angle of every segment (:data:`vidcap.body.SEGMENT_NAMES` order),
        radians, counter-clockwise from +x with y up.
    fore : numpy.ndarray, shape (10,)
        Foreshortening (drawn / full length) of every segment, in (0, 1].
    spread : float
        Lateral spread of shoulders and hips, 0 (side view) to 1 (front view).
    scores, margins : numpy.ndarray, shape (10,)
        Each segment's last search: its best S and best minus runner-up.
    drawn : numpy.ndarray, shape (10,), bool
        The segments that are part of the model (drawn when scoring).

    The arrays are never written to: :meth:`with_entries` and
    :func:`dataclasses.replace` return new states.
    """

    root: np.ndarray
    angles: np.ndarray
    fore: np.ndarray
    spread: float
    scores: np.ndarray
    margins: np.ndarray
    drawn: np.ndarray

    @classmethod
    def rest(cls, *, spread: float = 0.5) -> FitState:
        """The rest pose (torso and head up, limbs down, unforeshortened), nothing drawn,
        the root at the origin."""
        return cls(np.zeros(2), np.deg2rad(REST_DEG), np.ones(10), float(spread),
                   np.zeros(10), np.zeros(10), np.zeros(10, dtype=bool))

    def replace(self, **changes) -> FitState:
        """:func:`dataclasses.replace` without its per-call set-up (every move makes
        a state): the fields in ``changes`` replaced, the rest shared. What an engine
        memoised on this state (its joints, its S) goes along where the fields it
        depends on are unchanged (bit for bit: a search that ends where it started
        costs no new joints)."""
        new = object.__new__(FitState)
        memo = new.__dict__
        old = self.__dict__
        memo.update(old)
        memo.update(changes)
        if "_joints" in old or "_similarity" in old:
            _forget(memo, old, changes)
        return new

    def with_entries(self, **entries) -> FitState:
        """A copy with some entries of array fields set: ``field=(index, values)``
        (``index`` as numpy indexing takes it), e.g. ``st.with_entries(angles=(3, a),
        drawn=([2, 3], True))``."""
        new = object.__new__(FitState)
        memo = new.__dict__
        old = self.__dict__
        memo.update(old)
        check = "_joints" in old or "_similarity" in old  # a memo to keep or drop
        for name, (index, values) in entries.items():
            was = old[name]
            a = was.copy()
            a[index] = values
            memo[name] = a
            # _forget inlined (the hottest call of the fit): a copy has the dtype and
            # shape it was copied from, so the bytes tell
            if check and name in _MEMOISED_ON and a.tobytes() != was.tobytes():
                memo.pop("_similarity", None)
                if name != "drawn":
                    memo.pop("_joints", None)
                    check = False
        return new

    def drawing(self, segments) -> FitState:
        """This state with ``segments`` drawn (``slice(None)``: all of them)."""
        drawn = self.drawn
        if segments.__class__ is int:  # the common cases without numpy's reductions
            if drawn[segments]:
                return self
        elif segments.__class__ is slice and segments == _ALL:
            if drawn.tobytes() == _ALL_DRAWN:
                return self
        elif drawn[segments].all():
            return self
        return self.with_entries(drawn=(segments, True))


_POSE = frozenset({"root", "angles", "fore", "spread"})  # what the joints depend on
_MEMOISED_ON = _POSE | {"drawn"}  # what the joints and S depend on
_ALL = slice(None)
_ALL_DRAWN = np.ones(10, dtype=bool).tobytes()


def _same(a, b) -> bool:
    """``a`` and ``b`` hold the same bits (arrays: also the same dtype and shape)."""
    if a is b:
        return True
    if isinstance(a, np.ndarray):
        return (isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape
                and a.tobytes() == b.tobytes())
    # a float (the spread): equal and not a zero (0.0 and -0.0 compare equal)
    return type(a) is type(b) and a == b and a != 0


def _forget(memo: dict, old: dict, changed) -> None:
    """Drop from a new state's ``memo`` what an engine memoised on the ``old`` state
    and the ``changed`` fields invalidate (joints: the pose; S: the pose or drawn)."""
    for name in changed:
        if name in _POSE and not _same(memo[name], old[name]):
            memo.pop("_joints", None)
            memo.pop("_similarity", None)
            return
    if "drawn" in changed and not _same(memo["drawn"], old["drawn"]):
        memo.pop("_similarity", None)


def hang(st: FitState) -> float:
    """The direction of an arm hanging along the torso of ``st``, radians."""
    return float(np.mod(st.angles[S["torso"]] + np.pi, TWO_PI))


def keep_if_better(similarity: Callable[[FitState], float], st: FitState,
                   step: Callable[[FitState], FitState], *, tie: float,
                   prefer_kept: Callable[[FitState, FitState], bool] | None = None) -> FitState:
    """Try ``step`` on ``st``; keep its state unless it fits worse.

    Parameters
    ----------
    similarity : callable
        S of a state (:meth:`vidcap.video.fit.engine._MaskEngine.similarity`).
    st : FitState
        The state to start from (returned when the step is undone).
    step : callable
        ``step(st) -> FitState``, the move tried.
    tie : float
        S the new state may lose and still be kept (negative: it must gain more
        than ``-tie``).
    prefer_kept : callable, optional
        ``prefer_kept(new, st) -> bool``: within ``abs(tie)`` of ``st``'s S (or
        above it), a True here keeps ``st`` all the same (a tie-break such as
        straighter legs, or an arm nearer its prior).

    Returns
    -------
    FitState
        The step's state, or ``st``.
    """
    s_kept = similarity(st)
    new = step(st)
    s_new = similarity(new)
    if s_new < s_kept - tie:
        return st
    if prefer_kept is not None and s_new <= s_kept + abs(tie) and prefer_kept(new, st):
        return st
    return new


__all__ = ["FitState", "hang", "keep_if_better"]
