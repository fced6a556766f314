"""Routes as GeoJSON (WGS 84 or local metres), the zoomed route plot, and the plan command's new outputs and flags."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely.geometry

from planner import plan_route
from planner.cost_spec import CostSpec
from planner.plot import RouteLine, plot_routes, view_bounds
from planner.route import evaluate_route
from planner.route_geojson import GEOJSON_FORMAT_VERSION, routes_geojson, write_geojson
from terrain import procedural_map, transform_xy
from terrawatt_base.errors import InvalidParameterError, UnknownNameError
from terrawatt_cli import main

rasterio = pytest.importorskip("rasterio", reason="CRS transforms need the geo extra (rasterio)")

ORIGIN_UTM = (512_000.0, 4_990_000.0)  # zone 33N, about 15.15 E, 45.06 N


@pytest.fixture(scope="module")
def utm_map():
    tmap = procedural_map((60, 80), 1.0, seed=7, origin_xy_m=ORIGIN_UTM, obstacle_fraction=0.0)
    tmap.crs = "EPSG:32633"
    return tmap


@pytest.fixture(scope="module")
def utm_route(utm_map):
    cost = CostSpec().build(utm_map)
    x0, y0 = ORIGIN_UTM
    return plan_route(utm_map, (x0 + 5.5, y0 + 5.5), (x0 + 74.5, y0 + 52.5), cost=cost, planner="lattice")


def test_geojson_is_a_valid_feature_collection_in_wgs84(utm_map, utm_route):
    gj = json.loads(json.dumps(routes_geojson(utm_route, utm_map)))  # strict JSON round trip
    assert gj["type"] == "FeatureCollection" and len(gj["features"]) == 1
    assert gj["terrawatt"]["format_version"] == GEOJSON_FORMAT_VERSION
    assert gj["terrawatt"]["map_crs"] == "EPSG:32633" and "crs" not in gj  # RFC 7946: WGS 84, no crs member
    feature = gj["features"][0]
    line = shapely.geometry.shape(feature["geometry"])
    assert line.geom_type == "LineString" and line.is_valid and line.has_z
    lon, lat = np.array(feature["geometry"]["coordinates"])[:, :2].T
    assert np.all((15.0 < lon) & (lon < 15.3)) and np.all((45.0 < lat) & (lat < 45.1))
    assert "WGS 84" in feature["properties"]["coordinate_system"]


def test_coordinates_round_trip_to_the_map_metres(utm_map, utm_route):
    feature = routes_geojson(utm_route, utm_map)["features"][0]
    lonlat = np.array(feature["geometry"]["coordinates"])[:, :2]
    back = transform_xy(lonlat, "EPSG:4326", "EPSG:32633")
    np.testing.assert_allclose(back, utm_route.waypoints_m, atol=1e-6)
    np.testing.assert_allclose(feature["properties"]["waypoints_m"], utm_route.waypoints_m)
    z = np.array(feature["geometry"]["coordinates"])[:, 2]
    np.testing.assert_allclose(z, utm_map.sample("elevation", *utm_route.waypoints_m.T, method="bilinear"))


def test_per_vertex_energy_adds_up(utm_map, utm_route):
    props = routes_geojson(utm_route, utm_map)["features"][0]["properties"]
    cumulative = np.array(props["cumulative_energy_j"])
    k = utm_route.waypoints_m.shape[0]
    assert cumulative.shape == (k,) and len(props["segment_energy_j"]) == k - 1
    assert cumulative[0] == utm_route.turn_energy_j[0] > 0.0 and np.all(np.diff(cumulative) > 0)  # from rest
    assert cumulative[-1] == pytest.approx(utm_route.energy_j, rel=1e-12)
    assert props["energy_j"] == utm_route.energy_j and props["status"] == "exact"


def test_the_maps_own_crs_and_another_one(utm_map, utm_route):
    own = routes_geojson(utm_route, utm_map, crs="map")
    assert own["crs"]["properties"]["name"] == "EPSG:32633"
    np.testing.assert_allclose(np.array(own["features"][0]["geometry"]["coordinates"])[:, :2], utm_route.waypoints_m)
    other = routes_geojson(utm_route, utm_map, crs="EPSG:3857")
    assert other["crs"]["properties"]["name"] == "EPSG:3857"
    assert utm_route.to_geojson(utm_map)["features"][0]["properties"]["name"] == "route"


def test_a_map_without_crs_is_written_in_local_metres(wall_map):
    cost = CostSpec().build(wall_map)
    route = evaluate_route(cost, [[5.5, 5.5], [10.5, 20.5]])
    for where in (wall_map, wall_map.grid):
        gj = routes_geojson({"a": route}, where)
        feature = gj["features"][0]
        assert "no CRS" in feature["properties"]["coordinate_system"] and gj["terrawatt"]["map_crs"] is None
        coords = np.array(feature["geometry"]["coordinates"])
        np.testing.assert_allclose(coords[:, :2], route.waypoints_m)
        assert coords.shape[1] == (3 if where is wall_map else 2)
    with pytest.raises(InvalidParameterError, match="needs a map with a CRS"):
        routes_geojson(route, wall_map, crs="EPSG:4326")


def test_write_geojson_and_its_bad_inputs(tmp_path, utm_map, utm_route, wall_map):
    path = write_geojson([utm_route, utm_route], utm_map, tmp_path / "r.geojson")
    assert [f["properties"]["name"] for f in json.loads(path.read_text())["features"]] == ["route_0", "route_1"]
    with pytest.raises(InvalidParameterError, match="end in '.geojson'"):
        write_geojson(utm_route, utm_map, tmp_path / "r.txt")
    with pytest.raises(InvalidParameterError, match="is a directory"):
        write_geojson(utm_route, utm_map, tmp_path)
    with pytest.raises(InvalidParameterError, match="must be a planner.Route"):
        routes_geojson("route", utm_map)
    with pytest.raises(InvalidParameterError, match="empty"):
        routes_geojson([], utm_map)
    with pytest.raises(InvalidParameterError, match="TerrainMap or a Grid"):
        routes_geojson(utm_route, "map")
    with pytest.raises(InvalidParameterError, match="not a CRS"):
        routes_geojson(utm_route, utm_map, crs="EPSG:0")
    from planner.route import empty_route

    with pytest.raises(InvalidParameterError, match="no waypoints"):
        routes_geojson(empty_route("infeasible", "lattice", 0.0, 24.0), utm_map)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.geojson"]


# ------------------------------------------------------------------ the zoomed plot
def test_the_zoom_contains_the_route_with_a_margin_inside_the_map():
    tmap = procedural_map((200, 300), 1.0, seed=1)
    line = RouteLine("r", np.array([[100.0, 50.0], [140.0, 60.0], [150.0, 90.0]]), 1.0)
    xmin, ymin, xmax, ymax = view_bounds(tmap, [line], [(100.0, 50.0), (150.0, 90.0)])
    assert xmin < 100.0 and xmax > 150.0 and ymin < 50.0 and ymax > 90.0
    assert (xmax - xmin) < 0.5 * 300 and (ymax - ymin) < 0.5 * 200
    assert view_bounds(tmap, [line], extent="map") == tmap.bounds
    edge = RouteLine("e", np.array([[0.5, 0.5], [20.0, 5.0]]), 1.0)
    assert view_bounds(tmap, [edge])[:2] == (0.0, 0.0)  # clipped to the map
    assert view_bounds(tmap, []) == tmap.bounds
    with pytest.raises(UnknownNameError, match="extent"):
        view_bounds(tmap, [line], extent="world")
    with pytest.raises(InvalidParameterError, match="margin_frac"):
        view_bounds(tmap, [line], margin_frac=-1.0)


def test_plot_zooms_and_hatches_the_steep_cells(tmp_path, monkeypatch):
    from terrawatt_base import plot_target

    tmap = procedural_map((120, 160), 1.0, seed=3, ridge_slope_deg=40.0)
    line = RouteLine("r", np.array([[20.0, 20.0], [60.0, 50.0]]), 10.0)
    captured = {}
    original = plot_target.new_figure

    def keep(*args, **kwargs):
        captured["fig"], axes = original(*args, **kwargs)
        return captured["fig"], axes

    monkeypatch.setattr(plot_target, "new_figure", keep)
    out = plot_routes(tmap, [line], (20.0, 20.0), (60.0, 50.0), tmp_path / "z.png", max_slope_rad=np.radians(10.0))
    ax = captured["fig"].axes[0]
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    assert x0 <= 20.0 and x1 >= 60.0 and y0 <= 20.0 and y1 >= 50.0 and x1 - x0 < 100.0
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("steeper than 10 deg" in t for t in labels)
    assert out.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(InvalidParameterError, match="max_slope_rad"):
        plot_routes(tmap, [line], (20.0, 20.0), (60.0, 50.0), tmp_path / "y.png", max_slope_rad=-1.0)


# ------------------------------------------------------------------ the plan command
def _geographic_dem(path, n=24, deg=0.0002):
    data = np.tile(np.linspace(100.0, 104.0, n), (n, 1)).astype("float32")
    with rasterio.open(path, "w", driver="GTiff", height=n, width=n, count=1, dtype="float32", crs="EPSG:4326",
                       transform=rasterio.transform.from_origin(15.2, 45.06, deg, deg)) as dst:
        dst.write(data, 1)
    return path


def test_plan_writes_route_geojson_beside_route_json(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5", "--planner", "lattice",
               "--out", str(tmp_path / "out"), "--whole-map"])
    assert rc == 0
    gj = json.loads((tmp_path / "out" / "route.geojson").read_text())
    names = [f["properties"]["name"] for f in gj["features"]]
    assert names == ["min_energy", "lattice", "shortest"]
    assert "route.geojson" in capsys.readouterr().out
    assert json.loads((tmp_path / "out" / "route.json").read_text())["map_crs"] is None


def test_plan_on_a_geographic_dem_with_reproject(tmp_path, capsys):
    dem = _geographic_dem(tmp_path / "geo.tif")
    rc = main(["plan", "--map", str(dem), "--start", "1", "1", "--goal", "2", "2", "--planner", "lattice",
               "--out", str(tmp_path / "refused")])
    err = capsys.readouterr().err
    assert rc == 2 and "read it with --reproject utm (or EPSG:N) and --cell-size M" in err  # the library's words, flagged
    from terrain import read_geotiff

    tmap = read_geotiff(dem, reproject_to="utm", cell_size_m=5.0)
    xmin, ymin, xmax, ymax = tmap.bounds
    cx, cy = (xmin + xmax) / 2, (ymin + ymax) / 2
    rc = main(["plan", "--map", str(dem), "--reproject", "utm", "--cell-size", "5", "--planner", "lattice",
               "--start", str(cx - 100), str(cy - 100), "--goal", str(cx + 100), str(cy + 80),
               "--out", str(tmp_path / "out")])
    assert rc == 0, capsys.readouterr().err
    data = json.loads((tmp_path / "out" / "route.json").read_text())
    assert data["map_crs"] == "EPSG:32633"
    lon, lat = np.array(json.loads((tmp_path / "out" / "route.geojson").read_text())
                        ["features"][0]["geometry"]["coordinates"])[:, :2].T
    assert np.all((15.2 < lon) & (lon < 15.2 + 24 * 0.0002)) and np.all((45.06 - 24 * 0.0002 < lat) & (lat < 45.06))


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--reproject", "utm"], "--reproject and --cell-size go together"),
        (["--cell-size", "5"], "--reproject and --cell-size go together"),
        (["--reproject", "utm", "--cell-size", "-5"], "--cell-size must be a number > 0"),
        (["--reproject", "EPSG:4326", "--cell-size", "5"], "--reproject must be a projected CRS in metres"),
        (["--reproject", "utm", "--cell-size", "1e7"], "--cell-size 1e+07 m gives a 1 x 1 grid"),
    ],
)
def test_plan_reprojection_flags_are_checked(tmp_path, capsys, extra, message):
    dem = _geographic_dem(tmp_path / "geo.tif")
    rc = main(["plan", "--map", str(dem), "--start", "1", "1", "--goal", "2", "2", "--planner", "lattice",
               "--out", str(tmp_path / "out"), *extra])
    assert rc == 2 and message in capsys.readouterr().err


def test_plan_coarse_to_fine_from_the_command_line(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5", "--coarse-factor", "4",
               "--out", str(tmp_path / "out")])
    out = capsys.readouterr().out
    assert rc == 0 and "coarse-to-fine (x4)" in out
    data = json.loads((tmp_path / "out" / "route.json").read_text())
    assert data["planner"] == "coarse-to-fine" and data["coarse_to_fine"]["factor"] == 4
    wp = np.array(data["routes"]["min_energy"]["waypoints_m"])
    assert wp[:, 1].max() >= 30.0  # through the gap, which the 4 x coarser map could not see
    assert data["coarse_to_fine"]["fallback"] in ("wider corridor", "whole map")
    names = [f["properties"]["name"] for f in json.loads((tmp_path / "out" / "route.geojson").read_text())["features"]]
    assert names == ["min_energy"] and (tmp_path / "out" / "route.png").is_file()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--corridor", "5"], "give --coarse-factor F too"),
        (["--coarse-factor", "1"], "--coarse-factor must be an integer >= 2"),
        (["--coarse-factor", "4", "--corridor", "-1"], "--corridor must be a number > 0"),
    ],
)
def test_plan_coarse_to_fine_flags_are_checked(tmp_path, capsys, wall_map, extra, message):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5", "--out", str(tmp_path / "o"),
               *extra])
    assert rc == 2 and message in capsys.readouterr().err
