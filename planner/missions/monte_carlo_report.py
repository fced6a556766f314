"""A Monte Carlo study of a mission set up from names: plan the lattice route, drive it N times (a MonteCarloResult with
the route and its header)."""

from __future__ import annotations

import dataclasses

from energy import Battery
from terrain import TerrainMap
from terrawatt_base.checks import check_instance
from terrawatt_base.dask_client import Compute

from ..cost_spec import CostSpec
from ..planning import plan_route
from .mission_report import check_preset_grounds
from .monte_carlo import simulate_missions_mc
from .monte_carlo_result import MonteCarloResult
from .options import MissionTruth, MonteCarloStudy

__all__ = ["monte_carlo_mission"]


def monte_carlo_mission(
    terrain: TerrainMap,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    study: MonteCarloStudy,
    *,
    battery: Battery,
    pricing: CostSpec | None = None,
    compute: Compute | None = None,
    map_label: str = "map",
) -> MonteCarloResult:
    """Plan the lattice route and drive it ``study.n`` times with drawn parameters (:func:`simulate_missions_mc`).

    The edges are priced as ``pricing`` says (:meth:`planner.cost_spec.CostSpec.build`, at the
    mean); the route is the lattice planner's; the missions draw
    ground coefficients, payload, capacity fade, internal resistance and speed (or, with
    ``study.draw_from="model"``, the model's predictive distribution).

    Parameters
    ----------
    terrain : TerrainMap
        The map; its grounds are presets.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    study : MonteCarloStudy
        The missions: their number, what they draw (``"model"`` needs a model with an
        interval), the seed of the draws and of the route's refinement, and the most missions
        (%) below the reserve for :attr:`MonteCarloResult.ok`
        (:class:`planner.missions.options.MonteCarloStudy`).
    battery : Battery
        The nominal battery (e.g. :func:`planner.missions.mission_report.mission_battery`).
    pricing : CostSpec, optional
        How the edges are priced and the missions driven (:class:`planner.cost_spec.CostSpec`: the
        robot, its speed, the presets or a saved current model; default ``CostSpec()``); its
        ``risk``, when given, is the quantile of the route energy forecast checked against the
        usable battery (needs a model with an interval).
    compute : Compute, optional
        Where the missions run and whether a bar shows (:class:`terrawatt_base.dask_client.Compute`).
    map_label : str
        How the map is named.

    Returns
    -------
    MonteCarloResult
        With the route and the header; no mission (``n == 0``) when start and goal are not joined.

    Raises
    ------
    InvalidParameterError
        A bad number; ``risk`` or ``draw_from="model"`` with a cost that has no interval.
    UnknownNameError
        A ground of the map without a preset.
    """
    check_preset_grounds(terrain)
    study = check_instance("study", study, MonteCarloStudy)
    pricing = CostSpec.given(pricing)
    battery = check_instance("battery", battery, Battery)
    cost = pricing.build(terrain)
    if pricing.risk is not None or study.draw_from == "model":
        pricing.needs_interval(cost, also="draw_from")
    route = plan_route(terrain, start_xy_m, goal_xy_m, cost=cost, planner="lattice", seed=study.seed)
    header = dict(route=route, map_label=map_label, robot=pricing.robot,
                  start_xy_m=(float(start_xy_m[0]), float(start_xy_m[1])),
                  goal_xy_m=(float(goal_xy_m[0]), float(goal_xy_m[1])), risk_q=pricing.risk, max_risk_pct=study.max_risk_pct)
    if not route.found:
        return MonteCarloResult.no_route(battery=battery, **header)
    result = simulate_missions_mc(terrain, route, battery, study, cost=cost, compute=compute,
                                  truth=MissionTruth(robot=pricing.params, speed_mps=pricing.speed_mps))
    return dataclasses.replace(result, **header)
