"""The ``terrawatt`` command line: demo, plan (and the subcommands of later modules)."""

from __future__ import annotations

import argparse
import contextlib
import logging
import math
import os
import sys
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from energy import GROUND_PRESETS, PhysicsEnergyModel, ground_preset, robot_preset
from terrain import (
    UNKNOWN_GROUND,
    InvalidParameterError,
    OptionalDependencyError,
    TerrainMap,
    TerrawattError,
    UnknownNameError,
)
from terrain.atomic import write_json_atomic
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M, example_map

from .edge_cost import EnergyCost, warm_up_kernels
from .ompl_planner import PLANNERS, plan_route, shortest_route
from .plot import RouteLine, plot_routes
from .route import Route

__all__ = ["main", "build_cost", "load_map"]

log = logging.getLogger(__name__)


def _finite_or_none(x: float) -> float | None:
    return x if math.isfinite(x) else None


def load_map(path: str | os.PathLike[str], fill_nodata: str | None = None) -> TerrainMap:
    """Load a ``.npz`` map, or a GeoTIFF DEM (``.tif`` / ``.tiff``, needs the ``geo`` extra;
    ``fill_nodata`` as in :func:`terrain.geotiff.read_geotiff`)."""
    suffix = Path(path).suffix.lower()
    if suffix in (".tif", ".tiff"):
        from terrain.geotiff import read_geotiff

        return read_geotiff(path, fill_nodata=fill_nodata)
    return TerrainMap.load(path)


def _add_map_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--fill-nodata", choices=["nearest"], default=None,
        help="GeoTIFF DEMs: fill nodata cells from the nearest valid cell (default: refuse such DEMs)",
    )


def build_cost(
    tmap: TerrainMap,
    *,
    robot: str = "husky",
    speed_mps: float = 0.5,
    max_slope_deg: float = 20.0,
    unknown_ground: str | None = "gravel",
) -> EnergyCost:
    """Edge costs of the physics model on a map whose ground names are preset names.

    Raises
    ------
    UnknownNameError
        A ground class of the map has no preset of the same name.
    """
    model = PhysicsEnergyModel(robot_preset(robot))
    grounds = {}
    for gid, name in tmap.ground_names.items():
        if name not in GROUND_PRESETS:
            raise UnknownNameError(
                f"ground class {gid} of the map is named {name!r}, which has no preset; "
                f"known grounds: {sorted(GROUND_PRESETS)!r}"
            )
        grounds[gid] = ground_preset(name)
    unknown = ground_preset(unknown_ground) if unknown_ground else None
    return EnergyCost.from_model(
        tmap,
        model,
        grounds,
        speed_mps,
        unknown_ground=unknown,
        max_slope_rad=math.radians(max_slope_deg),
    )


def _route_row(label: str, route: Route, optimum_j: float) -> dict[str, Any]:
    ratio = route.drive_energy_j / optimum_j if route.status == "exact" and optimum_j > 0 else math.nan
    return {
        "route": label,
        "status": route.status,
        "energy_j": route.energy_j if route.found else math.nan,
        "energy_wh": route.energy_wh if route.found else math.nan,
        "charge_mah": route.charge_mah if route.found else math.nan,
        "length_m": route.length_m,
        "duration_s": route.duration_s,
        "ratio_to_lattice_optimum": ratio,
        "planning_time_s": route.planning_time_s,
    }


def _print_table(rows: Sequence[dict[str, Any]]) -> None:
    header = f"{'route':<26} {'status':<11} {'energy J':>10} {'Wh':>7} {'mAh':>8} {'length m':>9} {'time s':>8} {'/ optimum':>9} {'plan s':>7}"
    print(header)
    print("-" * len(header))
    for r in rows:
        print(
            f"{r['route']:<26} {r['status']:<11} {r['energy_j']:>10.1f} {r['energy_wh']:>7.3f} "
            f"{r['charge_mah']:>8.1f} {r['length_m']:>9.1f} {r['duration_s']:>8.1f} "
            f"{r['ratio_to_lattice_optimum']:>9.3f} {r['planning_time_s']:>7.3f}"
        )


def run_plan(
    tmap: TerrainMap,
    start: tuple[float, float],
    goal: tuple[float, float],
    *,
    planner: str,
    time_limit_s: float,
    seed: int,
    out_dir: Path,
    max_evaluations: int | None = None,
    robot: str,
    speed_mps: float,
    max_slope_deg: float,
    unknown_ground: str | None,
    map_label: str,
) -> dict[str, Any]:
    """Plan, compare with the shortest route and the lattice optimum, print, write files."""
    compile_s = warm_up_kernels()  # compiled once per environment, then loaded from numba's cache
    t0 = time.perf_counter()
    cost = build_cost(
        tmap, robot=robot, speed_mps=speed_mps, max_slope_deg=max_slope_deg, unknown_ground=unknown_ground
    )
    prep_s = time.perf_counter() - t0
    route = plan_route(
        tmap, start, goal, cost=cost, planner=planner, seed=seed,
        time_limit_s=None if max_evaluations is not None else time_limit_s, max_cost_evaluations=max_evaluations,
    )
    rows = []
    routes_json: dict[str, Any] = {}
    lines = []
    if route.found:
        shortest = shortest_route(cost, start, goal)
        optimum = plan_route(tmap, start, goal, cost=cost, planner="lattice", seed=seed, compare=False)
        rows.append(_route_row(f"min-energy ({planner})", route, route.lattice_energy_j))
        rows.append(_route_row("lattice + refinement", optimum, route.lattice_energy_j))
        rows.append(_route_row("shortest distance", shortest, route.lattice_energy_j))
        lines = [
            RouteLine(f"min-energy ({planner})", route.waypoints_m, route.energy_j, colour="#d32f2f"),
            RouteLine("shortest distance", shortest.waypoints_m, shortest.energy_j, colour="#1565c0", linestyle="--"),
        ]
        routes_json = {
            "min_energy": {**route.summary(), "waypoints_m": route.waypoints_m.tolist()},
            "lattice": {**optimum.summary(), "waypoints_m": optimum.waypoints_m.tolist()},
            "shortest": {**shortest.summary(), "waypoints_m": shortest.waypoints_m.tolist()},
        }
    print(f"map: {map_label}  {tmap.shape[0]} x {tmap.shape[1]} cells of {tmap.cell_size_m:g} m; grounds {tmap.ground_names}")
    print(
        f"robot: {robot}, speed {speed_mps:g} m/s, max slope {max_slope_deg:g} deg; "
        f"map preparation {prep_s:.2f} s"
    )
    budget = f"{max_evaluations} edge-cost evaluations" if max_evaluations is not None else f"time limit {time_limit_s:g} s"
    n_unknown = int(np.count_nonzero(np.asarray(tmap.ground) == UNKNOWN_GROUND))
    if n_unknown and unknown_ground:
        print(f"ground class unknown in {n_unknown} of {tmap.ground.size} cells: priced as {unknown_ground!r} "
              "(--unknown-ground NAME to choose, 'none' to refuse them)")
    print(f"start {start} -> goal {goal}; planner {planner}, {budget}, seed {seed}")
    if compile_s > 1.0:
        print(f"(compiled the edge-cost kernels in {compile_s:.1f} s: first run in this environment; not in the times below)")
    print()
    if not route.found:
        print(f"no route: status {route.status!r} after {route.planning_time_s:.3f} s")
    else:
        _print_table(rows)
        print()
        if route.status == "exact":
            print(
                f"energy saved vs shortest route: {route.energy_saved_pct:.1f} %  "
                f"(min-energy {route.energy_j:.0f} J vs shortest {route.shortest_energy_j:.0f} J); "
                f"drive energy / 16-connected lattice optimum: {route.optimality_ratio:.3f}"
            )
        else:
            short_m = math.dist(route.waypoints_m[-1], goal)
            print(
                f"the {planner} route is {route.status}: it ends {short_m:.1f} m short of the goal, so it is "
                "not compared with the shortest route; give the planner more time"
            )
    out_dir.mkdir(parents=True, exist_ok=True)
    result = {
        "map": map_label,
        "robot": robot,
        "speed_mps": speed_mps,
        "max_slope_deg": max_slope_deg,
        "start_xy_m": list(start),
        "goal_xy_m": list(goal),
        "planner": planner,
        "time_limit_s": time_limit_s if max_evaluations is None else None,
        "max_evaluations": max_evaluations,
        "seed": seed,
        "map_preparation_s": prep_s,
        "kernel_compile_s": compile_s,
        "status": route.status,
        "energy_saved_pct": _finite_or_none(route.energy_saved_pct) if route.found else None,
        "optimality_ratio": _finite_or_none(route.optimality_ratio) if route.found else None,
        "table": rows,
        "routes": routes_json,
    }
    json_path = write_json_atomic(out_dir / "route.json", result)
    png_path = plot_routes(
        tmap,
        lines,
        start,
        goal,
        out_dir / "route.png",
        title=f"terrawatt: minimum-energy route on {map_label}",
    )
    print(f"\nwrote {json_path} and {png_path}")
    return result


def _add_plan_options(p: argparse.ArgumentParser, *, default_time: float) -> None:
    p.add_argument("--planner", default="RRTstar", choices=PLANNERS, help="planner name (default RRTstar)")
    p.add_argument("--time-limit", type=float, default=default_time, metavar="S", help="planning time budget (s)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument(
        "--max-evaluations", type=int, default=None, metavar="N",
        help="work bound of OMPL planners: stop after N edge-cost evaluations instead of after --time-limit; "
             "with --seed the route is then the same on every run and machine",
    )
    p.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    p.add_argument("--robot", default="husky", help="robot preset: paper_seed, jackal or husky (default husky)")
    p.add_argument("--speed", type=float, default=0.5, metavar="M/S", help="planning speed (default 0.5 m/s)")
    p.add_argument("--max-slope-deg", type=float, default=20.0, help="steepest drivable slope (default 20 deg)")
    p.add_argument(
        "--unknown-ground",
        default="gravel",
        help="ground preset assumed where the map's ground class is unknown (-1); 'none' to refuse such cells",
    )


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``terrawatt`` command."""
    parser = argparse.ArgumentParser(
        prog="terrawatt", description="Energy-aware path planning for ground robots."
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress")
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="plan a minimum-energy route on the bundled example map")
    _add_plan_options(demo, default_time=1.0)
    plan = sub.add_parser("plan", help="plan a minimum-energy route on a map file (.npz or GeoTIFF)")
    plan.add_argument("--map", type=Path, required=True, metavar="FILE", help=".npz map or .tif DEM")
    _add_map_options(plan)
    plan.add_argument("--start", type=float, nargs=2, required=True, metavar=("X", "Y"), help="start (m)")
    plan.add_argument("--goal", type=float, nargs=2, required=True, metavar=("X", "Y"), help="goal (m)")
    _add_plan_options(plan, default_time=2.0)

    evaluate = sub.add_parser(
        "evaluate", help="leave-one-run-out evaluation of current models on BorealTC-layout logs"
    )
    evaluate.add_argument("--data", type=Path, required=True, metavar="DIR", help="directory with GROUND/imu_NN.csv + pro_NN.csv")
    evaluate.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    evaluate.add_argument("--grounds", nargs="+", metavar="NAME", help="ground folders to use (default all)")
    evaluate.add_argument(
        "--model", nargs="+", default=list(CURRENT_MODELS), choices=list(CURRENT_MODELS), dest="models",
        help="models to evaluate (default all)",
    )
    evaluate.add_argument(
        "--variants", nargs="+", default=["per_ground", "ground_agnostic"],
        choices=["per_ground", "ground_agnostic"], help="evaluation variants",
    )
    evaluate.add_argument("--seed", type=int, default=0, help="random seed of the learned models")
    evaluate.add_argument(
        "--workers", type=int, default=1, metavar="N",
        help="run the folds on a local dask cluster of N worker processes (default 1: serially, here; "
        "needs the distributed extra)",
    )
    evaluate.add_argument(
        "--scheduler", metavar="ADDRESS",
        help="run the folds on an existing dask cluster, e.g. tcp://host:8786 (not with --workers > 1)",
    )

    train = sub.add_parser("train", help="fit a current model on logs and save it to one file")
    train.add_argument("--data", type=Path, required=True, metavar="DIR", help="directory with GROUND/imu_NN.csv + pro_NN.csv")
    train.add_argument("--grounds", nargs="+", metavar="NAME", help="ground folders to use (default all)")
    train.add_argument("--model", default="estimator", choices=list(CURRENT_MODELS), help="model kind (default estimator)")
    train.add_argument("--seed", type=int, default=0, help="random seed")
    train.add_argument("--out", type=Path, required=True, metavar="FILE", help="model file to write (e.g. model.pt)")
    train.add_argument(
        "--threads", type=int, metavar="N",
        help="torch threads while training the estimator or paper model (default: torch's own setting)",
    )
    train.add_argument("--quiet", action="store_true", help="no progress bar with the training loss")

    mission = sub.add_parser(
        "mission",
        help="drive a planned route in simulation against a battery, learning current models on the way",
    )
    mission.add_argument("--map", default="example", metavar="FILE", help=".npz map, .tif DEM or 'example' (default)")
    _add_map_options(mission)
    mission.add_argument("--start", type=float, nargs=2, metavar=("X", "Y"), help="start (m); default: the example's")
    mission.add_argument("--goal", type=float, nargs=2, metavar=("X", "Y"), help="goal (m); default: the example's")
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

    predict = sub.add_parser("predict", help="predict drive currents of logs with a saved model")
    predict.add_argument("--model", type=Path, required=True, metavar="FILE", help="model file written by `terrawatt train`")
    predict.add_argument("--data", type=Path, required=True, metavar="DIR", help="directory with GROUND/imu_NN.csv + pro_NN.csv")
    predict.add_argument("--grounds", nargs="+", metavar="NAME", help="ground folders to use (default all)")
    predict.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    predict.add_argument(
        "--plots", action="store_true",
        help="also write one figure per run (measured vs estimated current, moving medians) into DIR/plots/",
    )
    return parser


def _current_model(name: str, seed: int) -> Any:
    from energy import (
        ConstantCurrentModel,
        LinearCurrentModel,
        PhysicsCurrentModel,
        VibrationCurrentEstimator,
    )

    factories = {
        "estimator": lambda: VibrationCurrentEstimator("default", seed=seed),
        "paper": lambda: VibrationCurrentEstimator("paper", seed=seed),
        "linear": LinearCurrentModel,
        "physics": PhysicsCurrentModel,
        "constant": ConstantCurrentModel,
    }
    return factories[name]()


#: Current models selectable on the command line: estimator (improved default), paper
#: (the source network), and the baselines.
CURRENT_MODELS = ("estimator", "paper", "linear", "physics", "constant")


@contextlib.contextmanager
def _dask_client(workers: int, scheduler: str | None, *, quiet: bool = True) -> Iterator[Any]:
    """A ``distributed.Client`` on ``scheduler``, or on a new local cluster of ``workers`` processes.

    Leaving the context closes the client and the local cluster it started. ``quiet``
    keeps dask's INFO messages (cluster start and stop) out of the log meanwhile.

    Raises
    ------
    OptionalDependencyError
        dask.distributed is not installed.
    InvalidParameterError
        No dask scheduler answers at ``scheduler``.
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:
        option = f"--scheduler {scheduler}" if scheduler is not None else f"--workers {workers}"
        raise OptionalDependencyError(
            f"{option} needs dask.distributed; install it with: pip install 'terrawatt[distributed]'"
        ) from exc
    dask_log = logging.getLogger("distributed")  # configured by the import above
    old_level = dask_log.level
    if quiet:
        dask_log.setLevel(max(dask_log.getEffectiveLevel(), logging.WARNING))
    try:
        if scheduler is not None:
            try:
                client = Client(scheduler)
            except (OSError, ValueError) as exc:  # unreachable (a TimeoutError is an OSError) or malformed
                raise InvalidParameterError(
                    f"--scheduler {scheduler!r}: cannot connect to a dask scheduler there ({exc}); "
                    "expected the address of a running scheduler, e.g. tcp://host:8786"
                ) from exc
            with client:
                yield client
        else:
            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True) as cluster, Client(cluster) as client:
                yield client
    finally:
        dask_log.setLevel(old_level)


def run_evaluate(args: argparse.Namespace) -> int:
    """``terrawatt evaluate``: write evaluation.json and evaluation.md."""
    from energy import evaluate_current_models, plot_vibration_spectra, read_borealtc

    if args.workers < 1:
        raise InvalidParameterError(f"--workers must be a positive number of processes, got {args.workers!r}")
    if args.scheduler is not None and args.workers > 1:
        raise InvalidParameterError(
            f"--workers {args.workers!r} and --scheduler {args.scheduler!r} exclude each other: "
            "give --workers N for a local cluster or --scheduler ADDRESS for an existing one"
        )
    with contextlib.ExitStack() as stack:
        client, workers = None, "1 worker (serial)"
        if args.workers > 1 or args.scheduler is not None:  # before reading: a missing extra or scheduler fails fast
            client = stack.enter_context(_dask_client(args.workers, args.scheduler, quiet=not args.verbose))
            where = args.scheduler if args.scheduler is not None else "a local cluster"
            workers = f"{len(client.nthreads())} dask workers ({where})"
            print(f"evaluating on {workers}", flush=True)
        logs = read_borealtc(args.data, grounds=args.grounds)
        models = {name: _current_model(name, args.seed) for name in args.models}
        t0 = time.perf_counter()
        result = evaluate_current_models(logs, models, variants=args.variants, progress=True, client=client)
        elapsed = time.perf_counter() - t0
    args.out.mkdir(parents=True, exist_ok=True)
    json_path = result.write_json(args.out / "evaluation.json")
    md_path = result.write_markdown(args.out / "evaluation.md")
    png_path = plot_vibration_spectra(logs, args.out / "spectra.png")
    print(result.to_markdown())
    print(
        f"\n{len(logs)} runs, {len(models)} models, {elapsed:.1f} s on {workers}; "
        f"wrote {json_path}, {md_path} and {png_path}"
    )
    return 0


def run_train(args: argparse.Namespace) -> int:
    """``terrawatt train``: fit one model on every run found and save it.

    The learned models (``estimator``, ``paper``) show a progress bar with the loss unless
    ``--quiet`` and train on ``--threads`` torch threads; the other models take neither.
    """
    from energy import VibrationCurrentEstimator, read_borealtc

    if args.threads is not None and args.threads < 1:
        raise InvalidParameterError(f"--threads must be a positive number of threads, got {args.threads!r}")
    model = _current_model(args.model, args.seed)
    if isinstance(model, VibrationCurrentEstimator):
        model = VibrationCurrentEstimator(model.config, seed=model.seed, progress=not args.quiet, n_threads=args.threads)
    elif args.threads is not None:
        raise InvalidParameterError(f"--threads applies to the estimator and paper models only, got --model {args.model!r}")
    logs = read_borealtc(args.data, grounds=args.grounds)
    t0 = time.perf_counter()
    model.fit(logs)
    elapsed = time.perf_counter() - t0
    path = model.save(args.out)
    print(f"fitted {args.model} on {len(logs)} runs ({sum(log.duration_s for log in logs):.0f} s of logs) in {elapsed:.1f} s; wrote {path}")
    return 0


def run_mission(args: argparse.Namespace) -> int:
    """``terrawatt mission``: adaptive mission in simulation; writes mission.json and plots."""
    from energy import Battery, TruthSimulator
    from terrain import CellModelRegistry

    from .adaptive import AdaptiveSettings, fit_prior_model, run_adaptive_mission

    if args.map == "example":
        tmap, label = example_map(), "bundled example map"
        start = tuple(args.start) if args.start else EXAMPLE_START_XY_M
        goal = tuple(args.goal) if args.goal else EXAMPLE_GOAL_XY_M
    else:
        if not (args.start and args.goal):
            raise InvalidParameterError("--start and --goal are required with a map file")
        tmap, label = load_map(args.map, args.fill_nodata), Path(args.map).name
        start, goal = tuple(args.start), tuple(args.goal)
    robot = robot_preset(args.robot)
    names = set(tmap.ground_names.values()) | {args.prior_ground}
    unknown = sorted(n for n in names if n not in GROUND_PRESETS)
    if unknown:
        raise UnknownNameError(f"grounds {unknown!r} have no preset; known grounds: {sorted(GROUND_PRESETS)!r}")
    grounds = {name: ground_preset(name) for name in names}
    truth = TruthSimulator(robot, grounds, seed=args.seed)
    battery = Battery(
        capacity_ah=args.battery_ah,
        voltage_v=args.battery_v if args.battery_v is not None else robot.battery_voltage_v,
        min_reserve_pct=args.reserve_pct,
    )
    prior = fit_prior_model(truth, args.prior_ground, seed=args.seed)
    settings = AdaptiveSettings(
        speed_mps=args.speed,
        leg_length_m=args.leg_m,
        max_updates=0 if args.no_adapt else AdaptiveSettings().max_updates,
        seed=args.seed,
    )
    registry = CellModelRegistry.from_terrain(tmap, prior, prior_name=f"{args.prior_ground}-prior")
    t0 = time.perf_counter()
    result = run_adaptive_mission(
        tmap, registry, robot, battery, truth, start, goal,
        physics_ground=grounds[args.prior_ground], settings=settings,
    )
    elapsed = time.perf_counter() - t0
    route0 = result.initial_route
    predicted_wh = result.replans[0].predicted_energy_j / 3600.0  # the stop-turn-go profile, prior models
    used_wh = (result.driven_energy_j + result.excitation_energy_j) / 3600.0
    budget = {
        "battery": {"capacity_ah": battery.capacity_ah, "voltage_v": battery.voltage_v,
                    "min_reserve_pct": battery.min_reserve_pct, "energy_capacity_wh": battery.energy_capacity_wh,
                    "usable_energy_wh": battery.usable_energy_wh},
        "predicted_energy_wh": predicted_wh,
        "edge_cost_energy_wh": route0.energy_wh,
        "predicted_fits": predicted_wh <= battery.usable_energy_wh,
        "actual_energy_wh": used_wh,
        "final_soc_pct": 100.0 * result.final_soc,
        "reserve_margin_pct": 100.0 * result.final_soc - battery.min_reserve_pct,
    }
    data = {**result.to_json_dict(), "budget": budget, "computing_time_s": elapsed}
    json_path = write_json_atomic(args.out / "mission.json", data)
    png_path = result.plot(args.out / "mission.png", tmap, registry)
    print(f"map: {label}; robot {args.robot}; battery {battery.capacity_ah:g} Ah at {battery.voltage_v:g} V "
          f"({battery.energy_capacity_wh:.0f} Wh, {battery.usable_energy_wh:.0f} Wh above the {battery.min_reserve_pct:g} % reserve)")
    print(f"start {start} -> goal {goal}; prior trained on {args.prior_ground}; adaptive updates {'off' if args.no_adapt else 'on'}")
    print(f"status: {result.status} — {result.reason}")
    print(f"first plan (prior models):  {predicted_wh:8.2f} Wh  {route0.length_m:7.1f} m  "
          f"({'fits' if budget['predicted_fits'] else 'does NOT fit'} the usable {battery.usable_energy_wh:.0f} Wh)")
    print(f"driven (actual):            {result.driven_energy_j / 3600:8.2f} Wh  in {len(result.legs)} legs")
    print(f"excitation manoeuvres:      {result.excitation_energy_j / 3600:8.2f} Wh")
    print(f"prediction error before / after updates: {result.error_before_update_pct:.1f} % / {result.error_after_update_pct:.1f} %")
    print(f"updates accepted: {result.accepted_updates} of {len(result.updates)}; route changes {result.route_changes}")
    for line in result.skipped_updates:
        print(f"skipped update {line}")
    print(f"final state of charge {budget['final_soc_pct']:.1f} % (margin {budget['reserve_margin_pct']:+.1f} points "
          f"above the reserve); loop computing {elapsed:.1f} s")
    print(f"wrote {json_path} and {png_path}")
    return 0 if result.status == "completed" else 1


def run_predict(args: argparse.Namespace) -> int:
    """``terrawatt predict``: per-run charge errors of a saved model, written as JSON."""
    from energy import compare_currents, load_current_model, plot_current_estimate, read_borealtc

    model = load_current_model(args.model)
    logs = read_borealtc(args.data, grounds=args.grounds)
    rows = []
    print(f"{'run':<28} {'side':<6} {'truth mAh':>10} {'pred mAh':>10} {'error %':>8} {'RMSE A':>7}")
    plots = []
    for log in logs:
        pred = model.predict(log)
        if args.plots:
            name = f"current_{log.meta.ground_label}_{Path(log.meta.source).stem}.png"
            plots.append(plot_current_estimate(log, pred, args.out / "plots" / name, label=Path(args.model).name))
        for k, side in enumerate(("left", "right")):
            truth = log.current_left_a if k == 0 else log.current_right_a
            err = compare_currents(log.time_s, truth, pred[:, k])
            row = {
                "run": log.meta.source,
                "ground": log.meta.ground_label,
                "side": side,
                "charge_true_mah": err.charge_true_mah,
                "charge_predicted_mah": err.charge_predicted_mah,
                "whole_run_error_pct": err.whole_run_error_pct,
                "section_error_pct": err.section_error_pct,
                "rmse_a": err.rmse_a,
            }
            rows.append(row)
            print(
                f"{str(log.meta.ground_label) + '/' + Path(log.meta.source).name:<28} {side:<6} {err.charge_true_mah:>10.1f} "
                f"{err.charge_predicted_mah:>10.1f} {err.whole_run_error_pct:>8.2f} {err.rmse_a:>7.2f}"
            )
    path = write_json_atomic(args.out / "predictions.json", {"model": str(args.model), "runs": rows})
    print(f"wrote {path}" + (f" and {len(plots)} figures in {args.out / 'plots'}" if plots else ""))
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``terrawatt`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    try:
        if args.command == "evaluate":
            return run_evaluate(args)
        if args.command == "train":
            return run_train(args)
        if args.command == "predict":
            return run_predict(args)
        if args.command == "mission":
            return run_mission(args)
        unknown = None if args.unknown_ground.lower() == "none" else args.unknown_ground
        if args.command == "demo":
            tmap, start, goal, label = example_map(), EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M, "bundled example map"
        else:
            tmap, start, goal, label = (load_map(args.map, args.fill_nodata), tuple(args.start), tuple(args.goal),
                                        args.map.name)
        result = run_plan(
            tmap,
            start,
            goal,
            planner=args.planner,
            time_limit_s=args.time_limit,
            max_evaluations=args.max_evaluations,
            seed=args.seed,
            out_dir=args.out,
            robot=args.robot,
            speed_mps=args.speed,
            max_slope_deg=args.max_slope_deg,
            unknown_ground=unknown,
            map_label=label,
        )
    except TerrawattError as exc:
        print(f"terrawatt: error: {exc}", file=sys.stderr)
        return 2
    return 0 if result["status"] == "exact" else 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
