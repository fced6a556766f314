"""Read and write GeoTIFF rasters as TerrainMaps (needs the optional ``geo`` extra: rasterio)."""

from __future__ import annotations

import logging
import os
import warnings
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
from scipy import ndimage

from .atomic import atomic_path
from .checks import fmt_number
from .errors import (
    DataRepairWarning,
    FileFormatError,
    ImplausibleDataWarning,
    InvalidParameterError,
    NodataError,
    OptionalDependencyError,
    UnitError,
    UnknownNameError,
)
from .terrain_map import UNKNOWN_GROUND, TerrainMap

__all__ = ["read_geotiff", "write_geotiff", "check_fill_method"]

logger = logging.getLogger(__name__)

_METRE_UNITS = ("", "m", "metre", "metres", "meter", "meters")
_FILL_METHODS = ("nearest",)
#: Cell sizes (m) plausible for a DEM without a CRS: outside, the unit is likely degrees.
_CELL_RANGE_M = (0.01, 10_000.0)
#: Slope (rad) of the cells that, when they are the majority, make a DEM implausible.
_STEEP_RAD = float(np.radians(60.0))


def _rasterio() -> ModuleType:
    """Import rasterio lazily, pointing at the ``geo`` extra when it is missing."""
    try:
        import rasterio
    except ImportError as exc:
        raise OptionalDependencyError(
            "GeoTIFF support needs rasterio; install it with: pip install 'terrawatt[geo]'"
        ) from exc
    return rasterio


def read_geotiff(
    path: str | os.PathLike[str], band: int | None = None, *, fill_nodata: str | None = None
) -> TerrainMap:
    """Read one band of a GeoTIFF as the elevation of a new :class:`TerrainMap`.

    The raster must have square pixels, no rotation, and horizontal and vertical units
    of metres (a projected CRS, or none). North-up rasters (the usual case, row 0 at the
    top) are flipped into TerrainMap's convention (row grows with y); the CRS is kept as
    a string. Scale and offset tags are applied.

    A DEM is one band: a file of several bands (an RGB orthophoto, a stack) is read only
    when ``band`` names the elevation band. Georeferencing that cannot be metres is refused
    (a geographic CRS; without a CRS, cells under 1 cm or over 10 km, which are what a DEM
    in degrees looks like). A DEM whose cells are mostly steeper than 60 degrees is read
    but warned about with :class:`ImplausibleDataWarning`: such terrain exists (a crop of
    a cliff or a quarry wall), so refusing it would refuse real data, whereas a wrong band
    or unit is never right; the planner's slope limit blocks such cells anyway.

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

    Returns
    -------
    TerrainMap
        Elevation only; ground unknown, no obstacles.

    Raises
    ------
    OptionalDependencyError
        rasterio is not installed.
    FileFormatError
        Missing or unreadable file; several bands and no ``band``; a rotated or
        non-square-pixel grid; a geographic CRS or units other than metres.
    UnitError
        No CRS and a cell size implausible for metres (below 1 cm or above 10 km).
    InvalidParameterError
        A band out of range; nodata cells when ``fill_nodata`` is None; no valid cell.
    UnknownNameError
        An unknown ``fill_nodata`` method.

    Warns
    -----
    ImplausibleDataWarning
        More than half of the cells are steeper than 60 degrees.
    """
    rasterio = _rasterio()
    check_fill_method(fill_nodata)
    path = Path(path)
    if not path.is_file():
        raise FileFormatError(f"GeoTIFF file {str(path)!r} does not exist")
    try:
        with rasterio.open(path) as src:
            if band is None:
                if src.count != 1:
                    raise FileFormatError(
                        f"GeoTIFF {str(path)!r} has {src.count} bands; a DEM has one. Name the elevation "
                        f"band with band=N (1..{src.count}), e.g. read_geotiff(path, band=1)"
                    )
                band = 1
            is_int = isinstance(band, (int, np.integer)) and not isinstance(band, bool)
            if not is_int or not 1 <= band <= src.count:
                raise InvalidParameterError(f"band must be an integer in 1..{src.count}, got {band!r}")
            transform, crs, shape = src.transform, src.crs, (src.height, src.width)
            units = (src.units[band - 1] or "").strip().lower()
            scale, offset = src.scales[band - 1], src.offsets[band - 1]
            data = src.read(band, masked=True)
    except rasterio.errors.RasterioError as exc:
        raise FileFormatError(f"cannot read {str(path)!r} as a raster: {exc}") from exc

    where = f"GeoTIFF {str(path)!r}"
    if transform.b != 0 or transform.d != 0:
        raise FileFormatError(
            f"{where} has a rotated or sheared transform {tuple(transform)[:6]!r}; "
            "warp it to a north-up grid first (e.g. gdalwarp)"
        )
    width_m, height_m = abs(transform.a), abs(transform.e)
    if not np.isclose(width_m, height_m, rtol=1e-6):
        raise FileFormatError(
            f"{where} has non-square pixels of {width_m!r} x {height_m!r} (CRS units); "
            "resample it to square pixels first (e.g. gdalwarp -tr)"
        )
    if crs is not None and (crs.is_geographic or crs.linear_units_factor[1] != 1.0):
        raise FileFormatError(
            f"{where} uses CRS {crs.to_string()!r} whose units are not metres; reproject it to a "
            "projected CRS in metres (e.g. UTM) first"
        )
    if units not in _METRE_UNITS:
        raise FileFormatError(f"{where} band {band} has vertical units {units!r}; expected metres")
    if crs is None and not _CELL_RANGE_M[0] <= width_m <= _CELL_RANGE_M[1]:
        raise UnitError(
            f"{where} has no CRS and cells of {fmt_number(width_m)}; that is implausible as metres "
            f"(expected {fmt_number(_CELL_RANGE_M[0])} to {fmt_number(_CELL_RANGE_M[1])} m) and looks like "
            "degrees: reproject it to a projected CRS in metres (e.g. UTM) first"
        )

    values = np.ma.getdata(data).astype(np.float64) * scale + offset
    invalid = np.ma.getmaskarray(data) | ~np.isfinite(values)
    n_bad = int(np.count_nonzero(invalid))
    if n_bad == invalid.size:
        raise InvalidParameterError(f"{where} band {band} holds no valid cell (all {n_bad} are nodata)")
    if n_bad and fill_nodata is None:
        raise NodataError(
            f"{where} band {band} has {n_bad} nodata/NaN cells of {invalid.size}; pass "
            "fill_nodata='nearest' to fill them from the nearest valid cell",
            n_nodata=n_bad,
            n_cells=int(invalid.size),
        )
    if n_bad:
        nearest = ndimage.distance_transform_edt(invalid, return_distances=False, return_indices=True)
        values = values[tuple(nearest)]
        message = f"filled {n_bad} nodata cells of {where} from their nearest valid cells"
        logger.info(message)
        warnings.warn(message, DataRepairWarning, stacklevel=2)

    if transform.e < 0:  # north-up: file row 0 is the northern edge
        values = values[::-1]
    if transform.a < 0:  # east-left: file column 0 is the eastern edge
        values = values[:, ::-1]
    rows, cols = shape
    xmin = min(transform.c, transform.c + transform.a * cols)
    ymin = min(transform.f, transform.f + transform.e * rows)
    tmap = TerrainMap(values, width_m, (xmin, ymin), crs=None if crs is None else crs.to_string())
    steep = float(np.mean(tmap.slope_rad > _STEEP_RAD))
    if steep > 0.5:
        warnings.warn(
            f"{where} band {band}: {100 * steep:.0f} % of the cells are steeper than 60 degrees; is it really "
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
    rasterio = _rasterio()
    path = Path(path)
    if path.suffix.lower() not in (".tif", ".tiff"):
        raise InvalidParameterError(f"GeoTIFF files end in '.tif' or '.tiff', got {str(path)!r}")
    data = tmap[layer]
    if data.dtype == bool:
        data = data.astype(np.uint8)
    xmin, _, _, ymax = tmap.bounds
    profile: dict[str, Any] = {
        "driver": "GTiff",
        "height": tmap.shape[0],
        "width": tmap.shape[1],
        "count": 1,
        "dtype": data.dtype.name,
        "transform": rasterio.Affine(tmap.cell_size_m, 0.0, xmin, 0.0, -tmap.cell_size_m, ymax),
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
