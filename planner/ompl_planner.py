"""Minimum-energy route planning with OMPL (and the reference lattice), returning Route results.

The OMPL problem is a 2-D real-vector space over the map bounds. A state is valid on a free
cell (no obstacle, slope at most ``max_slope_rad``); a motion is valid when its exact cell
walk crosses no blocked cell and meets no undrivable grade — a Python
:class:`ompl.base.MotionValidator` that calls the same compiled walk as the cost, so validity
and cost never disagree (no discrete validity resolution is involved). The objective's motion
cost is the segment's drive energy (J), asymmetric (``isSymmetric`` returns False: uphill
``!=`` downhill), with the admissible ``motionCostHeuristic`` of
:meth:`EnergyCost.lower_bound_j` (BIT* and informed sampling use it). OMPL does not dispatch
``costToGo`` to Python overrides and ``setCostToGoHeuristic`` rejects Python callables, so
the informed RRT* variants see a zero cost-to-go (admissible, weak). Turn energies are not
part of OMPL's objective (a 2-D state has no heading); every route is evaluated with them.

Choose a planner by name from :data:`PLANNERS`. ``"lattice"`` is the fast path: the
directed 16-connected lattice optimum. With ``refine=True`` (default) every exact route is
post-processed by :func:`refine_route`: OMPL's ``partialShortcutPath`` and ``perturbPath``
under the energy objective, then :meth:`EnergyCost.relax_path`; each step is kept only when
the route's true energy — segments plus turns, re-evaluated exactly — went down.

Determinism: give ``seed`` and ``max_cost_evaluations`` (a work bound counted in objective
motion-cost calls) and leave ``time_limit_s=None``; the same inputs then give the same route,
in any process and whatever was planned before. Time-bounded runs are not reproducible.

Every plan also reports the shortest-distance route's energy (``Route.energy_saved_pct``)
and the lattice optimum (``Route.optimality_ratio``) unless ``compare=False``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from numbers import Integral, Real
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrain.errors import (
    BlockedPositionError,
    GridMismatchError,
    InvalidParameterError,
    OutOfBoundsError,
    PlanningError,
    UnknownNameError,
)

from .edge_cost import EnergyCost, _point_free, _walk_forward
from .lattice import Lattice, string_pull
from .route import Route, _empty_route, evaluate_route

__all__ = [
    "plan_route",
    "shortest_route",
    "refine_route",
    "PlannerSettings",
    "PLANNERS",
    "OMPL_PLANNERS",
]

#: OMPL optimising planners that work with the Python energy objective.
OMPL_PLANNERS = ("RRTstar", "InformedRRTstar", "SORRTstar", "BITstar", "FMT")
#: Every planner name :func:`plan_route` accepts.
PLANNERS = OMPL_PLANNERS + ("lattice",)


@dataclass(frozen=True)
class PlannerSettings:
    """Tuning of the planners (defaults measured on 512 x 512 procedural maps).

    Parameters
    ----------
    rewire_factor : float
        RRT*-family rewiring radius factor (> 0; OMPL's default is 1.1). Smaller values
        make fewer ``motionCost`` calls per iteration, hence more iterations per second.
    range_m : float or None
        Maximum motion length of the RRT* family (m, > 0); ``None`` keeps OMPL's default
        (20 % of the map diagonal).
    goal_bias : float
        Probability of sampling the goal in the RRT* family, in [0, 1].
    fmt_samples : int
        Number of samples of FMT* (>= 10); FMT* is a batch planner: its work is fixed by
        this (500 samples take ~0.4 s on a 512 x 512 map), and it returns ``timeout`` if the
        time limit or the work bound cuts it short.
    bit_samples_per_batch : int
        Samples per batch of BIT* (>= 1).
    lattice_stride_cells : int
        Node spacing (cells) of the lattice used by the ``"lattice"`` planner (>= 1; the
        reference optimum of ``Route.optimality_ratio`` always uses 1). Coarser lattices
        solve faster; the refinement then recovers most of the difference.
    refine_max_steps : int
        Attempts of each OMPL refinement pass (``partialShortcutPath`` / ``perturbPath``), >= 1.
    refine_rounds : int
        Number of (shortcut, perturb) rounds (>= 1).

    Raises
    ------
    InvalidParameterError
        Any value out of range.
    """

    rewire_factor: float = 0.5
    range_m: float | None = None
    goal_bias: float = 0.05
    fmt_samples: int = 500
    bit_samples_per_batch: int = 200
    lattice_stride_cells: int = 1
    refine_max_steps: int = 300
    refine_rounds: int = 2

    def __post_init__(self) -> None:
        def real(name: str, lo: float, hi: float = math.inf, lo_open: bool = True) -> None:
            v = getattr(self, name)
            ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            ok = ok and (v > lo if lo_open else v >= lo) and v <= hi
            if not ok:
                raise InvalidParameterError(f"PlannerSettings.{name} must be a finite number in range, got {v!r}")

        def count(name: str, lo: int) -> None:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, Integral) or v < lo:
                raise InvalidParameterError(f"PlannerSettings.{name} must be an integer >= {lo}, got {v!r}")

        real("rewire_factor", 0.0)
        if self.range_m is not None:
            real("range_m", 0.0)
        real("goal_bias", 0.0, 1.0, lo_open=False)
        count("fmt_samples", 10)
        count("bit_samples_per_batch", 1)
        count("lattice_stride_cells", 1)
        count("refine_max_steps", 1)
        count("refine_rounds", 1)


# --------------------------------------------------------------------------- input checks
def _check_point(cost: EnergyCost, xy: Any, name: str) -> np.ndarray:
    try:
        p = np.asarray(xy, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be (x_m, y_m), got {xy!r}") from None
    if p.shape != (2,):
        raise InvalidParameterError(f"{name} must be (x_m, y_m), got {xy!r}")
    if not np.all(np.isfinite(p)):
        raise InvalidParameterError(f"{name} must be finite coordinates in metres, got {xy!r}")
    if not cost.terrain.contains(p[0], p[1]):
        raise OutOfBoundsError(f"{name} {tuple(p.tolist())!r} m lies outside the map bounds {cost.terrain.bounds!r}")
    r, c = cost.terrain.rowcol(p[0], p[1])
    if cost.blocked[r, c]:
        if cost.terrain.obstacle[r, c]:
            why = "on an obstacle"
        else:
            why = (
                f"on ground steeper ({math.degrees(float(cost.terrain.slope_rad[r, c])):.1f} deg) than "
                f"max_slope_rad ({math.degrees(cost.max_slope_rad):.1f} deg)"
            )
        raise BlockedPositionError(
            f"{name} {tuple(p.tolist())!r} m lies {why} (cell row {r}, col {c}); expected a free cell"
        )
    return p


def _check_budget(time_limit_s: Any, max_cost_evaluations: Any) -> tuple[float | None, int | None]:
    if max_cost_evaluations is not None:
        n = max_cost_evaluations
        if isinstance(n, bool) or not isinstance(n, Integral) or n < 1:
            raise InvalidParameterError(f"max_cost_evaluations must be an integer >= 1 or None, got {n!r}")
        max_cost_evaluations = int(max_cost_evaluations)
    if time_limit_s is None:
        if max_cost_evaluations is None:
            raise InvalidParameterError("time_limit_s and max_cost_evaluations are both None; give at least one budget")
        return None, max_cost_evaluations
    is_number = isinstance(time_limit_s, Real) and not isinstance(time_limit_s, bool)
    t = float(time_limit_s) if is_number else math.nan
    if not (math.isfinite(t) and t > 0):
        raise InvalidParameterError(f"time_limit_s must be a finite number > 0 or None, got {time_limit_s!r}")
    return t, max_cost_evaluations


def _check_seed(seed: Any) -> int | None:
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, Integral) or not 0 <= seed < 2**32 - 1:
        raise InvalidParameterError(f"seed must be an integer in [0, 2**32 - 1) or None, got {seed!r}")
    return int(seed)


# --------------------------------------------------------------------------- OMPL problem
def _ompl():
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    return ob, og, ou


def _seed_ompl(seed: int | None) -> None:
    """Seed OMPL's RNG with ``seed + 1`` (OMPL treats 0 as "no seed": runs seeded with 0 were
    not reproducible). OMPL logs an error when RNGs already exist in the process, yet the new
    seed does take effect for every RNG created afterwards (tested, whatever ran before), so
    that message is muted."""
    if seed is None:
        return
    _, _, ou = _ompl()
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)
    try:
        ou.RNG.setSeed(int(seed) + 1)
    finally:
        ou.setLogLevel(level)


class _Problem:
    """Space, validity, objective and start/goal of one solve (fresh per solve, OMPL trap 7)."""

    def __init__(self, cost: EnergyCost, start: np.ndarray, goal: np.ndarray, max_evals: int | None) -> None:
        ob, _, _ = _ompl()
        cells, table, geo = cost._cells, cost.grade_table_j_per_m, cost._geo
        walk = _walk_forward
        point_free = _point_free
        fmin = cost.min_energy_per_metre_j
        counter = [0]
        self.counter = counter
        self.cost = cost

        space = ob.RealVectorStateSpace(2)
        xmin, ymin, xmax, ymax = cost.terrain.bounds
        bounds = ob.RealVectorBounds(2)
        bounds.setLow(0, xmin)
        bounds.setLow(1, ymin)
        bounds.setHigh(0, xmax)
        bounds.setHigh(1, ymax)
        space.setBounds(bounds)
        si = ob.SpaceInformation(space)
        si.setStateValidityChecker(lambda s: bool(point_free(cells, geo, s[0], s[1])))

        class MotionValidator(ob.MotionValidator):
            def checkMotion(self, a, b):  # noqa: N802 - OMPL API
                return math.isfinite(walk(cells, table, geo, a[0], a[1], b[0], b[1]))

        class EnergyObjective(ob.OptimizationObjective):
            def motionCost(self, a, b):  # noqa: N802 - OMPL API
                counter[0] += 1
                return ob.Cost(walk(cells, table, geo, a[0], a[1], b[0], b[1]))

            def stateCost(self, s):  # noqa: N802 - OMPL API
                return ob.Cost(0.0)

            def isSymmetric(self):  # noqa: N802 - OMPL API
                return False

            def motionCostHeuristic(self, a, b):  # noqa: N802 - OMPL API
                return ob.Cost(fmin * math.hypot(b[0] - a[0], b[1] - a[1]))

        self.validator = MotionValidator(si)
        si.setMotionValidator(self.validator)
        si.setup()
        self.space, self.si = space, si
        self.objective = EnergyObjective(si)
        self.start_state = self.state(start)
        self.goal_state = self.state(goal)
        pdef = ob.ProblemDefinition(si)
        # A GoalState (sampleable, as BIT* needs); threshold well below a cell.
        pdef.setStartAndGoalStates(self.start_state, self.goal_state, 1e-6 * cost.terrain.cell_size_m)
        pdef.setOptimizationObjective(self.objective)
        self.pdef = pdef
        self.max_evals = max_evals

    def state(self, xy: np.ndarray):
        s = self.space.allocState()
        s[0] = float(xy[0])
        s[1] = float(xy[1])
        return s

    def path(self, waypoints: np.ndarray):
        _, og, _ = _ompl()
        path = og.PathGeometric(self.si)
        for p in waypoints:
            path.append(self.state(p))
        return path

    @staticmethod
    def coords(path) -> np.ndarray:
        """Copy a path's coordinates out at once (states are views, OMPL trap 5)."""
        n = path.getStateCount()
        out = np.empty((n, 2))
        for i in range(n):
            s = path.getState(i)
            out[i, 0] = s[0]
            out[i, 1] = s[1]
        return out

    def termination(self, deadline: float | None):
        ob, _, _ = _ompl()
        counter, max_evals = self.counter, self.max_evals

        def done() -> bool:
            if max_evals is not None and counter[0] >= max_evals:
                return True
            return deadline is not None and time.perf_counter() >= deadline

        return ob.PlannerTerminationCondition(done)


def _make_planner(name: str, problem: _Problem, settings: PlannerSettings):
    _, og, _ = _ompl()
    planner = getattr(og, name)(problem.si)
    if name in ("RRTstar", "InformedRRTstar", "SORRTstar"):
        planner.setRewireFactor(settings.rewire_factor)
        planner.setGoalBias(settings.goal_bias)
        if settings.range_m is not None:
            planner.setRange(settings.range_m)
    elif name == "BITstar":
        planner.setSamplesPerBatch(settings.bit_samples_per_batch)
    elif name == "FMT":
        planner.setNumSamples(settings.fmt_samples)
    planner.setProblemDefinition(problem.pdef)
    planner.setup()
    return planner


def _solve_ompl(
    cost: EnergyCost,
    start: np.ndarray,
    goal: np.ndarray,
    name: str,
    time_limit_s: float | None,
    max_evals: int | None,
    seed: int | None,
    settings: PlannerSettings,
) -> tuple[str, np.ndarray | None, float, int]:
    """Run one OMPL planner; returns (status, waypoints or None, planning time, cost evaluations)."""
    ob, _, ou = _ompl()
    level = ou.getLogLevel()
    # WARN would print RejectionInfSampler's note on each informed solve: Python objectives
    # cannot install a C++ cost-to-go function (setCostToGoHeuristic rejects Python
    # callables), so informed sampling uses the cost-to-come heuristic alone.
    ou.setLogLevel(ou.LOG_ERROR)
    try:
        _seed_ompl(seed)
        t0 = time.perf_counter()
        problem = _Problem(cost, start, goal, max_evals)
        planner = _make_planner(name, problem, settings)
        deadline = None if time_limit_s is None else t0 + time_limit_s
        status = planner.solve(problem.termination(deadline))
        kind = status.getStatus()
        PS = ob.PlannerStatus
        waypoints = None
        if kind in (PS.EXACT_SOLUTION, PS.APPROXIMATE_SOLUTION) and problem.pdef.hasSolution():
            waypoints = _Problem.coords(problem.pdef.getSolutionPath())
            exact = kind == PS.EXACT_SOLUTION and problem.pdef.hasExactSolution()
            result = "exact" if exact else "approximate"
        elif kind == PS.TIMEOUT:
            result = "timeout"
        elif kind == PS.INFEASIBLE:
            result = "infeasible"
        else:
            raise PlanningError(f"OMPL planner {name!r} returned status {status.asString()!r}")
        elapsed = time.perf_counter() - t0
        evals = problem.counter[0]
        planner.clear()
        del planner, problem
        return result, waypoints, elapsed, evals
    finally:
        ou.setLogLevel(level)


def refine_route(
    cost: EnergyCost,
    waypoints_m: Any,
    *,
    seed: int | None = None,
    max_steps: int = 300,
    rounds: int = 2,
    relax: bool = True,
) -> np.ndarray:
    """Improve a valid route with OMPL's energy-aware shortcuts; keep only true improvements.

    Each round runs ``PathSimplifier.partialShortcutPath`` and ``perturbPath`` with the energy
    objective; after each step the candidate's *true* energy (exact segments plus turns,
    :meth:`EnergyCost.path_energy_j`) is compared with the best so far and kept only if it
    went down (OMPL_NOTES trap 4: OMPL's own estimate can disagree). With ``relax``, the
    result is then polished by :meth:`EnergyCost.relax_path` (compiled vertex-wise pattern
    search on the true energy, turns included), again kept only if it lowers the energy.

    Parameters
    ----------
    cost : EnergyCost
        Edge costs.
    waypoints_m : array_like, shape (K, 2)
        A valid route (finite energy).
    seed : int, optional
        Seeds OMPL's RNG (the refinement is random).
    max_steps : int
        Attempts per pass (>= 1).
    rounds : int
        Number of (shortcut, perturb) rounds (>= 1).
    relax : bool
        Finish with :meth:`EnergyCost.relax_path`.

    Returns
    -------
    ndarray, shape (K', 2)
        A route with the same ends and true energy <= the input's.

    Raises
    ------
    InvalidParameterError
        An invalid input route, or bad ``max_steps`` / ``rounds``.
    """
    pts = np.asarray(waypoints_m, dtype=np.float64)
    best_e = cost.path_energy_j(pts)
    if not math.isfinite(best_e):
        raise InvalidParameterError("waypoints_m crosses a blocked cell; refine_route needs a valid route")
    for name, v in (("max_steps", max_steps), ("rounds", rounds)):
        if isinstance(v, bool) or not isinstance(v, Integral) or v < 1:
            raise InvalidParameterError(f"{name} must be an integer >= 1, got {v!r}")
    seed = _check_seed(seed)
    if pts.shape[0] < 3:
        return cost.relax_path(pts) if relax else pts.copy()
    _, og, ou = _ompl()
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_ERROR)
    try:
        _seed_ompl(seed)
        problem = _Problem(cost, pts[0], pts[-1], None)
        simplifier = og.PathSimplifier(problem.si, problem.pdef.getGoal(), problem.objective)
        best = pts.copy()
        step_m = 2.0 * cost.terrain.cell_size_m
        for _ in range(int(rounds)):
            for op in ("shortcut", "perturb"):
                path = problem.path(best)
                if op == "shortcut":
                    simplifier.partialShortcutPath(path, int(max_steps), 0, 0.33, 0.005)
                else:
                    simplifier.perturbPath(path, step_m, int(max_steps), 0, 0.005)
                cand = _Problem.coords(path)
                del path
                e = cost.path_energy_j(cand)
                if e < best_e:
                    best, best_e = cand, e
            step_m *= 0.5
        del simplifier, problem
        if relax:
            best = cost.relax_path(best)
        return best
    finally:
        ou.setLogLevel(level)


# --------------------------------------------------------------------------- plan_route
def _optimum_key(start: np.ndarray, goal: np.ndarray) -> tuple:
    return ("optimum", tuple(start.tolist()), tuple(goal.tolist()))


def _lattice_optimum(cost: EnergyCost, start: np.ndarray, goal: np.ndarray):
    """The 1-cell lattice's minimum-energy path for a query (cached on the cost)."""
    key = _optimum_key(start, goal)
    if key not in cost._cache:
        cost._cache[key] = Lattice.for_cost(cost, 1).shortest_path(start, goal, weight="energy")
    return cost._cache[key]


def shortest_route(cost: EnergyCost, start_xy_m: tuple[float, float], goal_xy_m: tuple[float, float]) -> Route:
    """The shortest-distance route between two points, costed in energy.

    The straight line when it is free; otherwise the shortest route on the 1-cell lattice
    (edge weights = lengths) straightened by greedy line-of-sight shortcuts
    (:func:`string_pull`). It is the baseline of ``Route.energy_saved_pct``.

    Returns
    -------
    Route
        ``planner="shortest"``; status ``"exact"``, or ``"infeasible"`` when start and goal
        lie in different free regions.

    Raises
    ------
    InvalidParameterError, OutOfBoundsError, BlockedPositionError
        As :func:`plan_route` for bad start / goal points.
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    start = _check_point(cost, start_xy_m, "start_xy_m")
    goal = _check_point(cost, goal_xy_m, "goal_xy_m")
    t0 = time.perf_counter()
    if math.isfinite(cost.segment_energy_one_j(start[0], start[1], goal[0], goal[1])):
        pts = np.array([start, goal])
    else:
        lp = Lattice.for_cost(cost, 1).shortest_path(start, goal, weight="length")
        if not lp.found:
            return _empty_route("infeasible", "shortest", time.perf_counter() - t0, cost.battery_voltage_v)
        pts = string_pull(cost, lp.waypoints_m)
    return evaluate_route(cost, pts, status="exact", planner="shortest", planning_time_s=time.perf_counter() - t0)


def _shortest_distance_energy(cost: EnergyCost, start: np.ndarray, goal: np.ndarray) -> float:
    """Energy (J, turns included) of :func:`shortest_route` (cached on the cost)."""
    key = ("shortest", tuple(start.tolist()), tuple(goal.tolist()))
    if key not in cost._cache:
        route = shortest_route(cost, start, goal)
        cost._cache[key] = route.energy_j if route.found else math.nan
    return cost._cache[key]


def plan_route(
    terrain: TerrainMap,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    *,
    cost: EnergyCost,
    planner: str = "RRTstar",
    time_limit_s: float | None = 1.0,
    seed: int | None = None,
    max_cost_evaluations: int | None = None,
    refine: bool = True,
    compare: bool = True,
    settings: PlannerSettings | None = None,
) -> Route:
    """Plan a minimum-energy route from start to goal.

    Parameters
    ----------
    terrain : TerrainMap
        The map; must be the grid ``cost`` was built on.
    start_xy_m, goal_xy_m : (float, float)
        World coordinates (m) of a free cell each.
    cost : EnergyCost
        Edge costs (see :meth:`EnergyCost.from_model`).
    planner : str
        One of :data:`PLANNERS`: ``"RRTstar"``, ``"InformedRRTstar"``, ``"SORRTstar"``,
        ``"BITstar"``, ``"FMT"`` (OMPL, minimising drive energy) or ``"lattice"`` (the
        directed 16-connected lattice optimum).
    time_limit_s : float or None
        Wall-clock budget of the OMPL solve (s); ignored by ``"lattice"``. ``None``
        requires ``max_cost_evaluations``.
    seed : int, optional
        Seeds OMPL's RNG (OMPL planners and the refinement).
    max_cost_evaluations : int, optional
        Work bound of OMPL planners: stop after this many objective motion-cost calls.
        With ``seed`` and ``time_limit_s=None`` the result is reproducible; with both
        budgets the first one reached stops the solve.
    refine : bool
        Post-process an exact route with :func:`refine_route` (OMPL energy shortcuts, then
        :meth:`EnergyCost.relax_path`), each step kept only if the true energy (turns
        included) went down. The route's ``planner`` then reads e.g. ``"RRTstar+refine"``;
        the refinement time is part of ``planning_time_s``.
    compare : bool
        Also compute the lattice optimum (``Route.lattice_energy_j``, ``optimality_ratio``)
        and the shortest-distance route's energy (``shortest_energy_j``,
        ``energy_saved_pct``). Their cost (the first call builds the lattice graph, cached
        on ``cost``) is not part of ``planning_time_s``.
    settings : PlannerSettings, optional
        Planner tuning.

    Returns
    -------
    Route
        ``status`` ``"exact"`` / ``"approximate"`` / ``"timeout"`` / ``"infeasible"``; the
        last three raise nothing (call :meth:`Route.raise_for_status` to get a
        :class:`PlanningError`). ``"infeasible"`` is decided before planning: start and goal
        lie in different 4-connected regions of free cells, which is exact when every grade
        of every ground is drivable; when the model marks some grades undrivable (``inf``)
        the lattice planner also reports ``"infeasible"`` if its 1-cell lattice has no route.

    Raises
    ------
    UnknownNameError
        Unknown planner name (the message lists the valid ones).
    InvalidParameterError
        NaN coordinates, bad budgets, seed or settings.
    OutOfBoundsError
        Start or goal outside the map.
    BlockedPositionError
        Start or goal on an obstacle or on ground steeper than ``cost.max_slope_rad``.
    GridMismatchError
        ``cost`` was built for another grid.

    Examples
    --------
    >>> from energy import PhysicsEnergyModel, ground_preset, robot_preset
    >>> from planner import EnergyCost
    >>> from terrain import flat_map
    >>> tmap = flat_map((30, 40), 1.0)  # level asphalt, 1 m cells
    >>> cost = EnergyCost.from_model(tmap, PhysicsEnergyModel(robot_preset("husky")),
    ...                              {"asphalt": ground_preset("asphalt")}, speed_mps=0.5)
    >>> route = plan_route(tmap, (5.0, 5.0), (35.0, 25.0), cost=cost, planner="lattice")
    >>> route.status, round(route.length_m, 2)  # level ground: the straight line
    ('exact', 36.06)
    """
    if not isinstance(planner, str) or planner not in PLANNERS:
        raise UnknownNameError(f"planner must be one of {list(PLANNERS)!r}, got {planner!r}")
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    if not isinstance(terrain, TerrainMap):
        raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
    if terrain is not cost.terrain and not terrain.same_grid(cost.terrain):
        raise GridMismatchError(f"cost was built for the grid of {cost.terrain!r}, not of {terrain!r}")
    settings = PlannerSettings() if settings is None else settings
    if not isinstance(settings, PlannerSettings):
        raise InvalidParameterError(f"settings must be a PlannerSettings, got {type(settings).__name__!r}")
    start = _check_point(cost, start_xy_m, "start_xy_m")
    goal = _check_point(cost, goal_xy_m, "goal_xy_m")
    if planner == "lattice" and time_limit_s is None and max_cost_evaluations is None:
        time_limit, max_evals = None, None
    else:
        time_limit, max_evals = _check_budget(time_limit_s, max_cost_evaluations)
    seed = _check_seed(seed)

    labels = cost.components()
    rs, cs = cost.terrain.rowcol(start[0], start[1])
    rg, cg = cost.terrain.rowcol(goal[0], goal[1])
    if labels[rs, cs] != labels[rg, cg]:
        return _empty_route("infeasible", planner, 0.0, cost.battery_voltage_v)

    if planner == "lattice":
        stride = settings.lattice_stride_cells
        lattice = Lattice.for_cost(cost, stride)  # building the graph is map preparation
        t0 = time.perf_counter()
        path = lattice.shortest_path(start, goal, weight="energy")
        if not path.found and stride > 1:  # a passage too narrow for the coarse lattice
            stride = 1
            path = Lattice.for_cost(cost, 1).shortest_path(start, goal, weight="energy")
        elapsed = time.perf_counter() - t0
        if stride == 1:
            cost._cache[_optimum_key(start, goal)] = path
        status = "exact" if path.found else "infeasible"
        waypoints = path.waypoints_m if path.found else None
    else:
        status, waypoints, elapsed, _ = _solve_ompl(cost, start, goal, planner, time_limit, max_evals, seed, settings)
    name = planner
    if waypoints is not None and status == "exact" and refine:
        t0 = time.perf_counter()
        waypoints = refine_route(
            cost, waypoints, seed=seed, max_steps=settings.refine_max_steps, rounds=settings.refine_rounds
        )
        elapsed += time.perf_counter() - t0
        name = f"{planner}+refine"
    if waypoints is None:
        route = _empty_route(status, name, elapsed, cost.battery_voltage_v)
    else:
        route = evaluate_route(cost, waypoints, status=status, planner=name, planning_time_s=elapsed)
    if compare:
        shortest = _shortest_distance_energy(cost, start, goal)
        optimum = _lattice_optimum(cost, start, goal)
        route = route.replace(
            shortest_energy_j=shortest,
            lattice_energy_j=optimum.objective if optimum.found else math.nan,
        )
    return route
