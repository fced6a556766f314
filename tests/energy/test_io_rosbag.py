"""Tests of energy.io.rosbag: ROS 1 bags, ROS 2 bags (sqlite3, MCAP)."""

from __future__ import annotations

import re
import sys
import warnings

import numpy as np
import pytest
from energy_io_samples import (
    BASE_NS,
    MS,
    bag_content,
    fuzz_settings,
    mutate_bytes,
    requires_rosbags,
    write_bag,
)
from hypothesis import given
from hypothesis import strategies as st

from energy import (
    read_rosbag,
)
from energy.io import BagTiming, BagTopics, LogCleaning
from terrain import (
    DataError,
    DataRepairWarning,
    FileFormatError,
    InvalidParameterError,
    OptionalDependencyError,
    TerrawattError,
    UnitError,
    UnknownNameError,
)


def expected_drive(content: dict, timeout_s: float | None = 0.5) -> dict:
    origin = min(content["imu_ns"][0], content["cur_ns"][0], content["cmd_ns"][0])
    sec = lambda ns: (np.asarray(ns, dtype=np.int64) - origin).astype(np.float64) / 1e9  # noqa: E731
    tc, ti, tv = sec(content["cur_ns"]), sec(content["imu_ns"]), sec(content["cmd_ns"])
    keep = (tc >= max(tc[0], ti[0])) & (tc <= min(tc[-1], ti[-1]))
    td = tc[keep]
    idx = np.searchsorted(tv, td, side="right") - 1
    valid = idx >= 0
    if timeout_s is not None:
        valid &= td - tv[np.maximum(idx, 0)] <= timeout_s
    v = np.where(valid, np.asarray(content["v"])[np.maximum(idx, 0)], 0.0)
    w = np.where(valid, np.asarray(content["w"])[np.maximum(idx, 0)], 0.0)
    return {"time_s": td, "v": v, "w": w, "left": np.asarray(content["left"])[keep],
            "right": np.asarray(content["right"])[keep], "ti": ti, "origin": origin}


@requires_rosbags
@pytest.mark.parametrize("kind", ["ros2", "mcap", "ros1"])
def test_rosbag_roundtrip_exact(tmp_path, kind):
    content = bag_content()
    path = write_bag(tmp_path / ("run.bag" if kind == "ros1" else "run"), kind, content)
    log = read_rosbag(path, BagTopics(cmd_vel_topic="/cmd_vel", imu_topic="/imu/data",
                                      current_topics=("/drive/current_left", "/drive/current_right")),
                      robot="jackal", ground_label="grass")
    exp = expected_drive(content)
    np.testing.assert_array_equal(log.time_s, exp["time_s"])
    np.testing.assert_array_equal(log.v_mps, exp["v"])
    np.testing.assert_array_equal(log.omega_radps, exp["w"])
    np.testing.assert_array_equal(log.current_left_a, exp["left"])
    np.testing.assert_array_equal(log.current_right_a, exp["right"])
    # IMU on header stamps (not the 1 ms later receive time), bracketing the drive span
    ia = np.flatnonzero(exp["ti"] <= log.time_s[0])[-1]
    ib = np.flatnonzero(exp["ti"] >= log.time_s[-1])[0]
    np.testing.assert_array_equal(log.accel_time_s, exp["ti"][ia : ib + 1])
    np.testing.assert_array_equal(log.accel_z_mps2, np.asarray(content["az"])[ia : ib + 1])
    assert log.meta.start_time_ns == exp["origin"] == BASE_NS
    assert log.meta.velocity_source == "commanded" and log.meta.robot == "jackal"
    assert "/imu/data: header stamps" in log.meta.notes and "/drive/current_left: receive time" in log.meta.notes
    # commands stop at 1.1 s: zero after the 0.5 s timeout, zero before the first one
    assert log.v_mps[log.time_s < 0.3].tolist() == [0.0] * int(np.sum(log.time_s < 0.3))
    assert np.all(log.v_mps[log.time_s > 1.6] == 0.0)
    assert np.any(log.v_mps > 0)


@requires_rosbags
def test_rosbag_receive_time_and_no_timeout(tmp_path):
    content = bag_content()
    path = write_bag(tmp_path / "run", "ros2", content)
    log = read_rosbag(path, BagTopics(current_topics=("/drive/current_left", "/drive/current_right")),
                      timing=BagTiming(use_header_stamps=False, cmd_vel_timeout_s=None))
    assert "/imu/data: receive time" in log.meta.notes
    # without a timeout the drive stream starts at the first command and the last command is held
    received = dict(content, imu_ns=[ns + MS for ns in content["imu_ns"]])  # IMU receive time = stamp + 1 ms
    exp = expected_drive(received, timeout_s=None)
    assert exp["origin"] == BASE_NS + MS
    keep = exp["time_s"] >= (content["cmd_ns"][0] - exp["origin"]) / 1e9
    np.testing.assert_array_equal(log.time_s, exp["time_s"][keep])
    np.testing.assert_array_equal(log.v_mps, exp["v"][keep])
    assert log.v_mps[-1] == content["v"][-1]


@requires_rosbags
def test_rosbag_multiarray_in_milliamps(tmp_path):
    content = bag_content()
    path = write_bag(tmp_path / "run", "mcap", content, multiarray=True, scale=1000.0)
    with pytest.raises(UnitError, match="declared in A but its values look like mA"):
        read_rosbag(path, BagTopics(current_topics="/drive/current"))
    log = read_rosbag(path, BagTopics(current_topics="/drive/current", current_unit="mA"))
    exp = expected_drive(content)
    np.testing.assert_allclose(log.current_left_a, exp["left"], rtol=1e-15)
    np.testing.assert_allclose(log.current_right_a, exp["right"], rtol=1e-15)


@requires_rosbags
def test_rosbag_odometry_measured_with_pose(tmp_path):
    content = bag_content()
    path = write_bag(tmp_path / "run.bag", "ros1", content, odom=True)
    log = read_rosbag(path, BagTopics(cmd_vel_topic="/odom",
                                      current_topics=("/drive/current_left", "/drive/current_right")))
    assert log.meta.velocity_source == "measured" and log.pose_xyh is not None
    origin = BASE_NS
    tv = (np.asarray(content["cmd_ns"]) - origin) / 1e9
    assert log.time_s[0] >= tv[0] and log.time_s[-1] <= tv[-1]  # inside the odometry span
    np.testing.assert_allclose(log.v_mps, np.interp(log.time_s, tv, content["v"]), atol=1e-12)
    np.testing.assert_allclose(log.pose_xyh[:, 0], np.interp(log.time_s, tv, np.arange(5.0)), atol=1e-12)
    np.testing.assert_allclose(log.pose_xyh[:, 2], np.interp(log.time_s, tv, 0.2 * np.arange(5)), atol=1e-12)


@requires_rosbags
def test_rosbag_bad_inputs(tmp_path):
    content = bag_content()
    path = write_bag(tmp_path / "run", "ros2", content, multiarray=True)
    with pytest.raises(DataError, match=r"topic\(s\) \['/drive/current_left'.* not in the bag"):
        read_rosbag(path, require_currents=True)
    assert not read_rosbag(path).has_currents  # optional by default: a log to predict from
    with pytest.raises(DataError, match="topic '/imu/data' has type 'sensor_msgs/msg/Imu'; expected one of"):
        read_rosbag(path, BagTopics(cmd_vel_topic="/imu/data", current_topics="/drive/current"))
    with pytest.raises(DataError, match="has type 'std_msgs/msg/Float64MultiArray'"):
        read_rosbag(path, BagTopics(current_topics=("/drive/current", "/drive/current")))
    with pytest.raises(FileFormatError, match="does not exist"):
        read_rosbag(tmp_path / "nothing")
    with pytest.raises(UnknownNameError, match="current_unit must be one of"):
        read_rosbag(path, BagTopics(current_topics="/drive/current", current_unit="uA"))
    with pytest.raises(InvalidParameterError, match="cmd_vel_timeout_s must be"):
        read_rosbag(path, BagTopics(current_topics="/drive/current"), timing=BagTiming(cmd_vel_timeout_s=0))
    not_a_bag = tmp_path / "junk.bag"
    not_a_bag.write_bytes(b"definitely not a bag")
    with pytest.raises(FileFormatError, match="cannot read bag"):
        read_rosbag(not_a_bag)


@requires_rosbags
@pytest.mark.parametrize("shift_s", [-100.0, -0.8, 0.8])
def test_rosbag_header_clock_offset_raises(tmp_path, shift_s):
    content = bag_content()
    shift_ns = round(shift_s * 1e9)
    stamps = [ns + shift_ns for ns in content["imu_ns"]]  # publisher clock off the recorder's
    path = write_bag(tmp_path / "run", "ros2", content, imu_stamp_ns=stamps)
    offset = (MS - shift_ns) / 1e9  # median of receive time - header stamp
    with pytest.raises(DataError, match=rf"topic '/imu/data': median \(receive time - header stamp\) is "
                                        rf"{re.escape(repr(offset))} s, expected within \+/-0\.5 s.*"
                                        r"use_header_stamps=False"):
        read_rosbag(path)
    # on receive time the IMU and the currents share the recorder's clock: same as an unshifted bag
    log = read_rosbag(path, timing=BagTiming(use_header_stamps=False))
    ref = read_rosbag(write_bag(tmp_path / "ref", "ros2", content), timing=BagTiming(use_header_stamps=False))
    np.testing.assert_array_equal(log.accel_time_s, ref.accel_time_s)
    np.testing.assert_array_equal(log.time_s, ref.time_s)
    # a wider tolerance is an explicit choice
    if abs(shift_s) < 1:
        assert read_rosbag(path, timing=BagTiming(max_clock_offset_s=1.0)).meta.notes.count("header stamps") == 1
    with pytest.raises(InvalidParameterError, match=r"max_clock_offset_s must be finite, got nan"):
        read_rosbag(path, timing=BagTiming(max_clock_offset_s=float("nan")))


@requires_rosbags
def test_rosbag_notes_clock_offset(tmp_path):
    log = read_rosbag(write_bag(tmp_path / "run", "mcap", bag_content()))
    assert "/imu/data: header stamps (median receive time - stamp 0.001 s)" in log.meta.notes


@requires_rosbags
def test_rosbag_unsorted_header_stamps_raise_then_sort(tmp_path):
    content = bag_content()
    ref = read_rosbag(write_bag(tmp_path / "ref", "ros2", content))
    stamps = list(content["imu_ns"])
    stamps[50], stamps[51] = stamps[51], stamps[50]  # received in order, stamped out of order
    path = write_bag(tmp_path / "run", "ros2", content, imu_stamp_ns=stamps)
    with pytest.raises(DataError, match=r"/imu/data: timestamps are not sorted; 1 step\(s\) go backwards, first at "
                                        r"index 51 .*repair=\('sort',\)"):
        read_rosbag(path)
    with pytest.warns(DataRepairWarning, match=r"/imu/data: sorted timestamps \(1 backward step"):
        log = read_rosbag(path, cleaning=LogCleaning(repair="sort"))
    np.testing.assert_array_equal(log.accel_time_s, ref.accel_time_s)
    i = int(np.searchsorted(log.accel_time_s, 0.5))  # stamp index 50 (t = 0.5 s)
    assert (log.accel_z_mps2[i], log.accel_z_mps2[i + 1]) == (content["az"][51], content["az"][50])


@requires_rosbags
def test_rosbag_duplicated_receive_times_raise_then_drop(tmp_path):
    content = bag_content()
    content["cur_ns"][5] = content["cur_ns"][4]
    path = write_bag(tmp_path / "run", "ros2", content)
    with pytest.raises(DataError, match=r"/drive/current_left: 1 duplicated timestamp\(s\), first at index 5 "
                                        r"\(t=0\.45 s\); pass repair=\('drop_duplicates',\)"):
        read_rosbag(path)
    with pytest.warns(DataRepairWarning) as record:
        log = read_rosbag(path, cleaning=LogCleaning(repair="drop_duplicates"))
    assert sorted(str(w.message).split(": ", 1)[1] for w in record) == [
        f"/drive/current_{side}: dropped 1 sample(s) with a duplicated timestamp" for side in ("left", "right")
    ]
    assert len(log) == 19 and log.current_left_a[4] == content["left"][4]


@requires_rosbags
def test_rosbag_nan_current_raises_then_interpolates(tmp_path):
    content = bag_content()
    content["left"][3] = float("nan")
    path = write_bag(tmp_path / "run", "mcap", content)
    with pytest.raises(DataError, match=r"/drive/current_left: column 'left' has 1 missing or non-finite value\(s\), "
                                        r"first at index 3 \(t=0\.35 s\); pass repair=\('interpolate_nans',\)"):
        read_rosbag(path)
    with pytest.warns(DataRepairWarning, match=r"interpolated 1 missing value\(s\) of column 'left'"):
        log = read_rosbag(path, cleaning=LogCleaning(repair=("interpolate_nans",)))
    assert log.current_left_a[3] == pytest.approx(0.5 * (content["left"][2] + content["left"][4]), abs=1e-12)


@requires_rosbags
@pytest.mark.parametrize("kind", ["ros2", "mcap"])
def test_rosbag_empty_topic(tmp_path, kind):
    path = write_bag(tmp_path / "run", kind, bag_content(), empty_topics=("/drive/current_right",))
    with pytest.raises(DataError, match=r"topic '/drive/current_right' has no messages"):
        read_rosbag(path)


def test_rosbag_without_rosbags_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)  # import of it now fails
    with pytest.raises(OptionalDependencyError, match=r"pip install 'terrawatt\[ros\]'"):
        read_rosbag(tmp_path / "run")


@requires_rosbags
def test_rosbag_multiarray_wrong_length(tmp_path):
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    path = tmp_path / "bad"
    with Writer2(path, version=9) as w:
        c = w.add_connection("/drive/current", "std_msgs/msg/Float64MultiArray", typestore=ts)
        ci = w.add_connection("/imu/data", "sensor_msgs/msg/Imu", typestore=ts)
        cv = w.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=ts)
        lay = T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
        w.write(c, BASE_NS, ts.serialize_cdr(T["std_msgs/msg/Float64MultiArray"](layout=lay, data=np.ones(3)),
                                             "std_msgs/msg/Float64MultiArray"))
        v3 = T["geometry_msgs/msg/Vector3"]
        w.write(cv, BASE_NS, ts.serialize_cdr(T["geometry_msgs/msg/Twist"](linear=v3(x=0.0, y=0.0, z=0.0),
                                              angular=v3(x=0.0, y=0.0, z=0.0)), "geometry_msgs/msg/Twist"))
        stamp = T["builtin_interfaces/msg/Time"](sec=1, nanosec=0)
        imu = T["sensor_msgs/msg/Imu"](
            header=T["std_msgs/msg/Header"](stamp=stamp, frame_id=""),
            orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            orientation_covariance=np.zeros(9), angular_velocity=v3(x=0.0, y=0.0, z=0.0),
            angular_velocity_covariance=np.zeros(9), linear_acceleration=v3(x=0.0, y=0.0, z=9.8),
            linear_acceleration_covariance=np.zeros(9))
        w.write(ci, BASE_NS, ts.serialize_cdr(imu, "sensor_msgs/msg/Imu"))
    with pytest.raises(DataError, match=r"1 message\(s\) do not hold exactly \[left, right\].*3 value"):
        read_rosbag(path, BagTopics(current_topics="/drive/current"))



# ===================================================================== hostile input
@pytest.fixture(scope="module")
def valid_bags(tmp_path_factory):
    """One valid ROS 1 bag file and one MCAP file (with its metadata.yaml), written once."""
    root = tmp_path_factory.mktemp("bags")
    ros1 = write_bag(root / "run.bag", "ros1", bag_content())
    mcap_dir = write_bag(root / "mcap", "mcap", bag_content())
    mcap = next(mcap_dir.glob("*.mcap"))
    return {"ros1": (ros1.read_bytes(), None), "mcap": (mcap.read_bytes(), (mcap.name, (mcap_dir / "metadata.yaml").read_bytes()))}


EDITS = st.lists(st.tuples(st.integers(0, 2), st.integers(0, 2**31), st.integers(0, 255)), min_size=1, max_size=6)


@requires_rosbags
@pytest.mark.parametrize("kind", ["ros1", "mcap"])
@fuzz_settings(40)
@given(edits=EDITS, truncate=st.one_of(st.none(), st.integers(0, 60_000)))
def test_fuzz_rosbag_mutated_bags(tmp_path, valid_bags, kind, edits, truncate):
    """Mutated ROS 1 and MCAP bags read or raise a TerrawattError, never another exception.

    Long run: ``TERRAWATT_FUZZ_EXAMPLES=20 python -m pytest -q tests/energy -k fuzz``.
    """
    data, extra = valid_bags[kind]
    data = mutate_bytes(data, edits)
    if truncate is not None:
        data = data[:truncate]
    if extra is None:
        path = tmp_path / "fuzz.bag"
        path.write_bytes(data)
    else:
        path = tmp_path / "fuzz"
        path.mkdir(exist_ok=True)
        (path / extra[0]).write_bytes(data)
        (path / "metadata.yaml").write_bytes(extra[1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataRepairWarning)
        for kwargs in ({}, {"repair": ("sort", "drop_duplicates", "interpolate_nans"), "allow_gaps": True}):
            try:
                read_rosbag(path, cleaning=LogCleaning(**kwargs))
            except TerrawattError:
                pass


@requires_rosbags
@fuzz_settings(30)
@given(data=st.binary(max_size=400))
def test_fuzz_rosbag_random_bytes(tmp_path, data):
    """Random bytes as a .bag file (or as a ROS 2 bag's metadata) raise a TerrawattError.

    Long run: ``TERRAWATT_FUZZ_EXAMPLES=20 python -m pytest -q tests/energy -k fuzz``.
    """
    path = tmp_path / "random.bag"
    path.write_bytes(b"#ROSBAG V2.0\n" + data)
    with pytest.raises(TerrawattError):
        read_rosbag(path)
    folder = tmp_path / "ros2"
    folder.mkdir(exist_ok=True)
    (folder / "metadata.yaml").write_bytes(data)
    with pytest.raises(TerrawattError):
        read_rosbag(folder)
