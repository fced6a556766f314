"""TerrainMap: a stack of named raster layers on one georeferenced :class:`~terrain.grid.Grid`."""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.atomic import atomic_open, remove_stale_temporaries
from terrawatt_base.checks import check_int, fmt_number
from terrawatt_base.errors import (
    FileFormatError,
    GridMismatchError,
    InvalidParameterError,
    TerrawattError,
    UnitError,
    UnknownNameError,
)
from terrawatt_base.formats import read_versioned_npz

from .georef import lonlat_to_xy, xy_to_lonlat
from .grid import Grid
from .surface import SURFACE_LAYERS, surface_layers

__all__ = ["TerrainMap", "MAP_FORMAT_VERSION", "UNKNOWN_GROUND", "MAX_ABS_ELEVATION_M"]

#: Version of the ``.npz`` map format written by :meth:`TerrainMap.save`.
MAP_FORMAT_VERSION = 1
#: Ground-class value of cells whose ground is not known.
UNKNOWN_GROUND = -1
#: Largest |elevation| (m) a map accepts: 100 km, beyond the relief of any planet from its datum
#: (a larger value is a nodata placeholder or another unit).
MAX_ABS_ELEVATION_M = 1.0e5

_DERIVED = SURFACE_LAYERS
_MAP_MAGIC = "terrawatt-map"
#: The dtype kinds each standard entry of a map file may hold (what :meth:`TerrainMap.save` writes; other layers keep
#: the dtype they were given). A text or boolean entry where numbers belong is a damaged or forged file, not a value to
#: convert.
_ENTRY_KINDS = {"__cell_size_m__": ("iuf", "a real number"), "__origin_xy_m__": ("iuf", "real numbers"),
                "__crs__": ("U", "text"), "__ground_ids__": ("iu", "integers"), "__ground_names__": ("U", "text"),
                "layer:elevation": ("iuf", "real numbers (m)"), "layer:ground": ("iu", "integer class ids"),
                "layer:obstacle": ("b", "booleans")}
_NAMES = {"b": "booleans", "i": "integers", "u": "integers", "f": "real numbers", "c": "complex numbers", "U": "text",
          "S": "bytes", "V": "raw records", "M": "dates", "m": "durations"}


class TerrainMap:
    """A georeferenced grid holding named layers (elevation, ground, obstacle, ...).

    Grid convention: ``origin_xy_m`` is the lower-left (south-west) corner of cell
    ``(0, 0)``. Row index grows with ``y`` (north), column index with ``x`` (east); a
    layer array is indexed ``[row, col]``. Cell ``(r, c)`` covers
    ``x in [x0 + c*d, x0 + (c+1)*d)``, ``y in [y0 + r*d, y0 + (r+1)*d)``. GeoTIFF
    readers flip north-up rasters into this convention.

    Standard layers:

    - ``"elevation"`` (float64, m) — required, finite everywhere.
    - ``"ground"`` (int16) — ground class per cell, ``-1`` = unknown; every other value
      must have a name in :attr:`ground_names`. Defaults to all ``-1``.
    - ``"obstacle"`` (bool) — impassable cells. Defaults to all ``False``.
    - ``"slope"``, ``"aspect"``, ``"grad_x"``, ``"grad_y"`` — derived from elevation
      (read-only, recomputed when elevation changes): slope in rad, aspect as the
      downslope direction in rad counter-clockwise from +x, gradients dz/dx, dz/dy
      (dimensionless, central differences with the true cell spacing).

    Any other layer with the grid's shape may be added with ``tmap[name] = array``.

    Parameters
    ----------
    elevation_m : array_like, shape (rows, cols)
        Elevation in metres.
    cell_size_m : float
        Side of a square cell in metres (> 0).
    origin_xy_m : (float, float)
        World coordinates of the lower-left corner of cell (0, 0).
    ground : array_like of int, optional
        Ground class per cell (``-1`` unknown).
    ground_names : mapping int -> str, optional
        Name of each ground class (e.g. ``{0: "asphalt", 1: "sand"}``).
    obstacle : array_like of bool, optional
        Impassable cells.
    crs : str, optional
        Coordinate reference system (e.g. ``"EPSG:32633"``), kept as metadata.

    Raises
    ------
    InvalidParameterError
        NaN/inf elevations, non-positive cell size, empty grid, bad dtypes.
    GridMismatchError
        A layer whose shape differs from the elevation's.
    UnknownNameError
        A ground value without a name in ``ground_names``.

    Examples
    --------
    >>> import numpy as np
    >>> from terrain import TerrainMap
    >>> tmap = TerrainMap(np.zeros((4, 5)), cell_size_m=2.0, origin_xy_m=(10.0, 20.0))
    >>> tmap.shape, tmap.bounds
    ((4, 5), (10.0, 20.0, 20.0, 28.0))
    >>> tmap.rowcol(11.0, 27.9)
    (3, 0)
    """

    def __init__(
        self,
        elevation_m: Any,
        cell_size_m: float,
        origin_xy_m: tuple[float, float] = (0.0, 0.0),
        *,
        ground: Any = None,
        ground_names: Mapping[int, str] | None = None,
        obstacle: Any = None,
        crs: str | None = None,
    ) -> None:
        if np.iscomplexobj(elevation_m):
            raise InvalidParameterError("elevation_m holds complex numbers; elevations are real numbers (m)")
        try:
            elev = np.array(elevation_m, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(
                f"elevation_m must be a 2-D array of real numbers, got {type(elevation_m).__name__}"
            ) from exc
        if elev.ndim != 2 or elev.shape[0] < 2 or elev.shape[1] < 2:
            raise InvalidParameterError(
                f"elevation_m must be a 2-D array of at least 2 x 2 cells, got shape {elev.shape!r}"
            )
        self._grid = Grid((int(elev.shape[0]), int(elev.shape[1])), cell_size_m, origin_xy_m)
        self.crs = crs
        self._ground_names: dict[int, str] = {}
        self._layers: dict[str, np.ndarray] = {}
        self._derived: dict[str, np.ndarray] = {}
        if ground_names is not None:
            self.ground_names = ground_names
        self["elevation"] = elev
        self["ground"] = np.full(self.shape, UNKNOWN_GROUND, np.int16) if ground is None else ground
        self["obstacle"] = np.zeros(self.shape, bool) if obstacle is None else obstacle

    # ------------------------------------------------------------------ grid
    @classmethod
    def from_bounds(
        cls, elevation_m: Any, bounds_m: tuple[float, float, float, float], **layers: Any
    ) -> TerrainMap:
        """Build a map whose grid exactly covers ``(xmin, ymin, xmax, ymax)`` with square cells.

        Raises
        ------
        InvalidParameterError
            If the bounds do not give square cells for the elevation's shape.
        """
        elev = np.asarray(elevation_m, dtype=np.float64)
        if elev.ndim != 2:
            raise InvalidParameterError(f"elevation_m must be 2-D, got shape {elev.shape!r}")
        grid = Grid.from_bounds(elev.shape, bounds_m)
        return cls(elev, grid.cell_size_m, grid.origin_xy_m, **layers)

    @property
    def grid(self) -> Grid:
        """The map's :class:`~terrain.grid.Grid` (shape, cell size, origin)."""
        return self._grid

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)`` of the grid."""
        return self._grid.shape

    @property
    def cell_size_m(self) -> float:
        """Side of a cell in metres."""
        return self._grid.cell_size_m

    @property
    def origin_xy_m(self) -> tuple[float, float]:
        """World coordinates of the lower-left corner of cell (0, 0)."""
        return self._grid.origin_xy_m

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` in metres."""
        return self._grid.bounds

    def same_grid(self, other: TerrainMap) -> bool:
        """True when ``other`` has the same shape, cell size and origin."""
        return self._grid == other.grid

    def contains(self, x_m: Any, y_m: Any) -> np.ndarray | bool:
        """Whether world points lie inside the map bounds (scalar or array)."""
        return self._grid.contains(x_m, y_m)

    def rowcol(self, x_m: Any, y_m: Any) -> tuple[Any, Any]:
        """Cell ``(row, col)`` containing world points; points on the far edges map inside.

        Raises
        ------
        OutOfBoundsError
            If any point lies outside the map bounds (or is NaN).
        """
        return self._grid.rowcol(x_m, y_m)

    def xy(self, row: Any, col: Any) -> tuple[Any, Any]:
        """World coordinates (m) of cell centres."""
        return self._grid.xy(row, col)

    def lonlat_to_xy(self, lon_deg: Any, lat_deg: Any) -> tuple[Any, Any]:
        """World coordinates (m) of WGS 84 longitude / latitude points (scalar or array); no bounds check.

        The map's metres are its CRS's coordinates (see :func:`terrain.georef.lonlat_to_xy`).

        Raises
        ------
        InvalidParameterError
            The map has no CRS; degrees out of range or not finite.
        """
        return lonlat_to_xy(lon_deg, lat_deg, self.crs)

    def xy_to_lonlat(self, x_m: Any, y_m: Any) -> tuple[Any, Any]:
        """WGS 84 longitude / latitude (degrees) of world points (m; scalar or array).

        Raises
        ------
        InvalidParameterError
            The map has no CRS; coordinates not finite.
        """
        return xy_to_lonlat(x_m, y_m, self.crs)

    def cell_centres(self) -> tuple[np.ndarray, np.ndarray]:
        """1-D arrays of the x (per column) and y (per row) coordinates of cell centres."""
        return self._grid.cell_centres()

    # ---------------------------------------------------------------- layers
    def __getitem__(self, name: str) -> np.ndarray:
        if name in self._layers:
            return self._layers[name]
        if name in _DERIVED:
            if not self._derived:
                self._derive()
            return self._derived[name]
        raise UnknownNameError(
            f"no layer named {name!r}; layers are {sorted([*self._layers, *_DERIVED])!r}"
        )

    def __setitem__(self, name: str, value: Any) -> None:
        if name in _DERIVED:
            raise InvalidParameterError(
                f"layer {name!r} is derived from elevation and read-only; set 'elevation' instead"
            )
        arr = np.array(value, copy=True)
        if arr.shape != self.shape:
            raise GridMismatchError(
                f"layer {name!r} has shape {arr.shape!r}; this map's grid is {self.shape!r}"
            )
        if name == "elevation":
            if np.iscomplexobj(arr) or arr.dtype.kind not in "biuf":
                raise InvalidParameterError(f"elevation must hold real numbers (m), got dtype {arr.dtype}")
            arr = arr.astype(np.float64)
            if not np.all(np.isfinite(arr)):
                n_bad = int(np.count_nonzero(~np.isfinite(arr)))
                raise InvalidParameterError(
                    f"elevation has {n_bad} NaN/inf cells; fill nodata before building a TerrainMap"
                )
            if float(np.max(np.abs(arr))) > MAX_ABS_ELEVATION_M:
                raise UnitError(
                    f"elevation reaches {fmt_number(float(np.max(np.abs(arr))))} m, beyond the "
                    f"{MAX_ABS_ELEVATION_M:g} m of any planetary relief: not elevations in metres (a nodata "
                    "placeholder? millimetres?)"
                )
            self._derived = {}
        elif name == "ground":
            if not (np.issubdtype(arr.dtype, np.integer) or arr.dtype == bool):
                if not np.all(np.isfinite(arr)) or np.any(arr != np.round(arr)):
                    raise InvalidParameterError(
                        f"ground layer must hold integer class ids, got dtype {arr.dtype}"
                    )
            if arr.size and (arr.min() < UNKNOWN_GROUND or arr.max() > np.iinfo(np.int16).max):
                raise InvalidParameterError(
                    f"ground layer holds class ids in [{int(arr.min())}, {int(arr.max())}]; expected ids in "
                    f"[0, {np.iinfo(np.int16).max}] or {UNKNOWN_GROUND} for unknown ground"
                )
            arr = arr.astype(np.int16)
            self._check_ground(arr)
        elif name == "obstacle":
            if arr.dtype != bool:
                if not np.all(np.isin(arr, (0, 1))):
                    raise InvalidParameterError("obstacle layer must be boolean (or 0/1)")
                arr = arr.astype(bool)
        arr.setflags(write=False)
        self._layers[name] = arr

    def __delitem__(self, name: str) -> None:
        if name in ("elevation", "ground", "obstacle"):
            raise InvalidParameterError(f"standard layer {name!r} cannot be removed")
        if name not in self._layers:
            raise UnknownNameError(f"no layer named {name!r}")
        del self._layers[name]

    def __contains__(self, name: object) -> bool:
        return name in self._layers or name in _DERIVED

    def __iter__(self) -> Iterator[str]:
        return iter(self._layers)

    def __len__(self) -> int:
        return len(self._layers)

    def keys(self) -> list[str]:
        """Names of the stored (non-derived) layers."""
        return list(self._layers)

    def __repr__(self) -> str:
        xmin, ymin, xmax, ymax = self.bounds
        return (
            f"TerrainMap(shape={self.shape}, cell_size_m={self.cell_size_m}, "
            f"bounds=({xmin:g}, {ymin:g}, {xmax:g}, {ymax:g}), layers={self.keys()}, "
            f"grounds={self._ground_names})"
        )

    @property
    def elevation_m(self) -> np.ndarray:
        """Elevation layer (m), read-only view."""
        return self._layers["elevation"]

    @property
    def ground(self) -> np.ndarray:
        """Ground-class layer (int16, -1 unknown), read-only view."""
        return self._layers["ground"]

    @property
    def obstacle(self) -> np.ndarray:
        """Obstacle layer (bool), read-only view."""
        return self._layers["obstacle"]

    @property
    def slope_rad(self) -> np.ndarray:
        """Slope magnitude (rad) per cell."""
        return self["slope"]

    @property
    def aspect_rad(self) -> np.ndarray:
        """Downslope direction (rad, counter-clockwise from +x) per cell."""
        return self["aspect"]

    @property
    def ground_names(self) -> dict[int, str]:
        """Mapping of ground class id to name (a copy)."""
        return dict(self._ground_names)

    @ground_names.setter
    def ground_names(self, names: Mapping[int, str]) -> None:
        if not isinstance(names, Mapping):
            raise InvalidParameterError(f"ground_names must be a mapping of class id to name, got {names!r}")
        clean: dict[int, str] = {}
        for key, value in names.items():
            k = check_int("ground class id", key, low=0, high=int(np.iinfo(np.int16).max))
            if not isinstance(value, str) or not value:
                raise InvalidParameterError(f"ground class {k} needs a non-empty name, got {value!r}")
            clean[k] = value
        if len(set(clean.values())) != len(clean):
            raise InvalidParameterError(f"ground names must be unique, got {clean!r}")
        if "ground" in self._layers:
            self._check_ground(self._layers["ground"], clean)
        self._ground_names = clean

    def ground_id(self, name: str) -> int:
        """Class id of the ground called ``name``."""
        for k, v in self._ground_names.items():
            if v == name:
                return k
        raise UnknownNameError(
            f"no ground class named {name!r}; known: {sorted(self._ground_names.values())!r}"
        )

    def _check_ground(self, arr: np.ndarray, names: Mapping[int, str] | None = None) -> None:
        names = self._ground_names if names is None else names
        values = np.unique(arr)
        bad = [int(v) for v in values if v != UNKNOWN_GROUND and int(v) not in names]
        if bad:
            raise UnknownNameError(
                f"ground layer holds class ids {bad!r} with no name; ground_names is {dict(names)!r} "
                f"(use {UNKNOWN_GROUND} for unknown ground)"
            )

    def _derive(self) -> None:
        for name, arr in surface_layers(self._layers["elevation"], self.cell_size_m).items():
            arr.setflags(write=False)
            self._derived[name] = arr

    def copy(self) -> TerrainMap:
        """An independent copy of the map and all its layers."""
        out = TerrainMap(
            self.elevation_m,
            self.cell_size_m,
            self._grid.origin_xy_m,
            ground=self.ground,
            ground_names=self._ground_names,
            obstacle=self.obstacle,
            crs=self.crs,
        )
        for name, arr in self._layers.items():
            if name not in out._layers:
                out[name] = arr
        return out

    # -------------------------------------------------------------- sampling
    def sample(self, name: str, x_m: Any, y_m: Any, method: str = "nearest") -> Any:
        """Value of a layer at world points.

        Parameters
        ----------
        name : str
            Layer name.
        x_m, y_m : float or array_like
            World coordinates (m).
        method : {"nearest", "bilinear"}
            ``"bilinear"`` interpolates between cell centres (float layers only) and clamps
            to the edge cells' values outside the outer ring of centres.

        Raises
        ------
        OutOfBoundsError
            If a point lies outside the map.
        UnknownNameError
            For an unknown layer or method.
        """
        layer = self[name]
        if method == "nearest":
            r, c = self.rowcol(x_m, y_m)
            return layer[r, c]
        if method != "bilinear":
            raise UnknownNameError(f"method must be 'nearest' or 'bilinear', got {method!r}")
        self.rowcol(x_m, y_m)  # bounds check
        x0, y0 = self._grid.origin_xy_m
        fc = np.clip((np.asarray(x_m, float) - x0) / self.cell_size_m - 0.5, 0, self.shape[1] - 1)
        fr = np.clip((np.asarray(y_m, float) - y0) / self.cell_size_m - 0.5, 0, self.shape[0] - 1)
        c0 = np.minimum(fc.astype(np.int64), self.shape[1] - 2)
        r0 = np.minimum(fr.astype(np.int64), self.shape[0] - 2)
        tc, tr = fc - c0, fr - r0
        v = layer.astype(float)
        out = (
            v[r0, c0] * (1 - tr) * (1 - tc)
            + v[r0, c0 + 1] * (1 - tr) * tc
            + v[r0 + 1, c0] * tr * (1 - tc)
            + v[r0 + 1, c0 + 1] * tr * tc
        )
        return float(out) if np.ndim(out) == 0 else out

    def segment_cells(
        self, start_xy_m: tuple[float, float], end_xy_m: tuple[float, float]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cells crossed by a straight segment and its exact length in each (see
        :meth:`Grid.segment_cells <terrain.grid.Grid.segment_cells>`).

        Raises
        ------
        OutOfBoundsError
            If either end lies outside the map.

        Examples
        --------
        >>> import numpy as np
        >>> from terrain import TerrainMap
        >>> tmap = TerrainMap(np.zeros((3, 3)), cell_size_m=1.0)
        >>> rows, cols, lengths = tmap.segment_cells((0.5, 0.5), (2.5, 0.5))
        >>> rows.tolist(), cols.tolist(), lengths.tolist()
        ([0, 0, 0], [0, 1, 2], [0.5, 1.0, 0.5])
        """
        return self._grid.segment_cells(start_xy_m, end_xy_m)

    def sample_segment(
        self, name: str, start_xy_m: tuple[float, float], end_xy_m: tuple[float, float]
    ) -> tuple[np.ndarray, np.ndarray]:
        """A layer's values along a straight segment, one per crossed cell, with lengths (m)."""
        rows, cols, lengths = self.segment_cells(start_xy_m, end_xy_m)
        return self[name][rows, cols], lengths

    # ----------------------------------------------------------- persistence
    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the map to a ``.npz`` file atomically (temporary file, then rename).

        The file carries a format version; :meth:`load` refuses other versions.
        """
        path = Path(path)
        if path.suffix != ".npz":
            raise InvalidParameterError(f"map files end in '.npz', got {str(path)!r}")
        payload: dict[str, np.ndarray] = {
            "__magic__": np.array(_MAP_MAGIC),
            "__version__": np.array(MAP_FORMAT_VERSION),
            "__cell_size_m__": np.array(self.cell_size_m),
            "__origin_xy_m__": np.array(self._grid.origin_xy_m),
            "__crs__": np.array("" if self.crs is None else self.crs),
            "__ground_ids__": np.array(sorted(self._ground_names), dtype=np.int64),
            "__ground_names__": np.array([self._ground_names[k] for k in sorted(self._ground_names)], dtype=str),
        }
        for name, arr in self._layers.items():
            payload[f"layer:{name}"] = arr
        with atomic_open(path, "wb") as fh:
            np.savez_compressed(fh, **payload)
        return path

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> TerrainMap:
        """Read a map written by :meth:`save`.

        Raises
        ------
        FileFormatError
            Missing, corrupt or foreign file; an entry of another kind of values than the writer's
            (text or booleans for a number, a cell size or an elevation).
        FormatVersionError
            A file of another format version.
        """
        path = Path(path)
        remove_stale_temporaries(path)
        content = read_versioned_npz(path, magic=_MAP_MAGIC, version=MAP_FORMAT_VERSION, what="map")
        for key, (kinds, expected) in _ENTRY_KINDS.items():
            arr = content.get(key)
            if arr is not None and arr.dtype.kind not in kinds:
                found = _NAMES.get(arr.dtype.kind, "values")
                raise FileFormatError(f"map file {str(path)!r}: entry {key!r} holds {found} ({arr.dtype}); expected "
                                      f"{expected}")
        try:
            names = dict(
                zip(content["__ground_ids__"].tolist(), content["__ground_names__"].tolist(), strict=True)
            )
            crs = str(content["__crs__"]) or None
            tmap = cls(
                content["layer:elevation"],
                float(content["__cell_size_m__"]),
                tuple(content["__origin_xy_m__"].tolist()),
                ground=content["layer:ground"],
                ground_names=names,
                obstacle=content["layer:obstacle"],
                crs=crs,
            )
        except KeyError as exc:
            raise FileFormatError(f"map file {str(path)!r} lacks entry {exc.args[0]!r}") from exc
        except TerrawattError:
            raise
        except (TypeError, ValueError) as exc:
            raise FileFormatError(f"map file {str(path)!r} has malformed metadata: {exc}") from exc
        for key, arr in content.items():
            if key.startswith("layer:") and key[6:] not in tmap._layers:
                tmap[key[6:]] = arr
        return tmap
