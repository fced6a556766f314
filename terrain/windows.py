"""Windowed preparation of a GeoTIFF DEM: slope, aspect and gradients tile by tile, with halo cells.

A DEM larger than memory is never read whole: :func:`iter_surface_windows` reads one tile
plus a halo of one cell (clipped at the raster's edges) with rasterio windows, derives its
layers with :func:`terrain.surface.surface_layers` — the function :class:`TerrainMap` uses —
and crops the halo. Central differences need one neighbour on each side, so every cropped
value equals the whole-map value exactly (same floating-point operations on the same
numbers); at the raster's own edges the tile's edge is the map's edge and the one-sided
differences agree too. :func:`windowed_surface` assembles the tiles into arrays (in memory,
or ``.npy`` memory maps in a folder). :class:`DemWindows` reads any block with its halo
(:class:`ElevationWindow`, a georeferenced :class:`TerrainMap` on demand), for planners that
work window by window.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from terrawatt_base.atomic import atomic_directory
from terrawatt_base.checks import check_choice, check_int
from terrawatt_base.errors import FileFormatError, InvalidParameterError, NodataError

from .georef import DemBand, dem_band, import_rasterio
from .grid import Grid
from .surface import SURFACE_LAYERS, surface_layers
from .terrain_map import TerrainMap

__all__ = ["SurfaceWindow", "WINDOW_LAYERS", "iter_surface_windows", "windowed_surface", "DemWindows", "ElevationWindow"]

#: Layers a window carries: the elevation and its surface layers.
WINDOW_LAYERS = ("elevation",) + SURFACE_LAYERS


@dataclass(frozen=True)
class SurfaceWindow:
    """One tile of a DEM in TerrainMap's convention (row 0 the southern edge).

    Attributes
    ----------
    rows, cols : slice
        Where the tile lies in the whole map's arrays.
    layers : dict of str to ndarray
        ``elevation`` (m) and the layers of :data:`terrain.surface.SURFACE_LAYERS`, halo cropped.
    """

    rows: slice
    cols: slice
    layers: dict[str, np.ndarray]


def _open(path: str | os.PathLike[str], band: int | None) -> tuple[object, DemBand, str]:
    rasterio = import_rasterio()
    p = Path(path)
    if not p.is_file():
        raise FileFormatError(f"GeoTIFF file {str(p)!r} does not exist")
    where = f"GeoTIFF {str(p)!r}"
    try:
        src = rasterio.open(p)
    except rasterio.errors.RasterioError as exc:
        raise FileFormatError(f"cannot read {str(p)!r} as a raster: {exc}") from exc
    try:
        info = dem_band(src, band, where)
    except Exception:
        src.close()
        raise
    return src, info, where


def _file_span(map_lo: int, map_hi: int, n: int, flip: bool) -> tuple[int, int]:
    """File index range of the map index range ``[map_lo, map_hi)`` along an axis of ``n`` cells."""
    return (n - map_hi, n - map_lo) if flip else (map_lo, map_hi)


@dataclass(frozen=True)
class ElevationWindow:
    """A block of a DEM's elevation with its halo cells, in TerrainMap's convention (row 0 the southern edge).

    Attributes
    ----------
    rows, cols : slice
        The block in the whole map's arrays (without halo).
    halo_rows, halo_cols : slice
        Where :attr:`elevation_m` lies in the whole map's arrays (the block grown by the halo,
        clipped at the map's edges).
    elevation_m : ndarray
        Elevation (m, float64) of the haloed block.
    cell_size_m : float
        Cell side (m).
    origin_xy_m : (float, float)
        South-west corner of the haloed block in the map's coordinates.
    crs : str or None
        The map's CRS.
    """

    rows: slice
    cols: slice
    halo_rows: slice
    halo_cols: slice
    elevation_m: np.ndarray
    cell_size_m: float
    origin_xy_m: tuple[float, float]
    crs: str | None

    @property
    def crop(self) -> tuple[slice, slice]:
        """The block inside :attr:`elevation_m` (index it to drop the halo)."""
        r0, c0 = self.rows.start - self.halo_rows.start, self.cols.start - self.halo_cols.start
        return slice(r0, r0 + self.rows.stop - self.rows.start), slice(c0, c0 + self.cols.stop - self.cols.start)

    def terrain_map(self) -> TerrainMap:
        """The haloed block as a georeferenced :class:`TerrainMap` (ground unknown, no obstacles).

        Its layers inside :attr:`crop` equal the whole map's (``read_geotiff``) exactly; only
        the halo's outer ring, where not the map's edge, differs (one-sided differences)."""
        return TerrainMap(self.elevation_m, self.cell_size_m, self.origin_xy_m, crs=self.crs)


class DemWindows:
    """An open GeoTIFF DEM read by windows (rasterio windows), never whole: a context manager.

    Parameters
    ----------
    path : str or path-like
        GeoTIFF DEM (one band, or ``band``), in metres as :func:`~terrain.read_geotiff` needs.
    band : int, optional
        1-based elevation band.

    Attributes
    ----------
    grid : Grid
        The whole map's grid (shape, cell size, south-west origin), as ``read_geotiff(path).grid``.
    crs : str or None
        The map's CRS.

    Raises
    ------
    FileFormatError, UnitError, InvalidParameterError
        As :func:`~terrain.read_geotiff` for the file, its band and georeferencing, and a
        raster under 2 x 2 cells.

    Examples
    --------
    Read the south-west 256 x 256 cells of a DEM as a georeferenced map::

        with DemWindows("dem.tif") as dem:
            win = dem.read(slice(0, 256), slice(0, 256))
            tmap = win.terrain_map()
    """

    def __init__(self, path: str | os.PathLike[str], band: int | None = None) -> None:
        self._rasterio = import_rasterio()
        self._src, self._info, self.where = _open(path, band)
        rows, cols = self._info.shape
        if rows < 2 or cols < 2:
            self._src.close()
            raise InvalidParameterError(f"{self.where} has {rows} x {cols} cells; a map needs at least 2 x 2")
        self.grid = Grid((rows, cols), self._info.cell_size_m, self._info.origin_xy_m)
        self.crs = self._info.crs

    def __enter__(self) -> DemWindows:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the file."""
        self._src.close()

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)`` of the whole map."""
        return self.grid.shape

    def read(self, rows: slice, cols: slice, *, halo: int = 1) -> ElevationWindow:
        """The elevation of map rows ``rows`` and columns ``cols`` (clipped to the map) with ``halo`` cells around.

        Raises
        ------
        InvalidParameterError
            An empty block, or ``halo`` not an integer >= 0.
        NodataError
            The haloed block holds nodata / NaN cells: windows fill nothing (a nearest-cell
            fill is not local), so fill the DEM first (e.g. gdal_fillnodata, or read it whole
            with ``fill_nodata="nearest"``).
        """
        h = check_int("halo", halo, low=0)
        n_rows, n_cols = self.shape
        r0, r1, _ = rows.indices(n_rows)
        c0, c1, _ = cols.indices(n_cols)
        if r1 <= r0 or c1 <= c0:
            raise InvalidParameterError(f"the window rows {rows!r}, cols {cols!r} hold no cell of the "
                                        f"{n_rows} x {n_cols} map")
        hr0, hr1, hc0, hc1 = max(0, r0 - h), min(n_rows, r1 + h), max(0, c0 - h), min(n_cols, c1 + h)
        info = self._info
        fr0, fr1 = _file_span(hr0, hr1, n_rows, info.flip_rows)
        fc0, fc1 = _file_span(hc0, hc1, n_cols, info.flip_cols)
        window = self._rasterio.windows.Window(fc0, fr0, fc1 - fc0, fr1 - fr0)
        data = self._src.read(info.band, window=window, masked=True)
        z = np.ma.getdata(data).astype(np.float64) * info.scale + info.offset
        bad = np.ma.getmaskarray(data) | ~np.isfinite(z)
        if bad.any():
            raise NodataError(
                f"{self.where} band {info.band} has {int(bad.sum())} nodata/NaN cells in map rows {hr0}..{hr1 - 1}, "
                f"cols {hc0}..{hc1 - 1}; windowed preparation fills nothing: fill the DEM first "
                "(gdal_fillnodata) or read it whole with fill_nodata='nearest'",
                n_nodata=int(bad.sum()),
                n_cells=int(bad.size),
            )
        if info.flip_rows:
            z = z[::-1]
        if info.flip_cols:
            z = z[:, ::-1]
        d = info.cell_size_m
        origin = (info.origin_xy_m[0] + hc0 * d, info.origin_xy_m[1] + hr0 * d)
        return ElevationWindow(slice(r0, r1), slice(c0, c1), slice(hr0, hr1), slice(hc0, hc1), z, d, origin, self.crs)

    def iter_blocks(self, window_cells: int, *, halo: int = 1) -> Iterator[ElevationWindow]:
        """Blocks of ``window_cells`` x ``window_cells`` cells (smaller at the map's far edges) at multiples of
        ``window_cells``, southern row of blocks first, each with ``halo`` cells around.

        Raises
        ------
        InvalidParameterError
            ``window_cells`` not an integer >= 2; as :meth:`read`.
        NodataError
            As :meth:`read`.
        """
        size = check_int("window_cells", window_cells, low=2)
        n_rows, n_cols = self.shape
        for r0 in range(0, n_rows, size):
            for c0 in range(0, n_cols, size):
                yield self.read(slice(r0, r0 + size), slice(c0, c0 + size), halo=halo)


def iter_surface_windows(
    path: str | os.PathLike[str], *, band: int | None = None, window_cells: int = 1024
) -> Iterator[SurfaceWindow]:
    """Tiles of a GeoTIFF DEM with their elevation, slope, aspect and gradients.

    Each tile is read with a one-cell halo (rasterio windows, :class:`DemWindows`), so memory
    holds one haloed tile at a time; the values equal those of ``read_geotiff(path)`` and its
    derived layers exactly (module docstring).

    Parameters
    ----------
    path : str or path-like
        GeoTIFF DEM (one band, or ``band``), in metres as :func:`~terrain.read_geotiff` needs.
    band : int, optional
        1-based elevation band.
    window_cells : int
        Tile side in cells (>= 2); the last tiles of a row or column may be smaller.

    Yields
    ------
    SurfaceWindow
        Tiles in map order (southern row of tiles first).

    Raises
    ------
    FileFormatError, UnitError, InvalidParameterError
        As :func:`~terrain.read_geotiff` for the file, its band and georeferencing.
    NodataError
        A tile holds nodata / NaN cells: windowed preparation fills nothing (a nearest-cell
        fill is not local), so fill the DEM first (e.g. gdal_fillnodata, or read it whole
        with ``fill_nodata="nearest"``).
    """
    size = check_int("window_cells", window_cells, low=2)
    with DemWindows(path, band) as dem:
        for win in dem.iter_blocks(size):
            z = win.elevation_m
            layers = {"elevation": z, **surface_layers(z, win.cell_size_m)}
            yield SurfaceWindow(win.rows, win.cols, {k: v[win.crop] for k, v in layers.items()})


def windowed_surface(
    path: str | os.PathLike[str],
    *,
    band: int | None = None,
    window_cells: int = 1024,
    layers: tuple[str, ...] = WINDOW_LAYERS,
    out_dir: str | os.PathLike[str] | None = None,
) -> dict[str, np.ndarray]:
    """Whole-map layers of a GeoTIFF DEM assembled from windows (:func:`iter_surface_windows`).

    Parameters
    ----------
    path, band, window_cells
        As :func:`iter_surface_windows`.
    layers : tuple of str
        Which of :data:`WINDOW_LAYERS` to keep (only those are held in memory).
    out_dir : path-like, optional
        Write each layer as ``<name>.npy`` in this folder (created) through a memory map,
        so not even the result needs to fit in memory; default: in-memory arrays.

    Returns
    -------
    dict of str to ndarray
        float64 arrays of the map's shape, rows growing with y, equal to the whole-map
        values (``read_geotiff(path)[name]``).

    Raises
    ------
    UnknownNameError
        A layer not in :data:`WINDOW_LAYERS`.
    FileFormatError, UnitError, InvalidParameterError, NodataError
        As :func:`iter_surface_windows`.
    """
    keep = tuple(check_choice("layers", name, WINDOW_LAYERS) for name in layers)
    if not keep:
        raise InvalidParameterError(f"layers must name at least one of {WINDOW_LAYERS!r}")
    if out_dir is None:
        return _fill({}, path, band, window_cells, keep, None)
    with atomic_directory(out_dir) as tmp:
        _fill({}, path, band, window_cells, keep, tmp)
    return {name: np.load(Path(out_dir) / f"{name}.npy", mmap_mode="r") for name in keep}


def _fill(out: dict[str, np.ndarray], path: str | os.PathLike[str], band: int | None, window_cells: int,
          keep: tuple[str, ...], folder: Path | None) -> dict[str, np.ndarray]:
    """Allocate ``keep`` layers (in memory, or ``.npy`` memory maps in ``folder``) and fill them tile by tile."""
    src, info, _ = _open(path, band)
    src.close()
    for name in keep:
        if folder is None:
            out[name] = np.empty(info.shape, dtype=np.float64)
        else:
            out[name] = np.lib.format.open_memmap(folder / f"{name}.npy", mode="w+", dtype=np.float64,
                                                  shape=info.shape)
    for win in iter_surface_windows(path, band=band, window_cells=window_cells):
        for name in keep:
            out[name][win.rows, win.cols] = win.layers[name]
    for arr in out.values():
        if isinstance(arr, np.memmap):
            arr.flush()
    return out
