"""Battery power for the diagnosis: measured (voltage x pack current) and predicted from the measured drive currents.

The power stage of :func:`energy.diagnosis.diagnose` explains the battery power beyond what
the measured drive currents draw. Per log, :func:`power_inputs` computes from the model's
physics basis (:func:`~energy.diagnosis.model_currents.physics_basis`) and the log:

- the motor speed ``omega_m`` of each side (the basis physics for the logged ``v`` and
  ``omega``) and the measured motor current ``I`` of each side (the logged current minus the
  basis's idle current, which the current sensor reads but the pack does not deliver);
- per side the back-EMF power ``Ke |omega_m| I`` and ``I^2`` (armature heat ``Ra I^2``);
- the electronics masks: stopped, moving, and the start-up window after each start.

The predicted battery power is, as in :func:`energy.drivetrain.drive_power`, per side
``P_e = Ke |omega_m| I + Ra I^2`` (``Ra`` only when the basis has ``armature_heat``), counted
in full when >= 0 and times ``regen_efficiency`` when negative, summed over the sides, plus
the electronics the basis has switched on (``sensor``: ``sensor_power_w +
sensor_power_per_mps_w |v|``; ``control``: :func:`energy.drivetrain.control_power`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from terrawatt_base.errors import DataError

from ..drivetrain import battery_side_w, control_power
from ..logs import InteractionLog
from ..models.base import log_currents
from .model_currents import PhysicsBasis, basis_breakdown

__all__ = ["POWER_EFFECTS", "PowerInputs", "power_logs_missing", "check_power_logs", "power_inputs",
           "predicted_battery_power_w"]

#: Electrical candidates, fitted on battery power: they change power, not the drive current.
POWER_EFFECTS: tuple[str, ...] = ("armature_heat", "sensor", "control")


@dataclass(frozen=True, eq=False)
class PowerInputs:
    """What the battery power of one log is predicted from (see the module docstring).

    ``back_emf_w`` and ``current_sq_a2`` are ``(N, 2)`` (per side ``Ke |omega_m| I`` and
    ``I^2``); ``speed_mps`` is ``|v|``; ``stopped`` / ``startup`` are 0/1 floats (the rest is
    moving, start-up included); ``ra0_ohm``, ``sensor0`` (W, W per m/s), ``control0_w`` are
    what the basis already counts; ``startup_excess_w`` the robot's start-up power above its
    stable one; ``regen`` its regeneration efficiency.
    """

    back_emf_w: np.ndarray
    current_sq_a2: np.ndarray
    speed_mps: np.ndarray
    stopped: np.ndarray
    startup: np.ndarray
    ra0_ohm: float
    sensor0: tuple[float, float]
    control0_w: np.ndarray
    startup_excess_w: float
    regen: float


def power_logs_missing(logs: Sequence[InteractionLog]) -> list[int]:
    """Indices of the logs without battery voltage and pack current."""
    return [k for k, log in enumerate(logs) if not log.has_battery_power]


def check_power_logs(logs: Sequence[InteractionLog]) -> None:
    """DataError unless every battery voltage of these power logs is > 0 (a pack current over
    0 V gives no power)."""
    for k, log in enumerate(logs):
        if log.battery_voltage_v is not None and log.battery_current_a is not None and np.any(log.battery_voltage_v <= 0):
            i = int(np.argmax(log.battery_voltage_v <= 0))
            raise DataError(f"logs[{k}] ({log.meta.source!r}): battery_voltage_v must be > 0 V where a pack current "
                            f"is logged; index {i} holds {float(log.battery_voltage_v[i])!r} V")


def power_inputs(basis: PhysicsBasis, log: InteractionLog) -> PowerInputs:
    """The :class:`PowerInputs` of one log with measured drive currents.

    Raises
    ------
    DataError
        Fewer than 2 drive samples, no drive currents.
    """
    log.require_currents("the power stage of the diagnosis")
    rb = basis.robot
    res = basis_breakdown(basis, log)
    omega_m = np.abs(np.asarray(res.motor_speed_radps))
    current = log_currents(log) - np.asarray(basis.rest_current_a)  # the sensor's rest offset is not drawn
    t, v, w = log.time_s, log.v_mps, log.omega_radps
    stopped = control_power(rb.replace(control_standby_power_w=1.0, control_stable_power_w=0.0,
                                       control_startup_power_w=0.0), v, w, t)
    startup = control_power(rb.replace(control_standby_power_w=0.0, control_stable_power_w=0.0,
                                       control_startup_power_w=1.0), v, w, t)
    on = set(basis.effects)
    control0 = control_power(rb, v, w, t) if "control" in on else np.zeros(len(log))
    sensor0 = (rb.sensor_power_w, rb.sensor_power_per_mps_w) if "sensor" in on else (0.0, 0.0)
    ra0 = rb.motor.armature_resistance_ohm if "armature_heat" in on else 0.0
    return PowerInputs(rb.motor.back_emf_v_s_per_rad * omega_m * current, current**2, np.abs(v), stopped, startup,
                       float(ra0), (float(sensor0[0]), float(sensor0[1])), control0,
                       float(rb.control_startup_power_w - rb.control_stable_power_w), float(rb.regen_efficiency))


def predicted_battery_power_w(inputs: PowerInputs) -> np.ndarray:
    """The basis's battery power (N,), W, from the measured currents (see the module docstring)."""
    p = inputs
    drive = battery_side_w(p.back_emf_w + p.ra0_ohm * p.current_sq_a2, p.regen).sum(axis=1)
    return drive + p.sensor0[0] + p.sensor0[1] * p.speed_mps + p.control0_w
