"""The result of a driven (or replayed) route: time series, energy budget, where the reserve was crossed."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from energy import EnergyBudget, InteractionLog
from energy.budget import CURRENT_CONVENTIONS
from terrain import TerrainMap
from terrawatt_base.answer import write_answer
from terrawatt_base.atomic import json_finite
from terrawatt_base.checks import check_choice, check_int, readonly
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.formats import result_document, write_result_json

from ..route import Route
from .figures import plot_mission

__all__ = [
    "MISSION_STATUSES",
    "MISSION_FORMAT_VERSION",
    "MissionResult",
]

#: ``completed``: the route was driven to its end with the state of charge at or above the
#: reserve throughout. ``reserve_violated``: the state of charge went below the reserve
#: (the crossing point is reported; with ``stop_at_reserve`` the series ends there).
MISSION_STATUSES = ("completed", "reserve_violated")
#: Version of the JSON of :meth:`MissionResult.to_dict` (mission.json of :meth:`MissionResult.write`).
MISSION_FORMAT_VERSION = 1

_SERIES = (
    "time_s",
    "x_m",
    "y_m",
    "heading_rad",
    "v_mps",
    "omega_radps",
    "current_left_a",
    "current_right_a",
    "power_w",
    "battery_current_a",
    "energy_wh",
    "predicted_energy_wh",
    "charge_mah",
    "soc",
)


@dataclass(frozen=True, eq=False, repr=False)
class MissionResult:
    """A driven (or replayed) route: time series and energy budget.

    Derived: ``n_samples``, ``duration_s``, ``feasible``, ``completed``. Methods:
    :meth:`summary`, :meth:`to_dict`, :meth:`plot`, :meth:`write`.

    Attributes
    ----------
    status : str
        One of :data:`MISSION_STATUSES`.
    source : str
        ``"truth"`` (driven with a TruthSimulator) or ``"replay"`` (a recorded log).
    route : Route
        The route that was driven.
    budget : EnergyBudget
        Predicted vs actual energy, reserve at arrival, feasibility, per-segment breakdown
        (one entry per route segment).
    time_s : ndarray, shape (N,)
        Sample times from the start of the mission (s).
    x_m, y_m, heading_rad : ndarray, shape (N,)
        Pose (m, m, rad).
    v_mps, omega_radps : ndarray, shape (N,)
        Speed and yaw rate of the log (commanded or measured, see ``log.meta``).
    current_left_a, current_right_a : ndarray, shape (N,)
        Logged side currents (A; their meaning is ``current_convention``).
    power_w : ndarray, shape (N,)
        Battery-side power: drive plus electronics (W).
    battery_current_a : ndarray, shape (N,)
        Battery current delivering ``power_w`` (A).
    energy_wh, predicted_energy_wh : ndarray, shape (N,)
        Cumulative actual energy and the prediction spread over each segment's samples in
        proportion to time (Wh).
    charge_mah : ndarray, shape (N,)
        Cumulative battery charge (mAh).
    soc : ndarray, shape (N,)
        State of charge (fraction).
    segment_index : ndarray of int, shape (N,)
        Route segment of each sample.
    reserve_crossed_time_s : float or None
        When the state of charge reached the reserve, or None.
    reserve_crossed_xy_m : (float, float) or None
        Where (interpolated along the driven path).
    reserve_crossed_segment : int or None
        In which route segment.
    speed_mps, accel_mps2, turn_rate_radps, yaw_accel_radps2 : float
        The velocity profile.
    current_convention : str
        How the side currents were turned into power (see
        :func:`energy.budget.log_battery_power_w`).
    truth_energy_j : float
        Noise-free battery energy of the truth simulator over the same samples (J; NaN
        for a replay). ``budget.actual_energy_j`` is what the logged (measured) currents
        give; the two differ by the measurement model.
    log : InteractionLog
        The driven log (with pose), for per-cell comparisons.
    depleted_time_s : float or None
        When the battery ran out (its state of charge reached 0), or None.
    depleted_xy_m : (float, float) or None
        Where (interpolated along the driven path).
    forecast : {"edges", "profile"}
        What priced ``budget.predicted_energy_j``: the route's edge energies, or the physics
        model over the whole driven profile (see :func:`planner.simulate_mission`).
    """

    status: str
    source: str
    route: Route
    budget: EnergyBudget
    time_s: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    heading_rad: np.ndarray
    v_mps: np.ndarray
    omega_radps: np.ndarray
    current_left_a: np.ndarray
    current_right_a: np.ndarray
    power_w: np.ndarray
    battery_current_a: np.ndarray
    energy_wh: np.ndarray
    predicted_energy_wh: np.ndarray
    charge_mah: np.ndarray
    soc: np.ndarray
    segment_index: np.ndarray
    reserve_crossed_time_s: float | None
    reserve_crossed_xy_m: tuple[float, float] | None
    reserve_crossed_segment: int | None
    speed_mps: float
    accel_mps2: float
    turn_rate_radps: float
    yaw_accel_radps2: float
    current_convention: str
    truth_energy_j: float
    log: InteractionLog
    depleted_time_s: float | None = None
    depleted_xy_m: tuple[float, float] | None = None
    forecast: str = "edges"

    def __post_init__(self) -> None:
        if self.status not in MISSION_STATUSES:
            raise InvalidParameterError(f"status must be one of {MISSION_STATUSES!r}, got {self.status!r}")
        if self.source not in ("truth", "replay"):
            raise InvalidParameterError(f"source must be 'truth' or 'replay', got {self.source!r}")
        if not isinstance(self.route, Route):
            raise InvalidParameterError(f"route must be a Route, got {type(self.route).__name__!r}")
        if not isinstance(self.budget, EnergyBudget):
            raise InvalidParameterError(f"budget must be an EnergyBudget, got {type(self.budget).__name__!r}")
        if not isinstance(self.log, InteractionLog):
            raise InvalidParameterError(f"log must be an InteractionLog, got {type(self.log).__name__!r}")
        n = np.shape(self.time_s)
        if len(n) != 1 or n[0] < 2:
            raise InvalidParameterError(f"time_s must be 1-D with at least 2 samples, got shape {n!r}")
        for name in _SERIES:
            arr = readonly(getattr(self, name), np.float64)
            if arr.shape != n:
                raise InvalidParameterError(f"{name} must have shape {n!r}, got {arr.shape!r}")
            object.__setattr__(self, name, arr)
        seg = readonly(self.segment_index, np.int64)
        if seg.shape != n:
            raise InvalidParameterError(f"segment_index must have shape {n!r}, got {seg.shape!r}")
        object.__setattr__(self, "segment_index", seg)
        if (self.status == "reserve_violated") == self.budget.feasible:
            raise InvalidParameterError(
                f"status {self.status!r} contradicts budget.feasible={self.budget.feasible!r}"
            )
        check_choice("current_convention", self.current_convention, CURRENT_CONVENTIONS)

    # ------------------------------------------------------------------ derived
    @property
    def n_samples(self) -> int:
        """Number of samples of the series."""
        return int(self.time_s.size)

    @property
    def duration_s(self) -> float:
        """Duration of the series (s)."""
        return float(self.time_s[-1] - self.time_s[0])

    @property
    def feasible(self) -> bool:
        """The state of charge stayed at or above the reserve."""
        return self.budget.feasible

    @property
    def completed(self) -> bool:
        """``status == "completed"``."""
        return self.status == "completed"

    # ---------------------------------------------------------------- output
    def to_dict(self, *, series_every: int = 1) -> dict[str, Any]:
        """JSON-ready result document, format ``terrawatt-mission``: settings, route, budget, crossing, series.

        Parameters
        ----------
        series_every : int
            Keep every ``series_every``-th sample of the time series (>= 1; the last
            sample is always kept). The budget is computed from all samples.

        Raises
        ------
        InvalidParameterError
            ``series_every`` not an int >= 1.
        """
        series_every = check_int("series_every", series_every, low=1)
        keep = np.arange(0, self.n_samples, int(series_every))
        if keep[-1] != self.n_samples - 1:
            keep = np.append(keep, self.n_samples - 1)
        series: dict[str, list[Any]] = {name: getattr(self, name)[keep].tolist() for name in _SERIES}
        series["segment_index"] = self.segment_index[keep].tolist()
        route = json_finite(self.route.summary())
        route["waypoints_m"] = self.route.waypoints_m.tolist()
        route["segment_energy_j"] = self.route.segment_energy_j.tolist()
        route["turn_energy_j"] = self.route.turn_energy_j.tolist()
        return result_document("mission", MISSION_FORMAT_VERSION, {
            "status": self.status,
            "source": self.source,
            "settings": {
                "speed_mps": self.speed_mps,
                "accel_mps2": self.accel_mps2,
                "turn_rate_radps": self.turn_rate_radps,
                "yaw_accel_radps2": self.yaw_accel_radps2,
                "current_convention": self.current_convention,
                "robot": self.log.meta.robot,
                "log_source": self.log.meta.source,
            },
            "route": route,
            "budget": self.budget.to_json_dict(),
            "reserve_crossing": None
            if self.reserve_crossed_time_s is None
            else {
                "time_s": self.reserve_crossed_time_s,
                "xy_m": list(self.reserve_crossed_xy_m),
                "segment": self.reserve_crossed_segment,
            },
            "depletion": None
            if self.depleted_time_s is None
            else {"time_s": self.depleted_time_s, "xy_m": list(self.depleted_xy_m)},
            "truth_energy_j": json_finite(self.truth_energy_j),
            "forecast": self.forecast,
            "duration_s": self.duration_s,
            "series_every": int(series_every),
            "series": series,
        })

    def summary(self) -> str:
        """A few lines for people: status, predicted against actual energy, arrival charge, the reserve crossing."""
        b = self.budget
        lines = [f"mission {self.status} ({self.source}): {self.route.length_m:.1f} m in {self.duration_s:.1f} s",
                 f"energy: predicted {b.predicted_energy_wh:.2f} Wh ({self.forecast} forecast), actual "
                 f"{b.actual_energy_wh:.2f} Wh, error {b.error_pct:+.2f} %",
                 f"arrival state of charge {b.arrival_soc_pct:.1f} % (margin {b.reserve_margin_pct:+.1f} points "
                 f"above the reserve)"]
        if self.reserve_crossed_time_s is not None:
            x, y = self.reserve_crossed_xy_m
            lines.append(f"below the reserve {self.reserve_crossed_time_s:.1f} s in, at ({x:.1f}, {y:.1f}) m")
        if self.depleted_time_s is not None:
            lines.append(f"the battery ran out {self.depleted_time_s:.1f} s in")
        return "\n".join(lines)

    def write(self, out_dir: str | os.PathLike[str], *, series_every: int = 1, terrain: TerrainMap | None = None,
              on_figure_error: str = "warn") -> list[Path]:
        """Write mission.json (:meth:`to_dict` with ``series_every``, a non-finite number as null) and mission.png
        (:meth:`plot`, over ``terrain`` when given) into ``out_dir``; return the files written (a figure that fails
        warns and is left out, :func:`terrawatt_base.answer.write_answer`).

        Raises
        ------
        InvalidParameterError
            ``series_every`` not an int >= 1 (before anything is written).
        """
        doc = self.to_dict(series_every=series_every)
        return write_answer(out_dir, {"mission.json": lambda p: write_result_json(p, doc)},
                            {"mission.png": lambda p: self.plot(p, terrain=terrain)}, on_figure_error=on_figure_error)

    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None, terrain: TerrainMap | None = None,
             title: str | None = None, dpi: int = 110) -> Path | tuple[Any, ...]:
        """SoC over time, predicted vs actual cumulative energy, and the driven path coloured
        by battery power (over the map's elevation when ``terrain`` is given):
        :func:`~planner.missions.figures.plot_mission`.

        Give exactly one of ``path`` (a PNG written atomically with matplotlib's Agg backend,
        no display needed) or ``ax`` (3 matplotlib Axes to draw into; nothing is written).

        Returns
        -------
        Path or tuple of 3 Axes
            The written file, or the axes drawn into.

        Raises
        ------
        InvalidParameterError
            Both or neither of ``path`` and ``ax``; a bad ``path`` or not 3 axes.
        """
        return plot_mission(self, path, terrain, ax=ax, title=title, dpi=dpi)

    def __repr__(self) -> str:
        b = self.budget
        return (
            f"MissionResult(status={self.status!r}, source={self.source!r}, samples={self.n_samples}, "
            f"duration_s={self.duration_s:.1f}, predicted_wh={b.predicted_energy_wh:.3f}, "
            f"actual_wh={b.actual_energy_wh:.3f}, error_pct={b.error_pct:+.2f}, "
            f"arrival_soc_pct={b.arrival_soc_pct:.2f}, reserve_crossed_time_s={self.reserve_crossed_time_s!r}"
            + ("" if self.depleted_time_s is None else f", depleted_time_s={self.depleted_time_s:.1f}")
            + ")"
        )
