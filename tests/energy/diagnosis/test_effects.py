"""The effect catalogue: names, lookup errors, vectorised apply, physics terms against the model."""

import numpy as np
import pytest

from energy import PhysicsCurrentModel, TruthSimulator, robot_preset
from energy.sim import PAPER_GROUNDS
from terrawatt_base.errors import InvalidParameterError, UnknownNameError
from energy.diagnosis import EFFECTS_CATALOGUE, NOT_IDENTIFIABLE_FROM_CURRENT, EffectParameter, effect, effect_from_spec
from energy.diagnosis.effects import resolve_effects
from energy.diagnosis.model_currents import clamps_at_zero, physics_basis, unclipped_prediction
from energy.sim import NoiseModel


@pytest.fixture(scope="module")
def log():
    sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, noise=NoiseModel.off(), velocity_time_constant_s=0.0)
    t = np.arange(400) * 0.01
    v = np.where(t < 2, 0.4, 0.0)
    w = np.where(t < 2, 0.3, 0.8)
    return sim.simulate_commands(t, v, w, ground="coated_wood", seed=1)


@pytest.fixture(scope="module")
def model(log):
    effects = [e for e in EFFECTS_CATALOGUE[:12] if e not in ("slope", "turning_resistance")]
    return PhysicsCurrentModel(ground=PAPER_GROUNDS["coated_wood"], fit_parameters=(), effects=effects,
                               clip_negative=False).fit([log])


def test_catalogue_names_every_drive_effect_and_lookup():
    for name in ("slope", "inertia", "turning_resistance", "gear_losses", "speed_saturation", "mass", "track_width",
                 "rolling_resistance", "motor_constant", "current_gain", "current_offset", "time_lag", "idle_current"):
        assert name in EFFECTS_CATALOGUE
        assert effect(name).name == name
    with pytest.raises(UnknownNameError, match="not in the catalogue"):
        effect("warp_drive")
    for name in NOT_IDENTIFIABLE_FROM_CURRENT:  # fitted on battery power, not on the currents
        assert name in EFFECTS_CATALOGUE and effect(name).kind == "electrical"
    with pytest.raises(InvalidParameterError, match="duplicate"):
        resolve_effects(["mass", "mass"])
    with pytest.raises(InvalidParameterError, match="must be a dict"):
        effect_from_spec("mass")


def test_effect_parameter_validates():
    with pytest.raises(InvalidParameterError, match="below high"):
        EffectParameter("g", 1.0, 2.0, 1.0, "1")
    with pytest.raises(InvalidParameterError, match="initial"):
        EffectParameter("g", 5.0, 0.0, 1.0, "1")


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


def test_rolling_resistance_binds_one_parameter_per_ground(model, log):
    e = effect("rolling_resistance").bind([log])
    assert [p.name for p in e.parameters] == ["rolling_resistance_coef_coated_wood"]
    assert effect_from_spec(e.spec()).parameters == e.parameters
    base = unclipped_prediction(model, log, physics_basis(model))
    same = e.apply(np.array([model.ground_.rolling_resistance_coef]), base, e.prepare(model, log))
    np.testing.assert_allclose(same, base, atol=1e-12)


def test_slope_needs_a_map_and_poses(log):
    assert "terrain map" in effect("slope").unsupported([log], None)


def test_parameter_table_is_exact_at_nodes_and_linear_between():
    from energy.diagnosis.model_currents import ParameterTable

    base = np.column_stack([np.linspace(0.0, 1.0, 5), np.linspace(1.0, 2.0, 5)])
    table = ParameterTable(lambda x: base * x ** 2, 0.0, 2.0, 0.7, n_nodes=5)
    assert 0.7 in table.nodes and table.n_computed == 0  # the nominal is a node; nothing computed yet
    np.testing.assert_allclose(table.at(0.7), base * 0.49)
    np.testing.assert_allclose(table.at(1.5), base * 2.25)
    np.testing.assert_allclose(table.at(1.75), base * (2.25 + 4.0) / 2.0)  # linear between 1.5 and 2.0
    per_sample = np.array([0.0, 0.7, 1.75, 2.0, 9.0])  # clipped to the bounds
    expected = base * np.array([0.0, 0.49, 3.125, 4.0, 4.0])[:, None]
    np.testing.assert_allclose(table.at(per_sample), expected)
    assert table.nodes.size == 6 and table.n_computed == 6


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
    import dataclasses

    measured = dataclasses.replace(log, meta=dataclasses.replace(log.meta, velocity_source="measured",
                                                                 track_width_m=0.555))
    assert "measured wheel speeds" in effect("track_width").unsupported([measured], None)
    assert effect("track_width").unsupported([log], None) is None
