"""The ROS 2 / Nav2 plan options (terrawatt_cli.ros2): targets, checks before any work, the files written, end to end through ``terrawatt plan``."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

import terrain
from planner import plan_route
from planner.cost_spec import CostSpec
from planner.energy_costmap import read_energy_geotiff
from planner.nav2_map import read_nav2_map
from planner.ros_export import read_route_bag
from terrawatt_base.errors import InvalidParameterError
from terrawatt_cli import error_message, main
from terrawatt_cli.ros2 import ROS2_FLAGS, add_ros2_arguments, check_ros2_outputs, nav2_targets, write_ros2_outputs

pytest.importorskip("rosbags", reason="ROS 2 bags need the ros extra (rosbags)")


@pytest.fixture(scope="module")
def wall():
    """The wall map (a 1-cell wall at x in [20, 21) m open at y in [30, 34) m), its cost and a lattice route around it
    (the fixture of tests/planner/test_ros_export.py: the two test folders share no helper module)."""
    tmap = terrain.wall_map((40, 40), 1.0, wall_col=20, gap_rows=(30, 34), ground="asphalt")
    cost = CostSpec().build(tmap)
    route = plan_route(tmap, (5.0, 5.0), (35.0, 5.0), cost=cost, planner="lattice")
    assert route.status == "exact" and route.waypoints_m.shape[0] >= 3 and route.turn_energy_j.sum() > 0
    return tmap, cost, route


def _parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_ros2_arguments(parser)
    return parser.parse_args(argv)


def test_nav2_targets_take_a_folder_a_yaml_or_a_prefix(tmp_path):
    assert nav2_targets(f"{tmp_path}/new/") == (tmp_path / "new" / "map.yaml", tmp_path / "new" / "map_energy.yaml")
    assert nav2_targets(str(tmp_path)) == (tmp_path / "map.yaml", tmp_path / "map_energy.yaml")
    assert nav2_targets(f"{tmp_path}/site.yaml") == (tmp_path / "site.yaml", tmp_path / "site_energy.yaml")
    assert nav2_targets(f"{tmp_path}/site") == (tmp_path / "site.yaml", tmp_path / "site_energy.yaml")


def test_the_ros2_flags_write_the_bag_the_nav2_maps_and_the_costmap(tmp_path, wall, capsys):
    pytest.importorskip("rasterio", reason="--energy-costmap needs the geo extra (rasterio)")
    tmap, cost, route = wall
    args = _parse(["--ros2-out", str(tmp_path / "route.mcap"), "--nav2-map", str(tmp_path / "nav2" / "site"),
                   "--energy-costmap", str(tmp_path / "energy.tif"), "--map-frame-origin", "2", "3"])
    check_ros2_outputs(args, [])
    written = write_ros2_outputs(args, route, tmap, cost)
    nav2 = tmp_path / "nav2"
    assert written == [tmp_path / "route.mcap", nav2 / "site.yaml", nav2 / "site.pgm", nav2 / "site_energy.yaml",
                       nav2 / "site_energy.pgm", tmp_path / "energy.tif"]
    bag = read_route_bag(tmp_path / "route.mcap")
    np.testing.assert_allclose(bag.positions_m[:, :2], route.waypoints_m - [2.0, 3.0], rtol=0, atol=1e-9)
    occupancy = read_nav2_map(nav2 / "site.yaml")
    assert occupancy.grid.origin_xy_m == (-2.0, -3.0)
    np.testing.assert_array_equal(occupancy.occupied, cost.blocked)
    assert read_nav2_map(nav2 / "site_energy.yaml").mode == "raw"
    assert np.isnan(read_energy_geotiff(tmp_path / "energy.tif").energy_per_metre_j[tmap.obstacle]).all()
    capsys.readouterr()


def test_a_map_frame_origin_far_from_the_map_is_refused_before_planning(tmp_path, capsys):
    rc = main(["plan", "--map", "example", "--start", "5", "5", "--goal", "40", "40", "--planner", "lattice",
               "--nav2-map", str(tmp_path / "nav2" / "site"), "--ros2-out", str(tmp_path / "route.mcap"),
               "--map-frame-origin", "1e308", "0", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1
    assert err.startswith("terrawatt: error: --map-frame-origin (1e+308, 0) lies 1e+308 m from the map (x 0 to ")
    assert "must lie within 1e+07 m of the map's bounds" in err
    assert list(tmp_path.iterdir()) == []  # nothing planned, nothing written


def test_the_ros2_flags_are_checked_before_any_work(tmp_path):
    check_ros2_outputs(_parse([]), [])  # nothing asked: nothing to check
    with pytest.raises(InvalidParameterError) as alone:
        check_ros2_outputs(_parse(["--map-frame-origin", "1", "2"]), [])
    assert error_message(alone.value, ROS2_FLAGS) == ("--map-frame-origin applies to --ros2-out and --nav2-map; give "
                                                      "one of them")  # the library's parameters, said by their flags
    with pytest.raises(InvalidParameterError, match="finite"):
        check_ros2_outputs(_parse(["--nav2-map", str(tmp_path / "m"), "--map-frame-origin", "nan", "0"]), [])
    dem = tmp_path / "dem.tif"
    dem.write_bytes(b"")
    with pytest.raises(InvalidParameterError, match="would replace the input"):
        check_ros2_outputs(_parse(["--energy-costmap", str(dem)]), [dem])
    with pytest.raises(InvalidParameterError, match="'.tif' or '.tiff'"):
        check_ros2_outputs(_parse(["--energy-costmap", str(tmp_path / "energy.png")]), [])
    with pytest.raises(InvalidParameterError, match="sqlite3"):
        check_ros2_outputs(_parse(["--ros2-out", str(tmp_path / "route.db3")]), [])
    with pytest.raises(InvalidParameterError, match="is also the command's own output"):
        check_ros2_outputs(_parse(["--ros2-out", str(tmp_path / "route.json")]), [], [tmp_path / "route.json"])
    with pytest.raises(InvalidParameterError, match="is also written for `bag`") as twice:
        check_ros2_outputs(_parse(["--ros2-out", str(tmp_path / "m.yaml"), "--nav2-map", str(tmp_path / "m")]), [])
    assert error_message(twice.value, ROS2_FLAGS).startswith("--nav2-map: ")
    assert error_message(twice.value, ROS2_FLAGS).endswith("is also written for --ros2-out; give another name")
    coarse = _parse(["--nav2-map", str(tmp_path / "m")])
    coarse.coarse_factor = 4
    with pytest.raises(InvalidParameterError, match="need the whole map"):
        check_ros2_outputs(coarse, [])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dem.tif"]  # nothing written by the checks


def test_no_bag_for_a_route_not_found(tmp_path, wall, capsys):
    tmap, cost, route = wall
    lost = route.replace(status="timeout", waypoints_m=np.empty((0, 2)), segment_energy_j=[], turn_energy_j=[])
    args = _parse(["--ros2-out", str(tmp_path / "route.mcap"), "--nav2-map", f"{tmp_path}/"])
    assert write_ros2_outputs(args, lost, tmap, cost) == [tmp_path / n for n in
                                                          ("map.yaml", "map.pgm", "map_energy.yaml", "map_energy.pgm")]
    assert "not written" in capsys.readouterr().out and not (tmp_path / "route.mcap").exists()


def test_plan_command_writes_ros2_and_nav2_outputs(tmp_path, capsys, wall):
    """End to end through ``terrawatt plan``: passes once terrawatt_cli/plan.py is wired to terrawatt_cli.ros2."""
    pytest.importorskip("rasterio", reason="--energy-costmap needs the geo extra (rasterio)")
    tmap, _, _ = wall
    path = tmap.save(tmp_path / "wall.npz")
    out = tmp_path / "out"
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5", "--planner", "lattice",
               "--out", str(out), "--ros2-out", str(out / "route.mcap"), "--nav2-map", str(out / "nav2"),
               "--energy-costmap", str(out / "energy.tif")])
    printed = capsys.readouterr().out
    assert rc == 0
    data = json.loads((out / "route.json").read_text())
    bag = read_route_bag(out / "route.mcap")
    np.testing.assert_allclose(bag.waypoints_m, data["routes"]["min_energy"]["waypoints_m"], rtol=0, atol=1e-9)
    assert bag.cumulative_energy_j[-1] == pytest.approx(data["routes"]["min_energy"]["energy_j"], rel=1e-12)
    assert read_nav2_map(out / "nav2.yaml").occupied[:, 20].sum() == 36  # the wall: 40 rows but the 4-row gap
    assert (out / "nav2_energy.pgm").is_file() and (out / "energy.tif").is_file()
    assert "route.mcap" in printed and "nav2.yaml" in printed
    # an output that would replace the input DEM is refused before any work
    dem = terrain.write_geotiff(tmap, tmp_path / "wall.tif")
    rc = main(["plan", "--map", str(dem), "--start", "5", "5", "--goal", "35", "5", "--planner", "lattice",
               "--out", str(tmp_path / "out2"), "--energy-costmap", str(dem)])
    assert rc == 2 and "would replace the input" in capsys.readouterr().err
    assert not (tmp_path / "out2").exists()
