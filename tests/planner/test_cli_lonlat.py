"""The command line in geographic terms: points as WGS 84 lon/lat, ground classes from a land cover (issue 21)."""

from __future__ import annotations

import csv
import json
import math
import re

import numpy as np
import pytest
from geo_fixtures import CLASSES, WATER, lonlat, write_geo_scene

from terrain import ground_classes_from_landcover, read_geotiff, write_geotiff
from terrawatt_cli import EXIT_BAD_INPUT, EXIT_NOT_ACHIEVED, EXIT_OK, main

rasterio = pytest.importorskip("rasterio")

CELL_M = 30.0


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """The synthetic scene of :mod:`geo_fixtures`: dem.tif (EPSG:4326), landcover.tif (UTM 32 N), classes.csv."""
    return write_geo_scene(tmp_path_factory.mktemp("scene"))


def _map_flags(scene, landcover=True):
    flags = ["--map", str(scene.dem), "--reproject", "utm", "--cell-size", str(CELL_M)]
    if landcover:
        flags += ["--landcover", str(scene.landcover), "--landcover-classes", str(scene.classes)]
    return flags


def _ll(point):
    return [repr(float(v)) for v in point]


def _metres(lon, lat, crs="EPSG:32632"):
    xs, ys = rasterio.warp.transform("EPSG:4326", crs, list(np.atleast_1d(lon)), list(np.atleast_1d(lat)))
    return np.column_stack([xs, ys])


def test_plan_from_lon_lat_on_a_geographic_dem_with_a_land_cover(scene, tmp_path, capsys):
    out = tmp_path / "out"
    rc = main(["plan", *_map_flags(scene), "--start-lonlat", *_ll(scene.start_lonlat),
               "--goal-lonlat", *_ll(scene.goal_lonlat), "--planner", "lattice", "--out", str(out),
               "--ros2-out", str(tmp_path / "route.mcap")])
    printed = capsys.readouterr().out
    assert rc == EXIT_OK
    assert "grounds {0: 'asphalt', 1: 'grass', 2: 'gravel'}" in printed  # a DEM alone has no ground classes
    result = json.loads((out / "route.json").read_text())
    assert result["map_crs"] == "EPSG:32632"
    assert result["start_lonlat_deg"] == pytest.approx(scene.start_lonlat, abs=1e-9)
    assert result["goal_lonlat_deg"] == pytest.approx(scene.goal_lonlat, abs=1e-9)

    # the GeoJSON's ends (WGS 84 lon, lat) lie within a cell of the lon/lat given
    feature = next(f for f in json.loads((out / "route.geojson").read_text())["features"]
                   if f["properties"]["name"] == "min_energy")
    coords = np.array(feature["geometry"]["coordinates"])[:, :2]
    for end, given in ((coords[0], scene.start_lonlat), (coords[-1], scene.goal_lonlat)):
        assert math.dist(_metres(*end)[0], _metres(*given)[0]) <= CELL_M

    # the grounds driven come from the land cover: sample its codes along the route every ~5 m
    steps = [np.linspace(a, b, max(int(math.dist(a, b) / 5.0), 2)) for a, b in zip(coords[:-1], coords[1:])]
    along = np.concatenate(steps)
    with rasterio.open(scene.landcover) as src:
        xy = _metres(along[:, 0], along[:, 1], src.crs)
        codes = np.array(list(src.sample(xy.tolist(), indexes=1)))[:, 0]
    driven = [CLASSES.get(int(c), "unknown") for c in codes]
    assert "obstacle" not in driven and WATER not in codes
    assert driven.count("asphalt") / len(driven) > 0.6  # the road: a DEM without land cover would not know it
    # and the map the planner used agrees with the land cover along the route
    tmap = ground_classes_from_landcover(read_geotiff(scene.dem, reproject_to="utm", cell_size_m=CELL_M),
                                         scene.landcover, scene.classes)
    wp = np.array(result["routes"]["min_energy"]["waypoints_m"])
    cells = [tmap.segment_cells(tuple(a), tuple(b)) for a, b in zip(wp[:-1], wp[1:])]
    rows, cols, lengths = (np.concatenate(k) for k in zip(*cells))
    assert not tmap.obstacle[rows, cols].any()
    on_road = lengths[tmap.ground[rows, cols] == tmap.ground_id("asphalt")].sum() / lengths.sum()
    assert on_road > 0.6

    # the route went to ROS 2 as well: the MCAP reads back, with rosbags alone, as a nav_msgs/Path of these waypoints
    pytest.importorskip("rosbags", reason="the ROS 2 output needs the ros extra")
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    with AnyReader([tmp_path / "route.mcap"], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        [conn] = [c for c in reader.connections if c.topic == "/terrawatt/route"]
        assert conn.msgtype == "nav_msgs/msg/Path"
        [(_, _, raw)] = list(reader.messages(connections=[conn]))
        path = reader.deserialize(raw, conn.msgtype)
    assert path.header.frame_id == "map"
    poses = np.array([[p.pose.position.x, p.pose.position.y] for p in path.poses])
    assert np.allclose(poses, wp, atol=1e-9)


def test_without_the_land_cover_the_route_does_not_know_the_road(scene, tmp_path, capsys):
    out = tmp_path / "out"
    rc = main(["plan", *_map_flags(scene, landcover=False), "--start-lonlat", *_ll(scene.start_lonlat),
               "--goal-lonlat", *_ll(scene.goal_lonlat), "--planner", "lattice", "--out", str(out)])
    assert rc == EXIT_OK and "grounds {}" in capsys.readouterr().out
    route = json.loads((out / "route.json").read_text())["routes"]["min_energy"]
    assert route["length_m"] < 1.02 * math.dist(*_metres(*zip(scene.start_lonlat, scene.goal_lonlat)))


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--start-lonlat", "10.3", "46.03"],
         r"--start-lonlat \(lon 10\.3, lat 46\.03\) is \(\d+\.?\d*, \d+\.?\d*\) m in the map's CRS EPSG:32632, "
         r"outside the map bounds \(.*\) m, which span lon 9\.99\d* to 10\.06\d*, lat 45\.99\d* to 46\.06\d*"),
        (["--start-lonlat", "10.04", "95"], r"latitude in \[-90, 90\], got \(10\.04, 95\)"),
    ],
)
def test_a_bad_lon_lat_is_refused_naming_both_forms(scene, tmp_path, capsys, flags, message):
    rc = main(["plan", *_map_flags(scene), *flags, "--goal-lonlat", *_ll(scene.goal_lonlat),
               "--out", str(tmp_path / "o")])
    assert rc == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert re.search(message, err), err


def test_start_and_start_lonlat_exclude_each_other(scene, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["plan", *_map_flags(scene), "--start", "1", "2", "--start-lonlat", *_ll(scene.start_lonlat),
              "--goal", "3", "4", "--out", str(tmp_path)])
    assert exc.value.code == 2
    assert "argument --start-lonlat: not allowed with argument --start" in capsys.readouterr().err


def test_lon_lat_on_a_map_without_crs_is_refused(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start-lonlat", "10", "46", "--goal", "35", "5",
               "--out", str(tmp_path / "o")])
    assert rc == EXIT_BAD_INPUT
    assert "the map has no CRS, so WGS 84 longitude / latitude cannot be placed on it" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--landcover", "LC"], "--landcover and --landcover-classes go together"),
        (["--landcover", "LC", "--landcover-classes", "BAD"],
         r"--landcover-classes bad\.csv: grounds \['meadow'\] have no preset"),
        (["--landcover", "LC", "--landcover-classes", "BROKEN"],
         r"broken\.csv', line 2: code 'ten' is not a land-cover code"),
        (["--landcover", "LC", "--landcover-classes", "OTHER"],  # another product's codes: every cell unknown
         r"landcover\.tif' holds codes \[10, 30, 40, 50, 60, 80\] in the \d+ x \d+ raster cells over the map, none of "
         r"them in land-cover classes file '.*other\.csv' \(codes \[1, 2\]\): no cell would take a ground"),
    ],
)
def test_bad_landcover_flags_are_refused(scene, tmp_path, capsys, flags, message):
    (tmp_path / "bad.csv").write_text("code,ground\n30,meadow\n")
    (tmp_path / "broken.csv").write_text("code,ground\nten,grass\n")
    (tmp_path / "other.csv").write_text("code,ground\n1,grass\n2,obstacle\n")
    paths = {"LC": str(scene.landcover), "BAD": str(tmp_path / "bad.csv"), "BROKEN": str(tmp_path / "broken.csv"),
             "OTHER": str(tmp_path / "other.csv")}
    rc = main(["plan", *_map_flags(scene, landcover=False), *[paths.get(f, f) for f in flags],
               "--start-lonlat", *_ll(scene.start_lonlat), "--goal-lonlat", *_ll(scene.goal_lonlat),
               "--out", str(tmp_path / "o")])
    assert rc == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert re.search(message, err) and err.count("\n") == 1


def test_windowed_plans_take_lon_lat_but_no_land_cover(scene, tmp_path, capsys):
    utm = write_geotiff(read_geotiff(scene.dem, reproject_to="utm", cell_size_m=CELL_M), tmp_path / "utm.tif")
    base = ["plan", "--map", str(utm), "--windowed", "--coarse-factor", "4", "--start-lonlat", *_ll(scene.start_lonlat),
            "--goal-lonlat", *_ll(scene.goal_lonlat)]
    rc = main([*base, "--landcover", str(scene.landcover), "--landcover-classes", str(scene.classes),
               "--out", str(tmp_path / "a")])
    assert rc == EXIT_BAD_INPUT and "cannot apply --landcover" in capsys.readouterr().err
    assert main([*base, "--out", str(tmp_path / "b")]) == EXIT_OK
    capsys.readouterr()
    result = json.loads((tmp_path / "b" / "route.json").read_text())
    assert result["start_xy_m"] == pytest.approx(_metres(*scene.start_lonlat)[0].tolist(), abs=1e-6)


def test_reach_from_a_lon_lat_depot(scene, tmp_path, capsys):
    rc = main(["reach", *_map_flags(scene), "--depot-lonlat", *_ll(scene.start_lonlat), "--battery-ah", "2",
               "--out", str(tmp_path)])
    assert rc == EXIT_OK
    capsys.readouterr()
    result = json.loads((tmp_path / "reach.json").read_text())
    assert result["depot_xy_m"] == pytest.approx(_metres(*scene.start_lonlat)[0].tolist(), abs=1e-6)


def test_mission_between_lon_lat_points(scene, tmp_path, capsys):
    goal = lonlat(0.70, 0.16)
    rc = main(["mission", *_map_flags(scene), "--start-lonlat", *_ll(scene.start_lonlat), "--goal-lonlat", *_ll(goal),
               "--battery-ah", "20", "--no-adapt", "--out", str(tmp_path)])
    assert rc == EXIT_OK
    capsys.readouterr()
    result = json.loads((tmp_path / "mission.json").read_text())
    assert result["final_xy_m"] == pytest.approx(_metres(*goal)[0].tolist(), abs=CELL_M)
    rc = main(["mission", "--start-lonlat", "10", "46", "--battery-ah", "20", "--out", str(tmp_path / "example")])
    assert rc == EXIT_BAD_INPUT and "has no CRS" in capsys.readouterr().err


def test_batch_pairs_in_lon_lat(scene, tmp_path, capsys):
    pairs = tmp_path / "pairs.csv"
    start, goal = scene.start_lonlat, lonlat(0.70, 0.16)
    pairs.write_text("name,start_lon,start_lat,goal_lon,goal_lat\n"
                     f"near,{start[0]!r},{start[1]!r},{goal[0]!r},{goal[1]!r}\n"
                     f"off,{start[0]!r},{start[1]!r},10.3,46.03\n")
    rc = main(["batch", *_map_flags(scene), "--pairs", str(pairs), "--no-progress", "--out", str(tmp_path / "o")])
    assert rc == EXIT_NOT_ACHIEVED  # the pair off the map is an error row, as in metres
    capsys.readouterr()
    with open(tmp_path / "o" / "batch.csv", newline="") as fh:
        rows = {r["name"]: r for r in csv.DictReader(fh)}
    assert rows["near"]["status"] == "exact" and rows["off"]["status"] == "error"
    assert [float(rows["near"][k]) for k in ("start_x_m", "start_y_m")] == pytest.approx(
        _metres(*start)[0].tolist(), abs=1e-6)
    assert "outside the map" in rows["off"]["error"]
