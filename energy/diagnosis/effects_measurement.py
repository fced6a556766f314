"""Measurement candidates: per-side current gain and offset, idle and rest levels, time lags between streams."""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..logs import InteractionLog, rest_samples
from ..models.base import CurrentModel
from .effect_base import BasisEffect, Effect, EffectParameter

__all__ = [
    "MEASUREMENT_CANDIDATES",
    "IMU_LAG_GRID_S",
    "OFFSET_PLAUSIBLE_A",
    "SENSOR_GAIN_PLAUSIBLE",
    "LAG_PLAUSIBLE_S",
    "CurrentGainEffect",
    "CurrentOffsetEffect",
    "IdleCurrentEffect",
    "RestCurrentEffect",
    "TimeLagEffect",
    "ImuLagEffect",
    "reads_vibration",
]

#: Measurement-effect candidates, in the order they are composed.
MEASUREMENT_CANDIDATES: tuple[str, ...] = ("idle_current", "rest_current", "current_offset", "current_gain", "time_lag",
                                           "imu_lag")
#: Lags (s) at which :class:`ImuLagEffect` re-predicts a log; its fit interpolates between them.
IMU_LAG_GRID_S: tuple[float, ...] = (-0.4, -0.3, -0.2, -0.1, 0.0, 0.1, 0.2, 0.3, 0.4)
#: Plausible current offsets and idle currents (A).
OFFSET_PLAUSIBLE_A = (-1.0, 1.0)
#: Plausible lags between streams (s).
LAG_PLAUSIBLE_S = (-0.5, 0.5)
_OFFSET_NOTE = "a sensor zero or an idle draw of at most 1 A"
_GAIN_NOTE = "a current sensor's calibration error (uncalibrated driver channels are off by tens of %)"
#: Plausible gains of a current sensor channel.
SENSOR_GAIN_PLAUSIBLE = (0.7, 1.4)
_LAG_NOTE = "a logging delay of at most half a second"


class IdleCurrentEffect(Effect):
    """A current drawn whatever the motion, the same on both sides: ``I + idle``."""

    name = "idle_current"
    kind = "measurement"
    parameters = (EffectParameter("idle_current_a", 0.0, -5.0, 5.0, "A", "idle_current_a", *OFFSET_PLAUSIBLE_A,
                                  _OFFSET_NOTE),)
    description = "idle current (same on both sides)"

    def prepare(self, model: Any, log: InteractionLog) -> None:
        return None

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Any) -> np.ndarray:
        return predicted_a + values[0]


class RestCurrentEffect(Effect):
    """The level the sensor logs standing still is off: ``I + [rest_left, rest_right]`` at the
    rest samples (:func:`energy.logs.rest_samples`: wheels still, not accelerating) only.

    Standing still is not driving: a model whose rest level is wrong (e.g. an idle current
    that also carries the current of driving) is off there and nowhere else, which no offset
    of the whole prediction can fix.
    """

    name = "rest_current"
    kind = "measurement"
    parameters = (EffectParameter("rest_left_a", 0.0, -5.0, 5.0, "A", None, *OFFSET_PLAUSIBLE_A, _OFFSET_NOTE),
                  EffectParameter("rest_right_a", 0.0, -5.0, 5.0, "A", None, *OFFSET_PLAUSIBLE_A, _OFFSET_NOTE))
    description = "level of the current logged standing still (per side)"

    def unsupported(self, logs: Sequence[Any], terrain: Any, model: Any = None) -> str | None:
        if not any(rest_samples(log).any() for log in logs if len(log) > 0):
            return "no log stands still"
        return None

    def prepare(self, model: Any, log: InteractionLog) -> np.ndarray:
        return rest_samples(log)[:, None].astype(np.float64)

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: np.ndarray) -> np.ndarray:
        return predicted_a + prepared * values[None, :2]


class CurrentOffsetEffect(Effect):
    """A per-side current offset (sensor zero): ``I + [offset_left, offset_right]``."""

    name = "current_offset"
    kind = "measurement"
    parameters = (EffectParameter("offset_left_a", 0.0, -5.0, 5.0, "A", None, *OFFSET_PLAUSIBLE_A, _OFFSET_NOTE),
                  EffectParameter("offset_right_a", 0.0, -5.0, 5.0, "A", None, *OFFSET_PLAUSIBLE_A, _OFFSET_NOTE))
    description = "per-side current offset"

    def prepare(self, model: Any, log: InteractionLog) -> None:
        return None

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Any) -> np.ndarray:
        return predicted_a + values[None, :2]


class CurrentGainEffect(BasisEffect):
    """A per-side current gain (sensor calibration, wear) on the current above the sensor's rest
    offset: ``rest + (I - rest) * [gain_left, gain_right]``.

    The rest level (the model's, or the robot's ``rest_current_a`` for a model that is not a
    physics one) is what the sensor reads with no current drawn; a gain error scales what is
    drawn, not that zero — scaling it too would make a gain pay for an offset.
    """

    name = "current_gain"
    kind = "measurement"
    parameters = (EffectParameter("gain_left", 1.0, 0.3, 3.0, "1", "gain_left", *SENSOR_GAIN_PLAUSIBLE, _GAIN_NOTE),
                  EffectParameter("gain_right", 1.0, 0.3, 3.0, "1", "gain_right", *SENSOR_GAIN_PLAUSIBLE, _GAIN_NOTE))
    description = "per-side current gain (above the rest offset)"

    def prepare(self, model: Any, log: InteractionLog) -> np.ndarray:
        return np.asarray(self.basis(model).rest_current_a, dtype=np.float64)

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: np.ndarray) -> np.ndarray:
        rest = prepared[None, :]
        return rest + (predicted_a - rest) * values[None, :2]


class TimeLagEffect(Effect):
    """A lag between the commands (or speeds) and the currents: the prediction at ``t - lag_s``.

    Shifted by linear interpolation on the log's clock (the ends hold their values); a
    positive lag means the currents follow the logged motion late (e.g. velocity tracking).
    """

    name = "time_lag"
    kind = "measurement"
    parameters = (EffectParameter("lag_s", 0.0, -0.5, 0.5, "s", "lag_s", *LAG_PLAUSIBLE_S, _LAG_NOTE),)
    description = "time lag between the motion and the current streams"
    period_s: float = 0.0
    scan = tuple(np.round(np.arange(-0.5, 0.5001, 0.02), 2).tolist())

    def bind(self, logs: Sequence[Any], terrain: Any = None, robot: Any = None) -> Effect:
        out = copy.copy(self)
        periods = [float(np.median(np.diff(log.time_s))) for log in logs if len(log) > 1]
        out.period_s = float(np.median(periods)) if periods else self.period_s
        return out

    def negligible(self, values: np.ndarray) -> bool:
        # Shifted by linear interpolation, a prediction is also smoothed, most at half a sample (the mean of two
        # neighbours), not at all at a whole one: a fit that gains only by smoothing (noisy model inputs) lands
        # within half a sample of 0. Beyond it a shift is a shift: a lag just under one sample (0.15 s at 6.5 Hz)
        # is a lag, whose fit lands on the whole sample where interpolation smooths nothing.
        return abs(float(values[0])) < 0.5 * self.period_s

    def prepare(self, model: Any, log: InteractionLog) -> np.ndarray:
        return np.asarray(log.time_s)

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: np.ndarray) -> np.ndarray:
        t = prepared
        shifted = t - float(values[0])
        return np.column_stack([np.interp(shifted, t, predicted_a[:, k]) for k in range(predicted_a.shape[1])])


#: Switches of a model configuration that make it read the IMU stream (those of
#: :class:`~energy.models.config.EstimatorConfig`): value when the feature is off.
_IMU_FEATURES_OFF: dict[str, Any] = {"local_spectrum": False, "run_features": "none", "use_yaw_slip": False}


def reads_vibration(model: Any) -> bool:
    """Whether ``model`` predicts from the IMU stream, read from what it declares (no model is run).

    - A model wrapping another (``model.base``, a :class:`~energy.models.base.CurrentModel`:
      the corrected and the adapted models) reads it when the wrapped one does.
    - Otherwise its configuration decides: the resolved one of a fitted model
      (``config_``, e.g. the vibration estimator's
      :class:`~energy.models.config.EstimatorConfig`), else ``config`` when it is not a
      preset name. A configuration with a vibration band (``band_hz``) reads the IMU unless
      it has the estimator's feature switches and every one is off (no local spectrum, no
      run features, no yaw-rate slip).

    An unfitted estimator configured by a preset name is not resolved here (that would load
    torch): fitted models, the only ones the diagnosis takes, carry ``config_``.
    """
    inner = getattr(model, "base", None)
    if isinstance(inner, CurrentModel) and inner is not model:
        return reads_vibration(inner)
    cfg = getattr(model, "config_", None)
    if cfg is None:
        cfg = getattr(model, "config", None)
    if cfg is None or isinstance(cfg, str) or getattr(cfg, "band_hz", None) is None:
        return False
    switches = {k: getattr(cfg, k) for k in _IMU_FEATURES_OFF if hasattr(cfg, k)}
    return not switches or any(v != _IMU_FEATURES_OFF[k] for k, v in switches.items())


class ImuLagEffect(Effect):
    """A clock offset between the IMU and the drive streams: the model fed the IMU stream
    shifted by ``lag_s`` (positive: the logged IMU times run late, the true vibration came
    ``lag_s`` earlier).

    Only for models that read the IMU (the vibration estimators). The log is re-predicted at
    each lag of :data:`IMU_LAG_GRID_S` once (:meth:`prepare`); the effect adds the difference
    to the prediction at lag 0, interpolated linearly between grid lags, so it composes with
    the other effects.
    """

    name = "imu_lag"
    kind = "measurement"
    parameters = (EffectParameter("lag_s", 0.0, IMU_LAG_GRID_S[0], IMU_LAG_GRID_S[-1], "s", "imu_lag_s",
                                  *LAG_PLAUSIBLE_S, _LAG_NOTE),)
    description = "time lag between the IMU and the drive streams"
    period_s: float = 0.0
    scan = IMU_LAG_GRID_S

    def applies_to(self, model: Any) -> bool:
        # a corrected model that already carries an IMU lag has it
        has = any(getattr(e, "name", None) == self.name for e in getattr(model, "effects_", ()))
        return reads_vibration(model) and not has

    def unsupported(self, logs: Sequence[Any], terrain: Any, model: Any = None) -> str | None:
        if any(getattr(log, "accel_time_s", None) is None or len(log.accel_time_s) < 2 for log in logs):
            return "a log has no IMU stream"
        return None

    def bind(self, logs: Sequence[Any], terrain: Any = None, robot: Any = None) -> Effect:
        out = copy.copy(self)
        periods = [float(np.median(np.diff(log.accel_time_s))) for log in logs if len(log.accel_time_s) > 1]
        out.period_s = float(np.median(periods)) if periods else self.period_s
        return out

    def negligible(self, values: np.ndarray) -> bool:
        # below one IMU sample the spectra barely move: a fit there is noise
        return abs(float(values[0])) < 0.5 * self.period_s

    def prepare(self, model: Any, log: InteractionLog) -> np.ndarray:
        grid = np.asarray(IMU_LAG_GRID_S)
        preds = [np.asarray(model.predict(dataclasses.replace(log, accel_time_s=log.accel_time_s - lag)),
                            dtype=np.float64) for lag in grid]
        table = np.stack(preds)  # (lags, N, 2)
        return table - table[int(np.argmin(np.abs(grid)))][None]

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: np.ndarray) -> np.ndarray:
        grid = np.asarray(IMU_LAG_GRID_S)
        lag = float(np.clip(values[0], grid[0], grid[-1]))
        k = int(np.clip(np.searchsorted(grid, lag) - 1, 0, grid.size - 2))
        w = (lag - grid[k]) / (grid[k + 1] - grid[k])
        return predicted_a + (1.0 - w) * prepared[k] + w * prepared[k + 1]
