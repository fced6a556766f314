"""Measurement of the synthetic logs: the :class:`NoiseModel` of the current sensor and the accelerometer."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from terrawatt_base.checks import check_bool, check_real

from ..battery import Battery

__all__ = ["NoiseModel", "measure_currents", "measure_battery"]


@dataclass(frozen=True, kw_only=True)
class NoiseModel:
    """How the drive currents and the accelerometer are measured.

    The logged current of a side is, in this order: ``gain * (I_motoring + offset)`` plus
    Gaussian noise, plus outlier spikes; braking (negative) values set to 0 when
    ``clip_negative``; rounded to multiples of ``quantisation_step_a``.

    Everything here changes what is *logged*, never what the battery pays: the simulator's
    battery power (``TruthRun.breakdown.total_power_w``, the pack's logged voltage and
    current) comes from the physics alone. In particular ``current_offset_a`` is the current
    sensor's rest offset (what it reads with the wheels still, as the real Husky's does),
    not a drag: a robot that knows it (``RobotParams.rest_current_a``) removes it when it
    turns logged currents into battery power (:func:`energy.budget.log_battery_power_w`).

    Parameters
    ----------
    current_noise_std_a : float
        Standard deviation of white Gaussian current noise (>= 0), A.
    outlier_rate : float
        Fraction of samples (per side) with an outlier spike, in [0, 1].
    outlier_magnitude_a : float
        Typical spike (>= 0), A; each spike is positive and uniform in [0.5, 1.5] times it.
    quantisation_step_a : float
        Resolution of the current sensor (>= 0; 0 = none), A. BorealTC's Husky logs show
        steps of about 0.13 A.
    current_offset_a : float
        The sensor's rest offset (>= 0), A, added to every logged sample (BorealTC's Husky
        logs 0 or 0.59 A standing still; the Husky preset's ``rest_current_a`` is 0.59 A).
    clip_negative : bool
        Report braking currents as 0, like the Husky driver.
    side_gain_std : float
        Log-normal spread (>= 0) of a per-run gain of each side's current (calibration,
        wear); 0 = exact.
    accel_noise_std_mps2 : float
        Standard deviation of white accelerometer noise (>= 0), m/s^2.
    battery_current_noise_rel : float
        Relative standard deviation (>= 0) of white noise on the logged pack current
        (0.01 = 1 % of the current), on top of ``battery_current_noise_std_a``.
    battery_current_noise_std_a : float
        Standard deviation of white pack-current noise (>= 0), A.
    battery_voltage_noise_std_v : float
        Standard deviation of white battery-voltage noise (>= 0), V.

    Raises
    ------
    InvalidParameterError
        Negative or non-finite values, a rate outside [0, 1].
    """

    current_noise_std_a: float = 0.1
    outlier_rate: float = 0.002
    outlier_magnitude_a: float = 2.0
    quantisation_step_a: float = 0.13
    current_offset_a: float = 0.59
    clip_negative: bool = True
    side_gain_std: float = 0.0
    accel_noise_std_mps2: float = 0.02
    battery_current_noise_rel: float = 0.01
    battery_current_noise_std_a: float = 0.05
    battery_voltage_noise_std_v: float = 0.01

    def __post_init__(self) -> None:
        own = "NoiseModel"
        for name in ("current_noise_std_a", "outlier_magnitude_a", "quantisation_step_a",
                     "current_offset_a", "side_gain_std", "accel_noise_std_mps2", "battery_current_noise_rel",
                     "battery_current_noise_std_a", "battery_voltage_noise_std_v"):
            check_real(name, getattr(self, name), low=0.0, owner=own)
        check_real("outlier_rate", self.outlier_rate, low=0.0, high=1.0, owner=own)
        check_bool(f"{own}.clip_negative", self.clip_negative)

    @classmethod
    def off(cls) -> NoiseModel:
        """No noise, outliers, quantisation, rest offset, clipping or gains: the logged
        currents are the physics model's motoring currents, the acceleration has no sensor
        noise, the battery voltage and pack current are exact."""
        return cls(current_noise_std_a=0.0, outlier_rate=0.0, outlier_magnitude_a=0.0,
                   quantisation_step_a=0.0, current_offset_a=0.0, clip_negative=False,
                   side_gain_std=0.0, accel_noise_std_mps2=0.0, battery_current_noise_rel=0.0,
                   battery_current_noise_std_a=0.0, battery_voltage_noise_std_v=0.0)


def measure_currents(
    noise: NoiseModel, drive_a: np.ndarray, rngs: Mapping[str, np.random.Generator]
) -> tuple[np.ndarray, np.ndarray]:
    """The clean and the measured side currents of motoring currents ``drive_a`` (N, 2), A.

    ``rngs`` holds the generators ``"side_gain"``, ``"current_noise"`` and ``"outliers"``
    (each drawn from only when its component is on, so switching one off leaves the
    others' draws unchanged). Clean: gains, rest offset and clipping; measured: plus
    noise, outliers and quantisation.
    """
    nm = noise
    n = drive_a.shape[0]
    gain = np.exp(nm.side_gain_std * rngs["side_gain"].standard_normal(2)) if nm.side_gain_std > 0 else np.ones(2)
    clean = gain * (drive_a + nm.current_offset_a)
    meas = clean.copy()
    if nm.current_noise_std_a > 0:
        meas += nm.current_noise_std_a * rngs["current_noise"].standard_normal((n, 2))
    if nm.outlier_rate > 0 and nm.outlier_magnitude_a > 0:
        r = rngs["outliers"]
        hit = r.random((n, 2)) < nm.outlier_rate
        meas += np.where(hit, nm.outlier_magnitude_a * r.uniform(0.5, 1.5, (n, 2)), 0.0)
    if nm.clip_negative:
        clean = np.maximum(clean, 0.0)
        meas = np.maximum(meas, 0.0)
    if nm.quantisation_step_a > 0:
        meas = np.round(meas / nm.quantisation_step_a) * nm.quantisation_step_a
    return clean, meas


def measure_battery(noise: NoiseModel, battery: Battery, power_w: np.ndarray,
                    rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The clean and the measured battery voltage and pack current of a battery power ``power_w`` (N,), W.

    The pack current is :meth:`Battery.current_a` (``V I - R I**2 = P``), the terminal
    voltage ``V - R I``; so clean voltage x clean current is ``power_w`` exactly. The
    measured ones add white noise from ``rng`` (relative and absolute on the current, absolute
    on the voltage; ``rng`` is drawn from only when some of it is on).

    Returns
    -------
    clean_voltage_v, clean_current_a, voltage_v, current_a : numpy.ndarray, shape (N,)
    """
    nm = noise
    current = np.asarray(battery.current_a(power_w), dtype=np.float64)
    voltage = battery.voltage_v - battery.internal_resistance_ohm * current
    n = current.shape[0]
    meas_i, meas_v = current.copy(), voltage.copy()
    if nm.battery_current_noise_rel > 0 or nm.battery_current_noise_std_a > 0:
        std = np.hypot(nm.battery_current_noise_rel * np.abs(current), nm.battery_current_noise_std_a)
        meas_i = meas_i + std * rng.standard_normal(n)
    if nm.battery_voltage_noise_std_v > 0:
        meas_v = np.maximum(meas_v + nm.battery_voltage_noise_std_v * rng.standard_normal(n), 0.0)
    return voltage, current, meas_v, meas_i
