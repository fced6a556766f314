"""Options and checks the ``terrawatt`` subcommands share: map reading, output paths, flags."""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import sys
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from energy import GROUND_PRESETS, CurrentModel, load_current_model
from terrain import (
    UNKNOWN_GROUND,
    DemWindows,
    FigureWarning,
    InvalidParameterError,
    NodataError,
    TerrainMap,
    UnknownNameError,
)
from terrawatt_base import figure_file
from terrawatt_base.atomic import check_output_path, probe_writable, refuse_overwriting_inputs
from terrawatt_base.checks import fmt_number
from terrawatt_base.dask_client import dask_client
from terrain.landcover import LandcoverClasses, ground_classes_from_landcover, read_landcover_classes

from planner.points import lonlat_points
from planner.risk import check_risk_level

__all__ = [
    "add_map_options",
    "read_map_file",
    "read_map_args",
    "landcover_classes_arg",
    "apply_landcover",
    "add_point_options",
    "point_arg",
    "check_outputs",
    "check_positive",
    "max_slope_rad",
    "unknown_ground",
    "check_grounds",
    "draw_figure",
    "warn_figures",
    "add_dask_options",
    "check_dask_flags",
    "dask_client_arg",
    "add_model_options",
    "check_model_flags",
    "load_model_arg",
]


def add_map_options(p: argparse.ArgumentParser, *, reproject: bool = True) -> None:
    """``--fill-nodata``, ``--reproject``, ``--cell-size``, ``--landcover`` and ``--landcover-classes`` (read them
    with :func:`read_map_args`); ``reproject=False`` offers no ``--reproject`` / ``--cell-size``."""
    p.add_argument(
        "--fill-nodata", choices=["nearest"], default=None,
        help="GeoTIFF DEMs: fill nodata cells from the nearest valid cell (default: refuse such DEMs)",
    )
    if reproject:
        p.add_argument(
            "--reproject", default=None, metavar="utm|EPSG:N",
            help="GeoTIFF DEMs: reproject to the UTM zone of the DEM's centre ('utm') or to a projected CRS in "
                 "metres (e.g. EPSG:32633); needed for DEMs in geographic coordinates (EPSG:4326); with --cell-size",
        )
        p.add_argument("--cell-size", type=float, default=None, metavar="M",
                       help="cell size (m) of the reprojected map; with --reproject")
    p.add_argument(
        "--landcover", type=Path, default=None, metavar="FILE",
        help="ground classes from a land-cover GeoTIFF of integer codes (e.g. ESA WorldCover), in any CRS, warped "
             "onto a map with a CRS by majority; with --landcover-classes",
    )
    p.add_argument(
        "--landcover-classes", type=Path, default=None, metavar="CSV",
        help="with --landcover: CSV 'code,ground' (optional 'label' column) naming each code's ground preset, or "
             "'obstacle' (impassable) or 'unknown'; codes left out and nodata keep unknown ground (--unknown-ground)",
    )


def read_map_file(
    path: str | os.PathLike[str],
    fill_nodata: str | None,
    reproject: str | None = None,
    cell_size: float | None = None,
) -> TerrainMap:
    """:func:`terrain.read_map`, its advice phrased with the CLI's ``--fill-nodata nearest``,
    ``--reproject`` and ``--cell-size``."""
    from terrain import read_map

    if (reproject is None) != (cell_size is None):
        raise InvalidParameterError(
            "--reproject and --cell-size go together: e.g. --reproject utm --cell-size 5 "
            f"(got --reproject {reproject}, --cell-size {cell_size})"
        )
    if cell_size is not None:
        check_positive("--cell-size", cell_size)
    try:
        return read_map(path, fill_nodata=fill_nodata, reproject_to=reproject, cell_size_m=cell_size)
    except NodataError as exc:
        raise NodataError(
            f"{Path(path).name} has {exc.n_nodata} nodata cells of {exc.n_cells}; give "
            "--fill-nodata nearest to fill them from the nearest valid cell",
            n_nodata=exc.n_nodata,
            n_cells=exc.n_cells,
        ) from exc
    except InvalidParameterError as exc:
        text = str(exc)
        if reproject is None or not text.startswith(("reproject_to", "cell_size_m")):
            raise
        raise InvalidParameterError(text.replace("reproject_to", "--reproject").replace("cell_size_m", "--cell-size")
                                    ) from exc


def read_map_args(args: argparse.Namespace) -> TerrainMap:
    """The map of a command's ``--map``, ``--fill-nodata``, (if offered) ``--reproject`` / ``--cell-size`` and
    ``--landcover`` / ``--landcover-classes`` (the classes file is read and checked before the map)."""
    classes = landcover_classes_arg(args)
    tmap = read_map_file(args.map, args.fill_nodata, getattr(args, "reproject", None), getattr(args, "cell_size", None))
    return apply_landcover(args, tmap, classes)


def landcover_classes_arg(args: argparse.Namespace) -> LandcoverClasses | None:
    """The mapping of ``--landcover-classes`` (:func:`terrain.landcover.read_landcover_classes`), or None without
    ``--landcover``; its grounds must be presets unless ``--model`` prices the grounds."""
    landcover, classes = getattr(args, "landcover", None), getattr(args, "landcover_classes", None)
    if (landcover is None) != (classes is None):
        raise InvalidParameterError(
            "--landcover and --landcover-classes go together: the land-cover raster and the CSV naming the ground of "
            f"each of its codes (got --landcover {landcover}, --landcover-classes {classes})"
        )
    if classes is None:
        return None
    mapping = read_landcover_classes(classes)
    if getattr(args, "model", None) is None:
        check_grounds(mapping.ground_names, f"--landcover-classes {Path(classes).name}")
    return mapping


def apply_landcover(args: argparse.Namespace, tmap: TerrainMap, classes: LandcoverClasses | None = None) -> TerrainMap:
    """``tmap`` with the ground classes of ``--landcover`` (:func:`terrain.landcover.ground_classes_from_landcover`),
    or ``tmap`` itself without the flag; ``classes`` as read by :func:`landcover_classes_arg` (read here if None)."""
    classes = landcover_classes_arg(args) if classes is None else classes
    if classes is None:
        return tmap
    return ground_classes_from_landcover(tmap, args.landcover, classes)


def add_point_options(p: argparse.ArgumentParser, name: str, what: str, *, required: bool,
                      default: str = "") -> None:
    """``--NAME X Y`` (the map's metres) or ``--NAME-lonlat LON LAT`` (WGS 84 degrees), one of them; read them
    with :func:`point_arg`. ``what`` names the point in the help, ``default`` says what it is when not given."""
    group = p.add_mutually_exclusive_group(required=required)
    group.add_argument(f"--{name}", type=float, nargs=2, metavar=("X", "Y"), help=f"{what} (m){default}")
    group.add_argument(
        f"--{name}-lonlat", type=float, nargs=2, metavar=("LON", "LAT"),
        help=f"{what} as WGS 84 longitude and latitude (degrees), placed on the map by its CRS; instead of --{name}",
    )


def point_arg(args: argparse.Namespace, name: str, where: TerrainMap | DemWindows) -> tuple[float, float] | None:
    """The point of :func:`add_point_options` in the map's metres, or None when neither flag was given.

    Raises
    ------
    InvalidParameterError
        ``--NAME-lonlat`` on a map without CRS, or degrees out of range.
    OutOfBoundsError
        ``--NAME-lonlat`` off the map (the message gives the point and the bounds in degrees and in metres).
    """
    lonlat = getattr(args, f"{name}_lonlat", None)
    if lonlat is not None:
        x, y = lonlat_points(lonlat, where, f"--{name}-lonlat")[0].tolist()
        return x, y
    xy = getattr(args, name, None)
    return None if xy is None else (float(xy[0]), float(xy[1]))


def check_outputs(directory: Path, files: Iterable[str] = (), inputs: Iterable[Path | None] = ()) -> None:
    """Before any work: ``directory`` can be a folder, each of ``files`` a file in it, none an input; it is writable.

    ``inputs`` are the command's input paths (``None`` for a flag not given): no output may
    be one of them or replace one, and the output folder may not be an input folder. The
    folder is created and a probe file written and removed in it, so an unwritable output
    fails now, in well under a second, not after the work.

    Raises
    ------
    InvalidParameterError
        A path of the wrong kind (a file where the folder goes, a folder where a file goes),
        an output that would replace an input, an output folder that cannot be written.
    """
    names = list(files)
    ins = list(inputs)
    check_output_path(directory, "--out", directory=True)
    for name in names:
        check_output_path(directory / name, f"--out {directory}: {name}")
    refuse_overwriting_inputs([directory, *(directory / n for n in names)], ins)
    probe_writable(directory)


#: Flags whose values are input paths (a ``--model`` that names a kind, a ``--map example``, are not files).
INPUT_FLAGS = ("map", "data", "pairs", "sites", "model", "calibration_data", "landcover", "landcover_classes")


def input_paths(args: argparse.Namespace) -> list[Path]:
    """The input paths a command was given (the flags of :data:`INPUT_FLAGS` that name existing files or folders)."""
    out = []
    for flag in INPUT_FLAGS:
        value = getattr(args, flag, None)
        if value is None or value == "example":
            continue
        path = Path(value)
        if path.exists():
            out.append(path)
    return out


def check_output_file(path: Path, inputs: Iterable[Path | None] = (), flag: str = "--out") -> None:
    """Before any work: ``path`` can be written as a file, is none of the inputs, and its folder is writable."""
    check_output_path(path, flag)
    refuse_overwriting_inputs([path], list(inputs), flag)
    probe_writable(path.parent if str(path.parent) else Path("."), flag)


def check_positive(flag: str, value: float | int) -> None:
    """``value`` a finite number > 0, or an error naming ``flag``."""
    if not (math.isfinite(value) and value > 0):
        raise InvalidParameterError(f"{flag} must be a number > 0, got {fmt_number(value)}")


def max_slope_rad(max_slope_deg: float) -> float:
    """``--max-slope-deg`` in radians, checked: in (0, 90) degrees."""
    if not (math.isfinite(max_slope_deg) and 0.0 < max_slope_deg < 90.0):
        raise InvalidParameterError(
            f"--max-slope-deg must be between 0 and 90 degrees (exclusive), got {fmt_number(max_slope_deg)}"
        )
    return math.radians(max_slope_deg)


def unknown_ground(name: str, tmap: TerrainMap) -> str | None:
    """``--unknown-ground``: a ground preset name, or None for ``none``; checked against the map.

    Raises
    ------
    UnknownNameError
        Not a preset name nor ``none``.
    InvalidParameterError
        ``none`` on a map with cells of unknown ground.
    """
    if name.lower() == "none":
        n = int(np.count_nonzero(np.asarray(tmap.ground) == UNKNOWN_GROUND))
        if n:
            raise InvalidParameterError(
                f"the map's ground class is unknown in {n} of {tmap.ground.size} cells and --unknown-ground none "
                f"refuses them; give --unknown-ground NAME, one of {sorted(GROUND_PRESETS)!r}"
            )
        return None
    if name not in GROUND_PRESETS:
        raise UnknownNameError(
            f"--unknown-ground must be a ground preset, one of {sorted(GROUND_PRESETS)!r}, or 'none'; got {name!r}"
        )
    return name


def check_grounds(names: Iterable[str], flag: str) -> None:
    """Every name a ground preset, or an error naming ``flag`` and the known grounds."""
    unknown = sorted(n for n in set(names) if n not in GROUND_PRESETS)
    if unknown:
        raise UnknownNameError(f"{flag}: grounds {unknown!r} have no preset; known grounds: {sorted(GROUND_PRESETS)!r}")


def draw_figure(path: Path, draw: Callable[[], Path]) -> Path | None:
    """Call ``draw`` (which writes the figure ``path``); on any failure warn on stderr and return None
    (:func:`terrawatt_base.figure_file.draw_figure`): a figure never fails a command whose results are written."""
    with warn_figures():
        return figure_file.draw_figure(path, draw)


@contextlib.contextmanager
def warn_figures() -> Iterator[None]:
    """A figure that fails inside (a :class:`~terrain.FigureWarning`) is one line on stderr, as :func:`draw_figure`'s."""
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
    """``--workers`` and ``--scheduler`` of :func:`add_dask_options`, checked before any work."""
    if args.workers < 1:
        raise InvalidParameterError(f"--workers must be a positive number of processes, got {args.workers!r}")
    if args.scheduler is not None and args.workers > 1:
        raise InvalidParameterError(
            f"--workers {args.workers!r} and --scheduler {args.scheduler!r} exclude each other: "
            "give --workers N for a local cluster or --scheduler ADDRESS for an existing one"
        )


@contextlib.contextmanager
def dask_client_arg(args: argparse.Namespace) -> Iterator[Any]:
    """The dask client of ``--workers N`` / ``--scheduler ADDRESS`` (closed on leaving), or None to run here."""
    if args.workers == 1 and args.scheduler is None:
        yield None
        return
    with dask_client(args.workers, args.scheduler, quiet=not args.verbose, flags=("--workers", "--scheduler")) as client:
        yield client


def add_model_options(p: argparse.ArgumentParser, *, risk: bool = False) -> None:
    """``--model FILE`` and ``--model-ground NAME`` (and, with ``risk``, ``--risk Q``): edge costs from a saved model."""
    p.add_argument(
        "--model", type=Path, default=None, metavar="FILE",
        help="price the edges with a saved current model (terrawatt train) instead of the physics presets: one per "
             "ground class of the map, which the model must have driven, on the robot of --robot (the physics "
             "model adds the slope term); --unknown-ground does not apply",
    )
    p.add_argument("--model-ground", default=None, nargs="+", metavar="NAME|CLASS=NAME",
                   help="with --model: NAME prices every cell as this training ground of the model (e.g. a map "
                        "without ground classes when the model drove several grounds); CLASS=NAME pairs price a "
                        "map ground class the model never drove as one it did (e.g. grass=asphalt sand=snow), the "
                        "other classes by their own names")
    if risk:
        p.add_argument(
            "--risk", type=float, default=None, metavar="Q",
            help="with --model of a model with a predictive interval: plan on the Q quantile of energy (Q in (0, 1)): "
                 "every edge costs mean + z_Q sd, which is the route's Q quantile on one ground and, for Q > 0.5, an "
                 "upper bound of it across grounds (their errors are independent); default: the mean",
        )


def check_model_flags(args: argparse.Namespace) -> None:
    """``--model``, ``--model-ground`` and ``--risk`` checked before any work (the file must exist)."""
    model = getattr(args, "model", None)
    if model is None:
        for flag, value in (("--model-ground", getattr(args, "model_ground", None)),
                            ("--risk", getattr(args, "risk", None))):
            if value is not None:
                raise InvalidParameterError(f"{flag} needs --model FILE (a saved current model; the physics presets "
                                            "have no training grounds nor an interval)")
        return
    if not Path(model).is_file():
        raise InvalidParameterError(f"--model {model} is not a file (write one with terrawatt train)")
    if getattr(args, "model_ground", None) is not None:
        args.model_ground = parse_model_ground(args.model_ground)
    if getattr(args, "risk", None) is not None:
        check_risk_level(args.risk, "--risk")


def parse_model_ground(tokens: Sequence[str] | str) -> str | dict[str, str]:
    """``--model-ground`` tokens: one ``NAME``, or ``CLASS=NAME`` pairs (a mapping of map class to training ground)."""
    items = [tokens] if isinstance(tokens, str) else list(tokens)
    if len(items) == 1 and "=" not in items[0]:
        return items[0]
    mapping: dict[str, str] = {}
    for token in items:
        cls, sep, name = token.partition("=")
        if not sep or not cls.strip() or not name.strip():
            raise InvalidParameterError(f"--model-ground takes one NAME or CLASS=NAME pairs, got {token!r}")
        if cls.strip() in mapping:
            raise InvalidParameterError(f"--model-ground names map class {cls.strip()!r} twice")
        mapping[cls.strip()] = name.strip()
    return mapping


def load_model_arg(args: argparse.Namespace) -> CurrentModel | None:
    """The model of ``--model`` (:func:`energy.load_current_model`), or None without the flag."""
    if getattr(args, "model", None) is None:
        return None
    return load_current_model(args.model)
