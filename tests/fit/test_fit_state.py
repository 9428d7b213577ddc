"""The fit's state value, its keep-or-revert helper and the options' door checks."""

import numpy as np
import pytest

from vidcap.video.fit.options import FitOptions
from vidcap.video.fit.state import FitState, hang, keep_if_better


def test_with_entries_returns_a_new_state_and_leaves_the_old_one():
    st = FitState.rest()
    new = st.with_entries(angles=(3, 1.0), drawn=([2, 3], True))
    assert new.angles[3] == 1.0 and new.drawn[[2, 3]].all() and not new.drawn[[0, 1, 4]].any()
    assert st.angles[3] == pytest.approx(np.deg2rad(270)) and not st.drawn.any()
    assert st.drawing(slice(None)).drawn.all()
    drawn = st.drawing(slice(None))
    assert drawn.drawing([0, 1]) is drawn  # nothing to change: the same value
    assert hang(st) == pytest.approx(np.deg2rad(270))  # torso up: arms hang down


def test_keep_if_better_keeps_gains_and_ties_and_reverts_losses():
    score = {}

    def similarity(st):
        return score[st.spread]

    start = FitState.rest(spread=0.5)
    score.update({0.5: 0.80, 0.1: 0.85, 0.2: 0.795, 0.3: 0.70})

    def to(spread):
        return lambda st: FitState.rest(spread=spread)

    assert keep_if_better(similarity, start, to(0.1), tie=0.01).spread == 0.1  # better
    assert keep_if_better(similarity, start, to(0.2), tie=0.01).spread == 0.2  # a tie
    assert keep_if_better(similarity, start, to(0.3), tie=0.01) is start  # worse
    # a negative tie: the step must gain more than it
    assert keep_if_better(similarity, start, to(0.1), tie=-0.1) is start
    # within the tie the tie-break may keep the start; a clear gain wins regardless
    assert keep_if_better(similarity, start, to(0.2), tie=0.01,
                          prefer_kept=lambda new, old: True) is start
    assert keep_if_better(similarity, start, to(0.1), tie=0.01,
                          prefer_kept=lambda new, old: True).spread == 0.1


@pytest.mark.parametrize("bad", [dict(height=0), dict(height=2.5), dict(fallback=-1.0),
                                 dict(warm_threshold=float("nan")), dict(warm_step_deg=0.0),
                                 dict(spread_value=1.5), dict(body_height=0.0)])
def test_fit_options_refuse_values_out_of_range(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        FitOptions(**bad)


def test_fit_sequence_checks_its_options_and_masks_before_fitting(monkeypatch):
    import vidcap.video.fit.tracking as tracking

    calls = []
    monkeypatch.setattr(tracking, "fit_frame", lambda *a, **k: calls.append(1))
    masks = np.zeros((3, 20, 10), bool)
    masks[:, 2:18, 4:6] = True
    with pytest.raises(TypeError, match="'heigth'"):
        tracking.fit_sequence(masks, heigth=40)
    with pytest.raises(ValueError, match="spread_value"):
        tracking.fit_sequence(masks, spread_value=2.0)
    with pytest.raises(ValueError, match=r"\(F, H, W\)"):
        tracking.fit_sequence(masks[0])
    assert calls == []


def test_a_state_keeps_its_memo_while_its_pose_is_the_same_bits():
    st = FitState.rest(spread=0.5)
    st.__dict__["_joints"] = "memo"  # what an engine memoises (_MaskEngine._posed)
    st.__dict__["_similarity"] = "S"
    same = st.with_entries(angles=(3, st.angles[3]), scores=(3, 0.7))
    assert same.__dict__.get("_joints") == "memo" and same.__dict__.get("_similarity") == "S"
    assert same.scores[3] == 0.7 and st.scores[3] == 0.0
    moved = st.with_entries(angles=(3, st.angles[3] + 1e-12))
    assert "_joints" not in moved.__dict__ and "_similarity" not in moved.__dict__
    drawn = st.drawing(3)  # the same pose, more of it drawn: the joints hold, S does not
    assert drawn.__dict__.get("_joints") == "memo" and "_similarity" not in drawn.__dict__
    assert st.replace(spread=0.5).__dict__.get("_joints") == "memo"
    assert "_joints" not in st.replace(spread=0.25).__dict__
    # a zero spread is recomputed whatever its sign (0.0 == -0.0, their joints may differ)
    zero = FitState.rest(spread=0.0)
    zero.__dict__["_joints"] = "memo"
    assert "_joints" not in zero.replace(spread=-0.0).__dict__
