"""``terrawatt tour``: which sites to visit on one charge, in what order, and what is left when back (:func:`planner.tours.plan_tour`)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from planner.missions import MissionDistributions
from planner.points import point_on_map
from planner.tables import check_planning_risk
from planner.tours import (
    TourFleet,
    TourSearch,
    plan_tour_on_map,
    read_tour_chargers_csv,
    read_tour_sites_csv,
    simulate_tours_mc,
)
from terrain import InvalidParameterError

from .common import (
    Checked,
    add_battery_options,
    add_dask_options,
    add_map_options,
    add_model_options,
    add_robot_options,
    battery_arg,
    bounded,
    check_dask_flags,
    check_model_flags,
    check_outputs,
    compute_arg,
    input_paths,
    load_model_arg,
    map_arg,
    positive,
    pricing_arg,
    warn_figures,
)

__all__ = ["add_parser", "run_tour"]

#: How ``tour`` names the parameters of the library's messages (:func:`terrawatt_cli.error_message`).
_FLAGS = {"depot_xy_m": "--depot", "n_robots": "--robots", "max_duration_s": "--max-duration",
          "time_limit_s": "--time-limit", "distributions": "--mc-priced-load", "improve": "--no-improve"}

_OUTPUTS = ("tour.json", "tour.geojson", "tour.png", "tour_soc.png")
#: ``--mc-priced-load``: the default draws but for the payload and the capacity fade, held at the priced robot's.
_PRICED_LOAD = MissionDistributions(payload_kg=(0.0, 0.0), capacity_fade_pct=(0.0, 0.0))
#: What ``--monte-carlo N`` adds (:meth:`planner.tours.TourCheck.write`).
_CHECK_OUTPUTS = ("tour_check.json", "tour_check.png")


def add_parser(sub: Any) -> None:
    """The ``tour`` subcommand."""
    p = sub.add_parser(
        "tour",
        help="many sites on one charge: which sites each robot visits, in what order, coming back above its reserve "
             "at a risk level; writes tour.json, tour.geojson, tour.png and tour_soc.png (with --monte-carlo N, "
             "tour_check.json and tour_check.png)",
        description="Prices every ordered pair of the depot and the sites on the map (uphill != downhill; on dask "
                    "with --workers), then chooses and orders the sites with PyVRP to maximise the value visited while "
                    "every robot's tour, at the Q quantile of its energy, returns above the reserve. Exit 0 with "
                    "tours, 1 when nothing is reachable, 2 on bad input.",
    )
    p.add_argument("--map", required=True, metavar="FILE", help=".npz map, .tif DEM or 'example' (the bundled map)")
    add_map_options(p)
    p.add_argument("--sites", type=Path, required=True, metavar="CSV",
                   help="sites file (as batch's): columns name, x_m, y_m or name, lon, lat in WGS 84 degrees; "
                        "optional value (default 1), service_energy_j, service_time_s, and a time window "
                        "tw_start_s, tw_end_s (s from the departure; both columns or neither, empty cells: none)")
    p.add_argument("--chargers", type=Path, default=None, metavar="CSV",
                   help="charging points the robots may stop at between sites, each stop charging to full (laid out as "
                        "the sites file: name, x_m, y_m or name, lon, lat; optional power_w (W; empty: at once), "
                        "connection_time_s (default 0) and max_visits (stops of the whole fleet, default 2)); the "
                        "energy then holds at Q per segment between charges; solved by OR-Tools)")
    depot = p.add_mutually_exclusive_group(required=True)
    depot.add_argument("--depot", type=float, nargs=2, action="append", metavar=("X", "Y"),
                       help="the depot the robots start from and come back to (m); repeat it for one depot per robot "
                            "(as many as --robots, which then defaults to their number)")
    depot.add_argument("--depot-lonlat", type=float, nargs=2, action="append", metavar=("LON", "LAT"),
                       help="the depot as WGS 84 longitude and latitude (degrees), placed on the map by its CRS; "
                            "instead of --depot, repeatable as it")
    add_battery_options(p, "each robot's battery capacity (Ah)")
    p.add_argument("--max-duration", type=float, default=None, metavar="S", action=Checked, check=positive,
                   help="each robot's longest tour, from leaving the depot to being back (s; driving, waiting and "
                        "service; default: no limit)")
    p.add_argument("--robots", type=int, default=None, metavar="N", action=Checked,
                   check=bounded("an integer >= 1", lambda v: v >= 1),
                   help="robots sharing the sites (default 1, or one per --depot when it is repeated)")
    p.add_argument("--risk", dest="tour_risk", type=float, default=0.9, metavar="Q", action=Checked,
                   check=check_planning_risk,
                   help="risk level Q in [0.5, 1) (default 0.9): every tour's energy at its Q quantile leaves the "
                        "reserve (with --model of a model with an interval; the presets' price is exact)")
    p.add_argument("--time-limit", type=float, default=10.0, metavar="S", action=Checked, check=positive,
                   help="the routing solver's time limit per solve (s, default 10)")
    p.add_argument("--seed", type=int, default=0, help="the routing solver's seed, and the --monte-carlo draws' "
                                                       "(default 0)")
    p.add_argument("--no-improve", dest="improve", action="store_false",
                   help="report the routing solver's tours as they are, without the improvement step priced as driven "
                        "(which inserts left-out sites that still fit, or swaps them in for sites of less value)")
    p.add_argument("--monte-carlo", type=int, default=None, metavar="N", action=Checked,
                   check=bounded("an integer >= 1", lambda v: v >= 1),
                   help="then drive each planned tour N times through the mission simulator, charged to full at "
                        "each charging stop (from the model's own distribution with --model of a model with an "
                        "interval, else drawn parameters; on the --workers cluster) and print the share that ends "
                        "above the reserve, and at each charger arrival, beside Q; writes tour_check.json and "
                        "tour_check.png (exit 1 also when a drive fails, as a Monte Carlo row with an error)")
    p.add_argument("--mc-draw", choices=("parameters", "model"), default=None,
                   help="--monte-carlo: draw the typed parameter ranges and simulate each drive, or draw from the "
                        "pricing model's distribution (default: the model's when it has an interval)")
    p.add_argument("--mc-priced-load", action="store_true",
                   help="--monte-carlo with drawn parameters: no payload and no capacity fade (the robot and battery "
                        "the plan priced) instead of the default ranges of 0-20 kg and 0-20 %%, so that the share "
                        "above the reserve checks the plan, not loads it never heard of")
    p.add_argument("--bag", action="store_true", help="also write each robot's tour as a ROS 2 bag (tour_<k>.mcap)")
    add_dask_options(p, "the pricing of the legs")
    add_robot_options(p)
    add_model_options(p)
    p.set_defaults(run=run_tour, flag_names=_FLAGS)


def run_tour(args: argparse.Namespace) -> int:
    """``terrawatt tour``: plan the tours (with ``--monte-carlo N``, drive them N times), write their files, print the
    summaries; exit 1 when nothing is reachable, a site is an error row (the others planned and written) or a driven
    tour failed, as ``batch`` does for its rows."""
    if args.robots is not None and args.robots != int(args.robots):
        raise InvalidParameterError(f"--robots must be an integer >= 1, got {args.robots!r}")
    flag, given = ("--depot", args.depot) if args.depot else ("--depot-lonlat", args.depot_lonlat)
    robots = int(args.robots) if args.robots is not None else len(given)
    if len(given) > 1 and len(given) != robots:
        raise InvalidParameterError(f"{flag} is given {len(given)} times but --robots is {robots}: give one depot "
                                    "per robot, or one for all")
    check_dask_flags(args)
    check_model_flags(args)
    if args.monte_carlo is None and (args.mc_draw is not None or args.mc_priced_load):
        raise InvalidParameterError("--mc-draw and --mc-priced-load apply to --monte-carlo N: add it")
    if args.mc_priced_load and args.mc_draw == "model":
        raise InvalidParameterError("--mc-priced-load holds drawn parameters, --mc-draw model draws none: give one")
    bags = tuple(f"tour_{k}.mcap" for k in range(robots)) if args.bag else ()
    checked = _CHECK_OUTPUTS if args.monte_carlo is not None else ()
    check_outputs(args.out, _OUTPUTS + bags + checked, input_paths(args))  # the bags too: none may replace an input
    tmap, label = map_arg(args)
    depots = [point_on_map(xy if flag == "--depot" else None, xy if flag != "--depot" else None, tmap,
                           names=("depot", "depot_lonlat")) for xy in given]
    sites = read_tour_sites_csv(args.sites, tmap)
    chargers = read_tour_chargers_csv(args.chargers, tmap) if args.chargers is not None else None
    pricing = pricing_arg(args, tmap, load_model_arg(args))
    with compute_arg(args, progress=False) as compute:
        fleet = TourFleet(battery=battery_arg(args, pricing.params), depot_xy_m=depots[0] if len(depots) == 1 else depots,
                          n_robots=robots, max_duration_s=args.max_duration)
        result = plan_tour_on_map(
            tmap, sites, fleet, search=TourSearch(risk=args.tour_risk, time_limit_s=args.time_limit, seed=args.seed,
                                              improve=args.improve),
            pricing=pricing, compute=compute, map_label=label, chargers=chargers)
        check = simulate_tours_mc(result, args.monte_carlo, seed=args.seed, draw_from=args.mc_draw,
                                  distributions=_PRICED_LOAD if args.mc_priced_load else None,
                                  compute=compute) if checked else None
    with warn_figures():
        written = result.write(args.out, bag=args.bag)
        written += check.write(args.out) if check is not None else []
    print(result.summary())
    if check is not None:
        print(f"\nMonte Carlo, each tour driven {args.monte_carlo} times:\n{check.summary()}")
    print("\nwrote " + ", ".join(str(w) for w in written))
    failed = check is not None and any(check.n_failed(robot) for robot in check.runs)
    return 0 if result.status == "planned" and not result.errors and not failed else 1
