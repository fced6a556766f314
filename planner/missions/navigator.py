"""The ride-along navigator: the learning loop a robot's own code drives, live or from a recorded drive.

:class:`Navigator` holds a map, the per-cell current models (a
:class:`planner.registry.CellModelRegistry`), the robot, its battery and a goal. ``plan(start)`` gives
the first route with its forecast; from then on the robot hands it what it measured,
chunk by chunk (:meth:`Navigator.observe`: an :class:`energy.InteractionLog` slice or plain
arrays, :mod:`planner.missions.observations`), and every call returns a
:class:`~planner.missions.decisions.Decision`.

Between checkpoints (every ``settings.leg_length_m`` driven, or where the caller says) a call
only checks the chunk, books its energy against the battery and keeps it. At a checkpoint the
loop of the design runs on what was driven since the last one:

1. **compare per cell** — each sample's measured current against the current the model
   serving its cell predicts (:meth:`planner.registry.CellEvidence.record` of the registry's evidence); the
   :class:`planner.registry.UpdatePolicy` flags regions whose error passes its threshold;
2. **update** each flagged region: a model the registry already holds that explains what was
   measured there (``"reuse"``); else a new model (``model_factory``, default
   :class:`energy.LinearCurrentModel`) fitted on **what the robot drove in the update's
   scope** (the last ``settings.history_s`` of driving kept; the first ``1 -
   validation_fraction`` of it to fit, the rest to validate, ``"driven"``), or on an
   excitation manoeuvre the navigator requests where the driven data are too few
   (``settings.update_source`` says which comes first; the robot's code decides whether to
   run it, :meth:`Navigator.observe_manoeuvre` / :meth:`Navigator.decline_manoeuvre`); the
   registry keeps the new model only if it validates better than the old
   (:meth:`planner.registry.CellModelRegistry.propose_update`);
3. **repair the route** — only the changed models' edge costs are recomputed, the incremental
   lattice search (:class:`~planner.IncrementalPlanner`) repairs its search from the robot's
   position, and the remaining legs are priced again;
4. **decide** — arrived; a new route; or, when the forecast of what remains at the chosen risk
   (:mod:`planner.missions.remaining`: the models' price corrected by this run's measured /
   predicted energy, with its interval) would cross the reserve, return to the depot if the
   way back fits, else stop.

The state of charge is the battery's own (:func:`energy.discharge_from_power`) over the
measured battery power where a chunk carries it (voltage × pack current), over the power of
the logged drive currents otherwise (:func:`energy.budget.log_battery_power_w`), and over the
models' predicted currents for a chunk without currents (forecast-only mode: nothing is
learned). Consecutive chunks are integrated across their boundary.

Every decision made at a checkpoint, and every decision that is not ``"continue"``, is kept
in :attr:`Navigator.decisions` with its evidence. The driven data kept for updates is bounded
by ``settings.history_s``; :meth:`Navigator.save` / :meth:`Navigator.load`
(:mod:`planner.missions.navigator_state`) write and read the whole state atomically, so a
robot that reboots mid-mission continues with the same decisions.

:func:`~planner.run_adaptive_mission` is one client of this class: the truth simulator plays
the robot and drives the manoeuvres it requests.
"""

from __future__ import annotations

import json
import math
import os
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from energy import (
    Battery,
    EnergyBudget,
    InteractionLog,
    LinearCurrentModel,
    RobotParams,
)
from energy.budget import log_battery_power_w
from terrain import DataError, InvalidParameterError, TerrainMap
from terrawatt_base.atomic import json_finite
from terrawatt_base.checks import check_instance, check_real, fmt_number, real_array

from ..lattice import Lattice
from ..learned_cost import LearnedEnergyModel
from ..planning import plan_route
from ..registry import CellModelRegistry
from ..replan import IncrementalPlanner
from ..route import Route, evaluate_route
from ..route_price import price_route
from ..settings import PlannerSettings
from .adaptive_results import AdaptiveResult, LegRecord, ReplanRecord, UpdateRecord
from .charge import MAX_JOIN_GAP_S, ChargeAccount
from .decisions import Decision, ManoeuvreRequest, RemainingForecast
from .legs import LegPredictor, cut_at_position
from .navigator_state import read_navigator_setup, restore_navigator_state, write_navigator_state
from .observations import observation_log
from .region_updates import RegionUpdates, as_xy
from .remaining import remaining_forecast
from .settings import AdaptiveSettings, MissionGoal, NavigatorModels
from .updates import (
    Comparison,
    predicted_currents,
)

__all__ = ["Navigator"]

#: Phases of a navigator: before its first plan, driving, waiting for a requested manoeuvre, over.
PHASES = ("idle", "driving", "manoeuvre", "finished")


class Navigator(RegionUpdates):
    """Plan, observe what the robot measured, learn per cell, repair the route, decide (module docstring).

    Parameters
    ----------
    terrain : TerrainMap
        The map (its ground classes segment update scopes; never priced by their names).
    registry : CellModelRegistry
        Per-cell models on the map's grid (changed in place by accepted updates).
    robot : RobotParams
        The robot (motor constants and electronics turn currents into battery power).
    battery : Battery
        Capacity, voltage, reserve and the state of charge at the start.
    goal : (float, float) or MissionGoal
        The goal in map metres, or a :class:`~planner.missions.settings.MissionGoal` (a goal in
        WGS 84 degrees through the map's CRS; a depot to return to when the rest of the mission
        does not fit: without one, the navigator stops).
    settings : AdaptiveSettings, optional
    models : NavigatorModels, optional
        The physics ground of the learned edge costs' slope term (default the asphalt preset),
        the factory of new current models (default :class:`energy.LinearCurrentModel`) and an
        edge-cost adapter over ``registry`` to reuse
        (:class:`~planner.missions.settings.NavigatorModels`).

    Raises
    ------
    InvalidParameterError
        Wrong argument types; ``models.learned`` bound to another registry.
    GridMismatchError
        ``registry`` on another grid.
    OutOfBoundsError, BlockedPositionError
        Goal or depot off the map or blocked (when planning).

    Notes
    -----
    A walk-through (plain arrays, decisions, the state on disk, replays): ``docs/ride_along.md``.
    """

    def __init__(
        self,
        terrain: TerrainMap,
        registry: CellModelRegistry,
        robot: RobotParams,
        battery: Battery,
        goal: tuple[float, float] | MissionGoal,
        *,
        settings: AdaptiveSettings | None = None,
        models: NavigatorModels | None = None,
    ) -> None:
        for name, value, cls in (("terrain", terrain, TerrainMap), ("registry", registry, CellModelRegistry),
                                 ("robot", robot, RobotParams), ("battery", battery, Battery)):
            if not isinstance(value, cls):
                raise InvalidParameterError(f"{name} must be a {cls.__name__}, got {type(value).__name__!r}")
        registry.check_grid(terrain)
        cfg = AdaptiveSettings() if settings is None else settings
        if not isinstance(cfg, AdaptiveSettings):
            raise InvalidParameterError(f"settings must be an AdaptiveSettings, got {type(cfg).__name__!r}")
        models = NavigatorModels() if models is None else check_instance("models", models, NavigatorModels)
        ground = models.physics_ground
        lem = models.learned if models.learned is not None else LearnedEnergyModel(registry, robot, ground)
        if lem.registry is not registry:
            raise InvalidParameterError("learned must be a LearnedEnergyModel over the same registry")
        goal = goal if isinstance(goal, MissionGoal) else MissionGoal(xy_m=goal)
        goal_xy_m = goal.xy_m
        if goal.lonlat_deg is not None:
            goal_xy_m = tuple(float(v) for v in terrain.lonlat_toas_xy(*goal.lonlat_deg))
        self.terrain, self.registry, self.robot, self.battery = terrain, registry, robot, battery
        self.settings, self.learned, self.physics_ground = cfg, lem, ground
        self.model_factory = LinearCurrentModel if models.model_factory is None else models.model_factory
        self.goal_xy_m = _pair("goal_xy_m", goal_xy_m)
        self.depot_xy_m = None if goal.depot_xy_m is None else _pair("depot_xy_m", goal.depot_xy_m)
        self._predictor = LegPredictor(lem, terrain, speed_mps=cfg.speed_mps, leg_length_m=cfg.leg_length_m,
                                       dt_s=cfg.forecast_dt_s)
        self._init_state()

    def _init_state(self) -> None:
        """The mutable state (what :mod:`planner.missions.navigator_state` saves)."""
        self.phase = "idle"
        self.status, self.reason = "max_legs", ""
        self.returning = False
        self.position_xy_m = np.full(2, math.nan)
        self.heading_rad: float | None = None
        self.leg_start_xy_m = np.full(2, math.nan)
        self.leg_start_heading_rad: float | None = None
        self.leg_start_time_s = 0.0
        self.time_s = math.nan  # the robot's clock: the last drive timestamp seen
        self.charge = ChargeAccount(self.battery)
        self.power_context: InteractionLog | None = None  # the last seconds booked (the control board's start-up)
        self.route: Route | None = None
        self.initial_route: Route | None = None
        self.cost: Any = None
        self.replanner: IncrementalPlanner | None = None
        self.pending: list[float] = []  # the models' price of each remaining leg (J)
        self.observed: list[tuple[float, float]] = []  # (predicted, actual) legs since the models changed
        self.pooled = (0.0, 0.0)  # squared log-ratio deviations and their dof over the earlier stretches
        self.class_samples: dict[int, int] = {}  # samples driven on each ground class in this run
        self._unseen_cache: tuple[Any, list[float]] | None = None
        self._dof_cache: tuple[Any, bytes, float] | None = None  # (cost, route, its interval's dof)
        self.legs: list[LegRecord] = []
        self.updates: list[UpdateRecord] = []
        self.replans: list[ReplanRecord] = []
        self.skipped: list[str] = []
        self.decisions: list[dict[str, Any]] = []  # every decision logged, as plain values
        self.validated: set[tuple[int, int]] = set()
        self.segment: list[InteractionLog] = []  # chunks since the last checkpoint
        self.segment_j = 0.0  # their battery energy
        self.segment_m = 0.0  # distance driven since the last checkpoint
        self.history: deque[tuple[InteractionLog, np.ndarray, np.ndarray]] = deque()  # (log, rows, cols)
        self.queue: list[Any] = []  # flagged regions still to decide at this checkpoint
        self.changed = False  # models changed at this checkpoint
        self.checkpoint_evidence: dict[str, Any] = {}
        self.comparison: Comparison | None = None  # the last leg's comparison, while its regions are decided
        self.tail: np.ndarray | None = None  # the route after the last checkpoint's cut
        self.updates_at_checkpoint = 0  # updates made before this checkpoint
        self._w0 = 0.0  # wall clock at the start of an update waiting for its manoeuvre
        self.request: ManoeuvreRequest | None = None
        self.n_chunks = 0
        self.update_wall = self.leg_power_w = 0.0
        self.vibrations: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.model_map_at_start = np.asarray(self.registry.model_id_map).copy()
        self.start_time_ns: int | None = None  # the recording's clock origin, when known (for bags written beside it)

    # ================================================================== public calls
    def plan(self, start_xy_m: tuple[float, float], *, heading_rad: float | None = None,
             time_s: float = 0.0) -> Decision:
        """The first route from ``start_xy_m``, with its forecast (a ``"new_route"`` decision, or ``"stop"``).

        Raises
        ------
        InvalidParameterError
            Called twice; start equal to the goal (within ``settings.goal_tolerance_m``).
        OutOfBoundsError, BlockedPositionError
            Start or goal off the map or blocked.
        """
        if self.phase != "idle":
            raise InvalidParameterError("plan() was already called: the navigator follows one mission")
        start = _pair("start_xy_m", start_xy_m)
        cfg = self.settings
        if np.hypot(*(start - self.goal_xy_m)) <= cfg.goal_tolerance_m:
            raise InvalidParameterError(
                f"start equals goal: start {tuple(start.tolist())!r} m lies within goal_tolerance_m="
                f"{fmt_number(cfg.goal_tolerance_m)} m of goal {tuple(self.goal_xy_m.tolist())!r} m; nothing to drive")
        self.time_s = check_real("time_s", time_s)
        self.model_map_at_start = np.asarray(self.registry.model_id_map).copy()
        self.position_xy_m = self.leg_start_xy_m = start
        self.heading_rad = self.leg_start_heading_rad = None if heading_rad is None else check_real(
            "heading_rad", heading_rad)
        self.leg_start_time_s = self.time_s
        t0 = time.perf_counter()
        builds0 = self.learned.table_builds
        self.cost = self.learned.energy_cost(self.terrain, cfg.speed_mps)
        refresh = time.perf_counter() - t0
        self.route = self.initial_route = self._search(start)
        planning_s = self.route.planning_time_s
        if cfg.planner == "lattice" and self.route.found:  # seed the incremental search for the replans
            t0 = time.perf_counter()
            self.replanner = IncrementalPlanner(
                Lattice.for_cost(self.cost, PlannerSettings().lattice_stride_cells), tuple(self.goal_xy_m))
            self.replanner.plan(tuple(start))
            planning_s += time.perf_counter() - t0
        self.pending = self._predictor.legs(self.route.waypoints_m, self.heading_rad) if self.route.found else []
        self.replans.append(ReplanRecord(0, "initial", sum(self.pending) if self.route.found else math.nan,
                                         math.nan, True, refresh, planning_s, self.learned.table_builds - builds0))
        self.charge.push(self.time_s, start[0], start[1], self.soc, 0.0, 0.0)
        self.phase = "driving"
        return self._closing_decision(None, "new_route", "the first plan", {})

    def observe(self, chunk: Any, *, checkpoint: bool | None = None) -> Decision:
        """Take what the robot measured since the last call; decide.

        Parameters
        ----------
        chunk : InteractionLog or mapping of arrays
            Time, pose, v / omega, optional currents, IMU and battery
            (:func:`~planner.missions.observations.observation_log`).
        checkpoint : bool, optional
            Run the checkpoint (compare, update, replan) at this chunk's end (True), never
            (False), or when ``settings.leg_length_m`` has been driven since the last one or
            the goal is reached (None).

        Returns
        -------
        Decision

        Raises
        ------
        InvalidParameterError
            Before :meth:`plan`; while a requested manoeuvre waits for its answer.
        DataError, OutOfBoundsError, UnitError
            A chunk refused (nothing of it is kept, the state is unchanged).
        """
        if self.phase == "idle":
            raise InvalidParameterError("call plan(start_xy_m) before observe()")
        if self.phase == "manoeuvre":
            raise InvalidParameterError(
                f"manoeuvre request {self.request.request_id} waits for its answer: observe_manoeuvre(logs) or "
                "decline_manoeuvre()")
        log = observation_log(chunk, self.terrain, previous_time_s=None if math.isnan(self.time_s) else self.time_s,
                              name=f"chunk {self.n_chunks}", robot=self.robot.name)
        if self.phase == "finished":  # the battery still pays for what the robot does; nothing is learned
            self._book(log, None, None, driving=True)
            self.position_xy_m = log.pose_xyh[-1, :2].copy()
            return Decision("stop" if self.status != "completed" else "arrived",
                            f"the mission is over ({self.status}): {self.reason}", self.time_s,
                            as_xy(self.position_xy_m))
        self.n_chunks += 1
        rows, cols = self.terrain.rowcol(log.pose_xyh[:, 0], log.pose_xyh[:, 1])
        rows, cols = np.asarray(rows), np.asarray(cols)
        energy_j, crossed = self._book(log, rows, cols, driving=True)
        xy = log.pose_xyh[:, :2]
        steps = np.hypot(*np.diff(np.vstack([self.position_xy_m, xy]), axis=0).T)
        self.segment_m += float(steps.sum())
        self.segment.append(log)
        self.segment_j += energy_j
        self.position_xy_m = xy[-1].copy()
        self.heading_rad = float(log.pose_xyh[-1, 2])
        if crossed:
            self._close_leg()
            return self._finish("reserve_violated", (
                f"the battery reached its {self.battery.min_reserve_pct:g} % reserve at "
                f"{as_xy(self.position_xy_m)!r} m during leg {len(self.legs) - 1}"), "stop")
        near_goal = np.hypot(*(self.position_xy_m - self._target())) <= self.settings.goal_tolerance_m
        if checkpoint is False or (checkpoint is None and self.segment_m < self.settings.leg_length_m
                                   and not near_goal):
            return Decision("continue", "driving", self.time_s, as_xy(self.position_xy_m), self.forecast())
        return self._checkpoint()

    def observe_manoeuvre(self, logs: InteractionLog | Sequence[InteractionLog]) -> Decision:
        """What the robot measured while driving the requested manoeuvre (its logs, in time order).

        The manoeuvre is made on the spot: its logs need no poses. Its energy is booked as
        excitation; a new model is fitted on the first ``1 - validation_fraction`` of each
        log and validated with the old on the rest.

        Raises
        ------
        InvalidParameterError
            No manoeuvre was requested; not logs.
        DataError
            Logs out of time order or without currents.
        """
        if self.phase != "manoeuvre":
            raise InvalidParameterError("no manoeuvre was requested: nothing to observe")
        xlogs = [logs] if isinstance(logs, InteractionLog) else list(logs)
        if not xlogs or not all(isinstance(x, InteractionLog) for x in xlogs):
            raise InvalidParameterError("observe_manoeuvre takes an InteractionLog or a sequence of them")
        prev = self.time_s
        for i, xl in enumerate(xlogs):
            xl.require_currents(f"manoeuvre log {i}")
            if not float(xl.time_s[0]) > prev:
                raise DataError(f"manoeuvre log {i} starts at t = {fmt_number(float(xl.time_s[0]), 9)} s, not after "
                                f"{fmt_number(prev, 9)} s: time went backwards")
            prev = float(xl.time_s[-1])
        return self._excite(xlogs)

    def decline_manoeuvre(self, reason: str = "declined by the robot") -> Decision:
        """The robot will not drive the requested manoeuvre: fit on the driven data if there is
        enough, else leave the region's model as it is (its evidence reset)."""
        if self.phase != "manoeuvre":
            raise InvalidParameterError("no manoeuvre was requested: nothing to decline")
        req = self.request
        self.phase, self.request = "driving", None
        region = self.queue[0]
        outcome = self._fit_driven(region, *self._scope(region))
        if outcome is None:
            self.skipped.append(f"after leg {len(self.legs) - 1}: no {req.ground!r} update, the manoeuvre was "
                                f"{reason} and the driven data are too few")
            self.registry.evidence.reset(region)
        else:
            self.changed |= outcome
        self.queue.pop(0)
        return self._work_queue()

    # ------------------------------------------------------------------ persistence
    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the whole state to the directory ``path``, atomically (:mod:`planner.missions.navigator_state`).

        Raises
        ------
        InvalidParameterError
            ``path`` holds something else; a model without ``save``.
        """
        return write_navigator_state(self, path)

    @classmethod
    def load(cls, path: str | os.PathLike[str], terrain: TerrainMap, *,
             model_factory: Callable[[], Any] | None = None) -> Navigator:
        """A navigator restored from :meth:`save` on its map; it continues with the same decisions.

        Raises
        ------
        FileFormatError
            Not a navigator state, another format version, a broken file.
        GridMismatchError
            ``terrain`` is not the map the state was saved on.
        """
        setup = read_navigator_setup(path, terrain)
        nav = cls(terrain, setup["registry"], setup["robot"], setup["battery"],
                  MissionGoal(xy_m=setup["goal_xy_m"], depot_xy_m=setup["depot_xy_m"]), settings=setup["settings"],
                  models=NavigatorModels(physics_ground=setup["physics_ground"], model_factory=model_factory))
        restore_navigator_state(nav, path, setup["document"])
        return nav

    def resume_comparison(self, log: InteractionLog, rows: np.ndarray, cols: np.ndarray) -> None:
        """The last leg's comparison again (not recorded twice), for regions still to decide after a restore."""
        self.comparison = Comparison(self.registry, log, rows, cols)

    # ------------------------------------------------------------------ read-outs
    @property
    def finished(self) -> bool:
        """Whether the mission is over (arrived, stopped)."""
        return self.phase == "finished"

    @property
    def pending_manoeuvre(self) -> ManoeuvreRequest | None:
        """The manoeuvre waiting for an answer, if any."""
        return self.request

    def forecast(self) -> RemainingForecast:
        """The energy of the rest of the mission as seen now (:mod:`planner.missions.remaining`)."""
        route = self.route.waypoints_m if self.route is not None and self.route.found else np.zeros((0, 2))
        return self._forecast_of(self.pending, route)

    def _forecast_of(self, pending: list[float], waypoints: np.ndarray) -> RemainingForecast:
        """The forecast of driving ``waypoints``, priced leg by leg as ``pending``."""
        return remaining_forecast(pending, self.observed, self.settings, self.charge, pooled=self.pooled,
                                  unseen_j=self._unseen_j(waypoints, float(sum(pending))),
                                  dof=self._route_dof(waypoints))

    def _route_dof(self, waypoints: np.ndarray) -> float:
        """The degrees of freedom of ``waypoints``' energy interval on the planning cost
        (:func:`planner.route_price.price_route`): ``inf`` (the normal distribution) without an
        interval or where every row is Gaussian; cached per cost and route. A route the cost
        cannot price (it crosses what the last update blocked) takes the least of every row's."""
        cost = self.cost
        if len(waypoints) < 2 or cost is None or not cost.has_interval or not any(
                math.isfinite(d) for d in cost.tables.spread_dof):
            return math.inf
        key = waypoints.tobytes() + repr(waypoints.shape).encode()
        if self._dof_cache is not None and self._dof_cache[0] is cost and self._dof_cache[1] == key:
            return self._dof_cache[2]
        try:
            dof = price_route(cost, waypoints, interval=True).dof
        except InvalidParameterError:
            dof = min(cost.tables.spread_dof)
        self._dof_cache = (cost, key, dof)
        return dof

    def _unseen_j(self, waypoints: np.ndarray, energy_j: float) -> list[float]:
        """The share of ``energy_j`` on each ground class of the route that this run has not driven
        (by length along the route, sampled every half cell; cached per route and classes seen)."""
        if len(waypoints) < 2 or energy_j <= 0:
            return []
        seen = frozenset(c for c, n in self.class_samples.items() if n >= self.settings.policy.min_samples)
        key = (waypoints.shape, waypoints.tobytes(), seen)
        if self._unseen_cache is not None and self._unseen_cache[0] == key:
            return [energy_j * f for f in self._unseen_cache[1]]
        seg = np.diff(waypoints, axis=0)
        length = np.hypot(seg[:, 0], seg[:, 1])
        step = 0.5 * self.terrain.cell_size_m
        pts = np.vstack([waypoints[i] + np.linspace(0.0, 1.0, max(int(length[i] / step), 1), endpoint=False)[:, None]
                         * seg[i] for i in range(len(seg)) if length[i] > 0] or [waypoints[:1]])
        r, c = self.terrain.rowcol(pts[:, 0], pts[:, 1])
        classes = np.asarray(self.terrain.ground)[np.asarray(r), np.asarray(c)]
        values, counts = np.unique(classes, return_counts=True)
        fractions = [float(n) / classes.size for v, n in zip(values.tolist(), counts.tolist()) if int(v) not in seen]
        self._unseen_cache = (key, fractions)
        return [energy_j * f for f in fractions]

    @property
    def soc(self) -> float:
        """State of charge now (measured power where the chunks carry it, else from the currents or the models)."""
        return self.charge.soc

    def result(self) -> AdaptiveResult:
        """The mission so far as an :class:`AdaptiveResult` (legs, updates, replans, series, budget)."""
        cat = self.charge.arrays()
        pos = self.position_xy_m
        status = self.status if self.phase == "finished" else "max_legs"
        reason = self.reason if self.phase == "finished" else "the mission is under way"
        return AdaptiveResult(
            status=status, reason=reason, final_xy_m=as_xy(pos),
            distance_to_goal_m=float(np.hypot(*(pos - self.goal_xy_m))), initial_route=self.initial_route,
            legs=tuple(self.legs), updates=tuple(self.updates), replans=tuple(self.replans), time_s=cat["t"],
            x_m=cat["x"], y_m=cat["y"], soc=cat["soc"], energy_j=cat["e"], predicted_energy_j=cat["p"],
            driven_energy_j=self.charge.driven_j, excitation_energy_j=self.charge.excitation_j,
            update_wall_time_s=self.update_wall, final_soc=self.soc, skipped_updates=tuple(self.skipped),
            budget=self.budget(),
        )

    def budget(self) -> EnergyBudget:
        """The whole mission's draw (driving and manoeuvres) against the first plan's prediction."""
        first = self.replans[0].predicted_energy_j if self.replans else math.nan
        route = self.initial_route
        return self.charge.budget(first if math.isfinite(first) else 0.0,
                                  route.duration_s if route is not None and route.found else 0.0)

    # ================================================================== booking
    def _power_w(self, log: InteractionLog, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Battery power of each sample: measured, from the logged currents, or from the models.

        Power from currents includes the control board's start-up after a start from rest, which
        depends on the samples before the chunk: the last seconds of the previous chunk (its
        ``context``) are joined in front, so a drive priced chunk by chunk is priced as a whole."""
        if log.has_battery_power:
            return np.asarray(log.battery_power_w, dtype=np.float64)
        if not log.has_currents:
            pred = predicted_currents(self.registry, log, rows, cols)
            log = replace(log, current_left_a=pred[:, 0], current_right_a=pred[:, 1])
        ctx = self.power_context
        both = None
        if ctx is not None and float(log.time_s[0]) - float(ctx.time_s[-1]) <= MAX_JOIN_GAP_S:
            both = _joined(ctx, log)
        self.power_context = _tail(log if both is None else both, self.robot.startup_duration_s + 1.0)
        if both is not None:
            return log_battery_power_w(both, self.robot)[len(ctx):]
        return log_battery_power_w(log, self.robot)

    def _book(self, log: InteractionLog, rows: np.ndarray | None, cols: np.ndarray | None, *,
              driving: bool) -> tuple[float, bool]:
        """Draw the battery through one log (:meth:`ChargeAccount.book`): its energy (J, to the
        reserve if reached) and whether the reserve was reached."""
        if rows is None:
            r, c = self.terrain.rowcol(*self.position_xy_m)
            rows, cols = np.full(len(log), int(r)), np.full(len(log), int(c))
        xy = log.pose_xyh[:, :2] if log.pose_xyh is not None else np.tile(self.position_xy_m, (len(log), 1))
        out = self.charge.book(log.time_s, self._power_w(log, rows, cols), xy, self._progress_prediction(log),
                               driving=driving)
        self.time_s = float(log.time_s[-1])
        return out

    def _progress_prediction(self, log: InteractionLog) -> np.ndarray:
        """The predicted energy of the leg under way, in proportion to the distance driven (J per sample)."""
        leg_j = self.pending[0] if self.pending else 0.0
        if log.pose_xyh is None or self.settings.leg_length_m <= 0:
            return np.full(len(log), 0.0)
        xy = log.pose_xyh[:, :2]
        d = self.segment_m + np.cumsum(np.hypot(*np.diff(np.vstack([self.position_xy_m, xy]), axis=0).T))
        return leg_j * np.minimum(d / self.settings.leg_length_m, 1.0)

    # ================================================================== the checkpoint
    def _close_leg(self) -> InteractionLog | None:
        """Record the leg driven since the last checkpoint; its log (None if nothing was driven)."""
        if not self.segment:
            return None
        seg = self.segment[0] if len(self.segment) == 1 else InteractionLog.concatenate(self.segment)
        head = np.vstack([self.leg_start_xy_m, self.position_xy_m])
        tail: np.ndarray | None = None
        if self.route is not None and self.route.found:
            head, tail = cut_at_position(np.asarray(self.route.waypoints_m), self.position_xy_m)
        leg_pred = self.pending.pop(0) if self.pending else self._predictor.leg(head, self.leg_start_heading_rad)
        route_j = evaluate_route(self.cost, head).energy_j if len(head) >= 2 else 0.0
        index = len(self.legs)
        duration = float(seg.time_s[-1] - self.leg_start_time_s)
        self.legs.append(LegRecord(index, as_xy(self.leg_start_xy_m), as_xy(self.position_xy_m), leg_pred,
                                   self.segment_j, duration, len(seg), route_j))
        self.observed.append((leg_pred, self.segment_j))
        self.charge.p_total += leg_pred
        self.leg_power_w = self.segment_j / max(duration, 1e-9)
        self.segment, self.segment_j, self.segment_m = [], 0.0, 0.0
        self.leg_start_xy_m, self.leg_start_heading_rad = self.position_xy_m.copy(), self.heading_rad
        self.leg_start_time_s = self.time_s
        self.tail = tail
        return seg

    def _checkpoint(self) -> Decision:
        """Close the leg, compare per cell, queue the flagged regions and work through them."""
        seg = self._close_leg()
        self.changed, self.queue = False, []
        evidence: dict[str, Any] = {"leg": self.legs[-1].index, "predicted_j": self.legs[-1].predicted_energy_j,
                                    "actual_j": self.legs[-1].actual_energy_j}
        if seg is not None and seg.has_currents:
            rows, cols = (np.asarray(a) for a in self.terrain.rowcol(seg.pose_xyh[:, 0], seg.pose_xyh[:, 1]))
            self.comparison = Comparison(self.registry, seg, rows, cols)
            self.comparison.record(self.registry)
            self._count_classes(rows, cols)
            self._remember(seg, rows, cols)
            regions = list(self.registry.evidence.flagged_regions(self.settings.policy))
            self.queue = regions
            evidence["flagged"] = [{"ground": self._ground_name(r), "cells": int(r.cell_count),
                                    "error_pct": 100.0 * float(r.relative_error)} for r in regions]
        else:
            evidence["flagged"] = []
            evidence["mode"] = "forecast only (no currents)"
            if seg is not None:
                self._count_classes(*(np.asarray(a) for a in self.terrain.rowcol(seg.pose_xyh[:, 0],
                                                                                 seg.pose_xyh[:, 1])))
        self.checkpoint_evidence = evidence
        self.updates_at_checkpoint = len(self.updates)
        return self._work_queue()

    def _count_classes(self, rows: np.ndarray, cols: np.ndarray) -> None:
        """Count the samples driven on each ground class (a class driven enough is no longer unseen)."""
        values, counts = np.unique(np.asarray(self.terrain.ground)[rows, cols], return_counts=True)
        for v, n in zip(values.tolist(), counts.tolist()):
            self.class_samples[int(v)] = self.class_samples.get(int(v), 0) + int(n)

    def _remember(self, seg: InteractionLog, rows: np.ndarray, cols: np.ndarray) -> None:
        """Keep the leg for driven updates; forget the oldest beyond ``settings.history_s``."""
        self.history.append((seg, rows, cols))
        total = sum(float(s.duration_s) for s, _, _ in self.history)
        while len(self.history) > 1 and total - float(self.history[0][0].duration_s) >= self.settings.history_s:
            total -= float(self.history.popleft()[0].duration_s)

    def _work_queue(self) -> Decision:
        """Decide the queued regions one by one (a manoeuvre request pauses), then close the checkpoint."""
        while self.queue:
            if sum(u.kind == "excitation" for u in self.updates) >= self.settings.max_updates:
                self.queue = []
                break
            outcome = self._update_region(self.queue[0])
            if isinstance(outcome, Decision):  # a manoeuvre request, or the reserve reached
                return outcome
            self.changed |= bool(outcome)
            self.queue.pop(0)
        return self._close_checkpoint()

    def _close_checkpoint(self) -> Decision:
        """After the updates: arrived, or the route repaired and the budget checked."""
        evidence = dict(self.checkpoint_evidence)
        evidence["updates"] = [vars(u) for u in self.updates[self.updates_at_checkpoint:]]
        target = self._target()
        tail = self.tail
        at_end = tail is None or len(tail) < 2
        if np.hypot(*(self.position_xy_m - target)) <= self.settings.goal_tolerance_m or at_end:
            where = "the depot" if self.returning else "the goal"
            return self._finish("completed", f"reached {where}", "arrived", evidence)
        if len(self.legs) >= self.settings.max_legs:
            return self._finish("max_legs", f"stopped after max_legs={self.settings.max_legs} legs", "stop", evidence)
        action, why = "continue", "on route"
        if self.changed:
            changed = self._replan(tail)
            if changed:
                action, why = "new_route", "the models changed: " + "; ".join(
                    f"{u.kind} update of {u.ground!r}" for u in self.updates[self.updates_at_checkpoint:] if u.accepted)
        else:
            self.route = evaluate_route(self.cost, tail, status="exact", planner=self.route.planner)
        return self._closing_decision(len(self.legs) - 1, action, why, evidence)

    def _closing_decision(self, checkpoint: int | None, action: str, why: str, evidence: dict[str, Any]) -> Decision:
        """The budget check on the route now; the decision, logged."""
        if not self.route.found:
            return self._finish("no_route", f"no route from {as_xy(self.position_xy_m)} to the goal "
                                            f"(planner status {self.route.status!r})", "stop", evidence)
        fc = self.forecast()
        if not fc.fits:
            need = (f"the remaining route needs {fc.risk_j / 3600:.2f} Wh ("
                    + ("predicted" if fc.risk is None else f"at risk {fc.risk:g}")
                    + f") but only {max(fc.available_j, 0.0) / 3600:.2f} Wh are left above the "
                    f"{self.battery.min_reserve_pct:g} % reserve")
            back = self._return_route() if self.depot_xy_m is not None and not self.returning else None
            if back is not None:
                return self._decide("return", need + "; the way back to the depot fits", checkpoint, evidence,
                                    route=back)
            return self._finish("budget_exceeded", need, "stop", evidence)
        return self._decide(action, why, checkpoint, evidence,
                            route=self.route if action == "new_route" else None)

    def _decide(self, action: str, reason: str, checkpoint: int | None, evidence: dict[str, Any], *,
                route: Route | None = None, manoeuvre: ManoeuvreRequest | None = None) -> Decision:
        fc = None if self.phase == "finished" else self.forecast()
        d = Decision(action, reason, self.time_s, as_xy(self.position_xy_m), fc, route, manoeuvre, checkpoint, evidence)
        self.decisions.append(json.loads(json.dumps(json_finite(d.to_dict()))))  # plain JSON, as saved
        return d

    def _finish(self, status: str, reason: str, action: str, evidence: dict[str, Any] | None = None) -> Decision:
        self.status, self.reason, self.phase = status, reason, "finished"
        self.pending = []
        return self._decide(action, reason, len(self.legs) - 1 if self.legs else None, evidence or {})

    def _target(self) -> np.ndarray:
        return self.depot_xy_m if self.returning else self.goal_xy_m

    # ================================================================== planning
    def _search(self, start: np.ndarray) -> Route:
        cfg = self.settings
        if self.replanner is not None:  # the lattice, searched incrementally
            return self.replanner.route(tuple(start), seed=cfg.seed)
        return plan_route(self.terrain, tuple(start), tuple(self._target()), cost=self.cost, planner=cfg.planner,
                          time_limit_s=cfg.planner_time_limit_s, seed=cfg.seed, compare=False)

    def _replan(self, tail: np.ndarray) -> bool:
        """Refresh the edge costs for the changed models and replan from here; keep the old route
        when the planner finds nothing better. Whether the route changed."""
        t1 = time.perf_counter()
        builds0 = self.learned.table_builds
        previous = self.cost
        self.cost = self.learned.energy_cost(self.terrain, self.settings.speed_mps, previous=previous)
        if self.replanner is not None:
            self.replanner.update(Lattice.for_cost(self.cost, self.replanner.lattice.stride_cells))
        previous.lattices.clear()  # a lattice and its cost hold each other: freed now, not at the next full GC
        refresh = time.perf_counter() - t1
        old_energy = evaluate_route(self.cost, tail).energy_j if len(tail) >= 2 else 0.0
        route = self._search(self.position_xy_m)
        if route.found:
            same = route.waypoints_m.shape == tail.shape and np.allclose(route.waypoints_m, tail, atol=1e-6)
            if not same and old_energy <= route.energy_j:  # nothing better: keep the old one
                route, same = evaluate_route(self.cost, tail, status="exact", planner="kept"), True
            self.pending = self._predictor.legs(route.waypoints_m, self.heading_rad)
        else:
            same, self.pending = False, []
        self.route = route
        self.update_wall += refresh
        self.replans.append(ReplanRecord(len(self.legs) - 1, "update", sum(self.pending) if route.found else math.nan,
                                         old_energy, not same, refresh, route.planning_time_s,
                                         self.learned.table_builds - builds0))
        return not same

    def _return_route(self) -> Route | None:
        """The route back to the depot, if it fits above the reserve at the risk level; the
        navigator then heads there."""
        back = plan_route(self.terrain, tuple(self.position_xy_m), tuple(self.depot_xy_m), cost=self.cost,
                          planner="lattice", seed=self.settings.seed, compare=False)
        if not back.found:
            return None
        pending = self._predictor.legs(back.waypoints_m, self.heading_rad)
        if not self._forecast_of(pending, back.waypoints_m).fits:
            return None
        self.returning, self.route, self.pending, self.replanner = True, back, pending, None
        self.replans.append(ReplanRecord(len(self.legs) - 1, "return", sum(pending), math.nan, True, 0.0,
                                         back.planning_time_s, 0))
        return back


def _tail(log: InteractionLog, seconds: float) -> InteractionLog:
    """The drive samples of the last ``seconds`` of a log (with currents; IMU reduced to its bounds)."""
    t = log.time_s
    k = int(np.searchsorted(t, float(t[-1]) - seconds))
    sel = slice(k, None)
    return InteractionLog(t[sel], log.v_mps[sel], log.omega_radps[sel], log.current_left_a[sel],
                          log.current_right_a[sel], t[[k, -1]] if t.size - k > 1 else t[sel],
                          np.zeros(2 if t.size - k > 1 else 1))


def _joined(first: InteractionLog, second: InteractionLog) -> InteractionLog | None:
    """The drive streams of two logs one after the other (None when the second does not follow the first)."""
    if not float(second.time_s[0]) > float(first.time_s[-1]) or second.current_left_a is None:
        return None

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(first, name), getattr(second, name)])

    t = cat("time_s")
    return InteractionLog(t, cat("v_mps"), cat("omega_radps"), cat("current_left_a"), cat("current_right_a"),
                          t[[0, -1]], np.zeros(2))


def _pair(name: str, value: Any) -> np.ndarray:
    arr = real_array(name, value, ndim=1)
    if arr.shape != (2,):
        raise InvalidParameterError(f"{name} must be an (x, y) pair, got {value!r}")
    return arr.copy()
