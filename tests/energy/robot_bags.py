"""Small ROS 1 bags like real robots record them (Husky: IMU 30 Hz + odometry + HuskyStatus;
Jackal: IMU 50 Hz + odometry, no current topic), written with the rosbags writer for tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

try:
    from rosbags.rosbag1 import Writer
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    HAVE_ROSBAGS = True
except ImportError:  # the 'ros' extra is optional
    HAVE_ROSBAGS = False

__all__ = ["HAVE_ROSBAGS", "requires_rosbags", "HUSKY_STATUS_MSG", "BASE_NS", "write_robot_bag"]

requires_rosbags = pytest.mark.skipif(not HAVE_ROSBAGS, reason="rosbags (the 'ros' extra) is not installed")

#: husky_msgs/HuskyStatus as Clearpath defines it (the bag carries it in its connection header).
HUSKY_STATUS_MSG = """\
Header header
uint32 uptime
float64 ros_control_loop_freq
float64 mcu_and_user_port_current
float64 left_driver_current
float64 right_driver_current
float64 battery_voltage
float64 left_driver_voltage
float64 right_driver_voltage
float64 left_driver_temp
float64 right_driver_temp
float64 left_motor_temp
float64 right_motor_temp
uint16 capacity_estimate
float64 charge_estimate
bool timeout
bool lockout
bool e_stop
bool ros_pause
bool no_battery
bool current_limit
"""

BASE_NS = 1_600_000_000_000_000_000
_S = 1_000_000_000


def write_robot_bag(
    path: Path,
    *,
    imu_hz: float = 30.0,
    odom_hz: float = 15.0,
    status_hz: float | None = 10.0,
    cmd_vel: bool = False,
    gravity: bool = True,
    in_g: bool = False,
    gyro: bool = True,
    duration_s: float = 6.0,
    seed: int = 0,
    kind: str = "ros1",
) -> dict[str, np.ndarray]:
    """Write a bag at ``path`` (``kind``: a ROS 1 ``.bag``, or a ROS 2 bag folder in sqlite3
    (``"ros2"``) or MCAP (``"mcap"``) storage) and return its truth (times in s from the first
    message).

    Topics: ``/imu/data`` (``sensor_msgs/Imu``, ``imu_hz``, gyro z = 0.3 sin t, a_z = 9.81 or
    0.09 + noise with ``gravity=False``), ``/odometry/filtered`` (``nav_msgs/Odometry``,
    ``odom_hz``), ``/cmd_vel`` (``geometry_msgs/Twist``, with ``cmd_vel``) and, unless
    ``status_hz`` is None, ``/status`` (``husky_msgs/HuskyStatus``: left/right driver current,
    battery voltage 26.5 V falling slowly).
    """
    rng = np.random.default_rng(seed)
    ros1 = kind == "ros1"
    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    ts.register(get_types_from_msg(HUSKY_STATUS_MSG, "husky_msgs/msg/HuskyStatus"))
    T = ts.types

    def header(ns: int):
        stamp = T["builtin_interfaces/msg/Time"](sec=ns // _S, nanosec=ns % _S)
        if ros1:
            return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id="base_link")
        return T["std_msgs/msg/Header"](stamp=stamp, frame_id="base_link")

    def vec(x=0.0, y=0.0, z=0.0):
        return T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)

    def ticks(hz: float) -> np.ndarray:
        return np.arange(0.0, duration_s, 1.0 / hz)

    truth: dict[str, np.ndarray] = {}
    msgs: list[tuple[int, str, str, object]] = []
    ti = ticks(imu_hz)
    az = (9.81 if gravity else 0.09) + 0.2 * rng.standard_normal(ti.size)
    if in_g:  # a driver that publishes in g (the truth stays in m/s^2)
        truth["az_published"] = az / 9.80665
    gz = 0.3 * np.sin(ti)
    truth.update(imu_t=ti, az=az, gz=gz)
    cov = np.zeros(9)
    gyro_cov = cov if gyro else np.r_[-1.0, np.zeros(8)]
    quat = T["geometry_msgs/msg/Quaternion"]
    for t, a, g in zip(ti, az / 9.80665 if in_g else az, gz):
        ns = BASE_NS + int(round(t * _S))
        m = T["sensor_msgs/msg/Imu"](
            header=header(ns), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0), orientation_covariance=cov,
            angular_velocity=vec(z=float(g) if gyro else 0.0), angular_velocity_covariance=gyro_cov,
            linear_acceleration=vec(z=float(a)), linear_acceleration_covariance=cov)
        msgs.append((ns, "/imu/data", "sensor_msgs/msg/Imu", m))
    to = ticks(odom_hz)
    v, w = 0.5 + 0.1 * np.sin(to), 0.2 * np.cos(to)
    truth.update(odom_t=to, v=v, w=w)
    for k, (t, vv, ww) in enumerate(zip(to, v, w)):
        ns = BASE_NS + int(round(t * _S))
        pose = T["geometry_msgs/msg/PoseWithCovariance"](
            pose=T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=0.05 * k, y=0.0, z=0.0),
                                             orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0)),
            covariance=np.zeros(36))
        tw = T["geometry_msgs/msg/TwistWithCovariance"](
            twist=T["geometry_msgs/msg/Twist"](linear=vec(x=float(vv)), angular=vec(z=float(ww))), covariance=np.zeros(36))
        m = T["nav_msgs/msg/Odometry"](header=header(ns), child_frame_id="base_link", pose=pose, twist=tw)
        msgs.append((ns, "/odometry/filtered", "nav_msgs/msg/Odometry", m))
        if cmd_vel:
            msgs.append((ns, "/cmd_vel", "geometry_msgs/msg/Twist",
                         T["geometry_msgs/msg/Twist"](linear=vec(x=float(vv)), angular=vec(z=float(ww)))))
    if status_hz is not None:
        tc = ticks(status_hz)
        left, right = 3.0 + np.sin(tc), 3.5 + np.cos(tc)
        volts = 26.5 - 0.01 * tc
        truth.update(status_t=tc, left=left, right=right, volts=volts)
        for t, lft, rgt, vlt in zip(tc, left, right, volts):
            ns = BASE_NS + int(round(t * _S))
            m = T["husky_msgs/msg/HuskyStatus"](
                header=header(ns), uptime=int(t * 1000), ros_control_loop_freq=10.0, mcu_and_user_port_current=0.5,
                left_driver_current=float(lft), right_driver_current=float(rgt), battery_voltage=float(vlt),
                left_driver_voltage=float(vlt), right_driver_voltage=float(vlt), left_driver_temp=30.0,
                right_driver_temp=30.0, left_motor_temp=35.0, right_motor_temp=35.0, capacity_estimate=400,
                charge_estimate=0.9, timeout=False, lockout=False, e_stop=False, ros_pause=False, no_battery=False,
                current_limit=False)
            msgs.append((ns, "/status", "husky_msgs/msg/HuskyStatus", m))
    if ros1:
        writer = Writer(path)
    else:
        writer = Writer2(path, version=9, storage_plugin=StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3)
    serialize = ts.serialize_ros1 if ros1 else ts.serialize_cdr
    with writer:
        conns = {}
        for ns, topic, typ, m in sorted(msgs, key=lambda x: x[0]):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, typ, typestore=ts)
            writer.write(conns[topic], ns, serialize(m, typ))
    return truth
