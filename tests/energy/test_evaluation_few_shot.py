"""Tests of energy.evaluation.few_shot: a model fitted without a ground, adapted on one of its runs, scored on the others."""

import pytest
from evaluation_samples import adapt_logs, adapt_settings

from energy import LinearCurrentModel
from energy.evaluation import TRIGGER_SCHEDULE, evaluate_few_shot, few_shot_scores
from terrawatt_base.errors import InvalidParameterError


@pytest.fixture(scope="module")
def logs():
    return adapt_logs()


def test_few_shot_adapts_on_one_run_of_a_ground_left_out(logs):
    res = evaluate_few_shot(logs, LinearCurrentModel(), name="linear", settings=adapt_settings(trigger=False))
    assert {r.protocol for r in res.runs} == {"few_shot"}
    # 2 target grounds x 3 adaptation runs x 2 T x 2 other runs x 2 sides
    assert len(res.runs) == 2 * 3 * 2 * 2 * 2
    assert all(r.adapt_run != r.run and r.ground == r.adapt_run.split("/")[0] for r in res.runs)
    sand = res.row_for("sand", "linear", schedule="20 s")
    assert sand.unadapted_median_pct > 30.0  # trained on grass only: half the current
    assert sand.adapted_median_pct < 0.5 * sand.unadapted_median_pct
    one = evaluate_few_shot(logs, LinearCurrentModel(), settings=adapt_settings(trigger=False), target_grounds=["sand"])
    assert {r.ground for r in one.runs} == {"sand"}


def test_few_shot_scores_of_one_ground(logs):
    model = LinearCurrentModel().fit(logs[:3])  # grass only
    scores, totals, skipped = few_shot_scores(model, logs[3:5], ["sand/a", "sand/b"], model_name="m",
                                      settings=adapt_settings(trigger=False))
    assert not skipped
    assert {(s.run, s.adapt_run) for s in scores} == {("sand/a", "sand/b"), ("sand/b", "sand/a")}
    assert {s.schedule for s in scores} == {"10 s", "20 s"} and TRIGGER_SCHEDULE not in {s.schedule for s in scores}
    assert len(scores) == 2 * 2 * 2  # adaptation runs x T x sides
    assert all(s.protocol == "few_shot" and s.model == "m" for s in scores)
    with pytest.raises(InvalidParameterError, match="runs must be at least 2 InteractionLogs with one name each, got 1 runs"):
        few_shot_scores(model, logs[3:4], ["sand/a"], model_name="m")
    with pytest.raises(InvalidParameterError, match="got 2 runs and 1 names"):
        few_shot_scores(model, logs[3:5], ["sand/a"], model_name="m")
