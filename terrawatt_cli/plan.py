"""``terrawatt demo`` and ``terrawatt plan``: a minimum-energy route compared with the shortest one."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from energy import GROUND_PRESETS
from terrain import DemWindows, InvalidParameterError, TerrainMap, UnknownNameError
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M, example_map

from planner import PLANNERS
from planner.coarse_report import plan_coarse, plan_coarse_windowed
from planner.plan_report import plan_and_compare
from .common import (
    add_map_options,
    add_model_options,
    add_point_options,
    check_model_flags,
    check_outputs,
    check_positive,
    input_paths,
    load_model_arg,
    max_slope_rad,
    point_arg,
    read_map_args,
    unknown_ground,
    warn_figures,
)
from .ros2 import add_ros2_arguments, check_ros2_outputs, write_ros2_outputs

__all__ = ["add_parsers", "run_demo", "run_plan_command"]

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


def _check_outputs(args: argparse.Namespace) -> None:
    check_outputs(args.out, _OUTPUTS, input_paths(args))
    check_ros2_outputs(args, input_paths(args), [args.out / n for n in _OUTPUTS])
    check_model_flags(args)


def run_demo(args: argparse.Namespace) -> int:
    """``terrawatt demo``: plan on the bundled example map."""
    _check_outputs(args)
    return _run(args, example_map(), EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M, "bundled example map")


def run_plan_command(args: argparse.Namespace) -> int:
    """``terrawatt plan``: on a map file (coarse-to-fine with ``--coarse-factor``, by windows with ``--windowed``)."""
    _check_outputs(args)
    if args.model is not None and (args.windowed or args.coarse_factor is not None):
        raise InvalidParameterError("--model plans on the whole map with --planner; it does not apply to "
                                    "--coarse-factor / --windowed yet")
    if args.windowed:
        return _run_windowed(args)
    tmap = read_map_args(args)
    return _run(args, tmap, point_arg(args, "start", tmap), point_arg(args, "goal", tmap), args.map.name)


def _check_coarse_flags(args: argparse.Namespace) -> None:
    factor, corridor = getattr(args, "coarse_factor", None), getattr(args, "corridor", None)
    if corridor is not None and factor is None:
        raise InvalidParameterError("--corridor applies to coarse-to-fine planning; give --coarse-factor F too")
    if factor is not None and factor < 2:
        raise InvalidParameterError(f"--coarse-factor must be an integer >= 2, got {factor}")
    if corridor is not None:
        check_positive("--corridor", corridor)


def _run(args: argparse.Namespace, tmap: TerrainMap, start: tuple[float, float], goal: tuple[float, float],
         label: str) -> int:
    check_positive("--speed", args.speed)
    check_positive("--time-limit", args.time_limit)
    if args.max_evaluations is not None:
        check_positive("--max-evaluations", args.max_evaluations)
    _check_coarse_flags(args)
    max_slope_rad(args.max_slope_deg)
    common = dict(robot=args.robot, speed_mps=args.speed, max_slope_deg=args.max_slope_deg, map_label=label)
    if getattr(args, "coarse_factor", None) is not None:
        return _finish(args, plan_coarse(tmap, start, goal, factor=args.coarse_factor, corridor_m=args.corridor,
                                         unknown_ground=unknown_ground(args.unknown_ground, tmap), **common))
    model = load_model_arg(args)
    report = plan_and_compare(
        tmap, start, goal, planner=args.planner, seed=args.seed, time_limit_s=args.time_limit,
        max_evaluations=args.max_evaluations, unknown_ground=None if model is not None else unknown_ground(
            args.unknown_ground, tmap), model=model, model_label=None if model is None else args.model.name,
        model_ground=args.model_ground, risk=args.risk, risk_name="--risk", **common,
    )
    return _finish(args, report, ros2=True)


def _run_windowed(args: argparse.Namespace) -> int:
    """``terrawatt plan --windowed``: its flags checked before any work, then the plan."""
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
    _check_coarse_flags(args)
    check_positive("--speed", args.speed)
    if args.fine_window_cells is not None:
        check_positive("--fine-window-cells", args.fine_window_cells)
    if args.unknown_ground.lower() == "none":
        raise InvalidParameterError(
            "a GeoTIFF DEM has no ground classes, so --unknown-ground none refuses every cell; give "
            f"--unknown-ground NAME, one of {sorted(GROUND_PRESETS)!r}")
    if args.unknown_ground not in GROUND_PRESETS:
        raise UnknownNameError(f"--unknown-ground must be a ground preset, one of {sorted(GROUND_PRESETS)!r}, "
                               f"or 'none'; got {args.unknown_ground!r}")
    max_slope_rad(args.max_slope_deg)
    with DemWindows(args.map) as dem:
        start, goal = point_arg(args, "start", dem), point_arg(args, "goal", dem)
    return _finish(args, plan_coarse_windowed(
        args.map, start, goal, factor=args.coarse_factor, corridor_m=args.corridor, robot=args.robot,
        speed_mps=args.speed, max_slope_deg=args.max_slope_deg, unknown_ground=args.unknown_ground,
        fine_window_cells=args.fine_window_cells))


def _finish(args: argparse.Namespace, report: Any, *, ros2: bool = False) -> int:
    """Print the report, write its files (and the ROS 2 / Nav2 outputs asked for); exit 0 for an exact route."""
    print(report.summary())
    with warn_figures():
        written = report.write(args.out, whole_map=args.whole_map)
    if ros2:
        written += write_ros2_outputs(args, report.route, report.terrain, report.cost)
    print("\nwrote " + ", ".join(str(p) for p in written))
    return 0 if report.route.status == "exact" else 1
