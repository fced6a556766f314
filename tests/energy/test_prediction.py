"""Tests of energy.prediction: predict_runs and RunPrediction on logs with and without measured currents."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from energy import ConstantCurrentModel, InteractionLog, LogMeta
from energy.prediction import RunPrediction, predict_runs
from terrain import InvalidParameterError, NotFittedError


def _log(source: str = "sand/pro_00.csv", left_a: float = 2.0, right_a: float = 4.0, voltage_v: float | None = 24.0,
         duration_s: float = 36.0) -> InteractionLog:
    t = np.linspace(0.0, duration_s, 37)
    ta = np.linspace(0.0, duration_s, 361)
    volts = None if voltage_v is None else np.full(t.size, voltage_v)
    return InteractionLog(t, np.full(t.size, 0.5), np.zeros(t.size), np.full(t.size, left_a), np.full(t.size, right_a),
                          ta, np.full(ta.size, 9.81), meta=LogMeta(source=source, ground_label="sand"),
                          battery_voltage_v=volts)


def test_charge_and_energy_of_a_constant_model():
    log = _log()
    model = ConstantCurrentModel().fit(log)  # predicts 2 A left, 4 A right
    (run,) = predict_runs(model, [log])
    assert run.run == "sand/pro_00" and run.ground == "sand" and run.duration_s == pytest.approx(36.0)
    assert run.charge_predicted_left_mah == pytest.approx(2.0 * 36.0 / 3.6)  # 20 mAh
    assert run.charge_predicted_right_mah == pytest.approx(40.0)
    assert run.charge_measured_left_mah == pytest.approx(20.0) and run.has_currents
    assert run.energy_predicted_wh == pytest.approx(24.0 * 6.0 * 36.0 / 3600.0)  # 1.44 Wh


def test_a_log_without_currents_or_voltage_and_repeated_names():
    model = ConstantCurrentModel().fit(_log())
    log = _log(voltage_v=None)
    bare = dataclasses.replace(log, current_left_a=None, current_right_a=None)
    runs = predict_runs(model, [log, bare])
    assert [r.run for r in runs] == ["sand/pro_00#0", "sand/pro_00#1"]
    assert not runs[1].has_currents and math.isnan(runs[1].charge_measured_left_mah)
    assert math.isnan(runs[0].energy_predicted_wh)
    assert runs[1].charge_predicted_left_mah == pytest.approx(20.0)
    plain = runs[1].to_dict()
    assert plain["charge_measured_left_mah"] is None and plain["energy_predicted_wh"] is None
    assert set(plain) == {f.name for f in dataclasses.fields(RunPrediction)}
    assert predict_runs(model, log)[0].run == "sand/pro_00"  # one log alone


def test_documented_errors():
    with pytest.raises(InvalidParameterError, match="model must be a CurrentModel, got 'constant'"):
        predict_runs("constant", [_log()])
    with pytest.raises(InvalidParameterError, match="logs must be one InteractionLog or a non-empty sequence of them"):
        predict_runs(ConstantCurrentModel().fit(_log()), [])
    with pytest.raises(InvalidParameterError, match="non-empty sequence"):
        predict_runs(ConstantCurrentModel().fit(_log()), [_log(), "run.csv"])
    with pytest.raises(NotFittedError):
        predict_runs(ConstantCurrentModel(), [_log()])
