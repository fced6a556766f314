"""Tests of energy.evaluation.adapt_results: AdaptScore, the adaptation rows, and the adapt protocols' EvaluationResult."""

import json
import math

import pytest
from evaluation_samples import adapt_logs, adapt_settings

from energy import LinearCurrentModel
from energy.evaluation import (
    ADAPT_FILES,
    ADAPT_FORMAT_VERSION,
    RELIABILITY_FILE,
    AdaptScore,
    EvaluationResult,
    check_evaluation_dir,
    evaluate_adaptation,
    summarise_adapt_scores,
)
from terrawatt_base.errors import InvalidParameterError, UnknownNameError
from terrawatt_base.formats import read_result_json


@pytest.fixture(scope="module")
def logs():
    return adapt_logs()


def test_writes_json_and_markdown(logs, tmp_path):
    res = evaluate_adaptation(logs[:3], LinearCurrentModel(), name="linear", settings=adapt_settings(trigger=False),
                              out_dir=tmp_path / "out")
    data = json.loads((tmp_path / "out" / ADAPT_FILES[0]).read_text())
    assert data["format"] == "terrawatt-adaptation" and data["settings"]["adapt_seconds"] == [10.0, 20.0]
    assert read_result_json(tmp_path / "out" / ADAPT_FILES[0], "adaptation", ADAPT_FORMAT_VERSION) == data  # through the one result codec
    assert len(data["runs"]) == len(res.runs) == 3 * 2 * 2
    md = (tmp_path / "out" / ADAPT_FILES[1]).read_text()
    assert "| per_ground | grass | linear | 20 s | 6 |" in md


def _score(ground: str, run: str, unadapted: float, adapted: float, protocol: str = "per_ground",
           schedule: str = "20 s", n_updates: int = 1) -> AdaptScore:
    return AdaptScore(protocol, ground, run, run, "m", "left", schedule, 20.0, 30.0, n_updates,
                      unadapted, unadapted, 1.0, adapted, adapted, 0.5, 2.0 * adapted, 2.0 * adapted, 0.7)


def test_adapt_score_checks_its_protocol():
    with pytest.raises(UnknownNameError, match=r"AdaptScore.protocol must be one of \('per_ground', 'few_shot'\), "
                                               r"got 'loo'"):
        _score("a", "a/1", 1.0, 0.5, protocol="loo")


def test_summaries_by_protocol_ground_then_all():
    scores = [_score("a", "a/1", 10.0, 2.0), _score("a", "a/2", 20.0, math.nan, n_updates=3),
              _score("b", "b/1", 30.0, 6.0), _score("b", "b/1", 5.0, 1.0, protocol="few_shot")]
    rows = summarise_adapt_scores(scores)
    assert [(s.protocol, s.ground) for s in rows] == [("per_ground", "a"), ("per_ground", "b"), ("per_ground", "all"),
                                                      ("few_shot", "b"), ("few_shot", "all")]
    a = rows[0]
    assert a.n_values == 2 and a.unadapted_median_pct == pytest.approx(15.0)
    assert a.adapted_median_pct == pytest.approx(2.0)  # NaN left out
    assert a.gain_median_pct == pytest.approx(4.0) and a.updates_mean == pytest.approx(2.0)
    assert rows[2].n_values == 3 and rows[2].unadapted_median_pct == pytest.approx(20.0)
    res = EvaluationResult(tuple(scores), rows, protocol="adapt", settings={"method": "regime"}, skipped=("short run",))
    assert res.row_for("a", "m", schedule="20 s") is rows[0]
    with pytest.raises(UnknownNameError, match="2 rows .give the schedule. for ground='all', model='m'"):
        res.row_for("all", "m")
    with pytest.raises(UnknownNameError, match="no row for ground='c', model='m', schedule='20 s'"):
        res.row_for("c", "m", schedule="20 s")
    assert res.to_dict()["runs"][1]["adapted_whole_pct"] is None and res.to_dict()["format"] == "terrawatt-adaptation"
    assert res.summary().endswith("Skipped: short run\n")
    with pytest.raises(InvalidParameterError, match="runs of protocol 'loo' must be RunScores"):
        EvaluationResult(tuple(scores), rows)


def test_check_evaluation_dir_of_the_adapt_protocols(tmp_path):
    assert check_evaluation_dir(tmp_path / "new", "adapt") == tmp_path / "new"
    (tmp_path / "f").write_text("x")
    with pytest.raises(InvalidParameterError, match="is a file"):
        check_evaluation_dir(tmp_path / "f", "few-shot")
    for name in (ADAPT_FILES[0], RELIABILITY_FILE):
        (tmp_path / name / name).mkdir(parents=True)
        with pytest.raises(InvalidParameterError, match="is a directory"):
            check_evaluation_dir(tmp_path / name, "adapt")
