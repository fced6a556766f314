"""The gyro yaw-rate stream of an interaction log: validated, kept by every reader, slicing and joining."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from robot_bags import requires_rosbags, write_robot_bag

from energy import InteractionLog, LogMeta, read_borealtc, read_csv_log, read_rosbag, write_csv_log
from energy.io import BagTopics, CsvLayout, read_borealtc_run
from terrain import DataError, DataRepairWarning, InvalidParameterError, UnitError

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "borealtc"


def gyro_log(n: int = 21, m: int = 201, **kw) -> InteractionLog:
    """Drive at 10 Hz, IMU at 100 Hz over 2 s; gyro z = 0.5 * t (rad/s), so interpolation is exact."""
    t, ta = np.arange(n) * 0.1, np.arange(m) * 0.01
    args = dict(time_s=t, v_mps=np.full(n, 0.4), omega_radps=np.full(n, 0.2), current_left_a=np.full(n, 2.0),
                current_right_a=np.full(n, 2.5), accel_time_s=ta, accel_z_mps2=9.81 + 0.01 * np.sin(ta),
                gyro_z_radps=0.5 * ta, meta=LogMeta(robot="husky", source="synthetic", ground_label="snow"))
    args.update(kw)
    return InteractionLog(**args)


def test_gyro_is_a_readonly_float_copy_on_the_imu_clock():
    raw = np.arange(201) * 0.005
    log = gyro_log(gyro_z_radps=raw)
    raw[0] = 9.0
    assert log.gyro_z_radps[0] == 0.0 and log.gyro_z_radps.dtype == np.float64
    assert not log.gyro_z_radps.flags.writeable
    assert gyro_log(gyro_z_radps=None).gyro_z_radps is None


def test_gyro_bad_length_and_non_finite():
    with pytest.raises(InvalidParameterError, match=r"gyro_z_radps must have the length of accel_time_s \(201\), got 21"):
        gyro_log(gyro_z_radps=np.zeros(21))
    bad = np.zeros(201)
    bad[7] = np.nan
    with pytest.raises(DataError, match=r"gyro_z_radps must be finite; 1 non-finite value\(s\), first at index 7"):
        gyro_log(gyro_z_radps=bad)
    with pytest.raises(InvalidParameterError, match="gyro_z_radps must be a 1-D"):
        gyro_log(gyro_z_radps=np.zeros((201, 1)))


def test_gyro_on_drive_times_and_its_errors():
    log = gyro_log()
    np.testing.assert_allclose(log.gyro_z_on(log.time_s), 0.5 * log.time_s, atol=1e-12)
    with pytest.raises(DataError, match="outside the acceleration record"):
        log.gyro_z_on([5.0])
    with pytest.raises(DataError, match=r"no gyro yaw rate \(gyro_z_radps\).*'wz'"):
        gyro_log(gyro_z_radps=None).gyro_z_on(log.time_s)


def test_gyro_survives_slice_resample_shift_and_split():
    log = gyro_log()
    part = log.slice(0.5, 1.0)
    np.testing.assert_allclose(part.gyro_z_radps, 0.5 * part.accel_time_s, atol=1e-12)
    assert part.accel_time_s.size == part.gyro_z_radps.size == 50
    res = log.resample(4.0, "previous")
    np.testing.assert_allclose(res.gyro_z_radps, 0.5 * res.accel_time_s, atol=1e-12)
    assert res.gyro_z_radps.size == res.accel_z_mps2.size
    shifted = log.shifted(10.0)
    np.testing.assert_array_equal(shifted.gyro_z_radps, log.gyro_z_radps)
    keep = np.r_[np.arange(0, 80), np.arange(120, 201)]  # a 0.4 s hole in the IMU stream
    holed = gyro_log(accel_time_s=log.accel_time_s[keep], accel_z_mps2=log.accel_z_mps2[keep],
                     gyro_z_radps=log.gyro_z_radps[keep])
    with pytest.warns(DataRepairWarning, match="dropped"):
        pieces = holed.split_at_gaps()
    assert len(pieces) == 2
    for p in pieces:
        np.testing.assert_allclose(p.gyro_z_radps, 0.5 * p.accel_time_s, atol=1e-12)


def test_gyro_concatenates_all_or_none():
    a, b = gyro_log(), gyro_log().shifted(3.0)
    joined = InteractionLog.concatenate([a, b])
    assert joined.gyro_z_radps.size == 402
    np.testing.assert_array_equal(joined.gyro_z_radps[201:], b.gyro_z_radps)
    with pytest.raises(DataError, match=r"gyro_z_radps present in logs \[True, False\]"):
        InteractionLog.concatenate([a, gyro_log(gyro_z_radps=None).shifted(3.0)])


def test_borealtc_wz_is_the_gyro():
    log = read_borealtc(FIXTURES, grounds=["asphalt"])[0]
    imu = np.genfromtxt(FIXTURES / "ASPHALT" / "imu_00.csv", delimiter=",", names=True)
    i0 = int(np.flatnonzero(imu["time"] == log.accel_time_s[0])[0])
    np.testing.assert_array_equal(log.gyro_z_radps, imu["wz"][i0 : i0 + log.accel_time_s.size])


def test_borealtc_without_wz_has_no_gyro(tmp_path):
    run = tmp_path / "ASPHALT"
    run.mkdir()
    shutil.copy(FIXTURES / "ASPHALT" / "pro_00.csv", run / "pro_00.csv")
    lines = (FIXTURES / "ASPHALT" / "imu_00.csv").read_text().splitlines()
    cols = lines[0].split(",")
    keep = [i for i, c in enumerate(cols) if c != "wz"]
    (run / "imu_00.csv").write_text("\n".join(",".join(r.split(",")[i] for i in keep) for r in lines) + "\n")
    log = read_borealtc_run(run / "imu_00.csv", run / "pro_00.csv")
    assert log.gyro_z_radps is None and log.accel_z_mps2.size > 0


def test_csv_roundtrip_keeps_gyro_and_voltage(tmp_path):
    n = 21
    log = gyro_log(battery_voltage_v=np.linspace(26.0, 25.9, n))
    back = read_csv_log(write_csv_log(log, tmp_path / "run.csv"))
    np.testing.assert_array_equal(back.gyro_z_radps, log.gyro_z_radps)
    np.testing.assert_array_equal(back.battery_voltage_v, log.battery_voltage_v)
    np.testing.assert_array_equal(back.current_left_a, log.current_left_a)
    plain = read_csv_log(write_csv_log(gyro_log(gyro_z_radps=None), tmp_path / "plain.csv"))
    assert plain.gyro_z_radps is None and plain.battery_voltage_v is None
    assert "gyro_z_radps" not in (tmp_path / "plain.csv").read_text().splitlines()[1]


def test_csv_gyro_in_degrees_is_converted_and_checked(tmp_path):
    path = tmp_path / "deg.csv"
    rows = ["t,v,w,il,ir,az,gz"] + [f"{k * 0.1:.1f},0.5,0.1,2.0,2.0,9.8,{10.0 * k}" for k in range(20)]
    path.write_text("\n".join(rows) + "\n")
    cols = {"time": "t", "v": "v", "omega": "w", "current_left": "il", "current_right": "ir", "accel_z": "az",
            "gyro_z": "gz"}
    log = read_csv_log(path, CsvLayout(cols, {"gyro_z": "deg/s"}, rates="single"))
    np.testing.assert_allclose(log.gyro_z_radps, np.deg2rad(10.0 * np.arange(20)))
    with pytest.raises(UnitError, match="gz.*looks like deg/s"):
        read_csv_log(path, CsvLayout(cols, rates="single"))


@requires_rosbags
def test_bag_gyro_is_the_imu_angular_velocity_z(tmp_path):
    truth = write_robot_bag(tmp_path / "j.bag", imu_hz=50.0, status_hz=None)
    log = read_rosbag(tmp_path / "j.bag", BagTopics(cmd_vel_topic="/odometry/filtered"))
    i0 = int(np.argmin(np.abs(truth["imu_t"] - log.accel_time_s[0])))
    np.testing.assert_allclose(log.gyro_z_radps, truth["gz"][i0 : i0 + log.accel_time_s.size])
    part = log.slice(1.0, 3.0)
    np.testing.assert_allclose(part.gyro_z_radps, 0.3 * np.sin(part.accel_time_s), atol=1e-9)


@requires_rosbags
def test_bag_imu_without_gyro_says_so(tmp_path):
    write_robot_bag(tmp_path / "nogyro.bag", status_hz=None, gyro=False)
    log = read_rosbag(tmp_path / "nogyro.bag", BagTopics(cmd_vel_topic="/odometry/filtered"))
    assert log.gyro_z_radps is None
    assert "no gyro (angular_velocity_covariance[0] == -1)" in log.meta.notes
