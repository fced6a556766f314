"""Options and checks the ``terrawatt`` subcommands share: map reading, points, outputs, flags, dask, models."""

from __future__ import annotations

import argparse
import contextlib
import math
import re
import sys
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from energy import GROUND_PRESETS, Battery, CurrentModel, load_current_model
from energy.params import resolve_unknown_ground, robot_params
from planner.cost_spec import CostSpec
from planner.missions.mission_report import mission_battery
from planner.model_cost import parse_model_ground
from planner.planning import RouteSearch
from planner.points import point_on_map
from planner.tables import check_planning_risk
from terrain import DemWindows, FigureWarning, InvalidParameterError, TerrainMap, TerrawattWarning
from terrain.io import read_map_with_options
from terrain.procedural import example_map
from terrawatt_base.atomic import check_output_path, probe_writable, refuse_overwriting_inputs
from terrawatt_base.checks import fmt_number
from terrawatt_base.dask_client import Compute, check_dask_options, dask_client

__all__ = [
    "pricing_arg", "flag_text", "POINT_FLAGS", "COMMON_FLAGS", "flagged_warnings",
    "Checked", "bounded", "positive", "add_battery_options", "battery_arg", "MAP_FLAGS", "add_map_options", "read_map_args", "map_arg", "add_point_options",
    "point_arg", "add_robot_options", "add_physics_robot_option", "robot_arg", "add_planner_options", "SEARCH_FLAGS", "search_arg",
    "check_outputs",
    "INPUT_FLAGS", "input_paths",
    "check_output_file", "warn_figures", "add_dask_options", "check_dask_flags", "compute_arg",
    "add_model_options", "check_model_flags", "load_model_arg",
]

#: The flags of the map options, by their names in :func:`terrain.io.read_map_with_options`.
MAP_FLAGS = {"fill_nodata": "--fill-nodata", "reproject_to": "--reproject", "cell_size_m": "--cell-size",
             "landcover": "--landcover", "landcover_classes": "--landcover-classes"}
#: The flags of the points of :func:`add_point_options`, by the names :func:`point_arg` gives them.
POINT_FLAGS = {key: f"--{flag}" for name in ("start", "goal", "depot")
               for key, flag in ((name, name), (f"{name}_lonlat", f"{name}-lonlat"))}
#: The library's parameters a message may name, and the flags that set them, in every command (a library error names
#: the parameter, :attr:`terrain.TerrawattError.parameter`; the command line says it by its flag): with the log
#: readers' (:data:`terrawatt_cli.data.DATA_FLAGS`), :data:`terrawatt_cli.PARAMETER_FLAGS`. A command adds its own
#: (``set_defaults(flag_names=...)``).
COMMON_FLAGS = {"risk": "--risk", "draw_from": "--mc-draw", "workers": "--workers", "scheduler": "--scheduler",
                "model_ground": "--model-ground", "unknown_ground": "--unknown-ground", "robot": "--robot",
                "band_hz": "--band", **MAP_FLAGS, **POINT_FLAGS}
#: Flags whose values are input paths (a ``--model`` that names a kind, a ``--map example``, are not files).
INPUT_FLAGS = ("map", "data", "pairs", "sites", "chargers", "model", "calibration_data", "landcover", "landcover_classes", "robot")


class Checked(argparse.Action):
    """Store ``check(value, flag)``: a bad value fails while parsing, one line naming the flag, exit 2."""

    def __init__(self, option_strings: list[str], dest: str, check: Callable[[Any, str], Any], **kwargs: Any) -> None:
        super().__init__(option_strings, dest, **kwargs)
        self.check = check

    def __call__(self, parser: Any, namespace: argparse.Namespace, values: Any, option_string: Any = None) -> None:
        setattr(namespace, self.dest, self.check(values, option_string or self.option_strings[0]))  # the flag typed


def bounded(expected: str, ok: Callable[[float], bool]) -> Callable[[float, str], float]:
    """A :class:`Checked` check: the value if ``ok(value)``, else "FLAG must be ``expected``, got VALUE"."""
    def check(value: float, flag: str) -> float:
        if not ok(value):
            raise InvalidParameterError(f"{flag} must be {expected}, got {fmt_number(value)}")
        return value
    return check


positive = bounded("a number > 0", lambda v: math.isfinite(v) and v > 0)


def add_map_options(p: argparse.ArgumentParser, *, reproject: bool = True) -> None:
    """The map options of :data:`MAP_FLAGS` (read by :func:`read_map_args`); without ``--reproject`` / ``--cell-size``
    if not ``reproject``."""
    p.add_argument("--fill-nodata", choices=["nearest"], default=None,
                   help="GeoTIFF DEMs: fill nodata cells from the nearest valid cell (default: refuse such DEMs)")
    if reproject:
        p.add_argument("--reproject", default=None, metavar="utm|EPSG:N",
                       help="GeoTIFF DEMs: reproject to the UTM zone of the DEM's centre ('utm') or to a projected CRS "
                            "in metres (e.g. EPSG:32633), as DEMs in geographic coordinates (EPSG:4326) need; with "
                            "--cell-size")
        p.add_argument("--cell-size", type=float, default=None, metavar="M",
                       help="cell size (m) of the reprojected map; with --reproject")
    p.add_argument("--landcover", type=Path, default=None, metavar="FILE",
                   help="ground classes from a land-cover GeoTIFF of integer codes (e.g. ESA WorldCover), in any CRS, "
                        "warped onto a map with a CRS by majority; with --landcover-classes")
    p.add_argument("--landcover-classes", type=Path, default=None, metavar="CSV",
                   help="CSV 'code,ground' (optional 'label' column) naming each code's ground preset, or 'obstacle' "
                        "(impassable) or 'unknown'; codes left out and nodata are unknown ground (--unknown-ground)")


def read_map_args(args: argparse.Namespace, source: Any = None) -> TerrainMap:
    """The map of ``--map`` (or ``source``, a map in memory) with its options (:func:`terrain.io.read_map_with_options`;
    the classes' grounds must be presets unless ``--model`` prices them)."""
    whole = source is None
    with flagged_warnings(COMMON_FLAGS):
        return read_map_with_options(
            args.map if whole else source, fill_nodata=args.fill_nodata if whole else None,
            reproject_to=getattr(args, "reproject", None) if whole else None,
            cell_size_m=getattr(args, "cell_size", None) if whole else None,
            landcover=getattr(args, "landcover", None), landcover_classes=getattr(args, "landcover_classes", None),
            known_grounds=GROUND_PRESETS if getattr(args, "model", None) is None else None)


def map_arg(args: argparse.Namespace) -> tuple[TerrainMap, str]:
    """The map of ``--map`` (the bundled one for ``example`` or without ``--map``) and how to name it."""
    if args.map is None or str(args.map) == "example":
        return read_map_args(args, example_map()), "bundled example map"
    return read_map_args(args), Path(args.map).name


def add_point_options(p: argparse.ArgumentParser, name: str, what: str, *, required: bool, default: str = "") -> None:
    """``--NAME X Y`` (the map's metres) or ``--NAME-lonlat LON LAT`` (WGS 84 degrees), one of them (:func:`point_arg`)."""
    group = p.add_mutually_exclusive_group(required=required)
    group.add_argument(f"--{name}", type=float, nargs=2, metavar=("X", "Y"), help=f"{what} (m){default}")
    group.add_argument(f"--{name}-lonlat", type=float, nargs=2, metavar=("LON", "LAT"),
                       help=f"{what} as WGS 84 longitude and latitude (degrees), placed on the map by its CRS; "
                            f"instead of --{name}")


def point_arg(args: argparse.Namespace, name: str, where: TerrainMap | DemWindows) -> tuple[float, float] | None:
    """The point of :func:`add_point_options` in the map's metres (:func:`planner.points.point_on_map`), or None."""
    return point_on_map(getattr(args, name, None), getattr(args, f"{name}_lonlat", None), where,
                        names=(name, f"{name}_lonlat"))  # said by their flags (POINT_FLAGS)


def flag_text(text: str, parameter: str | Sequence[str] | None, flags: Mapping[str, str]) -> str:
    """``text`` with the library parameters ``parameter`` names said by their ``flags``: the one place the command
    line renames the library's words (:func:`terrawatt_cli.error_message`, a diagnosis' model note).

    A parameter the text quotes in backticks (```model```) is replaced there only: the text marked which words
    are the parameter; one it does not quote is replaced wherever it stands as a whole word. A parameter without
    a flag is left as it is.

    Examples
    --------
    >>> flag_text("give start or start_lonlat, not both", ("start", "start_lonlat"), POINT_FLAGS)
    'give --start or --start-lonlat, not both'
    >>> flag_text("`model` prices the map like a model", "model", {"model": "--model"})
    '--model prices the map like a model'
    """
    for name in (parameter,) if isinstance(parameter, str) else (parameter or ()):
        flag, marked = flags.get(name), f"`{name}`"
        if marked in text:
            text = text.replace(marked, flag or marked)
        elif flag is not None:
            text = re.sub(rf"(?<![\w-]){re.escape(name)}(?![\w-])", flag, text)
    return text


@contextlib.contextmanager
def flagged_warnings(flags: Mapping[str, str]) -> Iterator[None]:
    """The library's warnings of the block issued again at its end, the parameters they name
    (:attr:`terrain.TerrawattWarning.parameter`) said by their ``flags`` (:func:`flag_text`); others as they were."""
    caught: list[warnings.WarningMessage] = []
    try:
        with warnings.catch_warnings(record=True) as log:
            warnings.simplefilter("always")
            caught = log
            yield
    finally:  # an error in the block too: its warnings are still said
        for w in caught:
            message = w.message
            if isinstance(message, TerrawattWarning) and message.parameter:
                message = type(message)(flag_text(str(message), message.parameter, flags))
            warnings.warn_explicit(message, w.category, w.filename, w.lineno)


def add_battery_options(p: argparse.ArgumentParser, capacity: str = "battery capacity (Ah)", *,
                        required: bool = True) -> None:
    """``--battery-ah`` (``required``), ``--voltage`` / ``--battery-v`` and ``--reserve`` / ``--reserve-pct`` (default
    20 %): :func:`battery_arg` reads them."""
    p.add_argument("--battery-ah", type=float, required=required, default=None, metavar="AH", action=Checked,
                   check=positive, help=capacity)
    p.add_argument("--voltage", "--battery-v", dest="voltage", type=float, default=None, metavar="V", action=Checked,
                   check=positive, help="battery voltage (default: the robot's)")
    p.add_argument("--reserve", "--reserve-pct", dest="reserve", type=float, default=20.0, metavar="PCT",
                   action=Checked, check=bounded("a percentage in [0, 100)", lambda v: 0.0 <= v < 100.0),
                   help="share of the battery kept in reserve (%%, in [0, 100), default 20)")


def battery_arg(args: argparse.Namespace, robot: Any) -> Battery | None:
    """The :class:`energy.Battery` of ``--battery-ah``, ``--voltage`` (default ``robot``'s) and ``--reserve``; None
    without ``--battery-ah`` (where it is not required)."""
    if args.battery_ah is None:
        return None
    return mission_battery(robot, args.battery_ah, args.voltage, args.reserve)


def add_robot_options(p: argparse.ArgumentParser, *, speed: str = "planning speed", slope: bool = True) -> None:
    """``--robot``, ``--speed``, ``--out`` and (with ``slope``) ``--max-slope-deg`` and ``--unknown-ground``."""
    p.add_argument("--robot", default="husky", metavar="NAME|FILE.json", action=Checked, check=robot_arg,
                   help="robot preset: paper_seed, jackal or husky (default husky), or a robot file of your robot's "
                        "parameters (energy.params.write_robot_file writes a preset's, to edit)")
    p.add_argument("--speed", type=float, default=0.5, action=Checked, check=positive, metavar="M/S",
                   help=f"{speed} (default 0.5 m/s)")
    p.add_argument("--out", type=Path, default=Path("out"), metavar="DIR", help="output directory (default out/)")
    if slope:
        p.add_argument("--max-slope-deg", type=float, default=20.0, action=Checked,
                       check=bounded("between 0 and 90 degrees (exclusive)", lambda v: 0.0 < v < 90.0),
                       help="steepest drivable slope (default 20 deg)")
        p.add_argument("--unknown-ground", default="gravel",
                       help="ground preset assumed where the map's ground class is unknown (-1); 'none' to refuse "
                            "such cells")


def add_physics_robot_option(p: argparse.ArgumentParser) -> None:
    """``--robot`` of the commands that fit current models: the physics model's robot."""
    p.add_argument("--robot", default=None, metavar="NAME|FILE.json", action=Checked, check=robot_arg,
                   help="the physics model's robot: a preset (husky, the default; jackal; paper_seed) or a robot file")


def robot_arg(value: str, flag: str) -> str:
    """A :class:`Checked` check of ``--robot``: a preset name or a robot file that reads (:func:`energy.params.robot_params`)."""
    robot_params(value, name=flag)
    return value


def add_planner_options(p: argparse.ArgumentParser, *, planner: str, time_s: float, choices: Iterable[str]) -> None:
    """``--planner``, ``--time-limit``, ``--max-evaluations`` and ``--seed``."""
    p.add_argument("--planner", default=planner, choices=list(choices), help=f"planner name (default {planner})")
    p.add_argument("--time-limit", type=float, default=time_s, action=Checked, check=positive, metavar="S",
                   help="OMPL planners: planning time budget (s; per pair in a batch)")
    p.add_argument("--max-evaluations", type=int, default=None, action=Checked, check=positive, metavar="N",
                   help="work bound of OMPL planners: stop after N edge-cost evaluations instead of after "
                        "--time-limit; with --seed the route is then the same on every run, machine and worker")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")


#: The flag of each :class:`planner.planning.RouteSearch` parameter (:func:`search_arg`).
SEARCH_FLAGS = {"planner": "--planner", "time_limit_s": "--time-limit", "max_cost_evaluations": "--max-evaluations",
                "seed": "--seed"}


def search_arg(args: argparse.Namespace) -> RouteSearch:
    """The :class:`planner.planning.RouteSearch` of :func:`add_planner_options`' flags: ``--max-evaluations``,
    when given, replaces ``--time-limit`` (the route is then the same on every run)."""
    return RouteSearch(args.planner, None if args.max_evaluations is not None else args.time_limit,
                       args.max_evaluations, seed=args.seed)


def check_outputs(directory: Path, files: Iterable[str] = (), inputs: Iterable[Path | None] = ()) -> None:
    """Before any work: ``directory`` is a writable folder (created; a probe file written and removed), each of
    ``files`` a file in it, none an input nor replacing one (``inputs``: the command's input paths, None for a flag
    not given)."""
    names = list(files)
    check_output_path(directory, "--out", directory=True)
    for name in names:
        check_output_path(directory / name, f"--out {directory}: {name}")
    refuse_overwriting_inputs([directory, *(directory / n for n in names)], list(inputs), "--out")
    probe_writable(directory, "--out")


def input_paths(args: argparse.Namespace) -> list[Path]:
    """The input paths a command was given (the flags of :data:`INPUT_FLAGS` that name existing files or folders)."""
    values = (getattr(args, flag, None) for flag in INPUT_FLAGS)
    return [Path(v) for v in values if v is not None and v != "example" and Path(v).exists()]


def check_output_file(path: Path, inputs: Iterable[Path | None] = (), flag: str = "--out") -> None:
    """Before any work: ``path`` can be written as a file, is none of the inputs, and its folder is writable."""
    check_output_path(path, flag)
    refuse_overwriting_inputs([path], list(inputs), flag)
    probe_writable(path.parent if str(path.parent) else Path("."), flag)


@contextlib.contextmanager
def warn_figures() -> Iterator[None]:
    """A figure that fails inside (a :class:`~terrain.FigureWarning`) is one line on stderr."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", FigureWarning)
        yield
    for w in caught:
        if issubclass(w.category, FigureWarning):
            print(f"terrawatt: warning: {w.message}", file=sys.stderr)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


def add_dask_options(p: argparse.ArgumentParser, what: str) -> None:
    """``--workers N`` / ``--scheduler ADDRESS``: run ``what`` on a local dask cluster or an existing one."""
    p.add_argument("--workers", type=int, default=1, metavar="N",
                   help=f"run {what} on a local dask cluster of N worker processes (default 1: here, one after "
                   "another; needs the distributed extra)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help=f"run {what} on an existing dask cluster, e.g. tcp://host:8786 (not with --workers > 1)")


def check_dask_flags(args: argparse.Namespace) -> None:
    """``--workers`` and ``--scheduler``, checked before any work (``dask_client.check_dask_options``)."""
    check_dask_options(args.workers, args.scheduler)


@contextlib.contextmanager
def compute_arg(args: argparse.Namespace, *, progress: bool) -> Iterator[Compute]:
    """Where ``--workers N`` / ``--scheduler ADDRESS`` say the tasks run, as a :class:`Compute`: the cluster opened
    here, before any work, so a missing extra or an unreachable scheduler fails fast (closed on leaving); ``-v``
    keeps dask's log."""
    if args.workers == 1 and args.scheduler is None:
        yield Compute(progress=progress)
        return
    with dask_client(args.workers, args.scheduler, quiet=not args.verbose) as client:
        yield Compute(client=client, where=args.scheduler or "local cluster", progress=progress)


def add_model_options(p: argparse.ArgumentParser, *, risk: bool = False) -> None:
    """``--model FILE`` and ``--model-ground NAME`` (and, with ``risk``, ``--risk Q``): edge costs from a saved model."""
    p.add_argument("--model", type=Path, default=None, metavar="FILE",
                   help="price the edges with a saved current model (terrawatt train) instead of the physics presets: "
                        "one per ground class of the map, which the model must have driven, on the robot of --robot "
                        "(the physics model adds the slope term); --unknown-ground does not apply")
    p.add_argument("--model-ground", default=None, nargs="+", metavar="NAME|CLASS=NAME", action=Checked,
                   check=parse_model_ground,
                   help="with --model: NAME prices every cell as this training ground of the model (e.g. a map without "
                        "classes); CLASS=NAME pairs price a map class the model never drove as one it did (e.g. "
                        "grass=asphalt), the other classes by their own names")
    if risk:
        p.add_argument("--risk", type=float, default=None, metavar="Q", action=Checked, check=check_planning_risk,
                       help="with --model of a model with a predictive interval: plan on the Q quantile of energy (Q "
                            "in [0.5, 1)), every edge at mean + z_Q sd: the route's Q quantile on one ground, for Q > "
                            "0.5 an upper bound of it across grounds; default: the mean")


def check_model_flags(args: argparse.Namespace) -> None:
    """``--model-ground`` and ``--risk`` need ``--model``, whose file must exist; checked before any work."""
    if args.model is not None and not Path(args.model).is_file():
        raise InvalidParameterError(f"--model {args.model} is not a file (write one with terrawatt train)")
    for flag, value in (("--model-ground", args.model_ground), ("--risk", getattr(args, "risk", None))):
        if args.model is None and value is not None:
            raise InvalidParameterError(f"{flag} needs --model FILE (a saved current model; the physics presets "
                                        "have no training grounds nor an interval)")


def pricing_arg(args: argparse.Namespace, terrain: TerrainMap | None, model: CurrentModel | None = None) -> CostSpec:
    """The :class:`planner.CostSpec` of the command's flags: ``--robot``, ``--speed``, ``--max-slope-deg``,
    ``--unknown-ground`` (not with a model), ``--model`` (loaded: ``model``), ``--model-ground``, ``--risk``; a flag
    the command does not have takes the spec's default (``--unknown-ground``: none, refusing such cells)."""
    ground = None
    if model is None and getattr(args, "unknown_ground", None) is not None:
        ground = resolve_unknown_ground(args.unknown_ground, terrain)
    return CostSpec(robot=args.robot, speed_mps=args.speed, max_slope_deg=getattr(args, "max_slope_deg", 20.0),
                    unknown_ground=ground, model=model, model_label=None if model is None else Path(args.model).name,
                    model_ground=getattr(args, "model_ground", None), risk=getattr(args, "risk", None))


def load_model_arg(args: argparse.Namespace) -> CurrentModel | None:
    """The model of ``--model`` (:func:`energy.load_current_model`), or None without the flag."""
    return None if args.model is None else load_current_model(args.model)
