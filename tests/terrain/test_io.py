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
