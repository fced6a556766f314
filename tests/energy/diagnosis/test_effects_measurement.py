"""Tests of energy.diagnosis.effects_measurement: current gain and offset, time lag (vectorised over samples)."""

import numpy as np
import pytest
from effect_samples import coated_wood_log, coated_wood_model

from energy.diagnosis import effect


@pytest.fixture(scope="module")
def log():
    return coated_wood_log()


@pytest.fixture(scope="module")
def model(log):
    return coated_wood_model(log)


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
