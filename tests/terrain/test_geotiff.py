"""Tests of terrain.geotiff: GeoTIFF round trips, orientation, nodata, unsupported grids."""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest

from terrain import (
    DataRepairWarning,
    FileFormatError,
    ImplausibleDataWarning,
    InvalidParameterError,
    OptionalDependencyError,
    TerrainMap,
    UnitError,
    UnknownNameError,
    procedural_map,
    read_geotiff,
    write_geotiff,
)


@pytest.fixture
def rasterio():
    return pytest.importorskip("rasterio")


def north_up(rasterio, west_m, north_m, xsize_m, ysize_m):
    """Transform of a north-up raster whose top-left corner is (west_m, north_m)."""
    return rasterio.Affine(xsize_m, 0.0, west_m, 0.0, -ysize_m, north_m)


def write_raw(rasterio, path, data, transform, crs="EPSG:32633", nodata=None, **extra):
    """Write ``data`` as file rows (row 0 first in the file) with the given transform."""
    profile = dict(
        driver="GTiff", height=data.shape[0], width=data.shape[1], count=1, dtype=data.dtype.name,
        transform=transform, crs=crs, nodata=nodata,
    )
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(data, 1)
        for key, value in extra.items():
            setattr(dst, key, value)
    return path


# -------------------------------------------------------------- round trips
def test_round_trip_is_exact(rasterio, tmp_path):
    tmap = procedural_map((30, 45), 2.0, seed=3, origin_xy_m=(500_000.0, 4_100_000.0))
    tmap.crs = "EPSG:32633"
    path = write_geotiff(tmap, tmp_path / "dem.tif")
    back = read_geotiff(path)
    assert back.same_grid(tmap) and back.crs == "EPSG:32633"
    np.testing.assert_array_equal(back.elevation_m, tmap.elevation_m)
    assert os.listdir(tmp_path) == ["dem.tif"]


def test_round_trip_without_crs(rasterio, tmp_path):
    tmap = procedural_map((8, 8), 0.5, seed=0)
    back = read_geotiff(write_geotiff(tmap, tmp_path / "dem.tiff"))
    assert back.crs is None and back.same_grid(tmap)


def test_north_up_file_is_flipped_so_rows_grow_with_y(rasterio, tmp_path):
    data = np.arange(12, dtype=np.float64).reshape(3, 4)  # file row 0 = north edge
    transform = north_up(rasterio, 100.0, 230.0, 10.0, 10.0)  # top-left corner
    tmap = read_geotiff(write_raw(rasterio, tmp_path / "a.tif", data, transform))
    np.testing.assert_array_equal(tmap.elevation_m, data[::-1])
    assert tmap.bounds == (100.0, 200.0, 140.0, 230.0)
    assert tmap.sample("elevation", 105.0, 225.0) == 0.0  # north-west pixel of the file
    assert tmap.sample("elevation", 135.0, 205.0) == 11.0  # south-east pixel


@pytest.mark.filterwarnings("ignore::terrawatt_base.errors.ImplausibleDataWarning")  # 1 m steps between 1 m cells
def test_south_up_and_east_left_files(rasterio, tmp_path):
    data = np.arange(6, dtype=np.float64).reshape(2, 3)
    south_up = rasterio.Affine(2.0, 0.0, 10.0, 0.0, 2.0, 20.0)  # file row 0 = south edge
    tmap = read_geotiff(write_raw(rasterio, tmp_path / "s.tif", data, south_up))
    np.testing.assert_array_equal(tmap.elevation_m, data)
    assert tmap.bounds == (10.0, 20.0, 16.0, 24.0)
    east_left = rasterio.Affine(-1.0, 0.0, 3.0, 0.0, -1.0, 2.0)  # file column 0 = east edge
    tmap = read_geotiff(write_raw(rasterio, tmp_path / "e.tif", data, east_left))
    np.testing.assert_array_equal(tmap.elevation_m, data[::-1, ::-1])
    assert tmap.bounds == (0.0, 0.0, 3.0, 2.0)


def test_band_scale_and_offset_are_applied(rasterio, tmp_path):
    data = np.array([[1, 2], [3, 4]], dtype=np.int16)
    path = write_raw(
        rasterio, tmp_path / "a.tif", data, north_up(rasterio, 0, 2, 1, 1), scales=(0.5,), offsets=(100.0,)
    )
    np.testing.assert_array_equal(read_geotiff(path).elevation_m, 100.0 + 0.5 * data[::-1])


def test_write_other_layers(rasterio, tmp_path, wall_map):
    wall_map.crs = "EPSG:32633"
    with rasterio.open(write_geotiff(wall_map, tmp_path / "o.tif", layer="obstacle")) as src:
        assert src.dtypes[0] == "uint8"
        np.testing.assert_array_equal(src.read(1)[::-1], wall_map.obstacle.astype(np.uint8))
    with rasterio.open(write_geotiff(wall_map, tmp_path / "g.tif", layer="ground")) as src:
        assert src.nodata == -1 and src.dtypes[0] == "int16"
    slope = read_geotiff(write_geotiff(wall_map, tmp_path / "s.tif", layer="slope"))
    np.testing.assert_array_equal(slope.elevation_m, wall_map.slope_rad)


def test_write_errors(rasterio, tmp_path, flat_map):
    with pytest.raises(InvalidParameterError, match=r"end in '.tif' or '.tiff'"):
        write_geotiff(flat_map, tmp_path / "a.png")
    with pytest.raises(UnknownNameError, match="no layer named 'cost'"):
        write_geotiff(flat_map, tmp_path / "a.tif", layer="cost")
    flat_map.crs = "not a crs"
    with pytest.raises(InvalidParameterError, match="'not a crs' is not understood"):
        write_geotiff(flat_map, tmp_path / "a.tif")
    assert os.listdir(tmp_path) == []


def test_failed_write_keeps_the_old_file(rasterio, tmp_path, flat_map, ramp_map, monkeypatch):
    path = write_geotiff(flat_map, tmp_path / "a.tif")

    def fail(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(rasterio, "open", fail)
    with pytest.raises(OSError, match="disk full"):
        write_geotiff(ramp_map, path)
    monkeypatch.undo()
    assert os.listdir(tmp_path) == ["a.tif"]
    np.testing.assert_array_equal(read_geotiff(path).elevation_m, flat_map.elevation_m)


# -------------------------------------------------------------------- nodata
def nodata_file(rasterio, tmp_path):
    data = np.arange(20, dtype=np.float32).reshape(4, 5)
    data[0, 0] = data[2, 3] = -9999.0
    return write_raw(rasterio, tmp_path / "n.tif", data, north_up(rasterio, 0, 4, 1, 1), nodata=-9999.0)


def test_nodata_raises_by_default(rasterio, tmp_path):
    with pytest.raises(InvalidParameterError, match="2 nodata/NaN cells of 20; pass fill_nodata='nearest'"):
        read_geotiff(nodata_file(rasterio, tmp_path))


@pytest.mark.filterwarnings("ignore::terrawatt_base.errors.ImplausibleDataWarning")  # 1 m steps between 1 m cells
def test_nodata_filled_from_the_nearest_cell_on_request(rasterio, tmp_path):
    with pytest.warns(DataRepairWarning, match="filled 2 nodata cells"):
        tmap = read_geotiff(nodata_file(rasterio, tmp_path), fill_nodata="nearest")
    z = tmap.elevation_m[::-1]  # back to file order
    assert z[0, 0] in (1.0, 5.0)  # file neighbours of the north-west corner
    assert z[2, 3] in (8.0, 12.0, 14.0, 18.0)
    assert z[1, 1] == 6.0  # valid cells untouched


def test_nan_cells_without_declared_nodata(rasterio, tmp_path):
    data = np.ones((3, 3))
    data[1, 1] = np.nan
    path = write_raw(rasterio, tmp_path / "nan.tif", data, north_up(rasterio, 0, 3, 1, 1))
    with pytest.raises(InvalidParameterError, match="has 1 nodata/NaN cells"):
        read_geotiff(path)
    with pytest.warns(DataRepairWarning):
        assert np.all(read_geotiff(path, fill_nodata="nearest").elevation_m == 1.0)


def test_all_nodata_raises_even_when_filling(rasterio, tmp_path):
    data = np.full((2, 2), -1.0)
    path = write_raw(rasterio, tmp_path / "a.tif", data, north_up(rasterio, 0, 2, 1, 1), nodata=-1.0)
    with pytest.raises(InvalidParameterError, match="no valid cell"):
        read_geotiff(path, fill_nodata="nearest")


def test_unknown_fill_method(rasterio, tmp_path):
    with pytest.raises(UnknownNameError, match="fill_nodata must be None or one of"):
        read_geotiff(nodata_file(rasterio, tmp_path), fill_nodata="mean")


# ----------------------------------------------------------- unsupported input
def test_rotated_transform(rasterio, tmp_path):
    rotated = rasterio.Affine(1.0, 0.2, 0.0, 0.2, -1.0, 10.0)
    with pytest.raises(FileFormatError, match="rotated or sheared"):
        read_geotiff(write_raw(rasterio, tmp_path / "r.tif", np.zeros((3, 3)), rotated))


def test_non_square_pixels(rasterio, tmp_path):
    transform = north_up(rasterio, 0, 10, 1.0, 2.0)
    with pytest.raises(FileFormatError, match="non-square pixels of 1.0 x 2.0"):
        read_geotiff(write_raw(rasterio, tmp_path / "n.tif", np.zeros((3, 3)), transform))


@pytest.mark.parametrize("crs", ["EPSG:4326", "EPSG:2263"])
def test_crs_not_in_metres(rasterio, tmp_path, crs):
    transform = north_up(rasterio, 0, 10, 1.0, 1.0)
    with pytest.raises(FileFormatError, match="units are not metres; reproject it to a projected CRS in metres"):
        read_geotiff(write_raw(rasterio, tmp_path / "g.tif", np.zeros((3, 3)), transform, crs=crs))


def test_vertical_units_not_in_metres(rasterio, tmp_path):
    transform = north_up(rasterio, 0, 3, 1, 1)
    path = write_raw(rasterio, tmp_path / "ft.tif", np.zeros((3, 3)), transform, units=("ft",))
    with pytest.raises(FileFormatError, match="vertical units 'ft'"):
        read_geotiff(path)


@pytest.mark.parametrize("band", [0, 2, 1.0])
def test_band_out_of_range(rasterio, tmp_path, flat_map, band):
    path = write_geotiff(flat_map, tmp_path / "a.tif")
    with pytest.raises(InvalidParameterError, match=r"band must be an integer in 1..1"):
        read_geotiff(path, band=band)


def test_missing_and_non_raster_files(rasterio, tmp_path):
    with pytest.raises(FileFormatError, match="does not exist"):
        read_geotiff(tmp_path / "none.tif")
    text = tmp_path / "t.tif"
    text.write_text("hello")
    with pytest.raises(FileFormatError, match="cannot read"):
        read_geotiff(text)


def test_missing_rasterio_names_the_geo_extra(tmp_path, flat_map, monkeypatch):
    monkeypatch.setitem(sys.modules, "rasterio", None)  # makes `import rasterio` fail
    with pytest.raises(OptionalDependencyError, match=r"pip install 'terrawatt\[geo\]'"):
        read_geotiff(tmp_path / "a.tif")
    with pytest.raises(OptionalDependencyError, match="needs rasterio"):
        write_geotiff(flat_map, tmp_path / "a.tif")


def test_loaded_map_is_a_plain_terrain_map(rasterio, tmp_path, ramp_map):
    back = read_geotiff(write_geotiff(ramp_map, tmp_path / "r.tif"))
    assert isinstance(back, TerrainMap) and back.ground_names == {} and not back.obstacle.any()
    np.testing.assert_allclose(back["grad_x"], ramp_map["grad_x"])


# ------------------------------------------------------- images and degrees
def rgb_file(rasterio, tmp_path):
    """A 3-band uint8 orthophoto-like GeoTIFF (bands of random colours, 1 m cells)."""
    rng = np.random.default_rng(5)
    data = rng.integers(0, 256, size=(3, 16, 16)).astype(np.uint8)
    data[1] = 40  # band 2 is flat: a plausible (if odd) DEM
    path = tmp_path / "rgb.tif"
    profile = dict(driver="GTiff", height=16, width=16, count=3, dtype="uint8",
                   transform=north_up(rasterio, 0, 16, 1, 1), crs="EPSG:32633")
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(data)
    return path, data


def test_a_multi_band_file_needs_its_elevation_band_named(rasterio, tmp_path):
    path, data = rgb_file(rasterio, tmp_path)
    with pytest.raises(FileFormatError, match=r"has 3 bands; a DEM has one. Name the elevation band with band=N \(1..3\)"):
        read_geotiff(path)
    np.testing.assert_array_equal(read_geotiff(path, band=2).elevation_m, data[1][::-1].astype(float))
    with pytest.warns(ImplausibleDataWarning, match=r"band 1: \d+ % of the cells are steeper than 60 degrees"):
        read_geotiff(path, band=1)  # random colours as heights: cliffs everywhere
    with pytest.raises(InvalidParameterError, match=r"band must be an integer in 1..3, got 4"):
        read_geotiff(path, band=4)


@pytest.mark.parametrize("cell", [0.0003, 0.005, 20_000.0])
def test_no_crs_and_a_cell_size_implausible_for_metres(rasterio, tmp_path, cell):
    transform = north_up(rasterio, 10.0, 50.0, cell, cell)
    path = write_raw(rasterio, tmp_path / "deg.tif", np.zeros((4, 4)), transform, crs=None)
    with pytest.raises(UnitError, match=r"no CRS and cells of .*implausible as metres.*looks like degrees"):
        read_geotiff(path)


def test_plausible_cell_sizes_without_crs_are_read(rasterio, tmp_path):
    for cell in (0.01, 10_000.0):
        path = write_raw(rasterio, tmp_path / "ok.tif", np.zeros((4, 4)), north_up(rasterio, 0, 0, cell, cell), crs=None)
        assert read_geotiff(path).cell_size_m == cell


def test_a_mostly_vertical_dem_warns_but_is_read(rasterio, tmp_path):
    z = np.tile(5.0 * np.arange(6), (6, 1))  # a 79 degree wall (grade 5)
    path = write_raw(rasterio, tmp_path / "cliffs.tif", z, north_up(rasterio, 0, 6, 1, 1))
    with pytest.warns(ImplausibleDataWarning, match="steeper than 60 degrees"):
        tmap = read_geotiff(path)
    np.testing.assert_array_equal(tmap.elevation_m, z[::-1])



# -------------------------------------------------------------- hostile DEMs
def test_a_complex_valued_dem_is_refused(rasterio, tmp_path):
    data = (np.arange(20.0).reshape(4, 5) + 1j).astype(np.complex64)
    path = write_raw(rasterio, tmp_path / "c.tif", data, north_up(rasterio, 0.0, 4.0, 1.0, 1.0))
    with pytest.raises(FileFormatError, match="holds complex64 values; elevations are real"):
        read_geotiff(path)
    with pytest.raises(InvalidParameterError, match="complex"):
        TerrainMap(data, 1.0)


def test_a_sparse_dem_declaring_more_cells_than_memory_is_refused_before_reading(rasterio, tmp_path, monkeypatch):
    path = tmp_path / "huge.tif"
    profile = dict(driver="GTiff", height=200_000, width=200_000, count=1, dtype="float32", tiled=True,
                   blockxsize=256, blockysize=256, sparse_ok=True, compress="deflate",
                   transform=north_up(rasterio, 0.0, 200_000.0, 1.0, 1.0), crs="EPSG:32633")
    with rasterio.open(path, "w", **profile):
        pass  # nothing written: a few kB declaring 4 * 10**10 cells
    assert path.stat().st_size < 5_000_000
    with pytest.raises(FileFormatError, match=r"its 200000 x 200000 cells read whole .* more than the memory budget"):
        read_geotiff(path)
    # a budget raised past what the machine has cannot let it through to die with MemoryError midway
    with monkeypatch.context() as m:
        m.setenv("TERRAWATT_MEMORY_BUDGET_BYTES", str(2**62))
        m.setattr("terrawatt_base.containers.physical_memory_bytes", lambda: 24 * 1024**3)
        with pytest.raises(FileFormatError, match=r"would take about 633 GiB in memory, more than this machine has "
                                                  r"\(24 GiB\); read it by windows"):
            read_geotiff(path)


def test_values_that_cannot_be_elevations_are_refused():
    with pytest.raises(UnitError, match="not elevations in metres"):
        TerrainMap(np.full((3, 3), 3.0e38), 1.0)
