"""Tests of planner.ros_outputs: nav2_targets and write_ros_outputs."""

from __future__ import annotations

import numpy as np
import pytest

from planner import plan_route
from planner.cost_spec import CostSpec
from planner.ros_outputs import nav2_targets, write_ros_outputs


@pytest.fixture
def wall(wall_map):
    cost = CostSpec().build(wall_map)
    return wall_map, cost, plan_route(wall_map, (5.0, 5.0), (35.0, 5.0), cost=cost, planner="lattice")


def test_nav2_targets_take_a_folder_a_yaml_or_a_prefix(tmp_path):
    assert nav2_targets(f"{tmp_path}/new/") == (tmp_path / "new" / "map.yaml", tmp_path / "new" / "map_energy.yaml")
    assert nav2_targets(tmp_path) == (tmp_path / "map.yaml", tmp_path / "map_energy.yaml")
    assert nav2_targets(tmp_path / "site.yml") == (tmp_path / "site.yaml", tmp_path / "site_energy.yaml")
    assert nav2_targets(f"{tmp_path}/site") == (tmp_path / "site.yaml", tmp_path / "site_energy.yaml")


def test_nothing_asked_writes_nothing(wall, tmp_path):
    assert write_ros_outputs(*wall) == []


def test_the_nav2_maps_and_the_bag(wall, tmp_path):
    pytest.importorskip("rosbags")
    from planner.nav2_map import read_nav2_map
    from planner.ros_export import read_route_bag

    tmap, cost, route = wall
    written = write_ros_outputs(route, tmap, cost, bag=tmp_path / "route.mcap", nav2_map=tmp_path / "nav2",
                                frame_origin_xy_m=(1.0, 2.0))
    assert written == [tmp_path / "route.mcap", tmp_path / "nav2.yaml", tmp_path / "nav2.pgm",
                       tmp_path / "nav2_energy.yaml", tmp_path / "nav2_energy.pgm"]
    bag = read_route_bag(tmp_path / "route.mcap")
    np.testing.assert_allclose(bag.positions_m[:, :2], route.waypoints_m - [1.0, 2.0], atol=1e-9)
    np.testing.assert_array_equal(read_nav2_map(tmp_path / "nav2.yaml").occupied, cost.blocked)


def test_a_route_not_found_writes_no_bag_but_the_maps(wall, tmp_path):
    tmap, cost, route = wall
    lost = route.replace(status="timeout", waypoints_m=np.empty((0, 2)), segment_energy_j=[], turn_energy_j=[])
    written = write_ros_outputs(lost, tmap, cost, bag=tmp_path / "route.mcap", nav2_map=f"{tmp_path}/")
    assert written == [tmp_path / n for n in ("map.yaml", "map.pgm", "map_energy.yaml", "map_energy.pgm")]
    assert not (tmp_path / "route.mcap").exists()


def test_the_energy_geotiff(wall, tmp_path):
    pytest.importorskip("rasterio")
    from planner.energy_costmap import read_energy_geotiff

    tmap, cost, route = wall
    assert write_ros_outputs(route, tmap, cost, energy_geotiff=tmp_path / "e.tif") == [tmp_path / "e.tif"]
    assert np.isnan(read_energy_geotiff(tmp_path / "e.tif").energy_per_metre_j[tmap.obstacle]).all()


def test_check_ros_outputs_refuses_bad_targets_before_any_work(tmp_path):
    from planner.ros_outputs import check_ros_outputs
    from terrain import InvalidParameterError

    check_ros_outputs()
    check_ros_outputs(nav2_map=tmp_path / "site", frame_origin_xy_m=(1.0, 2.0), others=[tmp_path / "route.json"])
    with pytest.raises(InvalidParameterError, match="^frame_origin_xy_m applies to `bag` and nav2_map") as alone:
        check_ros_outputs(frame_origin_xy_m=(1.0, 2.0))
    assert alone.value.parameter == ("frame_origin_xy_m", "bag", "nav2_map")  # the command line says its flags
    with pytest.raises(InvalidParameterError, match="frame_origin_xy_m must be two finite numbers"):
        check_ros_outputs(nav2_map=tmp_path / "site", frame_origin_xy_m=(np.nan, 0.0))
    with pytest.raises(InvalidParameterError, match="^`nav2_map`: .*site.yaml' is also the command's own output") as own:
        check_ros_outputs(nav2_map=tmp_path / "site", others=[tmp_path / "site.yaml"])
    assert own.value.parameter == ("nav2_map",)
    (tmp_path / "in.pgm").write_text("x")
    with pytest.raises(InvalidParameterError, match="^`nav2_map`: writing .* would replace the input") as replaced:
        check_ros_outputs(nav2_map=tmp_path / "in", inputs=[tmp_path / "in.pgm", None])
    assert replaced.value.parameter == "nav2_map"
    pytest.importorskip("rosbags")
    with pytest.raises(InvalidParameterError, match=r"^`nav2_map`: .*site.pgm' is also written for `bag`") as twice:
        check_ros_outputs(bag=tmp_path / "site.pgm", nav2_map=tmp_path / "site")
    assert twice.value.parameter == ("nav2_map", "bag")


def test_check_ros_outputs_checks_the_geotiff_suffix(tmp_path):
    pytest.importorskip("rasterio")
    from planner.ros_outputs import check_ros_outputs
    from terrain import InvalidParameterError

    check_ros_outputs(energy_geotiff=tmp_path / "energy.tif")
    with pytest.raises(InvalidParameterError, match="^`energy_geotiff` writes a GeoTIFF ending in '.tif' or '.tiff'") as bad:
        check_ros_outputs(energy_geotiff=tmp_path / "energy_geotiff.png")
    assert bad.value.parameter == "energy_geotiff"  # marked: the path's word stays a path when a front end renames it
    from terrawatt_cli import error_message
    from terrawatt_cli.ros2 import ROS2_FLAGS

    assert error_message(bad.value, ROS2_FLAGS).startswith("--energy-costmap writes a GeoTIFF ending in '.tif' or "
                                                           "'.tiff', got '") and "energy_geotiff.png'" in str(bad.value)
    assert error_message(bad.value, ROS2_FLAGS).endswith("energy_geotiff.png'")
