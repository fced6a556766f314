"""``terrawatt reach``: how far the robot can go (and come back) from a depot on one battery."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from terrain import TerrainMap
from terrawatt_base.errors import InvalidParameterError
from terrain.procedural import EXAMPLE_START_XY_M, example_map

from planner.reach_report import reach_on_battery
from .common import (
    add_map_options,
    add_model_options,
    add_point_options,
    apply_landcover,
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

__all__ = ["add_parser", "run_reach"]

_GEOTIFF_SUFFIXES = (".tif", ".tiff")


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
    p.add_argument("--battery-ah", type=float, required=True, metavar="AH", help="battery capacity (Ah)")
    p.add_argument("--voltage", "--battery-v", dest="voltage", type=float, default=None, metavar="V",
                   help="battery voltage (default: the robot's)")
    p.add_argument("--reserve", "--reserve-pct", dest="reserve", type=float, default=20.0, metavar="PCT",
                   help="share of the battery kept in reserve (%%, in [0, 100), default 20)")
    p.add_argument("--round-trip", action="store_true", help="budget the way there and back (default: one way)")
    p.add_argument("--robot", default="husky", help="robot preset: paper_seed, jackal or husky (default husky)")
    p.add_argument("--speed", type=float, default=0.5, metavar="M/S", help="driving speed (default 0.5 m/s)")
    p.add_argument("--max-slope-deg", type=float, default=20.0, help="steepest drivable slope (default 20 deg)")
    p.add_argument("--unknown-ground", default="gravel",
                   help="ground preset assumed where the map's ground class is unknown (-1); 'none' to refuse such cells")
    p.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    add_model_options(p)
    p.set_defaults(run=run_reach)


def _raster_name(args: argparse.Namespace, tmap: TerrainMap | None) -> str:
    geo = args.map is not None and args.map.suffix.lower() in _GEOTIFF_SUFFIXES
    return "reach.tif" if geo or (tmap is not None and tmap.crs) else "reach.npz"


def _check_flags(args: argparse.Namespace) -> None:
    check_positive("--battery-ah", args.battery_ah)
    check_positive("--speed", args.speed)
    if args.voltage is not None:
        check_positive("--voltage", args.voltage)
    if not (math.isfinite(args.reserve) and 0.0 <= args.reserve < 100.0):
        raise InvalidParameterError(f"--reserve must be a percentage in [0, 100), got {args.reserve!r}")
    if args.depot is None and args.depot_lonlat is None and args.map is not None:
        raise InvalidParameterError("--depot X Y is required with --map (the depot in the map's metres; or "
                                    "--depot-lonlat LON LAT in degrees)")
    if args.depot is not None and not all(math.isfinite(v) for v in args.depot):
        raise InvalidParameterError(f"--depot must be two finite coordinates (m), got {args.depot!r}")


def run_reach(args: argparse.Namespace) -> int:
    """``terrawatt reach``: writes reach.json, reach.png and the raster; exit 1 when no cell is reachable."""
    _check_flags(args)
    check_model_flags(args)
    max_slope_rad(args.max_slope_deg)
    # Both raster names are checked: which one is written depends on the map, read after the check.
    check_outputs(args.out, ("reach.json", "reach.png", "reach.npz", "reach.tif"), input_paths(args))
    if args.example:
        tmap, label = apply_landcover(args, example_map()), "bundled example map"
    else:
        tmap, label = read_map_args(args), args.map.name
    depot = point_arg(args, "depot", tmap) or EXAMPLE_START_XY_M
    model = load_model_arg(args)
    report = reach_on_battery(
        tmap, depot, battery_ah=args.battery_ah, voltage_v=args.voltage, reserve_pct=args.reserve,
        round_trip=args.round_trip, robot=args.robot, speed_mps=args.speed, max_slope_deg=args.max_slope_deg,
        unknown_ground=None if model is not None else unknown_ground(args.unknown_ground, tmap), model=model,
        model_label=None if model is None else args.model.name, model_ground=args.model_ground, map_label=label)
    with warn_figures():
        written = report.write(args.out, raster=_raster_name(args, tmap))
    print(report.summary())
    print(f"\nwrote {written[0]}, {written[1]}" + (f" and {written[2]}" if len(written) > 2 else ""))
    return 0 if report.reach.n_reachable_cells else 1
