"""The battery as a robot draws it, chunk by chunk: state of charge, energies, the series of a mission.

:class:`ChargeAccount` books each chunk's battery power (W at its timestamps) through
:func:`energy.discharge_from_power` from the state of charge the last chunk left, joined to
the last sample booked (so consecutive chunks integrate as one series; a gap longer than
:data:`MAX_JOIN_GAP_S` is not bridged). It stops a chunk where the reserve is reached and
keeps the series a mission result draws (time, position, state of charge, cumulative actual
and predicted energy) and the battery draw its budget is computed from.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from energy import Battery, EnergyBudget, discharge_from_power, energy_budget

__all__ = ["MAX_JOIN_GAP_S", "SERIES", "ChargeAccount"]

#: A gap between chunks longer than this (s) is not integrated across (the robot was off).
MAX_JOIN_GAP_S = 5.0
#: The series a :class:`ChargeAccount` keeps: time, x, y, state of charge, cumulative energy, cumulative prediction.
SERIES = ("t", "x", "y", "soc", "e", "p")


class ChargeAccount:
    """State of charge and energies of one mission, booked chunk by chunk (module docstring).

    Attributes
    ----------
    battery : Battery
    soc : float
        State of charge now.
    last_power : (float, float)
        Time (s) and power (W) of the last sample booked (NaN before any).
    e_total, p_total : float
        Energy drawn (J) and the predicted energy of the legs closed (J).
    driven_j, excitation_j : float
        Energy of driving and of manoeuvres (J).
    series : dict of lists of arrays
        The :data:`SERIES`.
    draw : list of (time, power) arrays
        Every sample booked, on one strictly increasing clock.
    """

    SCALARS = ("soc", "e_total", "p_total", "driven_j", "excitation_j")

    def __init__(self, battery: Battery) -> None:
        self.battery = battery
        self.soc = float(battery.initial_soc)
        self.last_power = (math.nan, math.nan)
        self.e_total = self.p_total = self.driven_j = self.excitation_j = 0.0
        self.series: dict[str, list[np.ndarray]] = {k: [] for k in SERIES}
        self.draw: list[tuple[np.ndarray, np.ndarray]] = []

    def available_j(self) -> float:
        """Nominal energy above the reserve at the current state of charge (J)."""
        return self.battery.replace(initial_soc=self.soc).usable_energy_wh * 3600.0

    def push(self, t: Any, x: Any, y: Any, soc: Any, e: Any, p: Any) -> None:
        """Extend the series."""
        for key, arr in zip(SERIES, (t, x, y, soc, e, p)):
            self.series[key].append(np.atleast_1d(np.asarray(arr, dtype=np.float64)))

    def book(self, t: np.ndarray, power_w: np.ndarray, xy: np.ndarray, predicted_j: np.ndarray, *,
             driving: bool) -> tuple[float, bool]:
        """Draw the battery through one chunk: its energy (J, to the reserve if reached) and
        whether the reserve was reached.

        Parameters
        ----------
        t, power_w : ndarray, shape (N,)
            The chunk's timestamps (s) and battery power (W).
        xy : ndarray, shape (N, 2)
            Where each sample was (m).
        predicted_j : ndarray, shape (N,)
            The predicted energy of the leg under way at each sample (J, from its start).
        driving : bool
            Driving (else a manoeuvre).
        """
        t = np.asarray(t, dtype=np.float64)
        power = np.asarray(power_w, dtype=np.float64)
        t_last, p_last = self.last_power
        joined = math.isfinite(t_last) and 0.0 < t[0] - t_last <= MAX_JOIN_GAP_S
        tt = np.concatenate(([t_last], t)) if joined else t
        pp = np.concatenate(([p_last], power)) if joined else power
        if tt.size < 2:  # a single sample and nothing to join: no time has passed
            tt, pp = np.array([t[0], t[0] + 1e-9]), np.array([power[0], power[0]])
        d = discharge_from_power(self.battery.replace(initial_soc=self.soc), tt - tt[0], pp)
        crossed = d.reserve_crossed_time_s is not None
        k = len(tt) if not crossed else int(d.reserve_crossed_index)
        energy, soc = np.asarray(d.energy_j), np.asarray(d.soc)
        if crossed:
            tc = float(d.reserve_crossed_time_s)
            e_end, soc_end = float(np.interp(tc, tt - tt[0], energy)), self.battery.reserve_soc
        else:
            e_end, soc_end = float(energy[-1]), float(soc[-1])
        off = 1 if joined else 0
        sel = slice(off, max(k, off + 1))
        e_series = self.e_total + energy[sel]
        n = e_series.size
        self.push(t[:n], xy[:n, 0], xy[:n, 1], soc[sel][:n], e_series, self.p_total + predicted_j[:n])
        if crossed:
            self._add_draw(np.append(tt[off:k], tt[0] + tc), np.append(pp[off:k], np.interp(tc, tt - tt[0], pp)))
        else:
            self._add_draw(tt[off:k], pp[off:k])
        self.e_total += e_end
        if driving:
            self.driven_j += e_end
        else:
            self.excitation_j += e_end
        self.soc = float(soc_end)
        self.last_power = (float(tt[min(k, len(tt)) - 1]), float(pp[min(k, len(pp)) - 1]))
        return e_end, crossed or (self.battery.reserve_soc > 0 and self.soc <= self.battery.reserve_soc + 1e-12)

    def _add_draw(self, t: np.ndarray, power_w: np.ndarray) -> None:
        """Book a battery draw (a series that starts where the last ended is moved on by a microsecond)."""
        t = np.asarray(t, dtype=np.float64)
        if t.size == 0:
            return
        if self.draw and t[0] <= self.draw[-1][0][-1]:
            t = t + (self.draw[-1][0][-1] - t[0]) + 1e-6
        self.draw.append((t, np.asarray(power_w, dtype=np.float64)))

    def budget(self, predicted_j: float, span_s: float) -> EnergyBudget:
        """The whole draw against ``predicted_j``; with nothing drawn, no draw over ``span_s``."""
        if self.draw:
            t, p = (np.concatenate(parts) for parts in zip(*self.draw))
        else:
            t, p = np.array([0.0, span_s if span_s > 0 else 1.0]), np.zeros(2)
        return energy_budget(discharge_from_power(self.battery, t - t[0], p), predicted_j)

    def arrays(self) -> dict[str, np.ndarray]:
        """The series, each one array."""
        return {k: np.concatenate(v) if v else np.zeros(0) for k, v in self.series.items()}
