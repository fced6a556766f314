"""read_map: one entry point that reads a map file by its suffix (.npz, or a GeoTIFF DEM)."""

from __future__ import annotations

import os
from pathlib import Path

from terrawatt_base.errors import FileFormatError, InvalidParameterError
from .geotiff import check_fill_method, read_geotiff
from .terrain_map import TerrainMap

__all__ = ["read_map", "MAP_SUFFIXES"]

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
                f"reproject_to and cell_size_m apply to GeoTIFF DEMs; {str(p)!r} is a .npz map (already in metres)"
            )
        return TerrainMap.load(p)
    raise FileFormatError(
        f"cannot read a map from {str(p)!r}: its suffix {p.suffix!r} is not one of "
        f"{', '.join(repr(s) for s in MAP_SUFFIXES)}"
    )
