"""Bags like real robots record them: a Husky's HuskyStatus currents and battery voltage, a Jackal
without current topics (predict only), an IMU with gravity removed, and the errors of bad names."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from robot_bags import BASE_NS, requires_rosbags, write_robot_bag

from energy import (
    BagTopics,
    InteractionLog,
    LogMeta,
    new_current_model,
    predict_runs,
    read_borealtc,
    read_csv_log,
    read_logs,
    read_rosbag,
    write_csv_log,
)
from energy.features import band_rms_spectra, log_band_edges_hz
from energy.io import BagTiming, LogCleaning
from terrain import DataError, InvalidParameterError, UnitError, UnknownNameError

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "borealtc"
HUSKY = dict(cmd_vel_topic="/odometry/filtered", current_topics="/status",
             current_fields=("left_driver_current", "right_driver_current"), voltage_field="battery_voltage")

pytestmark = requires_rosbags


@pytest.fixture(scope="module")
def bags(tmp_path_factory) -> dict[str, tuple[Path, dict]]:
    root = tmp_path_factory.mktemp("bags")
    out = {}
    for name, kw in {
        "husky": dict(imu_hz=30.0, odom_hz=10.0, status_hz=10.0),
        "jackal": dict(imu_hz=50.0, odom_hz=15.0, status_hz=None),
        "cmd_only": dict(imu_hz=50.0, odom_hz=20.0, status_hz=None, cmd_vel=True),
        "no_gravity": dict(imu_hz=50.0, status_hz=None, gravity=False, seed=3),
    }.items():
        path = root / f"{name}.bag"
        out[name] = (path, write_robot_bag(path, **kw))
    return out


def test_husky_status_currents_and_voltage_by_field_name(bags):
    path, truth = bags["husky"]
    log = read_rosbag(path, BagTopics(**HUSKY), robot="husky")
    assert log.has_currents and log.meta.missing_currents == ""
    # the drive stream sits on the status messages inside the overlap of status, IMU and odometry
    i = np.searchsorted(truth["status_t"], log.time_s - 1e-9)
    np.testing.assert_allclose(log.time_s, truth["status_t"][i], atol=1e-9)
    np.testing.assert_allclose(log.current_left_a, truth["left"][i])
    np.testing.assert_allclose(log.current_right_a, truth["right"][i])
    np.testing.assert_allclose(log.battery_voltage_v, truth["volts"][i])
    assert log.meta.velocity_source == "measured" and log.pose_xyh is not None
    assert log.accel_rate_hz == pytest.approx(30.0, rel=1e-3) and log.gyro_z_radps is not None
    assert log.meta.start_time_ns == BASE_NS and not log.meta.gravity_removed


def test_husky_status_fields_in_milliamps_and_nested_names(bags, tmp_path):
    path, truth = bags["husky"]
    log = read_rosbag(path, BagTopics(**HUSKY, current_unit="mA"), cleaning=LogCleaning(check_units=False))
    np.testing.assert_allclose(log.current_left_a[:3], truth["left"][:3] / 1000.0)
    nested = read_rosbag(path, BagTopics(**{**HUSKY, "current_fields": ("left_driver_current", "header.stamp.sec"),
                                            "voltage_field": None}), cleaning=LogCleaning(check_units=False))
    assert nested.current_right_a[0] == BASE_NS // 1_000_000_000


def test_jackal_bag_without_current_topics_reads_for_prediction(bags):
    path, truth = bags["jackal"]
    log = read_rosbag(path, BagTopics(cmd_vel_topic="/odometry/filtered"), robot="jackal")
    assert not log.has_currents and log.current_left_a is None and log.current_right_a is None
    assert "'/drive/current_left', '/drive/current_right'" in log.meta.missing_currents
    assert "no currents" in log.meta.notes
    # drive samples at the odometry messages (15 Hz), IMU at 50 Hz
    assert log.drive_rate_hz == pytest.approx(15.0, rel=1e-3) and log.accel_rate_hz == pytest.approx(50.0, rel=1e-3)
    np.testing.assert_allclose(log.v_mps, np.interp(log.time_s, truth["odom_t"], truth["v"]), atol=1e-9)
    with pytest.raises(DataError, match=r"training needs measured drive currents.*'/drive/current_left'.*"
                                        r"\(current_topics\).*\(current_fields\)$") as raised:
        log.require_currents("training")
    assert raised.value.parameter == ("current_topics", "current_fields")  # the command line says its flags
    with pytest.raises(DataError, match=r"topic\(s\) \['/drive/current_left', '/drive/current_right'\] not in the bag"):
        read_rosbag(path, BagTopics(cmd_vel_topic="/odometry/filtered"), require_currents=True)


def test_a_model_predicts_a_bag_without_currents(bags):
    model = new_current_model("physics", seed=0).fit(read_borealtc(FIXTURES))
    jackal = read_rosbag(bags["jackal"][0], BagTopics(cmd_vel_topic="/odometry/filtered"))
    husky = read_rosbag(bags["husky"][0], BagTopics(**HUSKY))
    runs = predict_runs(model, [jackal, husky])
    assert [r.has_currents for r in runs] == [False, True]
    assert runs[0].charge_predicted_left_mah > 0 and np.isnan(runs[0].charge_measured_left_mah)
    assert np.isnan(runs[0].energy_predicted_wh) and runs[1].energy_predicted_wh > 0
    assert runs[0].to_dict()["charge_measured_left_mah"] is None
    pred = model.predict(husky)
    expected_wh = np.trapezoid(husky.battery_voltage_v * pred.sum(axis=1), husky.time_s) / 3600.0
    assert runs[1].energy_predicted_wh == pytest.approx(expected_wh)


def test_commands_only_bag_without_currents_uses_a_drive_grid(bags):
    path, _ = bags["cmd_only"]
    log = read_rosbag(path, BagTopics(cmd_vel_topic="/cmd_vel"), timing=BagTiming(drive_rate_hz=5.0))
    assert not log.has_currents and log.meta.velocity_source == "commanded"
    np.testing.assert_allclose(np.diff(log.time_s), 0.2, atol=1e-9)
    assert "5 Hz grid" in log.meta.notes
    with pytest.raises(InvalidParameterError, match="drive_rate_hz"):
        read_rosbag(path, BagTopics(cmd_vel_topic="/cmd_vel"), timing=BagTiming(drive_rate_hz=0.0))


def test_gravity_removed_imu_is_accepted_flagged_and_the_vibration_features_do_not_need_gravity(bags, tmp_path):
    log = read_rosbag(bags["no_gravity"][0], BagTopics(cmd_vel_topic="/odometry/filtered"))
    assert log.meta.gravity_removed
    assert "linear_acceleration.z has gravity removed (median 0.0" in log.meta.notes
    assert abs(float(np.median(log.accel_z_mps2))) < 0.5
    # the flag and its note survive a CSV round trip
    back = read_csv_log(write_csv_log(log, tmp_path / "ng.csv"))
    assert back.meta.gravity_removed and not back.has_currents and back.meta.missing_currents == log.meta.missing_currents
    # the band features remove each segment's mean: adding gravity back changes nothing
    edges = log_band_edges_hz(8, 1.0, 24.0, 0.5)
    centres = np.array([2.0, 3.0, 4.0])
    a = band_rms_spectra(log.accel_time_s, log.accel_z_mps2, centres, 2.0, edges)
    b = band_rms_spectra(log.accel_time_s, log.accel_z_mps2 + 9.81, centres, 2.0, edges)
    np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)
    with_gravity = read_rosbag(bags["jackal"][0], BagTopics(cmd_vel_topic="/odometry/filtered"))
    assert not with_gravity.meta.gravity_removed


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    (dict(HUSKY, current_fields=("left_current", "right_driver_current")), DataError,
     r"topic '/status' \(husky_msgs/msg/HuskyStatus\) has no field 'left_current' \(named by current_fields\); its "
     r"numeric fields are \[.*'left_driver_current'"),
    (dict(HUSKY, voltage_field="battery_volts"), DataError,
     r"has no field 'battery_volts' \(named by voltage_field\)"),
    (dict(HUSKY, current_fields=("left_driver_current", "e_stop")), DataError,
     r"field 'e_stop' is not a number \(got bool\)"),
    (dict(HUSKY, current_fields=("left_driver_current", "header.stamp.minutes")), DataError,
     r"has no field 'header.stamp.minutes'"),
    (dict(cmd_vel_topic="/odometry/filtered", current_topics="/status"), DataError,
     r"'/status' has type 'husky_msgs/msg/HuskyStatus'; expected one of .*Float64MultiArray.*name its current fields "
     r"with current_fields \(e.g. left_driver_current right_driver_current\)"),
    (dict(cmd_vel_topic="/odometry/filtered", current_topics=("/status", "/status")), DataError,
     r"'/status' has type 'husky_msgs/msg/HuskyStatus'; expected one of .*Float64'"),
    (dict(HUSKY, current_fields=("left_driver_current",)), InvalidParameterError,
     r"current_fields must be 2 non-empty name\(s\)"),
    (dict(HUSKY, current_topics=("/status", "/other")), InvalidParameterError,
     r"give one current topic \(current_topics\)"),
    (dict(HUSKY, current_fields=None), InvalidParameterError,
     r"voltage_field is read beside the currents"),
    (dict(HUSKY, current_topics="/husky_status"), DataError,
     r"topic\(s\) \['/husky_status'\] not in the bag"),
])
def test_bad_status_names_are_clear_errors(bags, kwargs, error, match):
    with pytest.raises(error, match=match) as raised:
        read_rosbag(bags["husky"][0], BagTopics(**kwargs))
    assert not re.search(r"--[a-z]", str(raised.value))  # the library names parameters, never a command line's flags


def test_one_of_two_current_topics_and_a_voltage_in_millivolts(bags, tmp_path):
    with pytest.raises(DataError, match=r"current topic '/status' is in the bag but \['/missing'\] is not"):
        read_rosbag(bags["husky"][0], BagTopics(cmd_vel_topic="/odometry/filtered",
                                                current_topics=("/status", "/missing")))
    with pytest.raises(UnitError, match=r"battery voltage.*looks like mV"):
        read_rosbag(bags["husky"][0], BagTopics(**{**HUSKY, "voltage_field": "uptime"}))


def test_logs_with_and_without_currents_do_not_concatenate(bags):
    jackal = read_rosbag(bags["jackal"][0], BagTopics(cmd_vel_topic="/odometry/filtered"))
    t = np.arange(5) * 0.1
    other = InteractionLog(t, np.ones(5), np.zeros(5), np.ones(5), np.ones(5), t, np.full(5, 9.8),
                           pose_xyh=np.zeros((5, 3)), meta=LogMeta(velocity_source="measured"))
    with pytest.raises(DataError, match=r"current_left_a present in logs \[True, False\].*current topics or fields"):
        InteractionLog.concatenate([other, jackal.shifted(100.0)])
    with pytest.raises(InvalidParameterError, match="current_left_a and current_right_a must both be arrays or both be None"):
        InteractionLog(t, np.ones(5), np.zeros(5), np.ones(5), None, t, np.full(5, 9.8))


def test_read_logs_bag_topics_and_required_currents(bags):
    jackal, husky = bags["jackal"][0], bags["husky"][0]
    assert not read_logs(jackal, bag=BagTopics(cmd_vel_topic="/odometry/filtered"))[0].has_currents
    with pytest.raises(DataError, match=r"training, evaluation or diagnosis needs measured drive currents, and this log has none \(current topic"):
        read_logs(jackal, bag=BagTopics(cmd_vel_topic="/odometry/filtered"), require_currents=True)
    (log,) = read_logs(husky, bag=BagTopics(**{**HUSKY, "current_topics": ("/status",)}), require_currents=True)
    assert log.has_currents and log.battery_voltage_v is not None


def test_training_refuses_a_log_without_currents(bags):
    jackal = read_rosbag(bags["jackal"][0], BagTopics(cmd_vel_topic="/odometry/filtered"))
    husky = read_rosbag(bags["husky"][0], BagTopics(**HUSKY))
    match = r"training, adaptation, scoring or diagnosis needs measured drive currents.*'/drive/current_left'"
    for kind in ("constant", "linear", "physics"):
        with pytest.raises(DataError, match=match):
            new_current_model(kind).fit([husky, jackal])


def test_a_status_message_at_a_jittery_1_hz_passes_the_rate_check(tmp_path):
    truth = write_robot_bag(tmp_path / "slow.bag", status_hz=0.95, duration_s=12.0)
    log = read_rosbag(tmp_path / "slow.bag", BagTopics(**HUSKY))
    assert log.has_currents and len(log) == truth["status_t"].size
    assert log.drive_rate_hz == pytest.approx(0.95, rel=1e-6)


def test_a_slow_status_message_beside_fast_odometry_on_the_odometry_clock(tmp_path):
    truth = write_robot_bag(tmp_path / "slow.bag", status_hz=1.0, odom_hz=10.0, duration_s=12.0)
    on_status = read_rosbag(tmp_path / "slow.bag", BagTopics(**HUSKY))
    on_odom = read_rosbag(tmp_path / "slow.bag", BagTopics(**HUSKY, drive_clock="velocity"))
    assert on_status.drive_rate_hz == pytest.approx(1.0) and on_odom.drive_rate_hz == pytest.approx(10.0)
    np.testing.assert_allclose(on_odom.current_left_a, np.interp(on_odom.time_s, truth["status_t"], truth["left"]))
    np.testing.assert_allclose(on_odom.battery_voltage_v, np.interp(on_odom.time_s, truth["status_t"], truth["volts"]))
    np.testing.assert_allclose(on_odom.v_mps, np.interp(on_odom.time_s, truth["odom_t"], truth["v"]), atol=1e-9)
    assert on_odom.time_s[0] >= truth["status_t"][0] and on_odom.time_s[-1] <= truth["status_t"][-1]
    assert "interpolated linearly onto the velocity stream's drive times" in on_odom.meta.notes
    (via_layouts,) = read_logs(tmp_path / "slow.bag", bag=BagTopics(**{**HUSKY, "current_topics": ("/status",)},
                                                                   drive_clock="velocity"))
    np.testing.assert_array_equal(via_layouts.time_s, on_odom.time_s)
    with pytest.raises(UnknownNameError, match="drive_clock"):
        read_rosbag(tmp_path / "slow.bag", BagTopics(**HUSKY, drive_clock="imu"))


def test_the_battery_power_of_a_log_uses_its_measured_voltage(bags):
    from energy import robot_preset
    from energy.budget import log_battery_power_w

    husky = read_rosbag(bags["husky"][0], BagTopics(**HUSKY))
    robot = robot_preset("husky")
    power = log_battery_power_w(husky, robot, current_convention="battery", electronics=False)
    drawn = husky.current_left_a + husky.current_right_a - 2 * robot.rest_current_a  # the rest offset is not drawn
    np.testing.assert_allclose(power, husky.battery_voltage_v * drawn)
    assert not np.allclose(power, robot.battery_voltage_v * drawn)
    jackal = read_rosbag(bags["jackal"][0], BagTopics(cmd_vel_topic="/odometry/filtered"))
    with pytest.raises(DataError, match="log_battery_power_w needs measured drive currents"):
        log_battery_power_w(jackal, robot, current_convention="battery")


@requires_rosbags
def test_an_imu_publishing_in_g_is_refused_until_its_unit_is_given(tmp_path):
    write_robot_bag(tmp_path / "g.bag", in_g=True)
    with pytest.raises(UnitError, match=r"looks like an acceleration in g.*give accel_unit='g'") as raised:
        read_rosbag(tmp_path / "g.bag", BagTopics(**HUSKY))
    assert raised.value.parameter == "accel_unit"


@requires_rosbags
def test_the_command_line_says_the_accel_unit_by_its_flag(tmp_path, capsys):
    from terrawatt_cli import main

    write_robot_bag(tmp_path / "g.bag", in_g=True)
    rc = main(["train", "--model", "constant", "--data", str(tmp_path / "g.bag"), "--cmd-vel-topic",
               "/odometry/filtered", "--current-topics", "/status", "--current-fields", "left_driver_current",
               "right_driver_current", "--out", str(tmp_path / "m.zip")])
    err = capsys.readouterr().err
    assert rc == 2 and "looks like an acceleration in g" in err
    assert "give --accel-unit='g' for an IMU driver that publishes in g" in err, err


@requires_rosbags
def test_an_imu_in_g_reads_once_its_unit_is_given(tmp_path):
    truth = write_robot_bag(tmp_path / "g.bag", in_g=True)
    log = read_rosbag(tmp_path / "g.bag", BagTopics(**HUSKY, accel_unit="g"))
    assert not log.meta.gravity_removed
    assert np.median(log.accel_z_mps2) == pytest.approx(np.median(truth["az"]), rel=2e-3)  # m/s^2 again
    (via_layouts,) = read_logs(tmp_path / "g.bag", bag=BagTopics(**{**HUSKY, "current_topics": ("/status",)},
                                                                 accel_unit="g"))
    np.testing.assert_allclose(via_layouts.accel_z_mps2, log.accel_z_mps2)
