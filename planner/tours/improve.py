"""The improvement step priced as driven: sites inserted into (or swapped into) the chosen tours, every candidate
priced as the robot drives it.

The routing solver chooses the tours on a matrix whose arcs carry an *allowance* for the turn at the stop they leave
(:mod:`planner.tours.solver`); the real turns differ both ways, so the tours it keeps often leave energy unused, or its
optimum breaks its budget once driven and is cut back. This step starts from the tours that hold and, deterministically:

1. **inserts** a left-out site at its best position (the highest value first, ties by the least added energy at Q);
2. where none fits, **swaps** a chosen site for a left-out one of more value (the largest gain first);
3. where neither does, **relocates** a stop or **reverses** a run of stops (2-opt) within each tour while that lowers
   its energy at Q, and keeps the new orders only if an insertion or a swap then fits.

Every candidate is priced as :meth:`PairPrices.tour_interval` prices a tour — the legs' own prices, plus at every
stop the turn in place from the arriving leg's last segment to the leaving leg's first (the joined route's turn less
the stop-and-go the two legs already hold), each segment between charges with its service and waiting energy, one
ground's spreads adding along it — but in bulk (:class:`DrivenPricer`, equal to ``tour_interval`` to rounding: the
tests check it); times follow the reported timeline (the legs' stop-turn-go durations, the pivots at the stops, the
service, the waits, :func:`planner.tours.solver.walk_timeline`). A candidate is kept only if every segment of the
tour it touches holds at Q and every site starts within its window and the robot is back within its longest tour.
The tours it changes are priced again one by one by :meth:`PairPrices.tour_interval`, and a tour that would not hold
(never seen: the two prices agree) goes back to the solver's: no tour is returned above its budget at Q.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from energy.models.forecast import predictive_quantile
from energy.profiles import COLLINEAR_TOL_RAD, DEFAULT_YAW_ACCEL_RADPS2, move_duration_s
from terrawatt_base.errors import InvalidParameterError

from ..edge_cost import EnergyCost
from .pricing import PairPrices
from .solver import TourProblem, walk_timeline

__all__ = ["DrivenPricer", "ImproveOutcome", "improve_tours"]

_REL_TOL = 1e-9  # an energy lower by less than this share is no lower (the descent stops)


def _leg_ends(ways: np.ndarray) -> tuple[float, float, tuple[float, float]]:
    """The heading (rad) of a leg's first and last segments of positive length, and its last waypoint."""
    d = np.diff(ways, axis=0)
    d = d[np.hypot(d[:, 0], d[:, 1]) > 0]
    end = (float(ways[-1, 0]), float(ways[-1, 1]))
    if not len(d):
        return math.nan, math.nan, end
    return math.atan2(d[0, 1], d[0, 0]), math.atan2(d[-1, 1], d[-1, 0]), end


@dataclass(frozen=True, eq=False)
class DrivenPricer:
    """Tours priced in bulk as the robot drives them: the legs of :class:`PairPrices` and the turns at the stops.

    A tour's joined route (:meth:`PairPrices.tour_interval`) is its legs, each priced from rest to rest, and at every
    stop between two legs the turn in place from the heading of the arriving leg's last segment to that of the leaving
    leg's first: :meth:`EnergyCost.turn_energy_at` at the stop's ground, less the stop-and-go the two legs' own prices
    hold (none where it leaves on the heading it came: it still stops to serve). Its spread likewise
    (:meth:`EnergyCost.turn_spread_at` less the stop-and-go's). Build it with :meth:`of`.

    Attributes
    ----------
    prices : PairPrices
        The legs.
    q : float
        The level the tours are priced at.
    leave_rad, arrive_rad : ndarray, shape (P, P)
        The heading of each leg's first and last segments (NaN where no route).
    stop_row : ndarray of int, shape (P, P)
        The cost's table row (ground) under leg ``i -> j``'s last waypoint: where the turn at ``j`` is priced.
    ground_dof : ndarray, shape (G,)
        Each ground's degrees of freedom.
    """

    prices: PairPrices
    q: float
    leave_rad: np.ndarray
    arrive_rad: np.ndarray
    stop_row: np.ndarray
    ground_dof: np.ndarray

    @classmethod
    def of(cls, prices: PairPrices, q: float) -> DrivenPricer:
        """The pricer of tours of ``prices``' legs at level ``q`` (prices made by :func:`price_pairs`)."""
        cost = prices.cost
        if not isinstance(cost, EnergyCost):
            raise InvalidParameterError("these prices carry no cost to price tours with (make them with price_pairs, "
                                        "which keeps the cost the legs were priced on)", parameter="prices")
        n = len(prices)
        leave, arrive = np.full((n, n), math.nan), np.full((n, n), math.nan)
        ends = np.zeros((n, n, 2))
        for i in range(n):
            for j in range(n):
                ways = prices.waypoints[i][j]
                if i != j and ways is not None:
                    leave[i, j], arrive[i, j], ends[i, j] = _leg_ends(np.asarray(ways, dtype=float))
                else:
                    ends[i, j] = prices.xy_m[j]
        r, c = cost.terrain.rowcol(ends[..., 0].ravel(), ends[..., 1].ravel())
        rows = np.asarray(cost.ground_rows)[r, c].reshape(n, n)
        dof = (np.array(prices.ground_dof, dtype=float) if prices.ground_dof
               else np.full(len(prices.ground_labels), math.inf))
        return cls(prices, float(q), leave, arrive, rows.astype(np.int64), dof)

    def turns(self, before: np.ndarray, at: np.ndarray, after: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The turns at ``at`` between ``before -> at`` and ``at -> after`` (arrays of point indices, one shape):
        the energy they add to the two legs' prices (J), the ground row they are on, the spread they add there (J)
        and the pivot's time (s)."""
        cost = self.prices.cost
        angle = self.leave_rad[at, after] - self.arrive_rad[before, at]
        angle = np.abs((angle + math.pi) % (2.0 * math.pi) - math.pi)
        angle = np.where(np.isfinite(angle), angle, 0.0)  # no route: the leg's own price is inf
        turning = angle > COLLINEAR_TOL_RAD
        rows = self.stop_row[before, at]
        mean = np.where(turning, cost.turn_energy_at(rows, angle) - cost.stop_go_at(rows), 0.0)
        if cost.has_interval:
            spread = cost.turn_spread_at(rows, angle).reshape(angle.shape)
            spread = np.where(turning, spread - cost.tables.turn_sd_table_j[rows, 0], 0.0)
        else:
            spread = np.zeros(angle.shape)
        pivot = np.where(turning, move_duration_s(angle, cost.turn_rate_radps, DEFAULT_YAW_ACCEL_RADPS2), 0.0)
        return mean, rows, spread, pivot

    def segments(self, seqs: np.ndarray, chargers: np.ndarray, extra_j: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each segment's mean (J), per-ground spread (J) and ``q`` quantile (J) of the tours ``seqs``.

        Parameters
        ----------
        seqs : ndarray of int, shape (N, M)
            Tours of one length, ``depot, stops..., depot`` (point indices), cut into segments at the points where
            ``chargers`` (bool per point) is set: a segment leaving a charger turns there first.
        extra_j : ndarray, shape (N, M - 1), optional
            Energy added to the segment of each leg (J; e.g. the service and the waiting at the point it arrives at).

        Returns
        -------
        mean_j : ndarray, shape (N, S)
        sd_by_ground_j : ndarray, shape (N, S, G)
        quantile_j : ndarray, shape (N, S)
            ``S`` the most segments of a tour; a tour with fewer has zeros in the rest.
        """
        seqs = np.asarray(seqs, dtype=np.int64)
        n, m = seqs.shape
        a, b = seqs[:, :-1], seqs[:, 1:]
        leg_mean = self.prices.mean_j[a, b]
        leg_sd = self.prices.sd_by_ground_j[a, b]
        leg_mean = leg_mean + (0.0 if extra_j is None else extra_j)
        at_charger = chargers[seqs[:, :-1]].copy()
        at_charger[:, 0] = False  # the depot
        seg = np.cumsum(at_charger, axis=1)  # the segment of each leg (its leaving point's)
        n_seg = int(seg.max()) + 1 if seg.size else 1
        if m > 2:
            t_mean, t_row, t_sd, _ = self.turns(seqs[:, :-2], seqs[:, 1:-1], seqs[:, 2:])
            leg_mean = leg_mean.copy()
            leg_mean[:, 1:] += t_mean
            leg_sd = leg_sd.copy()
            np.add.at(leg_sd, (np.arange(n)[:, None], np.arange(1, m - 1)[None, :], t_row), t_sd)
        onehot = (seg[..., None] == np.arange(n_seg)).astype(float)
        with np.errstate(invalid="ignore"):
            mean = np.einsum("nj,njs->ns", np.where(np.isfinite(leg_mean), leg_mean, 0.0), onehot)
        mean = np.where(np.einsum("nj,njs->ns", (~np.isfinite(leg_mean)).astype(float), onehot) > 0, np.inf,
                        np.maximum(mean, 0.0))
        sd = np.einsum("njg,njs->nsg", leg_sd, onehot)
        sd = np.where(sd > 1e-12 * np.maximum(np.abs(sd).max(axis=2, keepdims=True), 1.0), sd, 0.0)
        dof = np.where(sd > 0, self.ground_dof, np.inf).min(axis=2)
        z = np.zeros(dof.shape)
        for d in np.unique(dof):  # a few distinct degrees of freedom: one quantile each
            z[dof == d] = predictive_quantile(self.q, float(d))
        # at least 0, as RouteEnergyInterval.quantile_j reads a route's energy (censored: never negative)
        return mean, sd, np.maximum(mean + z * np.sqrt(np.sum(sd ** 2, axis=2)), 0.0)


@dataclass(frozen=True)
class ImproveOutcome:
    """The tours after the improvement step: each robot's stops, the sites it added (an insertion adds one; a swap
    none), the swaps it made, the value before and after, and its time (s)."""

    tours: list[list[int]]
    added: int
    swapped: int
    value_before: float
    value_after: float
    time_s: float


class _Step:
    """One instance of the step: what each candidate tour of each robot is priced and timed with."""

    def __init__(self, pricer: DrivenPricer, problem: TourProblem, value: np.ndarray, service_time_s: np.ndarray,
                 window_s: np.ndarray, max_duration_s: np.ndarray) -> None:
        self.pricer, self.problem = pricer, problem
        n = len(pricer.prices)
        self.value = np.asarray(value, dtype=float)
        self.service_j = np.asarray(problem.service_j, dtype=float)
        self.service_s = np.asarray(service_time_s, dtype=float)
        self.window_s = np.asarray(window_s, dtype=float)
        self.shift_s = np.asarray(max_duration_s, dtype=float)
        self.drive_s = np.asarray(pricer.prices.duration_s, dtype=float)
        self.chargers = np.zeros(n, dtype=bool)
        self.chargers[problem.charger_points] = True

    def price(self, robot: int, stops_rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Whether each candidate tour of ``robot`` (rows of stops, one length) holds — every segment within its
        budget at Q, every site started in its window, back within the longest tour — and its energy at Q (J, the
        segments' quantiles summed; inf where it does not hold)."""
        d = int(self.problem.depot_points[robot])
        n = stops_rows.shape[0]
        seqs = np.hstack([np.full((n, 1), d), stops_rows, np.full((n, 1), d)]).astype(np.int64)
        m = seqs.shape[1]
        if m == 2:
            return np.ones(n, dtype=bool), np.zeros(n)
        _, _, _, pivot = self.pricer.turns(seqs[:, :-2], seqs[:, 1:-1], seqs[:, 2:])
        t = np.zeros(n)
        on_time = np.ones(n, dtype=bool)
        extra = np.zeros((n, m - 1))
        standby = float(self.problem.standby_w[robot])
        for k in range(1, m - 1):  # the timeline (walk_timeline's rule, in bulk)
            p = seqs[:, k]
            arrival = t + self.drive_s[seqs[:, k - 1], p]
            start = np.maximum(arrival, self.window_s[p, 0])
            on_time &= start <= self.window_s[p, 1]
            extra[:, k - 1] = self.service_j[p] + standby * (start - arrival)
            t = start + self.service_s[p] + pivot[:, k - 1]
        back = t + self.drive_s[seqs[:, -2], d]
        on_time &= back <= self.shift_s[robot]
        _, _, need = self.pricer.segments(seqs, self.chargers, extra)
        budget = np.full(need.shape, float(self.problem.full_budget_j[robot]))
        budget[:, 0] = float(self.problem.budget_j[robot])
        n_seg = 1 + self.chargers[seqs[:, 1:-1]].sum(axis=1)
        exists = np.arange(need.shape[1])[None, :] < n_seg[:, None]
        holds = on_time & np.all(~exists | (need <= budget), axis=1)
        return holds, np.where(holds, need.sum(axis=1), np.inf)

    def energy(self, robot: int, stops: list[int]) -> float:
        """The energy at Q of one tour (inf where it does not hold)."""
        return float(self.price(robot, np.array([stops], dtype=np.int64).reshape(1, len(stops)))[1][0])

    def best_insertion(self, tours: list[list[int]], left: list[int]) -> tuple[int, list[int], float] | None:
        """The insertion of a left-out site that holds: the highest value, ties by the least added energy at Q, then
        the first robot and position. ``(robot, new stops, added energy)`` or None."""
        best: tuple[float, float] | None = None
        out = None
        for r, stops in enumerate(tours):
            base = self.energy(r, stops)
            cands = _insertions(stops, left)
            if not len(cands):
                continue
            holds, energy = self.price(r, cands)
            for k in np.flatnonzero(holds):
                site = int(np.setdiff1d(cands[k], stops)[0]) if stops else int(cands[k][0])
                key = (-self.value[site], energy[k] - base)
                if best is None or key < best:
                    best, out = key, (r, cands[k].tolist(), float(energy[k] - base))
        return out

    def best_swap(self, tours: list[list[int]], left: list[int]) -> tuple[int, list[int], int, int] | None:
        """A chosen site swapped for a left-out one of more value, the new one at its best position, the tour holding:
        the largest gain, ties by the least added energy. ``(robot, new stops, site out, site in)`` or None."""
        best: tuple[float, float] | None = None
        out = None
        for r, stops in enumerate(tours):
            base = self.energy(r, stops)
            for i, s in enumerate(stops):
                if self.chargers[s]:
                    continue
                better = [u for u in left if self.value[u] > self.value[s]]
                if not better:
                    continue
                rest = stops[:i] + stops[i + 1:]
                cands = _insertions(rest, better)
                holds, energy = self.price(r, cands)
                for k in np.flatnonzero(holds):
                    u = int(np.setdiff1d(cands[k], rest)[0]) if rest else int(cands[k][0])
                    key = (-(self.value[u] - self.value[s]), energy[k] - base)
                    if best is None or key < best:
                        best, out = key, (r, cands[k].tolist(), s, u)
        return out

    def best_charged_insertion(self, tours: list[list[int]], left: list[int]) -> tuple[int, list[int]] | None:
        """A left-out site inserted together with a charging stop (one the fleet has visits left at), both at their
        best positions, the tour holding: the highest value, ties by the least added energy. ``(robot, new stops)``
        or None."""
        points = self.problem.charger_points.tolist()
        visits = self.problem.charger_visits.tolist()
        used = {c: sum(s == c for t in tours for s in t) for c in points}
        best: tuple[float, float] | None = None
        out = None
        for r, stops in enumerate(tours):
            base = self.energy(r, stops)
            for c, most in zip(points, visits):
                if used[c] >= most:
                    continue
                for pos in range(len(stops) + 1):
                    with_c = stops[:pos] + [c] + stops[pos:]
                    if (pos and stops[pos - 1] == c) or (pos < len(stops) and stops[pos] == c):
                        continue  # two stops in a row at one charger are one
                    cands = _insertions(with_c, left)
                    holds, energy = self.price(r, cands)
                    for k in np.flatnonzero(holds):
                        site = next(int(p) for p in cands[k] if p in left)
                        key = (-self.value[site], energy[k] - base)
                        if best is None or key < best:
                            best, out = key, (r, cands[k].tolist())
        return out

    def shortened(self, robot: int, stops: list[int]) -> list[int]:
        """``stops`` reordered by relocations of one stop and reversals of a run (2-opt), each the one that lowers the
        tour's energy at Q most while it holds, until none lowers it."""
        stops = list(stops)
        energy = self.energy(robot, stops)
        while len(stops) >= 2:
            cands = _reorders(stops)
            if not len(cands):
                break
            holds, e = self.price(robot, cands)
            k = int(np.argmin(e))
            if not holds[k] or not e[k] < energy * (1.0 - _REL_TOL):
                break
            stops, energy = cands[k].tolist(), float(e[k])
        return stops


def _insertions(stops: list[int], sites: list[int]) -> np.ndarray:
    """Every tour of ``stops`` with one of ``sites`` inserted at any position: rows of ``len(stops) + 1`` points."""
    base = np.asarray(stops, dtype=np.int64)
    n = len(stops)
    rows = []
    for u in sites:
        for pos in range(n + 1):
            rows.append(np.concatenate([base[:pos], [u], base[pos:]]))
    return np.array(rows, dtype=np.int64).reshape(len(rows), n + 1)


def _reorders(stops: list[int]) -> np.ndarray:
    """Every tour of ``stops`` with one stop moved elsewhere or one run of stops reversed (2-opt); none with one
    charger twice in a row (two stops in a row at one point are one, and its turn would go unpriced)."""
    base = list(stops)
    seen, rows = {tuple(base)}, []
    n = len(base)
    for i in range(n):
        rest = base[:i] + base[i + 1:]
        for j in range(n):
            cand = tuple(rest[:j] + [base[i]] + rest[j:])
            if cand not in seen:
                seen.add(cand)
                rows.append(cand)
    for i in range(n - 1):
        for j in range(i + 2, n + 1):
            cand = tuple(base[:i] + base[i:j][::-1] + base[j:])
            if cand not in seen:
                seen.add(cand)
                rows.append(cand)
    rows = [r for r in rows if all(a != b for a, b in zip(r, r[1:]))]
    return np.array(rows, dtype=np.int64).reshape(len(rows), n)


def improve_tours(prices: PairPrices, problem: TourProblem, tours: list[list[int]], *, value: Any,
                  candidates: Any, service_time_s: Any = None, window_s: Any = None,
                  max_duration_s: Any = None) -> ImproveOutcome:
    """The improvement step priced as driven on the solver's ``tours`` (module docstring).

    Parameters
    ----------
    prices : PairPrices
        The legs (with their cost).
    problem : TourProblem
        The problem the tours were solved on: depots, budgets, level, service energy, standby power, chargers.
    tours : list of list of int
        Each robot's stops (point indices), each holding at Q.
    value : array_like, shape (P,)
        Each point's value.
    candidates : array_like of int
        The sites that may be visited (the others stay out).
    service_time_s, window_s : array_like, optional
        Each point's service time (s) and window ``(earliest, latest)`` (s; inf: none): the timeline the result
        reports (default the problem's whole seconds).
    max_duration_s : array_like, optional
        Each robot's longest tour (s; inf or None: none; default the problem's).

    Returns
    -------
    ImproveOutcome
    """
    t0 = time.perf_counter()
    shift = (problem.shift_s.astype(float) if max_duration_s is None
             else np.array([math.inf if v is None else float(v) for v in max_duration_s]))
    shift = np.where(shift >= 10**12, math.inf, shift)
    window = problem.window_s.astype(float) if window_s is None else np.asarray(window_s, dtype=float)
    window = np.where(window >= 10**12, math.inf, window)
    step = _Step(DrivenPricer.of(prices, problem.risk), problem, value,
                 problem.service_s.astype(float) if service_time_s is None else service_time_s, window, shift)
    start = [list(map(int, t)) for t in tours]
    current = [list(t) for t in start]
    before = float(sum(step.value[s] for t in start for s in t))
    chosen = {s for t in current for s in t}
    left = [int(s) for s in candidates if int(s) not in chosen and step.value[int(s)] > 0]
    added = swapped = 0

    def insert_or_swap(tours: list[list[int]]) -> tuple[int, list[int], str] | None:
        """The best insertion of a left-out site into ``tours``, else the best swap (``left`` updated), or None."""
        move = step.best_insertion(tours, left)
        if move is not None:
            r, new, _ = move
            left.remove(next(s for s in new if s not in tours[r]))
            return r, new, "added"
        swap = step.best_swap(tours, left)
        if swap is None:
            return None
        r, new, out, into = swap
        left.remove(into)
        left.append(out)
        return r, new, "swapped"

    while left:
        done = insert_or_swap(current)
        charged = step.best_charged_insertion(current, left) if done is None and problem.has_chargers else None
        if charged is not None:
            r, new = charged
            left.remove(next(s for s in new if s in left))
            done = r, new, "added"
        if done is None:
            shorter = [step.shortened(r, t) for r, t in enumerate(current)]
            if shorter == current:
                break
            done = insert_or_swap(shorter)
            if done is None:
                break
        r, new, kind = done
        current[r] = new
        added, swapped = added + (kind == "added"), swapped + (kind == "swapped")
    for r, stops in enumerate(current):  # priced again one by one, as the result reports them
        if stops != start[r] and not _holds_as_reported(prices, step, r, stops):
            current[r] = start[r]
    after = float(sum(step.value[s] for t in current for s in t))
    if after < before:  # reverting may lose a swap's partner: keep the solver's tours
        current, after = start, before
    return ImproveOutcome(current, added, swapped, before, after, time.perf_counter() - t0)


def _holds_as_reported(prices: PairPrices, step: _Step, robot: int, stops: list[int]) -> bool:
    """Whether ``robot``'s tour holds at Q priced by :meth:`PairPrices.tour_interval` segment by segment (its service
    and the waits of the reported timeline) and is on time."""
    problem = step.problem
    d = int(problem.depot_points[robot])
    seq = [d, *stops, d]
    ends = [np.array(part, dtype=np.int64) for part in (seq[:-2], seq[1:-1], seq[2:])]
    turns = [float(t) for t in step.pricer.turns(*ends)[3]]
    arrivals, starts, back = walk_timeline(step.drive_s, step.service_s, step.window_s, seq, turns)
    if any(s > step.window_s[p, 1] for p, s in zip(stops, starts)) or back > step.shift_s[robot]:
        return False
    waits = [float(problem.standby_w[robot]) * (s - a) for a, s in zip(arrivals, starts)]
    first, extra, came = 0, 0.0, None
    for k in range(1, len(seq)):
        p = seq[k]
        extra += float(problem.service_j[p]) + (waits[k - 1] if k - 1 < len(waits) else 0.0)
        if step.chargers[p] or k == len(seq) - 1:
            budget = problem.budget_j[robot] if first == 0 else problem.full_budget_j[robot]
            if prices.tour_interval(seq[first:k + 1], extra, arrived_from=came).quantile_j(step.pricer.q) > budget:
                return False
            first, extra, came = k, 0.0, seq[k - 1]
    return True
