"""``terrawatt mission``: an adaptive mission in simulation against a battery; prints its budget."""

from __future__ import annotations

import argparse
from typing import Any

from energy import GROUND_PRESETS
from terrain import InvalidParameterError, UnknownNameError
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M

from planner.missions.mission_report import check_preset_grounds, simulate_adaptive_mission
from planner.missions.monte_carlo_report import monte_carlo_mission
from .common import (Checked, add_dask_options, add_map_options, add_model_options, add_point_options,
                     add_robot_options, bounded, check_dask_flags, check_model_flags, check_outputs, dask_client_arg,
                     input_paths, load_model_arg, map_arg, point_arg, positive, warn_figures)

__all__ = ["add_parser", "run_mission", "add_monte_carlo_options", "check_monte_carlo_flags", "run_monte_carlo"]

_OUTPUTS = ("mission.json", "mission.png")
_MC_OUTPUTS = ("monte_carlo.json", "monte_carlo.csv", "monte_carlo.png")


def _preset(name: str, flag: str) -> str:
    if name not in GROUND_PRESETS:
        raise UnknownNameError(f"{flag} {name!r} has no preset; known grounds: {sorted(GROUND_PRESETS)!r}")
    return name


def add_parser(sub: Any) -> None:
    """The ``mission`` subcommand."""
    p = sub.add_parser("mission",
                       help="drive a planned route in simulation against a battery, learning current models on the way")
    p.add_argument("--map", default="example", metavar="FILE", help=".npz map, .tif DEM or 'example' (default)")
    add_map_options(p)
    add_point_options(p, "start", "start", required=False, default="; default: the example's")
    add_point_options(p, "goal", "goal", required=False, default="; default: the example's")
    p.add_argument("--battery-ah", type=float, required=True, metavar="AH", action=Checked, check=positive,
                   help="battery capacity (Ah)")
    p.add_argument("--battery-v", type=float, default=None, metavar="V", action=Checked, check=positive,
                   help="battery voltage (default: the robot's)")
    p.add_argument("--reserve-pct", type=float, default=20.0, metavar="P", action=Checked,
                   check=bounded("in [0, 100)", lambda v: 0.0 <= v < 100.0), help="minimum reserve (%%, default 20)")
    add_robot_options(p, speed="driving speed", slope=False)
    p.add_argument("--prior-ground", default="asphalt", action=Checked, check=_preset,
                   help="ground the prior current model was trained on (default asphalt); other grounds are learned "
                        "on the way")
    p.add_argument("--leg-m", type=float, default=10.0, metavar="M", action=Checked, check=positive,
                   help="route driven between comparisons (m)")
    p.add_argument("--no-adapt", action="store_true", help="drive the first plan without model updates")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    add_monte_carlo_options(p)
    add_model_options(p, risk=True)
    p.set_defaults(run=run_mission)


def run_mission(args: argparse.Namespace) -> int:
    """``terrawatt mission``: adaptive mission in simulation; writes mission.json and mission.png.

    Exit code 0 when the robot reached the goal, 1 when the mission stopped short (budget
    exceeded, reserve crossed, no route).
    """
    check_monte_carlo_flags(args)
    check_model_flags(args)
    if args.risk is not None and args.monte_carlo is None:
        raise InvalidParameterError("--risk Q of mission checks the route's Q quantile against the usable battery in a "
                                    "--monte-carlo N study; the adaptive mission does not take it yet")
    if args.mc_draw == "model" and args.model is None:
        raise InvalidParameterError("--mc-draw model draws from a saved model's predictive distribution: give --model FILE")
    check_outputs(args.out, _OUTPUTS if args.monte_carlo is None else _MC_OUTPUTS, input_paths(args))
    if args.map != "example" and (
            (args.start is None and args.start_lonlat is None) or (args.goal is None and args.goal_lonlat is None)):
        raise InvalidParameterError("--start and --goal (or --start-lonlat and --goal-lonlat) are required with a "
                                    "map file")
    tmap, label = map_arg(args)
    start = point_arg(args, "start", tmap) or EXAMPLE_START_XY_M
    goal = point_arg(args, "goal", tmap) or EXAMPLE_GOAL_XY_M
    check_preset_grounds(tmap)
    if args.monte_carlo is not None:
        return run_monte_carlo(args, tmap, label, start, goal)
    report = simulate_adaptive_mission(
        tmap, start, goal, battery_ah=args.battery_ah, battery_v=args.battery_v, reserve_pct=args.reserve_pct,
        robot=args.robot, speed_mps=args.speed, prior_ground=args.prior_ground, leg_m=args.leg_m,
        adapt=not args.no_adapt, seed=args.seed, model=load_model_arg(args), model_ground=args.model_ground,
        map_label=label)
    with warn_figures():
        written = report.write(args.out)
    print(report.summary())
    print(f"wrote {written[0]}" + (f" and {written[1]}" if len(written) > 1 else ""))
    return 0 if report.completed else 1


def add_monte_carlo_options(p: argparse.ArgumentParser) -> None:
    """``--monte-carlo N``, its risk threshold and where its missions run."""
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
                        "from --model's predictive distribution (one standard-normal factor per ground, each edge at "
                        "mean + z sd)")
    add_dask_options(p, "the --monte-carlo missions")


def check_monte_carlo_flags(args: argparse.Namespace) -> None:
    """The ``--monte-carlo`` flags that go together, checked before any work."""
    if args.monte_carlo is None and (args.workers != 1 or args.scheduler is not None):
        raise InvalidParameterError("--workers and --scheduler apply to --monte-carlo N only")
    check_dask_flags(args)


def run_monte_carlo(args: argparse.Namespace, tmap: Any, label: str, start: tuple, goal: tuple) -> int:
    """``terrawatt mission --monte-carlo N``: plan the lattice route, drive it N times with drawn parameters.

    Exit code 0 when at most ``--max-risk-pct`` % of the missions go below the reserve, 1
    otherwise, when there is no route, or when a mission failed (its row in monte_carlo.csv
    says why; the statistics are over the completed missions).
    """
    model = load_model_arg(args)
    with dask_client_arg(args) as client:
        report = monte_carlo_mission(
            tmap, start, goal, args.monte_carlo, battery_ah=args.battery_ah, battery_v=args.battery_v,
            reserve_pct=args.reserve_pct, robot=args.robot, speed_mps=args.speed, seed=args.seed, model=model,
            model_label=None if model is None else args.model.name, model_ground=args.model_ground, risk=args.risk,
            draw_from=args.mc_draw, max_risk_pct=args.max_risk_pct, client=client,
            where=args.scheduler or "local cluster", progress=True, map_label=label, flags=("--risk", "--mc-draw"))
    print(report.summary())
    if report.result is None:
        return 1
    with warn_figures():
        written = report.write(args.out)
    print(f"wrote {written[0]}, {written[1]}" + (f" and {written[2]}" if len(written) > 2 else ""))
    return 0 if report.ok else 1
