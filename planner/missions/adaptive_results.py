"""The adaptive loop's records (legs, updates, replans) and its outcome, :class:`AdaptiveResult`."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from energy import EnergyBudget, InteractionLog
from terrain import TerrainMap
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.formats import result_document, write_result_json

from ..registry import CellModelRegistry
from ..route import Route
from .figures import plot_adaptive_mission

__all__ = [
    "ADAPTIVE_STATUSES",
    "ADAPTIVE_FORMAT_VERSION",
    "LegRecord",
    "UpdateRecord",
    "ReplanRecord",
    "AdaptiveResult",
]

ADAPTIVE_STATUSES = ("completed", "budget_exceeded", "reserve_violated", "no_route", "max_legs")
ADAPTIVE_FORMAT_VERSION = 1


@dataclass(frozen=True)
class LegRecord:
    """One driven leg: where, predicted and actual battery energy (J), duration (s).

    ``predicted_energy_j`` prices the leg's velocity profile with the models in use before it
    was driven; ``route_energy_j`` is the planner's edge-cost energy of the same leg.
    """

    index: int
    start_xy_m: tuple[float, float]
    end_xy_m: tuple[float, float]
    predicted_energy_j: float
    actual_energy_j: float
    duration_s: float
    n_samples: int
    route_energy_j: float


@dataclass(frozen=True)
class UpdateRecord:
    """One model update attempt after leg ``after_leg``."""

    after_leg: int
    ground: str
    region_cells: int
    scope_cells: int
    region_error_pct: float
    accepted: bool
    model_id: int | None
    validation_error_new: float
    validation_error_old: float
    excitation_energy_j: float
    excitation_duration_s: float
    wall_time_s: float
    kind: str = "excitation"  # "reuse": a model learned elsewhere assigned without a manoeuvre; "in_run": the
    # serving model updated in-run on the excitation data (AdaptiveSettings.in_run_update)


@dataclass(frozen=True)
class ReplanRecord:
    """A (re)plan: when, the remaining route's predicted energy, whether the route changed."""

    after_leg: int
    reason: str
    predicted_energy_j: float
    previous_route_energy_j: float
    route_changed: bool
    refresh_time_s: float
    planning_time_s: float
    tables_built: int


@dataclass(frozen=True, eq=False)
class AdaptiveResult:
    """Outcome of :func:`run_adaptive_mission` (see the module docstring).

    Attributes
    ----------
    status, reason : str
        One of :data:`ADAPTIVE_STATUSES` and a sentence saying why the loop stopped.
    final_xy_m : (float, float)
        Where the robot is at the end.
    distance_to_goal_m : float
    initial_route : Route
        The first plan (prior models).
    legs, updates, replans : tuple of records
    time_s, x_m, y_m, soc, energy_j, predicted_energy_j : ndarray
        Series over the whole mission (driving and excitation), cumulative energies (J).
    driven_energy_j, excitation_energy_j : float
        Actual battery energy of driving and of the excitation manoeuvres (J).
    update_wall_time_s : float
        Wall-clock time spent fitting/validating/refreshing for updates (s).
    final_soc : float
    skipped_updates : tuple of str
        Updates not attempted because the excitation manoeuvre and the remaining route did not
        both fit above the reserve, one sentence each.
    budget : EnergyBudget or None
        The whole mission's battery draw (driving and excitation manoeuvres) against the
        first plan's predicted energy (:func:`energy.energy_budget`): arrival state of
        charge, reserve margin, whether the prediction fitted, where the pack ran out.
    manoeuvre_logs : tuple of (int, InteractionLog)
        Each excitation manoeuvre's runs, with the leg after which it was driven, on the
        same clock as the legs.
    leg_logs : tuple of InteractionLog
        What the robot's sensors recorded on each leg, in order (commands, currents, IMU,
        poses, ground labels; the truth simulator's logs): the data to diagnose the planning
        model's gap on (:meth:`planner.missions.MissionReport.write` with ``logs=True``).
        Not in the JSON document.
    """

    status: str
    reason: str
    final_xy_m: tuple[float, float]
    distance_to_goal_m: float
    initial_route: Route
    legs: tuple[LegRecord, ...]
    updates: tuple[UpdateRecord, ...]
    replans: tuple[ReplanRecord, ...]
    time_s: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    soc: np.ndarray
    energy_j: np.ndarray
    predicted_energy_j: np.ndarray
    driven_energy_j: float
    excitation_energy_j: float
    update_wall_time_s: float
    final_soc: float
    skipped_updates: tuple[str, ...] = ()
    budget: EnergyBudget | None = None
    leg_logs: tuple[InteractionLog, ...] = ()
    manoeuvre_logs: tuple[tuple[int, InteractionLog], ...] = ()

    def __post_init__(self) -> None:
        if self.status not in ADAPTIVE_STATUSES:
            raise InvalidParameterError(f"status must be one of {ADAPTIVE_STATUSES!r}, got {self.status!r}")

    # ------------------------------------------------------------------ metrics
    @property
    def accepted_updates(self) -> int:
        """Number of accepted updates."""
        return sum(u.accepted for u in self.updates)

    def _legs_error_pct(self, legs: list[LegRecord]) -> float:
        pred = sum(leg.predicted_energy_j for leg in legs)
        act = sum(leg.actual_energy_j for leg in legs)
        return 100.0 * (pred - act) / act if act > 0 else math.nan

    @property
    def error_before_update_pct(self) -> float:
        """Prediction error (%) of the legs driven before the first accepted update (all legs if none)."""
        first = next((u.after_leg for u in self.updates if u.accepted), None)
        return self._legs_error_pct([lg for lg in self.legs if first is None or lg.index <= first])

    @property
    def error_after_update_pct(self) -> float:
        """Prediction error (%) of the legs driven after the last accepted update (NaN if none)."""
        last = next((u.after_leg for u in reversed(self.updates) if u.accepted), None)
        if last is None:
            return math.nan
        return self._legs_error_pct([lg for lg in self.legs if lg.index > last])

    @property
    def remaining_error_after_update_pct(self) -> float:
        """Error (%) of the remaining-route prediction made right after the last accepted update
        against the energy actually driven from there (NaN without update or unfinished)."""
        last = next((u.after_leg for u in reversed(self.updates) if u.accepted), None)
        plan = next((p for p in reversed(self.replans) if p.after_leg == last), None) if last is not None else None
        if plan is None or self.status != "completed":
            return math.nan
        act = sum(lg.actual_energy_j for lg in self.legs if lg.index > last)
        return 100.0 * (plan.predicted_energy_j - act) / act if act > 0 else math.nan

    @property
    def route_changes(self) -> int:
        """Replans that changed the route."""
        return sum(p.route_changed for p in self.replans if p.reason != "initial")

    def to_json_dict(self, *, series_every: int = 10) -> dict[str, Any]:
        """Plain JSON result document, format ``terrawatt-adaptive-mission`` (non-finite numbers become ``None``);
        series every ``series_every`` samples."""
        def num(x: Any) -> Any:
            if isinstance(x, (float, np.floating)):
                return float(x) if math.isfinite(x) else None
            if isinstance(x, (np.integer,)):
                return int(x)
            if isinstance(x, tuple):
                return [num(v) for v in x]
            return x

        def rec(r: Any) -> dict[str, Any]:
            return {k: num(v) for k, v in vars(r).items()}

        k = max(1, int(series_every))
        return result_document("adaptive-mission", ADAPTIVE_FORMAT_VERSION, {
            "status": self.status,
            "reason": self.reason,
            "final_xy_m": num(self.final_xy_m),
            "distance_to_goal_m": num(self.distance_to_goal_m),
            "final_soc": num(self.final_soc),
            "initial_route": self.initial_route.summary(),
            "initial_route_waypoints_m": self.initial_route.waypoints_m.tolist(),
            "driven_energy_j": num(self.driven_energy_j),
            "excitation_energy_j": num(self.excitation_energy_j),
            "update_wall_time_s": num(self.update_wall_time_s),
            "accepted_updates": self.accepted_updates,
            "route_changes": self.route_changes,
            "error_before_update_pct": num(self.error_before_update_pct),
            "error_after_update_pct": num(self.error_after_update_pct),
            "remaining_error_after_update_pct": num(self.remaining_error_after_update_pct),
            "legs": [rec(r) for r in self.legs],
            "updates": [rec(r) for r in self.updates],
            "skipped_updates": list(self.skipped_updates),
            "budget": None if self.budget is None else self.budget.to_json_dict(),
            "replans": [rec(r) for r in self.replans],
            "series": {name: [num(v) for v in getattr(self, name)[::k].tolist()]
                       for name in ("time_s", "x_m", "y_m", "soc", "energy_j", "predicted_energy_j")},
        })

    def save_json(self, path: str | os.PathLike[str], *, series_every: int = 10) -> Path:
        """Write :meth:`to_json_dict` atomically to ``path`` (:func:`~terrawatt_base.formats.write_result_json`)."""
        return write_result_json(path, self.to_json_dict(series_every=series_every))

    def plot(self, path: str | os.PathLike[str] | None = None, terrain: TerrainMap | None = None,
             registry: CellModelRegistry | None = None, *, axes: Any = None) -> Path | tuple[Any, ...]:
        """Four panels: route over cells coloured by model and by error, SoC, cumulative energy
        (:func:`~planner.missions.figures.plot_adaptive_mission`).

        Give exactly one of ``path`` (write a PNG atomically and return the path) or ``axes``
        (4 matplotlib Axes to draw into, row by row; nothing is written and they are
        returned); ``terrain`` and ``registry`` are required.

        Raises
        ------
        InvalidParameterError
            Both or neither of ``path`` and ``axes``; a bad ``path`` or not 4 axes; no
            ``terrain`` or ``registry``.
        """
        return plot_adaptive_mission(self, path, terrain, registry, axes=axes)
