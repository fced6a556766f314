"""Electrical candidates, fitted on battery power: armature heat, sensor power, control-board power.

Each one sets its quantity to the fitted value in place of what the model's physics basis
counts (nothing when the basis has the effect off, its robot's value when on), so the same
candidate finds a missing effect and a wrong value of a present one. They change the
battery power, never the drive current: they need logs with battery voltage and pack
current (:attr:`energy.logs.InteractionLog.has_battery_power`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..drivetrain import battery_side_w
from .effect_base import BasisEffect, EffectParameter
from .power_data import PowerInputs, power_inputs

__all__ = ["ElectricalEffect", "ArmatureHeatEffect", "SensorPowerEffect", "ControlPowerEffect"]


class ElectricalEffect(BasisEffect):
    """An effect of the battery power (kind ``"electrical"``); :meth:`apply` takes and returns ``(N, 1)`` W."""

    kind = "electrical"

    def unsupported(self, logs: Sequence[Any], terrain: Any, model: Any = None) -> str | None:
        missing = [k for k, log in enumerate(logs) if not getattr(log, "has_battery_power", False)]
        if missing:
            return (f"needs battery voltage and pack current (battery_voltage_v, battery_current_a) in every log; "
                    f"logs {missing[:5]!r} lack them")
        return None

    def prepare(self, model: Any, log: Any) -> PowerInputs:
        return power_inputs(self.basis(model), log)

    def basis_values(self, inputs: Sequence[PowerInputs]) -> list[float]:  # pragma: no cover - abstract
        """What the model's basis counts for each parameter (0 when the effect is off in it)."""
        raise NotImplementedError

    def priors(self, prepared: Sequence[Any] = ()) -> np.ndarray:
        """What the model's electrical basis already counts (its robot's value, or 0 with the effect off)."""
        if prepared and all(isinstance(p, PowerInputs) for p in prepared):
            return np.asarray(self.basis_values(prepared), dtype=np.float64)
        return self.initial


class ArmatureHeatEffect(ElectricalEffect):
    """Copper loss ``Ra I^2`` per side with a fitted armature resistance (battery side as the physics)."""

    name = "armature_heat"
    parameters = (EffectParameter("armature_resistance_ohm", 0.1, 0.0, 1000.0, "ohm", "armature_resistance_ohm",
                                  0.01, 100.0, "a drive motor's winding"),)
    description = "armature heat Ra I^2 (fitted resistance)"

    def basis_values(self, inputs: Sequence[PowerInputs]) -> list[float]:
        return [inputs[0].ra0_ohm]

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: PowerInputs) -> np.ndarray:
        p = prepared
        new = battery_side_w(p.back_emf_w + float(values[0]) * p.current_sq_a2, p.regen).sum(axis=1)
        old = battery_side_w(p.back_emf_w + p.ra0_ohm * p.current_sq_a2, p.regen).sum(axis=1)
        return predicted_a + (new - old)[:, None]


class SensorPowerEffect(ElectricalEffect):
    """Sensor power ``P_s + k |v|`` (W): a constant and a part growing with the speed."""

    name = "sensor"
    parameters = (EffectParameter("sensor_power_w", 1.0, 0.0, 500.0, "W", "sensor_power_w", 0.0, 200.0,
                                  "the sensors of a field robot"),
                  EffectParameter("sensor_power_per_mps_w", 0.5, 0.0, 100.0, "W s/m", "sensor_power_per_mps_w", 0.0,
                                  50.0, "sensing that works harder with speed"))
    description = "sensor power (constant + per m/s)"

    def basis_values(self, inputs: Sequence[PowerInputs]) -> list[float]:
        return [inputs[0].sensor0[0], inputs[0].sensor0[1]]

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: PowerInputs) -> np.ndarray:
        p = prepared
        change = (float(values[0]) - p.sensor0[0]) + (float(values[1]) - p.sensor0[1]) * p.speed_mps
        return predicted_a + change[:, None]


class ControlPowerEffect(ElectricalEffect):
    """Control-board power: ``standby`` when stopped, ``stable`` when moving (the start-up window
    after each start from rest adds the robot's rated start-up excess over its stable power)."""

    name = "control"
    parameters = (EffectParameter("control_standby_power_w", 1.0, 0.0, 500.0, "W", "control_standby_power_w", 0.0,
                                  200.0, "a robot's computers and drivers"),
                  EffectParameter("control_stable_power_w", 1.0, 0.0, 500.0, "W", "control_stable_power_w", 0.0,
                                  200.0, "a robot's computers and drivers"))
    description = "control-board power (standby when stopped, stable when moving)"

    def basis_values(self, inputs: Sequence[PowerInputs]) -> list[float]:
        control = np.concatenate([p.control0_w for p in inputs])
        stopped = np.concatenate([p.stopped for p in inputs]) > 0.5
        stable = ~stopped & ~(np.concatenate([p.startup for p in inputs]) > 0.5)
        return [float(np.median(control[m])) if m.any() else float("nan") for m in (stopped, stable)]

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: PowerInputs) -> np.ndarray:
        p = prepared
        new = float(values[0]) * p.stopped + float(values[1]) * (1.0 - p.stopped) + p.startup_excess_w * p.startup
        return predicted_a + (new - p.control0_w)[:, None]
