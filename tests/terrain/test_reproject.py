"""terrain.reproject: the target CRS of a DEM and a band warped onto a grid in metres."""

from __future__ import annotations

import numpy as np
import pytest

from terrain import InvalidParameterError, UnknownNameError
from terrain.georef import dem_band
from terrain.reproject import RESAMPLING_METHODS, WarpedDem, target_crs, warp_band

rasterio = pytest.importorskip("rasterio", reason="reprojection needs the geo extra (rasterio)")


def _write(path, data, crs, transform, nodata=None):
    with rasterio.open(path, "w", driver="GTiff", height=data.shape[0], width=data.shape[1], count=1,
                       dtype="float32", crs=crs, transform=transform, nodata=nodata) as dst:
        dst.write(data.astype("float32"), 1)
    return path


@pytest.fixture
def utm_ramp(tmp_path):
    """10 x 12 cells of 30 m in UTM 33N, north-up, elevation = column index (1 m per 30 m eastwards)."""
    data = np.tile(np.arange(12.0), (10, 1))
    return _write(tmp_path / "utm.tif", data, "EPSG:32633", rasterio.Affine(30.0, 0.0, 500_000.0, 0.0, -30.0, 4_990_000.0))


def _warp(path, to, cell_size_m, resampling="bilinear"):
    with rasterio.open(path) as src:
        info = dem_band(src, None, str(path), allow_geographic=True)
        return warp_band(src, info, to, cell_size_m, resampling)


def test_resampling_methods():
    assert RESAMPLING_METHODS == ("bilinear", "cubic", "nearest", "average")


def test_utm_target_is_the_zone_of_the_dems_centre():
    wgs84 = rasterio.crs.CRS.from_epsg(4326)
    assert target_crs(wgs84, (14.9, 44.9, 15.1, 45.1), "utm").to_string() == "EPSG:32633"
    assert target_crs(wgs84, (-70.7, -33.5, -70.5, -33.3), " UTM ").to_string() == "EPSG:32719"


def test_a_named_metric_crs_is_taken_as_given():
    wgs84 = rasterio.crs.CRS.from_epsg(4326)
    assert target_crs(wgs84, (0.0, 0.0, 1.0, 1.0), "EPSG:3857").to_string() == "EPSG:3857"


@pytest.mark.parametrize(
    ("to", "match"),
    [
        ("EPSG:4326", "reproject_to must be a projected CRS in metres"),
        ("not a crs", "reproject_to 'not a crs' is not a CRS rasterio understands"),
        ("", "reproject_to"),
    ],
)
def test_bad_targets_are_refused(to, match):
    with pytest.raises(InvalidParameterError, match=match):
        target_crs(rasterio.crs.CRS.from_epsg(4326), (0.0, 0.0, 1.0, 1.0), to)


def test_warping_onto_the_same_grid_keeps_every_value(utm_ramp):
    warped = _warp(utm_ramp, "EPSG:32633", 30.0, "nearest")
    assert isinstance(warped, WarpedDem)
    assert warped.crs == warped.source_crs == "EPSG:32633"
    assert warped.values.shape == (10, 12) and warped.values.dtype == np.float64
    assert np.array_equal(warped.values, np.tile(np.arange(12.0), (10, 1)))
    assert warped.footprint.all()
    assert tuple(warped.transform)[:6] == (30.0, 0.0, 500_000.0, 0.0, -30.0, 4_990_000.0)


def test_a_coarser_grid_averages_a_linear_ramp(utm_ramp):
    warped = _warp(utm_ramp, "EPSG:32633", 60.0, "average")
    assert warped.values.shape == (5, 6)
    np.testing.assert_allclose(warped.values, np.tile(np.arange(0.5, 12.0, 2.0), (5, 1)))


def test_nodata_stays_nan_and_scale_is_applied(tmp_path):
    data = np.ones((6, 6))
    data[0, 0] = -9999.0
    path = _write(tmp_path / "holed.tif", data, "EPSG:32633",
                  rasterio.Affine(10.0, 0.0, 500_000.0, 0.0, -10.0, 4_990_000.0), nodata=-9999.0)
    with rasterio.open(path, "r+") as dst:
        dst.scales = (2.0,)
        dst.offsets = (5.0,)
    warped = _warp(path, "EPSG:32633", 10.0, "nearest")
    assert np.isnan(warped.values[0, 0]) and np.isnan(warped.values).sum() == 1
    assert np.all(warped.values[~np.isnan(warped.values)] == 7.0)


def test_a_geographic_dem_goes_to_its_utm_zone(tmp_path):
    step = 1.0 / 1200.0
    path = _write(tmp_path / "geo.tif", np.zeros((20, 20)), "EPSG:4326",
                  rasterio.Affine(step, 0.0, 10.0, 0.0, -step, 46.05))
    warped = _warp(path, "utm", 20.0)
    assert warped.crs == "EPSG:32632" and warped.source_crs == "EPSG:4326"
    assert tuple(warped.transform)[0] == 20.0 and tuple(warped.transform)[4] == -20.0
    assert warped.footprint.any() and np.all(warped.values[warped.footprint] == 0.0)


def test_unknown_resampling_and_bad_cell_sizes_are_refused(utm_ramp):
    with pytest.raises(UnknownNameError, match="resampling must be one of .* got 'lanczos'"):
        _warp(utm_ramp, "EPSG:32633", 30.0, "lanczos")
    with pytest.raises(InvalidParameterError, match="cell_size_m"):
        _warp(utm_ramp, "EPSG:32633", 0.0)
    with pytest.raises(InvalidParameterError, match="expected at least 2 x 2"):
        _warp(utm_ramp, "EPSG:32633", 1000.0)


def test_a_source_without_crs_is_refused(tmp_path):
    path = _write(tmp_path / "nocrs.tif", np.zeros((4, 4)), None, rasterio.Affine(1.0, 0.0, 0.0, 0.0, -1.0, 4.0))
    with pytest.raises(InvalidParameterError, match="needs a source raster with a CRS"):
        _warp(path, "utm", 1.0)
