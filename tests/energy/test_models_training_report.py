"""Tests of energy.models.training_report: a model of a kind trained on logs, its options checked, reported, saved."""

from __future__ import annotations

import json

import numpy as np
import pytest
from evaluation_samples import score_logs

from energy.models import (
    LEARNED_KINDS,
    TRAINING_FORMAT_VERSION,
    ModelOptions,
    TrainingReport,
    check_learned_band,
    check_training_options,
    load_current_model,
    train_report,
)
from terrawatt_base.errors import InvalidParameterError, UnknownNameError


def test_a_baseline_gets_a_cross_validated_interval_and_says_so(tmp_path):
    logs = score_logs()
    report = train_report("linear", logs, interval_folds=3)
    assert isinstance(report, TrainingReport) and report.kind == "linear" and len(report.logs) == 6
    assert report.model.gives_interval and report.band_hz is None and report.fit_duration_s >= 0.0
    line = report.summary()
    assert line.startswith(f"fitted linear on 6 runs ({report.logs_duration_s:.0f} s of logs) with a forecast interval")
    path = report.write(tmp_path / "m.zip")
    assert path == tmp_path / "m.zip" and load_current_model(path).gives_interval
    assert "\n" not in line and "wrote" not in line  # the command adds the file it wrote


def test_the_report_as_a_dict_says_what_was_fitted_on_what_with_which_interval():
    report = train_report("linear", score_logs(), interval_folds=3)
    doc = report.to_dict()
    assert json.loads(json.dumps(doc, allow_nan=False)) == doc  # plain, strict JSON
    assert doc["format"] == "terrawatt-training" and doc["format_version"] == TRAINING_FORMAT_VERSION
    assert doc["kind"] == "linear" and doc["model_class"] == "LinearCurrentModel" and doc["n_runs"] == 6
    assert doc["grounds_s"] == pytest.approx({"grass": 3 * report.logs[0].duration_s,
                                              "sand": 3 * report.logs[3].duration_s})
    assert [r["run"] for r in doc["runs"]] == ["grass/pro_00", "grass/pro_01", "grass/pro_02",
                                              "sand/pro_10", "sand/pro_11", "sand/pro_12"]
    assert [r["ground"] for r in doc["runs"]] == ["grass"] * 3 + ["sand"] * 3
    assert doc["logs_duration_s"] == pytest.approx(report.logs_duration_s) and doc["band_hz"] is None
    assert doc["gives_interval"] and doc["interval"]["cross_validated"] and doc["interval"]["n_runs"] == 6
    assert doc["interval"]["n_grounds"] == 2 and doc["interval"]["new_ground_dof"] == 2.0  # a t with 2 dof
    bare = train_report("constant", score_logs()[:1], interval_folds=0).to_dict()
    assert bare["interval"] is None and not bare["gives_interval"] and bare["grounds_s"].keys() == {"grass"}


def test_the_run_charges_are_the_fitted_model_given_back_its_training_runs():
    logs = score_logs()
    report = train_report("linear", logs, interval_folds=3)
    rows = report.run_charges(0.8)
    assert [r.ground for r in rows] == ["grass"] * 3 + ["sand"] * 3
    for row, log in zip(rows, logs):
        measured = np.trapezoid(log.current_left_a + log.current_right_a, log.time_s)
        fitted = np.trapezoid(report.model.predict(log).sum(axis=1), log.time_s)
        assert row.measured_as == pytest.approx(measured) and row.fitted_as == pytest.approx(fitted)
        assert row.low_as < row.fitted_as < row.high_as
    # the linear model does not see the ground (sand draws 2.5 times grass): a least-squares fit with an
    # intercept gives the charge of all runs back, over on grass and under on sand - what the figure shows
    assert sum(r.fitted_as for r in rows) == pytest.approx(sum(r.measured_as for r in rows), rel=1e-3)
    assert all(r.fitted_as > 1.5 * r.measured_as for r in rows[:3])
    assert all(r.fitted_as < 0.8 * r.measured_as for r in rows[3:])
    wider = report.run_charges(0.95)
    assert all(w.high_as - w.low_as > r.high_as - r.low_as for w, r in zip(wider, rows))
    point = train_report("constant", logs, interval_folds=0).run_charges()
    assert all(np.isnan(r.low_as) and np.isnan(r.high_as) for r in point)
    with pytest.raises(InvalidParameterError, match="level"):
        report.run_charges(1.0)


def test_the_figure_draws_a_point_per_run_with_its_interval(tmp_path):
    from matplotlib.figure import Figure

    report = train_report("linear", score_logs(), interval_folds=3)
    ax = Figure().subplots()
    assert report.plot(ax=ax) is ax
    rows = report.run_charges()
    drawn = np.concatenate([line.get_xydata() for line in ax.lines if line.get_marker() == "o"])
    expected = np.array([[r.measured_as, r.fitted_as] for r in rows]) * (1000.0 / 3600.0)
    assert drawn.shape == (6, 2) and np.allclose(np.sort(drawn, axis=0), np.sort(expected, axis=0))
    assert len(ax.collections) == 2  # the interval bars of both grounds
    assert sorted(t.get_text() for t in ax.get_legend().get_texts()) == ["fitted = measured", "grass", "sand"]
    path = report.plot(tmp_path / "fit.png")
    assert path == tmp_path / "fit.png" and path.stat().st_size > 0
    with pytest.raises(InvalidParameterError, match="either path"):
        report.plot()


@pytest.mark.parametrize("folds, logs", [(0, score_logs()), (5, score_logs()[:1])])
def test_no_interval_without_folds_or_with_one_run(folds, logs):
    report = train_report("constant", logs, interval_folds=folds)
    assert not report.model.gives_interval and "without a forecast interval" in report.summary()


@pytest.mark.parametrize(
    "kwargs, error, message, parameter",
    [
        ({"n_threads": 0}, InvalidParameterError, "n_threads must be a positive number of threads, got 0", "n_threads"),
        ({"kind": "linear", "n_threads": 2}, InvalidParameterError,
         "n_threads applies to the estimator and paper models only, got kind 'linear'", ("n_threads", "kind")),
        ({"interval_folds": 1}, InvalidParameterError, r"interval_folds must be 0 \(no interval\) or >= 2, got 1",
         "interval_folds"),
        ({"interval_folds": -1}, InvalidParameterError, "interval_folds must be 0", "interval_folds"),
        ({"kind": "constant", "options": lambda: ModelOptions(band_hz=(1.0, 20.0))}, InvalidParameterError,
         "band_hz applies to the estimator and paper models only, got kind constant", ("band_hz", "kind")),
        ({"kind": "linear", "options": lambda: ModelOptions(robot="jackal")}, InvalidParameterError,
         "robot applies to the physics model only, got kind linear", ("robot", "kind")),
        ({"options": lambda: {"seed": 1}}, InvalidParameterError, "options must be", "options"),
        ({"kind": "forest"}, UnknownNameError, "kind must be one of", "kind"),
    ],
)
def test_bad_options_are_refused_naming_them(kwargs, error, message, parameter):
    kind = kwargs.pop("kind", "paper")
    if "options" in kwargs:
        kwargs["options"] = kwargs["options"]()
    with pytest.raises(error, match=message) as raised:
        check_training_options(kind, **kwargs)
    assert raised.value.parameter == parameter  # a front end says it in its own words (terrawatt_cli.error_message)
    with pytest.raises(error, match=message):  # train_report checks them before fitting
        train_report(kind, score_logs()[:1], **kwargs)


def test_a_band_needs_a_learned_kind():
    assert set(LEARNED_KINDS) == {"estimator", "paper"}
    assert check_learned_band(None, ["linear"]) is None
    assert check_learned_band((1, 20), ["linear", "paper"]) == (1.0, 20.0)
    with pytest.raises(InvalidParameterError, match="band_hz applies to the estimator and paper models only, got kind "
                       "linear constant"):
        check_learned_band((1, 20), ["linear", "constant"])


def test_no_logs_is_refused():
    with pytest.raises(InvalidParameterError, match="logs"):
        train_report("constant", [])


def test_the_physics_kind_is_fitted_on_the_robot_given_and_keeps_it(tmp_path):
    from energy import robot_preset
    from energy.params import write_robot_file

    logs = score_logs()
    rover = robot_preset("jackal").replace(name="rover", mass_kg=25.0)
    write_robot_file(rover, tmp_path / "rover.json")
    husky = train_report("physics", logs, interval_folds=0).model
    report = train_report("physics", logs, interval_folds=0, options=ModelOptions(robot=tmp_path / "rover.json"))
    assert husky.robot == "husky" and report.model.robot == rover and report.model.robot_ == rover
    assert train_report("physics", logs, interval_folds=0, options=ModelOptions(robot="jackal")).model.robot == "jackal"
    back = load_current_model(report.write(tmp_path / "physics.zip"))
    assert back.robot_ == rover and (back.predict(logs[0]) == report.model.predict(logs[0])).all()
    with pytest.raises(InvalidParameterError, match="robot applies to the physics model only, got kind linear"):
        check_training_options("linear", options=ModelOptions(robot="jackal"))
    with pytest.raises(UnknownNameError, match="robot 'rover' is neither a robot preset"):
        ModelOptions(robot="rover")


@pytest.mark.parametrize(
    "kwargs, error, message, parameter",
    [
        ({"band_hz": (5.0, 1.0)}, InvalidParameterError, "band_hz must be", "band_hz"),
        ({"seed": -1}, InvalidParameterError, "seed must be None or an integer", "seed"),
        ({"robot": "rover9"}, UnknownNameError, "robot 'rover9' is neither", "robot"),
    ],
)
def test_model_options_are_checked_when_made(kwargs, error, message, parameter):
    with pytest.raises(error, match=message) as raised:
        ModelOptions(**kwargs)
    assert raised.value.parameter == parameter


def test_model_options_give_the_band_to_the_learned_kinds_and_the_robot_to_physics():
    options = ModelOptions(seed=3, band_hz=[0, 20], robot="jackal")
    assert options.band_hz == (0.0, 20.0)
    assert options.new_model("physics").robot == "jackal" and options.new_model("estimator").seed == 3
    assert options.new_model("estimator").config.band_hz == (0.0, 20.0)
    options.check_kinds(["estimator", "physics"])  # both apply
    with pytest.raises(InvalidParameterError, match="band_hz applies to the estimator and paper models only"):
        options.check_kinds(["physics"])
