"""Large real-world maps: geographic DEMs reprojected on reading, windowed preparation, every command on them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from terrain import (
    FileFormatError,
    InvalidParameterError,
    NodataError,
    UnknownNameError,
    iter_surface_windows,
    lonlat_to_xy,
    procedural_map,
    read_geotiff,
    read_map,
    surface_layers,
    transform_xy,
    utm_crs,
    windowed_surface,
    write_geotiff,
    xy_to_lonlat,
)

rasterio = pytest.importorskip("rasterio", reason="GeoTIFF support needs the geo extra (rasterio)")

#: North-west corner and cell size (degrees) of the synthetic geographic DEM.
LON0, LAT0, DEG = 15.2, 45.06, 0.0005


def write_geographic_dem(path, n=40, nodata_cell=None):
    """A north-up EPSG:4326 DEM whose elevation rises 10 m per 0.01 deg of longitude."""
    lon = LON0 + (np.arange(n) + 0.5) * DEG
    data = np.tile(100.0 + 1000.0 * (lon - LON0), (n, 1)).astype("float32")
    nodata = None
    if nodata_cell is not None:
        data[nodata_cell] = -9999.0
        nodata = -9999.0
    profile = dict(driver="GTiff", height=n, width=n, count=1, dtype="float32", crs="EPSG:4326",
                   transform=rasterio.transform.from_origin(LON0, LAT0, DEG, DEG), nodata=nodata)
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(data, 1)
    return path


# ------------------------------------------------------------------ reprojection
def test_a_geographic_dem_is_refused_with_the_option_that_reprojects_it(tmp_path):
    path = write_geographic_dem(tmp_path / "geo.tif")
    with pytest.raises(FileFormatError, match=r"read it with reproject_to utm \(or EPSG:N\) and cell_size_m M$") as raised:
        read_geotiff(path)
    assert raised.value.parameter == ("reproject_to", "cell_size_m")  # the command line says --reproject, --cell-size


def test_reprojection_to_the_local_utm_zone(tmp_path):
    path = write_geographic_dem(tmp_path / "geo.tif")
    tmap = read_geotiff(path, reproject_to="utm", cell_size_m=5.0)
    assert tmap.crs == "EPSG:32633" == utm_crs(LON0, LAT0)
    assert tmap.cell_size_m == 5.0
    # 40 cells of 0.0005 deg: ~2.2 km north-south and ~1.6 km east-west at 45 deg N
    rows, cols = tmap.shape
    assert 430 <= rows <= 460 and 300 <= cols <= 330
    # the elevation range is kept (bilinear resampling never overshoots)
    assert 100.0 <= tmap.elevation_m.min() and tmap.elevation_m.max() <= 100.0 + 1000.0 * 40 * DEG
    # the map's centre is the DEM's centre
    xmin, ymin, xmax, ymax = tmap.bounds
    lonlat = transform_xy([[(xmin + xmax) / 2, (ymin + ymax) / 2]], tmap.crs, "EPSG:4326")[0]
    assert lonlat == pytest.approx([LON0 + 20 * DEG, LAT0 - 20 * DEG], abs=2 * DEG)
    # elevation rises eastwards (+x), as in the source
    assert float(np.median(tmap["grad_x"][~tmap.obstacle])) > 0


def test_the_empty_corners_of_a_warped_dem_are_obstacles(tmp_path):
    tmap = read_geotiff(write_geographic_dem(tmp_path / "geo.tif"), reproject_to="utm", cell_size_m=5.0)
    obstacle = tmap.obstacle
    assert obstacle.any() and obstacle.mean() < 0.2
    rows, cols = tmap.shape
    assert not obstacle[rows // 2, cols // 2]
    assert np.all(np.isfinite(tmap.elevation_m))


def test_reprojection_to_a_named_crs(tmp_path):
    tmap = read_geotiff(write_geographic_dem(tmp_path / "geo.tif"), reproject_to="EPSG:32632", cell_size_m=10.0)
    assert tmap.crs == "EPSG:32632" and tmap.cell_size_m == 10.0


def test_read_map_passes_the_reprojection_on(tmp_path):
    path = write_geographic_dem(tmp_path / "geo.tif")
    assert read_map(path, reproject_to="utm", cell_size_m=8.0).crs == "EPSG:32633"
    npz = procedural_map((8, 8), 1.0, seed=0).save(tmp_path / "m.npz")
    with pytest.raises(InvalidParameterError, match="apply to GeoTIFF DEMs"):
        read_map(npz, reproject_to="utm", cell_size_m=1.0)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"reproject_to": "utm"}, InvalidParameterError, "reproject_to and cell_size_m go together"),
        ({"cell_size_m": 5.0}, InvalidParameterError, "reproject_to and cell_size_m go together"),
        ({"reproject_to": "utm", "cell_size_m": -1.0}, InvalidParameterError, "cell_size_m must be > 0"),
        ({"reproject_to": "utm", "cell_size_m": float("nan")}, InvalidParameterError, "cell_size_m must be finite"),
        ({"reproject_to": "utm", "cell_size_m": 1e6}, InvalidParameterError, "gives a .* grid"),
        ({"reproject_to": "EPSG:4326", "cell_size_m": 5.0}, InvalidParameterError, "projected CRS in metres"),
        ({"reproject_to": "not a crs", "cell_size_m": 5.0}, InvalidParameterError, "not a CRS"),
        ({"reproject_to": "", "cell_size_m": 5.0}, InvalidParameterError, "non-empty string"),
        ({"reproject_to": "utm", "cell_size_m": 5.0, "resampling": "magic"}, UnknownNameError, "resampling"),
    ],
)
def test_bad_reprojection_arguments(tmp_path, kwargs, error, match):
    path = write_geographic_dem(tmp_path / "geo.tif")
    with pytest.raises(error, match=match):
        read_geotiff(path, **kwargs)


def test_nodata_inside_the_footprint_still_follows_fill_nodata(tmp_path):
    path = write_geographic_dem(tmp_path / "geo.tif", nodata_cell=(20, 20))
    with pytest.raises(NodataError, match="fill_nodata='nearest'"):
        read_geotiff(path, reproject_to="utm", cell_size_m=5.0)
    with pytest.warns(UserWarning, match="filled"):
        tmap = read_geotiff(path, reproject_to="utm", cell_size_m=5.0, fill_nodata="nearest")
    assert np.all(np.isfinite(tmap.elevation_m))


def test_a_dem_without_crs_cannot_be_reprojected(tmp_path):
    path = tmp_path / "nocrs.tif"
    write_geotiff(procedural_map((10, 10), 1.0, seed=0), path)
    with pytest.raises(InvalidParameterError, match="needs a source raster with a CRS"):
        read_geotiff(path, reproject_to="utm", cell_size_m=1.0)


def test_utm_zone_of_points():
    assert utm_crs(3.0, 51.0) == "EPSG:32631"
    assert utm_crs(-0.1, -10.0) == "EPSG:32730"
    with pytest.raises(InvalidParameterError):
        utm_crs(0.0, 95.0)


def test_transform_round_trip_and_bad_points():
    pts = np.array([[500_000.0, 4_990_000.0], [501_234.5, 4_987_654.3]])
    back = transform_xy(transform_xy(pts, "EPSG:32633", "EPSG:4326"), "EPSG:4326", "EPSG:32633")
    np.testing.assert_allclose(back, pts, atol=1e-6)
    with pytest.raises(InvalidParameterError, match=r"shape \(N, 2\)"):
        transform_xy(np.zeros((2, 3)), "EPSG:32633", "EPSG:4326")
    with pytest.raises(InvalidParameterError, match="not a CRS"):
        transform_xy(pts, "EPSG:999999999", "EPSG:4326")


# ------------------------------------------------------------------ windowed preparation
@pytest.fixture
def dem_path(tmp_path):
    tmap = procedural_map((131, 97), 0.5, seed=4)
    tmap.crs = "EPSG:32633"
    return write_geotiff(tmap, tmp_path / "dem.tif")


@pytest.mark.parametrize("window_cells", [2, 3, 16, 50, 1000])
def test_windowed_preparation_equals_the_whole_map_bit_for_bit(dem_path, window_cells):
    whole = read_geotiff(dem_path)
    layers = windowed_surface(dem_path, window_cells=window_cells)
    for name in ("elevation", "slope", "aspect", "grad_x", "grad_y"):
        assert np.array_equal(layers[name], whole[name]), name


def test_windows_tile_the_map_once(dem_path):
    seen = np.zeros((131, 97), int)
    for win in iter_surface_windows(dem_path, window_cells=40):
        seen[win.rows, win.cols] += 1
        assert win.layers["slope"].shape == seen[win.rows, win.cols].shape
    assert np.all(seen == 1)


def test_windowed_preparation_into_memory_maps(dem_path, tmp_path):
    layers = windowed_surface(dem_path, window_cells=32, layers=("slope",), out_dir=tmp_path / "prep")
    assert sorted(p.name for p in (tmp_path / "prep").iterdir()) == ["slope.npy"]
    assert np.array_equal(np.load(tmp_path / "prep" / "slope.npy"), read_geotiff(dem_path)["slope"])
    assert set(layers) == {"slope"}


def test_surface_layers_is_the_maps_formula(dem_path):
    whole = read_geotiff(dem_path)
    for name, arr in surface_layers(whole.elevation_m, whole.cell_size_m).items():
        assert np.array_equal(arr, whole[name])


def test_windowed_preparation_of_south_up_and_east_left_files(tmp_path):
    z = 0.05 * np.random.default_rng(0).normal(size=(23, 17)).cumsum(axis=0).cumsum(axis=1)
    for a, e in ((2.0, 2.0), (-2.0, -2.0)):
        path = tmp_path / f"f{a}{e}.tif"
        transform = rasterio.Affine(a, 0.0, 100.0 if a < 0 else 0.0, 0.0, e, 0.0 if e > 0 else 50.0)
        with rasterio.open(path, "w", driver="GTiff", height=23, width=17, count=1, dtype="float64",
                           crs="EPSG:32633", transform=transform) as dst:
            dst.write(z, 1)
        whole = read_geotiff(path)
        layers = windowed_surface(path, window_cells=5)
        assert np.array_equal(layers["grad_x"], whole["grad_x"]) and np.array_equal(layers["grad_y"], whole["grad_y"])


def test_windowed_preparation_refuses_nodata_and_bad_arguments(tmp_path, dem_path):
    path = write_geographic_dem(tmp_path / "geo.tif")
    with pytest.raises(FileFormatError, match="units are not metres"):
        windowed_surface(path)
    holed = tmp_path / "holed.tif"
    z = np.ones((10, 10), "float32")
    z[3, 4] = -9999.0
    with rasterio.open(holed, "w", driver="GTiff", height=10, width=10, count=1, dtype="float32",
                       crs="EPSG:32633", transform=rasterio.transform.from_origin(0, 10, 1, 1), nodata=-9999.0) as dst:
        dst.write(z, 1)
    with pytest.raises(NodataError, match="fill the DEM first"):
        windowed_surface(holed, window_cells=4)
    with pytest.raises(InvalidParameterError, match="window_cells"):
        windowed_surface(dem_path, window_cells=1)
    with pytest.raises(UnknownNameError, match="layers"):
        windowed_surface(dem_path, layers=("colour",))
    with pytest.raises(InvalidParameterError, match="at least one"):
        windowed_surface(dem_path, layers=())
    with pytest.raises(FileFormatError, match="does not exist"):
        windowed_surface(tmp_path / "missing.tif")
    assert math.isfinite(float(windowed_surface(dem_path, layers=("slope",))["slope"].max()))


def test_every_map_taking_command_reprojects_a_geographic_dem(tmp_path, capsys):
    from terrawatt_cli import main

    path = write_geographic_dem(tmp_path / "geo.tif")
    tmap = read_geotiff(path, reproject_to="utm", cell_size_m=20.0)
    xmin, ymin, xmax, ymax = tmap.bounds
    cx, cy = (xmin + xmax) / 2, (ymin + ymax) / 2
    rc = main(["reach", "--map", str(path), "--reproject", "utm", "--cell-size", "20", "--depot", str(cx), str(cy),
               "--battery-ah", "2", "--out", str(tmp_path / "reach")])
    assert rc == 0, capsys.readouterr().err
    import rasterio

    with rasterio.open(tmp_path / "reach" / "reach.tif") as src:
        assert src.crs.to_string() == "EPSG:32633"
    # the pair of flags is checked the same way by every command that takes --map
    (tmp_path / "sites.csv").write_text("x_m,y_m\n1,1\n2,2\n")
    for argv in (["batch", "--map", str(path), "--sites", str(tmp_path / "sites.csv"), "--all-pairs"],
                 ["mission", "--map", str(path), "--battery-ah", "1", "--start", "1", "1", "--goal", "2", "2"],
                 ["diagnose", "--model", "physics", "--data", str(tmp_path), "--map", str(path)]):
        capsys.readouterr()
        rc = main(argv + ["--reproject", "utm", "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err
        assert rc == 2 and "--reproject and --cell-size go together" in err, (argv[0], err)


def test_a_point_outside_the_projections_domain_is_named_not_a_gdal_error():
    """(0, 0) lies 99 degrees of longitude from UTM zone 14's central meridian: GDAL refuses the whole batch;
    the other points still transform and the bad one comes back NaN, then a clear error by lon/lat."""
    xy = transform_xy([[-99.0, 35.0], [0.0, 0.0]], "EPSG:4326", "EPSG:32614")
    assert np.all(np.isfinite(xy[0])) and np.all(np.isnan(xy[1]))
    np.testing.assert_allclose(xy[0], transform_xy([[-99.0, 35.0]], "EPSG:4326", "EPSG:32614")[0])
    with pytest.raises(InvalidParameterError, match=r"\(0, 0\) cannot be expressed in the map's CRS 'EPSG:32614'"):
        lonlat_to_xy(0.0, 0.0, "EPSG:32614")


def test_a_map_point_without_longitude_latitude_is_named():
    with pytest.raises(InvalidParameterError, match=r"\(1e\+300, 0\) of the map's CRS 'EPSG:32614' has no longitude"):
        xy_to_lonlat(1e300, 0.0, "EPSG:32614")
