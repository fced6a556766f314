"""Energy costmaps: each cell's energy per metre (J/m) at the planning speed, as a raster and a float32 GeoTIFF.

An :class:`~planner.EnergyCost` prices a cell by its ground's table of energy per horizontal
metre against the *signed* grade met in the direction of travel, so a cell has no single
cost: uphill is dearer than downhill. A costmap needs one number per cell;
:func:`energy_costmap` gives it as a statistic over headings of ``f(|grad z| cos(theta))``:

- ``"mean"`` — the average over headings (what an isotropic planner pays on average);
- ``"min"`` — the cheapest heading (never above what any straight motion through the cell costs);
- ``"max"`` — the dearest heading (``inf`` when some heading meets a grade the ground cannot
  be driven at).

Blocked cells (obstacles, cells steeper than the cost's ``max_slope_rad``) are NaN.
:func:`write_energy_geotiff` writes the costmap as a north-up float32 GeoTIFF with the map's
CRS and transform (NaN nodata); :func:`read_energy_geotiff` reads it back.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrain import Grid
from terrain.georef import import_rasterio
from terrawatt_base.atomic import atomic_path, check_output_path
from terrawatt_base.checks import check_choice, check_int, check_real, readonly
from terrawatt_base.errors import FileFormatError, InvalidParameterError

from .edge_cost import EnergyCost

__all__ = [
    "COSTMAP_STATISTICS",
    "COSTMAP_FORMAT_VERSION",
    "DEFAULT_COSTMAP_HEADINGS",
    "EnergyCostmap",
    "energy_costmap",
    "write_energy_geotiff",
    "read_energy_geotiff",
]

#: Statistics over headings that :func:`energy_costmap` can take.
COSTMAP_STATISTICS = ("mean", "min", "max")
#: Version of the ``TERRAWATT_*`` tags of the GeoTIFF costmaps written here.
COSTMAP_FORMAT_VERSION = 1
#: Heading intervals over [0, pi] of the ``"mean"`` statistic (trapezoidal rule).
DEFAULT_COSTMAP_HEADINGS = 64
_UNITS = "J/m"


@dataclass(frozen=True)
class EnergyCostmap:
    """Each cell's energy per horizontal metre (J/m) at a planning speed, on a grid.

    Attributes
    ----------
    energy_per_metre_j : ndarray, shape (rows, cols)
        J per horizontal metre, indexed ``[row, col]`` in the map's convention (row 0 the
        southern edge); NaN for blocked cells, ``+inf`` where the statistic meets a grade
        the ground cannot be driven at. Read-only float64.
    grid : Grid
        Shape, cell size and origin (the map's coordinates: its CRS when it has one).
    crs : str or None
        The map's CRS.
    statistic : str
        One of :data:`COSTMAP_STATISTICS`.
    speed_mps : float
        Planning speed the energies hold at (m/s).

    Raises
    ------
    InvalidParameterError
        A grid that is not a :class:`~terrain.Grid`, values of another shape, negative or
        ``-inf`` values, an unknown statistic, a speed that is not finite and > 0.
    """

    energy_per_metre_j: np.ndarray
    grid: Grid
    crs: str | None
    statistic: str
    speed_mps: float

    def __post_init__(self) -> None:
        if not isinstance(self.grid, Grid):
            raise InvalidParameterError(f"grid must be a terrain.Grid, got {type(self.grid).__name__!r}")
        values = readonly(self.energy_per_metre_j, np.float64)
        if values.shape != self.grid.shape:
            raise InvalidParameterError(
                f"energy_per_metre_j has shape {values.shape!r}; the grid has {self.grid.shape!r}")
        if np.any(values < 0):
            raise InvalidParameterError(
                f"energy_per_metre_j must be >= 0 (NaN blocked, inf undrivable), got minimum {float(np.nanmin(values))!r}")
        check_choice("statistic", self.statistic, COSTMAP_STATISTICS)
        if self.crs is not None and (not isinstance(self.crs, str) or not self.crs.strip()):
            raise InvalidParameterError(f"crs must be None or a non-empty string, got {self.crs!r}")
        object.__setattr__(self, "energy_per_metre_j", values)
        object.__setattr__(self, "speed_mps", check_real("speed_mps", self.speed_mps, low=0.0, low_inclusive=False))

    @property
    def blocked(self) -> np.ndarray:
        """Cells without an energy (NaN): obstacles and cells steeper than the slope limit."""
        return np.isnan(self.energy_per_metre_j)

    def __repr__(self) -> str:
        free = self.energy_per_metre_j[np.isfinite(self.energy_per_metre_j)]
        span = f"{free.min():.1f}-{free.max():.1f} J/m" if free.size else "no finite cell"
        return (f"EnergyCostmap({self.statistic}, {self.grid.shape[0]} x {self.grid.shape[1]} cells of "
                f"{self.grid.cell_size_m:g} m, {span} at {self.speed_mps:g} m/s, {int(self.blocked.sum())} blocked)")


def _interpolate(table: np.ndarray, rows: Any, grades: np.ndarray, grade_max: float) -> np.ndarray:
    """``table[rows]`` at ``grades``, linear on the uniform grade grid (clamped at its ends);
    ``inf`` where a neighbouring sample is (the rule of the edge-cost kernels)."""
    n = table.shape[1]
    step = 2.0 * grade_max / (n - 1)
    fi = (grades + grade_max) / step
    i0 = np.clip(np.floor(fi), 0, n - 2).astype(np.int64)
    w = np.clip(fi - i0, 0.0, 1.0)
    lo, hi = table[rows, i0], table[rows, i0 + 1]
    with np.errstate(invalid="ignore"):
        out = lo * (1.0 - w) + hi * w
    return np.where(np.isinf(lo) | np.isinf(hi), np.inf, out)


def energy_costmap(cost: EnergyCost, *, statistic: str = "mean",
                   n_headings: int = DEFAULT_COSTMAP_HEADINGS) -> EnergyCostmap:
    """Each cell's energy per horizontal metre (J/m) at the cost's planning speed.

    A cell of gradient magnitude ``m = |grad z|`` presents the grade ``m cos(theta)`` to a
    motion at heading ``theta`` from its steepest ascent; the energy per metre is the cell's
    ground table at that grade (the same interpolation as the edge costs). ``"min"`` and
    ``"max"`` are exact over all headings; ``"mean"`` is the trapezoidal average over
    ``n_headings`` equal intervals of ``theta`` in ``[0, pi]``, tabulated once per ground on
    the table's grade nodes and interpolated linearly in ``m`` (a flat cell is exact). The
    turns' energy is not in it.

    Parameters
    ----------
    cost : EnergyCost
        Edge costs of the map (its tables, gradients and blocked cells).
    statistic : {"mean", "min", "max"}
        Statistic over headings.
    n_headings : int
        Heading intervals of ``"mean"`` (>= 2).

    Returns
    -------
    EnergyCostmap
        NaN for blocked cells.

    Raises
    ------
    InvalidParameterError
        ``cost`` not an EnergyCost; ``n_headings`` not an integer >= 2.
    UnknownNameError
        An unknown statistic.

    Examples
    --------
    >>> from planner import EnergyCost
    >>> from terrain import flat_map
    >>> tmap = flat_map((4, 5), 1.0)
    >>> from planner import CostSpec
    >>> cost = CostSpec().build(tmap)
    >>> costmap = energy_costmap(cost)
    >>> per_metre = float(cost.segment_energy_j([[0.5, 0.5]], [[4.5, 0.5]])[0]) / 4.0
    >>> bool(abs(costmap.energy_per_metre_j[2, 3] - per_metre) < 1e-9 * per_metre)
    True
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    check_choice("statistic", statistic, COSTMAP_STATISTICS)
    k = check_int("n_headings", n_headings, low=2)
    table = np.asarray(cost.tables.grade_table_j_per_m, dtype=np.float64)
    gmax = float(cost.grade_max)
    half = (table.shape[1] - 1) // 2  # index of grade 0
    step = 2.0 * gmax / (table.shape[1] - 1)
    tmap = cost.terrain
    free = ~np.asarray(cost.blocked)
    rows = np.asarray(cost.ground_rows)[free]
    mag = np.hypot(np.asarray(tmap["grad_x"]), np.asarray(tmap["grad_y"]))[free]
    mag = np.minimum(mag, gmax)  # a free cell is not steeper than the limit; guard rounding
    if statistic == "mean":
        theta = np.linspace(0.0, math.pi, k + 1)
        weights = np.full(k + 1, 1.0 / k)
        weights[[0, -1]] *= 0.5
        nodes = np.arange(half + 1) * step  # gradient magnitudes on the table's grade nodes
        grades = nodes[:, None] * np.cos(theta)[None, :]
        per_node = np.stack([
            np.where(np.isinf(v).any(axis=1), np.inf, np.nan_to_num(v, posinf=0.0) @ weights)
            for v in (_interpolate(table, r, grades, gmax) for r in range(table.shape[0]))
        ])  # (n_rows, half + 1)
        u = mag / step
        j0 = np.clip(np.floor(u), 0, half - 1).astype(np.int64)
        w = np.clip(u - j0, 0.0, 1.0)
        lo, hi = per_node[rows, j0], per_node[rows, j0 + 1]
        with np.errstate(invalid="ignore"):
            value = np.where(np.isinf(lo) | np.isinf(hi), np.inf, lo * (1.0 - w) + hi * w)
    else:
        # over |grade| <= m the piecewise-linear table reaches its extreme at a node inside or at +-m
        pick = np.minimum if statistic == "min" else np.maximum
        left = pick.accumulate(table[:, half::-1], axis=1)
        right = pick.accumulate(table[:, half:], axis=1)
        inner = pick(left, right)  # (n_rows, half + 1): extreme over nodes with |grade| <= j * step
        j_in = np.clip(np.floor(mag / step * (1.0 + 1e-12)), 0, half).astype(np.int64)
        ends = pick(_interpolate(table, rows, mag, gmax), _interpolate(table, rows, -mag, gmax))
        value = pick(inner[rows, j_in], ends)
    out = np.full(tmap.shape, np.nan)
    out[free] = value
    return EnergyCostmap(out, tmap.grid, tmap.crs, statistic, cost.speed_mps)


def write_energy_geotiff(path: str | os.PathLike[str], costmap: EnergyCostmap) -> Path:
    """Write a costmap as a single-band north-up float32 GeoTIFF, atomically.

    The map's CRS and transform are stored (a map without a CRS gives a GeoTIFF without
    one), NaN is the nodata value (blocked cells), ``+inf`` stays ``+inf``; the band's unit
    is ``J/m`` and the tags ``TERRAWATT_FORMAT_VERSION``, ``TERRAWATT_STATISTIC`` and
    ``TERRAWATT_SPEED_MPS`` say what it holds.

    Parameters
    ----------
    path : path-like
        Output file ending in ``.tif`` or ``.tiff``.
    costmap : EnergyCostmap

    Returns
    -------
    Path

    Raises
    ------
    InvalidParameterError
        Another suffix; ``path`` a folder; not an EnergyCostmap; a CRS rasterio does not understand.
    OptionalDependencyError
        rasterio (the ``geo`` extra) is not installed.
    """
    target = check_output_path(path, "path")
    if target.suffix.lower() not in (".tif", ".tiff"):
        raise InvalidParameterError(f"GeoTIFF files end in '.tif' or '.tiff', got {str(target)!r}")
    if not isinstance(costmap, EnergyCostmap):
        raise InvalidParameterError(f"costmap must be an EnergyCostmap, got {type(costmap).__name__!r}")
    rasterio = import_rasterio()
    grid = costmap.grid
    profile: dict[str, Any] = {
        "driver": "GTiff", "height": grid.shape[0], "width": grid.shape[1], "count": 1, "dtype": "float32",
        "transform": grid.north_up_transform, "crs": costmap.crs, "nodata": float("nan"), "compress": "deflate",
    }
    with atomic_path(target) as tmp:
        try:
            with rasterio.open(tmp, "w", **profile) as dst:
                dst.write(costmap.energy_per_metre_j[::-1].astype(np.float32), 1)  # row 0 north
                dst.units = (_UNITS,)
                dst.set_band_description(1, f"energy per horizontal metre ({costmap.statistic} over headings)")
                dst.update_tags(TERRAWATT_FORMAT_VERSION=str(COSTMAP_FORMAT_VERSION),
                                TERRAWATT_STATISTIC=costmap.statistic,
                                TERRAWATT_SPEED_MPS=repr(costmap.speed_mps))
        except rasterio.errors.CRSError as exc:
            raise InvalidParameterError(f"map CRS {costmap.crs!r} is not understood by rasterio: {exc}") from exc
    return target


def read_energy_geotiff(path: str | os.PathLike[str]) -> EnergyCostmap:
    """Read a costmap written by :func:`write_energy_geotiff` (values as float64, rows flipped back).

    Raises
    ------
    FileFormatError
        Not a readable GeoTIFF; not a terrawatt costmap (its tags), of a newer format
        version, or of another unit; a rotated, mirrored or non-square-pixel grid.
    OptionalDependencyError
        rasterio (the ``geo`` extra) is not installed.
    """
    rasterio = import_rasterio()
    src_path = Path(path)
    where = str(src_path)
    try:
        with rasterio.open(src_path) as src:
            tags = src.tags()
            transform, crs, units = src.transform, src.crs, src.units[0] if src.count else None
            values = src.read(1).astype(np.float64) if src.count == 1 else None
            count = src.count
    except rasterio.errors.RasterioIOError as exc:
        raise FileFormatError(f"cannot read GeoTIFF {where!r}: {exc}") from exc
    if "TERRAWATT_STATISTIC" not in tags or count != 1 or values is None:
        raise FileFormatError(f"{where!r} is not a terrawatt energy costmap (no TERRAWATT_STATISTIC tag or "
                              f"{count} bands); write one with write_energy_geotiff")
    try:
        version = int(tags.get("TERRAWATT_FORMAT_VERSION", ""))
    except ValueError:
        version = -1
    if not 1 <= version <= COSTMAP_FORMAT_VERSION:
        raise FileFormatError(f"{where!r} has costmap format version {tags.get('TERRAWATT_FORMAT_VERSION')!r}; "
                              f"this release reads 1 to {COSTMAP_FORMAT_VERSION}")
    if units != _UNITS:
        raise FileFormatError(f"{where!r} holds values in {units!r}; expected {_UNITS!r}")
    try:
        grid = Grid.from_transform(values.shape, transform)
        if transform.e < 0:  # north-up: file row 0 is the northern edge
            values = values[::-1]
        return EnergyCostmap(values, grid, None if crs is None else crs.to_string(), tags["TERRAWATT_STATISTIC"],
                             float(tags.get("TERRAWATT_SPEED_MPS", "nan")))
    except (InvalidParameterError, ValueError) as exc:
        raise FileFormatError(f"{where!r} is not a valid energy costmap: {exc}") from exc
