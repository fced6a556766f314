"""Reproject a DEM band to a projected CRS in metres (rasterio.warp): the local UTM zone or a named CRS."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_real, check_text, fmt_number
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from .georef import DemBand, check_metric_crs, import_rasterio, parse_crs, transform_xy, utm_crs

__all__ = ["WarpedDem", "RESAMPLING_METHODS", "target_crs", "warp_band"]

#: Resampling methods :func:`warp_band` accepts (names of ``rasterio.enums.Resampling``).
RESAMPLING_METHODS = ("bilinear", "cubic", "nearest", "average")


@dataclass(frozen=True)
class WarpedDem:
    """A DEM band reprojected onto a north-up grid of square cells in metres.

    Attributes
    ----------
    values : ndarray of float64, shape (rows, cols)
        Elevation (m), north-up (row 0 the northern edge); NaN where the source has nodata
        or no data at all.
    footprint : ndarray of bool
        Cells the source raster covers (outside it, a warped rectangle leaves corners empty).
    transform : affine.Affine
        North-up transform of ``values``.
    crs : str
        The target CRS.
    source_crs : str
        The source raster's CRS.
    """

    values: np.ndarray
    footprint: np.ndarray
    transform: Any
    crs: str
    source_crs: str


def target_crs(src_crs: Any, bounds: tuple[float, float, float, float], to: str) -> Any:
    """The CRS a DEM is reprojected to: ``"utm"`` (the WGS 84 UTM zone of the DEM's centre) or a named CRS.

    Raises
    ------
    InvalidParameterError
        ``to`` empty, not understood, or not a projected CRS in metres.
    """
    check_text("reproject_to", to)
    if to.strip().lower() == "utm":
        left, bottom, right, top = bounds
        centre = transform_xy([[(left + right) / 2, (bottom + top) / 2]], src_crs, "EPSG:4326")[0]
        return parse_crs(utm_crs(float(centre[0]), float(centre[1])), "reproject_to")
    return check_metric_crs(parse_crs(to, "reproject_to"), "reproject_to")


def warp_band(src: Any, info: DemBand, to: str, cell_size_m: float, resampling: str = "bilinear") -> WarpedDem:
    """Reproject band ``info.band`` of an open rasterio dataset (:func:`rasterio.warp.reproject`).

    Nodata and NaN source cells stay NaN; scale and offset are applied first.

    Parameters
    ----------
    src : rasterio dataset
        Open source raster (with a CRS).
    info : DemBand
        Its checked band (:func:`terrain.georef.dem_band` with ``allow_geographic=True``).
    to : str
        ``"utm"`` or a CRS (``"EPSG:32633"``); see :func:`target_crs`.
    cell_size_m : float
        Side of the target's square cells (m, > 0).
    resampling : str
        One of :data:`RESAMPLING_METHODS`.

    Raises
    ------
    InvalidParameterError
        A source without CRS; a bad ``cell_size_m`` or target CRS; a cell size that would
        give fewer than 2 x 2 or more than 2**31 cells.
    UnknownNameError
        An unknown resampling method.
    """
    rasterio = import_rasterio()
    from rasterio.enums import Resampling
    from rasterio.warp import calculate_default_transform, reproject

    cell = check_real("cell_size_m", cell_size_m, low=0.0, low_inclusive=False)
    if resampling not in RESAMPLING_METHODS:
        raise UnknownNameError(f"resampling must be one of {RESAMPLING_METHODS!r}, got {resampling!r}")
    if src.crs is None:
        raise InvalidParameterError(
            "reproject_to needs a source raster with a CRS; this one has none (set it first, e.g. gdal_edit -a_srs)",
            parameter="reproject_to")
    dst_crs = target_crs(src.crs, tuple(src.bounds), to)
    transform, width, height = calculate_default_transform(
        src.crs, dst_crs, src.width, src.height, *src.bounds, resolution=cell
    )
    if width < 2 or height < 2 or width * height > 2**31:
        raise InvalidParameterError(
            f"cell_size_m {fmt_number(cell)} m gives a {height} x {width} grid for this DEM; expected at least 2 x 2 and at "
            "most 2**31 cells (choose a cell size near the DEM's resolution in metres)", parameter="cell_size_m"
        )
    data = src.read(info.band, masked=True)
    values = np.ma.getdata(data).astype(np.float64) * info.scale + info.offset
    values[np.ma.getmaskarray(data) | ~np.isfinite(values)] = np.nan
    out = np.full((height, width), np.nan)
    common = {"src_transform": src.transform, "src_crs": src.crs, "dst_transform": transform, "dst_crs": dst_crs}
    try:
        reproject(values, out, src_nodata=np.nan, dst_nodata=np.nan, resampling=Resampling[resampling], **common)
        cover = np.zeros((height, width), np.uint8)
        reproject(np.ones(values.shape, np.uint8), cover, src_nodata=0, dst_nodata=0,
                  resampling=Resampling.nearest, **common)
    except rasterio.errors.RasterioError as exc:  # pragma: no cover - GDAL refusing a valid pair of CRS
        raise InvalidParameterError(f"cannot reproject to {dst_crs.to_string()!r}: {exc}") from exc
    return WarpedDem(out, cover.astype(bool), transform, dst_crs.to_string(), src.crs.to_string())
