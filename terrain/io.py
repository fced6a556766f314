"""read_map: one entry point that reads a map file by its suffix (.npz, or a GeoTIFF DEM), with its options."""

from __future__ import annotations

import math
import os
from collections.abc import Collection
from pathlib import Path

from terrawatt_base.checks import fmt_number
from terrawatt_base.errors import FileFormatError, InvalidParameterError, NodataError, UnknownNameError

from .geotiff import check_fill_method, read_geotiff
from .landcover import LandcoverClasses, ground_classes_from_landcover, read_landcover_classes
from .terrain_map import TerrainMap

__all__ = ["read_map", "read_map_with_options", "MAP_SUFFIXES"]

#: The suffixes :func:`read_map` reads (case-insensitive).
MAP_SUFFIXES = (".npz", ".tif", ".tiff")


def read_map(
    path: str | os.PathLike[str],
    *,
    fill_nodata: str | None = None,
    band: int | None = None,
    reproject_to: str | None = None,
    cell_size_m: float | None = None,
) -> TerrainMap:
    """Read a map file, choosing the reader by the file's suffix.

    - ``.npz``: a map written by :meth:`TerrainMap.save` (:meth:`TerrainMap.load`).
    - ``.tif`` / ``.tiff``: a GeoTIFF DEM (:func:`~terrain.geotiff.read_geotiff`; needs the
      ``geo`` extra, rasterio).

    Parameters
    ----------
    path : str or path-like
        The map file.
    fill_nodata : {None, "nearest"}
        GeoTIFF nodata cells: ``None`` refuses them, ``"nearest"`` fills them from the nearest
        valid cell. A ``.npz`` map never holds nodata, so it has nothing to fill.
    band : int, optional
        GeoTIFF: the 1-based elevation band, required when the file has several bands.
    reproject_to, cell_size_m : optional
        GeoTIFF: reproject the DEM to ``"utm"`` (the UTM zone of its centre) or a named
        projected CRS, at ``cell_size_m`` (see :func:`~terrain.geotiff.read_geotiff`); the
        way to read a DEM in geographic coordinates.

    Returns
    -------
    TerrainMap

    Raises
    ------
    FileFormatError
        A suffix other than those in :data:`MAP_SUFFIXES` (the message lists them), and
        whatever the chosen reader raises for a missing, corrupt or unsuitable file.
    InvalidParameterError
        ``band`` or ``reproject_to`` given for a ``.npz`` map (it has no bands and is in metres).
    UnknownNameError
        An unknown ``fill_nodata`` method.
    OptionalDependencyError
        A GeoTIFF without rasterio installed.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from terrain import flat_map, read_map
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = flat_map((4, 6), 0.5).save(pathlib.Path(folder.name) / "site.npz")
    >>> read_map(path).shape
    (4, 6)
    >>> read_map(pathlib.Path(folder.name) / "site.png")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.FileFormatError: cannot read a map from '...site.png': its suffix '.png' is not one of '.npz', '.tif', '.tiff'
    >>> folder.cleanup()
    """
    check_fill_method(fill_nodata)
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in (".tif", ".tiff"):
        return read_geotiff(p, band, fill_nodata=fill_nodata, reproject_to=reproject_to, cell_size_m=cell_size_m)
    if suffix == ".npz":
        if band is not None:
            raise InvalidParameterError(f"band applies to GeoTIFF DEMs; {str(p)!r} is a .npz map, got band={band!r}")
        if reproject_to is not None or cell_size_m is not None:
            raise InvalidParameterError(
                f"reproject_to and cell_size_m apply to GeoTIFF DEMs; {str(p)!r} is a .npz map (already in metres)",
                parameter=("reproject_to", "cell_size_m"))
        return TerrainMap.load(p)
    raise FileFormatError(
        f"cannot read a map from {str(p)!r}: its suffix {p.suffix!r} is not one of "
        f"{', '.join(repr(s) for s in MAP_SUFFIXES)}"
    )


def read_map_with_options(
    source: str | os.PathLike[str] | TerrainMap,
    *,
    fill_nodata: str | None = None,
    reproject_to: str | None = None,
    cell_size_m: float | None = None,
    landcover: str | os.PathLike[str] | None = None,
    landcover_classes: str | os.PathLike[str] | None = None,
    known_grounds: Collection[str] | None = None,
) -> TerrainMap:
    """A map file read with its options (:func:`read_map`), then its ground classes from a land cover.

    The land-cover classes file is read (:func:`~terrain.landcover.read_landcover_classes`)
    and checked before the map, so a bad mapping fails before a long read; then the map is
    read, and its ground classes come from ``landcover``
    (:func:`~terrain.landcover.ground_classes_from_landcover`).

    Parameters
    ----------
    source : str, path-like or TerrainMap
        The map file, or a map already in memory (then only the land cover applies).
    fill_nodata, reproject_to, cell_size_m : optional
        As :func:`read_map`; ``reproject_to`` and ``cell_size_m`` go together.
    landcover, landcover_classes : path-like, optional
        A land-cover GeoTIFF and the CSV naming each code's ground; they go together.
    known_grounds : collection of str, optional
        The ground names the classes file may use (e.g. the ground presets); None accepts any.

    Returns
    -------
    TerrainMap

    Raises
    ------
    InvalidParameterError
        One of a pair without the other; ``cell_size_m`` not > 0; reading options with a map in memory.
    NodataError
        A DEM with nodata cells and no ``fill_nodata``; the message says how to fill them.
    UnknownNameError
        A classes file naming a ground not in ``known_grounds``.
    TerrawattError
        As :func:`read_map`, :func:`~terrain.landcover.read_landcover_classes` and
        :func:`~terrain.landcover.ground_classes_from_landcover`.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from terrain import flat_map
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = flat_map((4, 6), 0.5).save(pathlib.Path(folder.name) / "site.npz")
    >>> read_map_with_options(path).shape
    (4, 6)
    >>> read_map_with_options(path, cell_size_m=5.0)
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: reproject_to and cell_size_m go together: e.g. reproject_to utm cell_size_m 5 (got reproject_to None, cell_size_m 5.0)
    >>> folder.cleanup()
    """
    if (landcover is None) != (landcover_classes is None):
        raise InvalidParameterError(
            f"landcover and landcover_classes go together: the land-cover raster and the CSV naming the ground of "
            f"each of its codes (got landcover {landcover}, landcover_classes {landcover_classes})",
            parameter=("landcover", "landcover_classes"))
    classes: LandcoverClasses | None = None
    if landcover_classes is not None:
        classes = read_landcover_classes(landcover_classes)
        unknown = sorted(set(classes.ground_names) - set(known_grounds if known_grounds is not None else
                                                          classes.ground_names))
        if unknown:
            raise UnknownNameError(f"landcover_classes {Path(landcover_classes).name}: grounds {unknown!r} have no "
                                   f"preset; known grounds: {sorted(known_grounds or ())!r}",
                                   parameter="landcover_classes")
    if isinstance(source, TerrainMap):
        if fill_nodata is not None or reproject_to is not None or cell_size_m is not None:
            raise InvalidParameterError("fill_nodata, reproject_to and cell_size_m apply to a map file, not to a map "
                                        "in memory", parameter=("fill_nodata", "reproject_to", "cell_size_m"))
        tmap = source
    else:
        tmap = _read_checked(source, fill_nodata, reproject_to, cell_size_m)
    return tmap if classes is None else ground_classes_from_landcover(tmap, landcover, classes)


def _read_checked(path: str | os.PathLike[str], fill_nodata: str | None, reproject_to: str | None,
                  cell_size_m: float | None) -> TerrainMap:
    """:func:`read_map`, the options that go together checked first; its errors name the options they are about."""
    if (reproject_to is None) != (cell_size_m is None):
        raise InvalidParameterError(f"reproject_to and cell_size_m go together: e.g. reproject_to utm cell_size_m 5 "
                                    f"(got reproject_to {reproject_to}, cell_size_m {cell_size_m})",
                                    parameter=("reproject_to", "cell_size_m"))
    if cell_size_m is not None and not (math.isfinite(cell_size_m) and cell_size_m > 0):
        raise InvalidParameterError(f"cell_size_m must be a number > 0, got {fmt_number(cell_size_m)}",
                                    parameter="cell_size_m")
    try:
        return read_map(path, fill_nodata=fill_nodata, reproject_to=reproject_to, cell_size_m=cell_size_m)
    except NodataError as exc:
        raise NodataError(f"{Path(path).name} has {exc.n_nodata} nodata cells of {exc.n_cells}; give "
                          f"fill_nodata nearest to fill them from the nearest valid cell",
                          n_nodata=exc.n_nodata, n_cells=exc.n_cells, parameter="fill_nodata") from exc
