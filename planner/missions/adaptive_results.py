"""The adaptive loop's records (legs, updates, replans) and its outcome, :class:`AdaptiveResult`.

The answer of :func:`planner.missions.run_adaptive_mission` and, with the header ``terrawatt mission``
prints (the map, the robot, the prior, the computing time) and the models it started with, of
:func:`planner.missions.mission_report.simulate_adaptive_mission`: mission.json, mission.png, the legs' logs
and their drive bag.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from energy import Battery, EnergyBudget, InteractionLog
from energy.io import write_csv_log, write_drive_bag
from terrain import TerrainMap
from terrawatt_base.answer import write_answer
from terrawatt_base.atomic import check_output_path, json_finite
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
    "check_logs_folder",
    "LOGS_FOLDER",
    "START_REGISTRY",
]

def _percent(value: float) -> str:
    return "n/a" if math.isnan(value) else f"{value:.1f} %"  # NaN: nothing to compare


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
        model's gap on (:meth:`write` with ``logs=True``). Not in the JSON document.
    battery : Battery or None
        The battery driven against (the header of :meth:`summary`).
    map_label, robot, prior_ground : str
        How the map is named; the robot; the ground the prior model was trained on.
    adapt : bool
        Whether the models were updated on the way.
    start_xy_m, goal_xy_m : (float, float) or None
        Start and goal (m).
    computing_time_s : float or None
        Seconds the loop took (in mission.json when known).
    terrain : TerrainMap or None
        The map (for the figure and the drive bag's GPS fixes).
    registry : CellModelRegistry or None
        The per-cell models after the mission (for the figure).
    start_registry : CellModelRegistry or None
        A copy of the per-cell models as the mission started: what a replay of its logs
        starts from (written as ``start_registry/`` beside the logs).
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
    battery: Battery | None = None
    map_label: str = "map"
    robot: str = ""
    prior_ground: str = ""
    adapt: bool = True
    start_xy_m: tuple[float, float] | None = None
    goal_xy_m: tuple[float, float] | None = None
    computing_time_s: float | None = None
    terrain: TerrainMap | None = field(default=None, repr=False)
    registry: CellModelRegistry | None = field(default=None, repr=False)
    start_registry: CellModelRegistry | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.status not in ADAPTIVE_STATUSES:
            raise InvalidParameterError(f"status must be one of {ADAPTIVE_STATUSES!r}, got {self.status!r}")

    # ------------------------------------------------------------------ metrics
    @property
    def completed(self) -> bool:
        """Whether the robot reached the goal."""
        return self.status == "completed"

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

    def to_dict(self, *, series_every: int = 10) -> dict[str, Any]:
        """The content of mission.json, format ``terrawatt-adaptive-mission`` (non-finite numbers become ``None``):
        series every ``series_every`` samples and, when known, ``computing_time_s``."""
        k = max(1, int(series_every))
        doc = result_document("adaptive-mission", ADAPTIVE_FORMAT_VERSION, json_finite({
            "status": self.status,
            "reason": self.reason,
            "final_xy_m": self.final_xy_m,
            "distance_to_goal_m": self.distance_to_goal_m,
            "final_soc": self.final_soc,
            "initial_route": self.initial_route.summary(),
            "initial_route_waypoints_m": self.initial_route.waypoints_m.tolist(),
            "driven_energy_j": self.driven_energy_j,
            "excitation_energy_j": self.excitation_energy_j,
            "update_wall_time_s": self.update_wall_time_s,
            "accepted_updates": self.accepted_updates,
            "route_changes": self.route_changes,
            "error_before_update_pct": self.error_before_update_pct,
            "error_after_update_pct": self.error_after_update_pct,
            "remaining_error_after_update_pct": self.remaining_error_after_update_pct,
            "legs": [vars(r) for r in self.legs],
            "updates": [vars(r) for r in self.updates],
            "skipped_updates": list(self.skipped_updates),
            "budget": None if self.budget is None else self.budget.to_json_dict(),
            "replans": [vars(r) for r in self.replans],
            "series": {name: getattr(self, name)[::k] for name in ("time_s", "x_m", "y_m", "soc", "energy_j",
                                                                      "predicted_energy_j")},
        }))
        return doc if self.computing_time_s is None else {**doc, "computing_time_s": self.computing_time_s}

    def summary(self) -> str:
        """What ``terrawatt mission`` prints: battery, status, plan against drive, errors, updates, final charge."""
        battery = self.battery
        if battery is None:
            raise InvalidParameterError("the summary needs the battery driven against (a mission's result has it)")
        budget, route0 = self.budget, self.initial_route
        lines = [
            f"map: {self.map_label}; robot {self.robot}; battery {battery.capacity_ah:g} Ah at {battery.voltage_v:g} V "
            f"({battery.energy_capacity_wh:.0f} Wh, {battery.usable_energy_wh:.0f} Wh above the "
            f"{battery.min_reserve_pct:g} % reserve)",
            f"start {self.start_xy_m} -> goal {self.goal_xy_m}; prior trained on {self.prior_ground}; "
            f"adaptive updates {'on' if self.adapt else 'off'}",
            f"status: {self.status} — {self.reason}",
            f"first plan (prior models):  {budget.predicted_energy_wh:8.2f} Wh  {route0.length_m:7.1f} m  "
            f"({'fits' if budget.predicted_feasible else 'does NOT fit'} the usable {battery.usable_energy_wh:.0f} Wh)",
            f"driven (actual):            {self.driven_energy_j / 3600:8.2f} Wh  in {len(self.legs)} legs",
            f"excitation manoeuvres:      {self.excitation_energy_j / 3600:8.2f} Wh",
            f"prediction error before / after updates: {_percent(self.error_before_update_pct)} / "
            f"{_percent(self.error_after_update_pct)}",
            f"updates accepted: {self.accepted_updates} of {len(self.updates)}; route changes {self.route_changes}",
        ]
        lines += [f"skipped update {line}" for line in self.skipped_updates]
        if budget.depleted:
            lines.append(f"the battery ran out {budget.depleted_time_s:.1f} s into the mission")
        loop = "" if self.computing_time_s is None else f"; loop computing {self.computing_time_s:.1f} s"
        lines.append(f"final state of charge {budget.arrival_soc_pct:.1f} % (margin {budget.reserve_margin_pct:+.1f} "
                     f"points above the reserve){loop}")
        return "\n".join(lines)

    def write(self, out_dir: str | os.PathLike[str], *, logs: bool = False, on_figure_error: str = "warn"
              ) -> list[Path]:
        """Write mission.json and mission.png into ``out_dir``; return the files written (a figure that fails
        warns and is left out, :func:`terrawatt_base.answer.write_answer`).

        With ``logs``, also each leg's log (:attr:`AdaptiveResult.leg_logs`) as a CSV log
        ``logs/leg_NNN.csv`` (:func:`energy.io.write_csv_log`) and each manoeuvre run
        (:attr:`AdaptiveResult.manoeuvre_logs`) as ``logs/manoeuvre_NNN_K.csv`` (run K after leg
        NNN), all on the robot's clock: a folder that :func:`energy.diagnose`,
        :func:`planner.missions.replay.replay_drive` and :func:`energy.io.read_logs` read; and the models the
        mission started with as ``start_registry/`` (:attr:`start_registry`, the ``registry`` a replay
        starts from): the previous mission's leg files there are
        replaced, and a folder holding anything else is refused before anything is written
        (:func:`check_logs_folder`).
        """
        out = Path(out_dir)
        if logs:
            check_logs_folder(out)
        written = write_answer(out, {"mission.json": lambda p: write_result_json(p, self.to_dict())},
                               {"mission.png": self.plot},
                               on_figure_error=on_figure_error)
        if logs:
            folder = out / LOGS_FOLDER
            folder.mkdir(exist_ok=True)
            new = [folder / f"leg_{k:03d}.csv" for k in range(len(self.leg_logs))]
            for path, log in zip(new, self.leg_logs):
                written.append(write_csv_log(log, path))
            runs: dict[int, int] = {}
            for after, log in self.manoeuvre_logs:
                k = runs[after] = runs.get(after, -1) + 1
                path = folder / f"manoeuvre_{after:03d}_{k}.csv"
                new.append(path)
                written.append(write_csv_log(log, path))
            for stale in sorted(set(_leg_files(folder)) - set(new)):
                stale.unlink()
            if self.start_registry is not None:
                written.append(self.start_registry.save(out / START_REGISTRY, lambda model, p: model.save(p)))
        return written

    def write_drive_bag(self, path: str | os.PathLike[str]) -> Path:
        """The legs the robot drove as one recorded drive, a ROS 2 MCAP (``.mcap``) or a ROS 1 bag
        (``.bag``): odometry (map poses), IMU, drive currents and, on a map with a CRS, GPS fixes
        (:func:`energy.io.write_drive_bag`). The manoeuvre runs are not in it (they were made on
        the spot, without poses): a replay of the bag learns from the driving. Atomic.

        Raises
        ------
        InvalidParameterError
            A path of another suffix; a mission that drove no leg.
        """
        legs = self.leg_logs
        if not legs:
            raise InvalidParameterError("the mission drove no leg: there is no drive to write")
        lonlat = None
        if self.terrain is not None and self.terrain.crs is not None:
            lonlat = [np.column_stack(self.terrain.xy_to_lonlat(log.pose_xyh[:, 0], log.pose_xyh[:, 1]))
                      for log in legs]
        return write_drive_bag(list(legs), path, lonlat_deg=lonlat)

    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None, terrain: TerrainMap | None = None,
             registry: CellModelRegistry | None = None) -> Path | tuple[Any, ...]:
        """Four panels: route over cells coloured by model and by error, SoC, cumulative energy
        (:func:`~planner.missions.figures.plot_adaptive_mission`).

        Give exactly one of ``path`` (write a PNG atomically and return the path) or ``ax``
        (4 matplotlib Axes to draw into, row by row; nothing is written and they are
        returned). ``terrain`` and ``registry`` default to the result's own (:attr:`terrain`,
        :attr:`registry`, which a mission's result has).

        Raises
        ------
        InvalidParameterError
            Both or neither of ``path`` and ``ax``; a bad ``path`` or not 4 axes; no
            ``terrain`` or ``registry``, given or the result's.
        """
        return plot_adaptive_mission(self, path, self.terrain if terrain is None else terrain,
                                     self.registry if registry is None else registry, ax=ax)


#: The folder of :meth:`AdaptiveResult.write` (``logs=True``) that holds the legs' logs.
LOGS_FOLDER = "logs"
#: The folder of :meth:`AdaptiveResult.write` (``logs=True``) that holds the models the mission started with.
START_REGISTRY = "start_registry"


def _leg_files(folder: Path) -> list[Path]:
    """The files an earlier mission wrote there: exactly the names :meth:`AdaptiveResult.write` gives
    (``leg_NNN.csv``, ``manoeuvre_NNN_K.csv``; a user's ``leg_0042.csv`` is not one of them)."""
    def ours(name: str) -> bool:
        m = re.fullmatch(r"leg_(\d{3,})\.csv", name)
        if m:
            return name == f"leg_{int(m.group(1)):03d}.csv"
        m = re.fullmatch(r"manoeuvre_(\d{3,})_(\d+)\.csv", name)
        return m is not None and name == f"manoeuvre_{int(m.group(1)):03d}_{int(m.group(2))}.csv"

    return [p for p in folder.iterdir() if p.is_file() and ours(p.name)] if folder.is_dir() else []


def check_logs_folder(out_dir: str | os.PathLike[str]) -> Path:
    """Before any work: ``out_dir/logs`` can take a mission's leg logs (missing, or a folder holding
    nothing but an earlier mission's ``leg_NNN.csv`` files, which writing replaces); returns it.

    Raises
    ------
    InvalidParameterError
        It is a file, or a folder holding other files (they would be read as logs beside the legs').
    """
    folder = check_output_path(Path(out_dir) / LOGS_FOLDER, "the mission's logs folder", directory=True)
    if folder.is_dir():
        others = sorted(p.name for p in folder.iterdir() if p not in set(_leg_files(folder)))
        if others:
            raise InvalidParameterError(f"the mission's logs folder {str(folder)!r} holds other files ({others[:3]!r}"
                                        f"{' ...' if len(others) > 3 else ''}): they would be read as logs beside the "
                                        "legs'; give another output folder or move them")
    start = Path(out_dir) / START_REGISTRY
    if start.exists() and not (start.is_dir() and ((start / "registry.npz").is_file() or not any(start.iterdir()))):
        raise InvalidParameterError(f"{str(start)!r} exists and is not a registry the mission wrote: the models the "
                                    "mission starts with cannot be written there")
    return folder
