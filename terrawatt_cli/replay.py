"""``terrawatt replay``: a recorded drive fed through the ride-along navigator; what it learned and decided."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from energy.io import read_navsat
from planner.missions.replay_report import place_by_gps, replay_recording
from planner.missions.settings import UPDATE_SOURCES, AdaptiveSettings, MissionGoal, ReplayFeed
from planner.model_cost import parse_model_ground
from planner.tables import check_planning_risk

from .common import (
    Checked,
    add_battery_options,
    add_map_options,
    add_point_options,
    battery_arg,
    bounded,
    check_model_flags,
    check_outputs,
    input_paths,
    load_model_arg,
    map_arg,
    point_arg,
    positive,
    pricing_arg,
    robot_arg,
    warn_figures,
)
from .data import add_data_options, logs_from_args

__all__ = ["add_parser", "run_replay"]

#: How ``replay`` names the parameters of the library's messages (:func:`terrawatt_cli.error_message`).
_FLAGS = {"registry": "--registry", "pricing.model": "--model", "physics_ground": "--physics-ground",
          "initial_soc": "--soc", "state_path": "--state", "goal_xy_m": "--goal", "goal_lonlat_deg": "--goal-lonlat",
          "depot_xy_m": "--depot", "chunk_s": "--chunk-s", "speed_up": "--speed-up", "mode": "--mode"}


def add_parser(sub: Any) -> None:
    """The ``replay`` subcommand."""
    p = sub.add_parser("replay", help="feed a recorded drive (a bag, an MCAP, a CSV log or a folder of legs) through "
                                      "the ride-along navigator: where its models are wrong, what it learned, each "
                                      "replan and decision")
    add_data_options(p)
    p.add_argument("--map", default="example", metavar="FILE", help=".npz map, .tif DEM or 'example' (default)")
    add_map_options(p)
    add_point_options(p, "goal", "goal", required=False, default="; default: where the recording ends")
    add_point_options(p, "depot", "depot to return to when the rest does not fit", required=False,
                      default="; default: no return, stop")
    models = p.add_mutually_exclusive_group()
    models.add_argument("--registry", type=Path, default=None, metavar="DIR",
                        help="the per-cell models the drive started with (a registry directory, e.g. the "
                             "start_registry/ that terrawatt mission --logs writes)")
    models.add_argument("--model", type=Path, default=None, metavar="FILE",
                        help="a saved current model (terrawatt train) serving every cell at the start")
    p.add_argument("--model-ground", default=None, nargs="+", metavar="NAME|CLASS=NAME", action=Checked,
                   check=parse_model_ground, help="with --model: serve each map class by the model's ground of that name (as terrawatt mission "
                        "--model does)")
    add_battery_options(p, "battery capacity (Ah; not needed when resuming from --state)", required=False)
    p.add_argument("--soc", type=float, default=1.0, metavar="F", action=Checked,
                   check=bounded("in (0, 1]", lambda v: 0.0 < v <= 1.0),
                   help="state of charge at the start of the recording (default 1)")
    p.add_argument("--robot", default="husky", metavar="NAME|FILE.json", action=Checked, check=robot_arg,
                   help="robot preset (default husky) or robot file")
    p.add_argument("--speed", type=float, default=0.5, action=Checked, check=positive, metavar="M/S",
                   help="planning speed (default 0.5 m/s)")
    p.add_argument("--physics-ground", default="asphalt", metavar="NAME",
                   help="ground preset of the physics slope term of the edge costs (default asphalt)")
    p.add_argument("--leg-m", type=float, default=10.0, metavar="M", action=Checked, check=positive,
                   help="distance between checkpoints of a long drive (m; a folder of legs: each leg)")
    p.add_argument("--update-source", choices=UPDATE_SOURCES, default="manoeuvre",
                   help="fit a flagged region's model on the recording's manoeuvres first (default; declined when the "
                        "recording holds none: then on the driving) or on the driving first")
    p.add_argument("--risk", type=float, default=None, metavar="Q", action=Checked, check=check_planning_risk,
                   help="decide on the Q quantile of the remaining energy (Q in [0.5, 1); default the forecast)")
    p.add_argument("--mode", choices=("auto", "legs", "drive"), default="auto",
                   help="legs: each log a leg, checked at its end; drive: one drive cut in --chunk-s chunks; auto "
                        "(default): legs for several logs")
    p.add_argument("--chunk-s", type=float, default=1.0, metavar="S", action=Checked, check=positive,
                   help="chunk length fed to the navigator in drive mode (default 1 s)")
    p.add_argument("--speed-up", type=float, default=None, metavar="N", action=Checked, check=positive,
                   help="pace the replay at N times real time (default: as fast as possible)")
    p.add_argument("--state", type=Path, default=None, metavar="DIR",
                   help="save the navigator's state here at each checkpoint; resume from it when it exists")
    p.add_argument("--gps-topic", default=None, metavar="TOPIC",
                   help="place the drive on the map by the bag's sensor_msgs/NavSatFix fixes (through the map's CRS) "
                        "instead of its odometry's positions")
    p.add_argument("--no-mcap", action="store_true", help="do not write replay.mcap")
    p.add_argument("--seed", type=int, default=0, help="seed of the navigator's refinement and manoeuvres (default 0)")
    p.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    p.set_defaults(run=run_replay, flag_names=_FLAGS)


def run_replay(args: argparse.Namespace) -> int:
    """``terrawatt replay``: exit 0 when the navigator reached the goal or the recording ended on the way, 1 when it
    stopped (the rest did not fit, no route, the reserve was reached)."""
    if args.model is None and args.model_ground is not None:
        check_model_flags(args)
    files = ("replay.json", "replay.png") + (() if args.no_mcap else ("replay.mcap",))
    check_outputs(args.out, files, [*input_paths(args), args.data])
    tmap, label = map_arg(args)
    logs = logs_from_args(args, require_currents=False)
    if args.gps_topic is not None:
        track = read_navsat(args.data, args.gps_topic, start_time_ns=logs[0].meta.start_time_ns)
        logs = place_by_gps(logs, track, tmap)
    goal = point_arg(args, "goal", tmap)
    if goal is None:  # the recording's last pose
        last = max(logs, key=lambda log: float(log.time_s[-1]))
        if last.pose_xyh is not None:
            goal = (float(last.pose_xyh[-1, 0]), float(last.pose_xyh[-1, 1]))
    model = load_model_arg(args)

    def say(decision: Any) -> None:
        print(f"t={decision.time_s:9.2f} s  {decision.action:9s} {decision.reason}")

    pricing = pricing_arg(args, tmap, model)
    battery = battery_arg(args, pricing.params)
    result = replay_recording(
        tmap, logs, None if goal is None else MissionGoal(xy_m=goal, depot_xy_m=point_arg(args, "depot", tmap)),
        battery=None if battery is None else battery.replace(initial_soc=args.soc), pricing=pricing,
        settings=AdaptiveSettings(leg_length_m=args.leg_m, seed=args.seed, update_source=args.update_source),
        registry=args.registry, physics_ground=args.physics_ground,
        feed=ReplayFeed(mode=args.mode, chunk_s=args.chunk_s, speed_up=args.speed_up, state_path=args.state,
                        on_decision=say), map_label=label)
    print(result.summary())
    with warn_figures():
        written = result.write(args.out, mcap=not args.no_mcap)
    print("wrote " + ", ".join(str(p) for p in written))
    nav = result.navigator
    return 1 if nav.finished and nav.status != "completed" else 0

