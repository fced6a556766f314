"""Options and checks the ``terrawatt`` subcommands share: map reading, output paths, flags."""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from energy import GROUND_PRESETS
from terrain import UNKNOWN_GROUND, InvalidParameterError, NodataError, TerrainMap, UnknownNameError
from terrain.atomic import check_output_path
from terrain.checks import fmt_number

__all__ = [
    "add_map_options",
    "read_map_file",
    "check_outputs",
    "check_positive",
    "max_slope_rad",
    "unknown_ground",
    "check_grounds",
    "draw_figure",
]


def add_map_options(p: argparse.ArgumentParser) -> None:
    """``--fill-nodata``."""
    p.add_argument(
        "--fill-nodata", choices=["nearest"], default=None,
        help="GeoTIFF DEMs: fill nodata cells from the nearest valid cell (default: refuse such DEMs)",
    )


def read_map_file(path: str | os.PathLike[str], fill_nodata: str | None) -> TerrainMap:
    """:func:`terrain.read_map`, its advice phrased with the CLI's ``--fill-nodata nearest``."""
    from terrain import read_map

    try:
        return read_map(path, fill_nodata=fill_nodata)
    except NodataError as exc:
        raise NodataError(
            f"{Path(path).name} has {exc.n_nodata} nodata cells of {exc.n_cells}; give "
            "--fill-nodata nearest to fill them from the nearest valid cell",
            n_nodata=exc.n_nodata,
            n_cells=exc.n_cells,
        ) from exc


def check_outputs(directory: Path, files: Iterable[str] = ()) -> None:
    """Before any work: ``directory`` can be a folder and each of ``files`` a file in it.

    Raises
    ------
    InvalidParameterError
        A path of the wrong kind (a file where the folder goes, a folder where a file goes).
    """
    check_output_path(directory, "--out", directory=True)
    for name in files:
        check_output_path(directory / name, f"--out {directory}: {name}")


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
    """Call ``draw`` (which writes the figure ``path``); on any failure warn on stderr and return None.

    A figure never fails a command whose results are already written: the failure is
    reported as one line and the command's exit code stays that of its results.
    """
    try:
        return draw()
    except Exception as exc:  # noqa: BLE001 - any failure of a figure is reported, never fatal
        print(f"terrawatt: warning: could not draw {path}: {type(exc).__name__}: {exc}", file=sys.stderr)
        return None
