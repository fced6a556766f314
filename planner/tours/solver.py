"""Which sites, in what order: the prize-collecting, energy-capacitated routing problem solved by PyVRP.

Each robot is a vehicle of its own (its depot, its budget above the reserve as the maximum
"distance"); each site a client with ``required=False`` and a prize. Arcs are each leg's own
quantile at Q (:meth:`PairPrices.arc_quantile_j`) plus the service energy of the site it
arrives at plus, on a leg leaving a site or a charger, an allowance for the turn in place there at Q
(:meth:`PairPrices.stop_turn_quantile_j`), rounded **up** to integer units of the largest budget /
:data:`UNITS`; budgets are rounded down.

**The turn at a stop.** A leg is priced from a free heading, and the turn the robot makes at a
stop (from the heading it arrived on to the one it leaves on) depends on the stops before and
after it, which an arc of the matrix cannot know. Every leg leaving a stop therefore carries, at
first, the turn of a quarter turn there (the mean heading change between directions of no
preferred sense), and each chosen tour is then priced exactly (below); where a tour breaks its
budget and one of its turns is above its arc's allowance, the allowance of that arc is raised to
that turn and the problem solved again (the arcs only grow, at most to a U-turn each). The dearest
turn (a U-turn) on every arc would make the matrix a bound, but it prices every stop as a U-turn:
on six instances of seven sites on the hills map it left out sites whose real turns fitted in
five (value 3-14 against exact optima 4-15), where the quarter turn reached the exact optimum in
all six (and in two of three instances with chargers: docs/tours.md). No turn is counted where a
tour starts (its depot: a free heading, as the mission simulator starts facing its first segment)
nor where it ends; a tour leaving a charger turns there first (in the segment after the charge).
In time the matrix allows the longest pivot (a U-turn) on every leg leaving a stop: a bound of a
few seconds a stop (:attr:`PairPrices.longest_turn_s`), so the time windows and longest tours the
solver keeps hold for the turns the robot makes; the reported timeline counts the turns made.

The chosen tours are then checked on their own quantile, priced exactly as the route the robot
drives (:meth:`PairPrices.tour_interval`: the legs joined, the turns at the stops included, the
spreads of one ground added along the whole tour); a tour above its budget whose turns are all
within their allowances tightens that robot's capacity by the excess (the spreads), and the
problem is solved again, until every tour holds. A tour that still
does not hold after :data:`_MAX_ROUNDS` solves loses stops, the one whose removal leaves the least
exact price first, until it holds: no tour is returned above its budget at Q.

**Charging points** (:class:`planner.tours.TourChargers`) are extra points of the pair matrix a tour
may stop at between sites, each stop charging the battery to full: the energy constraint holds per
*segment* (from the depot or a charge to the next charge or back), the first on the robot's budget
above the reserve from its initial charge, the others on a full battery's. Each segment is checked
on its own quantile (the spreads of one ground add along the segment; after a charge to full the
past segment's draw no longer matters for the charge). PyVRP's reload depots reset a vehicle's
*load* (what its clients deliver or pick up), not its distance (``max_distance`` spans the whole
route, reloads or not), and a tour's energy lies on its arcs, not at its clients: chargers do not
map onto them, so a problem with chargers is solved by OR-Tools, whose energy dimension takes a
charger's reset as slack (:func:`solve_ortools`): each charger is ``max_visits`` optional copies.
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

__all__ = ["TourPoints", "TourProblem", "walk_timeline", "solve_pyvrp", "solve_ortools", "solve_tours", "UNITS", "VALUE_SCALE", "SOLVERS",
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
_PYVRP_NO_CHARGERS = ("solver 'pyvrp' cannot stop at charging points (its reload depots reset a vehicle's load, not "
                      "the energy spent on the arcs); use solver='ortools' (the default with chargers)")


def walk_timeline(drive_s: np.ndarray, service_s: np.ndarray, window_s: np.ndarray,
                  seq: Sequence[int], turn_s: Sequence[Any] | None = None) -> tuple[list[Any], list[Any], Any]:
    """Arrival and start of service at each site of the tour ``seq`` (``depot, sites..., depot``, point
    indices) leaving at 0 and waiting where a window has not opened yet, and the return to the depot: in the
    arrays' own units (the solver's whole seconds, or the result's seconds); a start past a window's latest is
    returned as it is (the caller decides). ``turn_s``: the pivot at each stop ``seq[1:-1]`` after its service,
    before the robot leaves (none: the legs' times hold it, as the solver's do)."""
    t, arrivals, starts = drive_s.dtype.type(0), [], []
    for k, (a, b) in enumerate(zip(seq[:-2], seq[1:-1])):
        arrivals.append(t + drive_s[a, b])
        starts.append(max(arrivals[-1], window_s[b, 0]))
        t = starts[-1] + service_s[b] + (turn_s[k] if turn_s is not None else 0)
    back = t + drive_s[seq[-2], seq[-1]] if len(seq) >= 2 else t
    return arrivals, starts, back


@dataclass(frozen=True, eq=False)
class TourPoints:
    """What each point of a tour problem (depots, sites, chargers, by index) asks: its value, service energy (J),
    service time (s) and time window ``(earliest_s, latest_s)`` (no service time and no windows by default)."""

    value: Any
    service_j: Any
    service_time_s: Any = None
    window_s: Any = None


@dataclass(frozen=True, eq=False)
class TourProblem:
    """The routing problem in integer units, as the solver sees it.

    Attributes
    ----------
    arc_units : ndarray of int64, shape (P, P)
        Price of leg ``i -> j`` at Q (service at ``j`` and the allowance for the turn at ``i`` included, no turn at
        a depot); larger than every capacity where no route joins them.
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
        Driving time of leg ``i -> j`` (stop-turn-go, its ramps included) plus, leaving a site or a charger, the
        longest pivot there (a U-turn, :attr:`PairPrices.longest_turn_s`: a bound on the turn the robot makes, so
        windows and longest tours hold), whole seconds rounded up (:data:`HORIZON_S` where
        no route joins them).
    service_s : ndarray of int64, shape (P,)
        Service time at each point, whole seconds rounded up (0 at the depots).
    window_s : ndarray of int64, shape (P, 2)
        When service may start at each point, ``(earliest, latest)`` in whole seconds from the departure
        (``(0, HORIZON_S)`` without a window).
    shift_s : ndarray of int64, shape (R,)
        Each robot's longest tour, whole seconds rounded down (:data:`HORIZON_S`: no limit).
    full_units : ndarray of int64, shape (R,)
        Each robot's budget at Q after a charge to full (its capacity from a charger on; without
        chargers unused).
    charger_points : ndarray of int, shape (C,)
        The charging points (point indices; empty: none).
    charger_visits : ndarray of int, shape (C,)
        How many stops the fleet may make at each.
    risk : float
        The level Q.
    budget_j, full_budget_j : ndarray, shape (R,)
        Each robot's budget above the reserve from its initial charge and from a full one (J): what each
        segment's own quantile is checked against.
    service_j : ndarray, shape (P,)
        Service energy at each point (J).
    standby_w : ndarray, shape (R,)
        What each robot draws while it waits for a window to open (W): the waiting's energy is not in the
        arcs (it depends on the order), so the solver does not see it; the check of each tour counts it.
    turn_j : ndarray, shape (P, P)
        The allowance in arc ``i -> j`` for the turn in place at ``i`` at Q (J; 0 leaving a depot): at first the
        quarter turn of :meth:`PairPrices.stop_turn_quantile_j` on every arc leaving a point, raised arc by arc
        by :meth:`with_turn_allowance` to the turns of the tours that broke their budget.
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
    full_units: np.ndarray = None  # type: ignore[assignment]
    charger_points: np.ndarray = None  # type: ignore[assignment]
    charger_visits: np.ndarray = None  # type: ignore[assignment]
    risk: float = 0.5
    budget_j: np.ndarray = None  # type: ignore[assignment]
    full_budget_j: np.ndarray = None  # type: ignore[assignment]
    service_j: np.ndarray = None  # type: ignore[assignment]
    standby_w: np.ndarray = None  # type: ignore[assignment]
    turn_j: np.ndarray = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        n = self.arc_units.shape[0]
        if self.full_units is None:
            object.__setattr__(self, "full_units", np.asarray(self.capacity_units, dtype=np.int64).copy())
        if self.charger_points is None:
            object.__setattr__(self, "charger_points", np.zeros(0, dtype=np.int64))
            object.__setattr__(self, "charger_visits", np.zeros(0, dtype=np.int64))
        if self.budget_j is None:
            object.__setattr__(self, "budget_j", np.asarray(self.capacity_units, dtype=float) * self.unit_j)
        if self.full_budget_j is None:
            object.__setattr__(self, "full_budget_j", np.asarray(self.full_units, dtype=float) * self.unit_j)
        if self.service_j is None:
            object.__setattr__(self, "service_j", np.zeros(n))
        if self.turn_j is None:
            object.__setattr__(self, "turn_j", np.zeros((n, n)))
        if self.standby_w is None:
            object.__setattr__(self, "standby_w", np.zeros(len(self.depot_points)))
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

    @property
    def has_chargers(self) -> bool:
        """Whether the tours may stop at charging points."""
        return bool(self.charger_points.size)

    @classmethod
    def build(cls, prices: PairPrices, q: float, budgets_j: Any, depot_points: Any, site_points: Any,
              points: TourPoints, max_duration_s: Any = None, full_budgets_j: Any = None) -> TourProblem:
        """The problem of visiting ``site_points`` (what each point asks: :class:`TourPoints`) at risk ``q``, each
        robot's tour lasting at most its ``max_duration_s`` (``None`` or inf: no limit); ``full_budgets_j``: each
        robot's budget after a charge to full (default its budget; :meth:`with_chargers` adds the chargers)."""
        if not isinstance(points, TourPoints):
            raise InvalidParameterError(f"points must be a TourPoints, got {type(points).__name__!r}")
        values, service_j, service_time_s, window_s = points.value, points.service_j, points.service_time_s, \
            points.window_s
        budgets = np.asarray(budgets_j, dtype=float)
        full_j = budgets if full_budgets_j is None else np.asarray(full_budgets_j, dtype=float)
        unit = max(float(budgets.max()), float(full_j.max()), 1.0) / UNITS
        cap = np.floor(budgets / unit).astype(np.int64)
        full = np.floor(full_j / unit).astype(np.int64)
        service_j = np.asarray(service_j, dtype=float)
        turn = prices.stop_turn_quantile_j(q)  # the expected turn at the stop a leg leaves (none at a depot)
        turn[np.asarray(depot_points, dtype=np.int64)] = 0.0
        turn = np.repeat(turn[:, None], len(turn), axis=1)
        np.fill_diagonal(turn, 0.0)
        arc = prices.arc_quantile_j(q) + service_j[None, :] + turn
        big = int(max(cap.max(), full.max())) * 4 + 1
        units = np.where(np.isfinite(arc), np.ceil(np.minimum(arc, big * unit) / unit - 1e-9), big).astype(np.int64)
        np.fill_diagonal(units, 0)
        sites = np.asarray(site_points, dtype=np.int64)
        weight = int(cap.sum()) + 1
        prize = np.round(np.asarray(values, dtype=float)[sites] * VALUE_SCALE).astype(np.int64) * weight
        dur = np.asarray(prices.duration_s, dtype=float) + prices.longest_turn_s  # the pivot at the stop it leaves
        dur[np.asarray(depot_points, dtype=np.int64)] -= prices.longest_turn_s  # none at a depot
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
                   shift_s, full, risk=float(q), budget_j=budgets, full_budget_j=full_j, service_j=service_j,
                   turn_j=turn)

    def with_turn_allowance(self, turn_j: Any) -> TourProblem:
        """The same problem whose allowance in each arc ``i -> j`` for the turn at ``i`` is at least ``turn_j[i, j]``
        (J): an arc whose allowance grows grows by the difference, rounded up (never shrinks)."""
        new = np.maximum(np.asarray(turn_j, dtype=float), self.turn_j)
        grow = np.ceil((new - self.turn_j) / self.unit_j - 1e-9).astype(np.int64)
        if not np.any(grow > 0):
            return self
        big = int(max(self.capacity_units.max(), self.full_units.max())) * 4 + 1
        units = np.where(self.arc_units >= big, self.arc_units, np.minimum(self.arc_units + grow, big))
        np.fill_diagonal(units, 0)
        return dataclasses.replace(self, arc_units=units, turn_j=new)

    def with_chargers(self, charger_points: Any, max_visits: Any) -> TourProblem:
        """The same problem whose tours may stop at ``charger_points`` (point indices, each at most ``max_visits``
        times by the whole fleet) to charge to full (their stop time is their ``service_s``)."""
        pts = np.asarray(charger_points, dtype=np.int64).ravel()
        visits = np.broadcast_to(np.asarray(max_visits, dtype=np.int64), pts.shape).copy()
        return dataclasses.replace(self, charger_points=pts, charger_visits=visits)

    def segments(self, robot: int, stops: Any) -> list[list[int]]:
        """The tour ``depot, stops..., depot`` of ``robot`` cut at its charging stops: each segment's points, from
        the depot or a charger to the next charger or the depot (one segment without charging stops)."""
        d = int(self.depot_points[robot])
        chargers = set(self.charger_points.tolist())
        out, seg = [], [d]
        for p in [*(int(s) for s in stops), d]:
            seg.append(p)
            if p in chargers:
                out.append(seg)
                seg = [p]
        out.append(seg)
        return out

    def reaches(self, robot: int, point: int) -> bool:
        """Whether ``robot`` can visit ``point`` and come back, every segment within its capacity, charging at will
        (every charger as often as needed: a relaxation of the charger visits)."""
        d = int(self.depot_points[robot])
        cap, full = int(self.capacity_units[robot]), int(self.full_units[robot])
        arc = self.arc_units
        chargers = [int(c) for c in self.charger_points.tolist()]
        budget = {d: cap}
        frontier = [d]
        while frontier:  # the chargers the robot can get to from its depot
            u = frontier.pop()
            for c in chargers:
                if c not in budget and arc[u, c] <= budget[u]:
                    budget[c] = full
                    frontier.append(c)
        home = {d}
        grew = True
        while grew:  # the chargers it can get home from
            grew = False
            for c in chargers:
                if c not in home and any(arc[c, v] <= full for v in home):
                    home.add(c)
                    grew = True
        return any(arc[u, point] + arc[point, v] <= left for u, left in budget.items() for v in home)

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

    def waiting_j(self, robot: int, stops: Any) -> list[float]:
        """The energy ``robot`` spends waiting at each of ``stops`` for its window to open (J; its standby power
        times the wait, on the solver's whole seconds)."""
        if not self.standby_w[robot] or not stops:
            return [0.0] * len(stops)
        d = int(self.depot_points[robot])
        arrivals, starts, _ = walk_timeline(self.drive_s, self.service_s, self.window_s, [d, *stops, d])
        return [float(self.standby_w[robot]) * float(b - a) for a, b in zip(arrivals, starts)]

    def with_capacity(self, capacity_units: Any, full_units: Any = None) -> TourProblem:
        """The same problem with other capacities (and, with chargers, other capacities after a charge)."""
        full = self.full_units if full_units is None else np.asarray(full_units, dtype=np.int64)
        return dataclasses.replace(self, capacity_units=np.asarray(capacity_units, dtype=np.int64), full_units=full)


def solve_pyvrp(problem: TourProblem, time_limit_s: float = 10.0, seed: int = 0,
                no_improvement: int | None = None) -> list[list[int]]:
    """Each robot's sites (point indices, in visiting order) by PyVRP's hybrid genetic search.

    Stops after ``no_improvement`` iterations without a better solution (default
    ``max(2000, 100 * sites)``) or after ``time_limit_s``.

    Raises
    ------
    InvalidParameterError
        A problem with charging points (its reload depots reset a load, not the energy on the arcs:
        :func:`solve_ortools` solves those).
    """
    if problem.has_chargers:
        raise InvalidParameterError(_PYVRP_NO_CHARGERS)
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
    """Each robot's stops by OR-Tools' routing solver (disjunctions with the prizes as penalties): its sites and,
    with chargers, its charging stops (point indices, in visiting order).

    With time windows or longest tours, a time dimension (transit: the service where the arc leaves, then
    the drive; slack: the waiting) holds each site's start of service in its window and each robot's
    return within its longest tour, as PyVRP does.

    With chargers, each charger is ``charger_visits`` optional copies (no penalty when left out); the energy
    dimension counts what was spent since the last charge: it starts at ``full - capacity`` (what the robot
    lacks of a full battery), every arc adds its units, and an arc leaving a charger first takes the charge
    back (the transit less a constant ``K``, the slack there ``K`` less the dimension's value: down to 0,
    a charge to full); every robot's dimension stays within its full capacity. A charger's stop time is its
    service time in the time dimension.

    Raises
    ------
    OptionalDependencyError
        OR-Tools is not installed (a dependency of terrawatt: a broken install).
    """
    try:
        from ortools.constraint_solver import pywrapcp, routing_enums_pb2
    except ImportError as exc:
        raise OptionalDependencyError("solver 'ortools' (the comparison solver, and the one of tours with charging "
                                      "points) needs OR-Tools, a dependency of terrawatt: pip install ortools") from exc
    if problem.site_points.size == 0:
        return [[] for _ in problem.depot_points]
    depots = sorted(set(problem.depot_points.tolist()))
    copies = [int(c) for c, v in zip(problem.charger_points.tolist(), problem.charger_visits.tolist())
              for _ in range(int(v))]
    order = depots + problem.site_points.tolist() + copies
    n_fixed = len(depots) + problem.site_points.size  # nodes from here on are charger copies
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
    if copies:
        _ortools_charging(problem, routing, manager, matrix, n_fixed)
    else:
        routing.AddDimensionWithVehicleCapacity(cb, 0, [int(c) for c in problem.capacity_units], True, "energy")
    for k, prize in enumerate(problem.prize.tolist()):
        routing.AddDisjunction([manager.NodeToIndex(len(depots) + k)], int(prize))
    for node in range(n_fixed, len(order)):
        routing.AddDisjunction([manager.NodeToIndex(node)], 0)
    if problem.has_windows or np.any(problem.shift_s < HORIZON_S):
        _ortools_time(problem, routing, manager, idx, len(depots))
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = routing_enums_pb2.FirstSolutionStrategy.PATH_CHEAPEST_ARC
    params.local_search_metaheuristic = routing_enums_pb2.LocalSearchMetaheuristic.GUIDED_LOCAL_SEARCH
    params.time_limit.FromMilliseconds(int(1000 * time_limit_s))
    solution = _solve_charging(routing, params, time_limit_s) if copies else routing.SolveWithParameters(params)
    tours: list[list[int]] = [[] for _ in problem.depot_points]
    if solution is None:
        return tours
    for r in range(len(starts)):
        i = routing.Start(r)
        while not routing.IsEnd(i):
            node = manager.IndexToNode(i)
            if node >= len(depots) and (not tours[r] or tours[r][-1] != order[node]):  # two copies of one charger
                tours[r].append(int(order[node]))  # in a row are one stop (a leg of nothing, one charge to full)
            i = solution.Value(routing.NextVar(i))
    return tours


def _solve_charging(routing: Any, params: Any, time_limit_s: float) -> Any:
    """With chargers: OR-Tools' depth-first (complete) search for at most half the time limit, then its guided local
    search from the best it found for the rest.

    The local search alone moves one or two stops at a time, each move feasible, and a better tour
    often needs a site and a charging stop inserted together (e.g. a second charger on the way to a far
    site): it stalls in such local optima. The complete search finds those tours on small problems
    (it exhausts the tree well within the time) and gives the local search a start on large ones."""
    from ortools.constraint_solver import pywrapcp

    exact = pywrapcp.DefaultRoutingSearchParameters()
    exact.CopyFrom(params)
    exact.use_depth_first_search = True
    exact.time_limit.FromMilliseconds(int(500 * time_limit_s))
    t0 = time.perf_counter()
    first = routing.SolveWithParameters(exact)
    rest = pywrapcp.DefaultRoutingSearchParameters()
    rest.CopyFrom(params)
    rest.time_limit.FromMilliseconds(max(int(1000 * (time_limit_s - (time.perf_counter() - t0))), 1))
    if first is None:
        return routing.SolveWithParameters(rest)
    better = routing.SolveFromAssignmentWithParameters(first, rest)
    return better if better is not None else first


def _ortools_charging(problem: TourProblem, routing: Any, manager: Any, matrix: list[list[int]], n_fixed: int) -> None:
    """OR-Tools' energy dimension with charges to full at the charger copies (nodes ``n_fixed`` on)."""
    big = int(problem.full_units.max())

    def spent(i: int, j: int) -> int:
        a = manager.IndexToNode(i)
        return matrix[a][manager.IndexToNode(j)] - (big if a >= n_fixed else 0)

    routing.AddDimensionWithVehicleCapacity(routing.RegisterTransitCallback(spent), big,
                                            [int(c) for c in problem.full_units], False, "energy")
    energy = routing.GetDimensionOrDie("energy")
    solver = routing.solver()
    for r in range(len(problem.depot_points)):
        energy.CumulVar(routing.Start(r)).SetValue(int(problem.full_units[r] - problem.capacity_units[r]))
        energy.SlackVar(routing.Start(r)).SetValue(0)
    for node in range(len(matrix)):
        if node < len(set(problem.depot_points.tolist())):
            continue  # a depot is a start or an end: its start's slack is set above, an end has none
        i = manager.NodeToIndex(node)
        if node < n_fixed:
            energy.SlackVar(i).SetValue(0)
        else:  # the charge to full: leave with nothing spent
            solver.Add(energy.SlackVar(i) + energy.CumulVar(i) == big)


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


def solve_tours(prices: PairPrices, problem: TourProblem, *, solver: str | None = None, time_limit_s: float = 10.0,
                seed: int = 0) -> SolverOutcome:
    """Solve ``problem`` (built on ``prices``), check each tour on its own quantile, segment by segment between
    charges, each priced exactly as the route the robot drives (:meth:`PairPrices.tour_interval`: the turns at
    its stops included), tighten the capacities and solve again until every tour holds; a tour that still does not
    after :data:`_MAX_ROUNDS` solves loses stops until it does (none is returned above its budget at Q).

    ``solver``: ``"pyvrp"`` (the default without chargers) or ``"ortools"`` (the default, and the only one, with
    chargers: :func:`solve_pyvrp`).

    Raises
    ------
    InvalidParameterError
        An unknown solver; ``"pyvrp"`` on a problem with chargers.
    """
    solver = ("ortools" if problem.has_chargers else "pyvrp") if solver is None else solver
    if solver not in SOLVERS:
        raise InvalidParameterError(f"solver must be one of {SOLVERS!r}, got {solver!r}")
    if solver == "pyvrp" and problem.has_chargers:
        raise InvalidParameterError(_PYVRP_NO_CHARGERS)
    t0 = time.perf_counter()
    tours: list[list[int]] = [[] for _ in problem.depot_points]
    for rounds in range(1, _MAX_ROUNDS + 1):  # noqa: B007 (how many rounds were solved: the outcome says)
        tours = (solve_pyvrp(problem, time_limit_s, seed) if solver == "pyvrp"
                 else solve_ortools(problem, time_limit_s))
        cap, full = problem.capacity_units.copy(), problem.full_units.copy()
        turn = problem.turn_j.copy()
        holds = True
        for r, stops in enumerate(tours):
            factor = _budget_share(prices, problem, r, stops)
            if factor >= 1.0:
                continue
            holds = False
            seq = [int(problem.depot_points[r]), *stops, int(problem.depot_points[r])]
            over = False
            for a, b, c in zip(seq, seq[1:], seq[2:]):  # a turn above its arc's allowance: raise it there
                turned = prices.turn_interval(a, b, c).quantile_j(problem.risk)
                if turned > turn[b, c] + problem.unit_j:
                    turn[b, c], over = turned, True
            if not over:  # the turns are within their allowances: the spreads are not, tighten the capacity
                cap[r] = int(math.floor(cap[r] * factor)) - 1
                full[r] = int(math.floor(full[r] * factor)) - 1
        if holds:
            break
        problem = problem.with_capacity(np.maximum(cap, 0), np.maximum(full, 0)).with_turn_allowance(turn)
    else:
        tours = [_trimmed(prices, problem, r, stops) for r, stops in enumerate(tours)]
    return SolverOutcome(tours, problem, solver, time.perf_counter() - t0, rounds)


def _budget_share(prices: PairPrices, problem: TourProblem, robot: int, stops: list[int]) -> float:
    """The least over the segments of ``robot``'s tour of its budget over its exact price at Q (>= 1: it holds):
    each segment between charges priced as the route driven (:meth:`PairPrices.tour_interval`), with its service
    and waiting energy."""
    q, factor = problem.risk, 1.0
    waiting = iter([*problem.waiting_j(robot, stops), 0.0])  # per point after the depot (none back there)
    came_from = None  # the stop before a charger: the segment leaving it turns there first
    for k, seg in enumerate(problem.segments(robot, stops)):
        budget = problem.budget_j[robot] if k == 0 else problem.full_budget_j[robot]
        waited = sum(next(waiting) for _ in seg[1:])
        need = prices.tour_interval(seg, float(problem.service_j[seg[1:]].sum()) + waited,
                                    arrived_from=came_from).quantile_j(q)
        if need > budget:
            factor = min(factor, budget / need)
        came_from = seg[-2]
    return factor


def _trimmed(prices: PairPrices, problem: TourProblem, robot: int, stops: list[int]) -> list[int]:
    """``stops`` less the fewest stops, each time the one whose removal leaves the highest budget share, until the
    tour holds at Q (:func:`_budget_share`; an empty tour holds)."""
    stops = list(stops)
    while stops and _budget_share(prices, problem, robot, stops) < 1.0:
        shares = [_budget_share(prices, problem, robot, stops[:k] + stops[k + 1:]) for k in range(len(stops))]
        del stops[int(np.argmax(shares))]
    return stops
