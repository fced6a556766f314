"""Tests of energy.diagnosis.power_data: battery power measured and predicted from the measured drive currents."""

import dataclasses

import numpy as np
import pytest
from power_samples import sample_power_inputs, small_power_scenario

from energy import NoiseModel
from energy.diagnosis.model_currents import physics_basis
from energy.diagnosis.power_data import (
    POWER_EFFECTS,
    check_power_logs,
    power_inputs,
    power_logs_missing,
    predicted_battery_power_w,
)
from terrawatt_base.errors import DataError


def test_predicted_power_from_clean_currents_equals_the_truth():
    sc = dataclasses.replace(small_power_scenario("null"), noise=NoiseModel.off())
    model = sc.make_model(0)
    basis = physics_basis(model)
    for log in sc.make_logs(0):  # noise off: voltage x pack current is the truth's total battery power
        pred = predicted_battery_power_w(power_inputs(basis, log))
        assert float(np.max(log.battery_power_w)) > 100.0
        # the basis re-estimates the motor speed (slip) from v and omega (central, not backward, differences):
        # within 1 % but at a few samples of hard starts
        close = np.isclose(pred, log.battery_power_w, rtol=0.01, atol=0.05)
        assert close.mean() > 0.99
        assert float(np.sqrt(np.mean((pred - log.battery_power_w) ** 2))) < 0.5


def test_predicted_battery_power_of_hand_made_inputs():
    # drive: back-EMF + Ra I^2 per side, negative sides at half (regen 0.5); + sensor 3 + 2 |v|; + control
    p = predicted_battery_power_w(sample_power_inputs())
    assert p.tolist() == pytest.approx([0.0 + 3.0 + 5.0, 24.0 + 4.0 + 9.0, 55.0 + 5.0 + 7.0, (-3.0 + 4.5) + 5.0 + 7.0])
    assert POWER_EFFECTS == ("armature_heat", "sensor", "control")


def test_logs_without_power_and_a_voltage_that_is_not_positive():
    sc = small_power_scenario("null")
    logs = sc.make_logs(0)
    bare = dataclasses.replace(logs[1], battery_voltage_v=None, battery_current_a=None)
    assert power_logs_missing(logs) == [] and power_logs_missing([logs[0], bare]) == [1]
    check_power_logs(logs)
    check_power_logs([bare])  # nothing to check without a pack current
    zero = dataclasses.replace(logs[0], battery_voltage_v=np.where(np.arange(len(logs[0])) == 3, 0.0,
                                                                   logs[0].battery_voltage_v))
    with pytest.raises(DataError, match=r"logs\[1\] \(.*\): battery_voltage_v must be > 0 V where a pack current is "
                                        r"logged; index 3 holds 0.0 V"):
        check_power_logs([logs[1], zero])
    with pytest.raises(DataError):
        power_inputs(physics_basis(sc.make_model(0)), dataclasses.replace(logs[0], current_left_a=None,
                                                                          current_right_a=None))
