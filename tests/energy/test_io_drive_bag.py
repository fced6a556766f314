"""Tests of energy.io.drive_bag: a drive as a ROS 2 MCAP / ROS 1 bag, read back; GPS fixes; the battery topic."""

from __future__ import annotations

import os

import numpy as np
import pytest
from energy_io_samples import requires_rosbags

import energy.io.drive_bag as drive_bag
from energy import InteractionLog, LogMeta
from energy.io import (
    BagTopics,
    DriveBagTopics,
    LogCleaning,
    NavSatTrack,
    read_logs,
    read_navsat,
    read_rosbag,
    write_drive_bag,
)
from energy.io.drive_bag import drive_bag_time_zeros_ns
from energy.io.ros_messages import DEFAULT_START_TIME_NS
from terrain import DataError, InvalidParameterError

TOPICS = DriveBagTopics()
KINDS = [".mcap", ".bag"]


def drive_log(seed: int = 0, n: int = 40, t0_s: float = 0.0, *, currents: bool = True, battery: bool = True,
              gyro: bool = True, pose: bool = True) -> InteractionLog:
    """A small drive: 10 Hz drive stream, 100 Hz IMU from 5 ms before the first drive sample to 5 ms after the last."""
    rng = np.random.default_rng(seed)
    t = t0_s + np.arange(n) * 0.1
    ta = t0_s - 0.005 + np.arange(10 * n - 8) * 0.01
    v = 0.5 + 0.1 * np.sin(t)
    w = 0.2 * np.cos(t)
    heading = 0.4 * t  # beyond pi after ~8 s: wraps on the way back
    xyh = np.column_stack([np.cumsum(v) * 0.1, 0.3 * np.sin(t), heading])
    return InteractionLog(
        t, v, w,
        3.0 + rng.random(n) if currents else None, 3.5 + rng.random(n) if currents else None,
        ta, 9.81 + 0.2 * rng.standard_normal(ta.size),
        pose_xyh=xyh if pose else None,
        gyro_z_radps=0.3 * np.sin(ta) if gyro else None,
        battery_voltage_v=26.0 - 0.01 * t if battery else None,
        battery_current_a=5.0 + rng.random(n) if battery else None,
        meta=LogMeta(robot="husky", velocity_source="measured"),
    )


def lonlat_of(log: InteractionLog) -> np.ndarray:
    """Longitude, latitude near Quebec City: metres to degrees, roughly."""
    return np.column_stack([-71.2 + log.pose_xyh[:, 0] / 77_000.0, 46.8 + log.pose_xyh[:, 1] / 111_000.0])


def read_back(path, **cleaning) -> InteractionLog:
    topics = BagTopics(cmd_vel_topic=TOPICS.odom_topic, imu_topic=TOPICS.imu_topic,
                       current_topics=TOPICS.current_topics, battery_topic=TOPICS.battery_topic)
    return read_rosbag(path, topics, cleaning=LogCleaning(**cleaning))


def wrapped(angle_rad: np.ndarray) -> np.ndarray:
    return np.angle(np.exp(1j * angle_rad))


def assert_same_streams(read: InteractionLog, log: InteractionLog, shift_s: float) -> None:
    """``read`` holds ``log``'s streams, its times ``shift_s`` later (IMU: the samples bracketing the drive)."""
    np.testing.assert_allclose(read.time_s, log.time_s + shift_s, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(read.v_mps, log.v_mps)
    np.testing.assert_array_equal(read.omega_radps, log.omega_radps)
    np.testing.assert_allclose(read.pose_xyh[:, :2], log.pose_xyh[:, :2], rtol=0, atol=1e-12)
    np.testing.assert_allclose(wrapped(read.pose_xyh[:, 2] - log.pose_xyh[:, 2]), 0.0, atol=1e-12)
    if log.has_currents:
        np.testing.assert_array_equal(read.current_left_a, log.current_left_a)
        np.testing.assert_array_equal(read.current_right_a, log.current_right_a)
    else:
        assert not read.has_currents
    ia = np.flatnonzero(log.accel_time_s <= log.time_s[0])[-1]
    ib = np.flatnonzero(log.accel_time_s >= log.time_s[-1])
    ib = ib[0] if ib.size else log.accel_time_s.size - 1
    np.testing.assert_allclose(read.accel_time_s, log.accel_time_s[ia:ib + 1] + shift_s, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(read.accel_z_mps2, log.accel_z_mps2[ia:ib + 1])
    if log.gyro_z_radps is None:
        assert read.gyro_z_radps is None
    else:
        np.testing.assert_array_equal(read.gyro_z_radps, log.gyro_z_radps[ia:ib + 1])
    if log.battery_voltage_v is None:
        assert read.battery_voltage_v is None and read.battery_current_a is None
    else:  # BatteryState's fields are float32
        np.testing.assert_allclose(read.battery_voltage_v, log.battery_voltage_v, rtol=1e-6)
        np.testing.assert_allclose(read.battery_current_a, log.battery_current_a, rtol=1e-6)


@requires_rosbags
@pytest.mark.parametrize("suffix", KINDS)
def test_a_drive_reads_back_as_the_same_streams(tmp_path, suffix):
    log = drive_log()
    lonlat = lonlat_of(log)
    path = write_drive_bag(log, tmp_path / f"drive{suffix}", lonlat_deg=lonlat, start_time_ns=1_650_000_000 * 10**9)
    assert path == tmp_path / f"drive{suffix}" and path.is_file()
    read = read_back(path)
    # the earliest stamp (the first IMU sample, 5 ms before the drive) is read_rosbag's time zero
    assert read.meta.start_time_ns == 1_650_000_000 * 10**9 - 5_000_000
    assert read.meta.velocity_source == "measured"
    assert_same_streams(read, log, 0.005)
    track = read_navsat(path, TOPICS.navsat_topic, start_time_ns=read.meta.start_time_ns)
    assert isinstance(track, NavSatTrack) and len(track) == len(log)
    np.testing.assert_array_equal(track.time_s, read.time_s)  # on the log's clock
    np.testing.assert_array_equal(track.lonlat_deg, lonlat)
    assert track.status.tolist() == [0] * len(log) and track.has_fix.all() and np.isnan(track.alt_m).all()
    assert track.start_time_ns == read.meta.start_time_ns and track.topic == "/gps/fix"


@requires_rosbags
@pytest.mark.parametrize("suffix", KINDS)
def test_read_navsat_counts_from_the_bag_start_by_default(tmp_path, suffix):
    log = drive_log()
    path = write_drive_bag(log, tmp_path / f"drive{suffix}", lonlat_deg=lonlat_of(log))
    read = read_back(path)
    track = read_navsat(path)
    assert track.start_time_ns == read.meta.start_time_ns == DEFAULT_START_TIME_NS - 5_000_000
    np.testing.assert_array_equal(track.time_s, read.time_s)


@requires_rosbags
@pytest.mark.parametrize("suffix", KINDS)
def test_a_log_without_currents_battery_or_gyro(tmp_path, suffix):
    log = drive_log(3, currents=False, battery=False, gyro=False)
    path = write_drive_bag(log, tmp_path / f"bare{suffix}")
    read = read_back(path)
    assert_same_streams(read, log, 0.005)
    assert "no battery: topic '/battery' not in the bag" in read.meta.notes
    assert "not in the bag" in read.meta.missing_currents
    with pytest.raises(DataError, match=r"topic\(s\) \['/gps/fix'\] not in the bag"):
        read_navsat(path)


@requires_rosbags
@pytest.mark.parametrize("suffix", KINDS)
def test_legs_are_put_one_after_another_on_one_clock(tmp_path, suffix):
    legs = [drive_log(1), drive_log(2, n=30), drive_log(3, n=25, t0_s=7.3)]  # each leg's own clock
    start = 1_600_000_000 * 10**9
    zeros = drive_bag_time_zeros_ns(legs, start)
    assert zeros[0] == start
    for k in (1, 2):  # the next leg's first (IMU) sample one drive period (0.1 s) after the last leg's last sample
        prev_end_ns = zeros[k - 1] + round(max(legs[k - 1].time_s[-1], legs[k - 1].accel_time_s[-1]) * 1e9)
        first_ns = zeros[k] + round(min(legs[k].time_s[0], legs[k].accel_time_s[0]) * 1e9)
        assert first_ns - prev_end_ns == 100_000_000
    lonlat = [lonlat_of(leg) for leg in legs]
    path = write_drive_bag(legs, tmp_path / f"legs{suffix}", lonlat_deg=lonlat, start_time_ns=start)
    # between legs the IMU pauses for 10 of its periods: a gap for the reader
    with pytest.raises(DataError, match="gap"):
        read_back(path)
    read = read_back(path, allow_gaps=True)
    assert len(read) == sum(len(leg) for leg in legs)
    origin = read.meta.start_time_ns
    assert origin == start - 5_000_000
    pieces = read.split_at_gaps()
    assert len(pieces) == 3
    for leg, piece, zero in zip(legs, pieces, zeros.tolist()):
        assert_same_streams(piece, leg, (zero - origin) / 1e9)
    track = read_navsat(path, start_time_ns=origin)
    np.testing.assert_array_equal(track.lonlat_deg, np.vstack(lonlat))
    np.testing.assert_allclose(track.time_s, read.time_s, rtol=0, atol=0)


@requires_rosbags
@pytest.mark.parametrize("suffix", KINDS)
def test_the_bytes_are_the_same_for_the_same_input(tmp_path, suffix):
    legs = [drive_log(4), drive_log(5, n=20)]
    # the MCAP's rosbag2 metadata names its file after the target, so the same name in two folders
    a = write_drive_bag(legs, tmp_path / f"drive{suffix}", lonlat_deg=[lonlat_of(leg) for leg in legs])
    b = write_drive_bag(legs, tmp_path / "sub" / f"drive{suffix}", lonlat_deg=[lonlat_of(leg) for leg in legs])
    assert a.read_bytes() == b.read_bytes()
    write_drive_bag(legs[:1], a)  # replaces the file
    assert a.read_bytes() != b.read_bytes()


@requires_rosbags
def test_a_log_read_from_a_bag_keeps_its_absolute_time(tmp_path):
    path = write_drive_bag(drive_log(6), tmp_path / "first.mcap", start_time_ns=1_610_000_000 * 10**9)
    read = read_back(path)
    again = read_back(write_drive_bag(read, tmp_path / "second.bag"))  # its meta.start_time_ns is the default
    assert again.meta.start_time_ns == read.meta.start_time_ns
    assert_same_streams(again, read, 0.0)


@requires_rosbags
@pytest.mark.parametrize("suffix", KINDS)
def test_a_failed_write_leaves_no_file_and_keeps_the_old_one(tmp_path, suffix, monkeypatch):
    log = drive_log(7)
    target = tmp_path / f"drive{suffix}"

    def broken(bag, messages, *args):
        bag.parent.mkdir(parents=True, exist_ok=True)
        bag.write_bytes(b"half a bag")
        raise OSError("disk full")

    monkeypatch.setattr(drive_bag, "_write_messages", broken)
    with pytest.raises(OSError, match="disk full"):
        write_drive_bag(log, target)
    assert os.listdir(tmp_path) == []
    target.write_bytes(b"the old bag")
    with pytest.raises(OSError, match="disk full"):
        write_drive_bag(log, target)
    assert os.listdir(tmp_path) == [target.name] and target.read_bytes() == b"the old bag"


@requires_rosbags
def test_bad_inputs_raise_library_errors(tmp_path):
    log = drive_log()
    with pytest.raises(InvalidParameterError, match=r"logs\[1\] has no pose_xyh"):
        write_drive_bag([log, drive_log(pose=False)], tmp_path / "a.mcap")
    with pytest.raises(InvalidParameterError, match=r"lonlat_deg\[0\] must have shape \(40, 2\).*\(40, 3\)"):
        write_drive_bag([log], tmp_path / "a.mcap", lonlat_deg=[np.zeros((40, 3))])
    with pytest.raises(InvalidParameterError, match=r"lonlat_deg must have shape \(40, 2\).*\(39, 2\)"):
        write_drive_bag(log, tmp_path / "a.mcap", lonlat_deg=np.zeros((39, 2)))
    with pytest.raises(InvalidParameterError, match=r"one \(N, 2\) array of lon, lat .* per log \(2\), got 1 item"):
        write_drive_bag([log, log], tmp_path / "a.mcap", lonlat_deg=[lonlat_of(log)])
    with pytest.raises(InvalidParameterError, match=r"latitudes in \[-90, 90\]"):
        write_drive_bag(log, tmp_path / "a.mcap", lonlat_deg=lonlat_of(log)[:, ::-1] * [1.0, 2.0])
    (tmp_path / "dir.mcap").mkdir()
    with pytest.raises(InvalidParameterError, match=r"dir\.mcap' is a directory; expected a file name"):
        write_drive_bag(drive_log(pose=False), tmp_path / "dir.mcap")  # the path is checked first
    with pytest.raises(InvalidParameterError, match=r"a '\.mcap' file \(ROS 2\) or a '\.bag' file \(ROS 1\), got "
                                                    r"suffix '\.db3'"):
        write_drive_bag(log, tmp_path / "a.db3")
    with pytest.raises(InvalidParameterError, match=r"logs\[0\] has 1 drive sample; a drive bag needs 2 or more"):
        write_drive_bag(InteractionLog(log.time_s[:1], log.v_mps[:1], log.omega_radps[:1], None, None,
                                       log.accel_time_s, log.accel_z_mps2, pose_xyh=log.pose_xyh[:1]),
                        tmp_path / "a.mcap")
    with pytest.raises(InvalidParameterError, match=r"logs must be an InteractionLog or a non-empty sequence"):
        write_drive_bag([], tmp_path / "a.mcap")
    with pytest.raises(InvalidParameterError, match=r"stamps must lie in \(0, "):
        write_drive_bag(log, tmp_path / "a.mcap", start_time_ns=0)
    with pytest.raises(InvalidParameterError, match="topics must be a DriveBagTopics"):
        write_drive_bag(log, tmp_path / "a.mcap", topics=BagTopics())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir.mcap"]


@requires_rosbags
def test_read_logs_reads_a_drive_bag_with_its_bag_topics(tmp_path):
    log = drive_log(8)
    write_drive_bag(log, tmp_path / "runs" / "drive.bag")
    (read,) = read_logs(tmp_path / "runs", bag=TOPICS.bag_topics(), require_currents=True)
    assert_same_streams(read, log, 0.005)


@requires_rosbags
def test_the_battery_topic_and_a_status_voltage_field_are_one_or_the_other(tmp_path):
    path = write_drive_bag(drive_log(), tmp_path / "drive.mcap")
    with pytest.raises(InvalidParameterError, match="both give the battery voltage; name one of them"):
        read_rosbag(path, BagTopics(cmd_vel_topic="/odom", current_topics=("/status",), current_fields=("l", "r"),
                                    voltage_field="v", battery_topic="/battery"))
    with pytest.raises(InvalidParameterError, match="both give the battery voltage; name one of them"):
        BagTopics(current_topics=("/status",), current_fields=("l", "r"), voltage_field="v", battery_topic="/battery")
    with pytest.raises(InvalidParameterError, match="battery_topic"):
        BagTopics(battery_topic="")


@requires_rosbags
def test_a_battery_topic_far_short_of_the_drive_is_a_gap(tmp_path):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    from energy.io.ros_messages import messages_from_log

    log = drive_log()
    ts = get_typestore(Stores.ROS2_JAZZY)
    messages = messages_from_log(log, ts)
    batt = [m for m in messages if m[1] == "/battery"][10:21]  # only from 1.0 to 2.0 s of a 3.9 s drive
    rest = [m for m in messages if m[1] != "/battery"]
    with Writer(tmp_path / "partial", version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = {}
        for ns, topic, msgtype, msg in sorted(rest + batt, key=lambda m: m[0]):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=ts)
            writer.write(conns[topic], ns, ts.serialize_cdr(msg, msgtype))
    with pytest.raises(DataError, match=r"topic '/battery' spans \[1\.005, 2\.005\] s but the drive stream "
                                        r"\[0\.005, 3\.905\] s, more than 5 of its median periods further"):
        read_back(tmp_path / "partial")
    held = read_back(tmp_path / "partial", allow_gaps=True)
    np.testing.assert_allclose(held.battery_voltage_v[:11], log.battery_voltage_v[10], rtol=1e-6)
    np.testing.assert_allclose(held.battery_voltage_v[10:21], log.battery_voltage_v[10:21], rtol=1e-6)
    np.testing.assert_allclose(held.battery_current_a[20:], log.battery_current_a[20], rtol=1e-6)
    assert "/battery: battery interpolated linearly onto the drive times (29 drive sample(s) outside its span hold " \
        "its first or last value)" in held.meta.notes


@requires_rosbags
def test_read_navsat_refuses_what_it_cannot_read(tmp_path):
    path = write_drive_bag(drive_log(), tmp_path / "drive.bag")
    with pytest.raises(DataError, match=r"topic '/odom' has type 'nav_msgs/msg/Odometry'; expected one of "
                                        r"\('sensor_msgs/msg/NavSatFix',\)"):
        read_navsat(path, "/odom")
    with pytest.raises(InvalidParameterError, match="'interpolate_nans' does not apply to GPS fixes"):
        read_navsat(path, repair=("sort", "interpolate_nans"))
    with pytest.raises(InvalidParameterError, match="start_time_ns must be an integer"):
        read_navsat(path, start_time_ns=1.5)


@requires_rosbags
def test_a_battery_voltage_without_a_pack_current(tmp_path):
    log = drive_log(9)
    volts_only = InteractionLog(log.time_s, log.v_mps, log.omega_radps, log.current_left_a, log.current_right_a,
                                log.accel_time_s, log.accel_z_mps2, pose_xyh=log.pose_xyh,
                                battery_voltage_v=log.battery_voltage_v)
    read = read_back(write_drive_bag(volts_only, tmp_path / "drive.bag"))
    np.testing.assert_allclose(read.battery_voltage_v, log.battery_voltage_v, rtol=1e-6)
    assert read.battery_current_a is None and "/battery: no pack current (NaN in every message)" in read.meta.notes
