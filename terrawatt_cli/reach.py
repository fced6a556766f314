"""``terrawatt reach``: how far the robot can go (and come back) from a depot on one battery."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from planner.reach_report import reach_on_battery
from terrain import InvalidParameterError
from terrain.procedural import EXAMPLE_START_XY_M

from .common import (
    add_battery_options,
    add_map_options,
    add_model_options,
    add_point_options,
    add_robot_options,
    battery_arg,
    check_model_flags,
    check_outputs,
    input_paths,
    load_model_arg,
    map_arg,
    point_arg,
    pricing_arg,
    warn_figures,
)

__all__ = ["add_parser", "run_reach"]


def add_parser(sub: Any) -> None:
    """The ``reach`` subcommand."""
    p = sub.add_parser(
        "reach",
        help="energy reachability: the least energy from a depot to every cell (and back), within a battery",
        description="Least drive energy from a depot to every cell of a map on the directed 16-connected lattice "
                    "(with --round-trip: there and back), and the cells reachable with a battery above its reserve. "
                    "Writes reach.json, reach.png and the energy raster: reach.tif when the map is a GeoTIFF or has "
                    "a CRS, else reach.npz (every raster).",
    )
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--map", type=Path, metavar="FILE", help=".npz map or .tif DEM")
    source.add_argument("--example", action="store_true", help="the bundled example map")
    add_map_options(p)
    add_point_options(p, "depot", "depot", required=False,
                      default="; --depot or --depot-lonlat is required with --map, default with --example: the "
                              "example's start")
    add_battery_options(p)
    p.add_argument("--round-trip", action="store_true", help="budget the way there and back (default: one way)")
    add_robot_options(p, speed="driving speed")
    add_model_options(p)
    p.set_defaults(run=run_reach)


def run_reach(args: argparse.Namespace) -> int:
    """``terrawatt reach``: writes reach.json, reach.png and the raster; exit 1 when no cell is reachable."""
    if args.depot is None and args.depot_lonlat is None and args.map is not None:
        raise InvalidParameterError("--depot X Y is required with --map (the depot in the map's metres; or "
                                    "--depot-lonlat LON LAT in degrees)")
    check_model_flags(args)
    # both raster names: which one is written depends on the map, read after the check
    check_outputs(args.out, ("reach.json", "reach.png", "reach.npz", "reach.tif"), input_paths(args))
    tmap, label = map_arg(args)
    depot = point_arg(args, "depot", tmap) or EXAMPLE_START_XY_M
    pricing = pricing_arg(args, tmap, load_model_arg(args))
    geo = bool(tmap.crs) or str(args.map).lower().endswith((".tif", ".tiff"))
    report = reach_on_battery(
        tmap, depot, battery=battery_arg(args, pricing.params), round_trip=args.round_trip, pricing=pricing, map_label=label)
    with warn_figures():
        written = report.write(args.out, raster="reach.tif" if geo else "reach.npz")
    print(report.summary())
    print(f"\nwrote {written[0]}, {written[1]}" + (f" and {written[2]}" if len(written) > 2 else ""))
    return 0 if report.n_reachable_cells else 1
