"""A Monte Carlo study of a mission set up from names: plan the lattice route, drive it N times (a MonteCarloResult with
the route and its header)."""

from __future__ import annotations

import dataclasses

from energy import Battery
from terrain import TerrainMap
from terrawatt_base.checks import check_instance, check_real
from terrawatt_base.dask_client import Compute

from ..cost_spec import CostSpec
from ..planning import plan_route
from .mission_report import check_preset_grounds
from .monte_carlo import simulate_missions_mc
from .monte_carlo_result import MonteCarloResult

__all__ = ["monte_carlo_mission"]


def monte_carlo_mission(
    terrain: TerrainMap,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    n: int,
    *,
    battery: Battery,
    pricing: CostSpec | None = None,
    seed: int | None = 0,
    draw_from: str = "parameters",
    max_risk_pct: float = 5.0,
    compute: Compute | None = None,
    map_label: str = "map",
) -> MonteCarloResult:
    """Plan the lattice route and drive it ``n`` times with drawn parameters (:func:`simulate_missions_mc`).

    The edges are priced as ``pricing`` says (:meth:`planner.cost_spec.CostSpec.build`, at the
    mean); the route is the lattice planner's; the missions draw
    ground coefficients, payload, capacity fade, internal resistance and speed (or, with
    ``draw_from="model"``, the model's predictive distribution).

    Parameters
    ----------
    terrain : TerrainMap
        The map; its grounds are presets.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    n : int
        Missions.
    battery : Battery
        The nominal battery (e.g. :func:`planner.missions.mission_report.mission_battery`).
    pricing : CostSpec, optional
        How the edges are priced and the missions driven (:class:`planner.cost_spec.CostSpec`: the
        robot, its speed, the presets or a saved current model; default ``CostSpec()``); its
        ``risk``, when given, is the quantile of the route energy forecast checked against the
        usable battery (needs a model with an interval).
    seed : int or None
        Seed of the draws and of the route's refinement.
    draw_from : str
        ``"parameters"`` or ``"model"`` (needs a model with an interval).
    max_risk_pct : float
        Most missions (%) below the reserve for :attr:`MonteCarloResult.ok`.
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
    max_risk_pct = check_real("max_risk_pct", max_risk_pct, low=0.0, high=100.0)
    pricing = CostSpec() if pricing is None else check_instance("pricing", pricing, CostSpec)
    battery = check_instance("battery", battery, Battery)
    cost = pricing.build(terrain)
    if pricing.risk is not None or draw_from == "model":
        pricing.needs_interval(cost, also="draw_from")
    route = plan_route(terrain, start_xy_m, goal_xy_m, cost=cost, planner="lattice", seed=seed)
    header = dict(route=route, map_label=map_label, robot=pricing.robot,
                  start_xy_m=(float(start_xy_m[0]), float(start_xy_m[1])),
                  goal_xy_m=(float(goal_xy_m[0]), float(goal_xy_m[1])), risk_q=pricing.risk, max_risk_pct=max_risk_pct)
    if not route.found:
        return MonteCarloResult.no_route(battery=battery, **header)
    result = simulate_missions_mc(terrain, route, battery, n, robot=pricing.params, speed_mps=pricing.speed_mps,
                                  seed=seed, compute=compute, cost=cost, draw_from=draw_from)
    return dataclasses.replace(result, **header)
