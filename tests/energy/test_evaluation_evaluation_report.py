"""Tests of energy.evaluation.evaluation_report: models of named kinds evaluated by one protocol, printed and written."""

from __future__ import annotations

import json
import warnings

import pytest
from evaluation_samples import adapt_logs, score_logs

from energy.evaluation import (
    ADAPT_FILES,
    EVALUATION_FILES,
    EVALUATION_PROTOCOLS,
    RELIABILITY_FILE,
    SPECTRA_FILE,
    EvaluationResult,
    check_adapt_options,
    check_evaluation_options,
    evaluate_kinds,
    evaluation_files,
    results,
)
from energy.models import CURRENT_MODEL_KINDS, ModelOptions
from terrawatt_base.errors import FigureWarning, InvalidParameterError, UnknownNameError


def test_leave_one_run_out_is_scored_and_written_with_the_spectra(tmp_path):
    report = evaluate_kinds(score_logs(), ["constant", "linear"], variants=["per_ground"])
    assert isinstance(report, EvaluationResult) and report.protocol == "loo"
    assert report.kinds == ("constant", "linear") and len(report.logs) == 6 and report.duration_s >= 0.0
    assert report.summary().startswith("Both sides through the pack") and report.to_dict()["models"] == ["constant", "linear"]
    written = report.write(tmp_path)
    assert [p.name for p in written] == list(evaluation_files("loo")) == [*EVALUATION_FILES, SPECTRA_FILE, RELIABILITY_FILE]
    assert json.loads(written[0].read_text())["models"] == ["constant", "linear"]
    line = report.written_line(written)
    assert line.startswith("6 runs, 2 models, ") and " s on 1 worker (serial); wrote " in line
    assert line.endswith(f"{written[0]}, {written[1]}, {written[2]} and {written[3]}")


def test_a_figure_that_fails_is_a_warning_and_left_out(tmp_path, monkeypatch):
    def no_spectra(*args, **kwargs):
        raise RuntimeError("no canvas")

    monkeypatch.setattr(results, "plot_vibration_spectra", no_spectra)
    report = evaluate_kinds(score_logs(), ["constant"], variants=["per_ground"])
    with pytest.warns(FigureWarning, match="could not draw .*spectra.png: RuntimeError: no canvas"):
        written = report.write(tmp_path)
    assert [p.name for p in written] == [*EVALUATION_FILES, RELIABILITY_FILE] and not (tmp_path / SPECTRA_FILE).exists()
    assert report.written_line(written, workers="2 dask workers").endswith(f"on 2 dask workers; wrote {written[0]}, "
                                                                           f"{written[1]} and {written[2]}")
    with pytest.raises(RuntimeError, match="no canvas"):
        report.write(tmp_path / "again", on_figure_error="raise")


@pytest.mark.parametrize("protocol, trigger", [("adapt", True), ("few-shot", False)])
def test_the_adapt_protocols_write_their_files_and_reliability_figure(tmp_path, protocol, trigger):
    settings = check_adapt_options(protocol, adapt_seconds=[10.0])
    assert settings.trigger is trigger and settings.adapt_seconds == (10.0,)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # skipped folds of the short samples
        report = evaluate_kinds(adapt_logs(), ["linear"], protocol=protocol, settings=settings)
    assert report.protocol == protocol and report.kinds == ("linear",)
    assert report.to_dict()["format"] == "terrawatt-adaptation"
    written = report.write(tmp_path)
    assert [p.name for p in written] == [*ADAPT_FILES, RELIABILITY_FILE] == list(evaluation_files(protocol))
    assert report.written_line(written).endswith(f"wrote {written[0]}, {written[1]}, {written[2]}")


def test_the_default_kinds_follow_the_protocol_and_a_kind_named_twice_counts_once():
    assert check_evaluation_options() == CURRENT_MODEL_KINDS
    assert check_evaluation_options(protocol="few-shot") == ("estimator",)
    assert check_evaluation_options(["linear", "linear", "constant"]) == ("linear", "constant")
    assert EVALUATION_PROTOCOLS == ("loo", "adapt", "few-shot")


@pytest.mark.parametrize(
    "call, error, message, parameter",
    [
        (lambda: check_adapt_options(adapt_seconds=[10.0, 0.0]), InvalidParameterError,
         "adapt_seconds must be seconds > 0, got 0.0", "adapt_seconds"),
        (lambda: check_adapt_options(adapt_threshold_pct=-1.0), InvalidParameterError,
         "adapt_threshold_pct must be a percentage >= 0, got -1.0", "adapt_threshold_pct"),
        (lambda: check_adapt_options(adapt_method="guess"), UnknownNameError, "adapt_method", "adapt_method"),
        (lambda: check_adapt_options(adapt_shrink=True), UnknownNameError, "adapt_shrink must be one of", "adapt_shrink"),
        (lambda: check_adapt_options("cv"), UnknownNameError, "protocol must be one of", "protocol"),
        (lambda: check_evaluation_options(["linear"], options=ModelOptions(band_hz=(1.0, 12.0))), InvalidParameterError,
         "band_hz applies to the estimator and paper models only, got kinds linear", ("band_hz", "kinds")),
        (lambda: ModelOptions(band_hz=(12.0, 1.0)), InvalidParameterError, "band_hz must be", "band_hz"),
        (lambda: ModelOptions(seed=-1), InvalidParameterError, "seed must be None or an integer", "seed"),
        (lambda: check_evaluation_options(["forest"]), UnknownNameError, "kinds must be one of", "kinds"),
        (lambda: check_evaluation_options([]), InvalidParameterError, "kinds must name at least one model kind", "kinds"),
        (lambda: check_evaluation_options(options={"seed": 1}), InvalidParameterError, "options must be", "options"),
        (lambda: evaluate_kinds(score_logs(), ["linear"], settings=check_adapt_options()), InvalidParameterError,
         "settings applies to the adapt and few-shot protocols", ("settings", "protocol")),
        (lambda: evaluate_kinds(adapt_logs(), ["linear"], protocol="adapt", settings=check_adapt_options(
            adapt_seconds=[100.0])), InvalidParameterError, "adapt_seconds 100: no run lasts", "adapt_seconds"),
        (lambda: check_evaluation_options(["linear"], options=ModelOptions(robot="jackal")),
         InvalidParameterError, "robot applies to the physics model only, got kinds linear", ("robot", "kinds")),
        (lambda: ModelOptions(robot="rover"), UnknownNameError, "robot 'rover' is neither a robot preset", "robot"),
    ],
)
def test_bad_options_are_refused_naming_them(call, error, message, parameter):
    with pytest.raises(error, match=message) as caught:
        call()
    assert caught.value.parameter == parameter  # the command line says it by its flag


def test_the_physics_kind_is_evaluated_on_the_robot_given():
    from energy import robot_preset

    def rmse(report, model):
        return {r["ground"]: r["rmse_median_a"] for r in report.to_dict()["summary"] if r["model"] == model}

    heavy = robot_preset("husky").replace(mass_kg=120.0)
    plain = evaluate_kinds(score_logs(), ["physics", "linear"], variants=["per_ground"])
    other = evaluate_kinds(score_logs(), ["physics", "linear"], variants=["per_ground"], options=ModelOptions(robot=heavy))
    assert rmse(other, "linear") == rmse(plain, "linear")  # the robot is the physics model's only
    assert rmse(other, "physics") != rmse(plain, "physics")
