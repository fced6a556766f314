"""plan_tour: which sites each robot visits on one charge (or several, at charging points), in what order, so that it
comes back above its reserve at Q."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrawatt_base.checks import check_instance
from terrawatt_base.dask_client import Compute
from terrawatt_base.errors import BlockedPositionError, InvalidParameterError

from ..cost_spec import CostSpec
from ..edge_cost import EnergyCost
from ..route_price import RouteEnergyInterval
from .improve import ImproveOutcome, improve_tours
from .options import TourFleet, TourSearch
from .pricing import PairPrices, price_pairs
from .result import RobotTour, TourLeg, TourResult
from .sites import TourChargers, TourRobot, TourSites
from .solver import HORIZON_S, TourPoints, TourProblem, solve_tours, walk_timeline

__all__ = ["plan_tour", "plan_tour_on_map", "TOO_FAR", "NOT_WORTH_IT", "NO_ROUTE", "OUTSIDE_WINDOW", "TOO_LONG",
           "REASONS"]

#: Why a site is left out: no robot can go there and back above its reserve at Q.
TOO_FAR = "too far at Q: no robot reaches it and comes back above its reserve at the risk level"
#: Why a site is left out: reachable alone, but the charge is spent on sites of more value.
NOT_WORTH_IT = "not worth it: reachable alone, but the charge at Q goes to sites of more value (capacity)"
#: Why a site is left out: no route joins it to a depot.
NO_ROUTE = "no route: obstacles or slopes separate it from every depot"
#: Why a site is left out: every robot that could reach it on its charge arrives after its window closes.
OUTSIDE_WINDOW = ("outside its time window: no robot that reaches it at Q can get there (straight from its depot) "
                  "before the window closes")
#: Why a site is left out: every robot that could reach it in time is back after its ``max_duration_s``.
TOO_LONG = "too long: no robot that reaches it at Q and in time is back within its max_duration_s"
#: Every reason a site is left out, in the order they are tested.
REASONS = (NO_ROUTE, TOO_FAR, OUTSIDE_WINDOW, TOO_LONG, NOT_WORTH_IT)


def _robots(robots: Any) -> tuple[TourRobot, ...]:
    out = (robots,) if isinstance(robots, TourRobot) else tuple(robots) if isinstance(robots, Sequence) else None
    if not out or not all(isinstance(r, TourRobot) for r in out):
        raise InvalidParameterError(f"robots must be a TourRobot or a non-empty sequence of them, got {robots!r:.120}")
    names = [r.name for r in out]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise InvalidParameterError(f"robot names must be unique; {dup!r} appears {names.count(dup)} times")
    return out


def plan_tour(
    cost: EnergyCost,
    sites: TourSites,
    robots: TourRobot | Sequence[TourRobot],
    *,
    search: TourSearch | None = None,
    compute: Compute | None = None,
    map_label: str = "map",
    prices: PairPrices | None = None,
    chargers: TourChargers | None = None,
) -> TourResult:
    """Choose and order the sites each robot visits to maximise the value collected, every tour at risk level
    ``search.risk`` coming back above its reserve.

    Every ordered pair of depots and sites is priced on ``cost`` (:func:`planner.tours.pricing.price_pairs`:
    the planner's lattice routes, their mean energy and run-level spread per ground; asymmetric), the
    prize-collecting routing problem is solved by PyVRP on integer arc prices (each leg's own quantile, with an
    allowance for the turn at the stop it leaves), and each chosen tour is priced as the route the robot drives
    (its legs joined, the turn in place at every stop included: :meth:`PairPrices.tour_interval`) and checked on
    its own quantile (the spreads of one ground add along the whole tour), allowances raised or capacities
    tightened and the problem solved again until every tour holds (:mod:`planner.tours.solver`). Then the
    improvement step priced as driven inserts the left-out sites that still fit, or swaps them in for sites of less
    value (:func:`planner.tours.improve_tours`). The reported energies are those exact prices.

    With ``chargers`` a tour may stop at charging points between its sites, each stop charging the battery
    to full (:class:`planner.tours.TourChargers`: its stop time booked as service time); the energy then holds
    at Q per segment between charges (the first from the robot's initial charge, the others from a full one),
    each checked on its own quantile; the chargers are priced with the sites (extra points of the pair matrix)
    and the problem is solved by OR-Tools (PyVRP's reload depots reset a load, not the energy on the arcs).

    Parameters
    ----------
    cost : EnergyCost
        The map's edge costs (with an interval for risk levels to mean anything; without one,
        the mean is the price at every level).
    sites : TourSites
        The candidate sites; one off the map or on a blocked cell is an error row, the others are kept.
    robots : TourRobot or sequence of TourRobot
        The fleet: battery, reserve and depot each.
    search : TourSearch, optional
        The level Q in [0.5, 1) (``risk``), the routing solver (default "pyvrp", "ortools" with
        chargers: the only one that stops at them), its time limit per solve (s; it usually stops
        earlier, at no improvement), its seed and whether the improvement step priced as driven runs after it
        (:class:`planner.tours.options.TourSearch`; default ``TourSearch()``: Q = 0.9, 10 s, seed 0, the step on).
    compute : Compute, optional
        Where the legs are priced and whether a bar shows over the pricing
        (:class:`terrawatt_base.dask_client.Compute`, as :func:`planner.plan_batch`; default here).
    map_label : str
        How the result names the map.
    prices : PairPrices, optional
        The legs already priced (``result.prices`` of an earlier call on the same cost, depots and sites):
        solve again at another level, battery or with another solver without pricing again (the legs'
        routes stay those searched at the earlier level).
    chargers : TourChargers, optional
        Charging points the tours may stop at (each at most its ``max_visits`` times by the whole fleet).

    Returns
    -------
    TourResult
        Status ``"nothing reachable"`` when no robot can visit any site and come back at Q.

    Raises
    ------
    InvalidParameterError
        Bad arguments; a risk level below 0.5; a depot off the map; a charger named as a site; solver "pyvrp"
        with chargers.
    OutOfBoundsError
        A charger off the map.
    BlockedPositionError
        A depot or a charger on a blocked cell.

    Examples
    --------
    >>> from energy import Battery
    >>> from terrain import flat_map
    >>> cost = CostSpec().build(flat_map((40, 40), 1.0))
    >>> sites = TourSites(("a", "b", "far"), [[10.0, 10.0], [20.0, 10.0], [39.0, 39.0]], value=[1, 2, 5])
    >>> res = plan_tour(cost, sites, TourRobot(Battery(0.1, 24.0), (2.0, 2.0)))
    >>> res.tours[0].value, sorted(res.left_out)
    (3.0, ['far'])
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    if not isinstance(sites, TourSites):
        raise InvalidParameterError(f"sites must be a TourSites, got {type(sites).__name__!r}")
    fleet = _robots(robots)
    search = TourSearch() if search is None else check_instance("search", search, TourSearch)
    q, solver = search.risk, search.solver
    depots = sorted({r.depot_xy_m for r in fleet})
    dxy = np.array(depots, dtype=float)
    cost.check_inside(dxy, "depot")
    r, c = cost.terrain.rowcol(dxy[:, 0], dxy[:, 1])
    if np.any(np.asarray(cost.blocked)[r, c]):
        bad = depots[int(np.flatnonzero(np.asarray(cost.blocked)[r, c])[0])]
        raise BlockedPositionError(f"depot {bad!r} m lies on a blocked cell (an obstacle or a slope above the limit)")
    errors = sites.check_on(cost)
    if chargers is not None:
        if not isinstance(chargers, TourChargers):
            raise InvalidParameterError(f"chargers must be a TourChargers or None, got {type(chargers).__name__!r}")
        chargers.check_on(cost)
        same = sorted(set(chargers.names) & set(sites.names))
        if same:
            raise InvalidParameterError(f"charger and site names must differ (the result names stops by them); "
                                        f"{same[0]!r} is both")
    kept = [k for k, n in enumerate(sites.names) if n not in errors]
    depot_names = ["depot"] if len(depots) == 1 else [f"depot {k}" for k in range(len(depots))]
    charger_names = list(chargers.names) if chargers is not None else []
    names = depot_names + [sites.names[k] for k in kept] + charger_names
    pts = np.vstack([dxy, sites.xy_m[kept]] + ([chargers.xy_m] if chargers is not None else []))
    if prices is None:
        prices = price_pairs(cost, pts, names, risk=q, compute=compute)
    elif not isinstance(prices, PairPrices) or prices.names != tuple(names) or not np.allclose(prices.xy_m, pts):
        raise InvalidParameterError("prices must be the PairPrices of these depots, sites and chargers (result.prices "
                                    "of an earlier plan_tour on the same inputs)")
    elif prices.cost is not cost:  # the tours joined from its legs are priced on this cost
        prices = dataclasses.replace(prices, cost=cost)
    nd, nc = len(depots), len(charger_names)
    refill_j = max(rb.full_budget_j for rb in fleet)  # a stop is booked for the most a segment can leave to refill
    stop_s = chargers.stop_time_s(refill_j) if chargers is not None else np.zeros(0)
    value = np.concatenate([np.zeros(nd), sites.value[kept], np.zeros(nc)])
    service = np.concatenate([np.zeros(nd), sites.service_energy_j[kept], np.zeros(nc)])
    timing = _Timing(prices, np.concatenate([np.zeros(nd), sites.service_time_s[kept], stop_s]),
                     np.vstack([np.tile([0.0, np.inf], (nd, 1)), sites.time_window_s[kept],
                                np.tile([0.0, np.inf], (nc, 1))]))
    depot_points = np.array([depots.index(rb.depot_xy_m) for rb in fleet])
    budgets = np.array([rb.budget_j for rb in fleet])
    site_points = np.arange(nd, nd + len(kept))
    charger_points = np.arange(nd + len(kept), len(names))
    shifts = [rb.max_duration_s for rb in fleet]

    def problem(points: Any) -> TourProblem:
        built = dataclasses.replace(
            TourProblem.build(prices, q, budgets, depot_points, points,
                              TourPoints(value, service, timing.service_s, timing.window_s), shifts,
                              [rb.full_budget_j for rb in fleet]),
            standby_w=np.array([rb.standby_power_w for rb in fleet]))
        return built.with_chargers(charger_points, chargers.max_visits) if chargers is not None else built

    whole = problem(site_points)
    open_ = dataclasses.replace(whole, shift_s=np.full(len(fleet), HORIZON_S, dtype=np.int64))
    left_out: dict[str, str] = {}
    candidates = []
    for p in site_points.tolist():
        fits = [k for k in range(len(fleet)) if whole.reaches(k, p)]
        if not any(np.isfinite(prices.mean_j[d, p]) and np.isfinite(prices.mean_j[p, d]) for d in range(nd)):
            left_out[names[p]] = NO_ROUTE
        elif not fits:
            left_out[names[p]] = TOO_FAR
        elif all(open_.timeline(k, [p]) is None for k in fits):
            left_out[names[p]] = OUTSIDE_WINDOW
        elif all(whole.timeline(k, [p]) is None for k in fits):
            left_out[names[p]] = TOO_LONG
        elif value[p] <= 0:
            left_out[names[p]] = NOT_WORTH_IT
        else:
            candidates.append(p)
    values = {sites.names[k]: float(sites.value[k]) for k in kept}
    where_xy = {n: (float(x), float(y)) for n, (x, y) in zip(sites.names, sites.xy_m.tolist())}
    windows = {n: (float(e), float(late)) for n, (e, late) in zip(sites.names, sites.time_window_s.tolist())
               if e > 0 or np.isfinite(late)}
    at = _Points(value, service, timing, set(charger_points.tolist()), q)
    if not candidates:
        reachable = any(why == NOT_WORTH_IT for why in left_out.values())  # reachable, but worth nothing
        empty = tuple(_tour(prices, rb, [], d, at)
                      for rb, d in zip(fleet, depot_points.tolist()))
        return TourResult("planned" if reachable else "nothing reachable", q, empty, left_out, errors, values,
                          solver or ("ortools" if chargers is not None else "pyvrp"), prices.pricing_time_s, 0.0, 0,
                          prices.where, map_label, where_xy, cost.terrain, cost, prices, windows, chargers)
    outcome = solve_tours(prices, problem(np.array(candidates)), solver=solver, time_limit_s=search.time_limit_s,
                          seed=search.seed)
    if search.improve:  # the sites the matrix's allowances left out that fit priced as driven
        step = improve_tours(prices, outcome.problem, outcome.tours, value=value, candidates=candidates,
                             service_time_s=timing.service_s, window_s=timing.window_s, max_duration_s=shifts)
    else:
        got = float(sum(value[p] for t in outcome.tours for p in t))
        step = ImproveOutcome(outcome.tours, 0, 0, got, got, 0.0)
    chosen = {p for t in step.tours for p in t}
    for p in candidates:
        if p not in chosen:
            left_out[names[p]] = NOT_WORTH_IT
    tours = tuple(_tour(prices, rb, t, d, at)
                  for rb, t, d in zip(fleet, step.tours, depot_points.tolist()))
    return TourResult("planned", q, tours, left_out, errors, values, outcome.solver, prices.pricing_time_s,
                      outcome.solve_time_s, outcome.rounds, prices.where, map_label, where_xy, cost.terrain, cost,
                      prices, windows, chargers, step.added, step.swapped, step.time_s)


class _Timing:
    """Driving times (s) per leg, service time (s) and time window (s) per point, the pivots at the stops: a tour's
    timeline."""

    def __init__(self, prices: PairPrices, service_s: np.ndarray, window_s: np.ndarray) -> None:
        self.prices, self.service_s, self.window_s = prices, service_s, window_s
        self.drive_s = np.asarray(prices.duration_s, float)

    def turns(self, seq: list[int]) -> list[float]:
        """The pivot (s) at each stop ``seq[1:-1]`` before the robot leaves it (:meth:`PairPrices.turn_time_s`)."""
        return [self.prices.turn_time_s(a, b, c) for a, b, c in zip(seq, seq[1:], seq[2:])]

    def walk(self, seq: list[int]) -> tuple[tuple[float, ...], tuple[float, ...], float]:
        """Arrival and start of service at each site of ``depot, sites..., depot`` leaving at 0 (waiting until a
        window opens; pivoting at each stop after its service), and the return to the depot (s)."""
        if not seq:
            return (), (), 0.0
        arrivals, starts, back = walk_timeline(self.drive_s, np.asarray(self.service_s, float),
                                               np.asarray(self.window_s, float), seq, self.turns(seq))
        return tuple(map(float, arrivals)), tuple(map(float, starts)), float(back)


@dataclass(frozen=True)
class _Points:
    """What a tour of the points (depots, sites, chargers by index) reads: value, service energy (J), timing, the
    charger points and the level Q."""

    value: np.ndarray
    service: np.ndarray
    timing: _Timing
    chargers: set[int]
    q: float


def _tour(prices: PairPrices, robot: TourRobot, stops: list[int], depot: int, points: _Points) -> RobotTour:
    """One robot's :class:`RobotTour` from its stops (point indices: sites and chargers), the energy counted
    afresh after each charge."""
    service, value, q, timing, chargers = points.service, points.value, points.q, points.timing, points.chargers
    seq = [depot, *stops, depot] if stops else []
    sites = [p for p in stops if p not in chargers]
    arrivals, starts, back = timing.walk(seq)
    turns = [0.0, *timing.turns(seq)]  # the pivot each leg starts with (none at the depot)
    waiting = [robot.standby_power_w * (b - a) for a, b in zip(arrivals, starts)]  # electronics while it waits
    legs, cumulative = [], []
    first, served = 0, 0.0
    for k, (a, b) in enumerate(zip(seq[:-1], seq[1:])):
        came_from = seq[k - 1] if k else None  # a leg leaving a stop turns there first (none at the depot)
        legs.append(TourLeg(prices.names[a], prices.names[b], prices.waypoints[a][b],
                            prices.tour_interval([a, b], arrived_from=came_from),
                            float(prices.duration_s[a, b]) + turns[k]))
        served += float(service[b]) + (waiting[k] if k < len(waiting) else 0.0)
        # since the depot or the last charge (a segment leaving a charger turns there first)
        cumulative.append(prices.tour_interval(seq[first:k + 2], served, arrived_from=seq[first - 1] if first else None))
        if b in chargers:
            first, served = k + 1, 0.0
    energy = (prices.tour_interval(seq, float(service[sites].sum()) + sum(waiting)) if seq
              else RouteEnergyInterval(0.0, 0.0, {}))
    return RobotTour(robot.name, robot.battery, robot.depot_xy_m, tuple(prices.names[p] for p in sites), tuple(legs),
                     tuple(float(service[p]) for p in stops), float(value[sites].sum()) if sites else 0.0, energy,
                     tuple(cumulative), robot.budget_j, q, tuple(float(timing.service_s[p]) for p in stops),
                     arrivals, starts, back, robot.max_duration_s,
                     tuple(k for k, p in enumerate(stops) if p in chargers), tuple(waiting))


def plan_tour_on_map(
    terrain: TerrainMap,
    sites: TourSites,
    fleet: TourFleet,
    *,
    search: TourSearch | None = None,
    pricing: CostSpec | None = None,
    compute: Compute | None = None,
    map_label: str = "map",
    chargers: TourChargers | None = None,
) -> TourResult:
    """:func:`plan_tour` on a map priced as ``terrawatt tour`` prices it: a fleet of alike robots and the
    ``chargers`` they may stop at.

    Parameters
    ----------
    terrain : TerrainMap
        The map.
    sites : TourSites
        The sites (value, service, time windows).
    fleet : TourFleet
        ``n_robots`` alike robots, each carrying ``battery``, with one depot or one each, each tour
        lasting at most ``max_duration_s`` (:class:`planner.tours.options.TourFleet`); waiting for a
        window draws the robot's ``sensor_power_w + control_standby_power_w``.
    search : TourSearch, optional
        The tour's risk level (not the spec's), the solver, its time and seed
        (:class:`planner.tours.options.TourSearch`; default ``TourSearch()``).
    pricing : CostSpec, optional
        How the edges are priced (:meth:`planner.cost_spec.CostSpec.build`; default ``CostSpec()``).
    compute, map_label, chargers
        As :func:`plan_tour`.

    Returns
    -------
    TourResult

    Raises
    ------
    InvalidParameterError
        Not a TourFleet; as :func:`plan_tour`.
    """
    fleet = check_instance("fleet", fleet, TourFleet)
    pricing = CostSpec.given(pricing)
    standby_w = pricing.params.sensor_power_w + pricing.params.control_standby_power_w  # waiting for a window
    cost = pricing.build(terrain)
    robots = [TourRobot(fleet.battery, depot, f"robot {k}", fleet.max_duration_s, standby_w)
              for k, depot in enumerate(fleet.depot_xy_m)]
    return plan_tour(cost, sites, robots, search=search, compute=compute, map_label=map_label, chargers=chargers)
