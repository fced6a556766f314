"""Tests of energy.io.bag_messages: the bag path, topic types, topic times, message fields by name (no bag needed)."""

from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np
import pytest

from energy.io.bag_messages import bag_path, expect_type, field_values, import_rosbags, message_fields, topic_times
from terrain import DataError, FileFormatError, OptionalDependencyError


@dataclass
class Stamp:
    sec: int
    nanosec: int


@dataclass
class Header:
    stamp: Stamp


@dataclass
class Battery:
    volts: float
    ok: bool


@dataclass
class Status:
    header: Header
    left: float
    right: int
    battery: Battery
    name: str


def status(sec: int, nanosec: int = 0, left: float = 1.5) -> Status:
    return Status(Header(Stamp(sec, nanosec)), left, 2, Battery(24.0, True), "husky")


def test_bag_path_of_a_bag_file_a_folder_and_a_file_inside_a_ros2_bag(tmp_path):
    ros2 = tmp_path / "run"
    ros2.mkdir()
    (ros2 / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    (ros2 / "run_0.mcap").write_bytes(b"")
    assert bag_path(ros2 / "run_0.mcap") == ros2
    assert bag_path(ros2) == ros2
    (tmp_path / "a.bag").write_bytes(b"")
    assert bag_path(tmp_path / "a.bag") == tmp_path / "a.bag"
    with pytest.raises(FileFormatError, match=r"bag '.*gone\.bag' does not exist"):
        bag_path(tmp_path / "gone.bag")


def test_without_rosbags_the_error_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)  # import of it now fails
    with pytest.raises(OptionalDependencyError, match=r"pip install 'terrawatt\[ros\]'"):
        import_rosbags()


def test_expect_type_checks_the_type_and_that_there_are_messages():
    raw = {"/status": [(0, status(0))], "/empty": []}
    types = {"/status": "husky_msgs/msg/HuskyStatus", "/empty": "std_msgs/msg/Float32"}
    assert expect_type("b", raw, types, "/status", ("husky_msgs/msg/HuskyStatus",)) == "husky_msgs/msg/HuskyStatus"
    with pytest.raises(DataError, match=r"b: topic '/status' has type 'husky_msgs/msg/HuskyStatus'; expected one of "
                                        r"\('std_msgs/msg/Float32',\); a hint"):
        expect_type("b", raw, types, "/status", ("std_msgs/msg/Float32",), "; a hint")
    with pytest.raises(DataError, match="topic '/empty' has no messages"):
        expect_type("b", raw, types, "/empty", ("std_msgs/msg/Float32",))


def test_topic_times_use_header_stamps_near_the_receive_times():
    msgs = [(1_020_000_000 + k * 100_000_000, status(1, k * 100_000_000)) for k in range(5)]  # received 20 ms late
    notes: list[str] = []
    t = topic_times("b", "/status", msgs, True, 0.5, notes)
    assert t.tolist() == [1_000_000_000 + k * 100_000_000 for k in range(5)] and t.dtype == np.int64
    assert notes == ["/status: header stamps (median receive time - stamp 0.02 s)"]
    assert topic_times("b", "/status", msgs, False, 0.5, notes).tolist() == [ts for ts, _ in msgs]
    assert notes[-1] == "/status: receive time"


def test_topic_times_fall_back_to_receive_times_without_stamps():
    zero = [(10, status(0, 0)), (20, status(0, 5))]
    notes: list[str] = []
    assert topic_times("b", "/s", zero, True, 0.5, notes).tolist() == [10, 20]
    assert notes == ["/s: receive time (1 zero header stamp(s))"]
    plain = [(10, 1.0), (20, 2.0)]  # messages without a header
    assert topic_times("b", "/f", plain, True, 0.5, notes).tolist() == [10, 20]


def test_topic_times_refuse_clocks_that_disagree():
    msgs = [(5_000_000_000 + k, status(0, 1 + k)) for k in range(3)]  # 5 s apart
    with pytest.raises(DataError, match=r"b: topic '/status': median \(receive time - header stamp\) is 5 s, "
                                        r"expected within \+/-0\.5 s \(max_clock_offset_s\).*use_header_stamps=False"):
        topic_times("b", "/status", msgs, True, 0.5, [])


def test_message_fields_are_the_numeric_scalars_as_dotted_paths():
    assert message_fields(status(1)) == ["left", "right", "battery.volts"]  # no header, bool, str
    assert message_fields(3.0) == []


def test_field_values_by_name_and_nested_path():
    msgs = [(0, status(0, left=1.5)), (1, status(0, left=-2.0))]
    left = field_values("b", "/status", "T", msgs, "left", "current_fields")
    assert left.tolist() == [1.5, -2.0] and left.dtype == np.float64
    assert field_values("b", "/status", "T", msgs, "battery.volts", "voltage_field").tolist() == [24.0, 24.0]
    with pytest.raises(DataError, match=r"b: topic '/status' \(T\) has no field 'volts' \(named by voltage_field\); its "
                                        r"numeric fields are \['left', 'right', 'battery.volts'\]"):
        field_values("b", "/status", "T", msgs, "volts", "voltage_field")
    with pytest.raises(DataError, match=r"field 'battery.ok' is not a number \(got bool\)"):
        field_values("b", "/status", "T", msgs, "battery.ok", "voltage_field")
    with pytest.raises(DataError, match=r"field 'name' is not a number \(got str\)"):
        field_values("b", "/status", "T", msgs, "name", "current_fields")
