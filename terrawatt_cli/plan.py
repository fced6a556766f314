"""``terrawatt demo`` and ``terrawatt plan``: a minimum-energy route compared with the shortest one."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from planner import PLANNERS, CoarseOptions
from planner.plan_report import plan_and_compare, plan_coarse
from planner.ros_export import check_frame_origin
from terrain import DemWindows, InvalidParameterError, TerrainMap
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M, example_map

from .common import (
    COMMON_FLAGS,
    Checked,
    add_map_options,
    add_model_options,
    add_planner_options,
    add_point_options,
    add_robot_options,
    bounded,
    check_model_flags,
    check_outputs,
    flag_text,
    input_paths,
    load_model_arg,
    map_arg,
    point_arg,
    positive,
    pricing_arg,
    search_arg,
    warn_figures,
)
from .ros2 import ROS2_FLAGS, add_ros2_arguments, check_ros2_outputs, write_ros2_outputs

__all__ = ["add_parsers", "run_demo", "run_plan_command", "coarse_arg"]

_OUTPUTS = ("route.json", "route.geojson", "route.png")
#: How ``plan`` names the parameters of the library's messages (:func:`terrawatt_cli.error_message`).
_FLAGS = {"factor": "--coarse-factor", "corridor_m": "--corridor", "fine_window_budget_cells": "--fine-window-cells",
          "model": "--model", "planner": "--planner",
          **ROS2_FLAGS}
#: The map options a windowed read cannot apply (they need the whole map), by their flags.
_WHOLE_MAP_FLAGS = ("fill_nodata", "reproject", "cell_size", "landcover")


def add_parsers(sub: Any) -> None:
    """The ``demo`` and ``plan`` subcommands."""
    demo = sub.add_parser("demo", help="plan a minimum-energy route on the bundled example map")
    plan = sub.add_parser("plan", help="plan a minimum-energy route on a map file (.npz or GeoTIFF)")
    plan.add_argument("--map", type=Path, required=True, metavar="FILE|example",
                      help=".npz map, .tif DEM or 'example' (the bundled map)")
    add_map_options(plan)
    add_point_options(plan, "start", "start", required=True)
    add_point_options(plan, "goal", "goal", required=True)
    plan.add_argument("--coarse-factor", type=int, default=None, metavar="F", action=Checked,
                      check=bounded("an integer >= 2", lambda v: v >= 2),
                      help="big maps: plan coarse-to-fine (the lattice on a map F times coarser, then the 1-cell "
                           "lattice in a corridor around that route) instead of --planner, without the comparison "
                           "(which needs the whole 1-cell lattice: about 10 GB at 4096 x 4096 cells)")
    plan.add_argument("--corridor", type=float, default=None, metavar="M", action=Checked, check=positive,
                      help="with --coarse-factor: corridor half-width (m; default three coarse cells)")
    plan.add_argument("--windowed", action="store_true",
                      help="with --coarse-factor on a GeoTIFF DEM: read the DEM by windows, never whole (the full "
                           "resolution only in the corridor's window), for DEMs larger than memory")
    plan.add_argument("--fine-window-cells", type=int, default=None, metavar="N", action=Checked, check=positive,
                      help="with --windowed: the most full-resolution cells the fine stage reads at once (default "
                           "8192^2, about 7 GiB once priced); a larger corridor is followed in chained windows")
    for p, time_s, run in ((demo, 1.0, run_demo), (plan, 2.0, run_plan_command)):
        add_planner_options(p, planner="RRTstar", time_s=time_s, choices=PLANNERS)
        add_robot_options(p)
        p.add_argument("--whole-map", action="store_true",
                       help="draw the whole map in route.png (default: zoom on the routes with a margin)")
        add_model_options(p, risk=True)
        add_ros2_arguments(p)
        p.set_defaults(run=run, flag_names=_FLAGS)


def _check_flags(args: argparse.Namespace) -> None:
    check_outputs(args.out, _OUTPUTS, input_paths(args))
    check_ros2_outputs(args, input_paths(args), [args.out / n for n in _OUTPUTS])
    check_model_flags(args)


def run_demo(args: argparse.Namespace) -> int:
    """``terrawatt demo``: plan on the bundled example map."""
    _check_flags(args)
    return _run(args, example_map(), EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M, "bundled example map")


def coarse_arg(args: argparse.Namespace) -> CoarseOptions | None:
    """The :class:`planner.CoarseOptions` of ``--coarse-factor``, ``--corridor`` and (with ``--windowed``)
    ``--fine-window-cells``; None without ``--coarse-factor``. Refuses, before any work, the flags coarse-to-fine
    planning cannot take: ``--corridor`` or ``--windowed`` alone, ``--model``, and with ``--windowed`` a map that is
    not a GeoTIFF or the map options that need the whole map."""
    factor, windowed = getattr(args, "coarse_factor", None), getattr(args, "windowed", False)
    if args.corridor is not None and factor is None:
        raise InvalidParameterError("--corridor applies to coarse-to-fine planning; give --coarse-factor F too")
    if args.model is not None and (factor is not None or windowed):
        raise InvalidParameterError("--model plans on the whole map with --planner; it does not apply to "
                                    "--coarse-factor / --windowed yet")
    if windowed:
        if factor is None:
            raise InvalidParameterError("--windowed plans coarse-to-fine; give --coarse-factor F too")
        if args.map is None or Path(args.map).suffix.lower() not in (".tif", ".tiff"):
            raise InvalidParameterError(f"--windowed reads GeoTIFF DEMs (.tif, .tiff), got --map "
                                        f"{None if args.map is None else Path(args.map).name}")
        for dest in _WHOLE_MAP_FLAGS:
            if getattr(args, dest, None) is not None:
                raise InvalidParameterError(
                    f"--windowed reads the DEM as it is and cannot apply --{dest.replace('_', '-')} (it needs the "
                    "whole map): fill or reproject the DEM first (gdal_fillnodata, gdalwarp), or plan without "
                    "--windowed")
    if factor is None:
        return None
    return CoarseOptions(factor=factor, corridor_m=args.corridor,
                         fine_window_budget_cells=args.fine_window_cells if windowed else None)


def run_plan_command(args: argparse.Namespace) -> int:
    """``terrawatt plan``: on a map file (coarse-to-fine with ``--coarse-factor``, by windows with ``--windowed``)."""
    _check_flags(args)
    coarse = coarse_arg(args)
    if args.windowed:
        pricing = pricing_arg(args, None)
        with DemWindows(args.map) as dem:
            start, goal = point_arg(args, "start", dem), point_arg(args, "goal", dem)
        return _finish(args, plan_coarse(args.map, start, goal, options=coarse, pricing=pricing))
    tmap, label = map_arg(args)
    return _run(args, tmap, point_arg(args, "start", tmap), point_arg(args, "goal", tmap), label, coarse)


def _run(args: argparse.Namespace, tmap: TerrainMap, start: tuple[float, float], goal: tuple[float, float],
         label: str, coarse: CoarseOptions | None = None) -> int:
    if getattr(args, "map_frame_origin", None) is not None:  # before planning: near the map (the writers check it too)
        check_frame_origin(args.map_frame_origin, bounds=tmap.bounds)
    if coarse is not None:
        return _finish(args, plan_coarse(tmap, start, goal, options=coarse, pricing=pricing_arg(args, tmap),
                                         map_label=label))
    return _finish(args, plan_and_compare(
        tmap, start, goal, search=search_arg(args), pricing=pricing_arg(args, tmap, load_model_arg(args)),
        map_label=label), ros2=True)


def _finish(args: argparse.Namespace, report: Any, *, ros2: bool = False) -> int:
    """Print the report (the setting it names, ``unknown_ground``, by its flag), write its files (and the ROS 2 / Nav2
    outputs asked for); exit 0 for an exact route."""
    print(flag_text(report.summary(), "unknown_ground", COMMON_FLAGS))
    with warn_figures():
        written = report.write(args.out, whole_map=args.whole_map)
    if ros2:
        written += write_ros2_outputs(args, report.route, report.terrain, report.cost)
    print("\nwrote " + ", ".join(str(p) for p in written))
    return 0 if report.route.status == "exact" else 1
