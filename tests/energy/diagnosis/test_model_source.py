"""Tests of energy.diagnosis.model_source: the model under diagnosis, checked before any work, never fitted on its logs."""

from __future__ import annotations

import dataclasses

import pytest
from diagnosis_scenarios import scenario

from energy import PhysicsCurrentModel
from energy.diagnosis import ModelUnderDiagnosis, check_model_source, model_under_diagnosis
from terrawatt_base.errors import InvalidParameterError, UnknownNameError


@pytest.fixture(scope="module")
def runs():
    """Three 8 s runs of the turning case (its ground a preset), each its own source, and a physics model."""
    sc = dataclasses.replace(scenario("turning_resistance"), n_runs=3, run_duration_s=8.0)
    logs = [dataclasses.replace(log, meta=dataclasses.replace(log.meta, source=f"run_{k}.csv"))
            for k, log in enumerate(sc.make_logs(0))]
    return logs, sc.make_model(0)


def test_the_kind_of_each_source(tmp_path, runs):
    path = runs[1].save(tmp_path / "m.zip")
    assert check_model_source("physics", robot="husky", ground="asphalt", without=["inertia"]) == "physics"
    assert check_model_source("estimator", calibration=[1]) == "estimator"
    assert check_model_source(path) == check_model_source(str(path)) == "file"


@pytest.mark.parametrize("model, kwargs, error, message, parameter", [
    ("nowhere.zip", {}, InvalidParameterError, "`model` must be 'physics', 'estimator' or a model file; 'nowhere.zip'",
     "model"),
    (3, {}, InvalidParameterError, "`model` must be a string or a path", "model"),
    ("physics", {"robot": "rover"}, UnknownNameError, "robot 'rover' is neither a robot preset", "robot"),
    ("physics", {"ground": "lava"}, UnknownNameError, "`ground` 'lava' is not a ground preset", "ground"),
    ("physics", {"without": ["warp"]}, UnknownNameError, r"`without` \['warp'\]: not physics drive effects",
     "without"),
    ("physics", {"without": ["inertia", "inertia"]}, InvalidParameterError, "`without` names an effect twice",
     "without"),
    ("estimator", {"ground": "sand"}, InvalidParameterError, "`ground` applies to `model` physics only",
     ("ground", "model")),
    ("estimator", {"calibration": None, "without": ["inertia"]}, InvalidParameterError,
     "`without` applies to `model`", ("without", "model")),
    ("estimator", {}, InvalidParameterError, "`model` estimator needs `calibration`", ("model", "calibration")),
])
def test_bad_sources_are_refused_naming_the_argument(model, kwargs, error, message, parameter):
    with pytest.raises(error, match=message) as raised:
        check_model_source(model, **kwargs)
    assert raised.value.parameter == parameter  # the command line says it by its flag
    assert "--" not in str(raised.value)


def test_a_file_with_calibration_runs_is_refused_naming_both(tmp_path, runs):
    path = runs[1].save(tmp_path / "m.zip")
    with pytest.raises(InvalidParameterError, match="`calibration` applies to `model` physics or estimator") as raised:
        check_model_source(path, calibration="cal")
    assert raised.value.parameter == ("calibration", "model")


def test_the_physics_as_given_is_not_fitted_on_the_logs(runs):
    logs, _ = runs
    src = model_under_diagnosis("physics", logs, without=["turning_resistance"])
    assert isinstance(src, ModelUnderDiagnosis) and isinstance(src.model, PhysicsCurrentModel)
    assert src.kind == "physics" and src.reference_robot is None
    ground = logs[0].meta.ground_label
    assert src.note.startswith(f"physics, the husky and {ground} presets as given without turning_resistance")
    assert "not fitted on the 3 runs it is diagnosed on" in src.note
    assert src.model.fitted_ == {}  # no coefficient fitted
    every = model_under_diagnosis("physics", logs, ground="asphalt", robot="husky")
    assert "husky and asphalt presets as given (every drive effect)" in every.note


def test_the_physics_is_calibrated_on_other_runs_only(runs):
    logs, _ = runs
    src = model_under_diagnosis("physics", logs[:1], calibration_logs=logs[1:], calibration_label="cal/")
    assert "coefficients fitted on the 2 runs of cal/" in src.note and "which are not diagnosed" in src.note
    assert src.model.fitted_ and all(f"{k} = " in src.note for k in src.model.fitted_)
    with pytest.raises(InvalidParameterError, match=r"`calibration_logs` holds runs that `logs` diagnoses too: "
                       r"\['run_1.csv'\]; calibrate on runs that are not diagnosed") as raised:
        model_under_diagnosis("physics", logs[:2], calibration_logs=logs[1:])
    assert raised.value.parameter == ("calibration_logs", "logs")
    with pytest.raises(InvalidParameterError, match="logs must be a non-empty sequence"):
        model_under_diagnosis("physics", [])


def _renamed(log, **meta):
    return dataclasses.replace(log, meta=dataclasses.replace(log.meta, **meta))


def test_calibration_runs_that_cannot_calibrate_are_refused_naming_them(runs):
    import numpy as np

    logs, _ = runs
    diagnosed, cal = logs[:1], logs[1:]
    # a byte-identical copy of a diagnosed run under another name, its clock shifted
    copy = dataclasses.replace(_renamed(logs[0], source="copy.csv"), time_s=logs[0].time_s + 100.0)
    with pytest.raises(InvalidParameterError, match=r"copies of diagnosed runs .* 'copy.csv' = 'run_0.csv'"):
        model_under_diagnosis("physics", diagnosed, calibration_logs=[*cal, copy])
    silent = dataclasses.replace(_renamed(logs[1], source="zero.csv"), current_left_a=np.zeros(len(logs[1])),
                                 current_right_a=np.zeros(len(logs[1])))
    with pytest.raises(InvalidParameterError, match=r"without drive current .* \['zero.csv'\]"):
        model_under_diagnosis("physics", diagnosed, calibration_logs=[silent])
    jackal = [_renamed(log, robot="jackal") for log in cal]
    with pytest.raises(InvalidParameterError, match=r"robot\(s\) \['jackal'\], not of \['husky'\]"):
        model_under_diagnosis("physics", diagnosed, calibration_logs=jackal, robot="husky")
    with pytest.raises(InvalidParameterError, match=r"robot\(s\) \['jackal'\], not of \['husky'\]"):
        model_under_diagnosis("estimator", diagnosed, calibration_logs=jackal)  # the diagnosed runs name it
    one_second = logs[1].slice(2.0, 3.0)
    with pytest.raises(InvalidParameterError, match=r"drives [\d.]+ s in all, fewer than the 5 s"):
        model_under_diagnosis("physics", diagnosed, calibration_logs=[one_second])
    short = model_under_diagnosis("physics", diagnosed, calibration_logs=cal)  # 16 s: used, said to be short
    assert "s of driving: its coefficients are uncertain" in short.note


def test_a_saved_model_is_loaded_as_it_is(tmp_path, runs):
    logs, model = runs
    path = model.save(tmp_path / "m.zip")
    src = model_under_diagnosis(path, logs, robot="husky")
    assert src.kind == "file" and src.reference_robot == "husky"
    assert src.note == f"{type(model).__name__} loaded from {path}"
    assert (src.model.predict(logs[0]) == model.predict(logs[0])).all()


def _relabelled(logs, labels_of):
    """The logs with per-sample ground labels ``labels_of(n)`` (an array of n names)."""
    return [dataclasses.replace(log, ground=labels_of(len(log)),
                                meta=dataclasses.replace(log.meta, ground_label=None)) for log in logs]


def _two_grounds(n):
    import numpy as np

    return np.where(np.arange(n) < n // 2, "grass", "asphalt")


def test_physics_as_given_drives_each_sample_on_its_own_ground_and_the_maps_slope(runs):
    tmap = dataclasses.replace(scenario("turning_resistance"), n_runs=3, run_duration_s=8.0).terrain
    logs = _relabelled(runs[0], _two_grounds)
    level = model_under_diagnosis("physics", logs)
    assert level.model.ground == {"asphalt": "asphalt", "grass": "grass"}
    assert level.model.terrain is None
    assert "asphalt, grass (a preset per ground label) presets as given" in level.note
    on_map = model_under_diagnosis("physics", logs, terrain=tmap)
    assert on_map.model.terrain is tmap and "on the map's slope under the logged poses" in on_map.note
    # without poses the map cannot be read under the runs: level ground (the slope stays a candidate)
    bare = [dataclasses.replace(log, pose_xyh=None) for log in logs]
    assert model_under_diagnosis("physics", bare, terrain=tmap).model.terrain is None
    # a ground asked for is used for every sample, as before
    assert model_under_diagnosis("physics", logs, ground="snow").model.ground == "snow"
    with pytest.raises(InvalidParameterError, match="terrain must be a TerrainMap"):
        model_under_diagnosis("physics", logs, terrain="map.npz")


def test_calibrated_physics_fits_a_ground_per_label_only_when_the_calibration_covers_the_diagnosed_grounds(runs):
    import numpy as np

    logs = _relabelled(runs[0], _two_grounds)
    diagnosed, cal = logs[:1], [dataclasses.replace(log, meta=dataclasses.replace(log.meta, source=f"cal_{k}"))
                                for k, log in enumerate(logs[1:])]
    covered = model_under_diagnosis("physics", diagnosed, calibration_logs=cal)
    assert covered.model.ground == {"asphalt": "asphalt", "grass": "grass"}
    assert {"grass.rolling_resistance_coef", "asphalt.rolling_resistance_coef"} <= set(covered.model.fitted_)
    other = _relabelled(cal, lambda n: np.where(np.arange(n) < n // 2, "grass", "snow"))
    assert model_under_diagnosis("physics", diagnosed, calibration_logs=other).model.ground == "asphalt"


def test_a_robot_file_is_the_physics_robot_and_the_corrected_model_keeps_its_parameters(tmp_path, runs):
    from energy import LinearCurrentModel, diagnose, robot_preset
    from energy.diagnosis import FitSettings
    from energy.params import write_robot_file

    rover = robot_preset("husky").replace(name="rover", mass_kg=60.0)
    write_robot_file(rover, tmp_path / "rover.json")
    logs = runs[0]
    source = model_under_diagnosis("physics", logs, robot=str(tmp_path / "rover.json"))
    assert source.model.robot_ == rover and "rover (robot file rover.json)" in source.note
    linear = LinearCurrentModel().fit(logs)  # not a physics model: the robot is the diagnosis' reference physics
    d = diagnose(linear, logs, effects=["slope", "current_gain"], robot=tmp_path / "rover.json",
                 settings=FitSettings(n_bootstrap=20))
    assert d.corrected_model.robot == rover  # the parameters, not a path a saved model would need again
