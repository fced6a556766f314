"""Battery and mission-budget arithmetic: state of charge, reserve crossing, predicted vs actual energy.

A :class:`Battery` is an ideal voltage source ``voltage_v`` behind an optional internal
resistance ``R``, with a capacity in Ah, a minimum reserve and an initial state of charge.

Conventions (all vectorised over sample arrays, integrated with the trapezoid rule):

- **Power** ``P`` (W) is what the load (motors, electronics) takes at the battery
  terminals, the quantity energy models predict. **Current** ``I`` (A) is the battery
  current that delivers it: ``V I - R I**2 = P``, i.e. ``I = P / V`` when ``R = 0``
  (:meth:`Battery.current_a`). Negative power (regeneration) gives negative current.
- **Energy** (J, Wh) is the cumulative load energy ``int P dt``; **charge** (mAh) the
  cumulative battery current ``int I dt`` (internal losses included through ``I``).
- **State of charge** ``SoC(t) = initial_soc - int I_eff dt / (3600 C)`` with ``C`` the
  capacity in Ah and ``I_eff = I (|I| / I_ref)**(k - 1)`` for discharge (Peukert, exponent
  ``k``, reference current ``I_ref = C / peukert_reference_duration``; ``k = 1`` default:
  ``I_eff = I``). Charging currents count as they are. A constant current ``I`` over ``t``
  seconds gives exactly ``initial_soc - I t / (3600 C)``.
- The **battery power of a log** (:func:`log_battery_power_w`) is the drive power of its
  two sides, derived from the logged currents, plus the electronics (sensor and control
  board) of the robot's parameters, computed exactly as the physics model does.
- The **reserve** is crossed at the first sample whose SoC is *below*
  ``min_reserve_pct / 100``; the crossing time is interpolated linearly between that sample
  and the previous one (exact for a constant current).

:func:`discharge_from_power` / :func:`discharge_from_current` turn a time series into a
:class:`Discharge`; :func:`energy_budget` compares a discharge with a prediction and gives
an :class:`EnergyBudget` (predicted vs actual energy, reserve at arrival, feasibility,
per-segment breakdown).
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from terrain.errors import DataError, InvalidParameterError, UnknownNameError

from .logs import InteractionLog
from .params import GroundParams, RobotParams
from .physics import PhysicsEnergyModel

__all__ = [
    "Battery",
    "Discharge",
    "EnergyBudget",
    "CURRENT_CONVENTIONS",
    "discharge_from_power",
    "discharge_from_current",
    "energy_budget",
    "log_battery_power_w",
]

#: What the drive currents of a log measure (see :func:`log_battery_power_w`).
CURRENT_CONVENTIONS = ("motor", "battery")

_S_PER_H = 3600.0
_AS_PER_MAH = 3.6


def _real(owner: str, name: str, value: Any, *, low: float | None = None, low_open: bool = False,
          high: float | None = None, high_open: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidParameterError(f"{owner}.{name} must be a real number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise InvalidParameterError(f"{owner}.{name} must be finite, got {value!r}")
    if low is not None and (v < low or (low_open and v == low)):
        raise InvalidParameterError(f"{owner}.{name} must be {'>' if low_open else '>='} {low!r}, got {value!r}")
    if high is not None and (v > high or (high_open and v == high)):
        raise InvalidParameterError(f"{owner}.{name} must be {'<' if high_open else '<='} {high!r}, got {value!r}")
    return v


def _readonly(a: Any, dtype: Any = np.float64) -> np.ndarray:
    arr = np.array(a, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class Battery:
    """A battery pack: capacity, voltage, minimum reserve, initial charge, optional losses.

    Parameters
    ----------
    capacity_ah : float
        Rated capacity ``C`` (Ah), > 0.
    voltage_v : float
        Nominal (open-circuit) voltage ``V`` (V), > 0; taken as constant over the discharge.
    min_reserve_pct : float
        State of charge (%) that must remain at all times, in [0, 100). Default 20.
    initial_soc : float
        State of charge at the start, a fraction in (0, 1]. Default 1 (full).
    internal_resistance_ohm : float
        Internal resistance ``R`` (ohm), >= 0. Default 0 (ideal source).
    peukert_exponent : float
        Peukert exponent ``k`` in [1, 2]. Default 1 (capacity independent of the rate).
    peukert_reference_duration_s : float
        Discharge duration at which ``capacity_ah`` is rated (s), > 0; the Peukert
        reference current is ``capacity_ah * 3600 / peukert_reference_duration_s``.
        Default 72000 s (the 20-hour rate).

    Raises
    ------
    InvalidParameterError
        A value that is not a finite real number in its range (e.g. ``capacity_ah <= 0``).

    Examples
    --------
    >>> b = Battery(capacity_ah=20.0, voltage_v=24.0, min_reserve_pct=20.0)
    >>> b.energy_capacity_wh, round(b.usable_energy_wh, 6)
    (480.0, 384.0)
    """

    capacity_ah: float
    voltage_v: float
    min_reserve_pct: float = 20.0
    initial_soc: float = 1.0
    internal_resistance_ohm: float = 0.0
    peukert_exponent: float = 1.0
    peukert_reference_duration_s: float = 72000.0

    def __post_init__(self) -> None:
        own = "Battery"
        set_ = object.__setattr__
        set_(self, "capacity_ah", _real(own, "capacity_ah", self.capacity_ah, low=0.0, low_open=True))
        set_(self, "voltage_v", _real(own, "voltage_v", self.voltage_v, low=0.0, low_open=True))
        set_(self, "min_reserve_pct",
             _real(own, "min_reserve_pct", self.min_reserve_pct, low=0.0, high=100.0, high_open=True))
        set_(self, "initial_soc", _real(own, "initial_soc", self.initial_soc, low=0.0, low_open=True, high=1.0))
        set_(self, "internal_resistance_ohm",
             _real(own, "internal_resistance_ohm", self.internal_resistance_ohm, low=0.0))
        set_(self, "peukert_exponent", _real(own, "peukert_exponent", self.peukert_exponent, low=1.0, high=2.0))
        set_(self, "peukert_reference_duration_s",
             _real(own, "peukert_reference_duration_s", self.peukert_reference_duration_s, low=0.0, low_open=True))

    # ------------------------------------------------------------------ derived
    @property
    def reserve_soc(self) -> float:
        """Minimum reserve as a fraction of the capacity."""
        return self.min_reserve_pct / 100.0

    @property
    def energy_capacity_j(self) -> float:
        """Nominal energy content of a full battery ``C V`` (J)."""
        return self.capacity_ah * self.voltage_v * _S_PER_H

    @property
    def energy_capacity_wh(self) -> float:
        """Nominal energy content of a full battery (Wh)."""
        return self.capacity_ah * self.voltage_v

    @property
    def usable_energy_wh(self) -> float:
        """Nominal energy between the initial charge and the reserve (Wh; negative when the
        battery starts below its reserve). Internal losses and Peukert are not deducted."""
        return (self.initial_soc - self.reserve_soc) * self.energy_capacity_wh

    @property
    def peukert_reference_current_a(self) -> float:
        """Current at which ``capacity_ah`` is rated (A)."""
        return self.capacity_ah * _S_PER_H / self.peukert_reference_duration_s

    @property
    def max_power_w(self) -> float:
        """Largest terminal power the source can deliver, ``V**2 / (4 R)`` (W; inf when R = 0)."""
        r = self.internal_resistance_ohm
        return math.inf if r == 0.0 else self.voltage_v**2 / (4.0 * r)

    # ---------------------------------------------------------------- conversions
    def current_a(self, power_w: Any) -> np.ndarray:
        """Battery current (A) delivering a terminal power: the root of ``V I - R I**2 = P``
        on the source's stable branch (``I = P / V`` when ``R = 0``).

        Parameters
        ----------
        power_w : array_like
            Terminal power (W); negative for charging.

        Returns
        -------
        numpy.ndarray
            Same shape as ``power_w``.

        Raises
        ------
        InvalidParameterError
            Non-finite power, or power above :attr:`max_power_w`.
        """
        p = _finite_array("power_w", power_w)
        v, r = self.voltage_v, self.internal_resistance_ohm
        if r == 0.0:
            return p / v
        over = p > self.max_power_w
        if np.any(over):
            raise InvalidParameterError(
                f"power_w {float(np.max(p))!r} W exceeds the battery's maximum deliverable power "
                f"V**2/(4 R) = {self.max_power_w!r} W (voltage_v={v!r}, internal_resistance_ohm={r!r}); "
                "expected a smaller load or a smaller internal resistance"
            )
        disc = np.sqrt(v * v - 4.0 * r * p)
        # 2P / (V + sqrt(V^2 - 4RP)) == (V - sqrt(...)) / (2R), without cancellation for small P.
        return 2.0 * p / (v + disc)

    def terminal_power_w(self, current_a: Any) -> np.ndarray:
        """Terminal power (W) of a battery current: ``V I - R I**2``.

        Raises
        ------
        InvalidParameterError
            Non-finite current.
        """
        i = _finite_array("current_a", current_a)
        return self.voltage_v * i - self.internal_resistance_ohm * i * i

    def effective_current_a(self, current_a: Any) -> np.ndarray:
        """Current that depletes the rated capacity (Peukert): ``I (|I| / I_ref)**(k-1)`` for
        discharge, ``I`` for charge (A).

        Raises
        ------
        InvalidParameterError
            Non-finite current.
        """
        i = _finite_array("current_a", current_a)
        k = self.peukert_exponent
        if k == 1.0:
            return i.copy()
        ratio = np.abs(i) / self.peukert_reference_current_a
        return np.where(i > 0, i * ratio ** (k - 1.0), i)

    def replace(self, **changes: Any) -> Battery:
        """A copy with some fields changed (validated again), e.g. ``initial_soc`` for the
        next leg of a mission."""
        return dataclasses.replace(self, **changes)

    def soc_after(self, charge_mah: float) -> float:
        """State of charge (fraction) after drawing ``charge_mah`` of *effective* charge."""
        return self.initial_soc - float(charge_mah) * _AS_PER_MAH / (self.capacity_ah * _S_PER_H)


def _finite_array(name: str, value: Any) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be numeric, got {value!r:.80}") from None
    if not np.all(np.isfinite(arr)):
        bad = np.atleast_1d(arr)[~np.isfinite(np.atleast_1d(arr))][:3]
        raise InvalidParameterError(f"{name} must be finite (no NaN or inf), got {bad!r}")
    return arr


def _check_series(time_s: Any, values: Any, name: str) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(time_s, dtype=np.float64)
    if t.ndim != 1 or t.size < 2:
        raise DataError(f"time_s must be 1-D with at least 2 samples, got shape {t.shape!r}")
    if not np.all(np.isfinite(t)):
        raise DataError(f"time_s must be finite, got {t[~np.isfinite(t)][:3]!r}")
    d = np.diff(t)
    if np.any(d <= 0):
        k = int(np.argmax(d <= 0)) + 1
        raise DataError(f"time_s must be strictly increasing; time_s[{k}]={t[k]!r} after time_s[{k - 1}]={t[k - 1]!r}")
    x = np.asarray(values, dtype=np.float64)
    if x.shape != t.shape:
        raise InvalidParameterError(f"{name} must have the shape of time_s {t.shape!r}, got {x.shape!r}")
    if not np.all(np.isfinite(x)):
        k = int(np.argmax(~np.isfinite(x)))
        raise DataError(f"{name} must be finite; first non-finite value at index {k} ({float(x[k])!r})")
    return t, x


def _cumtrapz(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.concatenate(([0.0], np.cumsum(0.5 * (x[1:] + x[:-1]) * np.diff(t))))


def _crossing(t: np.ndarray, soc: np.ndarray, level: float) -> tuple[int | None, float | None]:
    """First index with ``soc < level`` and the linearly interpolated crossing time."""
    below = soc < level
    if not np.any(below):
        return None, None
    k = int(np.argmax(below))
    if k == 0:
        return 0, float(t[0])
    s0, s1 = float(soc[k - 1]), float(soc[k])
    frac = (s0 - level) / (s0 - s1) if s0 != s1 else 1.0
    return k, float(t[k - 1] + min(max(frac, 0.0), 1.0) * (t[k] - t[k - 1]))


@dataclass(frozen=True, eq=False, repr=False)
class Discharge:
    """A battery's discharge over a sampled time series (see the module conventions).

    Attributes
    ----------
    battery : Battery
    time_s : ndarray, shape (N,)
        Strictly increasing sample times (s).
    power_w : ndarray, shape (N,)
        Terminal (load) power (W).
    current_a : ndarray, shape (N,)
        Battery current (A).
    energy_j : ndarray, shape (N,)
        Cumulative load energy from the first sample (J), starting at 0.
    charge_mah : ndarray, shape (N,)
        Cumulative battery charge (mAh), starting at 0 (not Peukert-adjusted).
    soc : ndarray, shape (N,)
        State of charge (fraction of the capacity; may go negative when the battery would
        be exhausted — nothing is clipped).
    reserve_crossed_index : int or None
        First sample below the reserve, or None.
    reserve_crossed_time_s : float or None
        Interpolated time at which the SoC reaches the reserve, or None.

    Derived: ``energy_wh``, ``soc_pct``, ``total_energy_j``, ``total_charge_mah``,
    ``final_soc``, ``reserve_crossed``.
    """

    battery: Battery
    time_s: np.ndarray
    power_w: np.ndarray
    current_a: np.ndarray
    energy_j: np.ndarray
    charge_mah: np.ndarray
    soc: np.ndarray
    reserve_crossed_index: int | None
    reserve_crossed_time_s: float | None

    def __post_init__(self) -> None:
        if not isinstance(self.battery, Battery):
            raise InvalidParameterError(f"battery must be a Battery, got {type(self.battery).__name__!r}")
        n = np.shape(self.time_s)
        for name in ("time_s", "power_w", "current_a", "energy_j", "charge_mah", "soc"):
            arr = _readonly(getattr(self, name))
            if arr.shape != n or arr.ndim != 1:
                raise InvalidParameterError(f"Discharge.{name} must have shape {n!r}, got {arr.shape!r}")
            object.__setattr__(self, name, arr)

    @property
    def energy_wh(self) -> np.ndarray:
        """Cumulative load energy (Wh)."""
        return self.energy_j / _S_PER_H

    @property
    def soc_pct(self) -> np.ndarray:
        """State of charge (%)."""
        return 100.0 * self.soc

    @property
    def total_energy_j(self) -> float:
        """Load energy over the whole series (J)."""
        return float(self.energy_j[-1])

    @property
    def total_charge_mah(self) -> float:
        """Battery charge over the whole series (mAh)."""
        return float(self.charge_mah[-1])

    @property
    def final_soc(self) -> float:
        """State of charge at the last sample (fraction)."""
        return float(self.soc[-1])

    @property
    def reserve_crossed(self) -> bool:
        """Whether the SoC went below the reserve."""
        return self.reserve_crossed_index is not None

    def __repr__(self) -> str:
        return (
            f"Discharge(samples={self.time_s.size}, duration_s={self.time_s[-1] - self.time_s[0]:.1f}, "
            f"energy_wh={self.total_energy_j / _S_PER_H:.3f}, charge_mah={self.total_charge_mah:.1f}, "
            f"final_soc={self.final_soc:.4f}, reserve_crossed_time_s={self.reserve_crossed_time_s!r})"
        )


def _discharge(battery: Battery, t: np.ndarray, power: np.ndarray, current: np.ndarray) -> Discharge:
    energy = _cumtrapz(t, power)
    charge_as = _cumtrapz(t, current)
    eff_as = charge_as if battery.peukert_exponent == 1.0 else _cumtrapz(t, battery.effective_current_a(current))
    soc = battery.initial_soc - eff_as / (battery.capacity_ah * _S_PER_H)
    k, tc = _crossing(t, soc, battery.reserve_soc)
    return Discharge(battery, t, power, current, energy, charge_as / _AS_PER_MAH, soc, k, tc)


def _check_battery(battery: Any) -> Battery:
    if not isinstance(battery, Battery):
        raise InvalidParameterError(f"battery must be a Battery, got {type(battery).__name__!r}")
    return battery


def discharge_from_power(battery: Battery, time_s: Any, power_w: Any) -> Discharge:
    """Discharge of a battery feeding a sampled terminal power.

    Parameters
    ----------
    battery : Battery
    time_s : array_like, shape (N,)
        Strictly increasing times (s), N >= 2.
    power_w : array_like, shape (N,)
        Terminal (load) power (W).

    Returns
    -------
    Discharge

    Raises
    ------
    InvalidParameterError
        ``battery`` not a Battery, shapes differ, power above :attr:`Battery.max_power_w`.
    DataError
        Fewer than 2 samples, non-finite values, times not strictly increasing.

    Examples
    --------
    >>> d = discharge_from_power(Battery(10.0, 24.0), [0.0, 3600.0], [24.0, 24.0])
    >>> round(d.total_charge_mah, 9), round(d.final_soc, 9)
    (1000.0, 0.9)
    """
    battery = _check_battery(battery)
    t, p = _check_series(time_s, power_w, "power_w")
    return _discharge(battery, t, p, battery.current_a(p))


def discharge_from_current(battery: Battery, time_s: Any, current_a: Any) -> Discharge:
    """Discharge of a battery delivering a sampled battery current.

    The terminal power is ``V I - R I**2``.

    Parameters
    ----------
    battery : Battery
    time_s : array_like, shape (N,)
        Strictly increasing times (s), N >= 2.
    current_a : array_like, shape (N,)
        Battery current (A), positive when discharging.

    Returns
    -------
    Discharge

    Raises
    ------
    InvalidParameterError
        ``battery`` not a Battery, shapes differ.
    DataError
        Fewer than 2 samples, non-finite values, times not strictly increasing.

    Examples
    --------
    >>> d = discharge_from_current(Battery(2.0, 12.0), [0.0, 1800.0], [1.0, 1.0])
    >>> round(d.final_soc, 12), round(d.total_energy_j / 3600.0, 9)
    (0.75, 6.0)
    """
    battery = _check_battery(battery)
    t, i = _check_series(time_s, current_a, "current_a")
    return _discharge(battery, t, battery.terminal_power_w(i), i)


@dataclass(frozen=True, eq=False, repr=False)
class EnergyBudget:
    """Predicted vs actual energy of a mission against a battery.

    Attributes
    ----------
    battery : Battery
    predicted_energy_j, actual_energy_j : float
        Load energy (J) predicted before driving and measured (or simulated) while driving.
    predicted_charge_mah, actual_charge_mah : float
        Battery charge (mAh). The predicted charge draws the predicted energy at a constant
        power over the mission's duration (so it includes internal resistance and Peukert
        like the actual one).
    predicted_arrival_soc, arrival_soc : float
        State of charge at the end (fraction), predicted and actual.
    duration_s : float
        Duration of the driven series (s).
    feasible : bool
        The actual SoC never went below the reserve.
    predicted_feasible : bool
        The predicted arrival SoC is at or above the reserve.
    reserve_crossed_time_s : float or None
        When the actual SoC reached the reserve (interpolated), or None.
    reserve_crossed_index : int or None
        First sample of the series below the reserve, or None.
    segment_predicted_j, segment_actual_j : ndarray, shape (S,)
        Per-segment breakdown (J); empty when no segments were given. The actual energy
        of a segment is the integral over the sample intervals that start in it, so the
        segments add up to ``actual_energy_j``.

    Derived: ``predicted_energy_wh``, ``actual_energy_wh``, ``error_pct``,
    ``arrival_soc_pct``, ``arrival_energy_wh``, ``reserve_margin_pct``,
    ``reserve_margin_wh``, ``segment_error_pct``; :meth:`to_json_dict`.
    """

    battery: Battery
    predicted_energy_j: float
    actual_energy_j: float
    predicted_charge_mah: float
    actual_charge_mah: float
    predicted_arrival_soc: float
    arrival_soc: float
    duration_s: float
    feasible: bool
    predicted_feasible: bool
    reserve_crossed_time_s: float | None = None
    reserve_crossed_index: int | None = None
    segment_predicted_j: np.ndarray = field(default_factory=lambda: np.empty(0))
    segment_actual_j: np.ndarray = field(default_factory=lambda: np.empty(0))

    def __post_init__(self) -> None:
        own = "EnergyBudget"
        _check_battery(self.battery)
        for name in ("predicted_energy_j", "actual_energy_j", "predicted_charge_mah", "actual_charge_mah",
                     "predicted_arrival_soc", "arrival_soc"):
            object.__setattr__(self, name, _real(own, name, getattr(self, name)))
        object.__setattr__(self, "duration_s", _real(own, "duration_s", self.duration_s, low=0.0))
        for name in ("feasible", "predicted_feasible"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise InvalidParameterError(f"{own}.{name} must be a bool, got {getattr(self, name)!r}")
            object.__setattr__(self, name, bool(getattr(self, name)))
        if (self.reserve_crossed_time_s is None) != (self.reserve_crossed_index is None):
            raise InvalidParameterError(
                f"{own}.reserve_crossed_time_s and reserve_crossed_index must both be set or both None, got "
                f"{self.reserve_crossed_time_s!r} and {self.reserve_crossed_index!r}"
            )
        if self.reserve_crossed_time_s is not None:
            crossed = _real(own, "reserve_crossed_time_s", self.reserve_crossed_time_s)
            object.__setattr__(self, "reserve_crossed_time_s", crossed)
            idx = self.reserve_crossed_index
            if isinstance(idx, bool) or not isinstance(idx, (int, np.integer)) or idx < 0:
                raise InvalidParameterError(f"{own}.reserve_crossed_index must be an int >= 0 or None, got {idx!r}")
            object.__setattr__(self, "reserve_crossed_index", int(idx))
        if self.feasible == (self.reserve_crossed_index is not None):
            raise InvalidParameterError(
                f"{own}.feasible={self.feasible!r} contradicts reserve_crossed_index={self.reserve_crossed_index!r}"
            )
        seg_p = _readonly(self.segment_predicted_j)
        seg_a = _readonly(self.segment_actual_j)
        if seg_p.ndim != 1 or seg_p.shape != seg_a.shape:
            raise InvalidParameterError(
                f"{own}.segment_predicted_j and segment_actual_j must be 1-D of equal length, got "
                f"{seg_p.shape!r} and {seg_a.shape!r}"
            )
        if not (np.all(np.isfinite(seg_p)) and np.all(np.isfinite(seg_a))):
            raise InvalidParameterError(f"{own} segment energies must be finite")
        object.__setattr__(self, "segment_predicted_j", seg_p)
        object.__setattr__(self, "segment_actual_j", seg_a)

    # ------------------------------------------------------------------ derived
    @property
    def predicted_energy_wh(self) -> float:
        """Predicted load energy (Wh)."""
        return self.predicted_energy_j / _S_PER_H

    @property
    def actual_energy_wh(self) -> float:
        """Actual load energy (Wh)."""
        return self.actual_energy_j / _S_PER_H

    @property
    def error_pct(self) -> float:
        """Prediction error ``100 (predicted - actual) / actual`` (%; positive: overestimate).
        NaN when the actual energy is 0."""
        if self.actual_energy_j == 0.0:
            return math.nan
        return 100.0 * (self.predicted_energy_j - self.actual_energy_j) / self.actual_energy_j

    @property
    def arrival_soc_pct(self) -> float:
        """Actual state of charge at the end (%)."""
        return 100.0 * self.arrival_soc

    @property
    def arrival_energy_wh(self) -> float:
        """Nominal energy left in the battery at the end, ``SoC C V`` (Wh)."""
        return self.arrival_soc * self.battery.energy_capacity_wh

    @property
    def reserve_margin_pct(self) -> float:
        """Arrival SoC minus the minimum reserve (percentage points; negative: reserve used)."""
        return self.arrival_soc_pct - self.battery.min_reserve_pct

    @property
    def reserve_margin_wh(self) -> float:
        """Nominal energy above the reserve at the end (Wh; negative: reserve used)."""
        return (self.arrival_soc - self.battery.reserve_soc) * self.battery.energy_capacity_wh

    @property
    def segment_error_pct(self) -> np.ndarray:
        """Per-segment ``100 (predicted - actual) / actual`` (%; NaN where actual is 0)."""
        a = self.segment_actual_j
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(a != 0.0, 100.0 * (self.segment_predicted_j - a) / np.where(a != 0.0, a, 1.0), np.nan)

    def to_json_dict(self) -> dict[str, Any]:
        """Plain JSON-ready values (units in the keys; NaN written as None)."""

        def num(x: float) -> float | None:
            return None if not math.isfinite(x) else float(x)

        b = self.battery
        return {
            "battery": {
                "capacity_ah": b.capacity_ah,
                "voltage_v": b.voltage_v,
                "min_reserve_pct": b.min_reserve_pct,
                "initial_soc": b.initial_soc,
                "internal_resistance_ohm": b.internal_resistance_ohm,
                "peukert_exponent": b.peukert_exponent,
                "peukert_reference_duration_s": b.peukert_reference_duration_s,
            },
            "predicted_energy_j": self.predicted_energy_j,
            "predicted_energy_wh": self.predicted_energy_wh,
            "predicted_charge_mah": self.predicted_charge_mah,
            "actual_energy_j": self.actual_energy_j,
            "actual_energy_wh": self.actual_energy_wh,
            "actual_charge_mah": self.actual_charge_mah,
            "error_pct": num(self.error_pct),
            "duration_s": self.duration_s,
            "predicted_arrival_soc_pct": 100.0 * self.predicted_arrival_soc,
            "arrival_soc_pct": self.arrival_soc_pct,
            "arrival_energy_wh": self.arrival_energy_wh,
            "reserve_margin_pct": self.reserve_margin_pct,
            "reserve_margin_wh": self.reserve_margin_wh,
            "feasible": self.feasible,
            "predicted_feasible": self.predicted_feasible,
            "reserve_crossed_time_s": self.reserve_crossed_time_s,
            "reserve_crossed_index": self.reserve_crossed_index,
            "segment_predicted_j": self.segment_predicted_j.tolist(),
            "segment_actual_j": self.segment_actual_j.tolist(),
            "segment_error_pct": [num(x) for x in self.segment_error_pct.tolist()],
        }

    def __repr__(self) -> str:
        return (
            f"EnergyBudget(predicted_wh={self.predicted_energy_wh:.3f}, actual_wh={self.actual_energy_wh:.3f}, "
            f"error_pct={self.error_pct:.2f}, arrival_soc_pct={self.arrival_soc_pct:.2f}, "
            f"feasible={self.feasible}, reserve_crossed_time_s={self.reserve_crossed_time_s!r})"
        )


def energy_budget(
    discharge: Discharge,
    predicted_energy_j: float,
    *,
    segment_index: Any = None,
    segment_predicted_j: Any = None,
) -> EnergyBudget:
    """Compare a discharge with a prediction: errors, reserve at arrival, feasibility, segments.

    Parameters
    ----------
    discharge : Discharge
        The driven (actual) series, from :func:`discharge_from_power` or
        :func:`discharge_from_current`.
    predicted_energy_j : float
        Predicted load energy of the whole series (J), >= 0.
    segment_index : array_like of int, shape (N,), optional
        Segment of each sample (``0 .. S-1``, non-decreasing not required). The interval
        ``[t_i, t_{i+1}]`` belongs to the segment of sample ``i``.
    segment_predicted_j : array_like, shape (S,), optional
        Predicted energy of each segment (J); required with ``segment_index``.

    Returns
    -------
    EnergyBudget

    Raises
    ------
    InvalidParameterError
        ``discharge`` not a Discharge; negative or non-finite prediction; segment arrays of
        wrong shape, negative, or an index outside ``0 .. S-1``; only one of the two
        segment arguments given.

    Examples
    --------
    >>> b = Battery(capacity_ah=1.0, voltage_v=10.0, min_reserve_pct=50.0)
    >>> d = discharge_from_power(b, [0.0, 3600.0], [6.0, 6.0])   # 6 Wh of 10 Wh
    >>> budget = energy_budget(d, predicted_energy_j=4.0 * 3600.0)
    >>> budget.feasible, budget.predicted_feasible, round(budget.reserve_crossed_time_s, 6)
    (False, True, 3000.0)
    """
    if not isinstance(discharge, Discharge):
        raise InvalidParameterError(f"discharge must be a Discharge, got {type(discharge).__name__!r}")
    pred = _real("energy_budget", "predicted_energy_j", predicted_energy_j, low=0.0)
    battery = discharge.battery
    t = discharge.time_s
    duration = float(t[-1] - t[0])
    # Predicted charge: the predicted energy at constant power over the same duration.
    p_mean = pred / duration if duration > 0 else 0.0
    i_mean = float(battery.current_a(p_mean))
    pred_charge_as = i_mean * duration
    pred_eff_as = float(battery.effective_current_a(i_mean)) * duration
    pred_soc = battery.initial_soc - pred_eff_as / (battery.capacity_ah * _S_PER_H)

    if (segment_index is None) != (segment_predicted_j is None):
        raise InvalidParameterError(
            "segment_index and segment_predicted_j must be given together, got "
            f"segment_index={'None' if segment_index is None else 'array'}, "
            f"segment_predicted_j={'None' if segment_predicted_j is None else 'array'}"
        )
    seg_pred = np.empty(0)
    seg_act = np.empty(0)
    if segment_index is not None:
        seg_pred = np.asarray(segment_predicted_j, dtype=np.float64)
        if seg_pred.ndim != 1 or not np.all(np.isfinite(seg_pred)) or np.any(seg_pred < 0):
            raise InvalidParameterError(
                f"segment_predicted_j must be a 1-D array of finite energies >= 0, got {seg_pred!r:.120}"
            )
        idx = np.asarray(segment_index)
        if idx.shape != t.shape or idx.dtype.kind not in "iu":
            raise InvalidParameterError(
                f"segment_index must be integers of shape {t.shape!r}, got dtype {idx.dtype!s} shape {idx.shape!r}"
            )
        s = seg_pred.size
        if np.any((idx < 0) | (idx >= s)):
            bad = idx[(idx < 0) | (idx >= s)][:3]
            raise InvalidParameterError(f"segment_index must lie in [0, {s - 1}], got {bad!r}")
        step_j = np.diff(discharge.energy_j)
        seg_act = np.bincount(idx[:-1].astype(np.intp), weights=step_j, minlength=s).astype(np.float64)

    return EnergyBudget(
        battery=battery,
        predicted_energy_j=pred,
        actual_energy_j=discharge.total_energy_j,
        predicted_charge_mah=pred_charge_as / _AS_PER_MAH,
        actual_charge_mah=discharge.total_charge_mah,
        predicted_arrival_soc=pred_soc,
        arrival_soc=discharge.final_soc,
        duration_s=duration,
        feasible=not discharge.reserve_crossed,
        predicted_feasible=pred_soc >= battery.reserve_soc,
        reserve_crossed_time_s=discharge.reserve_crossed_time_s,
        reserve_crossed_index=discharge.reserve_crossed_index,
        segment_predicted_j=seg_pred,
        segment_actual_j=seg_act,
    )


# A ground for electronics-only power: with every force effect off its coefficients are unused.
_NO_GROUND = GroundParams(name="electronics_only", static_friction_coef=1.0, coulomb_friction_coef=1.0,
                          rolling_resistance_coef=0.0)


def log_battery_power_w(
    log: InteractionLog,
    robot: RobotParams,
    *,
    current_convention: str = "motor",
    electronics: bool = True,
) -> np.ndarray:
    """Battery-side power (W) of every drive sample of a log: drive sides plus electronics.

    The same bookkeeping as :class:`~energy.physics.PhysicsEnergyModel`'s
    ``total_power_w``, so an energy predicted with that model (e.g. a planner's edge
    costs) and the energy of a driven log compare like with like.

    ``current_convention`` says what the logged side currents are:

    - ``"motor"`` (default; the Husky driver, BorealTC, :class:`~energy.truth.TruthSimulator`):
      the *motoring* armature current ``I_m`` of each side (positive while the motor drives
      its wheels in either direction, negative while back-driven). The side's electrical
      power is ``V_m I_m`` with the terminal voltage ``V_m = Ke |omega_m| + Ra I_m``; the
      motor speed comes from the log's speeds through the ICR kinematics,
      ``omega_m = N |v -/+ omega chi B / 2| / r``, capped at ``motor.max_speed_radps``
      (wheel slip is not observable in a log and is neglected: a slipping wheel spins a
      little faster, so this slightly underestimates). Negative side power counts times
      ``robot.regen_efficiency``, as in the physics model.
    - ``"battery"`` (e.g. Jackal's bridge feedback): battery-side bridge currents; the drive
      power is ``battery_voltage_v * (I_left + I_right)``.

    With ``electronics`` the robot's sensor power (``sensor_power_w`` plus
    ``sensor_power_per_mps_w * |v|``) and control-board power (standby / start-up / stable,
    from the log's speeds and times) are added; the logged drive currents do not hold them.

    Parameters
    ----------
    log : InteractionLog
    robot : RobotParams
        The robot that drove the log (motor constants, geometry, electronics).
    current_convention : {"motor", "battery"}
    electronics : bool
        Add the sensor and control-board power.

    Returns
    -------
    numpy.ndarray, shape (N,)

    Raises
    ------
    InvalidParameterError
        ``log`` or ``robot`` of the wrong type.
    UnknownNameError
        ``current_convention`` not in :data:`CURRENT_CONVENTIONS`.

    Examples
    --------
    >>> from energy import InteractionLog, robot_preset
    >>> robot = robot_preset("husky")
    >>> log = InteractionLog([0.0, 1.0], [0.0, 0.0], [0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [0.0, 1.0], [9.8, 9.8])
    >>> p = log_battery_power_w(log, robot, current_convention="battery", electronics=False)
    >>> p.tolist() == [3.0 * robot.battery_voltage_v] * 2
    True
    """
    if not isinstance(log, InteractionLog):
        raise InvalidParameterError(f"log must be an InteractionLog, got {type(log).__name__!r}")
    if not isinstance(robot, RobotParams):
        raise InvalidParameterError(f"robot must be a RobotParams, got {type(robot).__name__!r}")
    if current_convention not in CURRENT_CONVENTIONS:
        raise UnknownNameError(
            f"current_convention must be one of {CURRENT_CONVENTIONS!r}, got {current_convention!r}"
        )
    currents = np.column_stack([log.current_left_a, log.current_right_a])  # (N, 2) [left, right]
    if current_convention == "battery":
        drive = robot.battery_voltage_v * currents.sum(axis=1)
    else:
        mo = robot.motor
        half = robot.track_width_multiplier * robot.track_width_m / 2.0
        v_side = log.v_mps[:, None] + log.omega_radps[:, None] * half * np.array([-1.0, 1.0])
        omega_m = np.minimum(mo.gear_ratio * np.abs(v_side) / robot.wheel_radius_m, mo.max_speed_radps)
        side = (mo.back_emf_v_s_per_rad * omega_m + mo.armature_resistance_ohm * currents) * currents
        drive = np.where(side >= 0.0, side, robot.regen_efficiency * side).sum(axis=1)
    if not electronics:
        return drive
    model = PhysicsEnergyModel(robot, effects=("sensor", "control"))
    extra = model.power(log.v_mps, log.omega_radps, _NO_GROUND, time_s=log.time_s).total_power_w
    return drive + extra
