"""Tests of energy.diagnosis.effects_learned: the regime features and the ridge-penalised learned residual."""

import numpy as np
import pytest

from energy import InteractionLog
from energy.diagnosis import effect
from energy.diagnosis.effects_learned import LEARNED_FEATURES, LearnedResidualEffect, regime_features
from terrawatt_base.errors import InvalidParameterError


def _log() -> InteractionLog:
    t = np.arange(5) * 0.5
    v = np.array([0.0, 0.5, 1.0, 1.0, 0.0])
    w = np.array([0.0, 0.0, -0.5, 0.0, 1.0])  # standing still, straight, arc, straight, pivot
    return InteractionLog(t, v, w, np.ones(5), np.ones(5), t, np.full(5, 9.81))


def test_regime_features_of_each_sample():
    x = regime_features(_log())
    assert x.shape == (5, len(LEARNED_FEATURES)) and LEARNED_FEATURES[0] == "one"
    np.testing.assert_array_equal(x[:, 0], 1.0)
    np.testing.assert_array_equal(x[:, 1], [0.0, 0.5, 1.0, 1.0, 0.0])  # |v|
    np.testing.assert_array_equal(x[:, 2], [0.0, 0.0, 0.5, 0.0, 1.0])  # |omega|
    np.testing.assert_allclose(x[:, 3], np.gradient([0.0, 0.5, 1.0, 1.0, 0.0], np.arange(5) * 0.5))  # dv/dt
    np.testing.assert_allclose(x[:, 4], np.abs(x[:, 3]))
    np.testing.assert_array_equal(x[:, 5], [0.0, 0.0, 0.5, 0.0, 0.0])  # |v omega|
    np.testing.assert_array_equal(x[:, 6], [0.0, 0.0, 0.0, 0.0, 1.0])  # pivot


def test_the_learned_residual_adds_features_times_coefficients_per_side():
    e = LearnedResidualEffect()
    assert e.kind == "learned" and e.n_parameters == 2 * len(LEARNED_FEATURES)
    assert [p.name for p in e.parameters][:2] == ["one_left", "abs_v_left"]
    assert e.parameters[len(LEARNED_FEATURES)].name == "one_right"
    log = _log()
    prepared = e.prepare(None, log)
    values = np.zeros(e.n_parameters)
    values[0] = 0.5  # one_left
    values[len(LEARNED_FEATURES) + 1] = 2.0  # abs_v_right
    base = np.ones((5, 2))
    out = e.apply(values, base, prepared)
    np.testing.assert_allclose(out[:, 0], 1.5)
    np.testing.assert_allclose(out[:, 1], 1.0 + 2.0 * log.v_mps)
    np.testing.assert_allclose(e.penalty(values), 0.1 * values)  # sqrt of the 1e-2 ridge weight


def test_the_catalogue_names_it():
    assert effect("learned_residual").kind == "learned"
    with pytest.raises(InvalidParameterError, match="effect 'learned_residual' has 14 parameters, got 3 values"):
        LearnedResidualEffect().values_dict(np.zeros(3))
