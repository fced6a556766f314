"""simulate_missions_mc: N missions of one route with drawn parameters, in process or on dask, reproducible from one seed.

Each sample draws its parameters (:class:`MissionDistributions`: ground coefficients,
payload, capacity fade, internal resistance, speed) from its own generator, seeded by the
sample's child of ``numpy.random.SeedSequence(seed).spawn(n)``, and drives the route with
:func:`simulate_mission` against a :class:`energy.TruthSimulator` of the drawn robot and
grounds and the drawn battery. A sample depends on nothing but its child seed, so the
result is the same in process, on any number of workers and with any ``chunk_size``.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from energy import GROUND_PRESETS, Battery, GroundParams, RobotParams, TruthSimulator, ground_preset
from terrain import TerrainMap
from terrawatt_base.checks import check_instance
from terrawatt_base.containers import memory_limit_bytes, over_budget_message
from terrawatt_base.dask_client import Compute, client_worker_count, run_tasks
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from ..edge_cost import EnergyCost
from ..route import Route
from ..route_price import RouteEnergyInterval, price_route
from .monte_carlo_model import ModelMissionSetup
from .monte_carlo_result import MonteCarloResult, failed_row, mission_row
from .monte_carlo_sampling import MissionDistributions
from .options import MissionDrive, MissionTruth, MonteCarloStudy
from .simulate import simulate_mission
from .tracking import route_speed_mps

__all__ = ["simulate_missions_mc", "MissionSetup", "MC_SAMPLE_BYTES"]

#: Bytes one Monte Carlo mission is planned to hold (its seed sequence, drawn parameters and outcome
#: row): a study's size is checked against the memory budget before any seed is spawned.
MC_SAMPLE_BYTES = 4096



@dataclass(frozen=True)
class MissionSetup:
    """Everything a Monte Carlo sample needs besides its seed (sent to every dask worker once)."""

    terrain: TerrainMap
    route: Route
    robot: RobotParams
    grounds: Mapping[str, GroundParams]
    battery: Battery
    distributions: MissionDistributions
    nominal_speed_mps: float
    current_rate_hz: float
    drive: MissionDrive = MissionDrive()

    def _draw(self, seq: np.random.SeedSequence) -> tuple[Any, int, tuple[float, ...]]:
        """One mission's draws from its child seed: the sample, the truth's seed, the row's drawn columns."""
        rng = np.random.default_rng(seq)
        names = sorted(self.grounds)
        s = self.distributions.draw(rng, names, nominal_speed_mps=self.nominal_speed_mps)
        truth_seed = int(rng.integers(0, 2**32))
        drawn = (*(s.ground_scale[g] for g in names), s.payload_kg, s.battery(self.battery).capacity_ah,
                 s.internal_resistance_ohm, s.speed_mps)
        return s, truth_seed, drawn

    def drawn(self, seq: np.random.SeedSequence) -> tuple[float, ...]:
        """What one mission draws from its child seed: the ground factors, payload, capacity after fade,
        internal resistance and speed (the row's first columns)."""
        return self._draw(seq)[2]

    def run(self, seq: np.random.SeedSequence) -> tuple[tuple[float, ...], str]:
        """One mission from one child seed: the drawn parameters (:meth:`drawn`), then the outcome, as a row of
        numbers, and the error of a failed mission (:func:`mission_row`)."""
        s, truth_seed, drawn = self._draw(seq)
        robot = s.robot(self.robot)
        battery = s.battery(self.battery)

        def drive() -> tuple[float, ...]:
            truth = TruthSimulator(robot, s.grounds(self.grounds), current_rate_hz=self.current_rate_hz,
                                   seed=truth_seed)
            m = simulate_mission(self.terrain, self.route, robot, battery, truth,
                                 drive=dataclasses.replace(self.drive, speed_mps=s.speed_mps, seed=truth_seed))
            b = m.budget
            return (b.actual_energy_j, b.actual_charge_mah, b.duration_s, b.arrival_soc, float(np.min(m.soc)),
                    float(not b.feasible), float(b.depleted))

        return mission_row(drawn, drive)

    def run_chunk(self, seqs: list[np.random.SeedSequence]) -> list[tuple[tuple[float, ...], str]]:
        """:meth:`run` over several seeds (one dask task)."""
        return [self.run(q) for q in seqs]

    def failed_chunk(self, seqs: list[np.random.SeedSequence], exc: Exception) -> list[tuple[tuple[float, ...], str]]:
        """The rows of a task of :meth:`run_chunk` that failed with ``exc`` (a worker that died, an error outside
        the library): each mission's draws (:meth:`drawn`, here), its outcome NaN and ``exc`` its error."""
        return [failed_row(self.drawn(q), exc) for q in seqs]


def _grounds(terrain: TerrainMap, grounds: Any) -> dict[str, GroundParams]:
    names = sorted(set(terrain.ground_names.values()))
    if grounds is None:
        unknown = [n for n in names if n not in GROUND_PRESETS]
        if unknown:
            raise UnknownNameError(
                f"the map's grounds {unknown!r} have no preset; pass grounds={{name: GroundParams}} "
                f"(known presets: {sorted(GROUND_PRESETS)!r})"
            )
        return {n: ground_preset(n) for n in names}
    missing = [n for n in names if n not in grounds]
    if missing:
        raise UnknownNameError(f"grounds lacks the map's ground(s) {missing!r}; it has {sorted(grounds)!r}")
    return {n: grounds[n] for n in names}


def simulate_missions_mc(
    terrain: TerrainMap,
    route: Route,
    battery: Battery,
    study: MonteCarloStudy,
    *,
    truth: MissionTruth | None = None,
    compute: Compute | None = None,
    cost: EnergyCost | None = None,
    forecast: RouteEnergyInterval | None = None,
    drive: MissionDrive | None = None,
) -> MonteCarloResult:
    """Drive one route ``study.n`` times with drawn parameters: the risk of crossing the reserve and the energy
    percentiles.

    Parameters
    ----------
    terrain : TerrainMap
        The map of the route; every ground of it needs parameters (``truth.grounds``).
    route : Route
        A found route (e.g. from :func:`planner.plan_route`).
    battery : Battery
        The nominal battery: capacity before fade, voltage, reserve, initial charge.
    study : MonteCarloStudy
        How many missions, drawn from what (typed parameter ranges or the planning model's
        distribution), from which seed, in what chunks, and the share below the reserve it
        accepts (:class:`planner.missions.options.MonteCarloStudy`).
    truth : MissionTruth, optional
        The nominal robot, the map's grounds, the driving speed and the sampling rate of each
        simulated mission (:class:`planner.missions.options.MissionTruth`; default
        ``MissionTruth()``: the husky on the presets of the map's grounds at the route's speed).
    compute : Compute, optional
        Where the missions run and whether a bar shows over them, as :func:`planner.plan_batch`
        (:class:`terrawatt_base.dask_client.Compute`; default here, no bar).
    cost : EnergyCost, optional
        The cost that planned the route: when it carries its physics model, the study's
        ``predicted_energy_j`` is that model's forecast of the driven stop-turn-go profile at
        the nominal speed (:func:`planner.route_price.price_route` with ``how="profile"``), else the
        route's edge energy. When it carries a predictive interval (:mod:`planner.route_price`), the
        result's ``forecast`` is the route's energy distribution (P50, P90) on it;
        ``study.draw_from="model"`` needs one.
    forecast : RouteEnergyInterval, optional
        The route's energy distribution, instead of :func:`planner.route_price.price_route` of
        ``route`` on ``cost``: what ``draw_from="model"`` draws from (e.g. a tour's, whose legs
        and service energy are priced apart, :func:`planner.tours.simulate_tours_mc`).

    Returns
    -------
    MonteCarloResult
        One row per mission. A mission that fails with a library error (e.g. a drawn pack
        whose internal resistance cannot deliver the route's power) is a row of NaN outcomes
        with its reason in ``errors``, and the others go on (as a failed pair in
        :func:`planner.plan_batch`); so is every mission of a task that fails otherwise (a
        worker that dies, an error outside the library: its missions' draws, redrawn here from
        their seeds, are kept). The statistics are over the completed missions, the failed
        ones counted (``n_failed``, the summary).

    Raises
    ------
    InvalidParameterError
        Too many missions for the memory budget; wrong argument types; a route that was not
        found; not a ``Compute``; an unreachable scheduler; ``draw_from="model"`` without a
        cost that carries an interval; a ``drive`` that sets a speed or a seed.
    UnknownNameError
        A ground of the map without parameters.
    OptionalDependencyError
        A cluster is asked for but dask.distributed is not installed.

    Examples
    --------
    Usage (drives n simulated missions, so not run as a doctest)::

        route = plan_route(tmap, start, goal, cost=cost, planner="lattice")
        mc = simulate_missions_mc(tmap, route, Battery(5.0, 24.0), MonteCarloStudy(200, seed=1))
        print(mc.summary()); mc.plot("mc.png")
    """
    study = check_instance("study", study, MonteCarloStudy)
    truth = MissionTruth() if truth is None else check_instance("truth", truth, MissionTruth)
    n, seed, draw_from = study.n, study.seed, study.draw_from
    limit = memory_limit_bytes()
    if n * MC_SAMPLE_BYTES > limit:  # before a seed is spawned: a billion would exhaust memory
        raise InvalidParameterError(over_budget_message(
            f"n={n} missions", "their seeds and results", n * MC_SAMPLE_BYTES, limit,
            advice=f"run at most {limit // MC_SAMPLE_BYTES} missions"))
    if not isinstance(terrain, TerrainMap):
        raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
    if not isinstance(route, Route) or not route.found:
        what = f"status {route.status!r}" if isinstance(route, Route) else type(route).__name__
        raise InvalidParameterError(f"route must be a found Route, got {what!r}")
    if not isinstance(battery, Battery):
        raise InvalidParameterError(f"battery must be a Battery, got {type(battery).__name__!r}")
    drive = MissionDrive() if drive is None else check_instance("drive", drive, MissionDrive)
    if drive.speed_mps is not None or drive.seed is not None:
        raise InvalidParameterError("drive.speed_mps and drive.seed are each mission's draws; give neither (got "
                                    f"speed_mps={drive.speed_mps!r}, seed={drive.seed!r})", parameter="drive")
    robot, rate_hz = truth.robot, truth.current_rate_hz
    distributions = MissionDistributions() if study.distributions is None else study.distributions
    compute = Compute() if compute is None else check_instance("compute", compute, Compute)
    nominal = route_speed_mps(route, robot.turn_rate_radps) if truth.speed_mps is None else truth.speed_mps
    if cost is not None and not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost or None, got {type(cost).__name__!r}")
    if forecast is not None and not isinstance(forecast, RouteEnergyInterval):
        raise InvalidParameterError(f"forecast must be a RouteEnergyInterval or None, got {type(forecast).__name__!r}")
    if forecast is None and cost is not None and cost.has_interval:
        forecast = price_route(cost, route)
    setup: MissionSetup | ModelMissionSetup
    if draw_from == "model":
        if forecast is None:
            raise InvalidParameterError(
                "draw_from='model' draws from the planning model's predictive distribution: give cost= built by a "
                "current model with an interval (e.g. CostSpec(model=...).build); "
                + ("no cost was given" if cost is None else "this cost has none"))
        setup = ModelMissionSetup(forecast, battery, float(route.duration_s), nominal)
        predicted_j = forecast.mean_j
    else:
        setup = MissionSetup(terrain, route, robot, _grounds(terrain, truth.grounds), battery, distributions, nominal,
                             rate_hz, drive)
        TruthSimulator(robot, setup.grounds, current_rate_hz=rate_hz)  # what every sample meets, checked once
        predicted_j = route.energy_j  # the forecast, before any mission runs
        if cost is not None and cost.physics_model is not None:
            predicted_j = price_route(cost, route, how="profile", interval=False, speed_mps=nominal).mean_j
    used = int(np.random.SeedSequence().generate_state(1)[0]) if seed is None else seed  # in [0, 2**32)
    seqs = np.random.SeedSequence(used).spawn(n)
    chunks = [seqs[i:i + study.chunk_size] for i in range(0, n, study.chunk_size)]  # one task each
    with compute.session() as (client, where):
        t0 = time.perf_counter()
        # a task that fails (its worker died, an error outside the library) is a failed row per mission of it
        done = run_tasks([(type(setup).run_chunk, (chunk,)) for chunk in chunks], client=client, shared=(setup,),
                         progress=compute.progress, description="missions", sizes=[len(c) for c in chunks],
                         on_error=lambda i, exc: setup.failed_chunk(chunks[i], exc))
        rows = [row for chunk_rows in done for row in chunk_rows]
        n_used = client_worker_count(client)
        elapsed = time.perf_counter() - t0
    ground_names = setup.ground_names if draw_from == "model" else tuple(sorted(setup.grounds))
    k = len(ground_names)
    table = np.array([row for row, _ in rows], dtype=np.float64).reshape(n, -1)
    cols = table[:, k:].T
    return MonteCarloResult(
        seed=seed, entropy=used, distributions=distributions, battery=battery,
        predicted_energy_j=predicted_j, ground_names=ground_names, ground_scale=table[:, :k],
        payload_kg=cols[0], capacity_ah=cols[1], internal_resistance_ohm=cols[2], speed_mps=cols[3],
        energy_j=cols[4], charge_mah=cols[5], duration_s=cols[6], arrival_soc=cols[7], min_soc=cols[8],
        below_reserve=cols[9] > 0.5, depleted=cols[10] > 0.5, where=where, n_workers=n_used,
        elapsed_s=elapsed, draw_from=draw_from, forecast=forecast, errors=tuple(err for _, err in rows),
        max_risk_pct=study.max_risk_pct,
    )
