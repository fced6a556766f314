"""An adaptive mission in simulation against a battery, set up from names and reported (MissionReport)."""

from __future__ import annotations

import math
import os
import re
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from energy import GROUND_PRESETS, Battery, RobotParams, TruthSimulator, ground_preset, load_current_model
from energy.io import write_csv_log, write_drive_bag
from energy.params import robot_params
from terrain import TerrainMap
from terrawatt_base.atomic import check_output_path
from terrawatt_base.checks import check_bool, check_instance, check_real
from terrawatt_base.errors import InvalidParameterError, UnknownNameError
from terrawatt_base.figure_file import draw_figure
from terrawatt_base.formats import write_result_json

from ..cost_spec import CostSpec
from ..model_cost import model_energy_model
from ..registry import CellModelRegistry
from .adaptive import run_adaptive_mission
from .adaptive_results import AdaptiveResult
from .manoeuvres import fit_prior_model
from .settings import AdaptiveSettings

__all__ = ["MissionReport", "simulate_adaptive_mission", "mission_battery", "check_preset_grounds", "check_logs_folder",
           "LOGS_FOLDER", "START_REGISTRY"]


def check_preset_grounds(terrain: TerrainMap) -> None:
    """Every ground of the map a preset (the truth simulator drives presets), or an error naming those that are not.

    Raises
    ------
    UnknownNameError
        A ground of the map has no preset.
    """
    unknown = sorted(n for n in set(terrain.ground_names.values()) if n not in GROUND_PRESETS)
    if unknown:
        raise UnknownNameError(f"the map's grounds {unknown!r} have no preset; known grounds: {sorted(GROUND_PRESETS)!r}")


def mission_battery(robot: str | os.PathLike[str] | RobotParams, capacity_ah: float, voltage_v: float | None = None,
                    reserve_pct: float = 20.0) -> Battery:
    """The :class:`energy.Battery` of a mission: ``voltage_v`` defaults to the robot preset's battery voltage."""
    voltage = robot_params(robot).battery_voltage_v if voltage_v is None else voltage_v
    return Battery(capacity_ah=capacity_ah, voltage_v=voltage, min_reserve_pct=reserve_pct)


def _percent(value: float) -> str:
    return "n/a" if math.isnan(value) else f"{value:.1f} %"  # NaN: nothing to compare


@dataclass(frozen=True)
class MissionReport:
    """An adaptive mission (:class:`AdaptiveResult`) with its battery and setting, ready to print and write.

    Made by :func:`simulate_adaptive_mission`. :meth:`summary` is the text ``terrawatt mission``
    prints, :meth:`to_dict` the content of mission.json, :meth:`write` writes mission.json and
    mission.png.

    Attributes
    ----------
    result : AdaptiveResult
        The mission: status, legs, updates, the budget.
    battery : Battery
        The battery driven against.
    map_label, robot, prior_ground : str
        How the map is named; the robot preset; the ground the prior model was trained on.
    adapt : bool
        Whether the models were updated on the way.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    computing_time_s : float
        Seconds the loop took.
    terrain : TerrainMap
        The map.
    registry : CellModelRegistry
        The per-cell models after the mission.
    start_registry : CellModelRegistry or None
        A copy of the per-cell models as the mission started: what a replay of its logs
        starts from (written as ``start_registry/`` beside the logs).
    """

    result: AdaptiveResult
    battery: Battery
    map_label: str
    robot: str
    prior_ground: str
    adapt: bool
    start_xy_m: tuple[float, float]
    goal_xy_m: tuple[float, float]
    computing_time_s: float
    terrain: TerrainMap = field(default=None, repr=False, compare=False)  # type: ignore[assignment]
    registry: CellModelRegistry = field(default=None, repr=False, compare=False)  # type: ignore[assignment]
    start_registry: CellModelRegistry | None = field(default=None, repr=False, compare=False)

    @property
    def completed(self) -> bool:
        """Whether the robot reached the goal."""
        return self.result.status == "completed"

    def summary(self) -> str:
        """What ``terrawatt mission`` prints: battery, status, plan against drive, errors, updates, final charge."""
        result, battery = self.result, self.battery
        budget, route0 = result.budget, result.initial_route
        lines = [
            f"map: {self.map_label}; robot {self.robot}; battery {battery.capacity_ah:g} Ah at {battery.voltage_v:g} V "
            f"({battery.energy_capacity_wh:.0f} Wh, {battery.usable_energy_wh:.0f} Wh above the "
            f"{battery.min_reserve_pct:g} % reserve)",
            f"start {self.start_xy_m} -> goal {self.goal_xy_m}; prior trained on {self.prior_ground}; "
            f"adaptive updates {'on' if self.adapt else 'off'}",
            f"status: {result.status} — {result.reason}",
            f"first plan (prior models):  {budget.predicted_energy_wh:8.2f} Wh  {route0.length_m:7.1f} m  "
            f"({'fits' if budget.predicted_feasible else 'does NOT fit'} the usable {battery.usable_energy_wh:.0f} Wh)",
            f"driven (actual):            {result.driven_energy_j / 3600:8.2f} Wh  in {len(result.legs)} legs",
            f"excitation manoeuvres:      {result.excitation_energy_j / 3600:8.2f} Wh",
            f"prediction error before / after updates: {_percent(result.error_before_update_pct)} / "
            f"{_percent(result.error_after_update_pct)}",
            f"updates accepted: {result.accepted_updates} of {len(result.updates)}; route changes {result.route_changes}",
        ]
        lines += [f"skipped update {line}" for line in result.skipped_updates]
        if budget.depleted:
            lines.append(f"the battery ran out {budget.depleted_time_s:.1f} s into the mission")
        lines.append(f"final state of charge {budget.arrival_soc_pct:.1f} % (margin {budget.reserve_margin_pct:+.1f} "
                     f"points above the reserve); loop computing {self.computing_time_s:.1f} s")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """The content of mission.json: :meth:`AdaptiveResult.to_json_dict` and ``computing_time_s``."""
        return {**self.result.to_json_dict(), "computing_time_s": self.computing_time_s}

    def write(self, out_dir: str | os.PathLike[str], *, logs: bool = False, on_figure_error: str = "warn"
              ) -> list[Path]:
        """Write mission.json and mission.png into ``out_dir``; return the files written (a figure that fails
        warns and is left out, :func:`terrawatt_base.figure_file.draw_figure`).

        With ``logs``, also each leg's log (:attr:`AdaptiveResult.leg_logs`) as a CSV log
        ``logs/leg_NNN.csv`` (:func:`energy.io.write_csv_log`) and each manoeuvre run
        (:attr:`AdaptiveResult.manoeuvre_logs`) as ``logs/manoeuvre_NNN_K.csv`` (run K after leg
        NNN), all on the robot's clock: a folder that ``terrawatt diagnose --data``,
        ``terrawatt replay --data`` and :func:`energy.io.read_logs` read; and the models the
        mission started with as ``start_registry/`` (:attr:`start_registry`, what ``terrawatt
        replay --registry`` starts from): the previous mission's leg files there are
        replaced, and a folder holding anything else is refused before anything is written
        (:func:`check_logs_folder`).
        """
        out = Path(out_dir)
        if logs:
            check_logs_folder(out)
        out.mkdir(parents=True, exist_ok=True)
        written = [write_result_json(out / "mission.json", self.to_dict())]
        png = draw_figure(out / "mission.png", lambda: self.result.plot(out / "mission.png", self.terrain,
                                                                          self.registry), on_error=on_figure_error)
        written += [png] if png is not None else []
        if logs:
            folder = out / LOGS_FOLDER
            folder.mkdir(exist_ok=True)
            new = [folder / f"leg_{k:03d}.csv" for k in range(len(self.result.leg_logs))]
            for path, log in zip(new, self.result.leg_logs):
                written.append(write_csv_log(log, path))
            runs: dict[int, int] = {}
            for after, log in self.result.manoeuvre_logs:
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
        legs = self.result.leg_logs
        if not legs:
            raise InvalidParameterError("the mission drove no leg: there is no drive to write")
        lonlat = None
        if self.terrain is not None and self.terrain.crs is not None:
            lonlat = [np.column_stack(self.terrain.xy_to_lonlat(log.pose_xyh[:, 0], log.pose_xyh[:, 1]))
                      for log in legs]
        return write_drive_bag(list(legs), path, lonlat_deg=lonlat)


#: The folder of :meth:`MissionReport.write` (``logs=True``) that holds the legs' logs.
LOGS_FOLDER = "logs"
#: The folder of :meth:`MissionReport.write` (``logs=True``) that holds the models the mission started with.
START_REGISTRY = "start_registry"


def _leg_files(folder: Path) -> list[Path]:
    """The files an earlier mission wrote there: exactly the names :meth:`MissionReport.write` gives
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


def simulate_adaptive_mission(
    terrain: TerrainMap,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    *,
    battery: Battery,
    pricing: CostSpec | None = None,
    prior_ground: str = "asphalt",
    leg_m: float = 10.0,
    adapt: bool = True,
    seed: int = 0,
    map_label: str = "map",
) -> MissionReport:
    """Drive from start to goal in the truth simulator against a battery, learning current models on the way.

    The truth simulator (seeded) drives the map's grounds, which must be presets. Without
    ``model``, the robot starts with a prior linear model fitted on ``prior_ground``
    (:func:`planner.missions.fit_prior_model`) in every cell; with ``model`` (a saved current
    model), that model serves each ground class it drove (:func:`planner.model_cost.model_energy_model`).
    Then :func:`planner.missions.run_adaptive_mission` plans, drives ``leg_m`` legs, compares,
    updates (unless not ``adapt``) and replans.

    Parameters
    ----------
    terrain : TerrainMap
        The map; its grounds are presets.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    battery : Battery
        The battery driven against (e.g. :func:`mission_battery`: a capacity at the robot's voltage).
    pricing : CostSpec, optional
        The robot, its driving speed and, with a saved current model, the model serving the map's
        grounds instead of the prior (:class:`planner.cost_spec.CostSpec`; default ``CostSpec()``).
        The mission prices its edges by the per-cell models it learns, so the spec's slope limit,
        unknown ground and risk do not apply.
    leg_m, seed
        Route driven between comparisons (m), seed of the simulator.
    prior_ground : str
        Ground preset of the prior model, and the physics ground of the edge costs.
    adapt : bool
        Update the models on the way (False: drive the first plan).
    map_label : str
        How the map is named.

    Returns
    -------
    MissionReport

    Raises
    ------
    UnknownNameError
        A ground of the map, or ``prior_ground``, without a preset.
    InvalidParameterError
        A bad number; not a Battery.
    """
    check_preset_grounds(terrain)
    battery = check_instance("battery", battery, Battery)
    if prior_ground not in GROUND_PRESETS:
        raise UnknownNameError(f"prior_ground {prior_ground!r} has no preset; known grounds: {sorted(GROUND_PRESETS)!r}")
    check_real("leg_m", leg_m, low=0.0, low_inclusive=False)
    adapt = check_bool("adapt", adapt)
    pricing = CostSpec() if pricing is None else check_instance("pricing", pricing, CostSpec)
    robot_given, model = pricing.params, pricing.model
    grounds = {name: ground_preset(name) for name in sorted(set(terrain.ground_names.values()) | {prior_ground})}
    truth = TruthSimulator(robot_given, grounds, seed=seed)
    settings = AdaptiveSettings(speed_mps=pricing.speed_mps, leg_length_m=leg_m,
                                max_updates=AdaptiveSettings().max_updates if adapt else 0, seed=seed)
    learned = None
    if model is not None:  # the saved model serves every ground class it drove (one model id each)
        learned, _ = model_energy_model(terrain, model, robot_given, model_ground=pricing.model_ground,
                                        physics_ground=grounds[prior_ground])
        registry = learned.registry
    else:
        prior = fit_prior_model(truth, prior_ground, seed=seed)
        registry = CellModelRegistry.from_terrain(terrain, prior, prior_name=f"{prior_ground}-prior")
    start_registry = _snapshot(registry)
    t0 = time.perf_counter()
    result = run_adaptive_mission(terrain, registry, robot_given, battery, truth, start_xy_m, goal_xy_m,
                                  physics_ground=grounds[prior_ground], settings=settings, learned=learned)
    return MissionReport(result=result, battery=battery, map_label=map_label, robot=pricing.robot,
                         prior_ground=prior_ground,
                         adapt=adapt, start_xy_m=(float(start_xy_m[0]), float(start_xy_m[1])),
                         goal_xy_m=(float(goal_xy_m[0]), float(goal_xy_m[1])),
                         computing_time_s=time.perf_counter() - t0, terrain=terrain, registry=registry,
                         start_registry=start_registry)


def _snapshot(registry: CellModelRegistry) -> CellModelRegistry:
    """An independent copy of the registry as it is now (through its own files: what a replay starts from)."""
    with tempfile.TemporaryDirectory(prefix="terrawatt-registry-") as tmp:
        registry.save(Path(tmp) / "registry", lambda model, p: model.save(p))
        return CellModelRegistry.load(Path(tmp) / "registry", load_current_model)
