"""Routes as GeoJSON: LineStrings with per-vertex cumulative energy, in WGS 84 when the map has a CRS."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from terrain import Grid, TerrainMap
from terrain.georef import WGS84, parse_crs, transform_xy
from terrawatt_base.atomic import check_output_path, write_json_atomic
from terrawatt_base.checks import check_text
from terrawatt_base.errors import InvalidParameterError

__all__ = ["GEOJSON_FORMAT_VERSION", "routes_geojson", "write_geojson"]

#: Version of the ``terrawatt`` member of the GeoJSON files written here.
GEOJSON_FORMAT_VERSION = 1
_LOCAL = "local map metres (x east, y north); the map has no CRS"


def _route_fields(route: Any, name: str) -> None:
    """Refuse what is not a found route (duck-typed on :class:`planner.Route`'s fields)."""
    needed = ("status", "found", "waypoints_m", "segment_energy_j", "turn_energy_j", "energy_j", "summary")
    if not all(hasattr(route, f) for f in needed):
        raise InvalidParameterError(f"{name} must be a planner.Route, got {type(route).__name__!r}")
    if not route.found:
        raise InvalidParameterError(f"{name} has status {route.status!r} and no waypoints; only found routes are written")


def _target(where: Any, crs: str | None) -> tuple[Any, str | None, str]:
    """(map CRS or None, output CRS or None for local metres, coordinate-system text)."""
    if isinstance(where, TerrainMap):
        map_crs = where.crs
    elif isinstance(where, Grid):
        map_crs = None
    else:
        raise InvalidParameterError(f"where must be a TerrainMap or a Grid, got {type(where).__name__!r}")
    if crs is not None:
        check_text("crs", crs)
    if map_crs is None:
        if crs not in (None, "map"):
            raise InvalidParameterError(
                f"crs={crs!r} needs a map with a CRS; this one has none (its routes are written in local metres)"
            )
        return None, None, _LOCAL
    if crs == "map":
        return map_crs, map_crs, f"the map's CRS {map_crs} (x, y in its units)"
    out = parse_crs(WGS84 if crs is None else crs, "crs").to_string()
    text = "WGS 84 longitude, latitude (degrees)" if out == WGS84 else f"CRS {out}"
    return map_crs, out, text


def routes_geojson(
    routes: Any | Sequence[Any] | Mapping[str, Any],
    where: TerrainMap | Grid,
    *,
    crs: str | None = None,
) -> dict[str, Any]:
    """A GeoJSON FeatureCollection of routes, one LineString Feature each.

    Each feature's properties carry the route's summary (status, planner, J, Wh, mAh, m,
    s), ``cumulative_energy_j`` per vertex (segments and turns spent on leaving it; the
    last equals ``energy_j``), ``segment_energy_j`` per segment, ``turn_energy_j`` per
    vertex, the vertices in map metres (``waypoints_m``) and ``coordinate_system``. On a
    :class:`TerrainMap` each coordinate carries the elevation (m) as a third value.

    Parameters
    ----------
    routes : Route, sequence of Route, or mapping of name to Route
        Found routes (``exact`` or ``approximate``); names default to ``route_<i>``.
    where : TerrainMap or Grid
        The map the routes were planned on (a Grid has no CRS).
    crs : str, optional
        Coordinates' CRS. Default: WGS 84 longitude / latitude (RFC 7946) when the map has
        a CRS, the map's local metres otherwise (said in ``coordinate_system``). ``"map"``
        keeps the map's own CRS; any other CRS (``"EPSG:32633"``) is transformed to. A
        non-WGS 84 output names its CRS in the (pre-RFC 7946) ``crs`` member that GDAL and
        QGIS read.

    Returns
    -------
    dict
        The FeatureCollection (JSON-ready) with a ``terrawatt`` member: format version,
        map CRS, coordinate system.

    Raises
    ------
    InvalidParameterError
        Not routes, a route without waypoints, no route, ``where`` not a map or grid, a
        ``crs`` on a map without CRS, or a CRS rasterio does not understand.
    """
    if isinstance(routes, Mapping):
        named = list(routes.items())
    elif isinstance(routes, (list, tuple)):
        named = [(f"route_{i}", r) for i, r in enumerate(routes)]
    else:
        named = [("route_0", routes)]
    if not named:
        raise InvalidParameterError("routes is empty; expected at least one route")
    map_crs, out_crs, text = _target(where, crs)
    features = []
    for name, route in named:
        check_text("route name", name)
        _route_fields(route, f"route {name!r}")
        wp = np.asarray(route.waypoints_m, dtype=float)
        xy = wp if out_crs is None or out_crs == map_crs else transform_xy(wp, map_crs, out_crs)
        if not np.all(np.isfinite(xy)):
            raise InvalidParameterError(
                f"route {name!r} leaves the domain of the output CRS {text!r}: a waypoint has no coordinates there; "
                "write it in the map's CRS or in WGS 84"
            )
        coords = xy.tolist()
        if isinstance(where, TerrainMap):
            z = np.atleast_1d(where.sample("elevation", wp[:, 0], wp[:, 1], method="bilinear"))
            coords = [[*p, float(h)] for p, h in zip(coords, z.tolist(), strict=True)]
        seg = np.asarray(route.segment_energy_j, float)
        turn = np.asarray(route.turn_energy_j, float)
        cumulative = np.cumsum(turn) + np.concatenate([[0.0], np.cumsum(seg)])
        properties = {
            "name": name,
            **route.summary(),
            "cumulative_energy_j": cumulative.tolist(),
            "segment_energy_j": seg.tolist(),
            "turn_energy_j": turn.tolist(),
            "waypoints_m": wp.tolist(),
            "coordinate_system": text,
        }
        features.append({"type": "Feature", "geometry": {"type": "LineString", "coordinates": coords},
                         "properties": properties})
    collection: dict[str, Any] = {
        "type": "FeatureCollection",
        "features": features,
        "terrawatt": {"format_version": GEOJSON_FORMAT_VERSION, "map_crs": map_crs, "coordinate_system": text},
    }
    if out_crs is not None and out_crs != WGS84:
        collection["crs"] = {"type": "name", "properties": {"name": out_crs}}
    return collection


def write_geojson(
    routes: Any | Sequence[Any] | Mapping[str, Any],
    where: TerrainMap | Grid,
    path: str | os.PathLike[str],
    *,
    crs: str | None = None,
) -> Path:
    """Write :func:`routes_geojson` to ``path`` (``.geojson`` or ``.json``), atomically.

    Raises
    ------
    InvalidParameterError
        As :func:`routes_geojson`; another suffix; ``path`` a folder (checked first).
    """
    target = check_output_path(path, "path")
    if target.suffix.lower() not in (".geojson", ".json"):
        raise InvalidParameterError(f"GeoJSON files end in '.geojson' or '.json', got {str(target)!r}")
    return write_json_atomic(target, routes_geojson(routes, where, crs=crs))
