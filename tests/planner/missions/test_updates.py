"""Tests of planner.missions.updates: the charge errors that decide whether a model update is kept."""

from __future__ import annotations

import numpy as np
import pytest

from energy import InteractionLog, LogMeta
from planner.missions.updates import charge_error, validation_error
from terrawatt_base.errors import InvalidParameterError


class _Constant:
    """Predicts ``amps`` on each side."""

    def __init__(self, amps: float) -> None:
        self.amps = amps

    def predict(self, log):
        return np.full((len(log), 2), self.amps)


def _log(amps: float, n: int = 101) -> InteractionLog:
    t = np.linspace(0.0, 1.0, n)
    return InteractionLog(t, np.full(n, 0.5), np.zeros(n), np.full(n, amps), np.full(n, amps), t, np.full(n, 9.81),
                          meta=LogMeta())


def test_charge_error_is_relative_on_the_selected_samples():
    measured = np.column_stack([np.full(4, 2.0), np.full(4, -2.0)])  # |I| counts, whatever the sign
    predicted = np.column_stack([np.full(4, 3.0), np.full(4, 3.0)])
    dt = np.full(4, 0.5)
    assert charge_error(predicted, measured, dt, np.ones(4, bool)) == pytest.approx(0.5)
    predicted[2:] = 2.0
    assert charge_error(predicted, measured, dt, np.array([False, False, True, True])) == 0.0


def test_validation_error_compares_the_integrated_currents():
    logs = [_log(4.0), _log(4.0)]
    assert validation_error(_Constant(4.0), logs) == pytest.approx(0.0, abs=1e-12)
    assert validation_error(_Constant(5.0), logs) == pytest.approx(0.25)
    with pytest.raises(InvalidParameterError, match="validation logs hold no current"):
        validation_error(_Constant(1.0), [_log(0.0)])
