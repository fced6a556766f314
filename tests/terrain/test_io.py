"""Tests of terrain.io: read_map picks the reader by suffix."""

from __future__ import annotations

import numpy as np
import pytest

from terrain import FileFormatError, InvalidParameterError, UnknownNameError, read_map, write_geotiff


def test_npz_maps_are_read_with_terrain_map_load(tmp_path, ramp_map):
    back = read_map(ramp_map.save(tmp_path / "m.npz"))
    assert back.same_grid(ramp_map) and back.ground_names == ramp_map.ground_names
    np.testing.assert_array_equal(back.elevation_m, ramp_map.elevation_m)
    assert read_map(str(tmp_path / "m.npz"), fill_nodata="nearest").same_grid(ramp_map)  # nothing to fill


@pytest.mark.parametrize("name", ["dem.tif", "dem.TIFF"])
def test_geotiffs_are_read_with_read_geotiff(tmp_path, ramp_map, name):
    pytest.importorskip("rasterio")
    ramp_map.crs = "EPSG:32633"
    path = write_geotiff(ramp_map, tmp_path / "dem.tif")
    path = path.rename(tmp_path / name)
    back = read_map(path, band=1)
    assert back.same_grid(ramp_map) and back.crs == "EPSG:32633"
    np.testing.assert_array_equal(back.elevation_m, ramp_map.elevation_m)


@pytest.mark.parametrize("name", ["map.png", "map", "map.npy", "map.tif.bak"])
def test_other_suffixes_are_a_file_format_error_listing_the_suffixes(tmp_path, name):
    with pytest.raises(FileFormatError, match=r"is not one of '.npz', '.tif', '.tiff'"):
        read_map(tmp_path / name)


def test_options_that_cannot_apply(tmp_path, flat_map):
    path = flat_map.save(tmp_path / "m.npz")
    with pytest.raises(InvalidParameterError, match="band applies to GeoTIFF DEMs"):
        read_map(path, band=1)
    with pytest.raises(UnknownNameError, match="fill_nodata must be None or one of"):
        read_map(path, fill_nodata="mean")
    with pytest.raises(FileFormatError, match="does not exist|missing"):
        read_map(tmp_path / "none.npz")


def test_read_map_with_options_reads_a_map_and_its_errors_name_the_options(tmp_path, ramp_map):
    from terrain.io import read_map_with_options

    path = ramp_map.save(tmp_path / "m.npz")
    assert read_map_with_options(path).same_grid(ramp_map)
    with pytest.raises(InvalidParameterError, match="reproject_to and cell_size_m go together") as err:
        read_map_with_options(path, reproject_to="utm")
    assert err.value.parameter == ("reproject_to", "cell_size_m")  # the command line says them as its flags
    with pytest.raises(InvalidParameterError, match="reproject_to and cell_size_m go together"):
        read_map_with_options(path, cell_size_m=5.0)
    with pytest.raises(InvalidParameterError, match="cell_size_m must be a number > 0, got -5") as err:
        read_map_with_options(path, reproject_to="utm", cell_size_m=-5.0)
    assert err.value.parameter == "cell_size_m"
    with pytest.raises(InvalidParameterError, match="landcover and landcover_classes go together") as err:
        read_map_with_options(path, landcover=tmp_path / "lc.tif")
    assert err.value.parameter == ("landcover", "landcover_classes")
    with pytest.raises(InvalidParameterError, match="apply to a map file, not to a map in memory"):
        read_map_with_options(ramp_map, fill_nodata="nearest")
    assert read_map_with_options(ramp_map) is ramp_map


def test_read_map_with_options_checks_the_classes_grounds_before_the_map(tmp_path):
    from terrain.io import read_map_with_options

    classes = tmp_path / "classes.csv"
    classes.write_text("code,ground\n10,grass\n20,lava\n")
    with pytest.raises(UnknownNameError, match=r"landcover_classes classes\.csv: grounds \['lava'\] have no preset"):
        read_map_with_options(tmp_path / "missing.npz", landcover=tmp_path / "lc.tif", landcover_classes=classes,
                              known_grounds=("grass", "sand"))
    with pytest.raises(FileFormatError):  # any ground accepted: the missing map is next
        read_map_with_options(tmp_path / "missing.npz", landcover=tmp_path / "lc.tif", landcover_classes=classes)


def test_read_map_with_options_phrases_the_nodata_advice_with_its_names(tmp_path, ramp_map):
    rasterio = pytest.importorskip("rasterio")
    from terrain import NodataError
    from terrain.io import read_map_with_options

    elevation = ramp_map.elevation_m.astype(np.float32)
    elevation[0, 0] = -9999.0
    path = tmp_path / "holes.tif"
    with rasterio.open(path, "w", driver="GTiff", width=elevation.shape[1], height=elevation.shape[0], count=1,
                       dtype="float32", crs="EPSG:32633", nodata=-9999.0,
                       transform=rasterio.Affine(1.0, 0.0, 500000.0, 0.0, -1.0, 4980000.0)) as dst:
        dst.write(elevation, 1)
    with pytest.raises(NodataError, match="holes.tif has 1 nodata cells of .*; give fill_nodata nearest") as err:
        read_map_with_options(path)
    assert err.value.n_nodata == 1 and err.value.parameter == "fill_nodata"
    from terrain import DataRepairWarning

    with pytest.warns(DataRepairWarning, match="filled 1 nodata cells of GeoTIFF"):  # a repair is never silent
        assert read_map_with_options(path, fill_nodata="nearest").shape == ramp_map.shape
