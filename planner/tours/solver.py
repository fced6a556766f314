"""Which sites, in what order: the prize-collecting, energy-capacitated routing problem solved by PyVRP.

Each robot is a vehicle of its own (its depot, its budget above the reserve as the maximum
"distance"); each site a client with ``required=False`` and a prize. Arcs are each leg's own
quantile at Q (:meth:`PairPrices.arc_quantile_j`) plus the service energy of the site it
arrives at, rounded **up** to integer units of the largest budget / :data:`UNITS`; budgets are
rounded down. Prizes are the values (to :data:`VALUE_SCALE`) times one more than all budgets'
units, so the solver maximises the value first and spends the least energy on it second.

Time is counted in integer seconds: each leg's driving time (turns included) rounded **up**, each
site's service time rounded up as the client's ``service_duration``, and each site's time window
``(earliest_s, latest_s)`` as the client's ``tw_early`` (rounded up) / ``tw_late`` (rounded down),
so a tour on time in integer seconds is on time in the real ones (a window that holds no whole
second becomes ``(0, 0)``: closed to every robot that has to drive there). Every robot leaves its depot at 0;
one that arrives early waits until ``earliest_s`` (PyVRP's semantics); service starts by ``latest_s``;
a robot's ``max_duration_s`` (rounded down) is its vehicle's ``shift_duration``.

The chosen tours are then checked on their own quantile (:meth:`PairPrices.tour_interval`: the
spreads of one ground add along the whole tour); a tour above its budget tightens that robot's
capacity by the excess and the problem is solved again, until every tour holds.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.errors import InvalidParameterError, OptionalDependencyError

from .pricing import PairPrices

__all__ = ["TourProblem", "walk_timeline", "solve_pyvrp", "solve_ortools", "solve_tours", "UNITS", "VALUE_SCALE", "SOLVERS",
           "HORIZON_S"]

#: Integer units of the largest budget (an arc is rounded up by less than one).
UNITS = 100_000
#: Values are compared to 1 / VALUE_SCALE.
VALUE_SCALE = 100
#: Routing solvers by name.
SOLVERS = ("pyvrp", "ortools")
_MAX_ROUNDS = 8
#: Seconds that stand for "never" (no window's end; a leg without a route).
HORIZON_S = 10**12


def walk_timeline(drive_s: np.ndarray, service_s: np.ndarray, window_s: np.ndarray,
                  seq: Sequence[int]) -> tuple[list[Any], list[Any], Any]:
    """Arrival and start of service at each site of the tour ``seq`` (``depot, sites..., depot``, point
    indices) leaving at 0 and waiting where a window has not opened yet, and the return to the depot: in the
    arrays' own units (the solver's whole seconds, or the result's seconds); a start past a window's latest is
    returned as it is (the caller decides)."""
    t, arrivals, starts = drive_s.dtype.type(0), [], []
    for a, b in zip(seq[:-2], seq[1:-1]):
        arrivals.append(t + drive_s[a, b])
        starts.append(max(arrivals[-1], window_s[b, 0]))
        t = starts[-1] + service_s[b]
    back = t + drive_s[seq[-2], seq[-1]] if len(seq) >= 2 else t
    return arrivals, starts, back


@dataclass(frozen=True, eq=False)
class TourProblem:
    """The routing problem in integer units, as the solver sees it.

    Attributes
    ----------
    arc_units : ndarray of int64, shape (P, P)
        Conservative price of leg ``i -> j`` (service at ``j`` included); larger than every
        capacity where no route joins them.
    capacity_units : ndarray of int64, shape (R,)
        Each robot's budget at Q.
    depot_points : ndarray of int, shape (R,)
        Each robot's depot (a point index).
    site_points : ndarray of int, shape (S,)
        The candidate sites (point indices).
    prize : ndarray of int64, shape (S,)
        Each candidate's prize.
    unit_j : float
        Joules per unit.
    drive_s : ndarray of int64, shape (P, P)
        Driving time of leg ``i -> j`` (turns included), whole seconds rounded up (:data:`HORIZON_S` where
        no route joins them).
    service_s : ndarray of int64, shape (P,)
        Service time at each point, whole seconds rounded up (0 at the depots).
    window_s : ndarray of int64, shape (P, 2)
        When service may start at each point, ``(earliest, latest)`` in whole seconds from the departure
        (``(0, HORIZON_S)`` without a window).
    shift_s : ndarray of int64, shape (R,)
        Each robot's longest tour, whole seconds rounded down (:data:`HORIZON_S`: no limit).
    """

    arc_units: np.ndarray
    capacity_units: np.ndarray
    depot_points: np.ndarray
    site_points: np.ndarray
    prize: np.ndarray
    unit_j: float
    drive_s: np.ndarray = None  # type: ignore[assignment]
    service_s: np.ndarray = None  # type: ignore[assignment]
    window_s: np.ndarray = None  # type: ignore[assignment]
    shift_s: np.ndarray = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        n = self.arc_units.shape[0]
        if self.drive_s is None:
            object.__setattr__(self, "drive_s", np.zeros((n, n), dtype=np.int64))
        if self.service_s is None:
            object.__setattr__(self, "service_s", np.zeros(n, dtype=np.int64))
        if self.window_s is None:
            object.__setattr__(self, "window_s", np.tile(np.array([0, HORIZON_S], dtype=np.int64), (n, 1)))
        if self.shift_s is None:
            object.__setattr__(self, "shift_s", np.full(len(self.depot_points), HORIZON_S, dtype=np.int64))

    @property
    def has_windows(self) -> bool:
        """Whether a candidate site has a time window."""
        w = self.window_s[self.site_points]
        return bool(np.any(w[:, 0] > 0) or np.any(w[:, 1] < HORIZON_S))

    @classmethod
    def build(cls, prices: PairPrices, q: float, budgets_j: Any, depot_points: Any, site_points: Any,
              values: Any, service_j: Any, service_time_s: Any = None, window_s: Any = None,
              max_duration_s: Any = None) -> TourProblem:
        """The problem of visiting ``site_points`` (values, service energies, service times and time windows
        ``(earliest_s, latest_s)`` per point index; no service time and no windows by default) at risk ``q``, each
        robot's tour lasting at most its ``max_duration_s`` (``None`` or inf: no limit)."""
        budgets = np.asarray(budgets_j, dtype=float)
        unit = max(float(budgets.max()), 1.0) / UNITS
        cap = np.floor(budgets / unit).astype(np.int64)
        arc = prices.arc_quantile_j(q) + np.asarray(service_j, dtype=float)[None, :]
        big = int(cap.max()) * 4 + 1
        units = np.where(np.isfinite(arc), np.ceil(np.minimum(arc, big * unit) / unit - 1e-9), big).astype(np.int64)
        np.fill_diagonal(units, 0)
        sites = np.asarray(site_points, dtype=np.int64)
        weight = int(cap.sum()) + 1
        prize = np.round(np.asarray(values, dtype=float)[sites] * VALUE_SCALE).astype(np.int64) * weight
        dur = np.asarray(prices.duration_s, dtype=float)
        drive = np.where(np.isfinite(dur), np.ceil(np.minimum(dur, HORIZON_S) - 1e-9), HORIZON_S).astype(np.int64)
        np.fill_diagonal(drive, 0)
        n = units.shape[0]
        service_s = (np.zeros(n, dtype=np.int64) if service_time_s is None
                     else np.ceil(np.asarray(service_time_s, dtype=float) - 1e-9).astype(np.int64))
        win = np.tile([0.0, float(HORIZON_S)], (n, 1)) if window_s is None else np.asarray(window_s, dtype=float)
        windows = np.column_stack([np.ceil(np.minimum(win[:, 0], HORIZON_S) - 1e-9),
                                   np.floor(np.minimum(win[:, 1], HORIZON_S) + 1e-9)]).astype(np.int64)
        windows[windows[:, 0] > windows[:, 1]] = 0  # no whole second inside: only a site at the depot is on time
        shift = (np.full(len(budgets), float(HORIZON_S)) if max_duration_s is None
                 else np.array([HORIZON_S if v is None else v for v in max_duration_s], dtype=float))
        shift_s = np.floor(np.minimum(shift, HORIZON_S) + 1e-9).astype(np.int64)
        return cls(units, cap, np.asarray(depot_points, dtype=np.int64), sites, prize, unit, drive, service_s, windows,
                   shift_s)

    def tour_units(self, robot: int, sites: Any) -> int:
        """Units of the closed tour ``depot, sites..., depot`` of ``robot``."""
        d = int(self.depot_points[robot])
        seq = [d, *[int(s) for s in sites], d]
        return int(sum(self.arc_units[a, b] for a, b in zip(seq[:-1], seq[1:])))

    def timeline(self, robot: int, sites: Any) -> tuple[list[int], list[int], int] | None:
        """Arrival and start of service at each of ``sites`` (whole s) and the return to the depot on the tour
        ``depot, sites..., depot`` of ``robot`` leaving at 0, waiting at a site reached before its earliest
        start; ``None`` when service cannot start at some site by its latest or the robot is back after its
        longest tour."""
        d = int(self.depot_points[robot])
        seq = [d, *[int(s) for s in sites], d]
        arrivals, starts, back = walk_timeline(self.drive_s, self.service_s, self.window_s, seq)
        if any(start > self.window_s[s, 1] for s, start in zip(seq[1:-1], starts)):
            return None
        return (arrivals, starts, back) if back <= int(self.shift_s[robot]) else None

    def with_capacity(self, capacity_units: Any) -> TourProblem:
        """The same problem with other capacities."""
        return dataclasses.replace(self, capacity_units=np.asarray(capacity_units, dtype=np.int64))


def solve_pyvrp(problem: TourProblem, time_limit_s: float = 10.0, seed: int = 0,
                no_improvement: int | None = None) -> list[list[int]]:
    """Each robot's sites (point indices, in visiting order) by PyVRP's hybrid genetic search.

    Stops after ``no_improvement`` iterations without a better solution (default
    ``max(2000, 100 * sites)``) or after ``time_limit_s``.
    """
    import pyvrp
    from pyvrp.stop import MaxRuntime, MultipleCriteria, NoImprovement

    if problem.site_points.size == 0:
        return [[] for _ in problem.depot_points]
    model = pyvrp.Model()
    depots = sorted(set(problem.depot_points.tolist()))
    order = depots + problem.site_points.tolist()  # model location k is point order[k]
    locs = [model.add_location(float(k), 0.0) for k in range(len(order))]
    depot_of = {p: model.add_depot(locs[k]) for k, p in enumerate(depots)}
    for r, (d, cap) in enumerate(zip(problem.depot_points.tolist(), problem.capacity_units.tolist())):
        model.add_vehicle_type(1, start_depot=depot_of[d], end_depot=depot_of[d], max_distance=int(cap),
                               tw_early=0, start_late=0, shift_duration=int(problem.shift_s[r]),
                               name=f"robot {r}")  # leaves at 0
    for k, (p, prize) in enumerate(zip(problem.site_points.tolist(), problem.prize.tolist())):
        early, late = (int(v) for v in problem.window_s[p])
        model.add_client(locs[len(depots) + k], prize=int(prize), required=False,
                         service_duration=int(problem.service_s[p]), tw_early=early, tw_late=late)
    idx = np.asarray(order)
    sub = problem.arc_units[np.ix_(idx, idx)]
    drive = problem.drive_s[np.ix_(idx, idx)]
    for a in range(len(order)):
        for b in range(len(order)):
            if a != b:
                model.add_edge(locs[a], locs[b], int(sub[a, b]), duration=int(drive[a, b]))
    patience = max(2000, 100 * problem.site_points.size) if no_improvement is None else int(no_improvement)
    stop = MultipleCriteria([MaxRuntime(float(time_limit_s)), NoImprovement(patience)])
    # the prizes dwarf an arc (value first): let the penalty on excess energy grow as large as a prize
    params = pyvrp.SolveParams(penalty=pyvrp.PenaltyParams(max_penalty=max(1e5, 10.0 * float(problem.prize.max()))))
    result = model.solve(stop, seed=int(seed), display=False, collect_stats=False, params=params)
    tours: list[list[int]] = [[] for _ in problem.depot_points]
    if not result.best.is_feasible():
        return tours
    for route in result.best.routes():
        visits = [problem.site_points[a.idx].item() for a in route if a.is_client()]
        tours[route.vehicle_type()] = visits
    return tours


def solve_ortools(problem: TourProblem, time_limit_s: float = 10.0) -> list[list[int]]:
    """Each robot's sites by OR-Tools' routing solver (disjunctions with the prizes as penalties), for comparison.

    With time windows or longest tours, a time dimension (transit: the service where the arc leaves, then
    the drive; slack: the waiting) holds each site's start of service in its window and each robot's
    return within its longest tour, as PyVRP does.

    Raises
    ------
    OptionalDependencyError
        OR-Tools is not installed (the ``bench`` extra).
    """
    try:
        from ortools.constraint_solver import pywrapcp, routing_enums_pb2
    except ImportError as exc:
        raise OptionalDependencyError("solver 'ortools' needs OR-Tools: pip install 'terrawatt[bench]'") from exc
    if problem.site_points.size == 0:
        return [[] for _ in problem.depot_points]
    depots = sorted(set(problem.depot_points.tolist()))
    order = depots + problem.site_points.tolist()
    idx = np.asarray(order)
    sub = problem.arc_units[np.ix_(idx, idx)]
    loc = {p: k for k, p in enumerate(depots)}
    starts = [loc[d] for d in problem.depot_points.tolist()]
    manager = pywrapcp.RoutingIndexManager(len(order), len(starts), starts, starts)
    routing = pywrapcp.RoutingModel(manager)
    matrix = sub.tolist()

    def arc(i: int, j: int) -> int:
        return matrix[manager.IndexToNode(i)][manager.IndexToNode(j)]

    cb = routing.RegisterTransitCallback(arc)
    routing.SetArcCostEvaluatorOfAllVehicles(cb)
    routing.AddDimensionWithVehicleCapacity(cb, 0, [int(c) for c in problem.capacity_units], True, "energy")
    for k, prize in enumerate(problem.prize.tolist()):
        routing.AddDisjunction([manager.NodeToIndex(len(depots) + k)], int(prize))
    if problem.has_windows or np.any(problem.shift_s < HORIZON_S):
        _ortools_time(problem, routing, manager, idx, len(depots))
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = routing_enums_pb2.FirstSolutionStrategy.PATH_CHEAPEST_ARC
    params.local_search_metaheuristic = routing_enums_pb2.LocalSearchMetaheuristic.GUIDED_LOCAL_SEARCH
    params.time_limit.FromMilliseconds(int(1000 * time_limit_s))
    solution = routing.SolveWithParameters(params)
    tours: list[list[int]] = [[] for _ in problem.depot_points]
    if solution is None:
        return tours
    for r in range(len(starts)):
        i = routing.Start(r)
        while not routing.IsEnd(i):
            node = manager.IndexToNode(i)
            if node >= len(depots):
                tours[r].append(int(problem.site_points[node - len(depots)]))
            i = solution.Value(routing.NextVar(i))
    return tours


def _ortools_time(problem: TourProblem, routing: Any, manager: Any, idx: np.ndarray, n_depots: int) -> None:
    """OR-Tools' time dimension: leave at 0, wait at will, serve each site in its window, be back in time."""
    drive = problem.drive_s[np.ix_(idx, idx)].tolist()
    service = problem.service_s[idx].tolist()

    def travel(i: int, j: int) -> int:
        a, b = manager.IndexToNode(i), manager.IndexToNode(j)
        return service[a] + drive[a][b]

    horizon = HORIZON_S - 1  # a leg without a route never fits
    routing.AddDimension(routing.RegisterTransitCallback(travel), horizon, horizon, True, "time")
    clock = routing.GetDimensionOrDie("time")
    for k, p in enumerate(problem.site_points.tolist()):
        early, late = (int(v) for v in problem.window_s[p])
        clock.CumulVar(manager.NodeToIndex(n_depots + k)).SetRange(early, min(late, horizon))
    for r, shift in enumerate(problem.shift_s.tolist()):
        clock.CumulVar(routing.End(r)).SetMax(min(int(shift), horizon))


@dataclass(frozen=True)
class SolverOutcome:
    """The chosen tours and how they were found."""

    tours: list[list[int]]
    problem: TourProblem
    solver: str
    solve_time_s: float
    rounds: int


def solve_tours(prices: PairPrices, q: float, budgets_j: Any, depot_points: Any, site_points: Any, values: Any,
                service_j: Any, *, solver: str = "pyvrp", time_limit_s: float = 10.0, seed: int = 0,
                service_time_s: Any = None, window_s: Any = None, max_duration_s: Any = None) -> SolverOutcome:
    """Solve, check each tour on its own quantile, tighten and solve again until every tour holds.

    Raises
    ------
    InvalidParameterError
        An unknown solver.
    """
    if solver not in SOLVERS:
        raise InvalidParameterError(f"solver must be one of {SOLVERS!r}, got {solver!r}")
    t0 = time.perf_counter()
    budgets = np.asarray(budgets_j, dtype=float)
    service = np.asarray(service_j, dtype=float)
    problem = TourProblem.build(prices, q, budgets, depot_points, site_points, values, service, service_time_s,
                                window_s, max_duration_s)
    tours: list[list[int]] = [[] for _ in budgets]
    for rounds in range(1, _MAX_ROUNDS + 1):
        tours = (solve_pyvrp(problem, time_limit_s, seed) if solver == "pyvrp"
                 else solve_ortools(problem, time_limit_s))
        cap = problem.capacity_units.copy()
        holds = True
        for r, sites in enumerate(tours):
            d = int(problem.depot_points[r])
            need = prices.tour_interval([d, *sites, d], float(service[sites].sum())).quantile_j(q)
            if need > budgets[r]:
                holds = False
                cap[r] = int(math.floor(cap[r] * budgets[r] / need)) - 1
        if holds:
            break
        problem = problem.with_capacity(np.maximum(cap, 0))
    return SolverOutcome(tours, problem, solver, time.perf_counter() - t0, rounds)
