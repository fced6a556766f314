"""``terrawatt mission``: an adaptive mission in simulation against a battery; prints its budget."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import time
from pathlib import Path
from typing import Any

from energy import GROUND_PRESETS, Battery, TruthSimulator, ground_preset, robot_preset
from terrain import CellModelRegistry, InvalidParameterError, UnknownNameError
from terrawatt_base.atomic import write_json_atomic
from terrawatt_base.checks import fmt_number
from terrawatt_base.dask_client import dask_client
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M, example_map

from planner.edge_cost import DEFAULT_MAX_SLOPE_RAD
from planner.missions import AdaptiveSettings, fit_prior_model, run_adaptive_mission, simulate_missions_mc
from planner.model_cost import model_energy_model
from planner.planning import plan_route
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
    draw_figure,
    edge_cost_for,
    input_paths,
    load_model_arg,
    point_arg,
    read_map_args,
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
    unknown = sorted(n for n in set(tmap.ground_names.values()) if n not in GROUND_PRESETS)
    if unknown:
        raise UnknownNameError(f"the map's grounds {unknown!r} have no preset; known grounds: {sorted(GROUND_PRESETS)!r}")
    if args.monte_carlo is not None:
        return run_monte_carlo(args, tmap, label, start, goal)
    robot = robot_preset(args.robot)
    names = set(tmap.ground_names.values()) | {args.prior_ground}
    grounds = {name: ground_preset(name) for name in names}
    truth = TruthSimulator(robot, grounds, seed=args.seed)
    battery = Battery(
        capacity_ah=args.battery_ah,
        voltage_v=args.battery_v if args.battery_v is not None else robot.battery_voltage_v,
        min_reserve_pct=args.reserve_pct,
    )
    model = load_model_arg(args)
    settings = AdaptiveSettings(
        speed_mps=args.speed,
        leg_length_m=args.leg_m,
        max_updates=0 if args.no_adapt else AdaptiveSettings().max_updates,
        seed=args.seed,
    )
    learned = None
    if model is not None:  # the saved model serves every ground class it drove (one model id each)
        learned, _ = model_energy_model(tmap, model, robot, model_ground=args.model_ground,
                                        physics_ground=grounds[args.prior_ground])
        registry = learned.registry
    else:
        prior = fit_prior_model(truth, args.prior_ground, seed=args.seed)
        registry = CellModelRegistry.from_terrain(tmap, prior, prior_name=f"{args.prior_ground}-prior")
    t0 = time.perf_counter()
    result = run_adaptive_mission(
        tmap, registry, robot, battery, truth, start, goal,
        physics_ground=grounds[args.prior_ground], settings=settings, learned=learned,
    )
    elapsed = time.perf_counter() - t0
    json_path = write_json_atomic(args.out / "mission.json", {**result.to_json_dict(), "computing_time_s": elapsed})
    png_path = draw_figure(args.out / "mission.png", lambda: result.plot(args.out / "mission.png", tmap, registry))
    _print_summary(args, result, battery, label, start, goal, elapsed)
    print(f"wrote {json_path}" + (f" and {png_path}" if png_path is not None else ""))
    return 0 if result.status == "completed" else 1


def _percent(value: float) -> str:
    return "n/a" if value != value else f"{value:.1f} %"  # NaN: nothing to compare


def _print_summary(args: argparse.Namespace, result: Any, battery: Battery, label: str, start: tuple, goal: tuple,
                   elapsed: float) -> None:
    budget = result.budget
    route0 = result.initial_route
    print(f"map: {label}; robot {args.robot}; battery {battery.capacity_ah:g} Ah at {battery.voltage_v:g} V "
          f"({battery.energy_capacity_wh:.0f} Wh, {battery.usable_energy_wh:.0f} Wh above the "
          f"{battery.min_reserve_pct:g} % reserve)")
    print(f"start {start} -> goal {goal}; prior trained on {args.prior_ground}; "
          f"adaptive updates {'off' if args.no_adapt else 'on'}")
    print(f"status: {result.status} — {result.reason}")
    print(f"first plan (prior models):  {budget.predicted_energy_wh:8.2f} Wh  {route0.length_m:7.1f} m  "
          f"({'fits' if budget.predicted_feasible else 'does NOT fit'} the usable {battery.usable_energy_wh:.0f} Wh)")
    print(f"driven (actual):            {result.driven_energy_j / 3600:8.2f} Wh  in {len(result.legs)} legs")
    print(f"excitation manoeuvres:      {result.excitation_energy_j / 3600:8.2f} Wh")
    print(f"prediction error before / after updates: {_percent(result.error_before_update_pct)} / "
          f"{_percent(result.error_after_update_pct)}")
    print(f"updates accepted: {result.accepted_updates} of {len(result.updates)}; route changes {result.route_changes}")
    for line in result.skipped_updates:
        print(f"skipped update {line}")
    if budget.depleted:
        print(f"the battery ran out {budget.depleted_time_s:.1f} s into the mission")
    print(f"final state of charge {budget.arrival_soc_pct:.1f} % (margin {budget.reserve_margin_pct:+.1f} points "
          f"above the reserve); loop computing {elapsed:.1f} s")


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
    robot = robot_preset(args.robot)
    battery = Battery(capacity_ah=args.battery_ah,
                      voltage_v=args.battery_v if args.battery_v is not None else robot.battery_voltage_v,
                      min_reserve_pct=args.reserve_pct)
    model = load_model_arg(args)
    cost = edge_cost_for(tmap, robot=args.robot, speed_mps=args.speed, max_slope_rad=DEFAULT_MAX_SLOPE_RAD,
                         unknown_ground=None, model=model, model_ground=getattr(args, "model_ground", None))
    if (args.risk is not None or args.mc_draw == "model") and not cost.has_interval:
        raise InvalidParameterError(f"--risk and --mc-draw model need a model with a predictive interval; "
                                    f"{args.model.name} gives none")
    route = plan_route(tmap, start, goal, cost=cost, planner="lattice", seed=args.seed)
    print(f"map: {label}; robot {args.robot}; battery {battery.capacity_ah:g} Ah at {battery.voltage_v:g} V, "
          f"reserve {battery.min_reserve_pct:g} %")
    if not route.found:
        print(f"no route from {start} to {goal}: status {route.status!r}")
        return 1
    print(f"route: {route.length_m:.1f} m, planned {route.energy_wh:.2f} Wh; {args.monte_carlo} missions", flush=True)
    with contextlib.ExitStack() as stack:
        client = None
        if args.workers > 1 or args.scheduler is not None:
            client = stack.enter_context(dask_client(args.workers, args.scheduler, quiet=not args.verbose,
                                                     flags=("--workers", "--scheduler")))
        result = simulate_missions_mc(tmap, route, battery, args.monte_carlo, robot=robot, speed_mps=args.speed,
                                      seed=args.seed, client=client, progress=True, cost=cost,
                                      draw_from=args.mc_draw)
        if client is not None:  # where it ran, as the user named it
            result = dataclasses.replace(result, where=args.scheduler or "local cluster")
    json_path = result.write_json(args.out / "monte_carlo.json")
    csv_path = result.to_csv(args.out / "monte_carlo.csv")
    png_path = draw_figure(args.out / "monte_carlo.png", lambda: result.plot(args.out / "monte_carlo.png"))
    print(result.summary())
    fits = True
    if args.risk is not None:  # the reserve check on the forecast's quantile
        need_j = result.forecast.quantile_j(args.risk)
        fits = need_j <= battery.usable_energy_wh * 3600.0
        print(f"reserve check at Q = {args.risk:g}: the route's {args.risk:g} quantile {need_j / 3600:.2f} Wh "
              f"{'fits' if fits else 'does NOT fit'} the usable {battery.usable_energy_wh:.2f} Wh")
    print(f"wrote {json_path}, {csv_path}" + (f" and {png_path}" if png_path is not None else ""))
    return 0 if 100.0 * result.p_below_reserve <= args.max_risk_pct and fits and not result.n_failed else 1
