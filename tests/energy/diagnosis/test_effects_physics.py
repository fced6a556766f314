"""Tests of energy.diagnosis.effects_physics: switched-off physics terms and errors of the model's parameters."""

import dataclasses

import numpy as np
import pytest
from effect_samples import coated_wood_log, coated_wood_model

from energy import PhysicsCurrentModel
from energy.diagnosis import effect, effect_from_spec
from energy.diagnosis.model_currents import clamps_at_zero, physics_basis, unclipped_prediction
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
