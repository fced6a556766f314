"""ROS 2 out: a replayed drive's routes, forecasts and decisions on the drive's clock, read back."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import terrain
from planner import plan_route
from planner.cost_spec import CostSpec
from planner.replay_bag import FORECAST_FIELDS, FORECAST_VALUES, read_replay_bag, write_replay_bag
from planner.ros_export import write_route_bag
from terrawatt_base.errors import DataError, FileFormatError, InvalidParameterError, OutOfBoundsError

pytest.importorskip("rosbags", reason="ROS 2 bags need the ros extra (rosbags)")

START_NS = 1_700_000_000_123_456_789
ORIGIN_UTM = (512_000.0, 4_990_000.0)


@pytest.fixture(scope="module")
def hills():
    """A small hilly procedural map (30 x 40 m, 1 m cells), no obstacles."""
    return terrain.procedural_map((30, 40), 1.0, seed=3, obstacle_fraction=0.0)


def drive(offset=(0.0, 0.0)):
    """The inputs of a short replay: two replans, three forecasts, three decisions (times in s)."""
    dx, dy = offset
    route_a = np.array([[2.5, 2.5], [12.5, 2.5], [20.5, 10.5], [35.5, 25.5]]) + (dx, dy)
    route_b = np.array([[14.0, 6.0], [14.0, 20.0], [35.5, 25.5]]) + (dx, dy)
    forecasts = {
        "time_s": np.array([0.0, 0.5, 4.25]),
        "energy_j": np.array([5000.0, 4900.0, 4100.0]),
        "low_j": np.array([4500.0, 4450.0, 3800.0]),
        "high_j": np.array([5600.0, 5400.0, 4500.0]),
        "actual_j": np.array([math.nan, 4950.0, 4000.0]),
        "soc": np.array([0.9, 0.89, 0.85]),
    }
    decisions = [
        (0.5, {"action": "continue", "reason": "on plan", "time_s": 0.5, "route": None,
               "forecast": {"energy_j": 4900.0, "soc": 0.89}}),
        (4.25, {"action": "new_route", "reason": "sand slower than modelled", "time_s": 4.25,
                "forecast": {"energy_j": 4100.0, "low_j": math.nan}}),
        (4.25, {"action": "continue", "reason": "same instant", "time_s": 4.25}),
    ]
    return {"replans": [(0.0, route_a), (4.25, route_b)], "forecasts": forecasts, "decisions": decisions}


def test_mcap_round_trip_on_the_drives_clock(tmp_path, hills):
    inputs = drive()
    path = write_replay_bag(tmp_path / "replay.mcap", hills, **inputs, start_time_ns=START_NS)
    assert path == tmp_path / "replay.mcap" and sorted(p.name for p in tmp_path.iterdir()) == ["replay.mcap"]
    bag = read_replay_bag(path)
    assert bag.frame_id == "map"
    assert bag.route_stamps_ns.tolist() == [START_NS, START_NS + 4_250_000_000]
    for (_, waypoints), positions, yaw in zip(inputs["replans"], bag.route_positions_m, bag.route_yaw_rad, strict=True):
        np.testing.assert_allclose(positions[:, :2], waypoints, rtol=0, atol=1e-12)
        z = hills.sample("elevation", *waypoints.T, method="bilinear")
        np.testing.assert_allclose(positions[:, 2], z, rtol=0, atol=1e-12)
        d = np.diff(waypoints, axis=0)
        heading = np.arctan2(d[:, 1], d[:, 0])
        np.testing.assert_allclose(yaw, np.append(heading, heading[-1]), rtol=0, atol=1e-12)
    assert bag.forecast_stamps_ns.tolist() == [START_NS, START_NS + 500_000_000, START_NS + 4_250_000_000]
    for name in FORECAST_VALUES:
        np.testing.assert_array_equal(getattr(bag, f"forecast_{name}"), inputs["forecasts"][name])  # NaN kept
    assert bag.decision_stamps_ns.tolist() == [START_NS + 500_000_000] + [START_NS + 4_250_000_000] * 2
    assert [d["reason"] for d in bag.decisions] == ["on plan", "sand slower than modelled", "same instant"]
    assert bag.decisions[0]["forecast"] == {"energy_j": 4900.0, "soc": 0.89} and bag.decisions[0]["route"] is None
    assert bag.decisions[1]["forecast"]["low_j"] is None  # JSON has no NaN
    assert list(bag.decisions[1]) == ["action", "reason", "time_s", "forecast"]  # the dict's order kept
    assert not bag.route_stamps_ns.flags.writeable and not bag.forecast_energy_j.flags.writeable


def test_a_bag_directory_round_trips_and_is_replaced_whole(tmp_path, hills):
    target = tmp_path / "replay_bag"
    assert write_replay_bag(target, hills, **drive()) == target
    assert sorted(p.name for p in target.iterdir()) == ["metadata.yaml", "replay_bag.mcap"]
    bag = read_replay_bag(target)
    assert bag.route_stamps_ns.tolist() == [0, 4_250_000_000] and len(bag.decisions) == 3
    write_replay_bag(target, hills, replans=[], forecasts={}, decisions=[(1.0, {"action": "stop"})])
    again = read_replay_bag(target)
    assert again.route_stamps_ns.size == 0 and again.decisions == ({"action": "stop"},)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["replay_bag"]


def test_writing_is_deterministic_and_what_is_read_writes_the_same_bag(tmp_path, hills):
    a = write_replay_bag(tmp_path / "a" / "replay.mcap", hills, **drive(), start_time_ns=START_NS)
    b = write_replay_bag(tmp_path / "b" / "replay.mcap", hills, **drive(), start_time_ns=START_NS)
    assert a.read_bytes() == b.read_bytes()
    c = write_replay_bag(tmp_path / "c" / "replay.mcap", hills, start_time_ns=START_NS,
                         **read_replay_bag(a).as_inputs(start_time_ns=START_NS))
    assert c.read_bytes() == a.read_bytes()
    d1 = write_replay_bag(tmp_path / "d1" / "replay", hills, **drive())
    d2 = write_replay_bag(tmp_path / "d2" / "replay", hills, **drive())
    for name in ("metadata.yaml", "replay.mcap"):
        assert (d1 / name).read_bytes() == (d2 / name).read_bytes()


def test_raw_messages_are_standard_ros2_types_in_time_order(tmp_path, hills):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    path = write_replay_bag(tmp_path / "replay.mcap", hills, **drive(), start_time_ns=START_NS, frame_id="odom")
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        msgs = [(c.topic, t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages()]
    assert types == {"/terrawatt/route": "nav_msgs/msg/Path", "/terrawatt/remaining_energy": "std_msgs/msg/Float64MultiArray",
                     "/terrawatt/decision": "std_msgs/msg/String"}
    times = [t for _, t, _ in msgs]
    assert times == sorted(times) and len(msgs) == 2 + 3 + 3
    for topic, t, msg in msgs:
        if topic == "/terrawatt/route":
            assert msg.header.frame_id == "odom" and msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec == t
            assert all(p.header.stamp == msg.header.stamp and p.header.frame_id == "odom" for p in msg.poses)
        elif topic == "/terrawatt/remaining_energy":
            dim = msg.layout.dim[0]
            assert dim.label == "energy_j,low_j,high_j,actual_j,soc" and dim.size == 5 == len(msg.data)
        else:
            assert isinstance(json.loads(msg.data)["action"], str)


def test_empty_inputs_declare_the_topics_without_messages(tmp_path, hills):
    path = write_replay_bag(tmp_path / "empty.mcap", hills, replans=[], decisions=(),
                            forecasts={name: np.empty(0) for name in FORECAST_FIELDS})
    bag = read_replay_bag(path)
    assert bag.frame_id is None and bag.route_positions_m == () and bag.decisions == ()
    assert bag.route_stamps_ns.shape == bag.forecast_stamps_ns.shape == bag.forecast_soc.shape == (0,)
    assert read_replay_bag(write_replay_bag(tmp_path / "none.mcap", hills, replans=[], forecasts={},
                                           decisions=[])).forecast_energy_j.shape == (0,)


def test_poses_are_relative_to_the_frame_origin(tmp_path):
    tmap = terrain.procedural_map((30, 40), 1.0, seed=5, origin_xy_m=ORIGIN_UTM, obstacle_fraction=0.0)
    inputs = drive(offset=ORIGIN_UTM)
    bag = read_replay_bag(write_replay_bag(tmp_path / "utm.mcap", tmap, **inputs, frame_origin_xy_m=ORIGIN_UTM))
    for (_, waypoints), positions in zip(inputs["replans"], bag.route_positions_m, strict=True):
        np.testing.assert_allclose(positions[:, :2], waypoints - np.array(ORIGIN_UTM), rtol=0, atol=1e-9)
        assert np.abs(positions[:, :2]).max() < 100.0  # no UTM-sized numbers in the poses
    back = bag.as_inputs(frame_origin_xy_m=ORIGIN_UTM)["replans"]
    np.testing.assert_allclose(back[1][1], inputs["replans"][1][1], rtol=0, atol=1e-9)
    # without an origin the poses are the map's coordinates
    plain = read_replay_bag(write_replay_bag(tmp_path / "plain.mcap", tmap, **inputs))
    np.testing.assert_allclose(plain.route_positions_m[0][:, :2], inputs["replans"][0][1], rtol=0, atol=1e-9)


def test_unknown_forecast_values_are_nan(tmp_path, hills):
    forecasts = {name: np.full(2, math.nan) for name in FORECAST_VALUES} | {"time_s": np.array([1.0, 2.0])}
    bag = read_replay_bag(write_replay_bag(tmp_path / "nan.mcap", hills, replans=[], forecasts=forecasts,
                                           decisions=[]))
    assert bag.forecast_stamps_ns.tolist() == [10**9, 2 * 10**9]
    assert all(np.isnan(getattr(bag, f"forecast_{name}")).all() for name in FORECAST_VALUES)


def test_a_single_waypoint_route_has_one_pose_heading_east(tmp_path, hills):
    bag = read_replay_bag(write_replay_bag(tmp_path / "one.mcap", hills, replans=[(2.0, [[5.0, 5.0]])],
                                           forecasts={}, decisions=[]))
    assert bag.route_positions_m[0].shape == (1, 3) and bag.route_yaw_rad[0].tolist() == [0.0]


@pytest.mark.parametrize(("key", "change", "match"), [
    ("replans", lambda d: d["replans"].reverse(), r"replans times must not decrease: replans\[1\] at 0.0 s"),
    ("forecasts", lambda d: d["forecasts"]["time_s"].__setitem__(2, 0.25),
     r"forecasts\['time_s'\] times must not decrease: forecasts\['time_s'\]\[2\] at 0.25 s"),
    ("decisions", lambda d: d["decisions"].insert(0, (9.0, {"action": "stop"})),
     r"decisions times must not decrease: decisions\[1\] at 0.5 s"),
])
def test_unsorted_times_are_refused_naming_the_input(tmp_path, hills, key, change, match):
    inputs = drive()
    change(inputs)
    with pytest.raises(DataError, match=match):
        write_replay_bag(tmp_path / "replay.mcap", hills, **inputs)
    assert list(tmp_path.iterdir()) == []


def test_times_before_the_clock_starts_are_refused(tmp_path, hills):
    late = {"replans": [(-1.0, [[5.0, 5.0]])], "forecasts": {}, "decisions": []}
    with pytest.raises(DataError, match=r"replans\[0\] at -1.0 s is off the bag's clock"):
        write_replay_bag(tmp_path / "replay.mcap", hills, **late)
    bag = read_replay_bag(write_replay_bag(tmp_path / "replay.mcap", hills, **late, start_time_ns=START_NS))
    assert bag.route_stamps_ns.tolist() == [START_NS - 1_000_000_000]


def _with(key, value):
    inputs = drive()
    inputs[key] = value
    return inputs


def _forecasts(**changes):
    out = dict(drive()["forecasts"])
    out.update(changes)
    return {k: v for k, v in out.items() if v is not None}


@pytest.mark.parametrize(("inputs", "match"), [
    (_with("replans", [(0.0, np.zeros((3, 3)))]), r"replans\[0\]\[1\] \(waypoints_m\) must have shape \(N, 2\).*\(3, 3\)"),
    (_with("replans", [(0.0, np.zeros((0, 2)))]), r"replans\[0\]\[1\] \(waypoints_m\) must have shape \(N, 2\) with N >= 1"),
    (_with("replans", [(0.0, [1.0, 2.0])]), r"replans\[0\]\[1\] \(waypoints_m\) must be a 2-D array"),
    (_with("replans", [(0.0, [[1.0, math.nan]])]), r"replans\[0\]\[1\] \(waypoints_m\) has 1 NaN"),
    (_with("replans", [(0.0,)]), r"replans\[0\] must be a pair"),
    (_with("replans", np.zeros((2, 2))), "replans must be a sequence"),
    (_with("decisions", [(math.inf, {})]), r"decisions\[0\]\[0\] \(time_s\) must be finite"),
    (_with("forecasts", _forecasts(soc=np.array([0.9, 0.8]))), "equal lengths"),
    (_with("forecasts", _forecasts(energy_j=np.ones((3, 1)))), r"forecasts\['energy_j'\] must be a 1-D array"),
    (_with("forecasts", _forecasts(time_s=np.array([0.0, math.nan, 2.0]))), r"forecasts\['time_s'\] has 1 NaN"),
    (_with("forecasts", _forecasts(energy_j=np.array([1.0, -math.inf, 2.0]))), r"forecasts\['energy_j'\] has infinite"),
    (_with("forecasts", _forecasts(actual_j=np.array([1.0, math.inf, 2.0]))), r"forecasts\['actual_j'\] has infinite"),
    (_with("forecasts", _forecasts(soc=None)), r"missing \['soc'\]"),
    (_with("forecasts", _forecasts(power_w=np.zeros(3))), r"unknown \['power_w'\]"),
    (_with("forecasts", [1.0, 2.0]), "forecasts must be a mapping"),
    (_with("decisions", [(0.0, "continue")]), r"decisions\[0\]\[1\] must be a dict"),
    (_with("decisions", [(0.0, {"when": object()})]), r"decisions\[0\]\[1\] is not JSON-able"),
])
def test_bad_inputs_are_refused(tmp_path, hills, inputs, match):
    with pytest.raises(InvalidParameterError, match=match):
        write_replay_bag(tmp_path / "replay.mcap", hills, **inputs)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("name", "kwargs", "match"), [
    ("replay.bag", {}, "ROS 1 .bag"),
    ("replay.mcap", {"start_time_ns": -1}, "start_time_ns must be >= 0"),
    ("replay.mcap", {"frame_id": " "}, "frame_id"),
    ("replay.mcap", {"topic_prefix": "/terrawatt/"}, "topic_prefix"),
    ("replay.mcap", {"frame_origin_xy_m": (0.0, math.nan)}, r"frame_origin_xy_m\[1\]"),
    ("replay.mcap", {"frame_origin_xy_m": (0.0, 1e308)},
     r"frame_origin_xy_m \(0, 1e\+308\) lies 1e\+308 m from the map"),
])
def test_bad_arguments_are_refused(tmp_path, hills, name, kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        write_replay_bag(tmp_path / name, hills, **drive(), **kwargs)
    with pytest.raises(InvalidParameterError, match="terrain must be a TerrainMap"):
        write_replay_bag(tmp_path / "replay.mcap", "map.npz", **drive())
    assert list(tmp_path.iterdir()) == []


def test_numpy_values_in_decisions_become_json(tmp_path, hills):
    decision = {"action": "manoeuvre", "manoeuvre": {"time_s": np.array([0.0, 0.5]), "v_mps": np.array([0.2, math.nan])},
                "count": np.int64(3)}
    bag = read_replay_bag(write_replay_bag(tmp_path / "replay.mcap", hills, replans=[], forecasts={},
                                           decisions=[(1.0, decision)]))
    assert bag.decisions == ({"action": "manoeuvre", "manoeuvre": {"time_s": [0.0, 0.5], "v_mps": [0.2, None]},
                              "count": 3},)


def test_a_waypoint_off_the_map_names_the_replan(tmp_path, hills):
    inputs = _with("replans", [(0.0, [[5.0, 5.0]]), (1.0, [[5.0, 5.0], [80.0, 5.0]])])
    with pytest.raises(OutOfBoundsError, match=r"replans\[1\]\[1\]"):
        write_replay_bag(tmp_path / "replay.mcap", hills, **inputs)
    assert list(tmp_path.iterdir()) == []


def test_reading_what_is_not_a_replay_bag_fails_clearly(tmp_path, hills):
    other = write_replay_bag(tmp_path / "other.mcap", hills, **drive(), topic_prefix="/robot1")
    with pytest.raises(FileFormatError, match="no topic '/terrawatt/route'.*not a terrawatt replay bag"):
        read_replay_bag(other)
    assert len(read_replay_bag(other, topic_prefix="/robot1").decisions) == 3
    flat = terrain.flat_map((10, 10), 1.0)
    planned = plan_route(flat, (1.5, 1.5), (8.5, 8.5), cost=CostSpec().build(flat), planner="lattice")
    route_bag = write_route_bag(tmp_path / "route.mcap", planned, flat)
    with pytest.raises(FileFormatError, match="'/terrawatt/remaining_energy'"):
        read_replay_bag(route_bag)
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file")
    with pytest.raises(FileFormatError, match="cannot read bag"):
        read_replay_bag(junk)
    with pytest.raises(FileFormatError, match="does not exist"):
        read_replay_bag(tmp_path / "missing.mcap")
