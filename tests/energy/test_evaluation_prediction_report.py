"""Tests of energy.evaluation.prediction_report: a fitted model on logs, scored or predicted (an EvaluationResult of
protocol "prefit"), printed and written."""

from __future__ import annotations

import dataclasses
import json
import warnings

import pytest
from evaluation_samples import score_logs

from energy import LinearCurrentModel
from energy.evaluation import PREDICTIONS_FILE, PREDICTIONS_FORMAT_VERSION, EvaluationResult, predict_logs
from terrawatt_base import plot_target
from terrawatt_base.errors import FigureWarning, InvalidParameterError, UnknownNameError
from terrawatt_base.formats import read_result_json


@pytest.fixture(scope="module")
def fitted():
    logs = score_logs()
    return LinearCurrentModel().fit(logs), logs


def _no_currents(log):
    return dataclasses.replace(log, current_left_a=None, current_right_a=None)


def test_logs_with_currents_are_scored_and_written_with_figures(fitted, tmp_path):
    model, logs = fitted
    report = predict_logs(model, logs[:2], label="models/linear.zip")
    assert isinstance(report, EvaluationResult) and report.protocol == "prefit" and report.scored
    assert report.models == ("linear.zip",) and report.label == "models/linear.zip"
    text = report.summary().splitlines()
    assert text[0].split()[:4] == ["run", "side", "truth", "mAh"] and len(text) == 1 + 4  # two runs, two sides
    doc = report.to_dict()
    assert doc["model"] == "models/linear.zip" and {r["side"] for r in doc["runs"]} == {"left", "right"}
    written = report.write(tmp_path, figures=True)
    assert written[0] == tmp_path / PREDICTIONS_FILE and json.loads(written[0].read_text()) == json.loads(
        json.dumps(doc))
    assert [p.name for p in written[1:]] == ["current_grass_pro_00.png", "current_grass_pro_01.png"]
    assert report.written_line(written, figures=True) == f"wrote {written[0]} and 2 figures in {tmp_path / 'plots'}"
    assert report.written_line(written[:1]) == f"wrote {written[0]}"


def test_logs_without_currents_are_predicted_only(fitted, tmp_path):
    model, logs = fitted
    report = predict_logs(model, [logs[0], _no_currents(logs[1])], label="m.zip")
    assert not report.scored and len(report.predictions) == 2 and report.runs == ()
    with pytest.raises(InvalidParameterError, match="predictions are the answer of protocol 'prefit'"):
        EvaluationResult((), (), predictions=report.predictions)
    lines = report.summary().splitlines()
    assert "pred L mAh" in lines[0] and lines[2].split()[3:5] == ["-", "-"]  # nothing measured on the second
    assert report.to_dict()["scored"] is False
    written = report.write(tmp_path, figures=True)
    assert written == [tmp_path / PREDICTIONS_FILE] and not (tmp_path / "plots").exists()
    assert read_result_json(written[0], "predictions", PREDICTIONS_FORMAT_VERSION)["scored"] is False
    assert report.written_line(written, figures=True) == (
        f"1 of 2 logs have no measured currents: predictions only, no errors; wrote {written[0]} "
        "(no figures: they compare with measured currents)")


def test_a_failing_figure_warns_or_raises(fitted, tmp_path, monkeypatch):
    model, logs = fitted
    report = predict_logs(model, logs[:1])

    def broken(*args, **kwargs):
        raise RuntimeError("no canvas")

    monkeypatch.setattr(plot_target, "new_figure", broken)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert report.write(tmp_path / "a", figures=True) == [tmp_path / "a" / PREDICTIONS_FILE]
    assert any(issubclass(w.category, FigureWarning) and "no canvas" in str(w.message) for w in caught)
    with pytest.raises(RuntimeError, match="no canvas"):
        report.write(tmp_path / "b", figures=True, on_figure_error="raise")
    with pytest.raises(UnknownNameError, match="on_figure_error"):
        report.write(tmp_path / "c", on_figure_error="later")


def test_bad_arguments_are_refused(fitted):
    model, logs = fitted
    with pytest.raises(InvalidParameterError, match="model must be a CurrentModel"):
        predict_logs("linear", logs)
    with pytest.raises(InvalidParameterError, match="logs must be"):
        predict_logs(model, [])
    with pytest.raises(InvalidParameterError, match="label"):
        predict_logs(model, logs, label=" ")
