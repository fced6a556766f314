"""A coarse-to-fine plan reported: on a map in memory or on a GeoTIFF read by windows (CoarsePlanReport)."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from terrain import DemWindows, Grid, InvalidParameterError, TerrainMap
from terrawatt_base.checks import check_bool, check_instance
from terrawatt_base.figure_file import draw_figure
from terrawatt_base.formats import result_document, write_result_json

from .coarse import CoarseToFine, plan_coarse_to_fine
from .coarse_geotiff import plan_coarse_to_fine_geotiff
from .cost_spec import CostSpec, PricedMap
from .plan_report import (
    ROUTE_JSON_FORMAT_VERSION,
    compile_line,
    lonlat_fields,
    map_line,
    route_row,
    route_table,
)
from .plot import RouteLine, plot_routes
from .route_geojson import write_geojson
from .warmup import warm_up_kernels

__all__ = ["CoarsePlanReport", "plan_coarse", "plan_coarse_windowed", "check_coarse_options", "COARSE_OPTIONS",
           "COARSE_SEARCH_OBJECTIVE"]

#: What coarse-to-fine minimises (route.json's ``search_objective``): its corridor search has no heading, so the
#: route it returns is the least drive energy in the corridor and its turns are priced but not searched over.
COARSE_SEARCH_OBJECTIVE = ("drive energy in the corridor (the coarse-to-fine search has no heading: the route's "
                           "turns are priced, not minimised)")


@dataclass(frozen=True)
class CoarsePlanReport:
    """A coarse-to-fine plan (:class:`planner.CoarseToFine`) ready to print and write, like :class:`PlanReport`.

    Made by :func:`plan_coarse` (a map in memory) or :func:`plan_coarse_windowed` (a GeoTIFF
    DEM read by windows). There is no comparison: it needs the whole 1-cell lattice.

    Attributes
    ----------
    plan : CoarseToFine
        The plan: its route, coarse route, corridor, fallback and times.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    priced : PricedMap
        The map and how it was priced (the physics presets), with the times: the whole map priced
        in memory, or, read by windows, only the spec, the label and the compile time (the map
        preparation is 0: each window is priced as it is read).
    windowed : bool
        Whether the DEM was read by windows.
    grid : Grid
        The whole map's grid.
    """

    plan: CoarseToFine
    start_xy_m: tuple[float, float]
    goal_xy_m: tuple[float, float]
    priced: PricedMap = field(repr=False, compare=False)
    windowed: bool
    grid: Grid

    @property
    def terrain(self) -> TerrainMap | None:
        """The whole map, when it was given in memory."""
        return self.priced.terrain

    @property
    def route(self) -> Any:
        """The full-resolution route."""
        return self.plan.route

    @property
    def fine_map(self) -> TerrainMap | None:
        """The full-resolution map the route lies on: the whole map, or the fine window read (None for chained
        windows)."""
        return self.plan.fine_map if self.windowed else self.terrain

    def rows(self) -> list[dict[str, Any]]:
        """The table's one row (:func:`planner.plan_report.route_row`), or none when no route was found."""
        if not self.route.found:
            return []
        return [route_row(f"coarse-to-fine (x{self.plan.factor})", self.route, math.nan)]

    def summary(self) -> str:
        """What ``terrawatt plan --coarse-factor`` prints: the map, the robot, the stages and their times, the table."""
        plan, (rows, cols), priced = self.plan, self.grid.shape, self.priced
        speed = priced.robot_line() + "; "
        if self.windowed:
            lines = [f"map: {priced.map_label}  {rows} x {cols} cells of {self.grid.cell_size_m:g} m, read by windows; "
                     f"ground unknown, priced as {priced.spec.unknown_ground!r}",
                     speed + f"full-resolution cells read by the fine stage: {plan.fine_window_cells} of {rows * cols} "
                     f"({100 * plan.fine_window_cells / (rows * cols):.1f} %)"]
        else:
            lines = [map_line(priced.map_label, self.terrain), speed + f"map preparation {priced.map_preparation_s:.2f} s"]
        lines += compile_line(priced.kernel_compile_s)
        lines += [f"start {self.start_xy_m} -> goal {self.goal_xy_m}; coarse-to-fine, factor {plan.factor}, corridor "
                  f"{plan.corridor_m:g} m ({plan.corridor_cells} free cells searched; fallback: {plan.fallback})",
                  f"coarse route {plan.coarse_time_s:.2f} s, corridor search {plan.fine_time_s:.2f} s", ""]
        lines.append(route_table(self.rows()) if self.route.found else f"no route: status {self.route.status!r}")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """The content of route.json (as :meth:`PlanReport.to_dict`, with the coarse route and the stages)."""
        plan, route = self.plan, self.route
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
        """The route over the fine map (zoomed on it), or over the coarse map (``whole_map`` of a windowed plan,
        or no fine map: the only whole view held)."""
        fine, coarse = self.fine_map, self.plan.coarse_map
        shown = coarse if fine is None or (self.windowed and whole_map) else fine
        lines = [RouteLine("coarse-to-fine", self.route.waypoints_m, self.route.energy_j, colour="#d32f2f")
                 ] if self.route.found else []
        title = f"terrawatt: coarse-to-fine route on {self.priced.map_label}" + (
            f" (the x{self.plan.factor} coarse map)" if shown is coarse else "")
        return plot_routes(shown, lines, self.start_xy_m, self.goal_xy_m, path, ax=ax, title=title,
                           extent="map" if whole_map else "routes", max_slope_rad=self.priced.spec.max_slope_rad)

    def write(self, out_dir: str | os.PathLike[str], *, whole_map: bool = False,
              on_figure_error: str = "warn") -> list[Path]:
        """Write route.json, route.geojson (when found) and route.png into ``out_dir``; return the files written.

        The GeoJSON's elevations come from the fine map, or the coarse map when the fine stage
        ran in chained windows (no one fine map holds the route). A figure that fails warns,
        as :meth:`PlanReport.write`.
        """
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        written = [write_result_json(out / "route.json", self.to_dict())]
        if self.route.found:
            where = self.fine_map if self.fine_map is not None else self.plan.coarse_map
            written.append(write_geojson({"min_energy": self.route}, where, out / "route.geojson"))
        png = draw_figure(out / "route.png", lambda: self.plot(out / "route.png", whole_map=whole_map),
                          on_error=on_figure_error)
        return written + ([png] if png is not None else [])

#: The options :func:`check_coarse_options` names in its messages (``names`` keys).
COARSE_OPTIONS = ("factor", "corridor_m", "windowed", "path", "model", "planner", "fill_nodata", "reproject_to",
                  "cell_size_m", "landcover")


def _presets_only(pricing: CostSpec | None) -> CostSpec:
    pricing = CostSpec() if pricing is None else check_instance("pricing", pricing, CostSpec)
    if pricing.model is not None or pricing.risk is not None:
        raise InvalidParameterError("coarse-to-fine prices the map with the physics presets: give pricing without a "
                                    "model and a risk level", parameter="pricing")
    return pricing


def plan_coarse(
    terrain: TerrainMap,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    *,
    factor: int = 4,
    corridor_m: float | None = None,
    pricing: CostSpec | None = None,
    map_label: str = "map",
) -> CoarsePlanReport:
    """Price a map in memory with the presets and plan coarse-to-fine on it (:func:`planner.plan_coarse_to_fine`).

    ``pricing`` (:class:`planner.cost_spec.CostSpec`, default ``CostSpec()``) prices the map with the
    physics presets: coarse-to-fine takes no saved model and no risk level.

    Raises
    ------
    TerrawattError
        As :meth:`planner.cost_spec.CostSpec.build` and :func:`planner.plan_coarse_to_fine`;
        ``pricing`` with a model or a risk level.

    Examples
    --------
    >>> from terrain import wall_map
    >>> report = plan_coarse(wall_map((40, 40), 1.0, wall_col=20, gap_rows=(30, 34)), (5.0, 5.0), (35.0, 5.0))
    >>> report.route.status, report.rows()[0]["route"]
    ('exact', 'coarse-to-fine (x4)')
    """
    priced = _presets_only(pricing).price(terrain, map_label=map_label)
    plan = plan_coarse_to_fine(priced.cost, start_xy_m, goal_xy_m, factor=factor, corridor_m=corridor_m)
    return CoarsePlanReport(
        plan=plan, start_xy_m=(float(start_xy_m[0]), float(start_xy_m[1])),
        goal_xy_m=(float(goal_xy_m[0]), float(goal_xy_m[1])), priced=priced, windowed=False, grid=terrain.grid,
    )


def plan_coarse_windowed(
    path: str | os.PathLike[str],
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    *,
    factor: int = 4,
    corridor_m: float | None = None,
    pricing: CostSpec | None = None,
    fine_window_cells: int | None = None,
    map_label: str | None = None,
) -> CoarsePlanReport:
    """Plan coarse-to-fine on a GeoTIFF DEM read by windows, never whole (:func:`planner.plan_coarse_to_fine_geotiff`),
    every window priced by ``pricing`` (:meth:`planner.cost_spec.CostSpec.build`: the presets; every cell of a DEM
    without classes is of its unknown ground, which must name a preset); ``fine_window_cells`` is its
    ``fine_window_budget_cells`` and ``map_label`` defaults to the file's name.

    Raises
    ------
    TerrawattError
        As :func:`planner.plan_coarse_to_fine_geotiff`.
    OptionalDependencyError
        rasterio is not installed.
    """
    pricing = _presets_only(pricing)
    compile_s = warm_up_kernels()
    with DemWindows(path) as dem:
        grid = dem.grid
    plan = plan_coarse_to_fine_geotiff(path, start_xy_m, goal_xy_m, factor=factor, corridor_m=corridor_m,
                                       cost_from=pricing.build, fine_window_budget_cells=fine_window_cells)
    return CoarsePlanReport(
        plan=plan, start_xy_m=(float(start_xy_m[0]), float(start_xy_m[1])),
        goal_xy_m=(float(goal_xy_m[0]), float(goal_xy_m[1])),
        priced=PricedMap(pricing, Path(path).name if map_label is None else map_label, kernel_compile_s=compile_s),
        windowed=True, grid=grid,
    )


def check_coarse_options(
    *,
    factor: int | None = None,
    corridor_m: float | None = None,
    windowed: bool = False,
    path: str | os.PathLike[str] | None = None,
    model: Any = None,
    fill_nodata: str | None = None,
    reproject_to: str | None = None,
    cell_size_m: float | None = None,
    landcover: Any = None,
) -> None:
    """Refuse, before any work, what coarse-to-fine planning cannot do with the options of a plan.

    A corridor or a windowed read needs a coarse ``factor``; a saved ``model`` prices the whole
    map only (not :func:`plan_coarse`, nor :func:`plan_coarse_windowed`); a windowed read takes a
    GeoTIFF ``path`` as it is, so none of the options of :func:`terrain.io.read_map_with_options`
    that need the whole map (``fill_nodata``, ``reproject_to``, ``cell_size_m``, ``landcover``).
    Messages name the parameters (and ``planner``) as :data:`COARSE_OPTIONS`, and the error
    carries them (:attr:`terrain.TerrawattError.parameter`) for a front end to say them its way.

    Parameters
    ----------
    factor : int, optional
        The coarse factor (None: the plan is not coarse-to-fine).
    corridor_m : float, optional
        The corridor half-width asked for.
    windowed : bool
        Whether the DEM at ``path`` is to be read by windows.
    path : path-like, optional
        The map file (checked with ``windowed``).
    model : object, optional
        A saved current model pricing the edges (only whether it is given counts).
    fill_nodata, reproject_to, cell_size_m, landcover
        Options of :func:`terrain.io.read_map_with_options` asked for (only whether each is given counts).

    Raises
    ------
    InvalidParameterError
        An option that coarse-to-fine planning, or a windowed read, cannot take.

    Examples
    --------
    >>> check_coarse_options(factor=4, corridor_m=30.0)
    >>> check_coarse_options(corridor_m=30.0)
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: corridor_m applies to coarse-to-fine planning; give factor F too
    """
    windowed = check_bool("windowed", windowed)
    if corridor_m is not None and factor is None:
        raise InvalidParameterError("corridor_m applies to coarse-to-fine planning; give factor F too",
                                    parameter=("corridor_m", "factor"))
    if model is not None and (factor is not None or windowed):
        raise InvalidParameterError("model plans on the whole map with planner; it does not apply to factor / windowed "
                                    "yet", parameter=("model", "planner", "factor", "windowed"))
    if not windowed:
        return
    if factor is None:
        raise InvalidParameterError("windowed plans coarse-to-fine; give factor F too",
                                    parameter=("windowed", "factor"))
    if path is None or Path(path).suffix.lower() not in (".tif", ".tiff"):
        raise InvalidParameterError(f"windowed reads GeoTIFF DEMs (.tif, .tiff), got path "
                                    f"{None if path is None else Path(path).name}", parameter=("windowed", "path"))
    for key, value in (("fill_nodata", fill_nodata), ("reproject_to", reproject_to), ("cell_size_m", cell_size_m),
                       ("landcover", landcover)):
        if value is not None:
            raise InvalidParameterError(
                f"windowed reads the DEM as it is and cannot apply {key} (it needs the whole map): fill or "
                f"reproject the DEM first (gdal_fillnodata, gdalwarp), or plan without windowed",
                parameter=("windowed", key))
