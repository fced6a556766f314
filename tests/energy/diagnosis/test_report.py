"""Tests of energy.diagnosis.report: a diagnosis reported (summary, files, a failing figure) and diagnose_report."""

from __future__ import annotations

import dataclasses
import json
import warnings

import pytest
from diagnosis_scenarios import scenario

from energy import load_current_model
from energy.diagnosis import DIAGNOSIS_FILES, DiagnosisReport, diagnose_report, model_under_diagnosis
from terrawatt_base import plot_target
from terrawatt_base.errors import FigureWarning, InvalidParameterError, UnknownNameError


@pytest.fixture(scope="module")
def case():
    """The turning case: a physics model without turning resistance, diagnosed on 3 short runs on its map."""
    sc = dataclasses.replace(scenario("turning_resistance"), n_runs=3, run_duration_s=8.0)
    logs, tmap = sc.make_logs(0), sc.terrain
    src = model_under_diagnosis("physics", logs, ground="coated_wood", without=["turning_resistance"])
    report = diagnose_report(src, logs, terrain=tmap, effects=["turning_resistance", "idle_current"], seed=1)
    return src, report, logs, tmap


def test_the_report_carries_where_its_model_comes_from(case):
    src, report, logs, tmap = case
    assert isinstance(report, DiagnosisReport) and report.logs == tuple(logs) and report.terrain is tmap
    assert report.diagnosis.model_note == src.note and "presets as given" in src.note
    assert report.diagnosis.waterfall[0].label == "as given"


def test_the_summary_is_the_verdict_then_the_waterfall(case):
    _, report, _, _ = case
    text = report.summary()
    assert text.startswith(report.diagnosis.verdict[0])
    assert report.waterfall_table() in text and "charge err %" in report.waterfall_table()
    assert len(report.waterfall_table().splitlines()) == 1 + len(report.diagnosis.waterfall)
    assert report.power_table() == "" and "battery power" not in text  # no battery power in these logs
    assert "skipped" not in text  # logs with poses and a map: every figure has its data
    bare = DiagnosisReport(report.diagnosis, report.logs)
    assert "skipped gap_map.png: " in bare.summary()


def test_write_writes_every_file(case, tmp_path):
    _, report, _, _ = case
    written = report.write(tmp_path / "out")
    assert sorted(p.name for p in written) == sorted(DIAGNOSIS_FILES)
    doc = json.loads((tmp_path / "out" / "diagnosis.json").read_text())
    assert doc["model_note"] == report.diagnosis.model_note
    assert type(load_current_model(tmp_path / "out" / "corrected_model.zip")).__name__ == "CorrectedCurrentModel"


def test_a_failing_figure_warns_naming_its_file_or_raises(case, tmp_path, monkeypatch):
    _, report, _, _ = case

    def broken(*args, **kwargs):
        raise RuntimeError("no canvas")

    monkeypatch.setattr(plot_target, "new_figure", broken)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        written = report.write(tmp_path / "a")
    assert [p.name for p in written] == ["diagnosis.json", "diagnosis.md", "corrected_model.zip"]
    messages = [str(w.message) for w in caught if issubclass(w.category, FigureWarning)]
    assert len(messages) == len(DIAGNOSIS_FILES) - 3
    assert messages[0] == f"could not draw {tmp_path / 'a' / 'residual_time.png'}: RuntimeError: no canvas"
    with pytest.raises(RuntimeError, match="no canvas"):
        report.write(tmp_path / "b", on_figure_error="raise")
    with pytest.raises(UnknownNameError, match="on_figure_error"):
        report.write(tmp_path / "c", on_figure_error="ignore")


def test_bad_arguments_are_refused(case):
    src, report, logs, _ = case
    with pytest.raises(InvalidParameterError, match="source must be a ModelUnderDiagnosis"):
        diagnose_report(src.model, logs)
    with pytest.raises(InvalidParameterError, match="diagnosis must be a Diagnosis"):
        DiagnosisReport("d", tuple(logs))
    with pytest.raises(InvalidParameterError, match="logs must be a non-empty sequence"):
        DiagnosisReport(report.diagnosis, ())
    with pytest.raises(InvalidParameterError, match="terrain must be a TerrainMap"):
        DiagnosisReport(report.diagnosis, tuple(logs), "map")
