"""The adaptive mission loop: plan, drive a leg, compare per cell, update models, replan.

:func:`run_adaptive_mission` plans with the registry's current models (through
:class:`~planner.learned_cost.LearnedEnergyModel` edge costs), drives the route leg by leg
against a :class:`energy.TruthSimulator` (which knows the true grounds), records measured vs
predicted current per cell in the :class:`terrain.CellModelRegistry`, and where the
:class:`terrain.UpdatePolicy` flags a region it

1. runs the excitation manoeuvre there (:func:`~planner.missions.manoeuvres.excitation_manoeuvre`:
   a straight run over speed levels and a pivot run, simulated on the spot on the ground of
   the region's representative cell; its energy and time are charged to the battery through
   :func:`energy.discharge_from_power`, with the pack's internal resistance and Peukert
   behaviour),
2. fits a new model (``model_factory``, default :class:`energy.LinearCurrentModel`) on the
   first ``1 - validation_fraction`` of each excitation log,
3. validates new and old model on the held-back tails (absolute relative error of the
   integrated absolute current, both sides) and calls ``registry.propose_update``, which
   keeps the new model only if it is better,
4. refreshes the edge costs (only the new model's table is computed, and the lattice graph
   is reweighted only where cells changed model: ``energy_cost(..., previous=cost)``) and
   replans from the current position. With the lattice planner the replan is incremental:
   an :class:`~planner.replan.IncrementalPlanner` (D* Lite toward the goal), seeded after
   the first plan, takes the refreshed lattice's changed moves and repairs its search from
   the robot's position, then refines and costs the route as ``plan_route`` does (the same
   lattice optimum; among routes of equal energy it may pick another one).

Before exciting a flagged region, the loop tries the models it already has: the one that
best explains what the last leg measured in the region (integrated current, both sides) is
assigned to the update's scope without a manoeuvre when its error is under the policy
threshold and below the serving model's on the same samples (``UpdateRecord.kind ==
"reuse"``; a registry version like any other, so it rolls back). Without a segmentation
(``"region"``) this is what keeps a ground learned once from being excited again at every
new patch of it.

A (ground class, model) pair is excited at most once: the model fitted there, or the old
model that beat it, has been validated on fresh excitation data of that ground, so later
flags of the same pair only reset the evidence (the cells' error then comes from the
transients — pivots, stops — that small regions over-represent).

The scope of an update is, with ``update_scope="ground_class"`` (default), every cell of the
map's ground class at the representative cell that is served by the same model(s) as the
flagged region: the map's ground layer is used as a *segmentation* only (e.g. surface classes
from imagery), never for its energy; with ``"region"`` only the flagged cells.

Predictions (of each leg, of the remaining route for the budget check and after a replan)
price the velocity profile the robot will drive with the models serving the cells it crosses
(:meth:`LearnedEnergyModel.profile_energy_j` of the stop-turn-go profile): the edge costs the
planner minimises price steady driving plus turns in place, and miss the energy of stopping
and starting at every waypoint and leg end (a few per cent per 10 m leg, more with turns).
Both are recorded (``LegRecord.route_energy_j`` is the edge-cost figure). A remaining route
is predicted as the loop drives it: leg by leg, stopping at every leg end.

The loop stops at the goal, when the predicted energy of the remaining route exceeds the
energy above the battery's reserve (``"budget_exceeded"``), when the reserve is crossed while
driving (``"reserve_violated"``), when no route is found (``"no_route"``) or after
``max_legs`` legs (``"max_legs"``); the result says why and where.

Each leg runs as named steps of :class:`_Loop`: drive the leg (:meth:`_Loop.drive_leg`),
compare measured and predicted current per cell (:meth:`_Loop.compare_cells`), decide an
update for each flagged region (:meth:`_Loop.update_region`: reuse a model, or excite and
validate) and replan (:meth:`_Loop.replan`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from energy import (
    Battery,
    EnergyBudget,
    GroundParams,
    InteractionLog,
    LinearCurrentModel,
    RobotParams,
    TruthSimulator,
    discharge_from_power,
    energy_budget,
)
from energy.budget import log_battery_power_w
from terrain import CellModelRegistry, InvalidParameterError, TerrainMap
from terrawatt_base.checks import fmt_number, real_array

from ..lattice import Lattice
from ..learned_cost import LearnedEnergyModel
from ..planning import plan_route
from ..replan import IncrementalPlanner
from ..route import Route, evaluate_route
from ..settings import PlannerSettings
from .adaptive_results import AdaptiveResult, LegRecord, ReplanRecord, UpdateRecord
from .legs import LegPredictor, split_polyline
from .manoeuvres import excitation_manoeuvre
from .settings import AdaptiveSettings
from .simulate import simulate_mission
from .updates import adapted_model, best_other_model, charge_error, predicted_currents, validation_error

__all__ = ["run_adaptive_mission"]


def run_adaptive_mission(
    terrain: TerrainMap,
    registry: CellModelRegistry,
    robot: RobotParams,
    battery: Battery,
    truth: TruthSimulator,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    *,
    physics_ground: GroundParams,
    settings: AdaptiveSettings | None = None,
    model_factory: Callable[[], Any] | None = None,
    learned: LearnedEnergyModel | None = None,
) -> AdaptiveResult:
    """Drive from start to goal, updating per-cell current models and replanning.

    Parameters
    ----------
    terrain : TerrainMap
        The map (the truth simulator looks up its true grounds by the map's ground names).
    registry : CellModelRegistry
        Per-cell models on the map's grid (changed in place by accepted updates).
    robot : RobotParams
        The robot (normally ``truth.robot``).
    battery : Battery
        Capacity, voltage, reserve and initial state of charge.
    truth : TruthSimulator
        Drives the legs and the excitation manoeuvres.
    start_xy_m, goal_xy_m : (float, float)
        World coordinates (m).
    physics_ground : GroundParams
        Ground of the physics slope term of the learned edge costs.
    settings : AdaptiveSettings, optional
    model_factory : callable, optional
        Returns a new unfitted current model (``fit(logs)`` / ``predict(log)``); default
        :class:`energy.LinearCurrentModel`.
    learned : LearnedEnergyModel, optional
        Edge-cost adapter over ``registry`` (to reuse its table cache); built when None.

    Returns
    -------
    AdaptiveResult

    Raises
    ------
    InvalidParameterError
        Wrong argument types; ``learned`` bound to another registry.
    GridMismatchError
        ``registry`` on another grid.
    OutOfBoundsError, BlockedPositionError
        Start or goal outside the map or blocked.
    InvalidParameterError
        Start equals goal (within ``settings.goal_tolerance_m``): nothing to drive.
    """
    for name, value, cls in (("terrain", terrain, TerrainMap), ("registry", registry, CellModelRegistry),
                             ("robot", robot, RobotParams), ("battery", battery, Battery),
                             ("truth", truth, TruthSimulator), ("physics_ground", physics_ground, GroundParams)):
        if not isinstance(value, cls):
            raise InvalidParameterError(f"{name} must be a {cls.__name__}, got {type(value).__name__!r}")
    registry.check_grid(terrain)
    cfg = AdaptiveSettings() if settings is None else settings
    if not isinstance(cfg, AdaptiveSettings):
        raise InvalidParameterError(f"settings must be an AdaptiveSettings, got {type(cfg).__name__!r}")
    lem = learned if learned is not None else LearnedEnergyModel(registry, robot, physics_ground)
    if lem.registry is not registry:
        raise InvalidParameterError("learned must be a LearnedEnergyModel over the same registry")
    start = real_array("start_xy_m", start_xy_m, ndim=1)
    goal = real_array("goal_xy_m", goal_xy_m, ndim=1)
    if start.shape != (2,) or goal.shape != (2,):
        raise InvalidParameterError(f"start_xy_m and goal_xy_m must be (x, y) pairs, got {start_xy_m!r}, {goal_xy_m!r}")
    if np.hypot(*(start - goal)) <= cfg.goal_tolerance_m:
        raise InvalidParameterError(
            f"start equals goal: start {tuple(start.tolist())!r} m lies within goal_tolerance_m="
            f"{fmt_number(cfg.goal_tolerance_m)} m of goal {tuple(goal.tolist())!r} m; nothing to drive"
        )
    loop = _Loop(terrain, registry, robot, battery, truth, goal, cfg, lem,
                 LinearCurrentModel if model_factory is None else model_factory)
    loop.plan_initial(start)
    for leg_index in range(cfg.max_legs):
        if not loop.step(leg_index):
            break
    return loop.result()


class _Loop:
    """State and named steps of one adaptive mission."""

    def __init__(self, terrain: TerrainMap, registry: CellModelRegistry, robot: RobotParams, battery: Battery,
                 truth: TruthSimulator, goal: np.ndarray, cfg: AdaptiveSettings, lem: LearnedEnergyModel,
                 factory: Callable[[], Any]) -> None:
        self.terrain, self.registry, self.robot, self.battery, self.truth = terrain, registry, robot, battery, truth
        self.goal, self.cfg, self.lem, self.factory = goal, cfg, lem, factory
        self.predictor = LegPredictor(lem, terrain, speed_mps=cfg.speed_mps, leg_length_m=cfg.leg_length_m,
                                      dt_s=1.0 / truth.current_rate_hz)
        self.legs: list[LegRecord] = []
        self.leg_logs: list[InteractionLog] = []  # what the sensors recorded on each leg
        self.updates: list[UpdateRecord] = []
        self.replans: list[ReplanRecord] = []
        self.skipped: list[str] = []  # updates not attempted for lack of energy
        self.validated: set[tuple[int, int]] = set()  # (ground class, model id) validated on excitation data
        self.series: dict[str, list[np.ndarray]] = {k: [] for k in ("t", "x", "y", "soc", "e", "p")}
        self.heading: float | None = None
        self.soc = battery.initial_soc
        self.clock = self.e_total = self.p_total = 0.0
        self.driven_j = self.excitation_j = self.update_wall = 0.0
        self.status, self.reason = "max_legs", f"stopped after max_legs={cfg.max_legs} legs"
        self.pending: list[float] = []  # remaining legs' predicted energies (J)
        self.replanner: IncrementalPlanner | None = None  # the lattice planner's incremental search
        self.draw: list[tuple[np.ndarray, np.ndarray]] = []  # (time, battery power) of every drive and manoeuvre

    # ------------------------------------------------------------------ bookkeeping
    def push(self, t: Any, x: Any, y: Any, s: Any, e: Any, p: Any) -> None:
        for key, arr in zip(("t", "x", "y", "soc", "e", "p"), (t, x, y, s, e, p)):
            self.series[key].append(np.atleast_1d(np.asarray(arr, dtype=np.float64)))

    def push_here(self) -> None:
        """A sample at the current position (after a manoeuvre on the spot)."""
        self.push(self.clock, self.pos[0], self.pos[1], self.soc, self.e_total, self.p_total)

    def add_draw(self, t: np.ndarray, power_w: np.ndarray) -> None:
        """Book a battery draw at mission times ``t`` (a series that starts where the last ended
        is moved on by a microsecond: one series, strictly increasing)."""
        t = np.asarray(t, dtype=np.float64)
        if self.draw and t[0] <= self.draw[-1][0][-1]:
            t = t + (self.draw[-1][0][-1] - t[0]) + 1e-6
        self.draw.append((t, np.asarray(power_w, dtype=np.float64)))

    def available_j(self) -> float:
        """Nominal energy above the reserve at the current state of charge (J), from the battery."""
        return self.battery.replace(initial_soc=self.soc).usable_energy_wh * 3600.0

    def stop(self, status: str, reason: str) -> bool:
        self.status, self.reason = status, reason
        return False

    def plan(self, pos: np.ndarray) -> Route:
        cfg = self.cfg
        if self.replanner is not None:  # the lattice, searched incrementally
            return self.replanner.route(tuple(pos), seed=cfg.seed)
        return plan_route(self.terrain, tuple(pos), tuple(self.goal), cost=self.cost, planner=cfg.planner,
                          time_limit_s=cfg.planner_time_limit_s, seed=cfg.seed, compare=False)

    def plan_initial(self, start: np.ndarray) -> None:
        t0 = time.perf_counter()
        builds0 = self.lem.table_builds
        self.cost = self.lem.energy_cost(self.terrain, self.cfg.speed_mps)
        refresh = time.perf_counter() - t0
        self.pos = start
        self.route = self.initial_route = self.plan(start)
        planning_s = self.route.planning_time_s
        if self.cfg.planner == "lattice" and self.route.found:  # seed the incremental search for the replans
            t0 = time.perf_counter()
            lattice = Lattice.for_cost(self.cost, PlannerSettings().lattice_stride_cells)  # plan_route's lattice
            self.replanner = IncrementalPlanner(lattice, tuple(self.goal))
            self.replanner.plan(tuple(start))
            planning_s += time.perf_counter() - t0
        self.pending = self.predictor.legs(self.route.waypoints_m, None) if self.route.found else []
        self.replans.append(ReplanRecord(0, "initial", sum(self.pending) if self.route.found else math.nan, math.nan,
                                         True, refresh, planning_s, self.lem.table_builds - builds0))
        self.push(0.0, start[0], start[1], self.soc, 0.0, 0.0)

    # ------------------------------------------------------------------ one leg
    def step(self, leg_index: int) -> bool:
        """Drive leg ``leg_index``, compare, update, replan; False when the loop stops."""
        if np.hypot(*(self.pos - self.goal)) <= self.cfg.goal_tolerance_m:
            return self.stop("completed", "reached the goal")
        if not self.route.found:
            return self.stop("no_route", f"no route from {tuple(self.pos.round(2))} to the goal "
                                         f"(planner status {self.route.status!r})")
        avail_j, need_j = self.available_j(), sum(self.pending)
        if need_j > avail_j:
            return self.stop("budget_exceeded", (
                f"the remaining route needs {need_j / 3600:.2f} Wh (predicted) but only "
                f"{max(avail_j, 0.0) / 3600:.2f} Wh are left above the {self.battery.min_reserve_pct:g} % reserve"))
        tail, mr = self.drive_leg(leg_index)
        if mr.status == "reserve_violated":
            return self.stop("reserve_violated", (
                f"the battery reached its {self.battery.min_reserve_pct:g} % reserve at {mr.reserve_crossed_xy_m!r} m "
                f"during leg {leg_index}"))
        changed = False
        for region in self.compare_cells(mr.log):
            if sum(u.kind == "excitation" for u in self.updates) >= self.cfg.max_updates:
                break
            outcome = self.update_region(region, leg_index, mr)
            if outcome is None:  # the battery reached the reserve during the manoeuvre
                return False
            changed |= outcome
        if len(tail) < 2:  # the leg drove to the route's end: nothing to replan, even after an update
            return self.stop("completed", "reached the goal")
        if changed:
            self.replan(leg_index, tail)
        else:
            self.route = evaluate_route(self.cost, tail, status="exact", planner=self.route.planner)
        return True

    def drive_leg(self, leg_index: int) -> tuple[np.ndarray, Any]:
        """Drive the route's next leg (ends at the reserve); returns the rest of the route and the mission."""
        cfg = self.cfg
        head, tail = split_polyline(np.asarray(self.route.waypoints_m), cfg.leg_length_m)
        leg_route = evaluate_route(self.cost, head, status="exact", planner="leg")
        leg_pred_j = self.pending.pop(0) if self.pending else self.predictor.leg(head, self.heading)
        mr = simulate_mission(self.terrain, leg_route, self.robot, self.battery.replace(initial_soc=self.soc),
                              self.truth, self.cost, speed_mps=cfg.speed_mps, start_heading_rad=self.heading,
                              stop_at_reserve=True, seed=cfg.seed + 1000 + leg_index)
        budget = mr.budget
        self.leg_logs.append(mr.log)
        self.legs.append(LegRecord(leg_index, (float(self.pos[0]), float(self.pos[1])),
                                   (float(mr.x_m[-1]), float(mr.y_m[-1])), leg_pred_j, float(budget.actual_energy_j),
                                   float(mr.duration_s), int(mr.n_samples), float(budget.predicted_energy_j)))
        e_leg = np.asarray(mr.energy_wh) * 3600.0
        # the edge-cost prediction's progress along the leg, scaled to the profile prediction
        p_leg = np.asarray(mr.predicted_energy_wh) * 3600.0
        if budget.predicted_energy_j > 0:
            p_leg = p_leg * (leg_pred_j / budget.predicted_energy_j)
        self.push(self.clock + mr.time_s, mr.x_m, mr.y_m, mr.soc, self.e_total + e_leg, self.p_total + p_leg)
        self.add_draw(self.clock + mr.time_s, mr.power_w)
        self.clock += float(mr.time_s[-1])
        self.e_total += float(budget.actual_energy_j)
        self.p_total += leg_pred_j
        self.driven_j += float(budget.actual_energy_j)
        self.soc = float(mr.soc[-1])
        self.pos = np.array([mr.x_m[-1], mr.y_m[-1]])
        self.heading = float(mr.heading_rad[-1])
        self.leg_power_w = float(budget.actual_energy_j) / max(float(mr.duration_s), 1e-9)
        return tail, mr

    def compare_cells(self, log: InteractionLog) -> list[Any]:
        """Record measured vs predicted current per cell; the regions the policy flags."""
        rows, cols = self.terrain.rowcol(log.pose_xyh[:, 0], log.pose_xyh[:, 1])
        self.rows, self.cols = np.asarray(rows), np.asarray(cols)
        self.pred = predicted_currents(self.registry, log, self.rows, self.cols)
        self.meas = np.column_stack([log.current_left_a, log.current_right_a])
        self.dt = np.gradient(log.time_s)
        self.registry.record(self.rows, self.cols, np.abs(self.meas), np.abs(self.pred), self.dt)
        self.log = log
        return list(self.registry.flagged_regions(self.cfg.policy))

    # ------------------------------------------------------------------ decide an update
    def update_region(self, region: Any, leg_index: int, mr: Any) -> bool | None:
        """Reuse a model, skip, or excite and validate: True if the models changed, None if the
        battery reached the reserve during the manoeuvre."""
        cfg, registry = self.cfg, self.registry
        w0 = time.perf_counter()
        r, c = region.representative_row_col
        gid = int(self.terrain.ground[r, c])
        gname = self.terrain.ground_names.get(gid, str(gid))
        old_id = int(np.asarray(registry.model_id_map)[r, c])
        if cfg.update_scope == "ground_class":
            scope = (np.asarray(self.terrain.ground) == gid) & np.isin(np.asarray(registry.model_id_map),
                                                                       np.asarray(region.model_ids))
        else:
            scope = region.mask(registry.shape)
        if self.reuse(region, scope, gname, leg_index, w0):
            return True
        if (gid, old_id) in self.validated:
            # this model already proved itself on fresh excitation data of this ground: the
            # cells' error comes from transients (pivots, stops) they over-represent
            registry.reset_evidence(region)
            return False
        # Afford the manoeuvre? Estimated at the last leg's mean battery power, it and the
        # remaining route as predicted now must both fit above the reserve; else skip it.
        x_e_est = self.leg_power_w * (cfg.excitation_duration_s + cfg.turn_excitation_duration_s)
        if x_e_est > self.available_j() - sum(self.pending):
            self.skipped.append(f"after leg {leg_index}: no {gname!r} update, its ~{x_e_est / 3600:.2f} Wh "
                                "manoeuvre and the remaining route do not both fit above the reserve")
            registry.reset_evidence(region)
            return False
        return self.excite(region, scope, gid, gname, old_id, leg_index, w0)

    def reuse(self, region: Any, scope: np.ndarray, gname: str, leg_index: int, w0: float) -> bool:
        """Assign a model learned elsewhere that already explains what this leg measured in the
        region (the registry keeps it as a new version); True if one was assigned."""
        in_region = region.mask(self.registry.shape)[self.rows, self.cols]
        found = best_other_model(self.registry, self.log, in_region, self.meas, self.dt, region.model_ids,
                                 self.cfg.policy.min_samples)
        if found is None:
            return False
        mid, err = found
        err_now = charge_error(self.pred, self.meas, self.dt, in_region)  # the serving model(s), same samples
        if not err < min(self.cfg.policy.threshold_pct / 100.0, err_now):
            return False
        self.registry.assign(scope, mid, reason=(
            f"reuse: model {mid} ({self.registry.model_record(mid).name!r}) explains the {gname!r} region "
            f"driven in leg {leg_index} to {100 * err:.1f} % (the serving model: {100 * err_now:.1f} %)"))
        wall = time.perf_counter() - w0
        self.update_wall += wall
        self.updates.append(UpdateRecord(leg_index, gname, region.cell_count, int(np.count_nonzero(scope)),
                                         100.0 * region.relative_error, True, mid, err, err_now,
                                         0.0, 0.0, wall, kind="reuse"))
        return True

    def excite(self, region: Any, scope: np.ndarray, gid: int, gname: str, old_id: int, leg_index: int,
               w0: float) -> bool | None:
        """Drive the excitation manoeuvre on the spot, fit a new model on it, validate new and
        old on its held-back tails and let the registry keep the better one."""
        cfg, registry = self.cfg, self.registry
        seed = cfg.seed + 10_000 + 10 * len(self.updates)
        xlogs = excitation_manoeuvre(self.truth, gname, straight_s=cfg.excitation_duration_s,
                                     turn_s=cfg.turn_excitation_duration_s, speeds_mps=cfg.excitation_speeds_mps,
                                     omega_radps=cfg.excitation_omega_radps, seed=seed, sim_seed=seed + 2,
                                     dt_s=1.0 / self.truth.current_rate_hz)
        x_e, x_t, soc, crossed = self.discharge(xlogs)
        self.excitation_j += x_e
        self.e_total += x_e
        self.clock += x_t
        self.soc = soc
        self.push_here()
        if crossed:  # it stops at the reserve, nothing is learned
            self.update_wall += time.perf_counter() - w0
            self.stop("reserve_violated", (
                f"the battery reached its {self.battery.min_reserve_pct:g} % reserve {x_t:.1f} s into the "
                f"{gname!r} excitation manoeuvre at {tuple(self.pos.round(2).tolist())!r} m after leg "
                f"{leg_index}; no update was made from the incomplete data"))
            return None
        train, held = [], []
        for xl in xlogs:
            cut = xl.time_s[0] + (1.0 - cfg.validation_fraction) * (xl.time_s[-1] - xl.time_s[0])
            train.append(xl.slice(xl.time_s[0], cut))
            held.append(xl.slice(cut, xl.time_s[-1] + 1.0))
        new_model, kind = self.factory().fit(train), "excitation"
        err_new = validation_error(new_model, held)
        adapted = adapted_model(registry.model(old_id), train) if cfg.in_run_update else None
        err_adapted = validation_error(adapted, held) if adapted is not None else np.inf
        if err_adapted < err_new:  # the serving model updated in-run validates better than a refit
            new_model, err_new, kind = adapted, err_adapted, "in_run"
        err_old = validation_error(registry.model(old_id), held)
        decision = registry.propose_update(
            scope, new_model, err_new, err_old, name=f"update{len(self.updates) + 1}-{gname}",
            reason=f"region error {100 * region.relative_error:+.1f} % after leg {leg_index}",
            meta={"ground": gname, "after_leg": leg_index})
        if decision.accepted:
            self.lem.set_vibration(decision.model_id, xlogs[0].accel_time_s, xlogs[0].accel_z_mps2)
            self.validated.add((gid, int(decision.model_id)))
        else:
            self.validated.add((gid, old_id))
            registry.reset_evidence(region)
        wall = time.perf_counter() - w0
        self.update_wall += wall
        self.updates.append(UpdateRecord(leg_index, gname, region.cell_count, int(np.count_nonzero(scope)),
                                         100.0 * region.relative_error, bool(decision.accepted), decision.model_id,
                                         err_new, err_old, x_e, x_t, wall, kind))
        return bool(decision.accepted)

    def discharge(self, logs: list[InteractionLog]) -> tuple[float, float, float, bool]:
        """Draw the battery through ``logs`` driven one after another (:func:`energy.discharge_from_power`):
        energy (J), time (s), the state of charge after, and whether the reserve was reached
        (the manoeuvre then stops there)."""
        energy_j = elapsed_s = 0.0
        soc = self.soc
        for log in logs:
            t = log.time_s - log.time_s[0]
            power = log_battery_power_w(log, self.robot)
            d = discharge_from_power(self.battery.replace(initial_soc=soc), t, power)
            if d.reserve_crossed_time_s is not None:
                tc = float(d.reserve_crossed_time_s)
                k = int(d.reserve_crossed_index)
                self.add_draw(self.clock + elapsed_s + np.append(t[:k], tc),
                              np.append(power[:k], np.interp(tc, t, power)))
                return (energy_j + float(np.interp(tc, t, d.energy_j)), elapsed_s + tc,
                        self.battery.reserve_soc, True)
            self.add_draw(self.clock + elapsed_s + t, power)
            energy_j += float(d.total_energy_j)
            elapsed_s += float(t[-1])
            soc = float(d.final_soc)
        return energy_j, elapsed_s, soc, False

    # ------------------------------------------------------------------ replan
    def replan(self, leg_index: int, tail: np.ndarray) -> None:
        """Refresh the edge costs for the changed models and replan from here; keep the old
        route when the planner finds nothing better."""
        t1 = time.perf_counter()
        builds0 = self.lem.table_builds
        self.cost = self.lem.energy_cost(self.terrain, self.cfg.speed_mps, previous=self.cost)  # reweighted
        if self.replanner is not None:  # the changed moves of the refreshed lattice
            self.replanner.update(Lattice.for_cost(self.cost, self.replanner.lattice.stride_cells))
        refresh = time.perf_counter() - t1
        old_energy = evaluate_route(self.cost, tail).energy_j if len(tail) >= 2 else 0.0
        route = self.plan(self.pos)
        if route.found:
            same = route.waypoints_m.shape == tail.shape and np.allclose(route.waypoints_m, tail, atol=1e-6)
            if not same and old_energy <= route.energy_j:  # planner found nothing better: keep the old one
                route, same = evaluate_route(self.cost, tail, status="exact", planner="kept"), True
            self.pending = self.predictor.legs(route.waypoints_m, self.heading)  # the models changed
        else:
            same, self.pending = False, []
        self.route = route
        self.update_wall += refresh
        self.replans.append(ReplanRecord(leg_index, "update", sum(self.pending) if route.found else math.nan,
                                         old_energy, not same, refresh, route.planning_time_s,
                                         self.lem.table_builds - builds0))

    def budget(self) -> EnergyBudget:
        """The whole mission's draw (driving and manoeuvres) against the first plan's prediction;
        with nothing driven, no draw over the first plan's duration."""
        first = self.replans[0].predicted_energy_j
        predicted_j = first if math.isfinite(first) else 0.0
        if self.draw:
            t, p = (np.concatenate(parts) for parts in zip(*self.draw))
        else:
            span = self.initial_route.duration_s if self.initial_route.found else 0.0
            t, p = np.array([0.0, span if span > 0 else 1.0]), np.zeros(2)
        return energy_budget(discharge_from_power(self.battery, t, p), predicted_j)

    def result(self) -> AdaptiveResult:
        cat = {k: np.concatenate(v) for k, v in self.series.items()}
        pos = self.pos
        return AdaptiveResult(
            status=self.status, reason=self.reason, final_xy_m=(float(pos[0]), float(pos[1])),
            distance_to_goal_m=float(np.hypot(*(pos - self.goal))), initial_route=self.initial_route,
            legs=tuple(self.legs), updates=tuple(self.updates), replans=tuple(self.replans), time_s=cat["t"],
            x_m=cat["x"], y_m=cat["y"], soc=cat["soc"], energy_j=cat["e"], predicted_energy_j=cat["p"],
            driven_energy_j=self.driven_j, excitation_energy_j=self.excitation_j,
            update_wall_time_s=self.update_wall, final_soc=self.soc, skipped_updates=tuple(self.skipped),
            budget=self.budget(), leg_logs=tuple(self.leg_logs),
        )
