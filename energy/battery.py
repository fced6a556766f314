"""Battery arithmetic: state of charge, reserve crossing and depletion of a sampled discharge.

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
- The state of charge **never goes below 0**: the pack is *depleted* at the first sample
  whose unclamped SoC reaches 0 (time interpolated like the reserve crossing); from there
  the SoC stays at 0 (unless the series charges the pack) while energy and charge keep
  what the load would have drawn — the pack could not deliver it.
- The **reserve** is crossed at the first sample whose SoC is *below*
  ``min_reserve_pct / 100``; the crossing time is interpolated linearly between that sample
  and the previous one (exact for a constant current).

:func:`discharge_from_power` turns a time series into a
:class:`Discharge`; :meth:`Battery.soc_after_energy` steps a state of charge by one draw
of energy at a power (same losses), for loops that book energy leg by leg. Comparing a
discharge with a prediction is :func:`energy.energy_budget` (:mod:`energy.budget`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_optional_real, check_real, fmt_number, readonly, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

__all__ = [
    "Battery",
    "Discharge",
    "discharge_from_power",
    "S_PER_H",
    "AS_PER_MAH",
]

#: Seconds per hour (Wh <-> J, Ah <-> As).
S_PER_H = 3600.0
#: Ampere-seconds per mAh.
AS_PER_MAH = 3.6


def _check_battery(battery: Any) -> Battery:
    if not isinstance(battery, Battery):
        raise InvalidParameterError(f"battery must be a Battery, got {type(battery).__name__!r}")
    return battery


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
        set_(self, "capacity_ah", check_real("capacity_ah", self.capacity_ah, low=0.0, low_inclusive=False, owner=own))
        set_(self, "voltage_v", check_real("voltage_v", self.voltage_v, low=0.0, low_inclusive=False, owner=own))
        set_(self, "min_reserve_pct", check_real("min_reserve_pct", self.min_reserve_pct, low=0.0, high=100.0,
                                                 high_inclusive=False, owner=own))
        set_(self, "initial_soc", check_real("initial_soc", self.initial_soc, low=0.0, low_inclusive=False, high=1.0,
                                             owner=own))
        set_(self, "internal_resistance_ohm",
             check_real("internal_resistance_ohm", self.internal_resistance_ohm, low=0.0, owner=own))
        set_(self, "peukert_exponent", check_real("peukert_exponent", self.peukert_exponent, low=1.0, high=2.0,
                                                  owner=own))
        set_(self, "peukert_reference_duration_s",
             check_real("peukert_reference_duration_s", self.peukert_reference_duration_s, low=0.0,
                        low_inclusive=False, owner=own))

    # ------------------------------------------------------------------ derived
    @property
    def reserve_soc(self) -> float:
        """Minimum reserve as a fraction of the capacity."""
        return self.min_reserve_pct / 100.0

    @property
    def energy_capacity_j(self) -> float:
        """Nominal energy content of a full battery ``C V`` (J)."""
        return self.capacity_ah * self.voltage_v * S_PER_H

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
        return self.capacity_ah * S_PER_H / self.peukert_reference_duration_s

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
        p = real_array("power_w", power_w)
        v, r = self.voltage_v, self.internal_resistance_ohm
        if r == 0.0:
            return p / v
        over = p > self.max_power_w
        if np.any(over):
            raise InvalidParameterError(
                f"power_w {fmt_number(float(np.max(p)))} W exceeds the battery's maximum deliverable power "
                f"V**2/(4 R) = {fmt_number(self.max_power_w)} W (voltage_v={fmt_number(v)}, "
                f"internal_resistance_ohm={fmt_number(r)}); "
                "expected a smaller load or a smaller internal resistance"
            )
        disc = np.sqrt(v * v - 4.0 * r * p)
        # 2P / (V + sqrt(V^2 - 4RP)) == (V - sqrt(...)) / (2R), without cancellation for small P.
        return 2.0 * p / (v + disc)

    def terminal_power_w(self, current_a: Any) -> np.ndarray:
        """Terminal power (W) of a battery current: ``V I - R I**2`` (InvalidParameterError
        for a non-finite current)."""
        i = real_array("current_a", current_a)
        return self.voltage_v * i - self.internal_resistance_ohm * i * i

    def effective_current_a(self, current_a: Any) -> np.ndarray:
        """Current that depletes the rated capacity (Peukert): ``I (|I| / I_ref)**(k-1)`` for
        discharge, ``I`` for charge (A); InvalidParameterError for a non-finite current."""
        i = real_array("current_a", current_a)
        k = self.peukert_exponent
        if k == 1.0:
            return i.copy()
        ratio = np.abs(i) / self.peukert_reference_current_a
        return np.where(i > 0, i * ratio ** (k - 1.0), i)

    def replace(self, **changes: Any) -> Battery:
        """A copy with some fields changed (validated again), e.g. ``initial_soc`` for the
        next leg of a mission."""
        return dataclasses.replace(self, **changes)

    # ------------------------------------------------------------- stepping
    def _start_soc(self, soc: Any) -> float:
        start = check_optional_real("soc", soc, low=0.0, high=1.0)
        return self.initial_soc if start is None else start

    def soc_after(self, charge_mah: float, *, soc: float | None = None) -> float:
        """State of charge (fraction, never below 0) after drawing ``charge_mah`` of
        *effective* (Peukert-adjusted) charge from ``soc`` (default :attr:`initial_soc`).

        Examples
        --------
        >>> b = Battery(capacity_ah=1.0, voltage_v=12.0)
        >>> b.soc_after(250.0), b.soc_after(250.0, soc=0.5), b.soc_after(5000.0)
        (0.75, 0.25, 0.0)
        """
        drawn = check_real("charge_mah", charge_mah)
        return max(0.0, self._start_soc(soc) - drawn * AS_PER_MAH / (self.capacity_ah * S_PER_H))

    def soc_after_energy(self, energy_j: float, *, power_w: float, soc: float | None = None) -> float:
        """State of charge (fraction, never below 0) after the load draws ``energy_j`` at a
        constant terminal power ``power_w``, from ``soc`` (default :attr:`initial_soc`).

        The same arithmetic as :func:`discharge_from_power` on a constant power (and as the
        prediction of :func:`energy.energy_budget`): the draw lasts ``energy_j / power_w``
        seconds at the battery current :meth:`current_a` (internal resistance), depleting
        the capacity at :meth:`effective_current_a` (Peukert). Use it to book energy leg by
        leg instead of ``soc -= energy / capacity``.

        ``energy_j`` (J) is >= 0; ``power_w`` (W) > 0 and at most :attr:`max_power_w`;
        ``soc`` in [0, 1]. Returns the state of charge after the draw, clamped at 0
        (:meth:`time_to_empty_s` says when a draw runs the pack out). Anything else raises
        :class:`~terrawatt_base.errors.InvalidParameterError`.

        Examples
        --------
        >>> b = Battery(capacity_ah=1.0, voltage_v=10.0)
        >>> b.soc_after_energy(3600.0 * 2.5, power_w=5.0)  # 2.5 Wh of 10 Wh
        0.75
        >>> b.soc_after_energy(3600.0 * 20.0, power_w=5.0)  # more than the pack holds
        0.0
        """
        energy = check_real("energy_j", energy_j, low=0.0)
        power = check_real("power_w", power_w, low=0.0, low_inclusive=False)
        start = self._start_soc(soc)
        current = float(self.current_a(power))
        charge_as = float(self.effective_current_a(current)) * energy / power
        return max(0.0, start - charge_as / (self.capacity_ah * S_PER_H))

    def time_to_empty_s(self, power_w: float, *, soc: float | None = None) -> float:
        """Time (s) a constant terminal power ``power_w`` (> 0) takes to run the pack from
        ``soc`` (default :attr:`initial_soc`) down to 0, with the same losses as
        :meth:`soc_after_energy`.

        Examples
        --------
        >>> Battery(capacity_ah=1.0, voltage_v=10.0).time_to_empty_s(5.0, soc=0.5)
        3600.0
        """
        power = check_real("power_w", power_w, low=0.0, low_inclusive=False)
        start = self._start_soc(soc)
        current = float(self.effective_current_a(float(self.current_a(power))))
        return start * self.capacity_ah * S_PER_H / current


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


def _crossing(t: np.ndarray, soc: np.ndarray, level: float, *,
              inclusive: bool = False) -> tuple[int | None, float | None]:
    """First index with ``soc < level`` (``<=`` when ``inclusive``) and the linearly interpolated crossing time."""
    below = soc <= level if inclusive else soc < level
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
        State of charge (fraction of the capacity), never below 0: held at 0 from the
        depletion on (see the module conventions).
    reserve_crossed_index : int or None
        First sample below the reserve, or None.
    reserve_crossed_time_s : float or None
        Interpolated time at which the SoC reaches the reserve, or None.
    depleted_index : int or None
        First sample at which the pack is empty (SoC 0), or None.
    depleted_time_s : float or None
        Interpolated time at which the SoC reaches 0 (the pack runs out), or None.

    Derived: ``energy_wh``, ``soc_pct``, ``total_energy_j``, ``total_charge_mah``,
    ``final_soc``, ``reserve_crossed``, ``depleted``.
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
    depleted_index: int | None = None
    depleted_time_s: float | None = None

    def __post_init__(self) -> None:
        _check_battery(self.battery)
        n = np.shape(self.time_s)
        for name in ("time_s", "power_w", "current_a", "energy_j", "charge_mah", "soc"):
            arr = readonly(getattr(self, name), np.float64)
            if arr.shape != n or arr.ndim != 1:
                raise InvalidParameterError(f"Discharge.{name} must have shape {n!r}, got {arr.shape!r}")
            object.__setattr__(self, name, arr)
        if np.any(self.soc < 0.0):
            raise InvalidParameterError(f"Discharge.soc must be >= 0, got a minimum of {float(self.soc.min())!r}")
        if (self.depleted_index is None) != (self.depleted_time_s is None):
            raise InvalidParameterError(
                f"Discharge.depleted_index and depleted_time_s must both be set or both None, got "
                f"{self.depleted_index!r} and {self.depleted_time_s!r}"
            )

    @property
    def energy_wh(self) -> np.ndarray:
        """Cumulative load energy (Wh)."""
        return self.energy_j / S_PER_H

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

    @property
    def depleted(self) -> bool:
        """Whether the pack ran out (the SoC reached 0)."""
        return self.depleted_index is not None

    def __repr__(self) -> str:
        return (
            f"Discharge(samples={self.time_s.size}, duration_s={self.time_s[-1] - self.time_s[0]:.1f}, "
            f"energy_wh={self.total_energy_j / S_PER_H:.3f}, charge_mah={self.total_charge_mah:.1f}, "
            f"final_soc={self.final_soc:.4f}, reserve_crossed_time_s={self.reserve_crossed_time_s!r}, "
            f"depleted_time_s={self.depleted_time_s!r})"
        )


def _discharge(battery: Battery, t: np.ndarray, power: np.ndarray, current: np.ndarray) -> Discharge:
    energy = _cumtrapz(t, power)
    charge_as = _cumtrapz(t, current)
    eff_as = charge_as if battery.peukert_exponent == 1.0 else _cumtrapz(t, battery.effective_current_a(current))
    raw = battery.initial_soc - eff_as / (battery.capacity_ah * S_PER_H)
    # The first crossings happen before any clamping (the reserve is >= 0).
    k, tc = _crossing(t, raw, battery.reserve_soc)
    kd, td = _crossing(t, raw, 0.0, inclusive=True)
    # Held at 0 once empty; charging afterwards fills the pack from 0 (a running floor).
    soc = raw - np.minimum(np.minimum.accumulate(raw), 0.0)
    return Discharge(battery, t, power, current, energy, charge_as / AS_PER_MAH, soc, k, tc, kd, td)


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
