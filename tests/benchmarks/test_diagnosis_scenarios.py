"""Withheld-effect scenarios: finite logs, the withheld effect above the noise, the null model equal to the truth."""

import dataclasses

import numpy as np
import pytest
from diagnosis_scenarios import (
    MANOEUVRES,
    POWER_ONLY_EFFECTS,
    SCENARIOS,
    Scenario,
    manoeuvre_commands,
    null_scenario,
    pair_scenario,
    scenario,
    withheld_gap,
    withheld_gap_ratio,
)

from energy import PhysicsCurrentModel
from energy.diagnosis import EFFECTS_CATALOGUE, NOT_IDENTIFIABLE_FROM_CURRENT, FitSettings, diagnose
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

EXCITABLE = [name for name, sc in SCENARIOS.items() if sc.excitable]


def _currents(log):
    return np.column_stack([log.current_left_a, log.current_right_a])


def test_every_catalogued_effect_has_a_scenario():
    # the scenarios test a physics model, which does not read the IMU: imu_lag is checked with a
    # vibration-reading model in test_imu_lag.py
    expected = (set(EFFECTS_CATALOGUE) - {"learned_residual", "imu_lag"}) | set(NOT_IDENTIFIABLE_FROM_CURRENT)
    assert expected <= set(SCENARIOS)
    assert set(POWER_ONLY_EFFECTS) == {name for name, sc in SCENARIOS.items() if sc.power_logs}
    # the truth simulator starts within one sample of a command: the breakaway at standstill cannot show
    assert [name for name, sc in SCENARIOS.items() if not sc.excitable] == ["static_friction"]
    assert SCENARIOS["static_friction"].note
    for name, sc in SCENARIOS.items():
        assert sc.withheld == (name,) and scenario(name) is sc


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_scenario_makes_finite_logs_with_currents_and_poses(name):
    sc = SCENARIOS[name]
    logs = sc.make_logs(seed=3)
    assert len(logs) == sc.n_runs
    for log in logs:
        cur = _currents(log)
        assert np.all(np.isfinite(cur)) and cur.max() > 0 and cur.min() >= 0
        assert log.pose_xyh is not None and log.meta.velocity_source == "measured"
        assert abs(log.duration_s - sc.run_duration_s) < 0.05
        assert set(log.ground_labels.tolist()) == {sc.ground.name}
    model = sc.make_model(seed=3)
    assert isinstance(model, PhysicsCurrentModel) and model.is_fitted
    assert not set(sc.withheld) & set(model.effects_)
    assert model.predict(logs[0]).shape == (len(logs[0]), 2)


def test_same_seed_same_logs_other_seed_other_logs():
    sc = SCENARIOS["inertia"]
    a, b, c = sc.make_logs(5), sc.make_logs(5), sc.make_logs(6)
    assert np.array_equal(_currents(a[1]), _currents(b[1]))
    assert not np.array_equal(_currents(a[1]), _currents(c[1]))
    with pytest.raises(InvalidParameterError, match="seed"):
        sc.make_logs(-1)


@pytest.mark.parametrize("name", EXCITABLE)
def test_withheld_effect_exceeds_twice_the_noise(name):
    gap = withheld_gap(SCENARIOS[name], seed=0)
    ratios = (gap.ratio, gap.rms_ratio) + ((gap.power.ratio, gap.power.rms_ratio) if gap.power else ())
    assert max(ratios) > 2.0, gap
    assert withheld_gap_ratio(SCENARIOS[name], seed=0) == pytest.approx(max(ratios))
    assert gap.noise_rms_a == pytest.approx(0.14, abs=0.03)  # the default noise, per sample


@pytest.mark.parametrize("name", sorted(POWER_ONLY_EFFECTS))
def test_power_only_effects_change_nothing_in_the_currents_but_the_battery_power(name):
    gap = withheld_gap(SCENARIOS[name], seed=0)
    assert gap.charge_change_mah == 0.0 and gap.rms_change_a == 0.0
    assert SCENARIOS[name].note
    assert gap.power is not None and gap.power.ratio > 2.0 and gap.power.rms_ratio > 2.0
    assert gap.power.energy_change_pct > 2.0


def test_null_model_equals_the_truth_up_to_noise():
    sc = null_scenario()
    assert sc.withheld == ()
    gap = withheld_gap(sc, seed=1)
    assert gap.charge_change_mah == 0.0 and gap.ratio == 0.0
    model = sc.make_model(seed=1)
    logs = sc.make_logs(seed=1)
    mse = np.mean([np.mean((model.predict(log) - _currents(log)) ** 2) for log in logs])
    assert mse < 1.25 * gap.noise_rms_a**2
    charge_err = sum(float((model.predict(log) - _currents(log)).sum()) for log in logs)
    assert abs(charge_err) < 0.01 * sum(float(_currents(log).sum()) for log in logs)


def test_model_calibrated_rest_level_and_withheld_idle():
    # the model's rest level is calibrated at standstill (the sensor's 0.59 A offset); no idle on top
    model = SCENARIOS["inertia"].make_model()
    assert model.rest_current_a_ == pytest.approx([0.59, 0.59], abs=0.03)
    assert model.idle_current_a_ == 0.0
    withheld = SCENARIOS["idle_current"].make_model()
    assert withheld.rest_current_a_.tolist() == [0.0, 0.0] and withheld.idle_current_a_ == 0.0


def test_measurement_and_parameter_truths():
    gain = SCENARIOS["current_gain"]
    assert gain.true_values()["gain_left"] == 1.12 and gain.model_values()["gain_left"] == 1.0
    mass = SCENARIOS["mass"]
    assert mass.true_values()["mass_kg"] / mass.model_values()["mass_kg"] == pytest.approx(1.3)
    lag = SCENARIOS["time_lag"]
    truth_like = dataclasses.replace(lag, lag_s=0.0).make_logs(2)[0]
    lagged = lag.make_logs(2)[0]
    # the lagged currents equal the unlagged ones 0.12 s (12 samples) earlier, up to noise
    d_lag = np.abs(_currents(lagged)[12:] - _currents(truth_like)[:-12]).mean()
    d_same = np.abs(_currents(lagged) - _currents(truth_like)).mean()
    assert d_lag < 0.5 * d_same


def test_slope_scenario_drives_a_ramp():
    sc = SCENARIOS["slope"]
    assert sc.grade > 0 and float(sc.terrain.slope_rad.max()) > 0.1
    assert float(SCENARIOS["inertia"].terrain.slope_rad.max()) == 0.0


def test_pair_scenario():
    pair = pair_scenario("turning_resistance", "inertia")
    assert pair.withheld == ("turning_resistance", "inertia")
    assert pair.manoeuvres == ("pivots_arcs", "start_stop") and pair.n_runs == 6
    logs = pair.make_logs(0)
    assert len(logs) == 6
    assert withheld_gap_ratio(pair, 0) > 2.0
    with pytest.raises(InvalidParameterError, match="two different"):
        pair_scenario("inertia", "inertia")
    with pytest.raises(InvalidParameterError, match="excitable physics"):
        pair_scenario("inertia", "armature_heat")
    with pytest.raises(InvalidParameterError, match="excitable physics"):
        pair_scenario("inertia", "current_gain")
    with pytest.raises(UnknownNameError, match="scenario 'nope' is unknown"):
        pair_scenario("inertia", "nope")


def test_scenario_errors():
    with pytest.raises(UnknownNameError, match="scenario 'friction' is unknown"):
        scenario("friction")
    with pytest.raises(UnknownNameError, match="withheld effect 'warp_drive'"):
        Scenario("x", ("warp_drive",), "mixed")
    with pytest.raises(InvalidParameterError, match="tuple of effect names"):
        Scenario("x", "inertia", "mixed")
    with pytest.raises(UnknownNameError, match="manoeuvre"):
        Scenario("x", ("inertia",), "moonwalk")
    with pytest.raises(InvalidParameterError, match="n_runs"):
        Scenario("x", ("inertia",), "mixed", n_runs=1)
    with pytest.raises(InvalidParameterError, match="current_gain"):
        Scenario("x", ("current_gain",), "mixed", current_gain=(1.0,))
    with pytest.raises(InvalidParameterError, match="withheld_gap|Scenario"):
        withheld_gap("inertia")
    with pytest.raises(UnknownNameError, match="manoeuvre"):
        null_scenario("moonwalk")


def test_manoeuvre_commands_ramp_and_stay_on_the_map():
    for name in MANOEUVRES:
        p = manoeuvre_commands(name, 20.0, seed=4, start_xy_m=(40.0, 40.0))
        assert len(p) == 2000 and np.all(p.v_mps[:50] == 0) and np.all(p.v_mps[-50:] == 0)
        levels = (0.0,) + MANOEUVRES[name][0]
        span_mps = max(levels) - min(levels)
        assert np.abs(np.diff(p.v_mps)).max() <= span_mps * 0.01 / 0.3 + 1e-9  # ramps over 0.3 s
        assert np.all(np.abs(p.pose_xyh[:, :2] - 40.0) < 40.0)
    with pytest.raises(UnknownNameError, match="manoeuvre"):
        manoeuvre_commands("moonwalk", 10.0)
    with pytest.raises(InvalidParameterError, match="duration_s"):
        manoeuvre_commands("mixed", 1.0)


def test_a_withheld_effect_is_found_quickly():
    # a representative check of the benchmark: a short turning-resistance scenario, few candidates
    sc = dataclasses.replace(SCENARIOS["turning_resistance"], n_runs=3, run_duration_s=10.0)
    d = diagnose(sc.make_model(0), sc.make_logs(0), terrain=sc.terrain,
                 effects=["turning_resistance", "inertia", "current_gain", "idle_current"],
                 settings=FitSettings(n_blocks=3, n_bootstrap=20))
    assert d.current.ranking[0].name == "turning_resistance" and d.current.chosen[0] == "turning_resistance"
    assert d.current.ranking[0].shrink_pct > 80.0
    assert d.current.ranking[0].parameters["gain"] == pytest.approx(1.0, abs=0.2)
