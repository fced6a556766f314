"""The :class:`PowerBreakdown` of a sampled motion: battery power and where it goes, per sample."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import fmt_number, readonly
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError

__all__ = ["PowerBreakdown", "check_sample_times", "trapezoid"]

#: ``numpy.trapezoid`` (``numpy.trapz`` before numpy 2).
trapezoid = getattr(np, "trapezoid", None) or np.trapz


def check_sample_times(time_s: Any, n: int) -> np.ndarray:
    """``time_s`` as finite, strictly increasing float64 times of ``n`` samples.

    Raises
    ------
    DataError
        Wrong shape, NaN/inf, or times not strictly increasing.
    """
    t = np.asarray(time_s, dtype=np.float64)
    if t.ndim != 1 or t.shape[0] != n:
        raise DataError(f"time_s must be 1-D with {n} samples, got shape {t.shape!r}")
    if not np.all(np.isfinite(t)):
        raise DataError(f"time_s must be finite, got {[float(v) for v in t[~np.isfinite(t)][:3]]!r}")
    if n > 1 and np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0))
        raise DataError(
            f"time_s must be strictly increasing; time_s[{k}]={fmt_number(float(t[k]), 10)}, "
            f"time_s[{k + 1}]={fmt_number(float(t[k + 1]), 10)}"
        )
    return t


@dataclass(frozen=True, eq=False)
class PowerBreakdown:
    """Power of each sample, split by where it goes (returned by ``PhysicsEnergyModel.power``).

    Arrays of shape ``(n,)`` unless noted; ``(n, 2)`` arrays hold ``[left, right]``.
    Wheel-level components (``*_power_w`` other than the battery-side totals) are the
    demanded mechanical power ``sum_sides F_component * v_side`` (may be negative, e.g.
    slope downhill), before gearbox, motor and saturation.

    Attributes
    ----------
    total_power_w : battery-side total (drive + sensor + control), W.
    drive_power_w : battery-side motor power summed over both sides, W.
    sensor_power_w, control_power_w : electronics, W.
    armature_heat_power_w : ``Ra I^2`` summed over sides (0 with the effect off), W.
    motor_current_a : (n, 2) signed motor current per side, A.
    motor_voltage_v : (n, 2) motor terminal voltage ``Ke omega_m + Ra I``, V.
    motor_speed_radps : (n, 2) motor shaft speed (after speed saturation), rad/s.
    motor_torque_nm : (n, 2) motor shaft torque (after torque saturation), N m.
    motor_electrical_power_w : (n, 2) signed electrical power per side, W.
    inertia_power_w, slope_power_w, friction_power_w, viscous_power_w, turning_power_w,
    lateral_slip_power_w, longitudinal_slip_power_w : wheel-level components, W
        (friction = Coulomb + static + Stribeck; viscous = contact part only).
    saturated : bool, any side clipped by torque or speed saturation.
    traction_exceeded : bool, a side demands more than ``mu_k N_side`` (or the lateral
        force exceeds ``mu_k N``): the ground cannot carry the commanded motion.
    voltage_exceeded : bool, a side's terminal voltage ``|Ke omega_m + Ra I|`` exceeds the
        battery voltage: the DC motor's torque-speed line cannot deliver this sample
        (informative; saturation uses the paper's rectangular limits).
    """

    total_power_w: np.ndarray
    drive_power_w: np.ndarray
    sensor_power_w: np.ndarray
    control_power_w: np.ndarray
    armature_heat_power_w: np.ndarray
    motor_current_a: np.ndarray
    motor_voltage_v: np.ndarray
    motor_speed_radps: np.ndarray
    motor_torque_nm: np.ndarray
    motor_electrical_power_w: np.ndarray
    inertia_power_w: np.ndarray
    slope_power_w: np.ndarray
    friction_power_w: np.ndarray
    viscous_power_w: np.ndarray
    turning_power_w: np.ndarray
    lateral_slip_power_w: np.ndarray
    longitudinal_slip_power_w: np.ndarray
    saturated: np.ndarray
    traction_exceeded: np.ndarray
    voltage_exceeded: np.ndarray

    def __post_init__(self) -> None:
        n = np.shape(self.total_power_w)
        if len(n) != 1:
            raise InvalidParameterError(
                f"PowerBreakdown.total_power_w must be 1-D, got shape {n!r}"
            )
        for name, value in vars(self).items():
            arr = np.asarray(value)
            expected = (n[0], 2) if name.startswith("motor_") else n
            if arr.shape != expected:
                raise InvalidParameterError(
                    f"PowerBreakdown.{name} must have shape {expected!r}, got {arr.shape!r}"
                )
            object.__setattr__(self, name, readonly(np.ascontiguousarray(arr)))

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.total_power_w.shape[0])

    def energy_j(self, time_s: Any, component: str = "total_power_w") -> float:
        """Integrate a power component over ``time_s`` with the trapezoid rule.

        Parameters
        ----------
        time_s : array_like, shape (n,)
            Strictly increasing sample times, s.
        component : str
            Name of a ``(n,)`` power field (default ``"total_power_w"``).

        Returns
        -------
        float
            Energy in J.

        Raises
        ------
        DataError
            Times not finite, not strictly increasing or of the wrong length.
        UnknownNameError
            ``component`` is not a ``(n,)`` power field.
        """
        names = [k for k in vars(self) if k.endswith("_power_w") and not k.startswith("motor_")]
        if component not in names:
            raise UnknownNameError(
                f"component {component!r} is unknown; expected one of {sorted(names)!r}"
            )
        t = check_sample_times(time_s, self.n_samples)
        return float(trapezoid(getattr(self, component), t))
