"""``terrawatt demo`` and ``terrawatt plan``: a minimum-energy route compared with the shortest one."""

from __future__ import annotations

import argparse
import dataclasses
import functools
import math
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from energy import GROUND_PRESETS
from terrain import (
    UNKNOWN_GROUND,
    DemWindows,
    InvalidParameterError,
    OptionalDependencyError,
    TerrainMap,
    UnknownNameError,
)
from terrawatt_base.atomic import write_json_atomic
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M, example_map

from planner import (
    PLANNERS,
    CoarseToFine,
    EnergyCost,
    Route,
    plan_coarse_to_fine,
    plan_coarse_to_fine_geotiff,
    plan_route,
    warm_up_kernels,
)
from planner.planning import GRAPH_PLANNERS
from planner.plot import RouteLine, plot_routes
from planner.risk import INTERVAL_LEVEL, RouteEnergyInterval, risk_cost, route_energy_interval
from planner.route_geojson import write_geojson
from .common import (
    add_map_options,
    add_model_options,
    add_point_options,
    check_model_flags,
    check_outputs,
    check_positive,
    draw_figure,
    edge_cost_for,
    input_paths,
    load_model_arg,
    max_slope_rad,
    point_arg,
    read_map_args,
    unknown_ground,
)
from .ros2 import add_ros2_arguments, check_ros2_outputs, write_ros2_outputs

__all__ = ["add_parsers", "run_demo", "run_plan_command", "run_plan", "run_coarse_plan", "run_windowed_plan"]

_OUTPUTS = ("route.json", "route.geojson", "route.png")


def add_parsers(sub: Any) -> None:
    """The ``demo`` and ``plan`` subcommands."""
    demo = sub.add_parser("demo", help="plan a minimum-energy route on the bundled example map")
    _add_plan_options(demo, default_time=1.0)
    add_model_options(demo, risk=True)
    add_ros2_arguments(demo)
    demo.set_defaults(run=run_demo)
    plan = sub.add_parser("plan", help="plan a minimum-energy route on a map file (.npz or GeoTIFF)")
    plan.add_argument("--map", type=Path, required=True, metavar="FILE", help=".npz map or .tif DEM")
    add_map_options(plan)
    add_point_options(plan, "start", "start", required=True)
    add_point_options(plan, "goal", "goal", required=True)
    _add_plan_options(plan, default_time=2.0)
    plan.add_argument(
        "--coarse-factor", type=int, default=None, metavar="F",
        help="big maps: plan coarse-to-fine (the lattice on a map F times coarser, then the 1-cell lattice in a "
             "corridor around that route) instead of --planner, without the comparison (which needs the whole "
             "1-cell lattice: about 10 GB at 4096 x 4096 cells)",
    )
    plan.add_argument("--corridor", type=float, default=None, metavar="M",
                      help="with --coarse-factor: corridor half-width (m; default three coarse cells)")
    plan.add_argument(
        "--windowed", action="store_true",
        help="with --coarse-factor on a GeoTIFF DEM: read the DEM by windows, never whole (the coarse map tile by "
             "tile, the full resolution only in the corridor's window), for DEMs larger than memory",
    )
    plan.add_argument(
        "--fine-window-cells", type=int, default=None, metavar="N",
        help="with --windowed: the most full-resolution cells the fine stage reads at once (default 8192^2, about "
             "7 GiB once priced); a corridor whose bounding window is larger is followed in chained windows",
    )
    add_model_options(plan, risk=True)
    add_ros2_arguments(plan)
    plan.set_defaults(run=run_plan_command)


def _add_plan_options(p: argparse.ArgumentParser, *, default_time: float) -> None:
    p.add_argument("--planner", default="RRTstar", choices=PLANNERS, help="planner name (default RRTstar)")
    p.add_argument("--time-limit", type=float, default=default_time, metavar="S", help="planning time budget (s)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument(
        "--max-evaluations", type=int, default=None, metavar="N",
        help="work bound of OMPL planners: stop after N edge-cost evaluations instead of after --time-limit; "
             "with --seed the route is then the same on every run and machine",
    )
    p.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    p.add_argument("--whole-map", action="store_true",
                   help="draw the whole map in route.png (default: zoom on the routes with a margin)")
    p.add_argument("--robot", default="husky", help="robot preset: paper_seed, jackal or husky (default husky)")
    p.add_argument("--speed", type=float, default=0.5, metavar="M/S", help="planning speed (default 0.5 m/s)")
    p.add_argument("--max-slope-deg", type=float, default=20.0, help="steepest drivable slope (default 20 deg)")
    p.add_argument(
        "--unknown-ground",
        default="gravel",
        help="ground preset assumed where the map's ground class is unknown (-1); 'none' to refuse such cells",
    )


def run_demo(args: argparse.Namespace) -> int:
    """``terrawatt demo``: plan on the bundled example map."""
    check_outputs(args.out, _OUTPUTS, input_paths(args))
    check_ros2_outputs(args, input_paths(args), [args.out / n for n in _OUTPUTS])
    check_model_flags(args)
    return _run(args, example_map(), EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M, "bundled example map")


def run_plan_command(args: argparse.Namespace) -> int:
    """``terrawatt plan``: plan on a map file."""
    check_outputs(args.out, _OUTPUTS, input_paths(args))
    check_ros2_outputs(args, input_paths(args), [args.out / n for n in _OUTPUTS])
    check_model_flags(args)
    if args.model is not None and (args.windowed or args.coarse_factor is not None):
        raise InvalidParameterError("--model plans on the whole map with --planner; it does not apply to "
                                    "--coarse-factor / --windowed yet")
    if args.windowed:
        return _run_windowed(args)
    tmap = read_map_args(args)
    return _run(args, tmap, point_arg(args, "start", tmap), point_arg(args, "goal", tmap), args.map.name)


def _run(args: argparse.Namespace, tmap: TerrainMap, start: tuple[float, float], goal: tuple[float, float],
         label: str) -> int:
    check_positive("--speed", args.speed)
    check_positive("--time-limit", args.time_limit)
    if args.max_evaluations is not None:
        check_positive("--max-evaluations", args.max_evaluations)
    factor = getattr(args, "coarse_factor", None)
    corridor = getattr(args, "corridor", None)
    if corridor is not None and factor is None:
        raise InvalidParameterError("--corridor applies to coarse-to-fine planning; give --coarse-factor F too")
    if factor is not None:
        if factor < 2:
            raise InvalidParameterError(f"--coarse-factor must be an integer >= 2, got {factor}")
        if corridor is not None:
            check_positive("--corridor", corridor)
        result = run_coarse_plan(
            tmap, start, goal, factor=factor, corridor_m=corridor, out_dir=args.out, robot=args.robot,
            speed_mps=args.speed, max_slope_deg=args.max_slope_deg,
            unknown_ground=unknown_ground(args.unknown_ground, tmap), map_label=label, whole_map=args.whole_map,
        )
        return 0 if result["status"] == "exact" else 1
    model = load_model_arg(args)
    result = run_plan(
        tmap, start, goal, planner=args.planner, time_limit_s=args.time_limit, max_evaluations=args.max_evaluations,
        seed=args.seed, out_dir=args.out, robot=args.robot, speed_mps=args.speed, max_slope_deg=args.max_slope_deg,
        unknown_ground=None if model is not None else unknown_ground(args.unknown_ground, tmap), map_label=label,
        whole_map=args.whole_map, model=model, model_label=None if model is None else args.model.name,
        model_ground=getattr(args, "model_ground", None), risk=getattr(args, "risk", None), ros2=args,
    )
    return 0 if result["status"] == "exact" else 1


def _run_windowed(args: argparse.Namespace) -> int:
    """``terrawatt plan --windowed``: its flags checked before any work, then :func:`run_windowed_plan`."""
    if args.coarse_factor is None:
        raise InvalidParameterError("--windowed plans coarse-to-fine; give --coarse-factor F too")
    if args.map.suffix.lower() not in (".tif", ".tiff"):
        raise InvalidParameterError(f"--windowed reads GeoTIFF DEMs (.tif, .tiff), got --map {args.map.name}")
    for flag, value in (("--fill-nodata", args.fill_nodata), ("--reproject", args.reproject),
                        ("--cell-size", args.cell_size), ("--landcover", args.landcover)):
        if value is not None:
            raise InvalidParameterError(
                f"--windowed reads the DEM as it is and cannot apply {flag} (it needs the whole map): fill or "
                "reproject the DEM first (gdal_fillnodata, gdalwarp), or plan without --windowed")
    if args.coarse_factor < 2:
        raise InvalidParameterError(f"--coarse-factor must be an integer >= 2, got {args.coarse_factor}")
    check_positive("--speed", args.speed)
    if args.corridor is not None:
        check_positive("--corridor", args.corridor)
    if args.fine_window_cells is not None:
        check_positive("--fine-window-cells", args.fine_window_cells)
    if args.unknown_ground.lower() == "none":
        raise InvalidParameterError(
            "a GeoTIFF DEM has no ground classes, so --unknown-ground none refuses every cell; give "
            f"--unknown-ground NAME, one of {sorted(GROUND_PRESETS)!r}")
    if args.unknown_ground not in GROUND_PRESETS:
        raise UnknownNameError(f"--unknown-ground must be a ground preset, one of {sorted(GROUND_PRESETS)!r}, "
                               f"or 'none'; got {args.unknown_ground!r}")
    with DemWindows(args.map) as dem:
        start, goal = point_arg(args, "start", dem), point_arg(args, "goal", dem)
    result = run_windowed_plan(
        args.map, start, goal, factor=args.coarse_factor, corridor_m=args.corridor,
        out_dir=args.out, robot=args.robot, speed_mps=args.speed, max_slope_deg=args.max_slope_deg,
        unknown_ground=args.unknown_ground, whole_map=args.whole_map, fine_window_cells=args.fine_window_cells,
    )
    return 0 if result["status"] == "exact" else 1


def _route_row(label: str, route: Route, optimum_j: float) -> dict[str, Any]:
    ratio = route.drive_energy_j / optimum_j if route.status == "exact" and optimum_j > 0 else math.nan
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


def _print_table(rows: Sequence[dict[str, Any]]) -> None:
    header = (f"{'route':<26} {'status':<11} {'energy J':>10} {'Wh':>7} {'mAh':>8} {'length m':>9} {'time s':>8} "
              f"{'/ optimum':>9} {'plan s':>7}")
    print(header)
    print("-" * len(header))
    for r in rows:
        print(
            f"{r['route']:<26} {r['status']:<11} {r['energy_j']:>10.1f} {r['energy_wh']:>7.3f} "
            f"{r['charge_mah']:>8.1f} {r['length_m']:>9.1f} {r['duration_s']:>8.1f} "
            f"{r['ratio_to_lattice_optimum']:>9.3f} {r['planning_time_s']:>7.3f}"
        )


def _lonlat_fields(tmap: TerrainMap | None, start: tuple[float, float], goal: tuple[float, float]) -> dict[str, Any]:
    """route.json's ``start_lonlat_deg`` / ``goal_lonlat_deg`` (WGS 84) when the map has a CRS, else nothing."""
    if tmap is None or tmap.crs is None:
        return {}
    try:
        lon, lat = tmap.xy_to_lonlat([start[0], goal[0]], [start[1], goal[1]])
    except OptionalDependencyError:  # a .npz map with a CRS and no rasterio: its files stay in metres
        return {}
    return {"start_lonlat_deg": [lon[0], lat[0]], "goal_lonlat_deg": [lon[1], lat[1]]}


def _finite_or_none(x: float) -> float | None:
    return x if math.isfinite(x) else None


def run_plan(
    tmap: TerrainMap,
    start: tuple[float, float],
    goal: tuple[float, float],
    *,
    planner: str,
    time_limit_s: float,
    seed: int,
    out_dir: Path,
    max_evaluations: int | None = None,
    robot: str,
    speed_mps: float,
    max_slope_deg: float,
    unknown_ground: str | None,
    map_label: str,
    whole_map: bool = False,
    model: Any = None,
    model_label: str | None = None,
    model_ground: str | Mapping[str, str] | None = None,
    risk: float | None = None,
    ros2: argparse.Namespace | None = None,
) -> dict[str, Any]:
    """Plan once with its comparison (shortest route, lattice optimum), print, write files.

    Writes ``route.json``, ``route.geojson`` (the found routes as LineStrings: WGS 84 when the
    map has a CRS, else local metres) and ``route.png`` (zoomed on the routes unless
    ``whole_map``).

    With ``model`` (a saved current model, :func:`planner.model_energy_cost`) the edges are
    priced by it; when it gives an interval, the route's energy distribution
    (:func:`planner.route_energy_interval`: mean, P50, P90, central 80 %) is printed, written
    to route.json (``routes.min_energy.energy_interval``) and shaded in route.png. With
    ``risk`` Q the routes are planned on :func:`planner.risk_cost` (each edge at mean + z_Q sd):
    the table then shows that objective, the interval line the route's true distribution.
    Without ``model`` the output is that of the physics presets, unchanged."""
    slope_rad = max_slope_rad(max_slope_deg)
    compile_s = warm_up_kernels()  # compiled once per environment, then loaded from numba's cache
    t0 = time.perf_counter()
    mean_cost = edge_cost_for(tmap, robot=robot, speed_mps=speed_mps, max_slope_rad=slope_rad,
                              unknown_ground=unknown_ground, model=model, model_ground=model_ground)
    if risk is not None and not mean_cost.has_interval:
        raise InvalidParameterError(
            f"--risk {risk:g} needs a model with a predictive interval; the model {model_label or ''} gives none "
            "(its spreads are all 0): plan without --risk, or with a model that has one")
    cost = mean_cost if risk is None else risk_cost(mean_cost, risk)
    prep_s = time.perf_counter() - t0
    route = plan_route(
        tmap, start, goal, cost=cost, planner=planner, seed=seed, compare=True,
        time_limit_s=None if max_evaluations is not None else time_limit_s, max_cost_evaluations=max_evaluations,
    )
    rows: list[dict[str, Any]] = []
    routes_json: dict[str, Any] = {}
    lines = []
    interval: RouteEnergyInterval | None = None
    if route.found:
        shortest = route.comparison.shortest
        # the table's second row: the lattice planner with refinement (the route itself when it is one)
        optimum = route if planner == "lattice" else plan_route(tmap, start, goal, cost=cost, planner="lattice",
                                                                 seed=seed, compare=False)
        rows = [_route_row(f"min-energy ({planner})", route, route.lattice_energy_j),
                _route_row("lattice + refinement", optimum, route.lattice_energy_j),
                _route_row("shortest distance", shortest, route.lattice_energy_j)]
        lines = [
            RouteLine(f"min-energy ({planner}{'' if risk is None else f', planned on the {risk:g} quantile'})",
                      route.waypoints_m, route.energy_j, colour="#d32f2f"),
            RouteLine("shortest distance", shortest.waypoints_m, shortest.energy_j, colour="#1565c0", linestyle="--"),
        ]
        interval = route_energy_interval(mean_cost, route.waypoints_m) if mean_cost.has_interval else None
        if interval is not None:
            lines[0] = dataclasses.replace(lines[0], energy_band_j=interval.interval_j(INTERVAL_LEVEL),
                                           band_level=INTERVAL_LEVEL)
        routes_json = {
            "min_energy": {**route.summary(), "waypoints_m": route.waypoints_m.tolist(),
                           **({"energy_interval": interval.to_dict()} if interval is not None else {})},
            "lattice": {**optimum.summary(), "waypoints_m": optimum.waypoints_m.tolist()},
            "shortest": {**shortest.summary(), "waypoints_m": shortest.waypoints_m.tolist()},
        }
    print(f"map: {map_label}  {tmap.shape[0]} x {tmap.shape[1]} cells of {tmap.cell_size_m:g} m; grounds {tmap.ground_names}")
    print(f"robot: {robot}, speed {speed_mps:g} m/s, max slope {max_slope_deg:g} deg; map preparation {prep_s:.2f} s")
    if model is not None:
        print(f"edge costs: model {model_label} ({type(model).__name__}) on grounds {list(mean_cost.ground_labels)}"
              + (f"; planned on the {risk:g} quantile of energy (each edge at mean + z sd)" if risk is not None else "")
              + ("" if mean_cost.has_interval else "; the model gives no interval"))
    budget = f"{max_evaluations} edge-cost evaluations" if max_evaluations is not None else f"time limit {time_limit_s:g} s"
    if planner in GRAPH_PLANNERS:  # searches run to their end: no budget applies
        budget = "no budget (a graph search)"
    n_unknown = int(np.count_nonzero(np.asarray(tmap.ground) == UNKNOWN_GROUND))
    if n_unknown and unknown_ground:
        print(f"ground class unknown in {n_unknown} of {tmap.ground.size} cells: priced as {unknown_ground!r} "
              "(--unknown-ground NAME to choose, 'none' to refuse them)")
    print(f"start {start} -> goal {goal}; planner {planner}, {budget}, seed {seed}")
    if compile_s > 1.0:
        print(f"(compiled the edge-cost kernels in {compile_s:.1f} s: first run in this environment; not in the times below)")
    print()
    if not route.found:
        print(f"no route: status {route.status!r} after {route.planning_time_s:.3f} s")
    else:
        _print_table(rows)
        print()
        if interval is not None:
            lo, hi = interval.interval_j(INTERVAL_LEVEL)
            print(f"route energy (the model's interval): mean {interval.mean_j / 3600:.3f} Wh, P50 "
                  f"{interval.p50_j / 3600:.3f} Wh, P90 {interval.p90_j / 3600:.3f} Wh, sd {interval.sd_j / 3600:.3f} Wh; "
                  f"{100 * INTERVAL_LEVEL:.0f} % interval {lo / 3600:.3f}-{hi / 3600:.3f} Wh"
                  + ("  (the table shows the planning objective)" if risk is not None else ""))
        if route.status == "exact":
            print(
                f"energy saved vs shortest route: {route.energy_saved_pct:.1f} %  "
                f"(min-energy {route.energy_j:.0f} J vs shortest {route.shortest_energy_j:.0f} J); "
                f"drive energy / 16-connected lattice optimum: {route.optimality_ratio:.3f}"
            )
        else:
            short_m = math.dist(route.waypoints_m[-1], goal)
            print(
                f"the {planner} route is {route.status}: it ends {short_m:.1f} m short of the goal, so it is "
                "not compared with the shortest route; give the planner more time"
            )
    result = {
        "map": map_label,
        "map_crs": tmap.crs,
        "robot": robot,
        "speed_mps": speed_mps,
        "max_slope_deg": max_slope_deg,
        "start_xy_m": list(start),
        "goal_xy_m": list(goal),
        **_lonlat_fields(tmap, start, goal),
        "planner": planner,
        "time_limit_s": time_limit_s if max_evaluations is None else None,
        "max_evaluations": max_evaluations,
        "seed": seed,
        "map_preparation_s": prep_s,
        "kernel_compile_s": compile_s,
        "status": route.status,
        "energy_saved_pct": _finite_or_none(route.energy_saved_pct) if route.found else None,
        "optimality_ratio": _finite_or_none(route.optimality_ratio) if route.found else None,
        "table": rows,
        "routes": routes_json,
    }
    if model is not None:  # default files stay as they were
        result["model"] = {"file": model_label, "class": type(model).__name__, "model_ground": model_ground,
                           "grounds": list(mean_cost.ground_labels), "gives_interval": mean_cost.has_interval,
                           "risk_q": risk,
                           "objective": "energy mean" if risk is None else f"{risk:g} quantile: mean + z sd per edge"}
    out_dir.mkdir(parents=True, exist_ok=True)
    json_path = write_json_atomic(out_dir / "route.json", result)
    written = [json_path]
    if route.found:
        found = {"min_energy": route, "lattice": optimum, "shortest": shortest}
        written.append(write_geojson({k: r for k, r in found.items() if r.found}, tmap, out_dir / "route.geojson"))
    png_path = draw_figure(out_dir / "route.png", lambda: plot_routes(
        tmap, lines, start, goal, out_dir / "route.png", title=f"terrawatt: minimum-energy route on {map_label}",
        extent="map" if whole_map else "routes", max_slope_rad=slope_rad))
    written += [png_path] if png_path is not None else []
    if ros2 is not None:
        written += write_ros2_outputs(ros2, route, tmap, cost)
    print("\nwrote " + ", ".join(str(p) for p in written))
    return result


def run_coarse_plan(
    tmap: TerrainMap,
    start: tuple[float, float],
    goal: tuple[float, float],
    *,
    factor: int,
    corridor_m: float | None,
    out_dir: Path,
    robot: str,
    speed_mps: float,
    max_slope_deg: float,
    unknown_ground: str | None,
    map_label: str,
    whole_map: bool = False,
) -> dict[str, Any]:
    """Plan coarse-to-fine (:func:`planner.plan_coarse_to_fine`), print, write route.json, route.geojson, route.png."""
    slope_rad = max_slope_rad(max_slope_deg)
    compile_s = warm_up_kernels()
    t0 = time.perf_counter()
    cost = EnergyCost.from_presets(tmap, robot=robot, speed_mps=speed_mps, max_slope_rad=slope_rad,
                                   unknown_ground=unknown_ground)
    prep_s = time.perf_counter() - t0
    plan = plan_coarse_to_fine(cost, start, goal, factor=factor, corridor_m=corridor_m)
    print(f"map: {map_label}  {tmap.shape[0]} x {tmap.shape[1]} cells of {tmap.cell_size_m:g} m; grounds {tmap.ground_names}")
    print(f"robot: {robot}, speed {speed_mps:g} m/s, max slope {max_slope_deg:g} deg; map preparation {prep_s:.2f} s")
    return _report_coarse(plan, start, goal, out_dir=out_dir, robot=robot, speed_mps=speed_mps,
                          max_slope_deg=max_slope_deg, map_label=map_label, prep_s=prep_s, compile_s=compile_s,
                          fine_map=tmap, whole_map=whole_map)


def run_windowed_plan(
    path: Path,
    start: tuple[float, float],
    goal: tuple[float, float],
    *,
    factor: int,
    corridor_m: float | None,
    out_dir: Path,
    robot: str,
    speed_mps: float,
    max_slope_deg: float,
    unknown_ground: str,
    whole_map: bool = False,
    fine_window_cells: int | None = None,
) -> dict[str, Any]:
    """Plan coarse-to-fine from a GeoTIFF DEM read by windows (:func:`planner.plan_coarse_to_fine_geotiff`);
    print and write the files of :func:`run_coarse_plan` (route.png over the coarse map: the only whole view held)."""
    slope_rad = max_slope_rad(max_slope_deg)
    compile_s = warm_up_kernels()
    with DemWindows(path) as dem:
        grid = dem.grid
    cost_from = functools.partial(EnergyCost.from_presets, robot=robot, speed_mps=speed_mps, max_slope_rad=slope_rad,
                                  unknown_ground=unknown_ground)
    plan = plan_coarse_to_fine_geotiff(path, start, goal, factor=factor, corridor_m=corridor_m, cost_from=cost_from,
                                       fine_window_budget_cells=fine_window_cells)
    rows, cols = grid.shape
    print(f"map: {path.name}  {rows} x {cols} cells of {grid.cell_size_m:g} m, read by windows; ground unknown, "
          f"priced as {unknown_ground!r}")
    print(f"robot: {robot}, speed {speed_mps:g} m/s, max slope {max_slope_deg:g} deg; full-resolution cells read "
          f"by the fine stage: {plan.fine_window_cells} of {rows * cols} ({100 * plan.fine_window_cells / (rows * cols):.1f} %)")
    return _report_coarse(plan, start, goal, out_dir=out_dir, robot=robot, speed_mps=speed_mps,
                          max_slope_deg=max_slope_deg, map_label=path.name, prep_s=0.0, compile_s=compile_s,
                          fine_map=plan.fine_map, whole_map=whole_map, windowed=True)


def _report_coarse(plan: CoarseToFine, start: tuple[float, float], goal: tuple[float, float], *, out_dir: Path,
                   robot: str, speed_mps: float, max_slope_deg: float, map_label: str, prep_s: float, compile_s: float,
                   fine_map: TerrainMap | None, whole_map: bool, windowed: bool = False) -> dict[str, Any]:
    """Print a coarse-to-fine plan and write route.json, route.geojson, route.png.

    ``windowed``: the GeoJSON's elevations come from the fine window (the route lies in it);
    the figure zoomed on the route draws the fine window, the whole-map figure the coarse map."""
    route, factor = plan.route, plan.factor
    plot_map = plan.coarse_map if fine_map is None or (windowed and whole_map) else fine_map
    if compile_s > 1.0:
        print(f"(compiled the edge-cost kernels in {compile_s:.1f} s: first run in this environment; not in the times below)")
    print(f"start {start} -> goal {goal}; coarse-to-fine, factor {factor}, corridor {plan.corridor_m:g} m "
          f"({plan.corridor_cells} free cells searched; fallback: {plan.fallback})")
    print(f"coarse route {plan.coarse_time_s:.2f} s, corridor search {plan.fine_time_s:.2f} s\n")
    if route.found:
        _print_table([_route_row(f"coarse-to-fine (x{factor})", route, math.nan)])
    else:
        print(f"no route: status {route.status!r}")
    result = {
        "map": map_label, "map_crs": plan.coarse_map.crs if plan.coarse_map is not None else None, "robot": robot, "speed_mps": speed_mps, "max_slope_deg": max_slope_deg,
        "start_xy_m": list(start), "goal_xy_m": list(goal), **_lonlat_fields(plan.coarse_map, start, goal),
        "planner": "coarse-to-fine",
        "map_preparation_s": prep_s, "kernel_compile_s": compile_s, "status": route.status, "windowed": windowed,
        "coarse_to_fine": {k: v for k, v in plan.summary().items() if k not in route.summary()},
        "routes": {"min_energy": {**route.summary(), "waypoints_m": route.waypoints_m.tolist()}} if route.found else {},
        "coarse_waypoints_m": plan.coarse_waypoints_m.tolist(),
    }
    out_dir.mkdir(parents=True, exist_ok=True)
    written = [write_json_atomic(out_dir / "route.json", result)]
    lines = []
    if route.found:
        # chained fine windows leave no one fine map: the GeoJSON's elevations then come from the coarse map
        written.append(write_geojson({"min_energy": route}, fine_map if fine_map is not None else plan.coarse_map,
                                     out_dir / "route.geojson"))
        lines.append(RouteLine("coarse-to-fine", route.waypoints_m, route.energy_j, colour="#d32f2f"))
    title = f"terrawatt: coarse-to-fine route on {map_label}" + (f" (the x{factor} coarse map)"
                                                                  if plot_map is plan.coarse_map else "")
    png = draw_figure(out_dir / "route.png", lambda: plot_routes(
        plot_map, lines, start, goal, out_dir / "route.png", title=title,
        extent="map" if whole_map else "routes", max_slope_rad=math.radians(max_slope_deg)))
    written += [png] if png is not None else []
    print("\nwrote " + ", ".join(str(p) for p in written))
    return result
