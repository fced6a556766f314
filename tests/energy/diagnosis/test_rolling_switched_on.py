"""Per-ground rolling resistance for a model without Coulomb friction: Coulomb switched on, one coefficient per ground."""

import numpy as np
import pytest

from energy import PhysicsCurrentModel, TruthSimulator, robot_preset
from energy.diagnosis import effect
from energy.diagnosis.model_currents import motoring_currents_a, physics_basis, unclipped_prediction
from energy.sim import PAPER_GROUNDS, NoiseModel

GROUNDS = ("coated_wood", "snow_over_concrete")


@pytest.fixture(scope="module")
def logs():
    sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, noise=NoiseModel.off(), velocity_time_constant_s=0.0)
    t = np.arange(300) * 0.01
    v = np.where(t < 2.5, 0.6, 0.0)
    ground = np.where(t < 1.2, GROUNDS[0], GROUNDS[1])
    return [sim.simulate_commands(t, v, np.zeros_like(t), ground=list(ground), seed=3)]


@pytest.fixture(scope="module")
def model(logs):
    return PhysicsCurrentModel(ground=PAPER_GROUNDS[GROUNDS[0]], fit_parameters=(), effects=("inertia",),
                               clip_negative=False).fit(logs)


def test_offered_only_with_two_grounds_when_the_model_lacks_coulomb(model, logs):
    e = effect("rolling_resistance")
    assert e.applies_to(model)
    assert e.unsupported(logs, None, model) is None
    one = [logs[0].slice(0.0, 1.0)]
    assert "coulomb_friction candidate" in e.unsupported(one, None, model)
    with_coulomb = PhysicsCurrentModel(ground=PAPER_GROUNDS[GROUNDS[0]], fit_parameters=(),
                                       effects=("inertia", "coulomb_friction")).fit(logs)
    assert e.unsupported(one, None, with_coulomb) is None  # a coefficient error of the model's own Coulomb term


def test_switches_coulomb_on_with_a_coefficient_per_ground(model, logs):
    log = logs[0]
    e = effect("rolling_resistance").bind(logs)
    assert [p.name for p in e.parameters] == [f"rolling_resistance_coef_{g}" for g in sorted(GROUNDS)]
    basis = physics_basis(model)
    base = unclipped_prediction(model, log, basis)
    prep = e.prepare(model, log)
    zero = e.apply(np.zeros(2), base, prep)
    np.testing.assert_allclose(zero, base, atol=1e-12)  # coefficient 0: no Coulomb force, nothing changes
    coefs = np.array([0.05, 0.3])  # sorted order: coated_wood, snow_over_concrete
    got = e.apply(coefs, base, prep)
    grounds = [PAPER_GROUNDS[GROUNDS[0]].replace(rolling_resistance_coef=c) for c in coefs]
    idx = np.where(np.asarray(log.ground) == GROUNDS[0], 0, 1)
    want = base + motoring_currents_a(basis, log, effects=("inertia", "coulomb_friction"), ground=grounds,
                                      ground_index=idx) - motoring_currents_a(basis, log)
    np.testing.assert_allclose(got, want, atol=1e-12)
    moving = np.abs(log.v_mps) > 0.1
    snow = moving & (idx == 1)
    wood = moving & (idx == 0)
    assert (got - base)[snow].mean() > 3.0 * (got - base)[wood].mean() > 0.0  # the looser ground draws more


def test_table_interpolation_by_slot_equals_per_sample(model, logs):
    from energy.diagnosis.model_currents import ParameterTable
    from terrawatt_base.errors import InvalidParameterError

    log = logs[0]
    e = effect("rolling_resistance").bind(logs)
    prep = e.prepare(model, log)
    base = unclipped_prediction(model, log, physics_basis(model))
    for values in (np.array([0.013, 0.27]), np.array([0.0, 1.0]), np.array([0.5, 0.5])):
        fast = e.apply_surrogate(values, base, prep)
        slow = base + prep.table.at(e.per_sample(values, prep)) - prep.base_a
        np.testing.assert_array_equal(fast, slow)
        np.testing.assert_allclose(fast, e.apply(values, base, prep), atol=2e-3)  # the table is a surrogate
    with pytest.raises(InvalidParameterError, match="no slots"):
        ParameterTable(lambda x: np.zeros((3, 2)), 0.0, 1.0, 0.5).at_slots([0.1])
    with pytest.raises(InvalidParameterError, match=r"a value for each of \d+ slots"):
        prep.table.at_slots([0.1])
