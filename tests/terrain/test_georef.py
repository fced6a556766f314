"""WGS 84 longitude / latitude to a map's metres and back (terrain.georef, TerrainMap.lonlat_to_xy)."""

from __future__ import annotations

import numpy as np
import pytest

from terrain import InvalidParameterError, TerrainMap, lonlat_to_xy, read_geotiff, xy_to_lonlat
from terrain.georef import lonlat_bounds


@pytest.fixture
def rasterio():
    return pytest.importorskip("rasterio")


def test_the_central_meridian_of_a_utm_zone_is_its_false_easting(rasterio):
    x, y = lonlat_to_xy(15.0, 45.0, "EPSG:32633")
    assert x == pytest.approx(500_000.0, abs=1e-6)
    assert y == pytest.approx(4_982_950.4, abs=0.1)  # 45 deg N on the WGS 84 ellipsoid, scale 0.9996
    lon, lat = xy_to_lonlat(x, y, "EPSG:32633")
    assert (lon, lat) == pytest.approx((15.0, 45.0), abs=1e-9)


def test_arrays_keep_their_shape_and_round_trip(rasterio):
    lon = np.array([[14.1, 14.9], [15.5, 16.2]])
    lat = np.array([[44.0, 44.5], [45.5, 46.9]])
    x, y = lonlat_to_xy(lon, lat, "EPSG:32633")
    assert x.shape == y.shape == (2, 2)
    back = xy_to_lonlat(x, y, "EPSG:32633")
    np.testing.assert_allclose(back[0], lon, atol=1e-9)
    np.testing.assert_allclose(back[1], lat, atol=1e-9)


def test_a_map_read_from_a_geotiff_is_in_its_crs_coordinates_without_offset(rasterio, tmp_path):
    """A GeoTIFF map's metres are the CRS's: a pixel's lon / lat lands on that very cell."""
    rows, cols, d = 6, 8, 30.0
    west, north = 512_340.0, 4_990_110.0
    data = np.arange(rows * cols, dtype=np.float32).reshape(rows, cols)
    path = tmp_path / "utm.tif"
    transform = rasterio.Affine(d, 0.0, west, 0.0, -d, north)
    with rasterio.open(path, "w", driver="GTiff", height=rows, width=cols, count=1, dtype="float32",
                       crs="EPSG:32633", transform=transform) as dst:
        dst.write(data, 1)
    tmap = read_geotiff(path)
    assert tmap.bounds == pytest.approx((west, north - rows * d, west + cols * d, north))
    # file pixel (row 1, col 5), north-up: its centre's lon / lat computed by rasterio alone
    px, py = rasterio.transform.xy(transform, 1, 5)
    (lon,), (lat,) = rasterio.warp.transform("EPSG:32633", "EPSG:4326", [px], [py])
    x, y = tmap.lonlat_to_xy(lon, lat)
    assert (x, y) == pytest.approx((px, py), abs=1e-6)
    assert tmap.sample("elevation", x, y) == data[1, 5]
    assert tmap.xy_to_lonlat(x, y) == pytest.approx((lon, lat), abs=1e-9)


def test_a_reprojected_geographic_dem_places_lon_lat_on_the_right_ground(rasterio, tmp_path):
    """A DEM in EPSG:4326 whose elevation is a linear function of longitude, read with --reproject utm."""
    n, step = 60, 1.0 / 1200.0  # 3 arc-seconds
    lon0, lat0 = 10.0, 46.05  # north-west corner
    lons = lon0 + (np.arange(n) + 0.5) * step
    data = np.tile(1000.0 * (lons - lon0), (n, 1)).astype(np.float32)  # 1000 m per degree of longitude
    path = tmp_path / "geo.tif"
    with rasterio.open(path, "w", driver="GTiff", height=n, width=n, count=1, dtype="float32", crs="EPSG:4326",
                       transform=rasterio.Affine(step, 0.0, lon0, 0.0, -step, lat0)) as dst:
        dst.write(data, 1)
    tmap = read_geotiff(path, reproject_to="utm", cell_size_m=20.0)
    assert tmap.crs == "EPSG:32632"
    lon, lat = 10.02, 46.03
    x, y = tmap.lonlat_to_xy(lon, lat)
    assert tmap.sample("elevation", x, y, method="bilinear") == pytest.approx(1000.0 * (lon - lon0), abs=0.05)


def test_a_map_without_crs_refuses_lon_lat():
    tmap = TerrainMap(np.zeros((3, 3)), 1.0)
    with pytest.raises(InvalidParameterError, match="has no CRS, so WGS 84 longitude / latitude cannot be placed"):
        tmap.lonlat_to_xy(15.0, 45.0)
    with pytest.raises(InvalidParameterError, match="has no CRS"):
        tmap.xy_to_lonlat(0.5, 0.5)


@pytest.mark.parametrize(("lon", "lat"), [(15.0, 95.0), (190.0, 45.0), (float("nan"), 45.0)])
def test_degrees_out_of_range_are_refused(rasterio, lon, lat):
    with pytest.raises(InvalidParameterError, match=r"latitude in \[-90, 90\], got"):
        lonlat_to_xy(lon, lat, "EPSG:32633")


def test_lon_lat_bounds_cover_the_box(rasterio):
    west, south, east, north = lonlat_bounds((500_000.0, 4_982_950.4, 510_000.0, 4_992_950.4), "EPSG:32633")
    assert west == pytest.approx(15.0, abs=1e-9) and south == pytest.approx(45.0, abs=1e-4)
    assert 15.12 < east < 15.13 and 45.08 < north < 45.1
