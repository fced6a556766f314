"""Tests of energy.evaluation.results: RunScore, the summary rows, EvaluationResult and its JSON / markdown files."""

import json
import math

import numpy as np
import pytest
from evaluation_samples import score_logs

from energy import ConstantCurrentModel, LinearCurrentModel, evaluate_current_models
from energy.evaluation import (
    EVALUATION_FILES,
    EVALUATION_FORMAT_VERSION,
    RELIABILITY_FILE,
    EvaluationResult,
    RunScore,
    check_evaluation_dir,
    summarise_scores,
)
from terrawatt_base.errors import InvalidParameterError, UnknownNameError
from terrawatt_base.formats import read_result_json


@pytest.fixture(scope="module")
def result():
    return evaluate_current_models(score_logs(), {"constant": ConstantCurrentModel(), "linear": LinearCurrentModel()})


def test_summary_percentiles(result):
    rows = [r.whole_run_error_pct for r in result.runs
            if (r.variant, r.model, r.ground) == ("ground_agnostic", "constant", "sand")]
    s = result.row_for("sand", "constant", variant="ground_agnostic")
    assert s.whole_run_median_pct == pytest.approx(float(np.median(rows)))
    assert s.whole_run_p90_pct == pytest.approx(float(np.percentile(rows, 90)))
    with pytest.raises(UnknownNameError, match="no row for ground='ice', model='constant', variant='per_ground'"):
        result.row_for("ice", "constant", variant="per_ground")
    with pytest.raises(UnknownNameError, match="2 rows .give the variant"):
        result.row_for("sand", "constant")


def test_json_and_markdown_outputs(result, tmp_path):
    written = result.write(tmp_path)
    assert [p.name for p in written] == [*EVALUATION_FILES, RELIABILITY_FILE]  # no logs in the result: no spectra
    data = json.loads(written[0].read_text())
    assert data["format_version"] == EVALUATION_FORMAT_VERSION and data["models"] == ["constant", "linear"]
    assert len(data["runs"]) == len(result.runs) and len(data["summary"]) == len(result.rows)
    md = result.summary()
    battery, per_side = md.split("Per side (charge of each motor channel):")
    assert per_side.strip().count("\n") == 1 + len(result.rows)  # header, rule and one row per summary
    assert battery.count("| loo | all | linear | ground_agnostic | unadapted |") == 1  # the battery table: one row each
    assert len(data["totals"]) == len(result.runs) // 2 and len(data["total_summary"]) == len(result.total_summary())
    assert "| per_ground | sand | linear |" in md
    assert written[1].read_text() == md


def _score(run: str, ground: str, whole_pct: float, side: str = "left", variant: str = "per_ground") -> RunScore:
    return RunScore(variant, ground, run, "m", side, 10.0, 100.0, 100.0 + whole_pct, whole_pct, 2.0 * whole_pct, 0.1, 0.5)


def test_run_score_checks_its_variant_and_side():
    with pytest.raises(UnknownNameError, match=r"RunScore.variant must be one of \('per_ground', 'ground_agnostic', "
                                               r"'prefit'\), got 'cross'"):
        _score("a/1", "a", 1.0, variant="cross")
    with pytest.raises(UnknownNameError, match="RunScore.side must be one of"):
        _score("a/1", "a", 1.0, side="middle")


def test_summaries_per_ground_then_all_with_undefined_scores_left_out():
    scores = [_score("a/1", "a", 1.0), _score("a/1", "a", 3.0, side="right"), _score("a/2", "a", math.nan),
              _score("b/1", "b", 10.0)]
    rows = summarise_scores(scores, ("per_ground", "ground_agnostic"), ["a", "b"], ("m", "other"))
    assert [(s.variant, s.ground, s.model) for s in rows] == [("per_ground", "a", "m"), ("per_ground", "b", "m"),
                                                              ("per_ground", "all", "m")]
    a, _, pooled = rows
    assert (a.n_runs, a.n_values, a.n_undefined) == (2, 3, 1)
    assert a.whole_run_median_pct == pytest.approx(2.0) and a.section_median_pct == pytest.approx(4.0)
    assert pooled.whole_run_median_pct == pytest.approx(3.0) and pooled.n_runs == 3
    assert pooled.whole_run_p90_pct == pytest.approx(float(np.percentile([1.0, 3.0, 10.0], 90)))


def test_a_result_with_nan_and_skipped_grounds_writes_its_folder(tmp_path):
    scores = [_score("a/1", "a", math.nan), _score("a/2", "a", 4.0)]
    res = EvaluationResult(tuple(scores), summarise_scores(scores, ("per_ground",), ["a"], ("m",)), models=("m",),
                           variants=("per_ground",), section_s=30.0, skipped=("ground 'ice' has 1 run",))
    json_path, md_path, _ = res.write(tmp_path / "out")
    assert (json_path.name, md_path.name) == EVALUATION_FILES
    data = json.loads(json_path.read_text())
    assert data["format"] == "terrawatt-evaluation" and data["runs"][0]["whole_run_error_pct"] is None
    assert read_result_json(json_path, "evaluation", EVALUATION_FORMAT_VERSION) == data  # through the one result codec
    md = md_path.read_text()
    assert "30 s sections median %" in md and md.endswith("Skipped: ground 'ice' has 1 run\n")


def test_check_evaluation_dir_refuses_a_file_and_a_directory_in_place_of_a_result_file(tmp_path):
    assert check_evaluation_dir(tmp_path / "new") == tmp_path / "new"
    (tmp_path / "f").write_text("x")
    with pytest.raises(InvalidParameterError, match="is a file"):
        check_evaluation_dir(tmp_path / "f")
    (tmp_path / "d" / EVALUATION_FILES[1]).mkdir(parents=True)
    with pytest.raises(InvalidParameterError, match="is a directory"):
        check_evaluation_dir(tmp_path / "d")
