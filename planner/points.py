"""Points as checked ``(N, 2)`` arrays: the planner's one point validator, in metres or in WGS 84 longitude / latitude."""

from __future__ import annotations

from typing import Any

import numpy as np

from terrain import DemWindows, TerrainMap
from terrain.georef import lonlat_bounds, lonlat_to_xy
from terrawatt_base.checks import fmt_number, real_array
from terrawatt_base.errors import InvalidParameterError, OutOfBoundsError

__all__ = ["as_points", "lonlat_points", "point_on_map"]


def as_points(xy: Any, name: str) -> np.ndarray:
    """``xy`` as a float64 ``(N, 2)`` array of finite coordinates (m); a single ``(2,)`` point gives N = 1.

    Raises
    ------
    InvalidParameterError
        Not numbers, another shape, or NaN / inf coordinates (the message names ``name``).
    """
    arr = real_array(name, xy, finite=False)
    if arr.ndim == 1 and arr.shape[0] == 2:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InvalidParameterError(f"{name} must have shape (N, 2) (x_m, y_m), got shape {arr.shape!r}")
    if not np.all(np.isfinite(arr)):
        bad = arr[~np.all(np.isfinite(arr), axis=1)][0]
        raise InvalidParameterError(f"{name} must be finite coordinates in metres, got {tuple(bad.tolist())!r}")
    return arr


def lonlat_points(lonlat: Any, where: TerrainMap | DemWindows, name: str) -> np.ndarray:
    """WGS 84 ``(lon, lat)`` points (degrees; ``(2,)`` or ``(N, 2)``) as the map's ``(N, 2)`` metres, each on the map.

    The map's metres are its CRS's coordinates (:meth:`terrain.TerrainMap.lonlat_to_xy`).

    Parameters
    ----------
    lonlat : array_like
        Longitude, latitude pairs in degrees.
    where : TerrainMap or DemWindows
        The georeferenced map (its ``crs`` and ``grid``).
    name : str
        How messages name the points: the caller's parameter (``"start"``, ``"start_lonlat"``), which the errors
        carry (:attr:`~terrawatt_base.errors.TerrawattError.parameter`).

    Returns
    -------
    ndarray of float64, shape (N, 2)
        ``(x_m, y_m)`` per point.

    Raises
    ------
    InvalidParameterError
        Another shape, NaN / inf or out-of-range degrees; a map without CRS.
    OutOfBoundsError
        A point off the map; the message gives it in both forms (lon / lat and the map's
        x / y metres) with the map's bounds in both.

    Examples
    --------
    >>> import numpy as np
    >>> from terrain import TerrainMap
    >>> tmap = TerrainMap(np.zeros((4, 4)), 30.0, (500000.0, 4982900.0), crs="EPSG:32633")
    >>> lonlat_points((15.0, 45.0), tmap, "start").round(1).tolist()
    [[500000.0, 4982950.4]]
    """
    arr = real_array(name, lonlat, finite=False)
    if arr.ndim == 1 and arr.shape[0] == 2:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InvalidParameterError(f"{name} must have shape (N, 2) (lon_deg, lat_deg), got shape {arr.shape!r}",
                                    parameter=name)
    x, y = lonlat_to_xy(arr[:, 0], arr[:, 1], where.crs)
    xy = np.column_stack([x, y])
    inside = np.asarray(where.grid.contains(xy[:, 0], xy[:, 1]))
    if not np.all(inside):
        i = int(np.flatnonzero(~inside)[0])
        west, south, east, north = lonlat_bounds(where.grid.bounds, where.crs)
        box = ", ".join(fmt_number(float(b), 10) for b in where.grid.bounds)
        raise OutOfBoundsError(
            f"{name} (lon {fmt_number(float(arr[i, 0]), 10)}, lat {fmt_number(float(arr[i, 1]), 10)}) is "
            f"({fmt_number(float(xy[i, 0]), 10)}, {fmt_number(float(xy[i, 1]), 10)}) m in the map's CRS {where.crs}, "
            f"outside the map bounds ({box}) m, which span lon {fmt_number(west, 8)} to {fmt_number(east, 8)}, "
            f"lat {fmt_number(south, 8)} to {fmt_number(north, 8)}", parameter=name
        )
    return xy


def point_on_map(
    xy_m: Any, lonlat: Any, where: TerrainMap | DemWindows, *, names: tuple[str, str] = ("xy_m", "lonlat")
) -> tuple[float, float] | None:
    """One point given either in the map's metres or in WGS 84 degrees, as the map's ``(x_m, y_m)``.

    Parameters
    ----------
    xy_m : (float, float) or None
        The point in the map's metres.
    lonlat : (float, float) or None
        The point as longitude and latitude (degrees), placed by the map's CRS (:func:`lonlat_points`).
    where : TerrainMap or DemWindows
        The map.
    names : (str, str)
        How messages name ``xy_m`` and ``lonlat``: the caller's own parameters (e.g. ``("start",
        "start_lonlat")``), which the errors carry (:attr:`~terrawatt_base.errors.TerrawattError.parameter`).

    Returns
    -------
    (float, float) or None
        The point; None when neither is given.

    Raises
    ------
    InvalidParameterError
        Both given; not two finite coordinates; degrees on a map without CRS or out of range.
    OutOfBoundsError
        Degrees off the map (the message gives the point and the bounds in both forms).

    Examples
    --------
    >>> from terrain import flat_map
    >>> point_on_map((1, 2), None, flat_map((4, 4), 1.0)), point_on_map(None, None, flat_map((4, 4), 1.0))
    ((1.0, 2.0), None)
    """
    if xy_m is not None and lonlat is not None:
        raise InvalidParameterError(f"give {names[0]} or {names[1]}, not both", parameter=tuple(names))
    if lonlat is not None:
        x, y = lonlat_points(lonlat, where, names[1])[0].tolist()
        return x, y
    if xy_m is None:
        return None
    arr = real_array(names[0], xy_m, finite=False).ravel()
    if arr.shape != (2,) or not np.all(np.isfinite(arr)):
        raise InvalidParameterError(f"{names[0]} must be two finite coordinates (m), got {arr.tolist()!r}",
                                    parameter=names[0])
    return float(arr[0]), float(arr[1])
