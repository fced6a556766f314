"""Ground classes from a categorical land-cover raster (e.g. ESA WorldCover) and a code -> ground mapping.

A land cover is a GeoTIFF of integer class codes in any CRS; a mapping (a small CSV file,
:func:`read_landcover_classes`) names the ground of each code. :func:`ground_classes_from_landcover`
warps the codes onto a georeferenced map's grid by majority (GDAL's mode resampling) and makes
them the map's ground-class layer. Two ground names are reserved:

- ``obstacle``: the code's cells become obstacles (water, buildings, dense forest...);
- ``unknown``: the code's cells have unknown ground (``-1``), priced as the planner's
  ``unknown_ground`` says — the same as a code the mapping omits,
  but stated.

A raster and a mapping that have nothing to say about the map are refused: a land cover
that is all nodata over the map, or whose codes there are none of the mapping's, is a
:class:`DataError`. One that leaves more than :data:`UNKNOWN_SHARE_WARNING` of the map's
cells without a ground for no stated reason (nodata, off the raster, codes the mapping
omits) is used, with an :class:`ImplausibleDataWarning` that names the codes and their shares.
"""

from __future__ import annotations

import csv
import logging
import os
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from terrawatt_base.containers import memory_limit_bytes, over_budget_message
from terrawatt_base.errors import DataError, FileFormatError, ImplausibleDataWarning, InvalidParameterError

from .georef import import_rasterio, lonlat_bounds, parse_crs
from .terrain_map import UNKNOWN_GROUND, TerrainMap

__all__ = [
    "LandcoverClasses",
    "read_landcover_classes",
    "ground_classes_from_landcover",
    "OBSTACLE_GROUND",
    "UNKNOWN_GROUND_NAME",
    "LANDCOVER_COLUMNS",
    "MAX_CLASSES_BYTES",
    "UNKNOWN_SHARE_WARNING",
]

logger = logging.getLogger(__name__)

#: The ground name that makes a land-cover code an obstacle.
OBSTACLE_GROUND = "obstacle"
#: The ground name that leaves a land-cover code's ground unknown (``-1``).
UNKNOWN_GROUND_NAME = "unknown"
#: Columns of a classes file: required ``code`` and ``ground``, optional ``label`` (a description).
LANDCOVER_COLUMNS = ("code", "ground", "label")
#: Largest classes file read (bytes): a mapping is a few lines.
MAX_CLASSES_BYTES = 1024**2
_MAX_CODE = 2**31 - 1
_NAME = re.compile(r"^[A-Za-z0-9_\-]+$")
_CODE = re.compile(r"^[0-9]+$")
#: Share of the map's cells above which :func:`ground_classes_from_landcover` warns that the land cover leaves
#: them unknown for no stated reason (nodata, off the raster, a code the mapping omits; not a code mapped to
#: ``unknown``): a quarter of the map priced as the planner's ``unknown_ground`` is seldom what was meant.
UNKNOWN_SHARE_WARNING = 0.25
_NODATA = np.iinfo(np.uint16).max  # category of "no land-cover value" in the warp
_OFF_INDEX = np.iinfo(np.uint32).max  # a map cell centre off the raster, in the warp of code indices
_NODATA_INDEX = _OFF_INDEX - 1  # a map cell centre on a nodata cell
_FEW = 8  # codes listed in a message


@dataclass(frozen=True)
class LandcoverClasses:
    """The ground of each land-cover code.

    Attributes
    ----------
    grounds_by_code : mapping int -> str
        Ground name per code (read-only, sorted by code): a ground preset name such as
        ``"grass"``, or :data:`OBSTACLE_GROUND` / :data:`UNKNOWN_GROUND_NAME`.
    source : str or None
        The classes file it was read from (:func:`read_landcover_classes` sets it), for
        messages; not compared.

    Raises
    ------
    InvalidParameterError
        No codes, a code not an integer in [0, 2**31 - 1], a name that is not a non-empty
        word (letters, digits, ``_``, ``-``); a ``source`` that is not a string.

    Examples
    --------
    >>> classes = LandcoverClasses({10: "obstacle", 30: "grass", 50: "asphalt", 80: "obstacle"})
    >>> classes.ground_names, classes.obstacle_codes
    (('asphalt', 'grass'), (10, 80))
    """

    grounds_by_code: Mapping[int, str]
    source: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if self.source is not None and not isinstance(self.source, str):
            raise InvalidParameterError(f"source must be a file name (str) or None, got {self.source!r:.120}")
        if not isinstance(self.grounds_by_code, Mapping) or not self.grounds_by_code:
            raise InvalidParameterError(
                f"grounds_by_code must be a non-empty mapping of land-cover code to ground name, got "
                f"{self.grounds_by_code!r:.120}"
            )
        clean: dict[int, str] = {}
        for code, name in self.grounds_by_code.items():
            if not isinstance(code, (int, np.integer)) or isinstance(code, bool) or not 0 <= code <= _MAX_CODE:
                raise InvalidParameterError(f"land-cover codes must be integers in [0, {_MAX_CODE}], got {code!r}")
            if not isinstance(name, str) or not _NAME.match(name):
                raise InvalidParameterError(
                    f"land-cover code {int(code)} needs a ground name (letters, digits, '_' or '-'), got {name!r}"
                )
            reserved = name.lower() in (OBSTACLE_GROUND, UNKNOWN_GROUND_NAME)
            clean[int(code)] = name.lower() if reserved else name
        object.__setattr__(self, "grounds_by_code", MappingProxyType(dict(sorted(clean.items()))))

    @property
    def ground_names(self) -> tuple[str, ...]:
        """The grounds named (sorted), without the reserved ``obstacle`` and ``unknown``."""
        reserved = (OBSTACLE_GROUND, UNKNOWN_GROUND_NAME)
        return tuple(sorted({n for n in self.grounds_by_code.values() if n not in reserved}))

    @property
    def obstacle_codes(self) -> tuple[int, ...]:
        """The codes whose cells are obstacles."""
        return tuple(c for c, n in self.grounds_by_code.items() if n == OBSTACLE_GROUND)

    def describe(self) -> str:
        """How messages name the mapping: its classes file, or ``the mapping`` when made in memory."""
        return "the mapping" if self.source is None else f"land-cover classes file {self.source!r}"


def read_landcover_classes(path: str | os.PathLike[str]) -> LandcoverClasses:
    """Read a land-cover mapping: a UTF-8 CSV file with columns ``code,ground`` (and optionally ``label``).

    One row per code; blank lines and lines starting with ``#`` are skipped. ``ground`` is a
    ground name (a preset such as ``grass``), ``obstacle`` (the code's cells are impassable)
    or ``unknown`` (their ground stays unknown). For ESA WorldCover, e.g.::

        code,ground,label
        10,obstacle,Tree cover
        30,grass,Grassland
        50,asphalt,Built-up
        60,gravel,Bare / sparse vegetation
        80,obstacle,Permanent water bodies

    Codes the file omits (and the raster's nodata) leave the ground unknown.

    Raises
    ------
    FileFormatError
        A missing, non-regular, oversized (over :data:`MAX_CLASSES_BYTES`) or non-UTF-8 file;
        a header without ``code`` and ``ground`` or with other columns; a row with another
        number of fields, a code that is not a non-negative integer, a ground that is not a
        name, a code given twice; no rows. The message names the file and the line.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = pathlib.Path(folder.name) / "classes.csv"
    >>> _ = path.write_text("code,ground\\n10,obstacle\\n30,grass\\n")
    >>> dict(read_landcover_classes(path).grounds_by_code)
    {10: 'obstacle', 30: 'grass'}
    >>> folder.cleanup()
    """
    p = Path(path)
    where = f"land-cover classes file {str(p)!r}"
    if not p.exists():
        raise FileFormatError(f"{where} does not exist")
    if not p.is_file():  # a FIFO or a device would block or never end
        raise FileFormatError(f"{where} is not a regular file")
    size = p.stat().st_size
    if size > MAX_CLASSES_BYTES:
        raise FileFormatError(f"{where} holds {size} bytes; a mapping of land-cover codes is at most "
                              f"{MAX_CLASSES_BYTES // 1024} KiB")
    with open(p, "rb") as fh:
        raw = fh.read(MAX_CLASSES_BYTES + 1)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FileFormatError(f"{where} is not a UTF-8 text file: {exc}") from exc
    header: list[str] | None = None
    rows: dict[int, tuple[str, int]] = {}
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            fields = [f.strip() for f in next(csv.reader([line], strict=True))]
        except csv.Error as exc:
            raise FileFormatError(f"{where}, line {number}: not a CSV row: {exc}") from exc
        if header is None:
            header = _header(fields, where, number)
            continue
        if len(fields) != len(header):
            raise FileFormatError(f"{where}, line {number}: {len(fields)} fields {fields!r}; the header has "
                                  f"{len(header)} ({', '.join(header)})")
        row = dict(zip(header, fields, strict=True))
        code_text, name = row["code"], row["ground"]
        # a code of more digits than the largest is refused before int() (which refuses past 4300 digits)
        digits = code_text.lstrip("0") or "0"
        if not _CODE.match(code_text) or len(digits) > len(str(_MAX_CODE)) or int(digits) > _MAX_CODE:
            raise FileFormatError(f"{where}, line {number}: code {code_text[:20]!r}{'...' if len(code_text) > 20 else ''} "
                                  f"is not a land-cover code; expected an integer in [0, {_MAX_CODE}]")
        if not _NAME.match(name):
            raise FileFormatError(f"{where}, line {number}: ground {name!r} is not a ground name; expected a word "
                                  f"such as 'grass', or '{OBSTACLE_GROUND}' or '{UNKNOWN_GROUND_NAME}'")
        code = int(digits)
        if code in rows:
            raise FileFormatError(f"{where}, line {number}: code {code} is given twice (first on line {rows[code][1]})")
        rows[code] = (name, number)
    if header is None:
        raise FileFormatError(f"{where} is empty; expected a header 'code,ground' and one row per code")
    if not rows:
        raise FileFormatError(f"{where} has a header but no rows; expected one row per land-cover code")
    return LandcoverClasses({code: name for code, (name, _) in rows.items()}, source=str(p))


def _header(fields: list[str], where: str, number: int) -> list[str]:
    names = [f.lower() for f in fields]
    missing = [c for c in ("code", "ground") if c not in names]
    extra = [f for f in names if f not in LANDCOVER_COLUMNS]
    if missing or extra or len(set(names)) != len(names):
        raise FileFormatError(
            f"{where}, line {number}: header {fields!r}; expected the columns 'code' and 'ground' (and optionally "
            "'label'), each once" + (f"; {missing!r} missing" if missing else "")
            + (f"; {extra!r} unknown" if extra else "")
        )
    return names


def ground_classes_from_landcover(
    tmap: TerrainMap,
    path: str | os.PathLike[str],
    classes: LandcoverClasses | Mapping[int, str] | str | os.PathLike[str],
    *,
    band: int | None = None,
) -> TerrainMap:
    """A copy of ``tmap`` whose ground classes (and obstacles) come from a land-cover raster.

    The raster's codes are turned into grounds by ``classes`` and warped onto the map's grid
    (:func:`rasterio.warp.reproject` from the raster's CRS to the map's) by majority: each map
    cell takes the ground covering most of it (GDAL's ``mode`` resampling over the raster
    cells it overlaps; codes of one ground count together). Nodata cells do not vote; codes
    the mapping omits vote as unknown ground. Then, per map cell:

    - a ground name: that ground (a name new to the map gets the next free class id; grounds
      no cell takes get none);
    - ``obstacle``: an obstacle (added to the map's obstacles; the ground is kept);
    - ``unknown``, an omitted code, nodata, or outside the raster: the map's ground is kept
      (unknown, ``-1``, for a GeoTIFF DEM), which the planner prices as its
      ``unknown_ground``.

    Only the window of the raster around the map is read, and it must fit the memory budget
    (:func:`terrawatt_base.containers.memory_limit_bytes`), so a continental tile can serve a
    small map.

    The land cover must have something to say about the map: a window that is all nodata,
    or whose codes are none of the mapping's, is refused (the raster or the classes file is
    not the one meant). When more than :data:`UNKNOWN_SHARE_WARNING` of the map's cells (by
    the code at each cell's centre) take no ground because they are nodata, off the raster or
    a code the mapping omits, the map is made all the same with an
    :class:`~terrawatt_base.errors.ImplausibleDataWarning` naming those codes, their shares and
    the mapping's codes found nowhere over the map. Codes mapped to ``unknown`` are stated
    and never warned about.

    Parameters
    ----------
    tmap : TerrainMap
        A map with a CRS (e.g. ``read_geotiff(dem, reproject_to="utm", cell_size_m=30)``).
    path : str or path-like
        Land-cover GeoTIFF: integer class codes (e.g. ESA WorldCover's uint8 codes), any CRS.
    classes : LandcoverClasses, mapping of code to ground name, or path
        The mapping, or its CSV file (:func:`read_landcover_classes`).
    band : int, optional
        1-based band of the codes; required when the file has several.

    Returns
    -------
    TerrainMap
        A new map; ``tmap`` is not modified.

    Raises
    ------
    InvalidParameterError
        The map has no CRS; the raster does not overlap the map; a band out of range.
    DataError
        Over the map, the raster holds only nodata, or only codes the mapping lacks (the
        message lists the codes it holds and the mapping's).
    FileFormatError
        A missing or unreadable raster, one without CRS, with a rotated grid, of non-integer
        values, several bands and no ``band``, a window over the memory budget; a bad
        classes file (as :func:`read_landcover_classes`).
    OptionalDependencyError
        rasterio is not installed.

    Warns
    -----
    ImplausibleDataWarning
        More than :data:`UNKNOWN_SHARE_WARNING` of the map's cells end with unknown ground
        because they are nodata, off the raster or of codes the mapping omits (cells the map
        already gave a ground, or obstacles, do not count).
    """
    rasterio = import_rasterio()
    from rasterio.enums import Resampling
    from rasterio.warp import reproject, transform_bounds

    if not isinstance(tmap, TerrainMap):
        raise InvalidParameterError(f"tmap must be a TerrainMap, got {type(tmap).__name__}")
    if not isinstance(classes, LandcoverClasses):
        classes = LandcoverClasses(classes) if isinstance(classes, Mapping) else read_landcover_classes(classes)
    if tmap.crs is None:
        raise InvalidParameterError(
            "the map has no CRS, so a land-cover raster cannot be placed on it; read a georeferenced DEM (a GeoTIFF "
            "with a CRS) or set the map's crs"
        )
    map_crs = parse_crs(tmap.crs, "the map's crs")
    p = Path(path)
    where = f"land-cover GeoTIFF {str(p)!r}"
    if not p.is_file():
        raise FileFormatError(f"{where} does not exist" if not p.exists() else f"{where} is not a regular file")
    try:
        with rasterio.open(p) as src:
            band = _code_band(src, band, where)
            window = _window(src, transform_bounds(map_crs, src.crs, *tmap.bounds, densify_pts=21), where, tmap)
            (r0, r1), (c0, c1) = window
            # the codes and their mask, their index (int64, then uint32), their category (uint16)
            need = (r1 - r0) * (c1 - c0) * (np.dtype(src.dtypes[band - 1]).itemsize + 1 + 8 + 4 + 2)
            if need > memory_limit_bytes():
                raise FileFormatError(over_budget_message(
                    where, f"the {r1 - r0} x {c1 - c0} cells around the map", need,
                    advice="resample the land cover to a coarser grid first (gdalwarp -tr)"))
            win = rasterio.windows.Window(c0, r0, c1 - c0, r1 - r0)
            data = src.read(band, window=win, masked=True)
            src_transform, src_crs, src_nodata = src.window_transform(win), src.crs, src.nodata
    except rasterio.errors.RasterioError as exc:
        raise FileFormatError(f"cannot read {str(p)!r} as a raster: {exc}") from exc

    labels = [*classes.ground_names, OBSTACLE_GROUND, UNKNOWN_GROUND_NAME]
    category = {name: i for i, name in enumerate(labels)}
    values, inverse = np.unique(np.ma.getdata(data), return_inverse=True)
    inverse = inverse.reshape(data.shape)
    nodata_cells = np.ma.getmaskarray(data)
    del data
    votes = np.bincount(inverse[~nodata_cells], minlength=values.size)
    present = [int(v) for v in values[votes > 0].tolist()]
    _check_codes(present, classes, where, inverse.shape, src_nodata)
    lut = np.array([category[classes.grounds_by_code.get(int(v), UNKNOWN_GROUND_NAME)] for v in values.tolist()],
                   dtype=np.uint16)
    codes = lut[inverse]
    codes[nodata_cells] = _NODATA
    index = inverse.astype(np.uint32)  # the code at each cell, for the shares over the map
    index[nodata_cells] = _NODATA_INDEX
    del inverse, nodata_cells
    unmapped = [c for c in present if c not in classes.grounds_by_code]
    if unmapped:
        logger.info("%s: codes %s are not in %s; their cells vote as unknown ground", where, unmapped,
                    classes.describe())

    rows, cols = tmap.shape
    xmin, _, _, ymax = tmap.bounds
    d = tmap.cell_size_m
    dst_transform = rasterio.Affine(d, 0.0, xmin, 0.0, -d, ymax)
    warped = np.full((rows, cols), _NODATA, np.uint16)
    at_centre = np.full((rows, cols), _OFF_INDEX, np.uint32)
    try:
        reproject(codes, warped, src_transform=src_transform, src_crs=src_crs, src_nodata=_NODATA,
                  dst_transform=dst_transform, dst_crs=map_crs, dst_nodata=_NODATA, resampling=Resampling.mode)
        reproject(index, at_centre, src_transform=src_transform, src_crs=src_crs, dst_transform=dst_transform,
                  dst_crs=map_crs, dst_nodata=_OFF_INDEX, resampling=Resampling.nearest)
    except rasterio.errors.RasterioError as exc:  # pragma: no cover - GDAL refusing a valid pair of CRS
        raise InvalidParameterError(f"cannot warp {where} onto the map's CRS {tmap.crs!r}: {exc}") from exc
    del codes, index
    warped, at_centre = warped[::-1], at_centre[::-1]  # north-up -> row grows with y

    names = tmap.ground_names
    ids = {name: gid for gid, name in names.items()}
    ground = np.array(tmap.ground, copy=True)
    for name in classes.ground_names:
        cells = warped == category[name]
        if not cells.any():  # a ground the map does not have gets no name
            continue
        if name not in ids:
            ids[name] = max([*names, -1]) + 1
            names[ids[name]] = name
        ground[cells] = ids[name]
    out = tmap.copy()
    out.ground_names = names
    out["ground"] = ground
    out["obstacle"] = tmap.obstacle | (warped == category[OBSTACLE_GROUND])
    _warn_unknown_share(at_centre, (ground == UNKNOWN_GROUND) & ~out.obstacle, values, present, classes, where)
    logger.info("%s: %d of %d map cells took a ground, %d became obstacles, %d kept the map's ground", where,
                int(np.count_nonzero(warped < category[OBSTACLE_GROUND])), warped.size,
                int(np.count_nonzero(warped == category[OBSTACLE_GROUND])),
                int(np.count_nonzero(warped > category[OBSTACLE_GROUND])))
    return out


def _few(codes: list[int]) -> str:
    """At most :data:`_FEW` codes, and how many more."""
    shown = ", ".join(str(c) for c in codes[:_FEW])
    return f"[{shown}{f', ... ({len(codes) - _FEW} more)' if len(codes) > _FEW else ''}]"


def _percent(share: float) -> str:
    """A share as a whole percentage, never rounded to 0 % or 100 % when it is not."""
    if 0.0 < share < 0.01:
        return "< 1 %"
    if 0.99 < share < 1.0:
        return "> 99 %"
    return f"{100 * share:.0f} %"


def _check_codes(present: list[int], classes: LandcoverClasses, where: str, window: tuple[int, int],
                 nodata: float | None) -> None:
    """Refuse a window with no code (all nodata), or with none of the mapping's codes."""
    cells = f"the {window[0]} x {window[1]} raster cells over the map"
    if not present:
        value = "" if nodata is None else f" (value {nodata:g})"
        raise DataError(
            f"{where} holds only nodata{value} in {cells}: there is no land cover to take ground classes from; "
            "is it the land cover of this area?")
    if not any(c in classes.grounds_by_code for c in present):
        raise DataError(
            f"{where} holds codes {_few(present)} in {cells}, none of them in {classes.describe()} (codes "
            f"{_few(list(classes.grounds_by_code))}): no cell would take a ground; are the raster and the classes "
            "file of the same land-cover product?")


def _warn_unknown_share(at_centre: np.ndarray, unknown: np.ndarray, values: np.ndarray, present: list[int],
                        classes: LandcoverClasses, where: str) -> None:
    """Warn when more than :data:`UNKNOWN_SHARE_WARNING` of the map's cells end with unknown ground (``unknown``:
    passable cells of unknown ground) for no stated reason: their centre is nodata, off the raster or of a code the
    mapping omits (``at_centre``: the index into ``values`` of the code at each cell's centre, or a sentinel)."""
    n = at_centre.size
    stated = np.array([classes.grounds_by_code.get(int(v)) == UNKNOWN_GROUND_NAME for v in values.tolist()]
                      + [False, False])  # ... and the nodata and off-raster sentinels, last
    index = np.where(at_centre < values.size, at_centre, values.size + (at_centre == _OFF_INDEX)).astype(np.intp)
    counts = np.bincount(index[unknown & ~stated[index]], minlength=values.size + 2)
    names = [f"code {int(v)}" if int(v) not in classes.grounds_by_code else "mixed cells"
             for v in values.tolist()] + ["nodata", "off the raster"]
    parts: dict[str, int] = {}
    for name, k in zip(names, counts.tolist(), strict=True):
        if k:
            parts[name] = parts.get(name, 0) + int(k)
    ranked = sorted(parts.items(), key=lambda p: -p[1])
    share = sum(parts.values()) / n
    absent = [c for c in classes.grounds_by_code if c not in present]
    if absent:
        logger.info("%s: codes %s of %s are nowhere over the map", where, absent, classes.describe())
    if share <= UNKNOWN_SHARE_WARNING:
        return
    listed = ", ".join(f"{what}: {_percent(k / n)}" for what, k in ranked[:_FEW])
    more = f", and {len(ranked) - _FEW} more codes" if len(ranked) > _FEW else ""
    missing = (f"; codes {_few(absent)} of {classes.describe()} are nowhere over the map" if absent else "")
    warnings.warn(ImplausibleDataWarning(
        f"{where} leaves {_percent(share)} of the map's cells with unknown ground ({listed}{more}), priced as the "
        f"planner's unknown_ground{missing}; map the omitted codes in the classes file, or give a land cover that "
        "covers the map", parameter="unknown_ground"), stacklevel=3)


def _code_band(src: Any, band: int | None, where: str) -> int:
    """The checked band of class codes: integers, a CRS, no rotation."""
    if band is None:
        if src.count != 1:
            raise FileFormatError(f"{where} has {src.count} bands; name the band of class codes with band=N "
                                  f"(1..{src.count})")
        band = 1
    if not isinstance(band, (int, np.integer)) or isinstance(band, bool) or not 1 <= band <= src.count:
        raise InvalidParameterError(f"band must be an integer in 1..{src.count}, got {band!r}")
    dtype = src.dtypes[band - 1]
    if dtype not in np.sctypeDict or np.dtype(dtype).kind not in "iu":
        raise FileFormatError(f"{where}: band {band} holds {dtype} values; a land cover holds integer class codes "
                              "(e.g. uint8)")
    if src.crs is None:
        raise FileFormatError(f"{where} has no CRS; a land cover is placed on the map by its CRS (set it first, "
                              "e.g. gdal_edit -a_srs)")
    t = src.transform
    if t.b != 0 or t.d != 0:
        raise FileFormatError(f"{where} has a rotated or sheared transform {tuple(t)[:6]!r}; warp it to a north-up "
                              "grid first (e.g. gdalwarp)")
    return int(band)


def _window(src: Any, box: tuple[float, float, float, float], where: str,
            tmap: TerrainMap) -> tuple[tuple[int, int], tuple[int, int]]:
    """Rows and columns ``((r0, r1), (c0, c1))`` of the raster covering ``box`` (its CRS), two cells of margin."""
    left, bottom, right, top = box
    t = src.transform  # north-up or not, never rotated (checked)
    cs = [(x - t.c) / t.a for x in (left, right)]
    rs = [(y - t.f) / t.e for y in (bottom, top)]
    r0, r1 = max(int(np.floor(min(rs))) - 2, 0), min(int(np.ceil(max(rs))) + 2, src.height)
    c0, c1 = max(int(np.floor(min(cs))) - 2, 0), min(int(np.ceil(max(cs))) + 2, src.width)
    if r1 <= r0 or c1 <= c0:
        m = lonlat_bounds(tmap.bounds, tmap.crs)
        s = lonlat_bounds(tuple(src.bounds), src.crs, what=where)
        raise InvalidParameterError(
            f"{where} does not overlap the map: it spans lon {s[0]:.5f} to {s[2]:.5f}, lat {s[1]:.5f} to {s[3]:.5f}; "
            f"the map lon {m[0]:.5f} to {m[2]:.5f}, lat {m[1]:.5f} to {m[3]:.5f}"
        )
    return (r0, r1), (c0, c1)
