"""terrain.windows: DemWindows blocks with halo cells, and the windowed surface layers, equal to the whole map."""

from __future__ import annotations

import numpy as np
import pytest

from terrain import (
    DemWindows,
    FileFormatError,
    InvalidParameterError,
    NodataError,
    UnknownNameError,
    procedural_map,
    read_geotiff,
    write_geotiff,
)
from terrain.windows import WINDOW_LAYERS, iter_surface_windows, windowed_surface

rasterio = pytest.importorskip("rasterio", reason="GeoTIFF support needs the geo extra (rasterio)")


@pytest.fixture
def dem_path(tmp_path):
    tmap = procedural_map((41, 29), 2.0, seed=3, origin_xy_m=(100.0, 200.0))
    tmap.crs = "EPSG:32633"
    return write_geotiff(tmap, tmp_path / "dem.tif")


def test_a_block_is_the_whole_maps_cells_with_its_georeferencing(dem_path):
    whole = read_geotiff(dem_path)
    with DemWindows(dem_path) as dem:
        assert dem.grid == whole.grid and dem.crs == whole.crs and dem.shape == (41, 29)
        win = dem.read(slice(10, 20), slice(5, 12), halo=2)
    assert (win.halo_rows, win.halo_cols) == (slice(8, 22), slice(3, 14))
    assert np.array_equal(win.elevation_m, whole.elevation_m[8:22, 3:14])
    assert np.array_equal(win.elevation_m[win.crop], whole.elevation_m[10:20, 5:12])
    tmap = win.terrain_map()
    assert tmap.origin_xy_m == (100.0 + 3 * 2.0, 200.0 + 8 * 2.0) and tmap.crs == "EPSG:32633"
    # cell centres are the map's, and the layers inside the halo equal the whole map's
    assert tmap.xy(0, 0) == whole.xy(8, 3)
    for name in ("slope", "grad_x", "grad_y", "aspect"):
        assert np.array_equal(tmap[name][1:-1, 1:-1], whole[name][9:21, 4:13]), name


def test_blocks_clip_at_the_map_edges_and_tile_the_map_once(dem_path):
    seen = np.zeros((41, 29), int)
    with DemWindows(dem_path) as dem:
        corner = dem.read(slice(0, 1), slice(28, 40), halo=1)
        assert (corner.rows, corner.cols) == (slice(0, 1), slice(28, 29))
        assert (corner.halo_rows, corner.halo_cols) == (slice(0, 2), slice(27, 29))
        for win in dem.iter_blocks(8, halo=1):
            seen[win.rows, win.cols] += 1
            assert win.elevation_m[win.crop].shape == seen[win.rows, win.cols].shape
    assert np.all(seen == 1)


def test_bad_reads_are_refused(dem_path, tmp_path):
    with DemWindows(dem_path) as dem:
        with pytest.raises(InvalidParameterError, match="hold no cell"):
            dem.read(slice(50, 60), slice(0, 3))
        with pytest.raises(InvalidParameterError, match="halo"):
            dem.read(slice(0, 3), slice(0, 3), halo=-1)
        with pytest.raises(InvalidParameterError, match="window_cells"):
            next(dem.iter_blocks(1))
    with pytest.raises(FileFormatError, match="does not exist"):
        DemWindows(tmp_path / "missing.tif")
    tiny = tmp_path / "tiny.tif"
    with rasterio.open(tiny, "w", driver="GTiff", height=1, width=5, count=1, dtype="float32", crs="EPSG:32633",
                       transform=rasterio.Affine(1.0, 0.0, 0.0, 0.0, -1.0, 1.0)) as dst:
        dst.write(np.zeros((1, 5), "float32"), 1)
    with pytest.raises(InvalidParameterError, match="at least 2 x 2"):
        DemWindows(tiny)


def test_nodata_is_named_only_in_the_blocks_that_hold_it(tmp_path):
    path = tmp_path / "holed.tif"
    z = np.ones((12, 12), "float32")
    z[0, 11] = -9999.0  # file row 0 is the north edge: map row 11
    with rasterio.open(path, "w", driver="GTiff", height=12, width=12, count=1, dtype="float32", crs="EPSG:32633",
                       transform=rasterio.Affine(1.0, 0.0, 0.0, 0.0, -1.0, 12.0), nodata=-9999.0) as dst:
        dst.write(z, 1)
    with DemWindows(path) as dem:
        assert np.all(dem.read(slice(0, 6), slice(0, 6)).elevation_m == 1.0)
        with pytest.raises(NodataError, match=r"1 nodata/NaN cells in map rows 9..11, cols 9..11"):
            dem.read(slice(10, 11), slice(10, 11))


def test_window_layers_are_the_elevation_and_the_surface_layers():
    assert WINDOW_LAYERS == ("elevation", "slope", "aspect", "grad_x", "grad_y")


def test_surface_windows_tile_the_map_with_the_whole_maps_values(dem_path):
    whole = read_geotiff(dem_path)
    seen = np.zeros((41, 29), int)
    tiles = list(iter_surface_windows(dem_path, window_cells=8))
    assert len(tiles) == 6 * 4  # ceil(41 / 8) x ceil(29 / 8)
    assert (tiles[0].rows, tiles[0].cols) == (slice(0, 8), slice(0, 8))  # southern row of tiles first
    for tile in tiles:
        seen[tile.rows, tile.cols] += 1
        assert set(tile.layers) == set(WINDOW_LAYERS)
        for name in WINDOW_LAYERS:
            assert np.array_equal(tile.layers[name], whole[name][tile.rows, tile.cols]), name
    assert np.all(seen == 1)


def test_windowed_surface_equals_the_whole_map_in_memory_and_on_disk(dem_path, tmp_path):
    whole = read_geotiff(dem_path)
    in_memory = windowed_surface(dem_path, window_cells=7)
    assert set(in_memory) == set(WINDOW_LAYERS)
    for name in WINDOW_LAYERS:
        assert in_memory[name].dtype == np.float64 and np.array_equal(in_memory[name], whole[name]), name
    on_disk = windowed_surface(dem_path, window_cells=16, layers=("slope",), out_dir=tmp_path / "layers")
    assert list(on_disk) == ["slope"] and sorted(p.name for p in (tmp_path / "layers").iterdir()) == ["slope.npy"]
    assert isinstance(on_disk["slope"], np.memmap) and np.array_equal(on_disk["slope"], whole["slope"])


def test_windowed_surface_refuses_unknown_or_no_layers_and_a_tiny_window(dem_path):
    with pytest.raises(UnknownNameError, match="layers"):
        windowed_surface(dem_path, layers=("roughness",))
    with pytest.raises(InvalidParameterError, match="layers must name at least one of"):
        windowed_surface(dem_path, layers=())
    with pytest.raises(InvalidParameterError, match="window_cells"):
        next(iter_surface_windows(dem_path, window_cells=1))
