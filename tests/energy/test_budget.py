"""Tests of energy.budget: predicted vs actual energy, segments, depletion, the battery power of a log."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from energy import (
    EFFECTS,
    Battery,
    EnergyBudget,
    InteractionLog,
    NoiseModel,
    TruthSimulator,
    discharge_from_power,
    energy_budget,
    ground_preset,
    robot_preset,
)
from energy.budget import log_battery_power_w
from terrain import InvalidParameterError, UnknownNameError


def test_budget_arithmetic_and_segments():
    b = Battery(capacity_ah=1.0, voltage_v=10.0, min_reserve_pct=20.0)
    t = np.array([0.0, 10.0, 20.0, 30.0, 40.0])
    power = np.array([36.0, 36.0, 72.0, 72.0, 72.0])
    seg = np.array([0, 0, 1, 1, 1])
    d = discharge_from_power(b, t, power)
    budget = energy_budget(d, 2000.0, segment_index=seg, segment_predicted_j=[700.0, 1300.0])
    # intervals: [0,10] 360 J (seg 0), [10,20] 540 J (seg 0), [20,30] 720, [30,40] 720 (seg 1)
    np.testing.assert_allclose(budget.segment_actual_j, [900.0, 1440.0])
    assert budget.actual_energy_j == pytest.approx(2340.0)
    assert budget.segment_actual_j.sum() == pytest.approx(budget.actual_energy_j)
    assert budget.error_pct == pytest.approx(100.0 * (2000.0 - 2340.0) / 2340.0)
    np.testing.assert_allclose(budget.segment_error_pct, [100 * (700 - 900) / 900, 100 * (1300 - 1440) / 1440])
    assert budget.actual_charge_mah == pytest.approx(2340.0 / 10.0 / 3.6)
    assert budget.predicted_charge_mah == pytest.approx(2000.0 / 10.0 / 3.6)
    assert budget.arrival_soc == pytest.approx(1.0 - 2340.0 / 36000.0)
    assert budget.arrival_energy_wh == pytest.approx(10.0 - 2340.0 / 3600.0)
    assert budget.reserve_margin_wh == pytest.approx(8.0 - 2340.0 / 3600.0)
    assert budget.feasible and budget.predicted_feasible
    js = budget.to_json_dict()
    assert js["actual_energy_j"] == pytest.approx(2340.0) and js["reserve_crossed_time_s"] is None
    assert js["battery"]["capacity_ah"] == 1.0


def test_budget_predicted_infeasible():
    b = Battery(capacity_ah=1.0, voltage_v=10.0, min_reserve_pct=20.0)
    d = discharge_from_power(b, [0.0, 100.0], [1.0, 1.0])
    budget = energy_budget(d, predicted_energy_j=9.0 * 3600.0)  # 9 Wh of 8 usable
    assert budget.feasible and not budget.predicted_feasible
    assert budget.predicted_arrival_soc == pytest.approx(0.1)


def test_log_power_reproduces_physics_battery_power():
    # Noise-free log without wheel slip (not observable in a log): the motoring currents plus
    # electronics give back the physics model's battery power sample by sample.
    robot = robot_preset("husky")
    effects = [e for e in EFFECTS if e != "longitudinal_slip"]
    sim = TruthSimulator(robot, {"grass": ground_preset("grass")}, effects=effects, noise=NoiseModel.off(),
                         velocity_time_constant_s=0.0, seed=1)
    t = np.arange(600) * 0.01
    v = np.where(t < 3.0, 0.6 * np.minimum(t, 1.0), 0.0)
    w = np.where(t >= 3.0, 0.5 * np.minimum(t - 3.0, 1.0), 0.1)
    run = sim.run_commands(t, v, w, ground="grass")
    # NoiseModel.off(): a sensor without rest offset, so none is removed
    p = log_battery_power_w(run.log, robot, current_offset_a=0.0)
    np.testing.assert_allclose(p, run.breakdown.total_power_w, rtol=1e-9, atol=1e-9)
    drive = log_battery_power_w(run.log, robot, electronics=False, current_offset_a=0.0)
    np.testing.assert_allclose(drive, run.breakdown.drive_power_w, rtol=1e-9, atol=1e-9)


def test_the_sensor_rest_offset_is_logged_but_never_paid():
    # The same drive logged by a sensor with the Husky's rest offset (0.59 A on every sample):
    # the robot, which knows its sensor (rest_current_a), books the physics' battery power; the
    # offset reaches the logged currents only. Booked as if it were drawn current, it would cost.
    robot = robot_preset("husky")
    assert robot.rest_current_a == 0.59
    effects = [e for e in EFFECTS if e != "longitudinal_slip"]
    noise = dataclasses.replace(NoiseModel.off(), current_offset_a=0.59)
    sim = TruthSimulator(robot, {"grass": ground_preset("grass")}, effects=effects, noise=noise,
                         velocity_time_constant_s=0.0, seed=1)
    t = np.arange(600) * 0.01
    v = np.where(t < 3.0, 0.6 * np.minimum(t, 1.0), 0.0)
    w = np.where(t >= 3.0, 0.5 * np.minimum(t - 3.0, 1.0), 0.1)
    run = sim.run_commands(t, v, w, ground="grass")
    bare = TruthSimulator(robot, {"grass": ground_preset("grass")}, effects=effects, noise=NoiseModel.off(),
                          velocity_time_constant_s=0.0, seed=1).run_commands(t, v, w, ground="grass")
    np.testing.assert_allclose(run.log.current_left_a - bare.log.current_left_a, 0.59, atol=1e-12)  # logged
    np.testing.assert_allclose(run.breakdown.total_power_w, bare.breakdown.total_power_w)  # not paid
    np.testing.assert_allclose(log_battery_power_w(run.log, robot), run.breakdown.total_power_w, rtol=1e-9,
                               atol=1e-9)
    paid = log_battery_power_w(run.log, robot, current_offset_a=0.0)
    # booked as drawn current, the offset would add 5 % and more to this drive's energy
    assert np.trapezoid(paid - run.breakdown.total_power_w, t) > 0.05 * np.trapezoid(run.breakdown.total_power_w, t)
    with pytest.raises(InvalidParameterError, match="current_offset_a"):
        log_battery_power_w(run.log, robot, current_offset_a=-0.1)


def test_log_power_battery_convention_and_errors():
    robot = robot_preset("jackal")
    log = InteractionLog([0.0, 1.0, 2.0], [0.0] * 3, [0.0] * 3, [1.0, 2.0, 0.5], [1.0, 0.0, -0.5],
                         [0.0, 2.0], [9.8, 9.8])
    p = log_battery_power_w(log, robot, current_convention="battery", electronics=False)
    np.testing.assert_allclose(p, robot.battery_voltage_v * np.array([2.0, 2.0, 0.0]))
    with_el = log_battery_power_w(log, robot, current_convention="battery")
    np.testing.assert_allclose(with_el - p, robot.sensor_power_w + robot.control_standby_power_w)
    with pytest.raises(UnknownNameError, match="current_convention must be one of"):
        log_battery_power_w(log, robot, current_convention="duty")
    with pytest.raises(InvalidParameterError, match="robot must be a RobotParams"):
        log_battery_power_w(log, "jackal")



# ------------------------------------------------------------------ a pack too small: SoC never below 0
def test_tiny_battery_runs_out_and_the_budget_says_where() -> None:
    # 0.1 mAh at 24 V (8.64 J) feeding 100 W: empty after 0.0864 s; the old arithmetic
    # reported an arrival SoC of about -1156
    b = Battery(capacity_ah=1e-4, voltage_v=24.0, min_reserve_pct=20.0)
    t = np.linspace(0.0, 10.0, 101)
    d = discharge_from_power(b, t, np.full(t.size, 100.0))
    assert d.depleted and d.depleted_index == 1
    assert d.depleted_time_s == pytest.approx(3600.0 * 1e-4 * 24.0 / 100.0)
    assert d.soc.min() == 0.0 and d.final_soc == 0.0
    assert np.all(d.soc[1:] == 0.0) and d.soc[0] == 1.0
    assert d.reserve_crossed_time_s == pytest.approx(0.8 * d.depleted_time_s)
    assert d.total_energy_j == pytest.approx(1000.0)  # what the load asked for, not what it got
    budget = energy_budget(d, predicted_energy_j=1000.0)
    assert budget.arrival_soc == 0.0 and budget.predicted_arrival_soc == 0.0
    assert budget.depleted and budget.predicted_depleted
    assert not budget.feasible and not budget.predicted_feasible
    assert budget.depleted_time_s == pytest.approx(0.0864) and budget.depleted_index == 1
    assert budget.predicted_depleted_time_s == pytest.approx(0.0864)
    assert budget.arrival_soc_pct == 0.0 and budget.reserve_margin_pct == -20.0
    js = budget.to_json_dict()
    assert js["arrival_soc_pct"] == 0.0 and js["depleted_time_s"] == pytest.approx(0.0864)
    assert js["feasible"] is False and js["depleted_index"] == 1
    assert "depleted_time_s=0.0864" in repr(budget)


def test_no_depletion_leaves_the_budget_unchanged() -> None:
    b = Battery(capacity_ah=1.0, voltage_v=10.0, min_reserve_pct=0.0)
    d = discharge_from_power(b, [0.0, 3600.0], [10.0, 10.0])  # exactly the whole pack
    assert d.depleted and d.depleted_time_s == pytest.approx(3600.0) and d.final_soc == pytest.approx(0.0)
    d2 = discharge_from_power(b, [0.0, 1800.0], [10.0, 10.0])
    budget = energy_budget(d2, predicted_energy_j=5.0 * 3600.0)
    assert not budget.depleted and budget.depleted_time_s is None and budget.predicted_depleted_time_s is None
    assert budget.feasible and budget.arrival_soc == pytest.approx(0.5)


def test_depletion_with_zero_reserve_is_infeasible() -> None:
    # with min_reserve_pct = 0 the clamped SoC never goes *below* the reserve, yet the pack ran out
    b = Battery(capacity_ah=0.001, voltage_v=12.0, min_reserve_pct=0.0)
    d = discharge_from_power(b, [0.0, 10.0, 20.0], [10.0, 10.0, 10.0])
    budget = energy_budget(d, predicted_energy_j=1.0)
    assert d.depleted and d.reserve_crossed and budget.depleted and not budget.feasible
    assert budget.predicted_feasible and not budget.predicted_depleted
    assert d.depleted_time_s == pytest.approx(3600.0 * 0.001 * 12.0 / 10.0)


def test_charging_after_depletion_fills_from_zero() -> None:
    b = Battery(capacity_ah=0.001, voltage_v=10.0, min_reserve_pct=0.0)
    # 10 W for 3.6 s empties the 36 J pack; 72 J more asked for, then -10 W (charging) for 1.8 s
    d = discharge_from_power(b, [0.0, 3.6, 10.8, 10.8001, 12.6], [10.0, 10.0, 10.0, -10.0, -10.0])
    assert d.depleted_time_s == pytest.approx(3.6)
    assert d.soc[2] == 0.0 and d.soc[-1] == pytest.approx(0.5, rel=1e-3)


def test_budget_refuses_a_negative_soc_or_a_feasible_depletion() -> None:
    b = Battery(capacity_ah=1.0, voltage_v=10.0)
    base = dict(battery=b, predicted_energy_j=1.0, actual_energy_j=1.0, predicted_charge_mah=1.0,
                actual_charge_mah=1.0, predicted_arrival_soc=0.5, arrival_soc=0.5, duration_s=1.0,
                feasible=True, predicted_feasible=True)
    with pytest.raises(InvalidParameterError, match="EnergyBudget.arrival_soc must be >= 0"):
        EnergyBudget(**(base | {"arrival_soc": -643.8}))
    with pytest.raises(InvalidParameterError, match="feasible=True contradicts depleted_index"):
        EnergyBudget(**(base | {"depleted_time_s": 0.5, "depleted_index": 1}))
    with pytest.raises(InvalidParameterError, match="both be set or both None"):
        EnergyBudget(**(base | {"depleted_time_s": 0.5}))
