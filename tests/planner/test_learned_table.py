"""Tests of planner.learned_table: table grids, checked current predictions, models with an interval."""

from __future__ import annotations

import numpy as np
import pytest

from energy import InteractionLog, LogMeta
from planner.learned_table import increasing_grid, model_gives_interval, predict_currents
from terrawatt_base.errors import InvalidParameterError


def _log(n: int = 20) -> InteractionLog:
    return InteractionLog(np.arange(n) / 100, np.full(n, 0.5), np.zeros(n), np.full(n, 4.0), np.full(n, 4.0),
                          np.arange(n) / 100, np.full(n, 9.81), meta=LogMeta())


class _Model:
    def __init__(self, predict) -> None:
        self.predict = predict


def test_a_grid_is_a_strictly_increasing_array_of_positive_numbers():
    np.testing.assert_array_equal(increasing_grid("speeds_mps", (0.25, 0.5, 1.0)), [0.25, 0.5, 1.0])
    for bad in ((), (0.5, 0.5), (1.0, 0.5), (0.0, 1.0), (0.5, np.inf), [[0.5, 1.0]]):
        with pytest.raises(InvalidParameterError, match="speeds_mps must be a non-empty, strictly increasing"):
            increasing_grid("speeds_mps", bad)
    with pytest.raises(InvalidParameterError, match="speeds_mps must be a sequence of numbers"):
        increasing_grid("speeds_mps", ("fast",))


def test_predicted_currents_are_checked_and_the_model_named():
    log = _log()
    np.testing.assert_array_equal(predict_currents(_Model(lambda lg: np.ones((len(lg), 2))), log, "m"),
                                  np.ones((20, 2)))
    with pytest.raises(InvalidParameterError, match=r"model A must predict finite \(N, 2\) .* got shape \(20, 3\)"):
        predict_currents(_Model(lambda lg: np.ones((len(lg), 3))), log, "model A")
    with pytest.raises(InvalidParameterError, match="got non-finite values"):
        predict_currents(_Model(lambda lg: np.full((len(lg), 2), np.nan)), log, "model A")

    def fails(lg):
        raise ValueError("wrong features")

    with pytest.raises(InvalidParameterError, match="model A could not predict currents for a 20-sample log"):
        predict_currents(_Model(fails), log, "model A")


def test_a_model_gives_an_interval_only_with_a_predictive_distribution():
    class Spread:
        gives_interval = True

        def predict_distribution(self, log):
            return None

    class Flag:
        gives_interval = True

    assert model_gives_interval(Spread())
    assert not model_gives_interval(Flag()) and not model_gives_interval(object())
