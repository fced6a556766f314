"""Tests of energy.diagnosis.effects_measurement: current gain and offset, time lag (vectorised over samples)."""

import dataclasses

import numpy as np
import pytest
from diagnosis_scenarios import null_scenario, scenario
from effect_samples import coated_wood_log, coated_wood_model

from energy.diagnosis import FitSettings, diagnose, effect


@pytest.fixture(scope="module")
def log():
    return coated_wood_log()


@pytest.fixture(scope="module")
def model(log):
    return coated_wood_model(log)


def test_measurement_effects_vectorised(model, log):
    base = np.column_stack([np.linspace(0, 1, len(log)), np.linspace(1, 2, len(log))])
    g = effect("current_gain")  # a gain of what is drawn above the sensor's rest offset (the model's: 0.59 A)
    rest = model.rest_current_a_
    np.testing.assert_allclose(g.apply(np.array([2.0, 0.5]), base, g.prepare(model, log)),
                               rest + (base - rest) * [2.0, 0.5])
    o = effect("current_offset")
    np.testing.assert_allclose(o.apply(np.array([0.1, -0.2]), base, None), base + [0.1, -0.2])
    lag = effect("time_lag")
    shifted = lag.apply(np.array([0.1]), base, lag.prepare(model, log))
    np.testing.assert_allclose(shifted[20:, 0], base[10:-10, 0], atol=1e-9)  # 0.1 s = 10 samples later


def test_a_lag_just_under_one_drive_sample_is_a_lag_and_half_a_sample_is_not():
    # BorealTC-like 6.5 Hz drive streams whose currents run 0.15 s late: the fit lands on the whole sample
    # (where interpolation smooths nothing) and the lag is added; without a lag nothing is
    sc = dataclasses.replace(scenario("time_lag"), lag_s=0.15, n_runs=4, run_duration_s=20.0)
    logs = [log.resample(6.5) for log in sc.make_logs(1)]
    cands = ["time_lag", "current_gain", "idle_current"]
    d = diagnose(sc.make_model(1), logs, terrain=sc.terrain, effects=cands, settings=FitSettings(n_bootstrap=50))
    assert d.current.chosen[:1] == ("time_lag",)
    assert d.current.score("time_lag").parameters["lag_s"] == pytest.approx(0.15, abs=0.01)
    null = dataclasses.replace(null_scenario(), n_runs=4, run_duration_s=20.0)
    logs = [log.resample(6.5) for log in null.make_logs(1)]
    assert diagnose(null.make_model(1), logs, terrain=null.terrain, effects=cands,
                    settings=FitSettings(n_bootstrap=50)).current.chosen == ()
    lag = effect("time_lag").bind(logs)
    assert lag.period_s == pytest.approx(1 / 6.5)
    assert lag.negligible(np.array([0.49 / 6.5])) and not lag.negligible(np.array([-0.51 / 6.5]))
