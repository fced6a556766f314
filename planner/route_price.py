"""The price of a route: :func:`price_route`, the one door, its interval and the forecast of its stop-turn-go profile.

A route on a priced map (:class:`~planner.EnergyCost`) has one price with two readings
(``how``): ``"edges"``, the sum of its segments' and turns' edge costs (what the searches
minimise), or ``"profile"``, the drive the robot actually makes — priced by the model that priced
the map. Either comes with the map's predictive interval when it has one
(:class:`RouteEnergyInterval`: a mean, a spread per ground, a tail), and with a
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

**The interval.** A cost priced by a model with a predictive interval (:class:`~planner.LearnedEnergyModel`
over a model whose ``gives_interval`` is True) carries, beside its mean tables, the
**run-level** standard deviation of every table entry (:class:`~planner.CostTables`). That spread is
the part of the model's error shared by a whole run on one ground (what the model does not know
about the ground, how one run differs from another), so along a route it does not average out:

- the route's **mean** energy is the sum of its edge means (:meth:`planner.EnergyCost.path_energy_j`);
- **within one ground** (one table row) the edge spreads add **linearly**: each segment walked
  cell by cell adds its horizontal length times its row's spread at the cell's grade in the
  direction of travel (linear interpolation, as the mean tables are read), each turn its row's
  turn spread (:meth:`planner.EnergyCost.path_spreads_j`);
- the per-ground sums, grounds being independent of each other, combine by the **root of the
  sum of squares** (:func:`energy.models.forecast.combine_ground_sds`).

**Shape.** Each row's spreads are the scale of the model's predictive on that ground
(:attr:`planner.CostTables.spread_dof`): a Gaussian (``dof = inf``) where the model knows the ground, a
**Student-t** with as many degrees of freedom as grounds taught the new-ground spread where it
never drove it (:mod:`energy.models.forecast`). The same predictive gives every interval the
planner reports: :class:`RouteEnergyInterval` (P50, P90, central intervals) takes the route's
energy as a Student-t with the **least** degrees of freedom of the grounds it crosses with a
spread (a Gaussian when all are known); the Monte Carlo missions draw each ground's factor from
its own predictive (:mod:`planner.missions.monte_carlo_model`); the navigator's forecast of what
remains uses the same quantile (:mod:`planner.missions.remaining`). What a risk level plans on
is :meth:`planner.CostTables.at_quantile` (:mod:`planner.tables` says why it bounds the route's quantile).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from energy import CommandProfile, drive_profile
from energy.models.forecast import check_dof, combine_ground_sds, predictive_quantile
from energy.profiles import DEFAULT_ACCEL_MPS2, DEFAULT_YAW_ACCEL_RADPS2, terrain_along
from terrawatt_base.checks import check_bool, check_choice, check_instance, check_real
from terrawatt_base.errors import InvalidParameterError

from .edge_cost import EnergyCost
from .points import as_points
from .route import Route
from .tables import check_risk_level

__all__ = ["PRICE_HOWS", "INTERVAL_LEVEL", "RouteEnergyInterval", "price_route", "profile_forecast_w",
           "segment_forecasts_j"]

#: How a route is priced: its edge costs, or the whole drive profile.
PRICE_HOWS = ("edges", "profile")

#: Time step (s) of the profile a forecast prices.
FORECAST_DT_S = 0.05

#: Central interval reported beside P50 / P90 (0.8: P10-P90).
INTERVAL_LEVEL = 0.8


@dataclass(frozen=True)
class RouteEnergyInterval:
    """The distribution of a route's battery energy under a model with an interval: a mean, a scale and a tail.

    Attributes
    ----------
    mean_j : float
        Mean energy (J): the sum of the edge means (turns included).
    sd_j : float
        Standard deviation (J): per ground the edge spreads summed linearly, the grounds
        combined by root-sum-of-squares.
    sd_by_ground_j : dict of str to float
        The linear per-ground sums (J), keyed by the cost's row labels (grounds the route
        does not cross are left out).
    dof : float
        Degrees of freedom of the Student-t the quantiles are read from (``inf``, the
        default: Gaussian): the least of the grounds the route crosses with a non-zero spread.
        A sum of independent Student-t's with other degrees of freedom has no closed form;
        the least is **conservative** (its tails are the heaviest of the parts'), exact on a
        route over one ground or over grounds that share one value.
    dof_by_ground : dict of str to float
        Each crossed ground's own degrees of freedom (keys of ``sd_by_ground_j``; a ground
        left out has ``dof``): what a Monte Carlo draw of the route draws per ground.

    Raises
    ------
    InvalidParameterError
        A negative or non-finite mean or spread, degrees of freedom not > 0.

    Examples
    --------
    >>> iv = RouteEnergyInterval(1000.0, 100.0, {"sand": 100.0})
    >>> round(iv.p90_j, 1), [round(x, 1) for x in iv.interval_j(0.8)]
    (1128.2, [871.8, 1128.2])
    >>> round(RouteEnergyInterval(1000.0, 100.0, {"sand": 100.0}, dof=3.0).p90_j, 1)  # a ground never driven
    1163.8
    """

    mean_j: float
    sd_j: float
    sd_by_ground_j: dict[str, float]
    dof: float = math.inf
    dof_by_ground: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("mean_j", "sd_j"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value >= 0):
                raise InvalidParameterError(f"RouteEnergyInterval.{name} must be a finite energy >= 0, got {value!r}")
            object.__setattr__(self, name, value)
        by = {str(k): float(v) for k, v in dict(self.sd_by_ground_j).items()}
        if any(not (math.isfinite(v) and v >= 0) for v in by.values()):
            raise InvalidParameterError(f"RouteEnergyInterval.sd_by_ground_j must hold finite spreads >= 0, got {by!r}")
        object.__setattr__(self, "sd_by_ground_j", by)
        object.__setattr__(self, "dof", check_dof(self.dof, "RouteEnergyInterval.dof"))
        dofs = {str(k): check_dof(v, "RouteEnergyInterval.dof_by_ground") for k, v in dict(self.dof_by_ground).items()}
        if set(dofs) - set(by):
            raise InvalidParameterError(f"RouteEnergyInterval.dof_by_ground names grounds without a spread: "
                                        f"{sorted(set(dofs) - set(by))!r}")
        object.__setattr__(self, "dof_by_ground", dofs)

    @classmethod
    def from_ground_spreads(cls, mean_j: float, sd_by_ground_j: Sequence[float], labels: Sequence[str],
                            dof_by_ground: Sequence[float]) -> RouteEnergyInterval:
        """A route's distribution from its linear spread sum on every ground (one per label, 0 where it does not go).

        The grounds with a spread are kept (with their degrees of freedom), the sd is their root-sum-of-squares and
        the tail the least degrees of freedom among them (a Gaussian when the route crosses no spread).

        Examples
        --------
        >>> iv = RouteEnergyInterval.from_ground_spreads(1000.0, [60.0, 0.0, 80.0], ["sand", "clay", "gravel"],
        ...                                              [float("inf"), 3.0, 5.0])
        >>> iv.sd_j, iv.sd_by_ground_j, iv.dof
        (100.0, {'sand': 60.0, 'gravel': 80.0}, 5.0)
        """
        crossed = [g for g, sd in enumerate(sd_by_ground_j) if sd > 0]
        dofs = {labels[g]: dof_by_ground[g] for g in crossed}
        return cls(mean_j, combine_ground_sds(sd_by_ground_j), {labels[g]: float(sd_by_ground_j[g]) for g in crossed},
                   min(dofs.values(), default=math.inf), dofs)

    def ground_dof(self, ground: str) -> float:
        """The degrees of freedom of ``ground``'s factor (its own, else the route's :attr:`dof`)."""
        return self.dof_by_ground.get(str(ground), self.dof)

    def quantile_j(self, q: float) -> float:
        """The ``q`` quantile of the route energy (J), ``q`` in (0, 1): ``mean + predictive_quantile(q, dof) * sd``,
        at least 0.

        The energy a route draws from the battery is never negative (every edge's mean is >= 0, and a
        risk level's tables floor each entry at 0: :meth:`~planner.tables.CostTables.at_quantile`), so the
        symmetric predictive is read censored at 0: a low quantile of a route whose spread is wide beside its
        mean is 0, not a negative energy; the upper quantiles a plan is priced at are the predictive's own.

        >>> RouteEnergyInterval(100.0, 100.0, {"sand": 100.0}).interval_j(0.8)
        (0.0, 228.15515655446004)
        """
        return max(self.mean_j + predictive_quantile(check_risk_level(q), self.dof) * self.sd_j, 0.0)

    @property
    def p50_j(self) -> float:
        """Median energy (J); the mean, the distribution (Gaussian or Student-t) being symmetric."""
        return self.mean_j

    @property
    def p90_j(self) -> float:
        """90th percentile of the energy (J)."""
        return self.quantile_j(0.9)

    def interval_j(self, level: float = INTERVAL_LEVEL) -> tuple[float, float]:
        """Central ``level`` interval of the energy (J), e.g. 0.8: (P10, P90)."""
        lv = check_risk_level(level, "level")
        return self.quantile_j(0.5 - lv / 2.0), self.quantile_j(0.5 + lv / 2.0)

    def to_dict(self) -> dict[str, Any]:
        """The block route.json holds under ``energy_interval`` (J and Wh, units in the keys)."""
        lo, hi = self.interval_j(INTERVAL_LEVEL)
        shape = "gaussian" if math.isinf(self.dof) else f"student-t with {self.dof:g} degrees of freedom"
        out = {
            "distribution": f"{shape}: per ground the run-level spreads add linearly, grounds independent",
            "mean_j": self.mean_j,
            "sd_j": self.sd_j,
            "p50_j": self.p50_j,
            "p90_j": self.p90_j,
            "central_level": INTERVAL_LEVEL,
            "central_interval_j": [lo, hi],
            "mean_wh": self.mean_j / 3600.0,
            "p50_wh": self.p50_j / 3600.0,
            "p90_wh": self.p90_j / 3600.0,
            "central_interval_wh": [lo / 3600.0, hi / 3600.0],
            "sd_by_ground_j": dict(self.sd_by_ground_j),
        }
        if not math.isinf(self.dof):  # a Gaussian's block stays as it was
            out["dof"] = self.dof
            out["dof_by_ground"] = {g: (d if math.isfinite(d) else None) for g, d in self.dof_by_ground.items()}
        return out


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
    >>> edges.sd_j, round(profile.mean_j / edges.mean_j, 2)  # the edges price the stops, starts and ramps too
    (0.0, 1.0)
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
        price = RouteEnergyInterval.from_ground_spreads(mean, per_row, cost.tables.ground_labels, cost.tables.spread_dof)
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
