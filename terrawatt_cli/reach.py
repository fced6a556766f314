"""``terrawatt reach``: how far the robot can go (and come back) from a depot on one battery."""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path
from typing import Any

from energy import robot_preset
from energy.battery import S_PER_H
from terrain import TerrainMap
from terrawatt_base.atomic import write_json_atomic
from terrawatt_base.errors import InvalidParameterError
from terrain.procedural import EXAMPLE_START_XY_M, example_map

from planner import Reachability, reachability, warm_up_kernels
from planner.reachability import warm_up_reachability
from .common import (
    add_map_options,
    add_model_options,
    add_point_options,
    apply_landcover,
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
    slope_rad = max_slope_rad(args.max_slope_deg)
    # Both raster names are checked: which one is written depends on the map, read after the check.
    check_outputs(args.out, ("reach.json", "reach.png", "reach.npz", "reach.tif"), input_paths(args))
    robot = robot_preset(args.robot)
    if args.example:
        tmap, label = apply_landcover(args, example_map()), "bundled example map"
    else:
        tmap, label = read_map_args(args), args.map.name
    depot = point_arg(args, "depot", tmap) or EXAMPLE_START_XY_M
    model = load_model_arg(args)
    ground = None if model is not None else unknown_ground(args.unknown_ground, tmap)
    voltage_v = args.voltage if args.voltage is not None else robot.battery_voltage_v
    budget_j = args.battery_ah * voltage_v * S_PER_H
    reserve_j = budget_j * args.reserve / 100.0
    compile_s = warm_up_kernels() + warm_up_reachability()
    t0 = time.perf_counter()
    cost = edge_cost_for(tmap, robot=args.robot, speed_mps=args.speed, max_slope_rad=slope_rad, unknown_ground=ground,
                         model=model, model_ground=args.model_ground)
    prep_s = time.perf_counter() - t0
    reach = reachability(cost, depot, budget_j=budget_j, reserve_j=reserve_j, round_trip=args.round_trip)
    total_s = time.perf_counter() - t0
    args.out.mkdir(parents=True, exist_ok=True)
    raster = reach.write(args.out / _raster_name(args, tmap))
    result = {
        "map": label,
        "robot": args.robot,
        "speed_mps": args.speed,
        "max_slope_deg": args.max_slope_deg,
        "battery_ah": args.battery_ah,
        "battery_voltage_v": voltage_v,
        "reserve_pct": args.reserve,
        "map_preparation_s": prep_s,
        "total_time_s": total_s,
        "kernel_compile_s": compile_s,
        "raster": raster.name,
        **reach.to_dict(),
    }
    if model is not None:  # default files stay as they were
        result["model"] = {"file": args.model.name, "class": type(model).__name__, "model_ground": args.model_ground,
                           "grounds": list(cost.ground_labels)}
    json_path = write_json_atomic(args.out / "reach.json", result)
    png_path = draw_figure(args.out / "reach.png", lambda: reach.plot(
        args.out / "reach.png", title=f"terrawatt: energy reachability on {label}"))
    _print_summary(reach, tmap, label, args, voltage_v, prep_s, total_s)
    if compile_s > 1.0:
        print(f"(compiled the kernels in {compile_s:.1f} s: first run in this environment; not in the times above)")
    print(f"\nwrote {raster}, {json_path}" + (f" and {png_path}" if png_path is not None else ""))
    return 0 if reach.n_reachable_cells else 1


def _print_summary(reach: Reachability, tmap: TerrainMap, label: str, args: argparse.Namespace, voltage_v: float,
                   prep_s: float, total_s: float) -> None:
    def wh(j: float) -> str:
        return "-" if math.isnan(j) else f"{j / S_PER_H:.2f} Wh"

    budget_wh = reach.budget_j / S_PER_H if reach.budget_j is not None else math.nan
    print(f"map: {label}  {tmap.shape[0]} x {tmap.shape[1]} cells of {tmap.cell_size_m:g} m")
    print(f"robot: {args.robot}, speed {args.speed:g} m/s, max slope {args.max_slope_deg:g} deg")
    print(f"battery {args.battery_ah:g} Ah at {voltage_v:g} V = {budget_wh:.1f} Wh; reserve {args.reserve:g} % "
          f"-> {reach.usable_energy_j / S_PER_H:.1f} Wh usable {'there and back' if reach.round_trip else 'one way'}")
    print(f"depot {reach.depot_xy_m}")
    print()
    rows = [
        ("reachable area", f"{reach.reachable_area_m2:,.0f} m^2 ({100 * reach.reachable_fraction:.1f} % of free cells)"),
        ("reachable cells", f"{reach.n_reachable_cells:,}"),
        ("farthest reachable", "-" if math.isnan(reach.farthest_reachable_m) else f"{reach.farthest_reachable_m:,.1f} m"),
        ("max one-way energy", wh(reach.max_forward_energy_j)),
    ]
    if reach.round_trip:
        rows.append(("max round-trip energy", wh(reach.max_round_trip_energy_j)))
    rows += [
        ("map preparation", f"{prep_s:.2f} s"),
        ("lattice moves", f"{reach.graph_time_s:.2f} s"),
        ("search", f"{reach.search_time_s:.2f} s"),
        ("total", f"{total_s:.2f} s"),
    ]
    for name, value in rows:
        print(f"{name:<24} {value}")
    if not reach.n_reachable_cells:
        print("\nno cell is reachable within the usable energy: a larger battery or a smaller --reserve")
