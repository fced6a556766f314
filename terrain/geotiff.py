"""Read and write GeoTIFF rasters as TerrainMaps (needs the optional ``geo`` extra: rasterio)."""

from __future__ import annotations

import logging
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from scipy import ndimage

from terrawatt_base.atomic import atomic_path
from terrawatt_base.containers import memory_limit_bytes, over_budget_message
from terrawatt_base.errors import (
    DataRepairWarning,
    FileFormatError,
    ImplausibleDataWarning,
    InvalidParameterError,
    NodataError,
    UnknownNameError,
)

from .georef import dem_band, import_rasterio
from .reproject import warp_band
from .terrain_map import UNKNOWN_GROUND, TerrainMap

__all__ = ["read_geotiff", "write_geotiff", "check_fill_method"]

logger = logging.getLogger(__name__)

_FILL_METHODS = ("nearest",)
#: Slope (rad) of the cells that, when they are the majority, make a DEM implausible.
_STEEP_RAD = float(np.radians(60.0))


def read_geotiff(
    path: str | os.PathLike[str],
    band: int | None = None,
    *,
    fill_nodata: str | None = None,
    reproject_to: str | None = None,
    cell_size_m: float | None = None,
    resampling: str = "bilinear",
) -> TerrainMap:
    """Read one band of a GeoTIFF as the elevation of a new :class:`TerrainMap`.

    The raster must have square pixels, no rotation, and horizontal and vertical units
    of metres (a projected CRS, or none) — or be reprojected on reading with
    ``reproject_to``. North-up rasters (the usual case, row 0 at the top) are flipped into
    TerrainMap's convention (row grows with y); the CRS is kept as a string (``tmap.crs``).
    Scale and offset tags are applied.

    A DEM is one band: a file of several bands (an RGB orthophoto, a stack) is read only
    when ``band`` names the elevation band. Georeferencing that cannot be metres is refused
    (a geographic CRS, unless reprojected; without a CRS, cells under 1 cm or over 10 km,
    which are what a DEM in degrees looks like). A DEM whose cells are mostly steeper than
    60 degrees is read but warned about with :class:`ImplausibleDataWarning`: such terrain
    exists (a crop of a cliff or a quarry wall), so refusing it would refuse real data,
    whereas a wrong band or unit is never right; the planner's slope limit blocks such
    cells anyway.

    Parameters
    ----------
    path : str or path-like
        GeoTIFF file.
    band : int, optional
        1-based index of the elevation band; required when the file has more than one.
    fill_nodata : {None, "nearest"}
        What to do with nodata / NaN cells. ``None`` (default) raises; ``"nearest"``
        gives each such cell the value of the nearest valid cell and warns with
        :class:`DataRepairWarning`.
    reproject_to : {None, "utm"} or str
        Reproject the DEM (:func:`rasterio.warp.reproject`) to the WGS 84 UTM zone of its
        centre (``"utm"``) or to a named projected CRS in metres (``"EPSG:32633"``); the
        usual way to read a DEM in geographic coordinates (EPSG:4326). The map's ``crs`` is
        the target CRS. Cells outside the source's footprint (the corners a warped
        rectangle leaves empty) become obstacles, their elevation taken from the nearest
        covered cell; nodata inside the footprint follows ``fill_nodata``.
    cell_size_m : float, optional
        Cell side of the reprojected map (m); required with ``reproject_to``.
    resampling : str
        Resampling of the reprojection: ``"bilinear"`` (default), ``"cubic"``,
        ``"nearest"`` or ``"average"``.

    Returns
    -------
    TerrainMap
        Elevation only; ground unknown, no obstacles (but for a reprojection's empty corners).

    Raises
    ------
    OptionalDependencyError
        rasterio is not installed.
    FileFormatError
        Missing or unreadable file; several bands and no ``band``; a rotated or
        non-square-pixel grid; a geographic CRS or units other than metres without
        ``reproject_to`` (the message names it).
    UnitError
        No CRS and a cell size implausible for metres (below 1 cm or above 10 km).
    InvalidParameterError
        A band out of range; nodata cells when ``fill_nodata`` is None; no valid cell;
        ``reproject_to`` without ``cell_size_m`` (or the reverse), a target CRS that is
        not projected in metres, a source without CRS.
    UnknownNameError
        An unknown ``fill_nodata`` or ``resampling`` method.

    Warns
    -----
    ImplausibleDataWarning
        More than half of the cells are steeper than 60 degrees.
    """
    rasterio = import_rasterio()
    check_fill_method(fill_nodata)
    if (reproject_to is None) != (cell_size_m is None):
        raise InvalidParameterError(
            "reproject_to and cell_size_m go together: give both (e.g. reproject_to='utm', cell_size_m=5.0) "
            f"or neither, got reproject_to={reproject_to!r}, cell_size_m={cell_size_m!r}"
        )
    path = Path(path)
    if not path.is_file():
        raise FileFormatError(f"GeoTIFF file {str(path)!r} does not exist")
    where = f"GeoTIFF {str(path)!r}"
    footprint = None
    try:
        with rasterio.open(path) as src:
            info = dem_band(src, band, where, allow_geographic=reproject_to is not None)
            need = int(src.width) * int(src.height) * 17  # float64 values + the mask + float64 workspace
            if need > memory_limit_bytes():
                raise FileFormatError(over_budget_message(
                    where, f"its {src.width} x {src.height} cells read whole", need,
                    advice="read it by windows: terrain.iter_surface_windows, or plan coarse-to-fine by windows "
                           "(planner.plan_coarse_to_fine on the file's path, a coarse `factor` F)"), parameter="factor")
            if reproject_to is None:
                data = src.read(info.band, masked=True)
                values = np.ma.getdata(data).astype(np.float64)  # in place from here: big DEMs
                if info.scale != 1.0:
                    values *= info.scale
                if info.offset != 0.0:
                    values += info.offset
                invalid = np.ma.getmaskarray(data)
                invalid |= ~np.isfinite(values)
                del data
                cell, origin, crs = info.cell_size_m, info.origin_xy_m, info.crs
                flip_rows, flip_cols = info.flip_rows, info.flip_cols
            else:
                warped = warp_band(src, info, reproject_to, cell_size_m, resampling)
                values, footprint = warped.values, warped.footprint
                invalid = ~np.isfinite(values)
                t = warped.transform
                cell, crs = abs(t.a), warped.crs
                origin = (t.c, t.f + t.e * values.shape[0])
                flip_rows, flip_cols = True, False
    except rasterio.errors.RasterioError as exc:
        raise FileFormatError(f"cannot read {str(path)!r} as a raster: {exc}") from exc

    outside = None if footprint is None else ~footprint
    missing = invalid if outside is None else invalid & ~outside
    n_bad = int(np.count_nonzero(missing))
    if np.all(invalid):
        raise InvalidParameterError(f"{where} band {info.band} holds no valid cell (all {invalid.size} are nodata)")
    if n_bad and fill_nodata is None:
        raise NodataError(
            f"{where} band {info.band} has {n_bad} nodata/NaN cells of {invalid.size}; pass "
            "fill_nodata='nearest' to fill them from the nearest valid cell",
            n_nodata=n_bad,
            n_cells=int(invalid.size),
        )
    if np.any(invalid):
        nearest = ndimage.distance_transform_edt(invalid, return_distances=False, return_indices=True)
        values = values[tuple(nearest)]
    if n_bad:
        message = f"filled {n_bad} nodata cells of {where} from their nearest valid cells"
        logger.info(message)
        warnings.warn(message, DataRepairWarning, stacklevel=2)
    if outside is not None and outside.any():
        logger.info("%s: %d cells outside the reprojected footprint are obstacles", where, int(outside.sum()))

    if flip_rows:  # north-up: file row 0 is the northern edge
        values = values[::-1]
        outside = None if outside is None else outside[::-1]
    if flip_cols:  # east-left: file column 0 is the eastern edge
        values = values[:, ::-1]
    tmap = TerrainMap(values, cell, origin, crs=crs, obstacle=outside)
    del values, invalid, missing  # the map holds its own copy: free ours before deriving slopes
    steep = float(np.mean(tmap.slope_rad > _STEEP_RAD))
    if steep > 0.5:
        warnings.warn(
            f"{where} band {info.band}: {100 * steep:.0f} % of the cells are steeper than 60 degrees; is it really "
            "a DEM in metres (not an image band, not elevations in another unit)?",
            ImplausibleDataWarning,
            stacklevel=2,
        )
    return tmap


def check_fill_method(fill_nodata: str | None) -> str | None:
    """``fill_nodata`` if it is ``None`` or a known method (``"nearest"``).

    Raises
    ------
    UnknownNameError
        Any other value; the message lists the methods.
    """
    if fill_nodata is not None and (not isinstance(fill_nodata, str) or fill_nodata not in _FILL_METHODS):
        raise UnknownNameError(f"fill_nodata must be None or one of {_FILL_METHODS!r}, got {fill_nodata!r}")
    return fill_nodata


def write_geotiff(
    tmap: TerrainMap, path: str | os.PathLike[str], layer: str = "elevation"
) -> Path:
    """Write one layer of a map as a single-band north-up GeoTIFF, atomically.

    The file is written to a temporary file in the same directory, then renamed.
    Boolean layers are stored as uint8; the ground layer declares ``-1`` (unknown) as
    nodata; the map's CRS string is stored when it has one.

    Parameters
    ----------
    tmap : TerrainMap
        Source map.
    path : str or path-like
        Output file, ending in ``.tif`` or ``.tiff``.
    layer : str
        Layer name (derived layers such as ``"slope"`` work too).

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    OptionalDependencyError
        rasterio is not installed.
    InvalidParameterError
        A path without a GeoTIFF suffix, or a CRS rasterio does not understand.
    UnknownNameError
        An unknown layer.
    """
    rasterio = import_rasterio()
    path = Path(path)
    if path.suffix.lower() not in (".tif", ".tiff"):
        raise InvalidParameterError(f"GeoTIFF files end in '.tif' or '.tiff', got {str(path)!r}")
    data = tmap[layer]
    if data.dtype == bool:
        data = data.astype(np.uint8)
    profile: dict[str, Any] = {
        "driver": "GTiff",
        "height": tmap.shape[0],
        "width": tmap.shape[1],
        "count": 1,
        "dtype": data.dtype.name,
        "transform": tmap.grid.north_up_transform,
        "crs": tmap.crs,
        "nodata": UNKNOWN_GROUND if layer == "ground" else None,
        "compress": "deflate",
    }
    with atomic_path(path) as tmp:
        try:
            with rasterio.open(tmp, "w", **profile) as dst:
                dst.write(data[::-1], 1)
                if layer == "elevation":
                    dst.units = ("m",)
        except rasterio.errors.CRSError as exc:
            raise InvalidParameterError(f"map CRS {tmap.crs!r} is not understood by rasterio: {exc}") from exc
    return path
