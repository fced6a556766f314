"""A route planned and reported: the printed table, route.json, GeoJSON and figure (PlanReport).

:func:`plan_and_compare` plans with a planner of :data:`planner.PLANNERS` and compares the route
with the shortest route and the lattice optimum; :func:`plan_coarse` plans coarse-to-fine
(:func:`planner.plan_coarse_to_fine`) on a map in memory or on a GeoTIFF read by windows, with
no comparison (it needs the whole 1-cell lattice). Both give a :class:`PlanReport`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from terrain import UNKNOWN_GROUND, InvalidParameterError, OptionalDependencyError, TerrainMap
from terrawatt_base.answer import write_answer
from terrawatt_base.atomic import json_finite
from terrawatt_base.checks import check_instance
from terrawatt_base.formats import format_name, result_document, write_result_json

from .coarse import CoarseOptions, CoarseToFine
from .cost_spec import CostSpec, PlanModel, PricedMap
from .edge_cost import EnergyCost
from .planning import GRAPH_PLANNERS, RouteSearch, plan_coarse_to_fine, plan_route, search_objective
from .plot import RouteLine, plot_routes
from .route import Route
from .route_geojson import write_geojson
from .route_price import INTERVAL_LEVEL, RouteEnergyInterval, price_route
from .warmup import warm_up_kernels

__all__ = [
    "ROUTE_JSON_FORMAT",
    "ROUTE_JSON_FORMAT_VERSION",
    "PlanModel",
    "PlanReport",
    "plan_and_compare",
    "plan_coarse",
    "COARSE_SEARCH_OBJECTIVE",
    "route_row",
    "route_table",
    "lonlat_fields",
    "map_line",
    "compile_line",
]

#: route.json's ``format`` and ``format_version`` (written by :meth:`PlanReport.write`).
ROUTE_JSON_FORMAT = format_name("route")
ROUTE_JSON_FORMAT_VERSION = 1
#: What coarse-to-fine minimises (route.json's ``search_objective``): its corridor search has no heading, so the
#: route it returns is the least drive energy in the corridor and its turns are priced but not searched over.
COARSE_SEARCH_OBJECTIVE = ("drive energy in the corridor (the coarse-to-fine search has no heading: the route's "
                           "turns are priced, not minimised)")

_TABLE_HEADER = (f"{'route':<26} {'status':<11} {'energy J':>10} {'Wh':>7} {'mAh':>8} {'length m':>9} {'time s':>8} "
                 f"{'/ optimum':>9} {'plan s':>7}")


def route_row(label: str, route: Route, optimum_j: float) -> dict[str, Any]:
    """One row of the comparison table (route.json's ``table``): energy, charge, length, time, ratio to ``optimum_j``.

    Energies are NaN for a route not found; the ratio is the energy (drive and turns) over
    ``optimum_j`` for an exact route (NaN otherwise, or when ``optimum_j`` is not > 0).
    """
    ratio = route.energy_j / optimum_j if route.status == "exact" and optimum_j > 0 else math.nan
    return {
        "route": label,
        "status": route.status,
        "energy_j": route.energy_j if route.found else math.nan,
        "energy_wh": route.energy_wh if route.found else math.nan,
        "charge_mah": route.charge_mah if route.found else math.nan,
        "length_m": route.length_m,
        "duration_s": route.duration_s,
        "ratio_to_lattice_optimum": ratio,
        "planning_time_s": route.planning_time_s,
    }


def route_table(rows: Sequence[Mapping[str, Any]]) -> str:
    """Rows of :func:`route_row` as a fixed-width text table (a header, a rule, a line per row).

    Examples
    --------
    >>> route_table([]).split()[:5]
    ['route', 'status', 'energy', 'J', 'Wh']
    """
    lines = [_TABLE_HEADER, "-" * len(_TABLE_HEADER)]
    for r in rows:
        lines.append(
            f"{r['route']:<26} {r['status']:<11} {r['energy_j']:>10.1f} {r['energy_wh']:>7.3f} "
            f"{r['charge_mah']:>8.1f} {r['length_m']:>9.1f} {r['duration_s']:>8.1f} "
            f"{r['ratio_to_lattice_optimum']:>9.3f} {r['planning_time_s']:>7.3f}"
        )
    return "\n".join(lines)


def lonlat_fields(terrain: TerrainMap | None, start: Sequence[float], goal: Sequence[float]) -> dict[str, Any]:
    """route.json's ``start_lonlat_deg`` / ``goal_lonlat_deg`` (WGS 84) when the map has a CRS, else nothing
    (also for a map with a CRS but no rasterio to transform it: its files stay in metres)."""
    if terrain is None or terrain.crs is None:
        return {}
    try:
        lon, lat = terrain.xy_to_lonlat([start[0], goal[0]], [start[1], goal[1]])
    except OptionalDependencyError:
        return {}
    return {"start_lonlat_deg": [lon[0], lat[0]], "goal_lonlat_deg": [lon[1], lat[1]]}


def map_line(label: str, terrain: TerrainMap) -> str:
    """``map: LABEL  R x C cells of S m; grounds {...}``: the first line of a plan's summary."""
    return (f"map: {label}  {terrain.shape[0]} x {terrain.shape[1]} cells of {terrain.cell_size_m:g} m; "
            f"grounds {terrain.ground_names}")


def compile_line(compile_s: float) -> list[str]:
    """The note on compiling the kernels when it took over a second (a first run in an environment), else nothing."""
    if compile_s <= 1.0:
        return []
    return [f"(compiled the edge-cost kernels in {compile_s:.1f} s: first run in this environment; "
            "not in the times below)"]


@dataclass(frozen=True)
class PlanReport:
    """A minimum-energy route, ready to print and write: compared, or planned coarse-to-fine.

    Made by :func:`plan_and_compare` (the route compared with the shortest route and the lattice
    optimum) or :func:`plan_coarse` (coarse-to-fine, ``coarse`` set: no comparison, on a map in
    memory or on a GeoTIFF read by windows). :meth:`summary` is the text ``terrawatt plan``
    prints, :meth:`to_dict` the content of route.json, :meth:`write` writes route.json,
    route.geojson and route.png.

    Attributes
    ----------
    route : Route
        The minimum-energy route of ``planner``, with its comparison (:class:`RouteComparison`)
        unless planned coarse-to-fine.
    lattice : Route or None
        The lattice planner's route with refinement (``route`` itself when the planner is the
        lattice); None when ``route`` was not found, or planned coarse-to-fine.
    interval : RouteEnergyInterval or None
        The route's energy distribution, when the cost has a predictive interval.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    search : RouteSearch
        How the route was searched (the planner, its budget and seed; ``"coarse"`` without a
        budget or seed for a coarse-to-fine plan).
    priced : PricedMap
        The map and how it was priced (robot, speed, slope limit, model, risk), with the times:
        the header of the summary and of route.json. A GeoTIFF read by windows has only the
        spec, the label and the compile time (each window is priced as it is read).
    coarse : CoarseToFine or None
        The coarse-to-fine plan (its coarse route, corridor, fallback, stages, windows read).
    """

    route: Route
    lattice: Route | None
    interval: RouteEnergyInterval | None
    start_xy_m: tuple[float, float]
    goal_xy_m: tuple[float, float]
    search: RouteSearch
    priced: PricedMap = field(repr=False, compare=False)
    coarse: CoarseToFine | None = None

    @property
    def terrain(self) -> TerrainMap | None:
        """The map (None for a GeoTIFF read by windows: no one map in memory)."""
        return self.priced.terrain

    @property
    def windowed(self) -> bool:
        """Whether the map was a GeoTIFF read by windows (coarse-to-fine)."""
        return self.coarse is not None and self.priced.terrain is None

    @property
    def fine_map(self) -> TerrainMap | None:
        """The full-resolution map the route lies on: the map, or the fine window read by a windowed coarse-to-fine
        plan (None for chained windows)."""
        return self.coarse.fine_map if self.windowed else self.terrain

    @property
    def cost(self) -> EnergyCost:
        """The cost the routes were planned on (the risk cost with a risk level)."""
        return self.priced.cost

    @property
    def model(self) -> PlanModel | None:
        """The saved model that priced the edges, or None for the physics presets."""
        return self.priced.model

    @property
    def shortest(self) -> Route | None:
        """The shortest-distance route of the comparison (None when the route has none)."""
        return None if self.route.comparison is None else self.route.comparison.shortest

    @property
    def risk_q(self) -> float | None:
        """The quantile of energy planned on, or None (the mean)."""
        return None if self.model is None else self.model.risk_q

    def rows(self) -> list[dict[str, Any]]:
        """The comparison table's rows (:func:`route_row`): min-energy, lattice + refinement, shortest; none
        when no route was found."""
        if not self.route.found:
            return []
        if self.coarse is not None:
            return [route_row(f"coarse-to-fine (x{self.coarse.factor})", self.route, math.nan)]
        optimum_j = self.route.lattice_energy_j
        return [route_row(f"min-energy ({self.planner})", self.route, optimum_j),
                route_row("lattice + refinement", self.lattice, optimum_j),
                route_row("shortest distance", self.shortest, optimum_j)]

    def table(self) -> str:
        """The comparison table as text (:func:`route_table`)."""
        return route_table(self.rows())

    @property
    def planner(self) -> str:
        """The planner's name (:attr:`search`)."""
        return self.search.planner

    def _budget(self) -> str:
        if self.planner in GRAPH_PLANNERS:  # searches run to their end: no budget applies
            return "no budget (a graph search)"
        if self.search.max_cost_evaluations is not None:
            return f"{self.search.max_cost_evaluations} edge-cost evaluations"
        return f"time limit {self.search.time_limit_s:g} s"

    def summary(self) -> str:
        """What ``terrawatt plan`` prints: the map, robot and planner, the table, the interval, the saving (a
        coarse-to-fine plan: the map, the robot, the stages and their times, the table)."""
        if self.coarse is not None:
            return self._coarse_summary()
        t, route, priced = self.terrain, self.route, self.priced
        lines = [map_line(priced.map_label, t),
                 f"{priced.robot_line()}; map preparation {priced.map_preparation_s:.2f} s"]
        if self.model is not None:
            lines.append(self.model.line())
        n_unknown = int(np.count_nonzero(np.asarray(t.ground) == UNKNOWN_GROUND))
        unknown_ground = priced.spec.preset_unknown_ground
        if n_unknown and unknown_ground:
            lines.append(f"ground class unknown in {n_unknown} of {t.ground.size} cells: priced as "
                         f"{unknown_ground!r} (unknown_ground NAME to choose, None / 'none' to refuse them)")
        lines.append(f"start {self.start_xy_m} -> goal {self.goal_xy_m}; planner {self.planner}, {self._budget()}, "
                     f"seed {self.search.seed}")
        lines += compile_line(priced.kernel_compile_s)
        lines.append("")
        if not route.found:
            lines.append(f"no route: status {route.status!r} after {route.planning_time_s:.3f} s")
            return "\n".join(lines)
        lines += [self.table(), ""]
        if self.interval is not None:
            iv = self.interval
            lo, hi = iv.interval_j(INTERVAL_LEVEL)
            lines.append(f"route energy (the model's interval): mean {iv.mean_j / 3600:.3f} Wh, P50 "
                         f"{iv.p50_j / 3600:.3f} Wh, P90 {iv.p90_j / 3600:.3f} Wh, sd {iv.sd_j / 3600:.3f} Wh; "
                         f"{100 * INTERVAL_LEVEL:.0f} % interval {lo / 3600:.3f}-{hi / 3600:.3f} Wh"
                         + ("" if math.isinf(iv.dof) else f", Student-t with {iv.dof:g} dof (a ground the model "
                                                          "never drove)")
                         + ("  (the table shows the planning objective)" if self.risk_q is not None else ""))
        if route.status == "exact":
            lines.append(f"energy saved vs shortest route: {route.energy_saved_pct:.1f} %  "
                         f"(min-energy {route.energy_j:.0f} J vs shortest {route.shortest_energy_j:.0f} J); "
                         f"energy / heading-lattice optimum (turns in both): {route.optimality_ratio:.3f}")
        else:
            short_m = math.dist(route.waypoints_m[-1], self.goal_xy_m)
            lines.append(f"the {self.planner} route is {route.status}: it ends {short_m:.1f} m short of the goal, so "
                         "it is not compared with the shortest route; give the planner more time")
        return "\n".join(lines)

    def _coarse_summary(self) -> str:
        plan, (rows, cols), priced = self.coarse, self.coarse.grid.shape, self.priced
        speed = priced.robot_line() + "; "
        if self.windowed:
            lines = [f"map: {priced.map_label}  {rows} x {cols} cells of {plan.grid.cell_size_m:g} m, read by windows; "
                     f"ground unknown, priced as {priced.spec.unknown_ground!r}",
                     speed + f"full-resolution cells read by the fine stage: {plan.fine_window_cells} of {rows * cols} "
                     f"({100 * plan.fine_window_cells / (rows * cols):.1f} %)"]
        else:
            lines = [map_line(priced.map_label, self.terrain),
                     speed + f"map preparation {priced.map_preparation_s:.2f} s"]
        lines += compile_line(priced.kernel_compile_s)
        lines += [f"start {self.start_xy_m} -> goal {self.goal_xy_m}; coarse-to-fine, factor {plan.factor}, corridor "
                  f"{plan.corridor_m:g} m ({plan.corridor_cells} free cells searched; fallback: {plan.fallback})",
                  f"coarse route {plan.coarse_time_s:.2f} s, corridor search {plan.fine_time_s:.2f} s", ""]
        lines.append(route_table(self.rows()) if self.route.found else f"no route: status {self.route.status!r}")
        return "\n".join(lines)

    def _routes(self) -> dict[str, Route]:
        if not self.route.found:
            return {}
        if self.coarse is not None:
            return {"min_energy": self.route}
        return {"min_energy": self.route, "lattice": self.lattice, "shortest": self.shortest}

    def to_dict(self) -> dict[str, Any]:
        """The content of route.json: the query, how it was planned, the table and every route with its waypoints.

        A result document (:func:`terrawatt_base.formats.result_document`); NaN is written as null
        (:func:`terrawatt_base.formats.write_result_json`). A coarse-to-fine plan writes its coarse route and
        stages instead of the comparison.
        """
        if self.coarse is not None:
            return self._coarse_dict()
        route = self.route
        routes = {name: {**r.summary(), "waypoints_m": r.waypoints_m.tolist()} for name, r in self._routes().items()}
        if self.interval is not None:
            routes["min_energy"]["energy_interval"] = self.interval.to_dict()
        result = result_document("route", ROUTE_JSON_FORMAT_VERSION, {
            "map": self.priced.map_label,
            "map_crs": self.terrain.crs,
            **self.priced.fields(),
            "start_xy_m": list(self.start_xy_m),
            "goal_xy_m": list(self.goal_xy_m),
            **lonlat_fields(self.terrain, self.start_xy_m, self.goal_xy_m),
            "planner": self.planner,
            "search_objective": search_objective(self.planner),
            "time_limit_s": self.search.time_limit_s if self.search.max_cost_evaluations is None else None,
            "max_evaluations": self.search.max_cost_evaluations,
            "seed": self.search.seed,
            "map_preparation_s": self.priced.map_preparation_s,
            "kernel_compile_s": self.priced.kernel_compile_s,
            "status": route.status,
            "energy_saved_pct": json_finite(route.energy_saved_pct) if route.found else None,
            "optimality_ratio": json_finite(route.optimality_ratio) if route.found else None,
            "table": self.rows(),
            "routes": routes,
        })
        if self.model is not None:  # files planned on the presets stay as they were
            result["model"] = self.model.to_dict()
        return result

    def _coarse_dict(self) -> dict[str, Any]:
        plan, route = self.coarse, self.route
        return result_document("route", ROUTE_JSON_FORMAT_VERSION, {
            "map": self.priced.map_label, "map_crs": plan.coarse_map.crs if plan.coarse_map is not None else None,
            **self.priced.fields(),
            "start_xy_m": list(self.start_xy_m), "goal_xy_m": list(self.goal_xy_m),
            **lonlat_fields(plan.coarse_map, self.start_xy_m, self.goal_xy_m),
            "planner": "coarse-to-fine",
            "search_objective": COARSE_SEARCH_OBJECTIVE,
            "map_preparation_s": self.priced.map_preparation_s, "kernel_compile_s": self.priced.kernel_compile_s,
            "status": route.status, "windowed": self.windowed,
            "coarse_to_fine": {k: v for k, v in plan.summary().items() if k not in route.summary()},
            "routes": ({"min_energy": {**route.summary(), "waypoints_m": route.waypoints_m.tolist()}}
                       if route.found else {}),
            "coarse_waypoints_m": plan.coarse_waypoints_m.tolist(),
        })

    def plot(self, path: str | os.PathLike[str] | None = None, *, whole_map: bool = False, ax: Any = None) -> Any:
        """The map with the minimum-energy and the shortest routes (:func:`planner.plot.plot_routes`), zoomed on
        the routes unless ``whole_map``; the route's energy interval shaded when there is one. A coarse-to-fine
        route is drawn over the fine map (zoomed on it), or over the coarse map (``whole_map`` of a windowed plan,
        or no fine map: the only whole view held)."""
        if self.coarse is not None:
            return self._coarse_plot(path, whole_map=whole_map, ax=ax)
        lines = []
        if self.route.found:
            risk = "" if self.risk_q is None else f", planned on the {self.risk_q:g} quantile"
            band = {} if self.interval is None else {"energy_band_j": self.interval.interval_j(INTERVAL_LEVEL),
                                                     "band_level": INTERVAL_LEVEL}
            lines = [RouteLine(f"min-energy ({self.planner}{risk})", self.route.waypoints_m, self.route.energy_j,
                               colour="#d32f2f", **band),
                     RouteLine("shortest distance", self.shortest.waypoints_m, self.shortest.energy_j,
                               colour="#1565c0", linestyle="--")]
        return plot_routes(self.terrain, lines, self.start_xy_m, self.goal_xy_m, path, ax=ax,
                           title=f"terrawatt: minimum-energy route on {self.priced.map_label}",
                           extent="map" if whole_map else "routes", max_slope_rad=self.priced.spec.max_slope_rad)

    def _coarse_plot(self, path: str | os.PathLike[str] | None, *, whole_map: bool, ax: Any) -> Any:
        fine, coarse = self.fine_map, self.coarse.coarse_map
        shown = coarse if fine is None or (self.windowed and whole_map) else fine
        lines = [RouteLine("coarse-to-fine", self.route.waypoints_m, self.route.energy_j, colour="#d32f2f")
                 ] if self.route.found else []
        title = f"terrawatt: coarse-to-fine route on {self.priced.map_label}" + (
            f" (the x{self.coarse.factor} coarse map)" if shown is coarse else "")
        return plot_routes(shown, lines, self.start_xy_m, self.goal_xy_m, path, ax=ax, title=title,
                           extent="map" if whole_map else "routes", max_slope_rad=self.priced.spec.max_slope_rad)

    def write(self, out_dir: str | os.PathLike[str], *, whole_map: bool = False,
              on_figure_error: str = "warn") -> list[Path]:
        """Write route.json, route.geojson (the routes found; WGS 84 when the map has a CRS) and route.png into
        ``out_dir`` (created), each atomically; return the files written.

        A figure that fails warns (:class:`~terrawatt_base.errors.FigureWarning`) and is left out,
        unless ``on_figure_error="raise"`` (:func:`terrawatt_base.answer.write_answer`). The GeoJSON of a
        coarse-to-fine route takes its elevations from the fine map, or the coarse map when the fine stage ran in
        chained windows (no one fine map holds the route).
        """
        found = {name: r for name, r in self._routes().items() if r.found}
        where = self.terrain if self.coarse is None else (
            self.fine_map if self.fine_map is not None else self.coarse.coarse_map)
        return write_answer(out_dir, {"route.json": lambda p: write_result_json(p, self.to_dict()),
                                      "route.geojson": lambda p: write_geojson(found, where, p) if found else None},
                            {"route.png": lambda p: self.plot(p, whole_map=whole_map)}, on_figure_error=on_figure_error)


def plan_and_compare(
    terrain: TerrainMap,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    *,
    search: RouteSearch | None = None,
    pricing: CostSpec | None = None,
    map_label: str = "map",
) -> PlanReport:
    """Plan a minimum-energy route and compare it with the shortest route and the lattice optimum.

    The kernels are compiled (or loaded) first (:func:`planner.warm_up_kernels`), the map is
    priced (:meth:`planner.cost_spec.CostSpec.build`: the physics presets, or a saved model), the
    route planned with ``compare=True`` (:func:`planner.plan_route`) and, for a planner other
    than the lattice, the lattice route with refinement planned too (the table's second row).

    Parameters
    ----------
    terrain : TerrainMap
        The map.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    search : RouteSearch, optional
        The planner, its budget, seed and tuning (:class:`planner.planning.RouteSearch`; default
        ``RouteSearch()``: RRT* for a second, seed 0).
    pricing : CostSpec, optional
        How the map is priced (:class:`planner.cost_spec.CostSpec`: the robot, speed, slope limit,
        the physics presets or a saved current model, a risk level); default ``CostSpec()``, the
        husky presets at 0.5 m/s. With a model that gives an interval, the route's energy
        distribution is reported (:func:`planner.route_price.price_route`); with its ``risk`` the
        route is planned on that quantile of energy (:meth:`planner.cost_spec.CostSpec.at_risk`).
    map_label : str
        How the map is named in the summary, the figure and route.json.

    Returns
    -------
    PlanReport

    Raises
    ------
    InvalidParameterError
        ``search`` not a :class:`~planner.planning.RouteSearch`; a ``risk`` with a model that gives
        no interval.
    TerrawattError
        As :func:`planner.plan_route` (points off the map or blocked, start equal to goal).

    Examples
    --------
    >>> from terrain import wall_map
    >>> report = plan_and_compare(wall_map((40, 40), 1.0, wall_col=20, gap_rows=(30, 34)), (5.0, 5.0),
    ...                           (35.0, 5.0), search=RouteSearch("lattice"), map_label="wall")
    >>> report.route.status, [row["route"] for row in report.rows()]
    ('exact', ['min-energy (lattice)', 'lattice + refinement', 'shortest distance'])
    """
    search = RouteSearch() if search is None else check_instance("search", search, RouteSearch)
    pricing = CostSpec.given(pricing)
    priced = pricing.price(terrain, map_label=map_label)
    mean_cost, cost = priced.mean_cost, priced.cost
    route = plan_route(terrain, start_xy_m, goal_xy_m, cost=cost, planner=search.planner, seed=search.seed,
                       compare=True, time_limit_s=search.time_limit_s, max_cost_evaluations=search.max_cost_evaluations,
                       settings=search.settings)
    lattice = interval = None
    if route.found:
        lattice = route if search.planner == "lattice" else plan_route(
            terrain, start_xy_m, goal_xy_m, cost=cost, planner="lattice", seed=search.seed, compare=False,
            settings=search.settings)
        interval = price_route(mean_cost, route) if mean_cost.has_interval else None
    return PlanReport(
        route=route, lattice=lattice, interval=interval,
        start_xy_m=(float(start_xy_m[0]), float(start_xy_m[1])), goal_xy_m=(float(goal_xy_m[0]), float(goal_xy_m[1])),
        search=search, priced=priced,
    )


def _presets_only(pricing: CostSpec | None) -> CostSpec:
    pricing = CostSpec.given(pricing)
    if pricing.model is not None or pricing.risk is not None:
        raise InvalidParameterError("coarse-to-fine prices the map with the physics presets: give pricing without a "
                                    "model and a risk level", parameter="pricing")
    return pricing


def plan_coarse(
    source: TerrainMap | str | os.PathLike[str],
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    *,
    options: CoarseOptions | None = None,
    pricing: CostSpec | None = None,
    map_label: str | None = None,
) -> PlanReport:
    """Price a map with the presets and plan coarse-to-fine on it (:func:`planner.plan_coarse_to_fine`): a map in
    memory, or a GeoTIFF DEM read by windows, never whole.

    Parameters
    ----------
    source : TerrainMap or path-like
        The map in memory (priced whole), or a GeoTIFF DEM (every window priced by
        ``pricing``: every cell of a DEM without classes is of its unknown ground, which must
        name a preset).
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    options : CoarseOptions, optional
        Factor, corridor and, for a GeoTIFF, its windows (default ``CoarseOptions()``).
    pricing : CostSpec, optional
        The physics presets (default ``CostSpec()``): coarse-to-fine takes no saved model and no
        risk level.
    map_label : str, optional
        How the map is named (default ``"map"``, or a GeoTIFF's file name).

    Returns
    -------
    PlanReport
        With ``coarse`` set and no comparison.

    Raises
    ------
    TerrawattError
        As :meth:`planner.cost_spec.CostSpec.build` and :func:`planner.plan_coarse_to_fine`;
        ``pricing`` with a model or a risk level.
    OptionalDependencyError
        A GeoTIFF without rasterio installed.

    Examples
    --------
    >>> from terrain import wall_map
    >>> report = plan_coarse(wall_map((40, 40), 1.0, wall_col=20, gap_rows=(30, 34)), (5.0, 5.0), (35.0, 5.0))
    >>> report.route.status, report.rows()[0]["route"]
    ('exact', 'coarse-to-fine (x4)')
    """
    pricing = _presets_only(pricing)
    options = CoarseOptions() if options is None else check_instance("options", options, CoarseOptions)
    if isinstance(source, TerrainMap):
        priced = pricing.price(source, map_label="map" if map_label is None else map_label)
        plan = plan_coarse_to_fine(priced.cost, start_xy_m, goal_xy_m, options)
    else:
        compile_s = warm_up_kernels()
        plan = plan_coarse_to_fine(source, start_xy_m, goal_xy_m, options, cost_from=pricing)
        priced = PricedMap(pricing, Path(source).name if map_label is None else map_label, kernel_compile_s=compile_s)
    return PlanReport(
        route=plan.route, lattice=None, interval=None, start_xy_m=(float(start_xy_m[0]), float(start_xy_m[1])),
        goal_xy_m=(float(goal_xy_m[0]), float(goal_xy_m[1])), search=RouteSearch("coarse", None, seed=None),
        priced=priced, coarse=plan,
    )
