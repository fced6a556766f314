"""``terrawatt mission``: an adaptive mission in simulation against a battery; prints its budget."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from energy import GROUND_PRESETS
from terrain import InvalidParameterError, UnknownNameError
from terrawatt_base.checks import fmt_number
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M, example_map

from planner.missions.mission_report import check_preset_grounds, simulate_adaptive_mission
from planner.missions.monte_carlo_report import monte_carlo_mission
from .common import (
    add_dask_options,
    add_map_options,
    add_model_options,
    add_point_options,
    apply_landcover,
    check_dask_flags,
    check_model_flags,
    check_outputs,
    check_positive,
    dask_client_arg,
    input_paths,
    load_model_arg,
    point_arg,
    read_map_args,
    warn_figures,
)

__all__ = ["add_parser", "run_mission", "add_monte_carlo_options", "check_monte_carlo_flags", "run_monte_carlo"]

_OUTPUTS = ("mission.json", "mission.png")
_MC_OUTPUTS = ("monte_carlo.json", "monte_carlo.csv", "monte_carlo.png")


def add_parser(sub: Any) -> None:
    """The ``mission`` subcommand."""
    mission = sub.add_parser(
        "mission",
        help="drive a planned route in simulation against a battery, learning current models on the way",
    )
    mission.add_argument("--map", default="example", metavar="FILE", help=".npz map, .tif DEM or 'example' (default)")
    add_map_options(mission)
    add_point_options(mission, "start", "start", required=False, default="; default: the example's")
    add_point_options(mission, "goal", "goal", required=False, default="; default: the example's")
    mission.add_argument("--battery-ah", type=float, required=True, metavar="AH", help="battery capacity (Ah)")
    mission.add_argument("--battery-v", type=float, default=None, metavar="V", help="battery voltage (default: the robot's)")
    mission.add_argument("--reserve-pct", type=float, default=20.0, metavar="P", help="minimum reserve (%%, default 20)")
    mission.add_argument("--robot", default="husky", help="robot preset (default husky)")
    mission.add_argument("--speed", type=float, default=0.5, metavar="M/S", help="driving speed (default 0.5 m/s)")
    mission.add_argument(
        "--prior-ground", default="asphalt",
        help="ground the prior current model was trained on (default asphalt); other grounds are learned on the way",
    )
    mission.add_argument("--leg-m", type=float, default=10.0, metavar="M", help="route driven between comparisons (m)")
    mission.add_argument("--no-adapt", action="store_true", help="drive the first plan without model updates")
    mission.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    mission.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    add_monte_carlo_options(mission)
    add_model_options(mission, risk=True)
    mission.set_defaults(run=run_mission)


def _check_flags(args: argparse.Namespace) -> None:
    for flag, value in (("--battery-ah", args.battery_ah), ("--speed", args.speed), ("--leg-m", args.leg_m)):
        check_positive(flag, value)
    if args.battery_v is not None:
        check_positive("--battery-v", args.battery_v)
    if not 0.0 <= args.reserve_pct < 100.0:
        raise InvalidParameterError(f"--reserve-pct must be in [0, 100), got {fmt_number(args.reserve_pct)}")
    if args.prior_ground not in GROUND_PRESETS:
        raise UnknownNameError(
            f"--prior-ground {args.prior_ground!r} has no preset; known grounds: {sorted(GROUND_PRESETS)!r}"
        )


def run_mission(args: argparse.Namespace) -> int:
    """``terrawatt mission``: adaptive mission in simulation; writes mission.json and mission.png.

    Exit code 0 when the robot reached the goal, 1 when the mission stopped short (budget
    exceeded, reserve crossed, no route).
    """
    _check_flags(args)
    check_monte_carlo_flags(args)
    check_model_flags(args)
    if args.risk is not None and args.monte_carlo is None:
        raise InvalidParameterError("--risk Q of mission checks the route's Q quantile against the usable battery in a "
                                    "--monte-carlo N study; the adaptive mission does not take it yet")
    if args.mc_draw == "model" and args.model is None:
        raise InvalidParameterError("--mc-draw model draws from a saved model's predictive distribution: give --model FILE")
    check_outputs(args.out, _OUTPUTS if args.monte_carlo is None else _MC_OUTPUTS, input_paths(args))
    if args.map == "example":
        tmap, label = apply_landcover(args, example_map()), "bundled example map"
        start = point_arg(args, "start", tmap) or EXAMPLE_START_XY_M
        goal = point_arg(args, "goal", tmap) or EXAMPLE_GOAL_XY_M
    else:
        if (args.start is None and args.start_lonlat is None) or (args.goal is None and args.goal_lonlat is None):
            raise InvalidParameterError("--start and --goal (or --start-lonlat and --goal-lonlat) are required with a "
                                        "map file")
        tmap, label = read_map_args(args), Path(args.map).name
        start, goal = point_arg(args, "start", tmap), point_arg(args, "goal", tmap)
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


# ------------------------------------------------------------------ --monte-carlo N
def add_monte_carlo_options(p: argparse.ArgumentParser) -> None:
    """``--monte-carlo N``, its risk threshold and where its missions run."""
    p.add_argument("--monte-carlo", type=int, default=None, metavar="N",
                   help="instead of one adaptive mission, drive the lattice route N times with drawn ground "
                        "coefficients, payload, capacity fade, internal resistance and speed (seeded by --seed); "
                        "writes monte_carlo.json, .csv and .png")
    p.add_argument("--max-risk-pct", type=float, default=5.0, metavar="P",
                   help="--monte-carlo: exit 1 when more than P %% of the missions go below the reserve (default 5)")
    p.add_argument("--mc-draw", choices=("parameters", "model"), default="parameters",
                   help="--monte-carlo: draw the typed parameter ranges and simulate each mission (default), or draw "
                        "from --model's predictive distribution (one standard-normal factor per ground, each edge at "
                        "mean + z sd)")
    add_dask_options(p, "the --monte-carlo missions")


def check_monte_carlo_flags(args: argparse.Namespace) -> None:
    """The ``--monte-carlo`` flags, checked before any work."""
    if args.monte_carlo is None:
        if args.workers != 1 or args.scheduler is not None:
            raise InvalidParameterError("--workers and --scheduler apply to --monte-carlo N only")
        return
    if args.monte_carlo < 1:
        raise InvalidParameterError(f"--monte-carlo must be a number of missions >= 1, got {args.monte_carlo!r}")
    if not 0.0 <= args.max_risk_pct <= 100.0:
        raise InvalidParameterError(f"--max-risk-pct must be in [0, 100], got {fmt_number(args.max_risk_pct)}")
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
