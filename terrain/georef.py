"""Raster georeferencing shared by the GeoTIFF readers: rasterio on demand, DEM band checks, CRS transforms."""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np

from terrawatt_base.checks import check_text, fmt_number, real_array
from terrawatt_base.errors import FileFormatError, InvalidParameterError, OptionalDependencyError, UnitError

__all__ = [
    "import_rasterio",
    "DemBand",
    "dem_band",
    "check_metric_crs",
    "parse_crs",
    "utm_crs",
    "transform_xy",
    "lonlat_to_xy",
    "xy_to_lonlat",
    "lonlat_bounds",
    "WGS84",
    "METRE_UNITS",
    "REPROJECT_ADVICE",
    "REPROJECT_PARAMETERS",
]

#: The CRS of GeoJSON coordinates (longitude, latitude in degrees).
WGS84 = "EPSG:4326"
#: Vertical units read as metres (lower case; empty: undeclared).
METRE_UNITS = ("", "m", "metre", "metres", "meter", "meters")
#: Cell sizes (m) plausible for a DEM without a CRS: outside, the unit is likely degrees.
_CELL_RANGE_M = (0.01, 10_000.0)
#: How to reproject a geographic DEM, for messages; their errors carry :data:`REPROJECT_PARAMETERS`.
REPROJECT_ADVICE = "read it with reproject_to utm (or EPSG:N) and cell_size_m M"
#: The parameters :data:`REPROJECT_ADVICE` names (the errors' :attr:`~terrawatt_base.errors.TerrawattError.parameter`).
REPROJECT_PARAMETERS = ("reproject_to", "cell_size_m")


def import_rasterio() -> ModuleType:
    """Import rasterio lazily, pointing at the ``geo`` extra when it is missing.

    Raises
    ------
    OptionalDependencyError
        rasterio is not installed.
    """
    try:
        import rasterio
        import rasterio.warp  # noqa: F401 - the submodules the readers use
        import rasterio.windows  # noqa: F401
    except ImportError as exc:
        raise OptionalDependencyError(
            "GeoTIFF support needs rasterio; install it with: pip install 'terrawatt[geo]'"
        ) from exc
    return rasterio


@dataclass(frozen=True)
class DemBand:
    """The checked georeferencing of one elevation band of an open raster.

    Attributes
    ----------
    band : int
        1-based band index.
    shape : (int, int)
        ``(rows, cols)`` of the file.
    cell_size_m : float
        Square cell side in CRS units (metres, unless ``geographic``).
    origin_xy_m : (float, float)
        Lower-left (south-west) corner.
    flip_rows, flip_cols : bool
        The file is north-up (row 0 the northern edge) / east-left: flip into TerrainMap's
        convention (row grows with y, column with x).
    scale, offset : float
        The band's value transform (``z = raw * scale + offset``).
    crs : str or None
        The CRS as a string.
    geographic : bool
        The CRS is not in metres (geographic, or projected in other units); only
        reprojection makes such a band a map.
    """

    band: int
    shape: tuple[int, int]
    cell_size_m: float
    origin_xy_m: tuple[float, float]
    flip_rows: bool
    flip_cols: bool
    scale: float
    offset: float
    crs: str | None
    geographic: bool


def dem_band(src: Any, band: int | None, where: str, *, allow_geographic: bool = False) -> DemBand:
    """Check that band ``band`` of an open rasterio dataset is a DEM TerrainMap can hold.

    Square pixels, no rotation, vertical units of metres; horizontal units of metres (a
    projected CRS, or none with a plausible cell size) unless ``allow_geographic``.

    Raises
    ------
    FileFormatError
        Several bands and no ``band``; a rotated or non-square-pixel grid; a CRS not in
        metres (unless ``allow_geographic``); vertical units other than metres.
    InvalidParameterError
        A band out of range.
    UnitError
        No CRS and a cell size implausible for metres.
    """
    if band is None:
        if src.count != 1:
            raise FileFormatError(
                f"{where} has {src.count} bands; a DEM has one. Name the elevation "
                f"band with band=N (1..{src.count}), e.g. read_geotiff(path, band=1)"
            )
        band = 1
    is_int = isinstance(band, (int, np.integer)) and not isinstance(band, bool)
    if not is_int or not 1 <= band <= src.count:
        raise InvalidParameterError(f"band must be an integer in 1..{src.count}, got {band!r}")
    band = int(band)
    kind = np.dtype(src.dtypes[band - 1]).kind if src.dtypes[band - 1] in np.sctypeDict else "c"
    if kind not in "iuf":  # complex (complex64, complex_int16...), bool, text: no elevations
        raise FileFormatError(f"{where}: band {band} holds {src.dtypes[band - 1]} values; elevations are real "
                              "numbers (integer or floating point)")
    transform, crs = src.transform, src.crs
    if transform.b != 0 or transform.d != 0:
        raise FileFormatError(
            f"{where} has a rotated or sheared transform {tuple(transform)[:6]!r}; "
            "warp it to a north-up grid first (e.g. gdalwarp)"
        )
    width, height = abs(transform.a), abs(transform.e)
    if not np.isclose(width, height, rtol=1e-6) and not allow_geographic:
        raise FileFormatError(
            f"{where} has non-square pixels of {width!r} x {height!r} (CRS units); "
            "resample it to square pixels first (e.g. gdalwarp -tr)"
        )
    geographic = crs is not None and (crs.is_geographic or crs.linear_units_factor[1] != 1.0)
    if geographic and not allow_geographic:
        raise FileFormatError(
            f"{where} uses CRS {crs.to_string()!r} whose units are not metres; reproject it to a "
            f"projected CRS in metres (e.g. UTM): {REPROJECT_ADVICE}", parameter=REPROJECT_PARAMETERS
        )
    units = (src.units[band - 1] or "").strip().lower()
    if units not in METRE_UNITS:
        raise FileFormatError(f"{where} band {band} has vertical units {units!r}; expected metres")
    if crs is None and not _CELL_RANGE_M[0] <= width <= _CELL_RANGE_M[1]:
        raise UnitError(
            f"{where} has no CRS and cells of {fmt_number(width)}; that is implausible as metres "
            f"(expected {fmt_number(_CELL_RANGE_M[0])} to {fmt_number(_CELL_RANGE_M[1])} m) and looks like "
            "degrees: reproject it to a projected CRS in metres (e.g. UTM) first"
        )
    rows, cols = src.height, src.width
    xmin = min(transform.c, transform.c + transform.a * cols)
    ymin = min(transform.f, transform.f + transform.e * rows)
    return DemBand(
        band=band,
        shape=(rows, cols),
        cell_size_m=float(width),
        origin_xy_m=(float(xmin), float(ymin)),
        flip_rows=transform.e < 0,
        flip_cols=transform.a < 0,
        scale=float(src.scales[band - 1]),
        offset=float(src.offsets[band - 1]),
        crs=None if crs is None else crs.to_string(),
        geographic=bool(geographic),
    )


def parse_crs(value: Any, name: str = "crs") -> Any:
    """A ``rasterio.crs.CRS`` from a user string (``"EPSG:32633"``, WKT, PROJ).

    Raises
    ------
    InvalidParameterError
        Not a non-empty string, or a CRS rasterio does not understand.
    """
    rasterio = import_rasterio()
    check_text(name, value)
    try:
        return rasterio.crs.CRS.from_user_input(value)
    except rasterio.errors.CRSError as exc:
        raise InvalidParameterError(f"{name} {value!r} is not a CRS rasterio understands: {exc}",
                                    parameter=name) from exc


def check_metric_crs(crs: Any, name: str) -> Any:
    """``crs`` (a rasterio CRS) if it is projected in metres, else an error naming ``name``."""
    if crs.is_geographic or crs.linear_units_factor[1] != 1.0:
        raise InvalidParameterError(
            f"{name} must be a projected CRS in metres (e.g. a UTM zone 'EPSG:326NN'), got {crs.to_string()!r}",
            parameter=name)
    return crs


def utm_crs(lon_deg: float, lat_deg: float) -> str:
    """The WGS 84 UTM zone of a point, as ``"EPSG:326NN"`` (north) or ``"EPSG:327NN"`` (south).

    Examples
    --------
    >>> utm_crs(15.2, 45.0), utm_crs(-70.6, -33.4)
    ('EPSG:32633', 'EPSG:32719')
    """
    if not (math.isfinite(lon_deg) and math.isfinite(lat_deg) and -90 <= lat_deg <= 90):
        raise InvalidParameterError(f"a UTM zone needs a longitude and a latitude in degrees, got {(lon_deg, lat_deg)!r}")
    zone = int(math.floor(((lon_deg + 180.0) % 360.0) / 6.0)) + 1
    return f"EPSG:{32600 + zone if lat_deg >= 0 else 32700 + zone}"


def transform_xy(xy: Any, src_crs: Any, dst_crs: Any) -> np.ndarray:
    """Points ``(N, 2)`` from one CRS to another (:func:`rasterio.warp.transform`).

    A point the target CRS cannot express (outside a projection's domain) comes back as
    ``(nan, nan)``; callers that need every point check for it and say which.

    Raises
    ------
    InvalidParameterError
        Points not of shape ``(N, 2)`` or not finite; a CRS rasterio does not understand.
    """
    rasterio = import_rasterio()
    pts = real_array("xy", xy, ndim=2)
    if pts.shape[1] != 2:
        raise InvalidParameterError(f"xy must have shape (N, 2), got {pts.shape!r}")
    src = parse_crs(src_crs, "src_crs") if isinstance(src_crs, str) else src_crs
    dst = parse_crs(dst_crs, "dst_crs") if isinstance(dst_crs, str) else dst_crs
    if pts.shape[0] == 0:
        return pts
    try:
        xs, ys = rasterio.warp.transform(src, dst, pts[:, 0].tolist(), pts[:, 1].tolist())
    except Exception:  # noqa: BLE001 - GDAL refuses the whole batch for one point outside the projection's domain
        return np.array([_transform_one(rasterio, src, dst, p) for p in pts], dtype=float).reshape(-1, 2)
    return np.column_stack([np.asarray(xs, float), np.asarray(ys, float)])


def _transform_one(rasterio: Any, src: Any, dst: Any, point: np.ndarray) -> tuple[float, float]:
    """One point through :func:`rasterio.warp.transform`; ``(nan, nan)`` where the CRS cannot express it."""
    try:
        (x,), (y,) = rasterio.warp.transform(src, dst, [float(point[0])], [float(point[1])])
    except Exception:  # noqa: BLE001 - GDAL's CPLE errors: "Point outside of projection domain"
        return math.nan, math.nan
    return float(x), float(y)


def _require_crs(crs: Any, what: str) -> Any:
    """``crs`` as a rasterio CRS, or the error of a map that cannot take geographic points."""
    if crs is None:
        raise InvalidParameterError(
            f"{what} has no CRS, so WGS 84 longitude / latitude cannot be placed on it: give points in its metres "
            "(x, y), or use a georeferenced map (a GeoTIFF with a CRS)"
        )
    return parse_crs(crs, "crs") if isinstance(crs, str) else crs


def lonlat_to_xy(lon_deg: Any, lat_deg: Any, crs: Any, *, what: str = "the map") -> tuple[Any, Any]:
    """WGS 84 longitude / latitude (degrees) as coordinates of ``crs``: a map's ``x, y`` (m).

    A georeferenced :class:`~terrain.TerrainMap`'s metres *are* its CRS's coordinates (its
    ``origin_xy_m`` is the CRS position of its south-west corner; no local offset), so the
    result is directly a point of the map. Scalars give floats, arrays arrays.

    Parameters
    ----------
    lon_deg, lat_deg : float or array_like
        Longitude in [-180, 180], latitude in [-90, 90] (degrees, WGS 84).
    crs : str or rasterio CRS or None
        The map's CRS (``tmap.crs``); ``None`` raises.
    what : str
        How messages name the map.

    Returns
    -------
    (x, y)
        Coordinates in ``crs`` (m for a projected CRS in metres).

    Raises
    ------
    InvalidParameterError
        ``crs`` is None (a map without CRS) or not understood; coordinates not finite or out
        of range; a point the CRS cannot express (the transform gives NaN / inf).
    OptionalDependencyError
        rasterio is not installed.

    Examples
    --------
    >>> x, y = lonlat_to_xy(15.0, 45.0, "EPSG:32633")  # the central meridian of UTM zone 33
    >>> round(x, 3), round(y)
    (500000.0, 4982950)
    """
    dst = _require_crs(crs, what)
    lon, lat = np.broadcast_arrays(real_array("lon_deg", lon_deg, finite=False),
                                   real_array("lat_deg", lat_deg, finite=False))
    bad = ~(np.isfinite(lon) & np.isfinite(lat) & (np.abs(lon) <= 180.0) & (np.abs(lat) <= 90.0))
    if np.any(bad):
        i = int(np.flatnonzero(bad.ravel())[0])
        raise InvalidParameterError(
            f"longitude / latitude must be finite degrees, longitude in [-180, 180] and latitude in [-90, 90], got "
            f"({fmt_number(float(lon.ravel()[i]), 10)}, {fmt_number(float(lat.ravel()[i]), 10)})"
        )
    xy = transform_xy(np.column_stack([lon.ravel(), lat.ravel()]), WGS84, dst)
    if not np.all(np.isfinite(xy)):
        i = int(np.flatnonzero(~np.all(np.isfinite(xy), axis=1))[0])
        raise InvalidParameterError(
            f"longitude / latitude ({fmt_number(float(lon.ravel()[i]), 10)}, {fmt_number(float(lat.ravel()[i]), 10)}) "
            f"cannot be expressed in {what}'s CRS {dst.to_string()!r}"
        )
    if lon.ndim == 0:
        return float(xy[0, 0]), float(xy[0, 1])
    return xy[:, 0].reshape(lon.shape), xy[:, 1].reshape(lon.shape)


def xy_to_lonlat(x_m: Any, y_m: Any, crs: Any, *, what: str = "the map") -> tuple[Any, Any]:
    """Coordinates of ``crs`` (a map's ``x, y``) as WGS 84 longitude / latitude (degrees); the
    inverse of :func:`lonlat_to_xy`.

    Raises
    ------
    InvalidParameterError
        ``crs`` is None (a map without CRS) or not understood; coordinates not finite or outside
        the projection's domain.

    Examples
    --------
    >>> lon, lat = xy_to_lonlat(500000.0, 4982950.4, "EPSG:32633")
    >>> round(lon, 6), round(lat, 4)
    (15.0, 45.0)
    """
    src = _require_crs(crs, what)
    x, y = np.broadcast_arrays(real_array("x_m", x_m), real_array("y_m", y_m))
    ll = transform_xy(np.column_stack([x.ravel(), y.ravel()]), src, WGS84)
    if not np.all(np.isfinite(ll)):
        i = int(np.flatnonzero(~np.all(np.isfinite(ll), axis=1))[0])
        raise InvalidParameterError(
            f"point ({fmt_number(float(x.ravel()[i]), 10)}, {fmt_number(float(y.ravel()[i]), 10)}) of {what}'s CRS "
            f"{src.to_string()!r} has no longitude / latitude (outside the projection's domain)"
        )
    if x.ndim == 0:
        return float(ll[0, 0]), float(ll[0, 1])
    return ll[:, 0].reshape(x.shape), ll[:, 1].reshape(x.shape)


def lonlat_bounds(
    bounds: tuple[float, float, float, float], crs: Any, *, what: str = "the map"
) -> tuple[float, float, float, float]:
    """``(west, south, east, north)`` in degrees of a ``(xmin, ymin, xmax, ymax)`` box of ``crs``
    (:func:`rasterio.warp.transform_bounds`, edges densified: the box's curved outline is covered).

    Raises
    ------
    InvalidParameterError
        ``crs`` is None or not understood.
    """
    rasterio = import_rasterio()
    src = _require_crs(crs, what)
    west, south, east, north = rasterio.warp.transform_bounds(src, WGS84, *bounds, densify_pts=21)
    return float(west), float(south), float(east), float(north)
