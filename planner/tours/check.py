"""The planned tours driven by the mission simulator, Monte Carlo: the share that ends above the reserve, beside Q."""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from energy import Battery
from terrawatt_base.answer import fmt_fixed, write_answer
from terrawatt_base.atomic import json_finite, save_figure
from terrawatt_base.checks import check_instance, check_int, check_seed
from terrawatt_base.dask_client import Compute
from terrawatt_base.errors import InvalidParameterError
from terrawatt_base.formats import result_document, write_result_json
from terrawatt_base.plot_target import check_ax, check_plot_target, new_figure

from ..missions import (
    MissionDistributions,
    MissionDrive,
    MissionTruth,
    MonteCarloResult,
    MonteCarloStudy,
    simulate_missions_mc,
)
from ..route import Route
from ..route_price import RouteEnergyInterval
from .result import TourResult

__all__ = ["TourCheck", "simulate_tours_mc", "TOUR_CHECK_FORMAT_VERSION"]

#: Version of tour_check.json (format ``terrawatt-tour-check``, :meth:`TourCheck.to_dict`).
TOUR_CHECK_FORMAT_VERSION = 1


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
    stops : dict of str to tuple of str
        Per robot, where each segment of its tour ends: its charging stops' names, then its depot's. A robot
        not named here has its stops named ``"stop 1"``, ... and ``"depot"`` (:meth:`stop_names`).
    map_label : str
        How the map is named.

    :meth:`summary` prints it, :meth:`to_dict` is tour_check.json, :meth:`plot` draws the share above the
    reserve at each stop beside Q, :meth:`write` writes the JSON and the figure.
    """

    risk: float
    runs: dict[str, tuple[MonteCarloResult, ...]]
    draw_from: str
    stops: dict[str, tuple[str, ...]] = field(default_factory=dict)
    map_label: str = "map"

    def __post_init__(self) -> None:
        if self.draw_from not in ("model", "parameters"):
            raise InvalidParameterError(f"draw_from must be 'model' or 'parameters', got {self.draw_from!r}")
        for name, studies in self.runs.items():
            if not studies or not all(isinstance(mc, MonteCarloResult) for mc in studies):
                raise InvalidParameterError(f"runs[{name!r}] must be one MonteCarloResult or more, got {studies!r:.80}")
            if len({mc.n for mc in studies}) != 1:
                raise InvalidParameterError(f"runs[{name!r}] must drive every segment as often, got "
                                            f"{[mc.n for mc in studies]!r}")
        for name, places in self.stops.items():
            if name not in self.runs or len(places) != len(self.runs[name]):
                raise InvalidParameterError(f"stops[{name!r}] must name the end of each of the robot's "
                                            f"{len(self.runs.get(name, ()))} segments, got {places!r}")

    def stop_names(self, robot: str) -> tuple[str, ...]:
        """Where each segment of ``robot``'s tour ends: its charging stops, then back at its depot."""
        k = len(self.runs[robot])
        return self.stops.get(robot) or (*(f"stop {j + 1}" for j in range(k - 1)), "depot")

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

    def share_of(self, robot: str) -> float:
        """The share of ``robot``'s completed tours above the reserve at every charger arrival and back (NaN if none
        completed)."""
        flags = self.above_reserve(robot)
        return float(flags.mean()) if flags.size else math.nan

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
        if not self.runs:
            return f"no tour to drive at Q = {self.risk:g}: no robot visits a site"
        lines = []
        n_failed = 0
        for name, studies in self.runs.items():
            failed = self.n_failed(name)
            n_failed += failed
            tours = f"{studies[0].n} tours" if not failed else f"{studies[0].n - failed} completed tours"
            line = f"{name}: {100 * self.share_of(name):.1f} % of {tours} end above the reserve"
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

    def to_dict(self) -> dict[str, Any]:
        """tour_check.json: a ``terrawatt-tour-check`` result document (``format_version``
        :data:`TOUR_CHECK_FORMAT_VERSION`), strict JSON (NaN as ``None``).

        The level Q, what was drawn, the share above the reserve over every robot and the failed tours; per robot
        (with a tour) its missions ``n`` and failed tours, its share above the reserve at every stop, where each
        segment ends (``stops``) and the share above it there (``share_above_at_stops``), and each segment's Monte
        Carlo study as its own ``terrawatt-monte-carlo`` document without the per-sample columns
        (:meth:`planner.MonteCarloResult.to_dict` with ``samples=False``: energy percentiles, the reserve risk and
        its interval, the battery, the forecast).
        """
        robots = [{"robot": name, "n": studies[0].n, "n_failed": self.n_failed(name),
                   "share_above_reserve": self.share_of(name), "stops": list(self.stop_names(name)),
                   "share_above_at_stops": list(self.share_above_at_stops(name)),
                   "segments": [mc.to_dict(samples=False) for mc in studies]}
                  for name, studies in self.runs.items()]
        return json_finite(result_document("tour-check", TOUR_CHECK_FORMAT_VERSION, {
            "map": self.map_label, "risk": self.risk, "draw_from": self.draw_from,
            "share_above_reserve": self.share_above_reserve,
            "n_failed": sum(self.n_failed(name) for name in self.runs), "robots": robots}))

    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None) -> Path | Any:
        """Per robot, the share of its tours above the reserve at each stop (a bar per charger arrival and one back
        at the depot), beside the level Q the tours were planned at; the legend gives each robot's share above it at
        every stop and its failed tours.

        Give exactly one of ``path`` (write a PNG atomically and return the path) or ``ax`` (a matplotlib Axes to
        draw into; nothing is written and it is returned).

        Raises
        ------
        InvalidParameterError
            Both or neither of ``path`` and ``ax``; a bad ``path`` or ``ax``.
        """
        target = check_plot_target(path, ax)
        n_bars = sum(len(studies) + 1 for studies in self.runs.values())
        if target is None:
            axes = check_ax(ax)
        else:
            fig, axes = new_figure((max(6.0, 1.5 + 0.55 * n_bars), 4.0))
        ticks: list[float] = []
        labels: list[str] = []
        x0 = 0
        for k, (name, studies) in enumerate(self.runs.items()):
            shares = 100.0 * np.array(self.share_above_at_stops(name), dtype=float)
            x = x0 + np.arange(shares.size)
            failed = self.n_failed(name)
            label = (f"{name}: {fmt_fixed(100 * self.share_of(name))} % above at every stop"
                     + (f"; {failed} of {studies[0].n} tours failed" if failed else ""))
            bars = axes.bar(x, np.nan_to_num(shares), width=0.7, color=f"C{k}", label=label)
            axes.bar_label(bars, labels=[fmt_fixed(s) for s in shares], fontsize=7)
            ticks += x.tolist()
            labels += self.stop_names(name)
            x0 += shares.size + 1
        axes.axhline(100.0 * self.risk, color="k", ls="--", lw=1, label=f"planned at Q = {self.risk:g}")
        axes.set_xticks(ticks, labels, rotation=45 if len(ticks) > 8 else 0, fontsize=8)
        axes.set_ylim(0.0, 100.0 + 8.0 * (len(self.runs) + 2))  # room above the bars for the legend
        axes.set_yticks(np.arange(0, 101, 20))
        axes.set_xlabel("arrival at")
        axes.set_ylabel("tours above the reserve (%)")
        n = next(iter(self.runs.values()))[0].n if self.runs else 0
        axes.set_title(f"tours on {self.map_label} driven {n} times (draws from the {self.draw_from}):\n"
                       "the share above the reserve at each stop", fontsize=9)
        axes.legend(fontsize=8, loc="upper center")
        if target is None:
            return axes
        fig.tight_layout()
        return save_figure(fig, target)

    def write(self, out_dir: str | os.PathLike[str], *, on_figure_error: str = "warn") -> list[Path]:
        """Write tour_check.json and (with a tour driven) tour_check.png into ``out_dir``; return the files written
        (a figure that fails warns and is left out)."""
        return write_answer(out_dir, {"tour_check.json": lambda p: write_result_json(p, self.to_dict())},
                            {"tour_check.png": self.plot} if self.runs else {}, on_figure_error=on_figure_error)


def simulate_tours_mc(result: TourResult, n: int = 1000, *, seed: int | None = 0, draw_from: str | None = None,
                      distributions: MissionDistributions | None = None, truth: MissionTruth | None = None,
                      compute: Compute | None = None) -> TourCheck:
    """Drive each planned tour ``n`` times through :func:`planner.simulate_missions_mc`, its battery charged to full at
    each charging stop.

    With a cost that carries an interval the missions draw from the planning model's own
    distribution (``draw_from="model"``: one factor per ground per tour, the whole tour's
    energy, service included, as priced); otherwise the truth simulator drives the tour's
    route with drawn parameters (service energy not included), stopping at every stop as the plan
    prices it — at a site it leaves on the heading it arrived on too (:class:`planner.missions.MissionDrive`'s
    ``stops``), where a route alone would be driven through. A tour with charging stops is
    driven segment by segment (from the depot or a charge to the next charge or back), each
    segment from the charge it starts with (the initial one, then full) and with the same seed, so
    mission ``i`` of every segment draws the same factors: one drive of the whole tour.
    ``distributions`` are the drawn parameters' ranges with ``draw_from="parameters"`` (default
    :class:`planner.missions.MissionDistributions`: a payload of 0–20 kg and a capacity fade of 0–20 % the
    plan did not price, so the share above the reserve measures those draws as much as the plan —
    docs/results.md, "The planner's price against the simulator, without draws"); ``truth`` the robot and
    grounds the truth simulator drives (default the robot and ground parameters the tour's cost was
    priced with, where it keeps them: :meth:`planner.CostSpec.build` with a physics model; else
    ``MissionTruth()``). ``compute`` says where the missions run
    (:class:`terrawatt_base.dask_client.Compute`, default here).

    Raises
    ------
    InvalidParameterError
        Not a planned TourResult; ``n < 1``; ``distributions`` with ``draw_from="model"``; a ``truth`` that is
        not a MissionTruth.
    """
    if not isinstance(result, TourResult) or result.cost is None:
        raise InvalidParameterError(f"result must be a TourResult from plan_tour, got {type(result).__name__!r}")
    n = check_int("n", n, low=1)
    seed = check_seed(seed)
    mode = draw_from or ("model" if result.cost.has_interval else "parameters")
    truth = _priced_truth(result) if truth is None else check_instance("truth", truth, MissionTruth)
    compute = Compute() if compute is None else check_instance("compute", compute, Compute)
    runs: dict[str, tuple[MonteCarloResult, ...]] = {}
    stops: dict[str, tuple[str, ...]] = {}
    with compute.session() as (client, where):  # one cluster for every segment of every tour
        each = compute if client is None else Compute(client=client, where=where, progress=compute.progress)
        for k, tour in enumerate(result.tours):
            if not tour.legs:
                continue
            studies = []
            for route, stops_at, battery, forecast in _segments(result, k):
                studies.append(simulate_missions_mc(
                    result.terrain, route, battery, MonteCarloStudy(n, seed=None if seed is None else seed + k,
                                                                    draw_from=mode, distributions=distributions),
                    truth=truth, cost=result.cost, forecast=forecast if mode == "model" else None, compute=each,
                    drive=MissionDrive(stops=stops_at)))
            runs[tour.robot] = tuple(studies)
            stops[tour.robot] = (*(tour.stops[j] for j in tour.charging_stops), tour.legs[-1].end)
    return TourCheck(result.risk, runs, mode, stops, result.map_label)


def _priced_truth(result: TourResult) -> MissionTruth:
    """The robot and the grounds' parameters the tour's cost was priced with (a physics-priced cost keeps them), else
    the default truth."""
    model, params = result.cost.physics_model, result.cost.ground_params
    if model is None or params is None:
        return MissionTruth()
    return MissionTruth(robot=model.robot, grounds=dict(zip(result.cost.tables.ground_labels, params)))


def _stops_along(result: TourResult, robot: int, legs: slice) -> tuple[int, ...]:
    """The waypoints of the route of ``legs`` joined (:meth:`TourResult.tour_route`) where one leg ends and the next
    starts: the stops the robot makes there to serve, whatever its heading (the plan prices each one,
    :meth:`planner.tours.PairPrices.tour_interval`)."""
    lengths = [len(leg.waypoints_m) - 1 for leg in result.tours[robot].legs[legs]]
    return tuple(int(k) for k in np.cumsum(lengths[:-1]))


def _segments(result: TourResult, robot: int) -> list[tuple[Route, tuple[int, ...], Battery, RouteEnergyInterval]]:
    """Each segment of the robot's tour between charges: its route, the waypoints of it the robot stops at (its
    stops), its battery (full after a charge) and its energy distribution over every ground of the tour (zero spread
    where it does not go), so that every segment draws the same factors in the same order."""
    tour = result.tours[robot]
    if not tour.charging_stops:
        return [(result.tour_route(robot), _stops_along(result, robot, slice(None)), tour.battery, tour.energy)]
    whole = tour.energy
    full = dataclasses.replace(tour.battery, initial_soc=1.0)
    out, first = [], 0
    for s, (end, seg) in enumerate(zip([*tour.charging_stops, len(tour.legs) - 1], tour.segments)):
        by = {g: seg.sd_by_ground_j.get(g, 0.0) for g in whole.sd_by_ground_j}
        forecast = RouteEnergyInterval(seg.mean_j, seg.sd_j, by, seg.dof, {g: whole.ground_dof(g) for g in by})
        legs = slice(first, end + 1)
        out.append((result.tour_route(robot, legs), _stops_along(result, robot, legs), tour.battery if s == 0 else full,
                    forecast))
        first = end + 1
    return out
