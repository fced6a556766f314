"""ROS 2 out: a route as a nav_msgs/Path bag (MCAP file or bag directory) read back."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import terrain
from planner import plan_route, write_route_bag
from planner.cost_spec import CostSpec
from planner.ros_export import read_route_bag, route_pose_times_s
from planner.route import evaluate_route
from terrawatt_base.errors import FileFormatError, GridMismatchError, InvalidParameterError

pytest.importorskip("rosbags", reason="ROS 2 bags need the ros extra (rosbags)")

ORIGIN_UTM = (512_000.0, 4_990_000.0)  # zone 33N


@pytest.fixture(scope="module")
def wall():
    """The wall map (a 1-cell wall at x in [20, 21) m open at y in [30, 34) m), its cost and a lattice route around it."""
    tmap = terrain.wall_map((40, 40), 1.0, wall_col=20, gap_rows=(30, 34), ground="asphalt")
    cost = CostSpec().build(tmap)
    route = plan_route(tmap, (5.0, 5.0), (35.0, 5.0), cost=cost, planner="lattice")
    assert route.status == "exact" and route.waypoints_m.shape[0] >= 3 and route.turn_energy_j.sum() > 0
    return tmap, cost, route


@pytest.fixture(scope="module")
def utm():
    """A hilly procedural map in UTM zone 33N, its cost and a route across it."""
    tmap = terrain.procedural_map((50, 60), 1.0, seed=7, origin_xy_m=ORIGIN_UTM, obstacle_fraction=0.0)
    tmap.crs = "EPSG:32633"
    cost = CostSpec().build(tmap)
    x0, y0 = ORIGIN_UTM
    route = plan_route(tmap, (x0 + 5.5, y0 + 5.5), (x0 + 54.5, y0 + 44.5), cost=cost, planner="lattice")
    assert route.status == "exact"
    return tmap, cost, route


def test_mcap_round_trip_gives_the_waypoints_elevations_and_frame(tmp_path, wall):
    tmap, cost, route = wall
    path = write_route_bag(tmp_path / "route.mcap", route, tmap, cost=cost)
    assert path == tmp_path / "route.mcap" and path.is_file()
    bag = read_route_bag(path)
    assert bag.frame_id == "map" and bag.stamp_ns == 0
    np.testing.assert_allclose(bag.positions_m[:, :2], route.waypoints_m, rtol=0, atol=1e-9)
    np.testing.assert_allclose(bag.waypoints_m, route.waypoints_m, rtol=0, atol=1e-9)
    z = tmap.sample("elevation", *route.waypoints_m.T, method="bilinear")
    np.testing.assert_allclose(bag.positions_m[:, 2], z, rtol=0, atol=1e-12)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["route.mcap"]  # no temporary left beside it


def test_yaw_follows_each_segment_and_the_last_pose_keeps_the_last(tmp_path, wall):
    tmap, cost, route = wall
    bag = read_route_bag(write_route_bag(tmp_path / "route.mcap", route, tmap, cost=cost))
    d = np.diff(route.waypoints_m, axis=0)
    heading = np.arctan2(d[:, 1], d[:, 0])
    np.testing.assert_allclose(bag.yaw_rad, np.append(heading, heading[-1]), rtol=0, atol=1e-12)


def test_cumulative_energy_is_monotone_and_ends_at_the_route_energy(tmp_path, wall):
    tmap, cost, route = wall
    bag = read_route_bag(write_route_bag(tmp_path / "route.mcap", route, tmap, cost=cost))
    energy = bag.cumulative_energy_j
    assert energy.shape == (route.waypoints_m.shape[0],)
    assert energy[0] == route.turn_energy_j[0] > 0.0 and np.all(np.diff(energy) > 0)  # leaving the start: from rest
    assert energy[-1] == pytest.approx(route.energy_j, rel=1e-12)
    # each step is the segment plus the turn at its far end
    np.testing.assert_allclose(np.diff(energy), route.segment_energy_j + route.turn_energy_j[1:], rtol=1e-12)
    assert bag.summary["energy_j"] == pytest.approx(route.energy_j, rel=1e-12)
    assert bag.summary["status"] == "exact" and bag.summary["shortest_energy_j"] is None  # not compared: null


def test_poses_are_stamped_with_the_planned_leaving_times(tmp_path, wall):
    tmap, cost, route = wall
    stamp = 1_700_000_000_123_456_789
    bag = read_route_bag(write_route_bag(tmp_path / "route.mcap", route, tmap, cost=cost, stamp_ns=stamp))
    assert bag.stamp_ns == stamp
    assert bag.pose_stamps_ns[0] == stamp and np.all(np.diff(bag.pose_stamps_ns) > 0)
    assert abs(int(bag.pose_stamps_ns[-1]) - (stamp + round(route.duration_s * 1e9))) <= 1
    times = route_pose_times_s(route, cost)
    np.testing.assert_array_equal(bag.pose_stamps_ns, stamp + np.rint(times * 1e9).astype(np.int64))
    # without the cost every pose carries the path's stamp
    plain = read_route_bag(write_route_bag(tmp_path / "plain.mcap", route, tmap, stamp_ns=stamp))
    assert np.all(plain.pose_stamps_ns == stamp)


def test_pose_times_on_a_straight_flat_route_are_the_ramped_profiles():
    tmap = terrain.flat_map((10, 30), 1.0)
    cost = CostSpec(speed_mps=0.5).build(tmap)
    route = evaluate_route(cost, [[0.5, 5.5], [10.5, 5.5], [25.5, 5.5]])  # straight on: driven through
    # 0.5 s ramping up to 0.5 m/s (0.0625 m), then 0.5 m/s; the same ramp down at the end (0.5 m/s^2)
    np.testing.assert_allclose(route_pose_times_s(route, cost), [0.0, 20.5, 51.0], rtol=1e-12, atol=1e-12)
    assert route.duration_s == 51.0


def test_the_map_crs_message_states_the_crs_and_the_frame_origin(tmp_path, utm):
    pytest.importorskip("rasterio", reason="the CRS's WKT needs the geo extra (rasterio)")
    tmap, cost, route = utm
    bag = read_route_bag(write_route_bag(tmp_path / "utm.mcap", route, tmap, cost=cost,
                                         frame_origin_xy_m=ORIGIN_UTM))
    assert bag.crs == "EPSG:32633" and "UTM zone 33N" in bag.crs_wkt
    assert bag.frame_origin_xy_m == ORIGIN_UTM
    # poses are local to the frame origin (no UTM-sized numbers) and add back to the waypoints exactly
    np.testing.assert_allclose(bag.positions_m[:, :2], route.waypoints_m - np.array(ORIGIN_UTM), rtol=0, atol=1e-9)
    assert np.abs(bag.positions_m[:, :2]).max() < 100.0
    np.testing.assert_allclose(bag.waypoints_m, route.waypoints_m, rtol=0, atol=1e-9)


def test_a_map_without_crs_says_local_metres(tmp_path, wall):
    tmap, cost, route = wall
    bag = read_route_bag(write_route_bag(tmp_path / "route.mcap", route, tmap))
    assert bag.crs is None and bag.crs_wkt is None and bag.frame_origin_xy_m == (0.0, 0.0)


def test_raw_messages_are_standard_ros2_types(tmp_path, wall):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    tmap, cost, route = wall
    path = write_route_bag(tmp_path / "route.mcap", route, tmap, cost=cost)
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        msgs = {c.topic: reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()}
    assert types == {"/terrawatt/route": "nav_msgs/msg/Path", "/terrawatt/route_energy": "std_msgs/msg/Float64MultiArray",
                     "/terrawatt/map_crs": "std_msgs/msg/String", "/terrawatt/route_summary": "std_msgs/msg/String"}
    path_msg = msgs["/terrawatt/route"]
    assert path_msg.header.frame_id == "map" and all(p.header.frame_id == "map" for p in path_msg.poses)
    q = path_msg.poses[0].pose.orientation
    assert (q.x, q.y) == (0.0, 0.0) and q.z**2 + q.w**2 == pytest.approx(1.0, abs=1e-15)
    dim = msgs["/terrawatt/route_energy"].layout.dim[0]
    assert dim.size == len(path_msg.poses) == dim.stride
    assert json.loads(msgs["/terrawatt/map_crs"].data)["frame_id"] == "map"


def test_a_bag_directory_round_trips_and_is_replaced_whole(tmp_path, wall):
    tmap, cost, route = wall
    target = tmp_path / "route_bag"
    assert write_route_bag(target, route, tmap, cost=cost) == target
    assert sorted(p.name for p in target.iterdir()) == ["metadata.yaml", "route_bag.mcap"]
    np.testing.assert_allclose(read_route_bag(target).waypoints_m, route.waypoints_m, rtol=0, atol=1e-9)
    write_route_bag(target, route, tmap, stamp_ns=7)  # an existing bag is replaced
    assert read_route_bag(target).stamp_ns == 7
    assert sorted(p.name for p in tmp_path.iterdir()) == ["route_bag"]


def test_writing_is_deterministic(tmp_path, wall):
    tmap, cost, route = wall
    a = write_route_bag(tmp_path / "a" / "route.mcap", route, tmap, cost=cost, stamp_ns=5)
    b = write_route_bag(tmp_path / "b" / "route.mcap", route, tmap, cost=cost, stamp_ns=5)
    assert a.read_bytes() == b.read_bytes()


def test_a_folder_that_is_not_a_bag_is_never_replaced(tmp_path, wall):
    tmap, cost, route = wall
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "route.json").write_text("{}")
    with pytest.raises(InvalidParameterError, match="not a ROS 2 bag"):
        write_route_bag(tmp_path / "results", route, tmap)
    assert (tmp_path / "results" / "route.json").read_text() == "{}"


@pytest.mark.parametrize(("name", "kwargs", "match"), [
    ("route.bag", {}, "ROS 1 .bag"),
    ("route.db3", {}, "sqlite3"),
    ("route.mcap", {"stamp_ns": -1}, "stamp_ns must be >= 0"),
    ("route.mcap", {"frame_id": " "}, "frame_id"),
    ("route.mcap", {"topic_prefix": "terrawatt"}, "topic_prefix"),
    ("route.mcap", {"frame_origin_xy_m": (0.0, math.nan)}, r"frame_origin_xy_m\[1\]"),
    ("route.mcap", {"frame_origin_xy_m": (1e308, 0.0)},
     r"frame_origin_xy_m \(1e\+308, 0\) lies 1e\+308 m from the map \(x 0 to 40, y 0 to 40 m\); a map frame origin "
     r"other than \(0, 0\) must lie within 1e\+07 m of the map's bounds: give it in the map's coordinates, in metres"),
])
def test_bad_arguments_are_refused(tmp_path, wall, name, kwargs, match):
    tmap, cost, route = wall
    with pytest.raises(InvalidParameterError, match=match):
        write_route_bag(tmp_path / name, route, tmap, **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_a_route_not_found_and_a_foreign_cost_are_refused(tmp_path, wall):
    tmap, cost, route = wall
    with pytest.raises(InvalidParameterError, match="status 'infeasible'"):
        write_route_bag(tmp_path / "r.mcap", route.replace(status="infeasible", waypoints_m=np.empty((0, 2)),
                                                           segment_energy_j=[], turn_energy_j=[]), tmap)
    with pytest.raises(GridMismatchError):
        write_route_bag(tmp_path / "r.mcap", route, tmap, cost=CostSpec().build(terrain.flat_map((8, 8), 1.0)))
    with pytest.raises(InvalidParameterError, match="duration"):
        write_route_bag(tmp_path / "r.mcap", route, tmap, cost=CostSpec(speed_mps=1.0).build(tmap))


def test_reading_what_is_not_a_route_bag_fails_clearly(tmp_path, wall):
    tmap, cost, route = wall
    other = write_route_bag(tmp_path / "other.mcap", route, tmap, topic_prefix="/robot1")
    with pytest.raises(FileFormatError, match="0 messages on '/terrawatt/route'"):
        read_route_bag(other)
    np.testing.assert_allclose(read_route_bag(other, topic_prefix="/robot1").waypoints_m, route.waypoints_m, atol=1e-9)
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file")
    with pytest.raises(FileFormatError, match="cannot read bag"):
        read_route_bag(junk)
    with pytest.raises(FileFormatError, match="does not exist"):
        read_route_bag(tmp_path / "missing.mcap")


