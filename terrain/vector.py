"""Rasterise shapely polygons and GeoJSON features into TerrainMap layers."""

from __future__ import annotations

import json
import logging
import os
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from terrawatt_base.errors import (
    FileFormatError,
    InvalidParameterError,
    TerrawattWarning,
    UnknownNameError,
)

from .terrain_map import TerrainMap

__all__ = [
    "rasterize_polygons",
    "set_ground_from_polygons",
    "set_obstacles_from_polygons",
    "read_geojson",
    "apply_geojson",
]

logger = logging.getLogger(__name__)

_POLYGONAL = ("Polygon", "MultiPolygon")


def _as_geometries(geoms: Any, name: str = "geoms") -> list[BaseGeometry]:
    """One polygonal geometry or a sequence of them, as a list; anything else raises."""
    items = [geoms] if isinstance(geoms, BaseGeometry) else geoms
    try:
        items = list(items)
    except TypeError:
        raise InvalidParameterError(
            f"{name} must be a shapely (Multi)Polygon or a sequence of them, got {geoms!r}"
        ) from None
    for i, geom in enumerate(items):
        if not isinstance(geom, BaseGeometry) or geom.geom_type not in _POLYGONAL:
            kind = geom.geom_type if isinstance(geom, BaseGeometry) else type(geom).__name__
            raise InvalidParameterError(
                f"{name}[{i}] is a {kind}; expected a Polygon or MultiPolygon "
                "(buffer points and lines into polygons first, e.g. line.buffer(width_m / 2))"
            )
        if not geom.is_valid:
            raise InvalidParameterError(
                f"{name}[{i}] is not a valid polygon ({shapely.is_valid_reason(geom)}); "
                "repair it first, e.g. with shapely.make_valid"
            )
    return items


def rasterize_polygons(
    tmap: TerrainMap,
    geoms: BaseGeometry | Sequence[BaseGeometry],
    values: Any = True,
    *,
    fill: Any = None,
    dtype: Any = None,
) -> np.ndarray:
    """Burn polygons into a new array on the map's grid (cell-centre-in-polygon rule).

    A cell takes a polygon's value when its centre lies inside the polygon or on its
    boundary; where polygons overlap, the later one wins. Geometries are in the map's
    world coordinates (m). Each polygon is tested against the cell centres inside its
    bounding box in one vectorised call (``shapely.intersects_xy`` on a prepared
    geometry).

    Parameters
    ----------
    tmap : TerrainMap
        Map whose grid is used.
    geoms : Polygon, MultiPolygon or sequence of them
        Valid polygonal geometries.
    values : scalar or sequence
        Value burnt for each geometry (one scalar for all, or one per geometry).
    fill : scalar, optional
        Value of cells covered by no polygon; default zero (``False`` for bool).
    dtype : numpy dtype, optional
        dtype of the result; defaults to the dtype of ``values``.

    Returns
    -------
    ndarray, shape ``tmap.shape``

    Raises
    ------
    InvalidParameterError
        A geometry that is not a valid (Multi)Polygon, or ``values`` of the wrong length.

    Warns
    -----
    TerrawattWarning
        When some geometries cover no cell centre (often a sign of another CRS).

    Examples
    --------
    >>> from shapely import box
    >>> from terrain import flat_map, rasterize_polygons
    >>> tmap = flat_map((3, 4), cell_size_m=1.0)
    >>> rasterize_polygons(tmap, box(1.0, 0.0, 3.0, 2.0)).astype(int)
    array([[0, 1, 1, 0],
           [0, 1, 1, 0],
           [0, 0, 0, 0]])
    >>> rasterize_polygons(tmap, [box(0, 0, 4, 3), box(2, 1, 4, 3)], [1, 7], fill=-1)
    array([[1, 1, 1, 1],
           [1, 1, 7, 7],
           [1, 1, 7, 7]])
    """
    items = _as_geometries(geoms)
    vals = np.asarray(values)
    if vals.ndim == 0:
        vals = np.broadcast_to(vals, (len(items),))
    elif vals.shape != (len(items),):
        raise InvalidParameterError(
            f"values must be a scalar or have one entry per geometry ({len(items)}), "
            f"got shape {vals.shape!r}"
        )
    if not (np.issubdtype(vals.dtype, np.number) or vals.dtype == bool):
        raise InvalidParameterError(f"values must be numbers or booleans, got dtype {vals.dtype}")
    out_dtype = np.dtype(vals.dtype if dtype is None else dtype)
    out = np.zeros(tmap.shape, out_dtype) if fill is None else np.full(tmap.shape, fill, out_dtype)
    xs, ys = tmap.cell_centres()
    missed = 0
    for geom, value in zip(items, vals, strict=True):
        xmin, ymin, xmax, ymax = geom.bounds if not geom.is_empty else (np.inf, np.inf, -np.inf, -np.inf)
        c0, c1 = np.searchsorted(xs, xmin, "left"), np.searchsorted(xs, xmax, "right")
        r0, r1 = np.searchsorted(ys, ymin, "left"), np.searchsorted(ys, ymax, "right")
        inside = np.zeros((0, 0), bool)
        if c0 < c1 and r0 < r1:
            was_prepared = shapely.is_prepared(geom)
            shapely.prepare(geom)
            inside = shapely.intersects_xy(geom, xs[None, c0:c1], ys[r0:r1, None])
            if not was_prepared:
                shapely.destroy_prepared(geom)
            out[r0:r1, c0:c1][inside] = value
        missed += not inside.any()
    if missed:
        warnings.warn(
            f"{missed} of {len(items)} geometries cover no cell centre of the map (bounds "
            f"{tmap.bounds!r}); are they in the map's coordinates?",
            TerrawattWarning,
            stacklevel=2,
        )
    return out


def _ground_ids(tmap: TerrainMap, names: Sequence[str], add_names: bool) -> tuple[list[int], dict[int, str]]:
    """Class ids for ``names`` and the (possibly extended) ground-name table."""
    table = tmap.ground_names
    by_name = {v: k for k, v in table.items()}
    ids = []
    for name in names:
        if not isinstance(name, str) or not name:
            raise InvalidParameterError(f"ground names must be non-empty strings, got {name!r}")
        if name not in by_name:
            if not add_names:
                raise UnknownNameError(
                    f"ground {name!r} is not one of the map's grounds {sorted(by_name)!r}; "
                    "pass add_names=True to add it"
                )
            new_id = max(table, default=-1) + 1
            table[new_id] = name
            by_name[name] = new_id
            logger.info("added ground class %d %r", new_id, name)
        ids.append(by_name[name])
    return ids, table


def _with_ground(
    tmap: TerrainMap, geoms: list[BaseGeometry], names: list[str], add_names: bool
) -> TerrainMap:
    ids, table = _ground_ids(tmap, names, add_names)
    burnt = rasterize_polygons(tmap, geoms, np.array(ids, np.int16), fill=-2)
    out = tmap.copy()
    out.ground_names = table
    out["ground"] = np.where(burnt == -2, tmap.ground, burnt)
    return out


def set_ground_from_polygons(
    tmap: TerrainMap,
    polygons: Mapping[str, BaseGeometry | Sequence[BaseGeometry]],
    *,
    add_names: bool = True,
) -> TerrainMap:
    """A copy of ``tmap`` whose ground classes are set from polygons, by ground name.

    Cells whose centres no polygon covers keep their ground. Where polygons overlap, the
    later entry of ``polygons`` wins. The input map is not modified.

    Parameters
    ----------
    tmap : TerrainMap
        Source map.
    polygons : mapping of ground name to (Multi)Polygon or sequence of them
        Areas of each ground, in the map's coordinates (m).
    add_names : bool
        Give a name not yet in ``tmap.ground_names`` the next free class id (True), or
        raise (False).

    Returns
    -------
    TerrainMap
        A new map.

    Raises
    ------
    UnknownNameError
        An unknown ground name when ``add_names`` is False.
    InvalidParameterError
        Bad geometries or names.

    Examples
    --------
    >>> from shapely import box
    >>> from terrain import flat_map, set_ground_from_polygons
    >>> tmap = set_ground_from_polygons(flat_map((2, 4)), {"sand": box(2, 0, 4, 2)})
    >>> tmap.ground_names, tmap.ground.tolist()
    ({0: 'asphalt', 1: 'sand'}, [[0, 0, 1, 1], [0, 0, 1, 1]])
    """
    if not isinstance(polygons, Mapping):
        raise InvalidParameterError(
            f"polygons must map ground names to polygons, got {type(polygons).__name__}"
        )
    geoms: list[BaseGeometry] = []
    names: list[str] = []
    for name, value in polygons.items():
        items = _as_geometries(value, f"polygons[{name!r}]")
        geoms += items
        names += [name] * len(items)
    return _with_ground(tmap, geoms, names, add_names)


def set_obstacles_from_polygons(
    tmap: TerrainMap,
    polygons: BaseGeometry | Sequence[BaseGeometry],
    *,
    replace: bool = False,
) -> TerrainMap:
    """A copy of ``tmap`` whose cells inside the polygons are obstacles.

    Parameters
    ----------
    tmap : TerrainMap
        Source map (not modified).
    polygons : (Multi)Polygon or sequence of them
        Impassable areas in the map's coordinates (m).
    replace : bool
        Discard the map's existing obstacles (True) or add to them (False).

    Returns
    -------
    TerrainMap

    Raises
    ------
    InvalidParameterError
        Bad geometries.

    Examples
    --------
    >>> from shapely import Point
    >>> from terrain import flat_map, set_obstacles_from_polygons
    >>> tmap = set_obstacles_from_polygons(flat_map((5, 5)), Point(2.5, 2.5).buffer(1.0))
    >>> tmap.obstacle.astype(int)
    array([[0, 0, 0, 0, 0],
           [0, 0, 1, 0, 0],
           [0, 1, 1, 1, 0],
           [0, 0, 1, 0, 0],
           [0, 0, 0, 0, 0]])
    """
    mask = rasterize_polygons(tmap, polygons, True)
    out = tmap.copy()
    out["obstacle"] = mask if replace else mask | tmap.obstacle
    return out


def read_geojson(path: str | os.PathLike[str]) -> list[tuple[BaseGeometry, dict[str, Any]]]:
    """Read a GeoJSON file into ``(geometry, properties)`` pairs.

    Accepts a FeatureCollection, a single Feature or a bare geometry (whose properties
    are then empty). Coordinates are taken as they are (no reprojection): they must be in
    the map's coordinates (m), not RFC 7946 longitude/latitude.

    Parameters
    ----------
    path : str or path-like
        GeoJSON file.

    Returns
    -------
    list of (shapely geometry, dict)

    Raises
    ------
    FileFormatError
        Missing file, invalid JSON, or a member that is not valid GeoJSON (the message
        names the feature index).
    """
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError as exc:
        raise FileFormatError(f"GeoJSON file {str(path)!r} does not exist") from exc
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as exc:  # "[" * 10**5 nests too deep
        # ValueError: JSONDecodeError, and an integer past Python's 4300-digit int() limit
        raise FileFormatError(f"{str(path)!r} is not a readable JSON file: {type(exc).__name__}: {str(exc)[:200]}") from exc
    kind = doc.get("type") if isinstance(doc, dict) else None
    if kind == "FeatureCollection":
        features = doc.get("features")
        if not isinstance(features, list):
            raise FileFormatError(f"{str(path)!r}: a FeatureCollection needs a 'features' list")
    elif kind == "Feature":
        features = [doc]
    elif isinstance(kind, str):
        features = [{"type": "Feature", "geometry": doc, "properties": {}}]
    else:
        raise FileFormatError(f"{str(path)!r} is JSON but not GeoJSON (no 'type' member at the top)")
    out = []
    for i, feature in enumerate(features):
        where = f"{str(path)!r}, feature {i}"
        if not isinstance(feature, dict) or feature.get("type") != "Feature":
            raise FileFormatError(f"{where}: expected an object with type 'Feature'")
        props = feature.get("properties") or {}
        if not isinstance(props, dict) or feature.get("geometry") is None:
            raise FileFormatError(f"{where}: needs a geometry and an object (or null) of properties")
        try:
            geom = shapely.geometry.shape(feature["geometry"])
        except Exception as exc:  # shapely raises many kinds for malformed geometry
            raise FileFormatError(f"{where}: invalid geometry: {exc}") from exc
        if not geom.is_valid:
            raise FileFormatError(f"{where}: invalid geometry ({shapely.is_valid_reason(geom)})")
        out.append((geom, props))
    return out


def apply_geojson(
    tmap: TerrainMap,
    source: str | os.PathLike[str] | Sequence[tuple[BaseGeometry, Mapping[str, Any]]],
    *,
    ground_key: str = "ground",
    obstacle_key: str = "obstacle",
    add_names: bool = True,
) -> TerrainMap:
    """A copy of ``tmap`` with grounds and obstacles taken from GeoJSON features.

    Each feature must say what it is through its properties: ``{"ground": "sand"}``
    sets that ground (later features win where they overlap), ``{"obstacle": true}``
    marks an obstacle (added to the map's obstacles); a feature may carry both.
    ``{"obstacle": false}`` alone is not enough.

    Parameters
    ----------
    tmap : TerrainMap
        Source map (not modified).
    source : path or sequence of (geometry, properties)
        A GeoJSON file, or the result of :func:`read_geojson`.
    ground_key, obstacle_key : str
        Property names holding the ground name (str) and the obstacle flag (bool).
    add_names : bool
        Passed to :func:`set_ground_from_polygons`.

    Returns
    -------
    TerrainMap

    Raises
    ------
    FileFormatError
        Unreadable GeoJSON, a feature with neither property, a ground that is not a
        non-empty string, an obstacle flag that is not a boolean, or a geometry that is
        not a (Multi)Polygon.
    UnknownNameError
        An unknown ground name when ``add_names`` is False.
    """
    features = read_geojson(source) if isinstance(source, (str, os.PathLike)) else list(source)
    ground_geoms: list[BaseGeometry] = []
    ground_names: list[str] = []
    obstacle_geoms: list[BaseGeometry] = []
    for i, (geom, props) in enumerate(features):
        ground = props.get(ground_key)
        obstacle = props.get(obstacle_key, False)
        if ground is not None and (not isinstance(ground, str) or not ground):
            raise FileFormatError(f"feature {i}: {ground_key!r} must be a non-empty string, got {ground!r}")
        if not isinstance(obstacle, bool):
            raise FileFormatError(f"feature {i}: {obstacle_key!r} must be true or false, got {obstacle!r}")
        if ground is None and not obstacle:
            raise FileFormatError(
                f"feature {i} has neither a {ground_key!r} name nor {obstacle_key!r}: true "
                f"(properties {props!r})"
            )
        if not isinstance(geom, BaseGeometry) or geom.geom_type not in _POLYGONAL:
            kind = geom.geom_type if isinstance(geom, BaseGeometry) else type(geom).__name__
            raise FileFormatError(f"feature {i} is a {kind}; expected a Polygon or MultiPolygon")
        if ground is not None:
            ground_geoms.append(geom)
            ground_names.append(ground)
        if obstacle:
            obstacle_geoms.append(geom)
    out = _with_ground(tmap, ground_geoms, ground_names, add_names) if ground_geoms else tmap
    if obstacle_geoms:
        out = set_obstacles_from_polygons(out, obstacle_geoms)
    return out.copy() if out is tmap else out
