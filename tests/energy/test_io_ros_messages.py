"""Tests of energy.io.ros_messages: a log as ROS messages, live messages as a log (the same log a bag of them gives)."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest
from energy_io_samples import requires_rosbags

from energy import InteractionLog, LogMeta
from energy.io import BagTopics, DriveBagTopics, LogCleaning, log_from_messages, read_rosbag, write_drive_bag
from energy.io.ros_messages import DEFAULT_START_TIME_NS, DRIVE_MESSAGE_TYPES, MAX_STAMP_NS, messages_from_log
from terrain import DataError, InvalidParameterError, UnitError

TOPICS = DriveBagTopics()


def drive_log(seed: int = 0, n: int = 30, *, currents: bool = True, battery: bool = True,
              pose: bool = True) -> InteractionLog:
    """A small drive: 10 Hz drive stream, 50 Hz IMU bracketing it."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.1
    ta = -0.01 + np.arange(5 * n - 3) * 0.02
    v = 0.6 + 0.1 * np.cos(t)
    return InteractionLog(
        t, v, 0.25 * np.sin(t),
        2.0 + rng.random(n) if currents else None, 2.5 + rng.random(n) if currents else None,
        ta, 9.8 + 0.3 * rng.standard_normal(ta.size),
        pose_xyh=np.column_stack([np.cumsum(v) * 0.1, 0.1 * t, 0.3 * t]) if pose else None,
        gyro_z_radps=0.25 * np.sin(ta),
        battery_voltage_v=25.0 - 0.02 * t if battery else None,
        battery_current_a=4.0 + rng.random(n) if battery else None,
        meta=LogMeta(robot="husky", velocity_source="measured"),
    )


def typestore(kind: str):
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS1_NOETIC if kind == "ros1" else Stores.ROS2_JAZZY)


def by_role(messages) -> dict:
    """The (stamp_ns, message) pairs of each stream, by log_from_messages' argument names."""
    topics = {TOPICS.odom_topic: "odom", TOPICS.imu_topic: "imu", TOPICS.current_topics[0]: "current_left",
              TOPICS.current_topics[1]: "current_right", TOPICS.battery_topic: "battery"}
    out: dict = {}
    for ns, topic, _, msg in messages:
        if topic in topics:
            out.setdefault(topics[topic], []).append((ns, msg))
    return out


def assert_same_log(a: InteractionLog, b: InteractionLog) -> None:
    for name in ("time_s", "v_mps", "omega_radps", "current_left_a", "current_right_a", "accel_time_s",
                 "accel_z_mps2", "pose_xyh", "gyro_z_radps", "battery_voltage_v", "battery_current_a"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None), name
        if x is not None:
            np.testing.assert_array_equal(x, y, err_msg=name)
    assert a.meta.start_time_ns == b.meta.start_time_ns
    assert a.meta.velocity_source == b.meta.velocity_source == "measured"
    assert a.meta.gravity_removed == b.meta.gravity_removed


def namespaces(msg):
    """A rosbags message as plain attribute objects, like an rclpy message (no dataclass)."""
    if dataclasses.is_dataclass(msg):
        return SimpleNamespace(**{f.name: namespaces(getattr(msg, f.name)) for f in dataclasses.fields(msg)})
    return msg


@requires_rosbags
@pytest.mark.parametrize("kind", ["ros2", "ros1"])
@pytest.mark.parametrize("streams", ["all", "bare"])
def test_live_messages_give_the_log_a_bag_of_them_gives(tmp_path, kind, streams):
    full = streams == "all"
    log = drive_log(1, currents=full, battery=full)
    path = write_drive_bag(log, tmp_path / ("drive.bag" if kind == "ros1" else "drive.mcap"))
    from_bag = read_rosbag(path, BagTopics(cmd_vel_topic=TOPICS.odom_topic, imu_topic=TOPICS.imu_topic,
                                           current_topics=TOPICS.current_topics, battery_topic=TOPICS.battery_topic),
                           robot="husky")
    live = log_from_messages(**by_role(messages_from_log(log, typestore(kind))), robot="husky")
    assert_same_log(live, from_bag)
    assert live.meta.source == "ROS messages" and live.meta.robot == "husky"
    assert live.has_currents is full and live.has_battery_power is full
    if not full:
        assert "current topic(s) ['/drive/current_left', '/drive/current_right'] not in the messages" in \
            live.meta.missing_currents


@requires_rosbags
def test_rclpy_like_messages_are_read_by_field_name():
    log = drive_log(2)
    streams = {role: [(ns, namespaces(m)) for ns, m in pairs]
               for role, pairs in by_role(messages_from_log(log, typestore("ros2"))).items()}
    live = log_from_messages(**streams)
    reference = log_from_messages(**by_role(messages_from_log(log, typestore("ros2"))))
    assert_same_log(live, reference)
    assert live.meta.start_time_ns == DEFAULT_START_TIME_NS - 10_000_000  # the first IMU sample, 10 ms early


@requires_rosbags
def test_messages_from_log_fills_each_stream():
    log = drive_log(3)
    lonlat = np.column_stack([np.full(len(log), 7.5), np.linspace(45.0, 45.001, len(log))])
    messages = messages_from_log(log, typestore("ros2"), time_zero_ns=2 * 10**18 // 2, lonlat_deg=lonlat)
    stamps = [ns for ns, *_ in messages]
    assert stamps == sorted(stamps) and stamps[0] == 10**18 - 10_000_000
    counts = {}
    for _, topic, *_ in messages:
        counts[topic] = counts.get(topic, 0) + 1
    n, m = len(log), log.accel_time_s.size
    assert counts == {"/odom": n, "/imu/data": m, "/drive/current_left": n, "/drive/current_right": n,
                      "/battery": n, "/gps/fix": n}
    assert {t for _, _, t, _ in messages} == set(DRIVE_MESSAGE_TYPES.values())
    odom = next(msg for _, topic, _, msg in messages if topic == "/odom")
    assert odom.header.frame_id == "map" and odom.child_frame_id == "base_link"
    assert odom.twist.twist.linear.x == log.v_mps[0] and odom.pose.pose.orientation.w == 1.0
    battery = [msg for _, topic, _, msg in messages if topic == "/battery"]
    assert battery[0].current == float(np.float32(-log.battery_current_a[0]))  # negative when discharging, float32
    fix = [msg for _, topic, _, msg in messages if topic == "/gps/fix"][-1]
    assert (fix.longitude, fix.latitude, fix.status.status) == (7.5, 45.001, 0) and np.isnan(fix.altitude)
    ros1 = messages_from_log(log, typestore("ros1"))
    assert ros1[0][3].header.seq == 0 and ros1[0][0] == DEFAULT_START_TIME_NS - 10_000_000


@requires_rosbags
def test_messages_from_log_refuses_what_ros_cannot_carry():
    ts = typestore("ros2")
    with pytest.raises(InvalidParameterError, match="log has no pose_xyh"):
        messages_from_log(drive_log(pose=False), ts)
    with pytest.raises(InvalidParameterError, match=r"stamps must lie in \(0, "):
        messages_from_log(drive_log(), ts, time_zero_ns=5_000_000)  # the first IMU sample at -5 ms
    with pytest.raises(InvalidParameterError, match=r"stamps must lie in \(0, "):
        messages_from_log(drive_log(), ts, time_zero_ns=MAX_STAMP_NS)
    with pytest.raises(InvalidParameterError, match="typestore must be a rosbags Typestore"):
        messages_from_log(drive_log(), object())
    with pytest.raises(InvalidParameterError, match=r"lonlat_deg must have shape \(30, 2\)"):
        messages_from_log(drive_log(), ts, lonlat_deg=np.zeros((30, 1)))


def test_drive_bag_topics_are_checked():
    assert TOPICS.bag_topics(drive_clock="velocity").drive_clock == "velocity"
    with pytest.raises(InvalidParameterError, match="each stream needs its own topic"):
        DriveBagTopics(battery_topic="/odom")
    with pytest.raises(InvalidParameterError, match=r"DriveBagTopics\.navsat_topic must start with '/'"):
        DriveBagTopics(navsat_topic="gps/fix")
    with pytest.raises(InvalidParameterError, match="current_topics must be two topics"):
        DriveBagTopics(current_topics="/current")
    with pytest.raises(InvalidParameterError, match="base_frame"):
        DriveBagTopics(base_frame="")


@requires_rosbags
def test_log_from_messages_refuses_empty_unsorted_or_foreign_input():
    streams = by_role(messages_from_log(drive_log(4), typestore("ros2")))
    with pytest.raises(DataError, match=r"ROS messages: topic '/odom' \(odom\) has no messages"):
        log_from_messages(**{**streams, "odom": []})
    with pytest.raises(DataError, match=r"topic '/drive/current_right' \(current_right\) has no messages"):
        log_from_messages(**{**streams, "current_right": []})
    imu = list(streams["imu"])
    imu[3], imu[4] = imu[4], imu[3]
    with pytest.raises(DataError, match=r"topic '/imu/data' \(imu\): receive stamps are not sorted; 1 step\(s\) go "
                                        r"backwards, first at index 4"):
        log_from_messages(**{**streams, "imu": imu})
    with pytest.raises(InvalidParameterError, match="current_left and current_right must both be given or both be"):
        log_from_messages(**{**streams, "current_right": None})
    with pytest.raises(InvalidParameterError, match=r"topic '/odom' \(odom\): the messages lack field\(s\) "
                                                    r"\['pose.pose.position', .*expected a nav_msgs/msg/Odometry"):
        log_from_messages(**{**streams, "odom": streams["imu"]})
    with pytest.raises(InvalidParameterError, match=r"'/battery' \(battery\): item 0 must be a \(stamp_ns, message\)"):
        log_from_messages(**{**streams, "battery": [m for _, m in streams["battery"]]})
    with pytest.raises(InvalidParameterError, match=r"battery\[0\] stamp_ns must be an integer"):
        log_from_messages(**{**streams, "battery": [(float(ns), m) for ns, m in streams["battery"]]})
    with pytest.raises(InvalidParameterError, match=r"topic '/imu/data' \(imu\) must be a list"):
        log_from_messages(**{**streams, "imu": "imu"})
    with pytest.raises(InvalidParameterError, match="topics must be a DriveBagTopics"):
        log_from_messages(**streams, topics={"odom": "/odom"})


@requires_rosbags
def test_log_from_messages_checks_like_the_reader():
    log = drive_log(5)
    streams = by_role(messages_from_log(log, typestore("ros2")))
    # a current in mA published as A: the reader's unit check
    milli = [(ns, type(m)(data=m.data * 1000.0)) for ns, m in streams["current_left"]]
    with pytest.raises(UnitError, match=r"ROS messages: /drive/current_left \(left\) is declared in A but its "
                                        r"values look like mA"):
        log_from_messages(**{**streams, "current_left": milli})
    unchecked = LogCleaning(check_units=False)
    assert log_from_messages(**{**streams, "current_left": milli}, cleaning=unchecked).current_left_a[0] == \
        pytest.approx(1000.0 * log.current_left_a[0])
    # header stamps far from the receive stamps: the reader's clock check
    late = [(ns + 2_000_000_000, m) for ns, m in streams["odom"]]
    with pytest.raises(DataError, match=r"topic '/odom': median \(receive time - header stamp\) is 2 s"):
        log_from_messages(**{**streams, "odom": late})
    # renamed topics name the streams in messages and notes
    topics = DriveBagTopics(odom_topic="/husky/odom", imu_topic="/husky/imu")
    renamed = log_from_messages(**streams, topics=topics, source="node buffer")
    assert "/husky/imu: header stamps" in renamed.meta.notes and renamed.meta.source == "node buffer"
    with pytest.raises(DataError, match=r"node buffer: topic '/husky/odom' \(odom\) has no messages"):
        log_from_messages(**{**streams, "odom": []}, topics=topics, source="node buffer")
