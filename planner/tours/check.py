"""The planned tours driven by the mission simulator, Monte Carlo: the share that ends above the reserve, beside Q."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from energy import Battery
from terrawatt_base.checks import check_instance, check_int, check_seed
from terrawatt_base.dask_client import Compute
from terrawatt_base.errors import InvalidParameterError

from ..missions import MonteCarloResult, MonteCarloStudy, simulate_missions_mc
from ..route import Route
from ..route_price import RouteEnergyInterval
from .result import TourResult

__all__ = ["TourCheck", "simulate_tours_mc"]


@dataclass(frozen=True)
class TourCheck:
    """Each robot's tour driven ``n`` times, segment by segment between charges.

    Attributes
    ----------
    risk : float
        The level the tours were planned at.
    runs : dict of str to tuple of MonteCarloResult
        Per robot (with a tour) one Monte Carlo study per segment of its tour: from the depot or a charge to
        the next charge or back (one study without chargers). Mission ``i`` of every segment is one drive of
        the whole tour: the same seed, the same draws (the run-level factors are shared by the whole run). A
        mission that failed in any segment (its study's ``errors``: a library error, a task that failed) fails
        the tour: the shares are over the others, the failed ones counted (:meth:`n_failed`, the summary).
    draw_from : str
        ``"model"`` (the planning model's own distribution) or ``"parameters"`` (the truth simulator).
    """

    risk: float
    runs: dict[str, tuple[MonteCarloResult, ...]]
    draw_from: str

    def completed(self, robot: str) -> np.ndarray:
        """Per mission of ``robot``'s tour, whether it completed in every segment."""
        return np.logical_and.reduce([mc.completed for mc in self.runs[robot]])

    def n_failed(self, robot: str) -> int:
        """How many of ``robot``'s simulated tours failed in some segment (left out of the shares)."""
        return int(np.count_nonzero(~self.completed(robot)))

    def above_reserve(self, robot: str) -> np.ndarray:
        """Per mission of ``robot``'s tour completed in every segment, whether it stayed above the reserve at every
        charger arrival and back at the depot."""
        studies = self.runs[robot]
        done = self.completed(robot)
        below = np.logical_or.reduce([np.asarray(mc.below_reserve, dtype=bool) for mc in studies])
        return ~below[done]

    @property
    def share_above_reserve(self) -> float:
        """The share of the robots' simulated tours that end above the reserve, and above it at every charger arrival
        (over every robot's missions)."""
        flags = [self.above_reserve(name) for name in self.runs]
        n = sum(f.size for f in flags)
        return sum(int(f.sum()) for f in flags) / n if n else math.nan

    def share_above_at_stops(self, robot: str) -> tuple[float, ...]:
        """The share of ``robot``'s missions above the reserve at the end of each segment: at each charger arrival,
        then back at the depot."""
        return tuple(1.0 - mc.p_below_reserve for mc in self.runs[robot])

    def summary(self) -> str:
        """One line per robot (with the share at each charger arrival, where it charges) and the total, beside Q;
        the tours that failed, if any, counted with the first reason."""
        lines = []
        n_failed = 0
        for name, studies in self.runs.items():
            flags = self.above_reserve(name)
            failed = self.n_failed(name)
            n_failed += failed
            tours = f"{studies[0].n} tours" if not failed else f"{flags.size} completed tours"
            line = f"{name}: {100 * flags.mean() if flags.size else math.nan:.1f} % of {tours} end above the reserve"
            if len(studies) > 1:
                at = ", ".join(f"{100 * s:.1f} %" for s in self.share_above_at_stops(name)[:-1])
                line += f" (above it at each charger arrival: {at}; at every one and back)"
            if failed:
                first = next(e for mc in studies for e in mc.errors if e)
                line += f"; {failed} of {studies[0].n} failed (first: {first})"
            lines.append(line)
        failures = f"; {n_failed} tours failed" if n_failed else ""
        lines.append(f"all: {100 * self.share_above_reserve:.1f} % above the reserve at Q = {self.risk:g} "
                     f"(draws from the {self.draw_from}){failures}")
        return "\n".join(lines)


def simulate_tours_mc(result: TourResult, n: int = 1000, *, seed: int | None = 0, draw_from: str | None = None,
                      compute: Compute | None = None) -> TourCheck:
    """Drive each planned tour ``n`` times through :func:`planner.simulate_missions_mc`, its battery charged to full at
    each charging stop.

    With a cost that carries an interval the missions draw from the planning model's own
    distribution (``draw_from="model"``: one factor per ground per tour, the whole tour's
    energy, service included, as priced); otherwise the truth simulator drives the tour's
    route with drawn parameters (service energy not included). A tour with charging stops is
    driven segment by segment (from the depot or a charge to the next charge or back), each
    segment from the charge it starts with (the initial one, then full) and with the same seed, so
    mission ``i`` of every segment draws the same factors: one drive of the whole tour.
    ``compute`` says where the missions run (:class:`terrawatt_base.dask_client.Compute`, default here).

    Raises
    ------
    InvalidParameterError
        Not a planned TourResult; ``n < 1``.
    """
    if not isinstance(result, TourResult) or result.cost is None:
        raise InvalidParameterError(f"result must be a TourResult from plan_tour, got {type(result).__name__!r}")
    n = check_int("n", n, low=1)
    seed = check_seed(seed)
    mode = draw_from or ("model" if result.cost.has_interval else "parameters")
    compute = Compute() if compute is None else check_instance("compute", compute, Compute)
    runs: dict[str, tuple[MonteCarloResult, ...]] = {}
    with compute.session() as (client, where):  # one cluster for every segment of every tour
        each = compute if client is None else Compute(client=client, where=where, progress=compute.progress)
        for k, tour in enumerate(result.tours):
            if not tour.legs:
                continue
            studies = []
            for route, battery, forecast in _segments(result, k):
                studies.append(simulate_missions_mc(
                    result.terrain, route, battery, MonteCarloStudy(n, seed=None if seed is None else seed + k,
                                                                    draw_from=mode),
                    cost=result.cost, forecast=forecast if mode == "model" else None, compute=each))
            runs[tour.robot] = tuple(studies)
    return TourCheck(result.risk, runs, mode)


def _segments(result: TourResult, robot: int) -> list[tuple[Route, Battery, RouteEnergyInterval]]:
    """Each segment of the robot's tour between charges: its route, its battery (full after a charge) and its energy
    distribution over every ground of the tour (zero spread where it does not go), so that every segment draws the
    same factors in the same order."""
    tour = result.tours[robot]
    if not tour.charging_stops:
        return [(result.tour_route(robot), tour.battery, tour.energy)]
    whole = tour.energy
    full = dataclasses.replace(tour.battery, initial_soc=1.0)
    out, first = [], 0
    for s, (end, seg) in enumerate(zip([*tour.charging_stops, len(tour.legs) - 1], tour.segments)):
        by = {g: seg.sd_by_ground_j.get(g, 0.0) for g in whole.sd_by_ground_j}
        forecast = RouteEnergyInterval(seg.mean_j, seg.sd_j, by, seg.dof, {g: whole.ground_dof(g) for g in by})
        out.append((result.tour_route(robot, slice(first, end + 1)), tour.battery if s == 0 else full, forecast))
        first = end + 1
    return out
