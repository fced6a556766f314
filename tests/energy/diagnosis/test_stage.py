"""The power stage of the diagnosis: electrical effects found on battery power, the null, bad input, today's behaviour kept."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from diagnosis_scenarios import POWER_ONLY_EFFECTS
from power_samples import N_BOOT, small_power_scenario

from energy.diagnosis import FitSettings, Stage, diagnose
from terrawatt_base.errors import DataError


@pytest.fixture(scope="module")
def found():
    """Each electrical scenario, small, seed 1: its scenario and its diagnosis."""
    out = {}
    for name in POWER_ONLY_EFFECTS:
        sc = small_power_scenario(name)
        out[name] = (sc, diagnose(sc.make_model(1), sc.make_logs(1), terrain=sc.terrain,
                                  settings=FitSettings(seed=1, n_bootstrap=N_BOOT)))
    return out


@pytest.mark.parametrize("name", sorted(POWER_ONLY_EFFECTS))
def test_each_electrical_effect_is_found_first_with_its_parameters(found, name):
    sc, d = found[name]
    assert isinstance(d.power, Stage)
    assert d.power.chosen[:1] == (name,) and d.power.ranking[0].name == name
    score = d.power.score(name)
    assert score.kind == "electrical" and score.shrink_pct > 80.0 and score.shrink_interval_pct[0] > 50.0
    truth = sc.true_values()
    for key, value in score.parameters.items():
        if key != "sensor_power_per_mps_w":  # the speed part of the sensor power is small beside the noise
            assert value == pytest.approx(truth[key], rel=0.2), key
    before, after = d.power.waterfall[0], d.power.waterfall[-1]
    assert abs(before.error_pct) > 3.0 and abs(after.error_pct) < 0.2 * abs(before.error_pct)
    assert after.rmse < 0.5 * before.rmse
    # the current stage finds nothing: the electronics and the copper loss draw no motor current
    assert not d.current.found
    # the plain-words verdict replaces "not identifiable from current logs" with the power findings
    assert not any("Not identifiable from current logs" in v for v in d.verdict)
    assert any(v.startswith(f"{name} (electrical;") for v in d.verdict)


def test_corrected_robot_carries_the_fitted_values(found):
    sc, d = found["armature_heat"]
    assert "armature_heat" in d.power.corrected_effects
    ra = d.power.fitted["armature_heat"]["armature_resistance_ohm"]
    assert d.power.corrected_robot.motor.armature_resistance_ohm == ra
    assert ra == pytest.approx(sc.robot.motor.armature_resistance_ohm, rel=0.2)
    sc, d = found["control"]
    assert d.power.corrected_robot.control_stable_power_w == pytest.approx(sc.robot.control_stable_power_w, rel=0.2)


def test_sensor_and_control_are_said_to_be_hard_to_tell_apart(found):
    # both are nearly constant while driving: the verdict measures it instead of assuming it
    for name, other in (("sensor", "control"), ("control", "sensor")):
        _, d = found[name]
        alone = {s.name: s.shrink_pct for s in d.power.ranking}
        assert alone[other] > 0.8 * alone[name]
        assert any(v.startswith(f"{other} alone explains") and "hardly tell them apart" in v for v in d.power.verdict)
        assert any("told apart from armature_heat" in v for v in d.power.verdict)


def test_null_with_power_logs_chooses_no_electrical_effect():
    sc = small_power_scenario("null")
    d = diagnose(sc.make_model(2), sc.make_logs(2), terrain=sc.terrain,
                 settings=FitSettings(seed=2, n_bootstrap=N_BOOT))
    assert d.power is not None and d.power.chosen == () and not d.power.found
    assert any("No unmodelled electrical effect found" in v for v in d.verdict)
    assert abs(d.power.before.error_pct) < 1.0
    assert d.power.waterfall[0].label == "as given" and len(d.power.waterfall) == 1


def _strip(log):
    return dataclasses.replace(log, battery_voltage_v=None, battery_current_a=None)


def test_logs_without_power_keep_todays_diagnosis_exactly():
    sc = small_power_scenario("sensor")
    model, logs = sc.make_model(0), sc.make_logs(0)
    with_power = diagnose(model, logs, terrain=sc.terrain, settings=FitSettings(seed=0, n_bootstrap=N_BOOT))
    plain = diagnose(model, [_strip(lg) for lg in logs], terrain=sc.terrain,
                     settings=FitSettings(seed=0, n_bootstrap=N_BOOT))
    assert plain.power is None and "power" not in plain.to_dict()
    assert plain.verdict[-1].startswith("Not identifiable from current logs") or any(
        v.startswith("Not identifiable from current logs") for v in plain.verdict)
    assert not any(n in plain.current.skipped for n in POWER_ONLY_EFFECTS)
    # the current stage is the same with and without the power fields
    assert [s.to_dict() for s in with_power.current.ranking] == [s.to_dict() for s in plain.current.ranking]
    assert with_power.current.chosen == plain.current.chosen and with_power.current.before == plain.current.before
    assert [w.to_dict() for w in with_power.current.waterfall] == [w.to_dict() for w in plain.current.waterfall]
    # some logs without power: no power stage; asked for by name: said why
    mixed = [logs[0], _strip(logs[1]), logs[2]]
    assert diagnose(model, mixed, settings=FitSettings(seed=0, n_bootstrap=N_BOOT)).power is None
    asked = diagnose(model, [_strip(lg) for lg in logs], effects=["sensor", "idle_current"],
                     settings=FitSettings(seed=0, n_bootstrap=N_BOOT))
    assert "battery voltage and pack current" in asked.current.skipped["sensor"]


def test_bad_battery_voltage_is_a_clear_error():
    sc = small_power_scenario("sensor")
    model, logs = sc.make_model(0), sc.make_logs(0)
    zero = dataclasses.replace(logs[1], battery_voltage_v=np.where(np.arange(len(logs[1])) == 7, 0.0,
                                                                   logs[1].battery_voltage_v))
    with pytest.raises(DataError, match=r"logs\[1\].*battery_voltage_v must be > 0 V.*index 7"):
        diagnose(model, [logs[0], zero, logs[2]], settings=FitSettings(seed=0, n_bootstrap=N_BOOT))
    before = logs[0].battery_current_a.copy()
    diagnose(model, logs, effects=["sensor"], settings=FitSettings(seed=0, n_bootstrap=N_BOOT))
    np.testing.assert_array_equal(logs[0].battery_current_a, before)  # nothing modified in place
