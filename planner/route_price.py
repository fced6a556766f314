"""The price of a route: :func:`price_route`, the one door, and the forecast of its whole stop-turn-go profile.

A route on a priced map (:class:`~planner.EnergyCost`) has one price with two readings
(``how``): ``"edges"``, the sum of its segments' and turns' edge costs (what the searches
minimise), or ``"profile"``, the drive the robot actually makes — priced by the model that priced
the map. Either comes with the map's predictive interval when it has one
(:class:`~planner.risk.RouteEnergyInterval`: a mean, a spread per ground, a tail), and with a
spread of 0 otherwise, so every caller (the plan, the Monte Carlo study, the navigator, the
tours) reads a route's energy from one object.

Edge costs price steady driving at the planning speed plus turns in place; a driven route
also starts and stops at every waypoint, pivots with a trapezoidal yaw rate and spends the
extra seconds of those ramps with its electronics on. :func:`profile_forecast_w` prices that
profile with the very physics model (robot, effects, ground parameters) that priced the
cost's tables, on the map's ground and slope under every pose (the rule of
:func:`energy.profiles.terrain_along`, which the truth simulator uses too), and
:func:`segment_forecasts_j` splits it into the turn and the straight of each route segment,
the way :func:`planner.simulate_mission` books them.

The interval is read from the priced map's own tables (:class:`~planner.CostTables`): each
segment walked cell by cell adds its horizontal length times its row's spread at the cell's
grade in the direction of travel (linear interpolation, as the mean tables are read), each turn
its row's turn spread; per ground the spreads add linearly, the grounds combine by
root-sum-of-squares, and the tail is the Student-t of the least degrees of freedom crossed
(:mod:`planner.risk` says why).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from energy import CommandProfile, drive_profile
from energy.models.forecast import combine_ground_sds
from energy.profiles import DEFAULT_ACCEL_MPS2, DEFAULT_YAW_ACCEL_RADPS2, terrain_along
from terrawatt_base.checks import check_bool, check_choice, check_instance, check_real
from terrawatt_base.errors import InvalidParameterError

from .edge_cost import EnergyCost
from .points import as_points
from .risk import RouteEnergyInterval
from .route import Route

__all__ = ["PRICE_HOWS", "price_route", "profile_forecast_w", "segment_forecasts_j"]

#: How a route is priced: its edge costs, or the whole drive profile.
PRICE_HOWS = ("edges", "profile")

#: Time step (s) of the profile a forecast prices.
FORECAST_DT_S = 0.05


def profile_forecast_w(cost: EnergyCost, profile: CommandProfile) -> np.ndarray:
    """Battery power (W) at every sample of a command profile, by the physics model that priced ``cost``.

    Parameters
    ----------
    cost : EnergyCost
        Built by :meth:`planner.CostSpec.build` on the robot's :class:`energy.PhysicsEnergyModel`.
    profile : CommandProfile
        Commands with poses on ``cost``'s map (e.g. :func:`energy.drive_profile`).

    Returns
    -------
    numpy.ndarray, shape (N,)

    Raises
    ------
    InvalidParameterError
        A cost without a physics model, a profile without poses.
    OutOfBoundsError
        A pose off the map.
    """
    if not isinstance(cost, EnergyCost) or cost.physics_model is None or cost.ground_params is None:
        raise InvalidParameterError("cost carries no physics model (build it with CostSpec.build on the robot's "
                                    "physics model) to forecast a profile with")
    if not isinstance(profile, CommandProfile) or profile.pose_xyh is None:
        raise InvalidParameterError("profile must be a CommandProfile with poses (pose_xyh)")
    t = np.asarray(profile.time_s, dtype=np.float64)
    v = np.asarray(profile.v_mps, dtype=np.float64)
    w = np.asarray(profile.omega_radps, dtype=np.float64)
    pose = np.asarray(profile.pose_xyh, dtype=np.float64)
    rows, cols, slope, _ = terrain_along(cost.terrain, pose[:, 0], pose[:, 1], pose[:, 2])
    ground_index = np.asarray(cost.ground_rows)[rows, cols]
    res = cost.physics_model.power(v, w, list(cost.ground_params), accel_mps2=np.gradient(v, t),
                                   alpha_radps2=np.gradient(w, t), slope_rad=slope, time_s=t,
                                   ground_index=ground_index)
    return np.asarray(res.total_power_w, dtype=np.float64)


def segment_forecasts_j(time_s: np.ndarray, power_w: np.ndarray, turn_s: np.ndarray,
                        straight_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The energy (J) of the turn and of the straight of each drivable segment of a profile.

    ``turn_s`` / ``straight_s`` are the planned durations
    (:func:`energy.profiles.planned_durations_s`) in the order the profile drives them;
    the power is integrated (trapezoid) between those time marks.

    Examples
    --------
    >>> t = np.linspace(0.0, 3.0, 31)
    >>> turn, straight = segment_forecasts_j(t, np.full(31, 2.0), np.array([1.0]), np.array([2.0]))
    >>> [round(float(turn[0]), 9), round(float(straight[0]), 9)]
    [2.0, 4.0]
    """
    t = np.asarray(time_s, dtype=np.float64) - float(time_s[0])
    p = np.asarray(power_w, dtype=np.float64)
    cumulative = np.concatenate(([0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(t))))
    marks = np.concatenate(([0.0], np.cumsum(np.column_stack([turn_s, straight_s]).ravel())))
    parts = np.diff(np.interp(marks, t, cumulative))
    return parts[0::2], parts[1::2]


def _waypoints(route: Route | Any) -> np.ndarray:
    if isinstance(route, Route):
        if not route.found:
            raise InvalidParameterError(f"route must be a found Route, got one with status {route.status!r}")
        return route.waypoints_m
    return as_points(route, "route")


def price_route(cost: EnergyCost, route: Route | Any, *, how: str = "edges", interval: bool | None = None,
                speed_mps: float | None = None, segment_cache: dict | None = None) -> RouteEnergyInterval:
    """The battery energy of driving ``route`` on ``cost``'s map: a mean, and its interval where the map has one.

    The one door to a route's price. ``how="edges"`` sums the edge costs of its segments and
    turns (what the planner minimised: :meth:`EnergyCost.path_energy_j`); ``how="profile"``
    prices the stop-turn-go drive the robot makes (start and stop at every waypoint, pivots
    with ramped yaw rates) with the model that priced the map: the physics model of
    :meth:`planner.CostSpec.build` with the physics model (:func:`energy.drive_profile` at the speed and
    the cost's turn rate, priced by :func:`profile_forecast_w` and integrated), or the learned
    model of :meth:`planner.LearnedEnergyModel.energy_cost`
    (:meth:`~planner.LearnedEnergyModel.predict_route_energy_j`). The spread is the edges'
    run-level spread per ground read from the map's tables (module docstring) either way: the
    profile moves the mean, not how much a ground's runs differ.

    Parameters
    ----------
    cost : EnergyCost
        The priced map.
    route : Route or array_like, shape (K, 2)
        A found route, or its waypoints (m).
    how : str
        ``"edges"`` or ``"profile"`` (:data:`PRICE_HOWS`).
    interval : bool, optional
        With the map's predictive interval (needs spread tables); ``False``: a spread of 0.
        Default: when the map has one (:attr:`EnergyCost.has_interval`).
    speed_mps : float, optional
        ``how="profile"``: the driving speed (default the cost's planning speed).
    segment_cache : dict, optional
        Per-segment spreads already walked, keyed by ``(x0, y0, x1, y1)``, filled as segments
        are walked: many routes of one cost that share segments (e.g. the legs of one
        shortest-path tree, :mod:`planner.tours.pricing`) walk each segment once. Only for one cost.

    Returns
    -------
    RouteEnergyInterval
        ``mean_j`` the price; ``sd_j`` 0 without an interval.

    Raises
    ------
    InvalidParameterError
        A route the map cannot drive (it crosses a blocked cell), fewer than 2 waypoints, a route
        that was not found; ``interval=True`` on a map without spreads; ``how="profile"`` on a
        map priced by neither a physics nor a learned model (e.g. tables given directly).
    OutOfBoundsError
        A waypoint off the map.

    Examples
    --------
    >>> from terrain import flat_map
    >>> from planner import CostSpec
    >>> cost = CostSpec().build(flat_map((10, 30), 1.0))
    >>> edges = price_route(cost, [[0.5, 0.5], [20.5, 0.5], [20.5, 8.5]])
    >>> profile = price_route(cost, [[0.5, 0.5], [20.5, 0.5], [20.5, 8.5]], how="profile")
    >>> edges.sd_j, bool(profile.mean_j > edges.mean_j)  # starts, stops and ramps cost more than steady driving
    (0.0, True)
    """
    cost = check_instance("cost", cost, EnergyCost)
    how = check_choice("how", how, PRICE_HOWS)
    pts = _waypoints(route)
    if pts.shape[0] < 2:
        raise InvalidParameterError(f"route needs at least 2 waypoints, got {pts.shape[0]}")
    with_interval = cost.has_interval if interval is None else check_bool("interval", interval)
    mean = cost.path_energy_j(pts)
    if not math.isfinite(mean):
        raise InvalidParameterError("the route crosses a blocked cell or an undrivable grade: it has no price")
    per_row = cost.path_spreads_j(pts, segment_cache=segment_cache) if with_interval else None
    if per_row is not None:
        tables = cost.tables
        spread = np.flatnonzero(per_row > 0).tolist()
        crossed = {tables.ground_labels[i]: float(per_row[i]) for i in spread}
        dofs = {tables.ground_labels[i]: tables.spread_dof[i] for i in spread}
        price = RouteEnergyInterval(mean, combine_ground_sds(per_row), crossed, min(dofs.values(), default=math.inf),
                                    dofs)
    else:
        price = RouteEnergyInterval(mean, 0.0, {})
    if how == "profile":
        speed = cost.speed_mps if speed_mps is None else check_real("speed_mps", speed_mps, low=0.0,
                                                                    low_inclusive=False)
        if cost.learned_model is not None:
            mean = cost.learned_model.predict_route_energy_j(cost.terrain, pts, speed)
        else:  # the profile of planner.simulate_mission, priced by the physics model of the tables
            profile = drive_profile(pts, speed, turn_rate_radps=cost.turn_rate_radps, dt_s=FORECAST_DT_S,
                                    accel_mps2=DEFAULT_ACCEL_MPS2, yaw_accel_radps2=DEFAULT_YAW_ACCEL_RADPS2)
            power = profile_forecast_w(cost, profile)
            t = np.asarray(profile.time_s, dtype=np.float64)
            mean = float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(t)))
        price = dataclasses.replace(price, mean_j=mean)
    return price
