"""Measurement candidates: per-side current gain and offset, an idle current, a time lag between streams."""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..logs import InteractionLog
from .effect_base import Effect, EffectParameter

__all__ = ["MEASUREMENT_CANDIDATES", "CurrentGainEffect", "CurrentOffsetEffect", "IdleCurrentEffect", "TimeLagEffect"]

#: Measurement-effect candidates, in the order they are composed.
MEASUREMENT_CANDIDATES: tuple[str, ...] = ("idle_current", "current_offset", "current_gain", "time_lag")


class IdleCurrentEffect(Effect):
    """A current drawn whatever the motion, the same on both sides: ``I + idle``."""

    name = "idle_current"
    kind = "measurement"
    parameters = (EffectParameter("idle_current_a", 0.0, -5.0, 5.0, "A", "idle_current_a"),)
    description = "idle current (same on both sides)"

    def prepare(self, model: Any, log: InteractionLog) -> None:
        return None

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Any) -> np.ndarray:
        return predicted_a + values[0]


class CurrentOffsetEffect(Effect):
    """A per-side current offset (sensor zero): ``I + [offset_left, offset_right]``."""

    name = "current_offset"
    kind = "measurement"
    parameters = (EffectParameter("offset_left_a", 0.0, -5.0, 5.0, "A"),
                  EffectParameter("offset_right_a", 0.0, -5.0, 5.0, "A"))
    description = "per-side current offset"

    def prepare(self, model: Any, log: InteractionLog) -> None:
        return None

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Any) -> np.ndarray:
        return predicted_a + values[None, :2]


class CurrentGainEffect(Effect):
    """A per-side current gain (sensor calibration, wear): ``I * [gain_left, gain_right]``."""

    name = "current_gain"
    kind = "measurement"
    parameters = (EffectParameter("gain_left", 1.0, 0.3, 3.0, "1", "gain_left"),
                  EffectParameter("gain_right", 1.0, 0.3, 3.0, "1", "gain_right"))
    description = "per-side current gain"

    def prepare(self, model: Any, log: InteractionLog) -> None:
        return None

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Any) -> np.ndarray:
        return predicted_a * values[None, :2]


class TimeLagEffect(Effect):
    """A lag between the commands (or speeds) and the currents: the prediction at ``t - lag_s``.

    Shifted by linear interpolation on the log's clock (the ends hold their values); a
    positive lag means the currents follow the logged motion late (e.g. velocity tracking).
    """

    name = "time_lag"
    kind = "measurement"
    parameters = (EffectParameter("lag_s", 0.0, -0.5, 0.5, "s", "lag_s"),)
    description = "time lag between the motion and the current streams"
    period_s: float = 0.0

    def bind(self, logs: Sequence[Any], terrain: Any = None, robot: Any = None) -> Effect:
        out = copy.copy(self)
        periods = [float(np.median(np.diff(log.time_s))) for log in logs if len(log) > 1]
        out.period_s = float(np.median(periods)) if periods else self.period_s
        return out

    def negligible(self, values: np.ndarray) -> bool:
        # a shift below one sample period only smooths the prediction by interpolation
        return abs(float(values[0])) < self.period_s

    def prepare(self, model: Any, log: InteractionLog) -> np.ndarray:
        return np.asarray(log.time_s)

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: np.ndarray) -> np.ndarray:
        t = prepared
        shifted = t - float(values[0])
        return np.column_stack([np.interp(shifted, t, predicted_a[:, k]) for k in range(predicted_a.shape[1])])
