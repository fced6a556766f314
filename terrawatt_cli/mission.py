"""``terrawatt mission``: an adaptive mission (or a Monte Carlo study of one) in simulation against a battery."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from planner.missions.adaptive_results import check_logs_folder
from planner.missions.mission_report import simulate_adaptive_mission
from planner.missions.monte_carlo_report import monte_carlo_mission
from planner.missions.options import MonteCarloStudy
from planner.missions.request import MissionRequest
from planner.missions.settings import AdaptiveSettings
from terrain import InvalidParameterError

from .common import (
    Checked,
    add_battery_options,
    add_dask_options,
    add_map_options,
    add_model_options,
    add_point_options,
    add_robot_options,
    battery_arg,
    bounded,
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

__all__ = ["add_parser", "run_mission"]

#: How ``mission`` names the parameters of the library's messages (:func:`terrawatt_cli.error_message`).
_FLAGS = {"start": "--start", "start_lonlat": "--start-lonlat", "goal": "--goal", "goal_lonlat": "--goal-lonlat",
          "prior_ground": "--prior-ground", "monte_carlo": "--monte-carlo", "workers": "--workers",
          "scheduler": "--scheduler", "model": "--model", "risk": "--risk", "draw_from": "--mc-draw",
          "n": "--monte-carlo", "max_risk_pct": "--max-risk-pct", "seed": "--seed", "leg_length_m": "--leg-m"}


def add_parser(sub: Any) -> None:
    """The ``mission`` subcommand."""
    p = sub.add_parser("mission",
                       help="drive a planned route in simulation against a battery, learning current models on the way")
    p.add_argument("--map", default="example", metavar="FILE", help=".npz map, .tif DEM or 'example' (default)")
    add_map_options(p)
    add_point_options(p, "start", "start", required=False, default="; default: the example's")
    add_point_options(p, "goal", "goal", required=False, default="; default: the example's")
    add_battery_options(p)
    add_robot_options(p, speed="driving speed", slope=False)
    p.add_argument("--prior-ground", default="asphalt",
                   help="ground the prior current model was trained on (default asphalt); other grounds are learned "
                        "on the way")
    p.add_argument("--leg-m", type=float, default=10.0, metavar="M", action=Checked, check=positive,
                   help="route driven between comparisons (m)")
    p.add_argument("--no-adapt", action="store_true", help="drive the first plan without model updates")
    p.add_argument("--logs", action="store_true",
                   help="also write what the robot's sensors recorded on each leg as CSV logs, OUT/logs/leg_NNN.csv "
                        "(commands, currents, IMU, poses, grounds), each manoeuvre run as OUT/logs/manoeuvre_NNN_K.csv "
                        "and the models it started with as OUT/start_registry/: diagnose the planning model on them "
                        "with terrawatt diagnose --data OUT/logs --model physics --map MAP, or replay them with "
                        "terrawatt replay --data OUT/logs --registry OUT/start_registry --goal X Y --battery-ah AH")
    p.add_argument("--drive-bag", type=Path, default=None, metavar="FILE.mcap|FILE.bag",
                   help="also write the legs the robot drove as one recorded drive: a ROS 2 MCAP (.mcap) or a ROS 1 "
                        "bag (.bag) of odometry, IMU, currents (and GPS on a map with a CRS); replay it with terrawatt "
                        "replay --data FILE --cmd-vel-topic /odom")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--monte-carlo", type=int, default=None, metavar="N", action=Checked,
                   check=bounded("a number of missions >= 1", lambda v: v >= 1),
                   help="instead of one adaptive mission, drive the lattice route N times with drawn ground "
                        "coefficients, payload, capacity fade, internal resistance and speed (seeded by --seed); "
                        "writes monte_carlo.json, .csv and .png")
    p.add_argument("--max-risk-pct", type=float, default=5.0, metavar="P", action=Checked,
                   check=bounded("in [0, 100]", lambda v: 0.0 <= v <= 100.0),
                   help="--monte-carlo: exit 1 when more than P %% of the missions go below the reserve (default 5)")
    p.add_argument("--mc-draw", choices=("parameters", "model"), default="parameters",
                   help="--monte-carlo: draw the typed parameter ranges and simulate each mission (default), or draw "
                        "from --model's predictive distribution (one factor per ground, standard normal or Student-t on a "
                        "ground the model never drove, each edge at mean + z sd)")
    add_dask_options(p, "the --monte-carlo missions")
    add_model_options(p, risk=True)
    p.set_defaults(run=run_mission, flag_names=_FLAGS)


def run_mission(args: argparse.Namespace) -> int:
    """``terrawatt mission``: exit 0 when the robot reached the goal (a study: when at most ``--max-risk-pct`` % of
    the missions went below the reserve), 1 otherwise (no route; a study's failed mission: its row says why)."""
    check_model_flags(args)
    request = MissionRequest(
        on_example=args.map == "example", start=args.start, start_lonlat=args.start_lonlat, goal=args.goal,
        goal_lonlat=args.goal_lonlat, prior_ground=args.prior_ground, monte_carlo=args.monte_carlo,
        workers=args.workers, scheduler=args.scheduler, model=args.model, risk=args.risk, draw_from=args.mc_draw,
)
    mc = args.monte_carlo is not None
    if mc and (args.logs or args.drive_bag is not None):
        raise InvalidParameterError("--logs and --drive-bag write the legs of one adaptive mission, not of "
                                    "--monte-carlo missions")
    if args.drive_bag is not None and args.drive_bag.suffix not in (".mcap", ".bag"):
        raise InvalidParameterError(f"--drive-bag {args.drive_bag} must end in .mcap (ROS 2) or .bag (ROS 1)")
    check_outputs(args.out, ("monte_carlo.json", "monte_carlo.csv", "monte_carlo.png") if mc else
                  ("mission.json", "mission.png"), input_paths(args))
    if args.logs:
        check_logs_folder(args.out)
    tmap, label = map_arg(args)
    start, goal = request.points(tmap)
    pricing = pricing_arg(args, tmap, load_model_arg(args))
    if not mc:
        settings = AdaptiveSettings(leg_length_m=args.leg_m, seed=args.seed,
                                    **({"max_updates": 0} if args.no_adapt else {}))
        report = simulate_adaptive_mission(
            tmap, start, goal, battery=battery_arg(args, pricing.params), pricing=pricing, settings=settings,
            prior_ground=args.prior_ground, map_label=label)
        with warn_figures():
            written = report.write(args.out, logs=args.logs)
        if args.drive_bag is not None:
            written.append(report.write_drive_bag(args.drive_bag))
        print(report.summary())
        logs_written = [p for p in written if p.suffix == ".csv"]
        legs = [p for p in logs_written if p.name.startswith("leg_")]
        print("wrote " + ", ".join(str(p) for p in written if p not in logs_written)
              + (f" and {len(legs)} leg logs and {len(logs_written) - len(legs)} manoeuvre runs in {legs[0].parent}"
                 if legs else ""))
        return 0 if report.completed else 1
    with compute_arg(args, progress=True) as compute:
        study = monte_carlo_mission(
            tmap, start, goal, MonteCarloStudy(args.monte_carlo, seed=args.seed, draw_from=args.mc_draw,
                                               max_risk_pct=args.max_risk_pct),
            battery=battery_arg(args, pricing.params), pricing=pricing, compute=compute, map_label=label)
    print(study.summary())
    if not study.n:  # no route: no mission driven
        return 1
    with warn_figures():
        written = study.write(args.out)
    print(f"wrote {written[0]}, {written[1]}" + (f" and {written[2]}" if len(written) > 2 else ""))
    return 0 if study.ok else 1
