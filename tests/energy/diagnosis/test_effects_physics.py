"""Tests of energy.diagnosis.effects_physics: switched-off physics terms and errors of the model's parameters."""

import dataclasses

import numpy as np
import pytest
from diagnosis_scenarios import null_scenario, scenario
from effect_samples import coated_wood_log, coated_wood_model
from turning_samples import small_scenario

from energy import PhysicsCurrentModel
from energy.diagnosis import FitSettings, diagnose, effect, effect_from_spec
from energy.diagnosis.model_currents import basis_breakdown, clamps_at_zero, physics_basis, unclipped_prediction
from energy.sim import PAPER_GROUNDS


@pytest.fixture(scope="module")
def log():
    return coated_wood_log()


@pytest.fixture(scope="module")
def model(log):
    return coated_wood_model(log)


def test_physics_term_is_the_model_with_the_effect_on(model, log):
    basis = physics_basis(model)
    base = unclipped_prediction(model, log, basis)
    np.testing.assert_allclose(base, model.predict(log))  # clip off: the same numbers
    e = effect("turning_resistance")
    assert e.applies_to(model) and not effect("inertia").applies_to(model)
    prepared = e.prepare(model, log)
    full = PhysicsCurrentModel(ground=PAPER_GROUNDS["coated_wood"], fit_parameters=(),
                               effects=tuple(model.effects_) + ("turning_resistance",), clip_negative=False).fit([log])
    np.testing.assert_allclose(e.apply(np.array([1.0]), base, prepared), full.predict(log), atol=1e-9)
    np.testing.assert_allclose(e.apply(np.array([0.0]), base, prepared), base)
    assert not clamps_at_zero(model)


def test_rolling_resistance_binds_one_parameter_per_ground(model, log):
    e = effect("rolling_resistance").bind([log])
    assert [p.name for p in e.parameters] == ["rolling_resistance_coef_coated_wood"]
    assert effect_from_spec(e.spec()).parameters == e.parameters
    base = unclipped_prediction(model, log, physics_basis(model))
    same = e.apply(np.array([model.ground_.rolling_resistance_coef]), base, e.prepare(model, log))
    np.testing.assert_allclose(same, base, atol=1e-12)


def test_slope_needs_a_map_and_poses(log):
    assert "terrain map" in effect("slope").unsupported([log], None)


def test_parameter_errors_are_exact_at_the_nominal_and_the_surrogate_is_close(model, log):
    basis = physics_basis(model)
    base = unclipped_prediction(model, log, basis)
    for name, value in (("mass", 1.23), ("track_width", 2.1), ("rolling_resistance", 0.05)):
        e = effect(name).bind([log])
        prep = e.prepare(model, log)
        nominal = e.nominal(basis)
        np.testing.assert_allclose(e.apply(np.full(e.n_parameters, nominal), base, prep), base, atol=1e-12)
        exact = e.apply(np.full(e.n_parameters, value), base, prep)
        fast = e.apply_surrogate(np.full(e.n_parameters, value), base, prep)
        assert np.sqrt(np.mean((fast - exact) ** 2)) < 0.05 * max(np.sqrt(np.mean((exact - base) ** 2)), 0.1)


def test_track_width_cannot_show_on_measured_wheel_speeds(log):
    measured = dataclasses.replace(log, meta=dataclasses.replace(log.meta, velocity_source="measured",
                                                                 track_width_m=0.555))
    assert "measured wheel speeds" in effect("track_width").unsupported([measured], None)
    assert effect("track_width").unsupported([log], None) is None


def test_rotor_inertia_adds_a_current_in_proportion_to_each_sides_wheel_acceleration(model, log):
    e = effect("rotor_inertia").bind([log])
    assert e.applies_to(model) and e.kind == "parameter" and e.parameters[0].true_name == "rotor_inertia_kg_m2"
    no_inertia = PhysicsCurrentModel(ground=PAPER_GROUNDS["coated_wood"], fit_parameters=(),
                                     effects=[x for x in model.effects_ if x != "inertia"]).fit([log])
    assert not e.applies_to(no_inertia)  # without the term the inertia candidate adds it whole
    basis = physics_basis(model)
    base = unclipped_prediction(model, log, basis)
    prep = e.prepare(model, log)
    np.testing.assert_allclose(e.apply(np.array([1.0]), base, prep), base, atol=1e-12)
    added = e.apply(np.array([4.0]), base, prep) - base
    # the rotor's current, Jm N a_side / (r Kt) per side, written out from the robot's numbers
    rb, t = basis.robot, log.time_s
    half = rb.track_width_multiplier * rb.track_width_m / 2.0
    a_side = np.gradient(log.v_mps, t)[:, None] + np.gradient(log.omega_radps, t)[:, None] * half * np.array([-1, 1])
    motor = rb.motor
    jm = motor.rotor_inertia_kg_m2
    expected = 3.0 * motor.rotor_inertia_kg_m2 * motor.gear_ratio * a_side / (rb.wheel_radius_m
                                                                              * motor.torque_constant_nm_per_a)
    # where the motor is not at its torque limit (a step of the commands asks for more than it has)
    free = ~basis_breakdown(basis, log, robot=rb.replace(motor=dataclasses.replace(motor, rotor_inertia_kg_m2=4 * jm))
                            ).saturated
    moving = (np.abs(log.v_mps) + np.abs(log.omega_radps) > 1e-3) & free
    assert moving.mean() > 0.9
    sign = np.sign(np.column_stack([log.v_mps, log.v_mps]) + np.outer(log.omega_radps, [-half, half]))
    np.testing.assert_allclose((added * sign)[moving], expected[moving], atol=1e-9)
    assert np.abs(added).max() > 0.01  # the drive accelerates: the term shows
    fast = e.apply_surrogate(np.array([4.0]), base, prep)
    np.testing.assert_allclose(fast, base + added, atol=1e-9)  # linear in the scale: the table is exact
    text = e.describe(np.array([3.0]), [prep])
    assert text.startswith(f"rotor inertia {3 * jm:.3g} kg m^2 (x3 of the model's {jm:.3g} kg m^2: +")
    assert f"{2 * jm * motor.gear_ratio ** 2 / rb.wheel_radius_m ** 2:.3g} kg of rotating mass" in text


def test_a_withheld_rotor_inertia_is_found_with_its_value_and_nothing_is_added_where_nothing_is_missing():
    sc = small_scenario(scenario("rotor_inertia"))  # truth: 6 x the model's rotor inertia
    cands = ["rotor_inertia", "mass", "time_lag", "current_gain"]
    d = diagnose(sc.make_model(1), sc.make_logs(1), terrain=sc.terrain, effects=cands,
                 settings=FitSettings(n_bootstrap=50))
    assert d.current.chosen[:1] == ("rotor_inertia",)
    assert d.current.score("rotor_inertia").parameters["rotor_inertia_scale"] == pytest.approx(6.0, rel=0.1)
    assert any("rotor_inertia" in s for s in d.verdict)
    null = small_scenario(null_scenario())
    d0 = diagnose(null.make_model(1), null.make_logs(1), terrain=null.terrain, effects=cands,
                  settings=FitSettings(n_bootstrap=50))
    assert d0.current.chosen == ()


def test_quadratic_drag_adds_the_current_of_a_speed_squared_force_on_each_side(model, log):
    e = effect("quadratic_drag").bind([log])
    assert e.kind == "physics" and e.parameters[0].name == "drag_coef_n_s2_per_m2"
    assert effect_from_spec(e.spec()).name == "quadratic_drag"
    basis = physics_basis(model)
    base = unclipped_prediction(model, log, basis)
    prep = e.prepare(model, log)
    np.testing.assert_allclose(e.apply(np.array([0.0]), base, prep), base, atol=1e-12)
    np.testing.assert_allclose(e.priors([prep]), [0.0])
    added = e.apply(np.array([15.0]), base, prep) - base
    # F = c v_s |v_s| per side at the wheel, through the gear (its efficiency: the model has gear losses) and Kt
    rb = basis.robot
    half = rb.track_width_multiplier * rb.track_width_m / 2.0
    v_side = np.column_stack([log.v_mps - log.omega_radps * half, log.v_mps + log.omega_radps * half])
    motor = rb.motor
    assert "gear_losses" in basis.effects
    expected = 15.0 * v_side**2 * rb.wheel_radius_m / (motor.gear_ratio * motor.gear_efficiency
                                                        * motor.torque_constant_nm_per_a)
    np.testing.assert_allclose(added, expected, atol=1e-9)
    assert added.min() >= 0.0 and added.max() > 0.05  # the arc and the pivot drive the sides: the term shows
    text = e.describe(np.array([15.0]), [prep])
    assert text.startswith("speed-squared drag 15 N s^2/m^2 per side (15 N per side at 1 m/s")
    assert e.plausibility_flags(np.array([15.0])) == ()
    assert e.plausibility_flags(np.array([150.0]))  # beyond loose ground


def test_a_withheld_quadratic_drag_is_found_with_its_value_and_nothing_is_added_where_nothing_is_missing():
    sc = small_scenario(scenario("quadratic_drag"))  # truth: 12 N s^2/m^2 per side on a speed sweep
    cands = ["quadratic_drag", "mass", "rolling_resistance", "current_gain", "motor_constant", "idle_current"]
    d = diagnose(sc.make_model(1), sc.make_logs(1), terrain=sc.terrain, effects=cands,
                 settings=FitSettings(n_bootstrap=50))
    assert d.current.chosen[:1] == ("quadratic_drag",)
    assert d.current.score("quadratic_drag").parameters["drag_coef_n_s2_per_m2"] == pytest.approx(12.0, rel=0.1)
    assert any("quadratic_drag" in s for s in d.verdict)
    null = small_scenario(null_scenario("speed_sweep"))
    d0 = diagnose(null.make_model(1), null.make_logs(1), terrain=null.terrain, effects=cands,
                  settings=FitSettings(n_bootstrap=50))
    assert d0.current.chosen == ()
