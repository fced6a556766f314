"""``terrawatt batch``: plan many (start, goal) pairs on one map, here or on dask (:func:`planner.plan_batch`)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from planner import PLANNERS, BatchPairs, read_pairs_csv
from planner.batch import plan_batch_on_map
from planner.batch_pairs import read_sites_csv
from terrain import InvalidParameterError

from .common import (
    add_dask_options,
    add_map_options,
    add_model_options,
    add_planner_options,
    add_robot_options,
    check_dask_flags,
    check_model_flags,
    check_outputs,
    compute_arg,
    input_paths,
    load_model_arg,
    map_arg,
    pricing_arg,
    search_arg,
)

__all__ = ["add_parser", "run_batch"]

_OUTPUTS = ("batch.csv", "batch.json")


def add_parser(sub: Any) -> None:
    """The ``batch`` subcommand."""
    batch = sub.add_parser(
        "batch",
        help="plan many (start, goal) pairs on one map, in process or on a dask cluster; writes batch.csv and batch.json",
        description="Exit 0 when every pair has a route, 1 when some pair has none or failed (its row says why), "
                    "2 on bad input.",
    )
    batch.add_argument("--map", required=True, metavar="FILE", help=".npz map, .tif DEM or 'example' (the bundled map)")
    add_map_options(batch)
    source = batch.add_mutually_exclusive_group(required=True)
    source.add_argument("--pairs", type=Path, metavar="CSV",
                        help="pairs file: columns start_x_m, start_y_m, goal_x_m, goal_y_m, or start_lon, start_lat, "
                             "goal_lon, goal_lat in WGS 84 degrees (on a map with a CRS), and optionally name")
    source.add_argument("--sites", type=Path, metavar="CSV",
                        help="sites file: columns x_m, y_m, or lon, lat in WGS 84 degrees, and optionally name")
    batch.add_argument("--all-pairs", action="store_true", help="with --sites: plan every ordered pair of sites")
    add_dask_options(batch, "the pairs")
    add_planner_options(batch, planner="lattice", time_s=1.0, choices=PLANNERS)
    add_robot_options(batch)
    batch.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_model_options(batch)
    batch.set_defaults(run=run_batch)


def run_batch(args: argparse.Namespace) -> int:
    """``terrawatt batch``: plan the pairs (degrees placed by the map's CRS), write batch.csv and batch.json."""
    if (args.sites is not None) != args.all_pairs:
        raise InvalidParameterError("--sites needs --all-pairs (every ordered pair of the sites is planned)"
                                    if args.sites is not None else "--all-pairs needs --sites CSV")
    check_dask_flags(args)
    check_model_flags(args)
    check_outputs(args.out, _OUTPUTS, input_paths(args))
    tmap, label = map_arg(args)
    if args.pairs is not None:
        pairs = read_pairs_csv(args.pairs, tmap)
    else:
        names, xy = read_sites_csv(args.sites, tmap)
        pairs = BatchPairs.all_pairs(xy, names)
    pricing = pricing_arg(args, tmap, load_model_arg(args))
    with compute_arg(args, progress=not args.no_progress) as compute:  # a missing extra or scheduler fails first
        report = plan_batch_on_map(tmap, pairs, search=search_arg(args), pricing=pricing, compute=compute,
                                   map_label=label)
    csv_path, json_path = report.write(args.out)
    print(report.summary())
    print(f"wrote {csv_path} and {json_path}")
    return 0 if report.all_found else 1
