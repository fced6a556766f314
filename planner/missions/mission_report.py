"""An adaptive mission in simulation against a battery, set up from names (an AdaptiveResult with its header)."""

from __future__ import annotations

import dataclasses
import os
import tempfile
import time
from pathlib import Path

from energy import GROUND_PRESETS, Battery, RobotParams, TruthSimulator, ground_preset, load_current_model
from energy.params import robot_params
from terrain import TerrainMap
from terrawatt_base.checks import check_instance
from terrawatt_base.errors import UnknownNameError

from ..cost_spec import CostSpec
from ..model_cost import model_energy_model
from ..registry import CellModelRegistry
from .adaptive import run_adaptive_mission
from .adaptive_results import AdaptiveResult
from .manoeuvres import fit_prior_model
from .navigator import Navigator
from .settings import AdaptiveSettings, NavigatorModels

__all__ = ["simulate_adaptive_mission", "mission_battery", "check_preset_grounds"]


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


def simulate_adaptive_mission(
    terrain: TerrainMap,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    *,
    battery: Battery,
    pricing: CostSpec | None = None,
    settings: AdaptiveSettings | None = None,
    prior_ground: str = "asphalt",
    map_label: str = "map",
) -> AdaptiveResult:
    """Drive from start to goal in the truth simulator against a battery, learning current models on the way.

    The truth simulator (seeded) drives the map's grounds, which must be presets. Without
    ``model``, the robot starts with a prior linear model fitted on ``prior_ground``
    (:func:`planner.missions.fit_prior_model`) in every cell; with ``model`` (a saved current
    model), that model serves each ground class it drove (:func:`planner.model_cost.model_energy_model`).
    Then :func:`planner.missions.run_adaptive_mission` plans, drives ``settings.leg_length_m``
    legs, compares, updates (unless ``settings.max_updates`` is 0) and replans.

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
    settings : AdaptiveSettings, optional
        The navigator's settings (legs, updates allowed, seed of the simulator and of the prior, ...;
        default ``AdaptiveSettings()``); its speed is the spec's. ``max_updates=0`` drives the first
        plan (the result says ``adapt=False``).
    prior_ground : str
        Ground preset of the prior model, and the physics ground of the edge costs.
    map_label : str
        How the map is named.

    Returns
    -------
    AdaptiveResult
        With its header (battery, map label, robot, prior, start and goal, computing time) and the
        models at the end and at the start.

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
    pricing = CostSpec.given(pricing)
    settings = AdaptiveSettings() if settings is None else check_instance("settings", settings, AdaptiveSettings)
    settings = dataclasses.replace(settings, speed_mps=pricing.speed_mps)
    seed, adapt = settings.seed, settings.max_updates > 0
    robot_given, model = pricing.params, pricing.model
    grounds = {name: ground_preset(name) for name in sorted(set(terrain.ground_names.values()) | {prior_ground})}
    truth = TruthSimulator(robot_given, grounds, seed=seed)
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
    nav = Navigator(terrain, registry, robot_given, battery, goal_xy_m, settings=settings,
                    models=NavigatorModels(physics_ground=grounds[prior_ground], learned=learned))
    result = run_adaptive_mission(nav, truth, start_xy_m)
    return dataclasses.replace(result, battery=battery, map_label=map_label, robot=pricing.robot,
                               prior_ground=prior_ground, adapt=adapt,
                               start_xy_m=(float(start_xy_m[0]), float(start_xy_m[1])),
                               goal_xy_m=(float(goal_xy_m[0]), float(goal_xy_m[1])),
                               computing_time_s=time.perf_counter() - t0, terrain=terrain, registry=registry,
                               start_registry=start_registry)


def _snapshot(registry: CellModelRegistry) -> CellModelRegistry:
    """An independent copy of the registry as it is now (through its own files: what a replay starts from)."""
    with tempfile.TemporaryDirectory(prefix="terrawatt-registry-") as tmp:
        registry.save(Path(tmp) / "registry", lambda model, p: model.save(p))
        return CellModelRegistry.load(Path(tmp) / "registry", load_current_model)
