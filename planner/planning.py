"""Plan a minimum-energy route: plan_route (OMPL, lattice, any-angle, coarse), shortest_route, plan_coarse_to_fine.

Choose a planner by name from :data:`PLANNERS`: the OMPL planners of
:data:`~planner.ompl.OMPL_PLANNERS` (a 2-D problem over the map whose objective is the
directed drive energy, :mod:`planner.ompl`), ``"lattice"``, the fast path: the optimum of the
16-connected lattice searched over node and heading, drive and turns
(:mod:`planner.heading_lattice`), or ``"anyangle"``: Theta* on the
drive energy in a corridor around a coarse lattice route (:mod:`planner.anyangle`), refined
by its compiled polish (:func:`planner.anyangle.polish_path`) instead of the OMPL shortcuts.
With ``refine=True`` (default) every other exact route is post-processed by
:func:`~planner.refine.refine_route`: OMPL's
``partialShortcutPath`` and ``perturbPath`` under the energy objective, then
:func:`~planner.refine.relax_path`; each step is kept only when the route's true energy —
segments plus turns, re-evaluated exactly — went down. The lattice's search minimises that
price (its states carry the heading); the OMPL and any-angle searches minimise drive energy
alone (a 2-D state has no heading), and their refinement adds the turns.

Determinism: the lattice search is exact and the refinement is seeded (``seed``, or 0 when
``seed=None``), so a lattice plan is the same in every run. OMPL planners are seeded only by
an explicit ``seed``; give it and ``max_cost_evaluations`` (a work bound counted in
objective motion-cost calls) and leave ``time_limit_s=None``, and the same inputs give the
same route in any process, whatever was planned before. Time-bounded runs are not
reproducible.

Coarse-to-fine (``planner="coarse"``, :mod:`planner.coarse`) has one door for its own result,
:func:`plan_coarse_to_fine`: on a map in memory (an :class:`EnergyCost`) or on a GeoTIFF DEM read
by windows (a path, :mod:`planner.coarse_geotiff`), tuned by one :class:`~planner.coarse.CoarseOptions`.

Comparisons (the shortest-distance route and the lattice optimum, :class:`RouteComparison`)
are computed only with ``compare=True``, once per query: they are cached on the cost
(:attr:`EnergyCost.results`, a bounded LRU cache).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrawatt_base.checks import check_bool, check_choice, check_instance, check_int, check_real, check_seed
from terrawatt_base.errors import GridMismatchError, InvalidParameterError

from .anyangle import anyangle_path
from .coarse import CoarseOptions, CoarseToFine, coarse_to_fine_in_memory
from .coarse_geotiff import CostBuilder, coarse_to_fine_windowed
from .edge_cost import EnergyCost
from .heading_lattice import heading_shortest_path
from .lattice import Lattice, LatticePath
from .ompl import OMPL_PLANNERS
from .ompl import solve as solve_ompl
from .problem import PlanningProblem
from .refined import REFINE_DEFAULT_SEED, refine_planned, shortest_of, shortest_route
from .route import Route, RouteComparison, empty_route, evaluate_route
from .settings import PlannerSettings

__all__ = ["plan_route", "RouteSearch", "shortest_route", "compare_route", "plan_coarse_to_fine", "PLANNERS", "PLANNER_SEARCHES",
           "PlannerSearch", "OMPL_PLANNERS", "GRAPH_PLANNERS", "REFINE_DEFAULT_SEED", "search_objective", "refine_planned"]

#: Every planner name :func:`plan_route` accepts (the keys of :data:`PLANNER_SEARCHES`).
PLANNERS = OMPL_PLANNERS + ("anyangle", "coarse", "lattice")
#: Planners that ignore time budgets (deterministic graph searches, run to their end).
GRAPH_PLANNERS = ("anyangle", "coarse", "lattice")


def search_objective(planner: str) -> str:
    """What ``planner``'s search minimises, in words (route.json's ``search_objective``): the lattice the
    reported price itself, drive and turns; the others drive energy, their turns paid only through the
    refinement, which keeps a step only when drive and turns together went down."""
    check_choice("planner", planner, PLANNERS)
    if planner == "lattice":
        return "drive and turn energy (the heading lattice's optimum: the price every route reports)"
    return ("drive energy (a search without heading cannot see turns); the refinement keeps only steps that "
            "lower drive and turn energy together")


# --------------------------------------------------------------------------- input checks
def _check_budget(time_limit_s: Any, max_cost_evaluations: Any) -> tuple[float | None, int | None]:
    if max_cost_evaluations is not None:
        max_cost_evaluations = check_int("max_cost_evaluations", max_cost_evaluations, low=1)
    if time_limit_s is None:
        if max_cost_evaluations is None:
            raise InvalidParameterError("time_limit_s and max_cost_evaluations are both None; give at least one budget")
        return None, max_cost_evaluations
    return check_real("time_limit_s", time_limit_s, low=0.0, low_inclusive=False), max_cost_evaluations


def _lattice_optimum(problem: PlanningProblem) -> LatticePath:
    """The 1-cell heading lattice's minimum-energy path of a query, turns included (cached on the cost)."""
    return problem.cost.results.get_or_make(("optimum", *problem.key), lambda: heading_shortest_path(
        Lattice.for_cost(problem.cost, 1), problem.start, problem.goal))


def compare_route(cost: EnergyCost, start_xy_m: tuple[float, float], goal_xy_m: tuple[float, float]) -> RouteComparison:
    """The baselines of a query: the shortest-distance route and the 1-cell lattice optimum.

    Computed once per (cost, start, goal) and cached on the cost (:attr:`EnergyCost.results`,
    least recently used dropped beyond :data:`~planner.cache.CACHE_SIZE` entries). The
    first call builds the 1-cell lattice graph of the cost (cached too).

    Raises
    ------
    InvalidParameterError, OutOfBoundsError, BlockedPositionError
        As :func:`plan_route` for bad start / goal points.
    """
    return _compare(PlanningProblem(cost, start_xy_m, goal_xy_m))


def _compare(problem: PlanningProblem) -> RouteComparison:
    """:func:`compare_route` of a checked problem."""
    def make() -> RouteComparison:
        optimum = _lattice_optimum(problem)
        return RouteComparison(shortest=shortest_of(problem),
                               lattice_optimum_j=optimum.objective if optimum.found else math.nan)

    return problem.cost.results.get_or_make(("comparison", *problem.key), make)


@dataclass(frozen=True)
class RouteSearch:
    """How a route is searched: the planner, its budget, its seed and its tuning — checked once.

    What :func:`plan_route` takes beside the map, the points and the cost, as one value: the
    batch (:func:`planner.plan_batch`) and the plan command (:func:`planner.plan_report.plan_and_compare`)
    take one instead of threading five options, and :meth:`plan` plans a pair with it.

    Parameters
    ----------
    planner : str
        One of :data:`PLANNERS` (as :func:`plan_route`).
    time_limit_s : float or None
        Wall-clock budget of an OMPL solve (s, > 0); ignored by the graph planners. ``None``
        requires ``max_cost_evaluations`` (but for those).
    max_cost_evaluations : int, optional
        Work bound of an OMPL solve (>= 1), as :func:`plan_route`.
    seed : int, optional
        Seeds OMPL and the refinement, as :func:`plan_route`.
    settings : PlannerSettings, optional
        Planner tuning (default ``PlannerSettings()``).

    Raises
    ------
    UnknownNameError
        An unknown planner.
    InvalidParameterError
        A bad budget (or none), seed or settings (the message names the parameter).

    Examples
    --------
    >>> RouteSearch("lattice").time_limit_s, RouteSearch("BITstar", None, 20_000, seed=1).max_cost_evaluations
    (1.0, 20000)
    """

    planner: str = "RRTstar"
    time_limit_s: float | None = 1.0
    max_cost_evaluations: int | None = None
    seed: int | None = 0
    settings: PlannerSettings | None = None

    def __post_init__(self) -> None:
        check_choice("planner", self.planner, PLANNERS)
        if not (self.planner in GRAPH_PLANNERS and self.time_limit_s is None and self.max_cost_evaluations is None):
            time_limit, max_evals = _check_budget(self.time_limit_s, self.max_cost_evaluations)
            object.__setattr__(self, "time_limit_s", time_limit)
            object.__setattr__(self, "max_cost_evaluations", max_evals)
        object.__setattr__(self, "seed", check_seed(self.seed))
        if self.settings is not None:
            check_instance("settings", self.settings, PlannerSettings)

    def plan(self, cost: EnergyCost, start_xy_m: tuple[float, float], goal_xy_m: tuple[float, float], *,
             compare: bool = False) -> Route:
        """:func:`plan_route` on ``cost``'s map with this search (``compare`` as there)."""
        return plan_route(cost.terrain, start_xy_m, goal_xy_m, cost=cost, planner=self.planner,
                          time_limit_s=self.time_limit_s, seed=self.seed,
                          max_cost_evaluations=self.max_cost_evaluations, compare=compare, settings=self.settings)


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
    compare: bool = False,
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
        Edge costs (see :meth:`planner.CostSpec.build`).
    planner : str
        One of :data:`PLANNERS`: ``"RRTstar"``, ``"InformedRRTstar"``, ``"SORRTstar"``,
        ``"BITstar"``, ``"FMT"`` (OMPL, minimising drive energy), ``"lattice"`` (the
        heading lattice's optimum, drive and turns), ``"anyangle"`` (Theta* around a coarse
        lattice route, :func:`planner.anyangle.anyangle_path`) or ``"coarse"``
        (coarse-to-fine for big maps, :func:`plan_coarse_to_fine`, tuned by
        ``settings.coarse_factor`` / ``coarse_corridor_m``); the last three deterministic.
    time_limit_s : float or None
        Wall-clock budget of the OMPL solve (s); ignored by the graph planners
        (:data:`GRAPH_PLANNERS`). ``None`` requires ``max_cost_evaluations`` (but for those).
    seed : int, optional
        Seeds OMPL's RNG for the OMPL planners and the refinement (``None`` or an integer
        in ``[0, 2**32)``). ``None`` leaves OMPL planners unseeded and seeds the refinement
        with :data:`REFINE_DEFAULT_SEED` (0), so a lattice plan is reproducible.
    max_cost_evaluations : int, optional
        Work bound of OMPL planners: stop after this many objective motion-cost calls.
        With ``seed`` and ``time_limit_s=None`` the result is reproducible; with both
        budgets the first one reached stops the solve.
    refine : bool
        Post-process an exact route with :func:`refine_route` (OMPL energy shortcuts, then
        :meth:`EnergyCost.relax_path`), each step kept only if the true energy (turns
        included) went down. The route's ``planner`` then reads e.g. ``"RRTstar+refine"``;
        the refinement time is part of ``planning_time_s``. An ``"anyangle"`` route is
        refined by :func:`planner.anyangle.polish_path` alone (kept only if it lowers the
        true energy too).
    compare : bool
        Also compute the query's :class:`RouteComparison` (:func:`compare_route`: the
        shortest-distance route and the lattice optimum), stored as ``Route.comparison``
        (``shortest_energy_j``, ``energy_saved_pct``, ``lattice_energy_j``,
        ``optimality_ratio``). Computed once per query and cached on ``cost``; its time (the
        first call builds the 1-cell lattice graph) is not part of ``planning_time_s``.
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
        NaN coordinates, start equals goal, bad budgets, seed or settings.
    OutOfBoundsError
        Start or goal outside the map.
    BlockedPositionError
        Start or goal on an obstacle or on ground steeper than ``cost.max_slope_rad``.
    GridMismatchError
        ``cost`` was built for another grid.

    Examples
    --------
    >>> from planner import CostSpec
    >>> from terrain import flat_map
    >>> tmap = flat_map((30, 40), 1.0)  # level asphalt, 1 m cells
    >>> cost = CostSpec(speed_mps=0.5).build(tmap)  # the Husky's physics on the asphalt preset
    >>> route = plan_route(tmap, (5.0, 5.0), (35.0, 25.0), cost=cost, planner="lattice")
    >>> route.status, round(route.length_m, 2)  # level ground: the straight line
    ('exact', 36.06)
    """
    search = RouteSearch(planner, time_limit_s, max_cost_evaluations, seed, settings)  # the search's options, checked
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    if not isinstance(terrain, TerrainMap):
        raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
    if terrain is not cost.terrain and not terrain.same_grid(cost.terrain):
        raise GridMismatchError(f"cost was built for the grid of {cost.terrain!r}, not of {terrain!r}")
    settings = PlannerSettings() if search.settings is None else search.settings
    refine = check_bool("refine", refine)
    compare = check_bool("compare", compare)
    problem = PlanningProblem(cost, start_xy_m, goal_xy_m)  # the points, checked once for the whole query

    if not problem.connected:
        route = empty_route("infeasible", planner, 0.0, cost.battery_voltage_v)
    else:
        route = _plan(problem, planner, search.time_limit_s, search.max_cost_evaluations, search.seed, refine,
                      settings)
    if compare:
        route = route.replace(comparison=_compare(problem))
    return route


def plan_coarse_to_fine(
    source: EnergyCost | str | os.PathLike[str],
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    options: CoarseOptions | None = None,
    *,
    cost_from: CostBuilder | None = None,
    compare: bool = False,
) -> CoarseToFine:
    """Coarse-to-fine planning for big maps, in memory or from a GeoTIFF read by windows: the one door.

    The lattice route on a cost ``options.factor`` times coarser, then the 1-cell lattice in a
    corridor around it (widened four times, then the whole map, when it holds no route):
    :mod:`planner.coarse` on a map in memory, :mod:`planner.coarse_geotiff` on a DEM never
    read whole. ``plan_route(planner="coarse")`` is the same search on a map in memory,
    returning its route only (and refined).

    Parameters
    ----------
    source : EnergyCost or path-like
        The full-resolution cost of a map in memory, or a GeoTIFF DEM (metres, no nodata) read
        by windows, each window priced by ``cost_from``.
    start_xy_m, goal_xy_m : (float, float)
        Points on the map (m).
    options : CoarseOptions, optional
        Factor, corridor, and for a GeoTIFF its tiles, fine-window budget and band; default
        ``CoarseOptions()`` (factor 4, a corridor of three coarse cells).
    cost_from : CostSpec or callable, optional
        A GeoTIFF only: how each window is priced, alike — a :class:`~planner.CostSpec` or a
        ``TerrainMap -> EnergyCost`` (default ``CostSpec()``, the Husky on the presets).
    compare : bool
        A map in memory only: also compute the full-resolution 1-cell lattice optimum (builds
        the whole lattice: the expensive step this function avoids) and the ratio.

    Returns
    -------
    CoarseToFine
        The route (status ``"exact"``, or ``"infeasible"`` when not even the whole map joins
        start and goal), the coarse route, corridor, fallback, times, the windows read.

    Raises
    ------
    InvalidParameterError
        ``source`` neither an EnergyCost nor a path; ``options`` not a CoarseOptions; ``compare``
        with a GeoTIFF; ``cost_from`` with a map in memory, or not pricing every window alike
        with an EnergyCost on it; a fine-window budget too small for a window of the corridor;
        bad points; start equal to goal; a factor leaving fewer than 2 x 2 coarse cells.
    OutOfBoundsError, BlockedPositionError
        A point outside the map, or on an obstacle or ground steeper than the slope limit.
    FileFormatError, UnitError, NodataError
        A GeoTIFF that cannot be read as a DEM in metres, or a window with nodata cells.
    PlanningError
        A GeoTIFF whose corridor holds no route while the whole map exceeds the fine-window budget.

    Examples
    --------
    >>> from planner import CostSpec
    >>> from terrain import procedural_map
    >>> cost = CostSpec(unknown_ground="gravel").build(procedural_map((96, 96), 1.0, seed=2))
    >>> plan = plan_coarse_to_fine(cost, (8.0, 8.0), (88.0, 80.0), CoarseOptions(factor=4), compare=True)
    >>> plan.route.status, bool(1.0 <= plan.ratio_to_optimum < 1.05)
    ('exact', True)
    """
    options = CoarseOptions() if options is None else check_instance("options", options, CoarseOptions)
    if isinstance(source, (str, os.PathLike)):
        if check_bool("compare", compare):
            raise InvalidParameterError("compare needs the whole 1-cell lattice: a GeoTIFF read by windows has no "
                                        "comparison; plan on a map in memory to compare", parameter="compare")
        return coarse_to_fine_windowed(source, start_xy_m, goal_xy_m, options, cost_from=cost_from)
    if not isinstance(source, EnergyCost):
        raise InvalidParameterError(f"source must be an EnergyCost (a map in memory) or the path of a GeoTIFF DEM, got "
                                    f"{type(source).__name__!r}", parameter="source")
    if cost_from is not None:
        raise InvalidParameterError("cost_from prices the windows of a GeoTIFF; a map in memory is priced already "
                                    "(give its EnergyCost)", parameter="cost_from")
    return coarse_to_fine_in_memory(source, start_xy_m, goal_xy_m, options, compare=compare)


# --------------------------------------------------------------------------- the planners, by name
#: A search: ``(problem, time_limit_s, max_cost_evaluations, seed, settings) -> (status, waypoints or None, seconds)``.
PlannerSearch = Callable[[PlanningProblem, "float | None", "int | None", "int | None", PlannerSettings],
                         "tuple[str, np.ndarray | None, float]"]


def _lattice_search(problem: PlanningProblem, time_limit: float | None, max_evals: int | None, seed: int | None,
                    settings: PlannerSettings) -> tuple[str, np.ndarray | None, float]:
    """The heading lattice's optimum, drive and turns (at the settings' stride; 1 cell where a passage is too
    narrow)."""
    cost, start, goal = problem.cost, problem.start, problem.goal
    stride = settings.lattice_stride_cells
    lattice = Lattice.for_cost(cost, stride)  # building the graph is map preparation
    t0 = time.perf_counter()
    path = heading_shortest_path(lattice, start, goal)
    if not path.found and stride > 1:  # a passage too narrow for the coarse lattice
        stride = 1
        path = heading_shortest_path(Lattice.for_cost(cost, 1), start, goal)
    elapsed = time.perf_counter() - t0
    if stride == 1:
        cost.results[("optimum", *problem.key)] = path
    return ("exact", path.waypoints_m, elapsed) if path.found else ("infeasible", None, elapsed)


def _anyangle_search(problem: PlanningProblem, time_limit: float | None, max_evals: int | None, seed: int | None,
                     settings: PlannerSettings) -> tuple[str, np.ndarray | None, float]:
    """Theta* on the drive energy in a corridor around a coarse lattice route."""
    path = anyangle_path(problem.cost, problem.start, problem.goal, guide_stride_cells=settings.anyangle_guide_stride_cells,
                         corridor_cells=settings.anyangle_corridor_cells)
    return ("exact", path.waypoints_m, path.solve_time_s) if path.found else ("infeasible", None, path.solve_time_s)


def _coarse_search(problem: PlanningProblem, time_limit: float | None, max_evals: int | None, seed: int | None,
                   settings: PlannerSettings) -> tuple[str, np.ndarray | None, float]:
    """Coarse-to-fine: the lattice on a cost ``settings.coarse_factor`` times coarser, then the 1-cell lattice in a
    corridor around that route (:func:`plan_coarse_to_fine`)."""
    options = CoarseOptions(factor=settings.coarse_factor, corridor_m=settings.coarse_corridor_m)
    found = coarse_to_fine_in_memory(problem.cost, problem.start, problem.goal, options)
    route = found.route
    if route.status != "exact":
        return route.status, None, route.planning_time_s
    return "exact", route.waypoints_m, route.planning_time_s


def _ompl_search(name: str) -> PlannerSearch:
    def search(problem: PlanningProblem, time_limit: float | None, max_evals: int | None, seed: int | None,
               settings: PlannerSettings) -> tuple[str, np.ndarray | None, float]:
        cost = problem.cost
        status, waypoints, elapsed, _ = solve_ompl(cost.arrays, cost.min_energy_per_metre_j, problem.start,
                                                   problem.goal, name, time_limit, max_evals, seed, settings)
        return status, waypoints, elapsed

    search.__doc__ = f"OMPL's {name} on the drive-energy objective."
    return search


#: Every planner :func:`plan_route` runs, by name: the one registry (:data:`PLANNERS` is its keys).
PLANNER_SEARCHES: dict[str, PlannerSearch] = {
    **{name: _ompl_search(name) for name in OMPL_PLANNERS},
    "anyangle": _anyangle_search,
    "coarse": _coarse_search,
    "lattice": _lattice_search,
}


def _plan(
    problem: PlanningProblem,
    planner: str,
    time_limit: float | None,
    max_evals: int | None,
    seed: int | None,
    refine: bool,
    settings: PlannerSettings,
) -> Route:
    """Search (the planner's entry of :data:`PLANNER_SEARCHES`), then refine an exact route and price it."""
    cost = problem.cost
    status, waypoints, elapsed = PLANNER_SEARCHES[planner](problem, time_limit, max_evals, seed, settings)
    name = planner
    if waypoints is not None and status == "exact" and refine:
        t0 = time.perf_counter()
        waypoints, name = refine_planned(problem, planner, waypoints, seed, settings)
        elapsed += time.perf_counter() - t0
    if waypoints is None:
        return empty_route(status, name, elapsed, cost.battery_voltage_v)
    return evaluate_route(cost, waypoints, status=status, planner=name, planning_time_s=elapsed)
