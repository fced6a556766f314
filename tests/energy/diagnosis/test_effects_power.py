"""Tests of energy.diagnosis.effects_power: armature heat, sensor and control-board power, on battery power."""

import dataclasses

import numpy as np
import pytest
from power_samples import sample_power_inputs, small_power_scenario

from energy.diagnosis import effect
from energy.diagnosis.effects_power import ArmatureHeatEffect, ControlPowerEffect, ElectricalEffect, SensorPowerEffect
from energy.diagnosis.power_data import predicted_battery_power_w


def _power(inputs):
    return predicted_battery_power_w(inputs)[:, None]


def test_the_basis_values_change_nothing():
    p = sample_power_inputs()
    base = _power(p)
    for e in (ArmatureHeatEffect(), SensorPowerEffect(), ControlPowerEffect()):
        assert isinstance(e, ElectricalEffect) and e.kind == "electrical"
        np.testing.assert_allclose(e.apply(e.priors([p]), base, p), base, atol=1e-12)
    assert ArmatureHeatEffect().priors([p]).tolist() == [0.5]
    assert SensorPowerEffect().priors([p]).tolist() == [3.0, 2.0]
    assert ControlPowerEffect().priors([p]).tolist() == [5.0, 7.0]  # medians when stopped and when moving stably
    assert SensorPowerEffect().priors().tolist() == [1.0, 0.5]  # without inputs: the start values


def test_each_effect_sets_its_quantity_to_the_fitted_value():
    p = sample_power_inputs()
    base = _power(p)
    heat = ArmatureHeatEffect().apply(np.array([1.5]), base, p)  # Ra 0.5 -> 1.5 ohm: + I^2 per side (halved when regenerating)
    np.testing.assert_allclose(heat - base, [[0.0], [8.0], [10.0], [0.5 * 4.0 + 1.0]])
    assert _power(dataclasses.replace(p, ra0_ohm=1.5)) == pytest.approx(heat)
    sensor = SensorPowerEffect().apply(np.array([4.0, 0.0]), base, p)
    np.testing.assert_allclose(sensor - base, (1.0 - 2.0 * p.speed_mps)[:, None])
    control = ControlPowerEffect().apply(np.array([6.0, 10.0]), base, p)
    # standby 6 when stopped; stable 10 when moving, plus the start-up excess (2 W) while starting
    np.testing.assert_allclose(control - base, [[1.0], [3.0], [3.0], [3.0]])


def test_logs_without_battery_power_cannot_show_an_electrical_effect():
    logs = small_power_scenario("null").make_logs(0)
    bare = dataclasses.replace(logs[1], battery_voltage_v=None, battery_current_a=None)
    assert effect("sensor").unsupported(logs, None) is None
    why = effect("control").unsupported([logs[0], bare], None)
    assert "needs battery voltage and pack current" in why and "logs [1] lack them" in why
