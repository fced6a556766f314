"""Tests of energy.diagnosis.selection: significance, greedy selection on held-out data, the plausible alternative."""

import pytest
from gain_samples import gained_logs_and_model

from energy.diagnosis import effect, make_split
from energy.diagnosis.case import prepare_data
from energy.diagnosis.fit import SetRunner, score_effect_set
from energy.diagnosis.result import EffectScore
from energy.diagnosis.selection import SIGNIFICANT_SHRINK_PCT, plausible_alternative, select_effects, significant


@pytest.fixture(scope="module")
def case():
    logs, model = gained_logs_and_model()
    effects = [effect("current_gain"), effect("idle_current")]
    return effects, prepare_data(model, logs, effects, split=make_split(logs, "runs", n_blocks=4))


def test_the_gain_is_significant_and_nothing_improves_on_itself(case):
    (gain, _), data = case
    none, with_gain = score_effect_set([], data), score_effect_set([gain], data)
    assert significant(none, with_gain, none, n_bootstrap=50, seed=0)
    assert not significant(with_gain, with_gain, none, n_bootstrap=50, seed=0)  # 0 points gained
    assert SIGNIFICANT_SHRINK_PCT == 2.0


def test_greedy_selection_chooses_the_gain_first_and_scores_every_candidate(case):
    effects, data = case
    sel = select_effects(effects, SetRunner(data), n_bootstrap=50, seed=0)
    assert sel.chosen[0].name == "current_gain" and sel.order[0].name == "current_gain"
    assert set(sel.scores) == {"current_gain", "idle_current"} and set(sel.alone) == set(sel.scores)
    assert len(sel.sets) == len(sel.chosen) + 1 and sel.sets[0] is sel.none
    top = sel.scores["current_gain"]
    assert top.shrink_pct > 95.0 and top.added_pct == pytest.approx(top.shrink_pct)
    assert top.parameters["gain_left"] == pytest.approx(1.3, rel=0.03)
    assert top.parameters["gain_right"] == pytest.approx(0.8, rel=0.03)


def _score(name, shrink, interval=(0.0, 100.0), kind="parameter", alone_flags=()):
    return EffectScore(name, kind, {}, shrink, interval, 1, alone_flags=alone_flags)


def test_the_plausible_alternative_explains_a_similar_gap_with_unflagged_values():
    doubtful = _score("motor_constant", 50.0, interval=(40.0, 60.0))
    ranking = [doubtful, _score("mass", 45.0), _score("gear_losses", 55.0, alone_flags=("pinned",)),
               _score("learned_residual", 58.0, kind="learned"), _score("idle_current", 30.0), _score("inertia", 41.0)]
    assert plausible_alternative(doubtful, ranking).name == "mass"
    assert plausible_alternative(doubtful, ranking, chosen=("mass",)).name == "inertia"
    assert plausible_alternative(doubtful, ranking, chosen=("mass", "inertia")) is None
