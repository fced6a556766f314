"""Every ordered pair of a tour's points priced on the map: one lattice search per point, here or as dask tasks.

A leg ``i -> j`` is the lattice route that minimises the leg's price at the risk level (on
:meth:`planner.CostTables.at_quantile` when the cost carries an interval, as planning at a ``risk`` does; else the
mean), found by :meth:`planner.Lattice.paths_from`: one Dijkstra per point, not one per pair.
The leg is then priced on the cost itself: its mean energy (drive and turns,
:meth:`EnergyCost.path_energy_j`, the plan price), its run-level spread per ground
(:func:`planner.route_price.price_route`, linear within a ground) and its duration. Legs are
directed: uphill != downhill, so the matrices are asymmetric.

**Turns at the stops.** A leg is searched and priced from a free heading: its turns are those
between its own waypoints. The robot drives the legs joined, and at every stop it turns in place
from the heading it arrived on to the one it leaves on (a U-turn where it leaves a site the way it
came) — a turn that depends on the stops before and after, which no leg of the matrix can know.
So a tour is priced as what the robot drives, the legs joined into one route priced by
:func:`planner.route_price.price_route` (:meth:`PairPrices.tour_interval`), and the matrix the
solver reads carries, on every leg leaving a stop, an allowance for the expected turn in place at
that stop (:meth:`PairPrices.stop_turn_quantile_j`; :mod:`planner.tours.solver` says why not the
dearest).

**A stop at every site.** The robot stops at every site to serve it, whatever the turn there: where
it arrives and leaves on one heading, the joined route would drive through, so the stop-and-go
(the turn table's column 0) is added there (:meth:`PairPrices.tour_interval`); each leg's own price
already holds it (from rest to rest), so the solver's allowance is the pivot alone.

**Time.** A leg's time is its route driven stop-turn-go from rest to rest
(:func:`planner.route_time.route_duration_s`: its ramps included); at each stop the robot pivots
after serving, before it leaves (:meth:`PairPrices.turn_time_s`), which a tour's timeline counts
(arrival at the next stop). The solver's matrix allows the longest pivot (a U-turn,
:attr:`PairPrices.longest_turn_s`) on every leg leaving a stop: a bound, so the windows and longest
tours it keeps hold for the turns the robot makes.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from energy.models.forecast import predictive_quantile
from energy.profiles import COLLINEAR_TOL_RAD, DEFAULT_YAW_ACCEL_RADPS2, move_duration_s
from terrawatt_base.checks import check_instance
from terrawatt_base.dask_client import Compute, client_worker_count, run_tasks
from terrawatt_base.errors import InvalidParameterError

from ..batch import shippable_cost
from ..edge_cost import EnergyCost
from ..lattice import Lattice
from ..route_price import RouteEnergyInterval, price_route
from ..route_time import route_duration_s
from ..tables import check_risk_level

__all__ = ["PairPrices", "price_pairs", "price_from", "STOP_TURN_RAD"]

#: The heading change the solver's matrix allows for at every stop (rad): a quarter turn, the mean heading change
#: between two directions of no preferred sense (:meth:`PairPrices.stop_turn_quantile_j`).
STOP_TURN_RAD = math.pi / 2


@dataclass(frozen=True, eq=False)
class PairPrices:
    """The priced legs between every ordered pair of points (depots and sites).

    Attributes
    ----------
    names : tuple of str
        One per point.
    xy_m : ndarray, shape (P, 2)
        The points (m).
    mean_j : ndarray, shape (P, P)
        Mean energy of leg ``i -> j`` (J; ``inf`` where no route joins them, 0 on the diagonal).
    sd_by_ground_j : ndarray, shape (P, P, G)
        The leg's run-level spread per ground (J; linear sums, zeros without an interval).
    ground_labels : tuple of str
        The ``G`` grounds (the cost's row labels).
    duration_s : ndarray, shape (P, P)
        Driving time of each leg (s): its route driven stop-turn-go from rest to rest
        (:func:`planner.route_time.route_duration_s`; the turn at the stop it leaves is
        :meth:`turn_time_s`).
    waypoints : tuple of tuple of ndarray or None
        ``waypoints[i][j]`` the leg's route (m), None where there is none.
    pricing_time_s : float
        Seconds to price them.
    where : str
        ``"in process"``, ``"local cluster"`` or ``"given client"``.
    n_workers : int
        Processes that priced them.
    ground_dof : tuple of float
        Per ground, the degrees of freedom of its spread (the cost's ``spread_dof``: ``inf`` for a
        Gaussian, finite for a Student-t; empty: all Gaussian).
    cost : EnergyCost or None
        The cost the legs were priced on: what prices a tour of them joined (:meth:`tour_interval`)
        and the turns at the stops (:meth:`stop_turn_quantile_j`). None only for a matrix made by hand,
        which prices no tour.
    """

    names: tuple[str, ...]
    xy_m: np.ndarray
    mean_j: np.ndarray
    sd_by_ground_j: np.ndarray
    ground_labels: tuple[str, ...]
    duration_s: np.ndarray
    waypoints: tuple[tuple[np.ndarray | None, ...], ...]
    pricing_time_s: float
    where: str = "in process"
    n_workers: int = 1
    ground_dof: tuple[float, ...] = ()
    cost: EnergyCost | None = field(default=None, repr=False)
    _walked: dict = field(default_factory=dict, init=False, repr=False, compare=False)  # the cost's segment spreads

    def __len__(self) -> int:
        return len(self.names)

    def _dof(self, g: int) -> float:
        return float(self.ground_dof[g]) if self.ground_dof else math.inf

    def arc_quantile_j(self, q: float) -> np.ndarray:
        """Each leg's own ``q`` quantile (J): ``mean + t_q * sqrt(sum_g S_g**2)`` (``inf`` where no route).

        ``t_q`` is the quantile of the leg's predictive: the least degrees of freedom of the
        grounds it crosses (a Gaussian's ``z_q`` where every one is Gaussian), as
        :func:`planner.route_price.price_route` gives a route. For ``q >= 0.5`` a sum of these
        along a tour is never below the tour's own quantile (the spreads of one ground add along
        the whole tour: the norm of a sum is at most the sum of the norms; a tour's degrees of
        freedom are at least its heaviest leg's), so a capacity on them is conservative.
        """
        q = check_risk_level(q)
        crossed = self.sd_by_ground_j > 0
        dof = np.full(self.mean_j.shape, math.inf)
        for g in range(len(self.ground_labels)):
            dof = np.where(crossed[:, :, g], np.minimum(dof, self._dof(g)), dof)
        z = np.empty_like(dof)
        for d in np.unique(dof):  # a few distinct degrees of freedom: one quantile each
            z[dof == d] = predictive_quantile(q, float(d))
        sd = np.sqrt(np.sum(self.sd_by_ground_j ** 2, axis=2))
        return self.mean_j + z * sd

    def _priced_cost(self, what: str) -> EnergyCost:
        if not isinstance(self.cost, EnergyCost):
            raise InvalidParameterError(f"these prices carry no cost to price {what} with (make them with price_pairs, "
                                        "which keeps the cost the legs were priced on)", parameter="prices")
        return self.cost

    def stop_turn_quantile_j(self, q: float) -> np.ndarray:
        """Per point, the ``q`` quantile of the expected turn in place there (J): the allowance for the turn at a stop.

        A tour turns at each stop from the heading it arrived on to the one it leaves on, which
        depends on the stops before and after it: no leg of the matrix can know it. Between
        headings of no preferred direction the heading change averages a quarter turn (pi / 2),
        so the allowance is the turn of pi / 2 on the ground under the point
        (:meth:`EnergyCost.turn_energy_at`, the cost's rule for a turn) at its ``q`` quantile
        (``mean + t_q * sd``, ``t_q`` the quantile of that ground's predictive), less the stop-and-go
        the two legs' own prices already hold (each leg ends at rest and starts from rest,
        :meth:`EnergyCost.stop_go_at`; the turn's entry holds one too). It is what
        :meth:`planner.tours.TourProblem.build` adds to every leg leaving a stop; it is not a bound
        (a U-turn costs about twice as much), so each chosen tour is then priced exactly
        (:meth:`tour_interval`) and checked (:func:`planner.tours.solve_tours`).
        """
        q = check_risk_level(q)
        cost = self._priced_cost("the turns at the stops")
        r, c = cost.terrain.rowcol(self.xy_m[:, 0], self.xy_m[:, 1])
        rows = np.asarray(cost.ground_rows)[r, c]
        turn = cost.turn_energy_at(rows, np.full(rows.shape, STOP_TURN_RAD)) - cost.stop_go_at(rows)
        if cost.has_interval:
            z = np.array([predictive_quantile(q, self._dof(int(g))) for g in rows])
            turn = turn + z * cost.turn_spread_at(rows, np.full(rows.shape, STOP_TURN_RAD))
        return turn

    def turn_time_s(self, before: int, at: int, after: int) -> float:
        """The time (s) the robot pivots at point ``at`` between the legs ``before -> at`` and ``at -> after``: from
        the heading it arrived on to the one it leaves on, on the stop-turn-go profile's ramped yaw rate
        (:func:`energy.profiles.move_duration_s` at the cost's turn rate; 0 where it leaves on the heading it came).
        The stop-and-go there is in the two legs' own times (each is driven from rest to rest).

        Raises
        ------
        InvalidParameterError
            A leg that no route joins; prices without their cost.
        """
        cost = self._priced_cost("the turns at the stops")
        ways = (self.waypoints[before][at], self.waypoints[at][after])
        if before == at or at == after:
            return 0.0
        if ways[0] is None or ways[1] is None:
            raise InvalidParameterError(f"the turn at {at!r} between {before!r} and {after!r} uses a leg that no "
                                        "route joins")
        angle = _heading_change_rad(*ways)
        if angle <= COLLINEAR_TOL_RAD:
            return 0.0
        return float(move_duration_s(angle, cost.turn_rate_radps, DEFAULT_YAW_ACCEL_RADPS2))

    @property
    def longest_turn_s(self) -> float:
        """The longest pivot at a stop (s): a U-turn at the cost's turn rate, what the solver allows on every leg
        leaving a stop (:meth:`planner.tours.TourProblem.build`: a bound, so time windows and longest tours hold
        for the turns the robot makes)."""
        cost = self._priced_cost("the turns at the stops")
        return float(move_duration_s(math.pi, cost.turn_rate_radps, DEFAULT_YAW_ACCEL_RADPS2))

    def tour_interval(self, points: Any, extra_mean_j: float = 0.0, *, arrived_from: int | None = None
                      ) -> RouteEnergyInterval:
        """The energy distribution of driving the legs ``points[0] -> points[1] -> ...`` in one run: what the robot
        drives, the legs joined into one route priced by :func:`planner.route_price.price_route` (the turn in place
        at every stop between two legs included, and its stop-and-go where the robot leaves on the heading it
        came: it stops to serve every stop; from a free heading at ``points[0]``, none after the last).

        The spreads of one ground add linearly along the whole route; grounds combine by the root of
        the sum of squares. ``extra_mean_j`` (e.g. the sites' service energy) is added to the mean.
        ``arrived_from``: the point the robot came to ``points[0]`` from (e.g. the stop before a charger, for the
        segment that leaves it): the turn at ``points[0]`` is then counted too (the route from ``arrived_from``
        less its first leg).

        Raises
        ------
        InvalidParameterError
            A leg that no route joins; prices without their cost.
        """
        idx = [int(p) for p in np.asarray(points, dtype=np.int64).ravel()]
        if len(idx) < 2:
            return RouteEnergyInterval(float(extra_mean_j), 0.0, {})
        if arrived_from is None:
            mean, per_ground = self._joined(idx)
        else:
            before = [int(arrived_from), idx[0]]
            (mean, per_ground), (lead, lead_ground) = self._joined(before + idx[1:]), self._joined(before)
            mean, per_ground = mean - lead, _difference(per_ground, lead_ground)
        dofs = [self._dof(g) for g in range(len(self.ground_labels))]
        return RouteEnergyInterval.from_ground_spreads(max(mean, 0.0) + float(extra_mean_j), per_ground,
                                                       self.ground_labels, dofs)

    def turn_interval(self, before: int, at: int, after: int) -> RouteEnergyInterval:
        """The energy distribution of the turn in place at point ``at`` between the legs ``before -> at`` and
        ``at -> after``: the two legs joined less each alone (:func:`planner.route_price.price_route` of each)."""
        (both, both_g), (a, a_g), (b, b_g) = (self._joined([before, at, after]), self._joined([before, at]),
                                              self._joined([at, after]))
        dofs = [self._dof(g) for g in range(len(self.ground_labels))]
        return RouteEnergyInterval.from_ground_spreads(max(both - a - b, 0.0), _difference(both_g, a_g + b_g),
                                                       self.ground_labels, dofs)

    def _joined(self, idx: list[int]) -> tuple[float, np.ndarray]:
        """The mean (J) and the per-ground linear spreads (J) of the legs ``idx[0] -> idx[1] -> ...`` joined."""
        cost = self._priced_cost("a tour")
        ways = [self.waypoints[a][b] for a, b in zip(idx[:-1], idx[1:]) if a != b]
        if any(w is None for w in ways):
            raise InvalidParameterError(f"the tour {idx!r} uses a leg that no route joins")
        if not ways:
            return 0.0, np.zeros(len(self.ground_labels))
        pts = np.vstack([ways[0]] + [w[1:] for w in ways[1:]])
        price = price_route(cost, pts, interval=cost.has_interval, segment_cache=self._walked)
        index = {label: g for g, label in enumerate(self.ground_labels)}
        per_ground = np.zeros(len(self.ground_labels))
        for label, sd in price.sd_by_ground_j.items():
            per_ground[index[label]] = sd
        mean = price.mean_j
        # the robot stops at every stop to serve it: where it arrives and leaves on one heading the joined route
        # drives through, so the stop-and-go there is added (the turn table's column 0, its spread too)
        stops = np.cumsum([len(w) - 1 for w in ways[:-1]]).astype(np.int64)  # where one leg ends and the next starts
        angles, _ = cost.turn_energies_j(pts)
        through = stops[angles[stops] <= COLLINEAR_TOL_RAD]
        if through.size:
            xy = pts[through]
            r, c = cost.terrain.rowcol(xy[:, 0], xy[:, 1])
            rows = np.asarray(cost.ground_rows)[r, c]
            mean += float(np.sum(cost.stop_go_at(rows)))
            if cost.has_interval:
                for row in rows.tolist():
                    per_ground[index[self.ground_labels[row]]] += float(cost.tables.turn_sd_table_j[row, 0])
        return mean, per_ground


def _heading_change_rad(arriving: np.ndarray, leaving: np.ndarray) -> float:
    """The heading change (rad, in [0, pi]) where the leg ``arriving`` ends and the leg ``leaving`` starts (their
    last and first segments of positive length)."""
    a, b = np.diff(arriving, axis=0), np.diff(leaving, axis=0)
    a, b = a[np.hypot(a[:, 0], a[:, 1]) > 0][-1], b[np.hypot(b[:, 0], b[:, 1]) > 0][0]
    change = math.atan2(b[1], b[0]) - math.atan2(a[1], a[0])
    return abs((change + math.pi) % (2.0 * math.pi) - math.pi)


def _difference(whole: np.ndarray, part: np.ndarray) -> np.ndarray:
    """Per-ground linear spreads (J) of a route less those of its part: rounding left at 0 (a ground only the part
    crosses is not crossed, its tail not counted)."""
    out = whole - part
    return np.where(out > 1e-9 * np.maximum(whole, 1.0), out, 0.0)


def price_from(search_cost: EnergyCost, cost: EnergyCost, i: int, xy_m: np.ndarray
               ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, list[np.ndarray | None]]:
    """Price every leg from point ``i`` to the points ``xy_m``: one search on ``search_cost``'s lattice.

    Returns ``(i, mean_j, sd_by_ground_j, duration_s, waypoints)``, one entry per point (the task of
    :func:`price_pairs`, module-level so dask workers import it by reference).
    """
    n, g = xy_m.shape[0], len(cost.tables.ground_labels)
    mean = np.full(n, math.inf)
    sd = np.zeros((n, g))
    dur = np.full(n, math.inf)
    ways: list[np.ndarray | None] = [None] * n
    mean[i], dur[i] = 0.0, 0.0
    paths = Lattice.for_cost(search_cost).paths_from(tuple(xy_m[i]), xy_m)
    index = {label: k for k, label in enumerate(cost.tables.ground_labels)}
    walked: dict = {}  # the legs of one search share most of their segments
    for j, path in enumerate(paths):
        if j == i or not path.found:
            continue
        pts = path.waypoints_m
        if cost.has_interval:
            iv = price_route(cost, pts, interval=True, segment_cache=walked)
            mean[j] = iv.mean_j
            for label, s in iv.sd_by_ground_j.items():
                sd[j, index[label]] = s
        else:
            mean[j] = price_route(cost, pts, interval=False).mean_j
        dur[j] = route_duration_s(pts, cost.speed_mps, cost.turn_rate_radps)
        ways[j] = pts
    return i, mean, sd, dur, ways


def price_pairs(
    cost: EnergyCost,
    xy_m: Any,
    names: Any,
    *,
    risk: float = 0.9,
    compute: Compute | None = None,
) -> PairPrices:
    """Price every ordered pair of points on ``cost``: one lattice search per point, here or on dask.

    Parameters
    ----------
    cost : EnergyCost
        The map's edge costs (with or without an interval).
    xy_m : array_like, shape (P, 2)
        The points (m), already checked to lie on free cells.
    names : sequence of str
        One per point.
    risk : float
        The level the legs are searched at (:meth:`planner.CostTables.at_quantile`; ignored without an interval).
    compute : Compute, optional
        Where the points are priced and whether a bar shows over them
        (:class:`terrawatt_base.dask_client.Compute`; default here; on dask one task per point,
        the costs sent once, as :func:`planner.plan_batch`).

    Returns
    -------
    PairPrices

    Raises
    ------
    InvalidParameterError
        Not an EnergyCost; bad points or names; not a ``Compute``.
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    pts = np.asarray(xy_m, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 1 or not np.all(np.isfinite(pts)):
        raise InvalidParameterError(f"xy_m must be (P, 2) finite points, got shape {pts.shape!r}")
    names = tuple(names)
    if len(names) != pts.shape[0]:
        raise InvalidParameterError(f"names must name the {pts.shape[0]} points, got {len(names)}")
    q = check_risk_level(risk, "risk")
    search = cost.with_tables(cost.tables.at_quantile(q)) if cost.has_interval else cost
    compute = Compute() if compute is None else check_instance("compute", compute, Compute)
    p = pts.shape[0]
    with compute.session() as (client, where):
        t0 = time.perf_counter()
        shared = (search, cost)
        if client is not None:  # the workers get the costs without their caches, once
            shipped = shippable_cost(cost)
            shared = (shipped if search is cost else shippable_cost(search), shipped)
        rows = list(run_tasks([(price_from, (i, pts)) for i in range(p)], client=client, shared=shared,
                              progress=compute.progress, description="legs"))
        n_used = client_worker_count(client)
        elapsed = time.perf_counter() - t0
    return PairPrices(
        names=names, xy_m=pts, mean_j=np.array([r[1] for r in rows]), sd_by_ground_j=np.array([r[2] for r in rows]),
        ground_labels=tuple(cost.tables.ground_labels), duration_s=np.array([r[3] for r in rows]),
        waypoints=tuple(tuple(r[4]) for r in rows), pricing_time_s=elapsed, where=where, n_workers=n_used,
        ground_dof=tuple(float(d) for d in cost.tables.spread_dof), cost=cost)
