"""A drive as ROS messages and back: a log as odometry, IMU, current, battery and GPS messages; live messages as a log.

The two directions share one set of topic names, :class:`DriveBagTopics`:

- :func:`messages_from_log` turns an :class:`~energy.logs.InteractionLog` into the messages a
  robot would have published (``rosbags`` message classes of a given typestore, ROS 1 or ROS 2),
  each with its stamp; :func:`energy.io.drive_bag.write_drive_bag` writes them as a bag;
- :func:`log_from_messages` turns messages received live (``rosbags`` dataclasses or rclpy
  messages: only field names are read) into the log a bag of the same messages gives: it
  calls the bag reader's own conversion, alignment and checks
  (:func:`energy.io.rosbag.log_from_topic_messages`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_int, check_text, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

from ..logs import InteractionLog
from .bag_messages import TopicMessages
from .cleaning import LogCleaning
from .rosbag import BagTiming, BagTopics, log_from_topic_messages

__all__ = [
    "DEFAULT_START_TIME_NS",
    "MAX_STAMP_NS",
    "DRIVE_MESSAGE_TYPES",
    "DriveBagTopics",
    "check_lonlat",
    "messages_from_log",
    "log_from_messages",
]

#: Bag time (ns since the Unix epoch) of a written log's ``time_s == 0`` when neither the caller
#: nor the log's ``meta.start_time_ns`` gives one: 2023-11-14 22:13:20 UTC.
DEFAULT_START_TIME_NS = 1_700_000_000 * 1_000_000_000
#: Latest stamp a message may carry (ns): ROS 2's ``builtin_interfaces/Time.sec`` is an int32.
MAX_STAMP_NS = (2**31 - 1) * 1_000_000_000
#: Message type of each stream of a drive, by the field of :class:`DriveBagTopics` naming its topic.
DRIVE_MESSAGE_TYPES = {
    "odom_topic": "nav_msgs/msg/Odometry",
    "imu_topic": "sensor_msgs/msg/Imu",
    "current_topics": "std_msgs/msg/Float64",
    "battery_topic": "sensor_msgs/msg/BatteryState",
    "navsat_topic": "sensor_msgs/msg/NavSatFix",
}
_NS = 1_000_000_000
#: Fields a live message of each stream must have (dotted paths), checked on its first message.
_NEEDS = {
    "odom": ("header.stamp", "pose.pose.position", "pose.pose.orientation", "twist.twist.linear",
             "twist.twist.angular"),
    "imu": ("linear_acceleration.z", "angular_velocity.z", "angular_velocity_covariance"),
    "current_left": ("data",),
    "current_right": ("data",),
    "battery": ("voltage", "current"),
}


@dataclass(frozen=True)
class DriveBagTopics:
    """The topics (and frames) of a recorded drive: what :func:`~energy.io.drive_bag.write_drive_bag`
    writes and :func:`log_from_messages` reads.

    Parameters
    ----------
    odom_topic : str
        ``nav_msgs/msg/Odometry``: pose (x, y, yaw) in ``map_frame``, twist (v, omega) in ``base_frame``.
    imu_topic : str
        ``sensor_msgs/msg/Imu``: vertical acceleration and gyro yaw rate.
    current_topics : (str, str)
        Left and right drive current (A), ``std_msgs/msg/Float64``.
    battery_topic : str
        ``sensor_msgs/msg/BatteryState``: pack voltage and current.
    navsat_topic : str
        ``sensor_msgs/msg/NavSatFix``: longitude, latitude.
    map_frame, base_frame : str
        The odometry's frame and child frame; ``base_frame`` also stamps the IMU, battery and GPS.

    Raises
    ------
    InvalidParameterError
        An empty or non-string name, a topic not starting with ``/``, two streams on one topic.

    Examples
    --------
    >>> DriveBagTopics().bag_topics().cmd_vel_topic
    '/odom'
    """

    odom_topic: str = "/odom"
    imu_topic: str = "/imu/data"
    current_topics: tuple[str, str] = ("/drive/current_left", "/drive/current_right")
    battery_topic: str = "/battery"
    navsat_topic: str = "/gps/fix"
    map_frame: str = "map"
    base_frame: str = "base_link"

    def __post_init__(self) -> None:
        cur = self.current_topics
        if isinstance(cur, str) or not isinstance(cur, Iterable) or len(tuple(cur)) != 2:
            raise InvalidParameterError(
                f"DriveBagTopics.current_topics must be two topics (left, right), got {cur!r:.80}")
        object.__setattr__(self, "current_topics", tuple(cur))
        topics = {"odom_topic": self.odom_topic, "imu_topic": self.imu_topic,
                  "current_topics[0]": self.current_topics[0], "current_topics[1]": self.current_topics[1],
                  "battery_topic": self.battery_topic, "navsat_topic": self.navsat_topic}
        for name, topic in topics.items():
            check_text(name, topic, owner="DriveBagTopics")
            if not topic.startswith("/"):
                raise InvalidParameterError(f"DriveBagTopics.{name} must start with '/', got {topic!r}")
        if len(set(topics.values())) != len(topics):
            raise InvalidParameterError(f"DriveBagTopics: each stream needs its own topic, got {topics!r}")
        check_text("map_frame", self.map_frame, owner="DriveBagTopics")
        check_text("base_frame", self.base_frame, owner="DriveBagTopics")

    def bag_topics(self, **options: Any) -> BagTopics:
        """The :class:`~energy.io.BagTopics` that read a bag of these topics back (``options``: its other fields).

        The odometry is the velocity topic, the battery topic is read when present; the drive
        stream takes the current messages' times (the drive times when the log had currents).
        """
        return BagTopics(cmd_vel_topic=self.odom_topic, imu_topic=self.imu_topic, current_topics=self.current_topics,
                         battery_topic=self.battery_topic, **options)


def _stamp_ns(time_zero_ns: int, t_s: np.ndarray) -> np.ndarray:
    return time_zero_ns + np.rint(np.asarray(t_s, dtype=np.float64) * _NS).astype(np.int64)


def check_lonlat(name: str, value: Any, n: int) -> np.ndarray:
    """``value`` as an ``(n, 2)`` float64 array: finite longitudes in [-180, 180], latitudes in [-90, 90] (degrees)."""
    arr = real_array(name, value, ndim=2)
    if arr.shape != (n, 2):
        raise InvalidParameterError(f"{name} must have shape ({n}, 2) (lon, lat in degrees per drive sample), got "
                                    f"shape {arr.shape!r}")
    if np.any(np.abs(arr[:, 0]) > 180.0) or np.any(np.abs(arr[:, 1]) > 90.0):
        raise InvalidParameterError(f"{name} must hold longitudes in [-180, 180] and latitudes in [-90, 90] degrees "
                                    f"(lon first), got lon in [{arr[:, 0].min():g}, {arr[:, 0].max():g}], lat in "
                                    f"[{arr[:, 1].min():g}, {arr[:, 1].max():g}]")
    return arr


def messages_from_log(
    log: InteractionLog,
    typestore: Any,
    *,
    time_zero_ns: int | None = None,
    lonlat_deg: Any = None,
    topics: DriveBagTopics = DriveBagTopics(),
) -> list[tuple[int, str, str, Any]]:
    """The ROS messages of a drive log, each with its stamp, in time order.

    Parameters
    ----------
    log : InteractionLog
        A log with ``pose_xyh``.
    typestore : rosbags Typestore
        The message classes (``rosbags.typesys.get_typestore(Stores.ROS2_JAZZY)`` or a ROS 1
        store: a header with a ``seq`` field gets ``seq=0``).
    time_zero_ns : int, optional
        The stamp (ns since the epoch) of the log's ``time_s == 0``; by default the log's
        ``meta.start_time_ns``, else :data:`DEFAULT_START_TIME_NS`.
    lonlat_deg : array_like, shape (N, 2), optional
        Longitude, latitude (degrees) at the drive timestamps: one ``NavSatFix`` each (status
        fix, GPS service, altitude NaN: not known, covariance unknown).
    topics : DriveBagTopics

    Returns
    -------
    list of (int, str, str, message)
        ``(stamp_ns, topic, message type, message)`` sorted by stamp (streams in the order of
        :data:`DRIVE_MESSAGE_TYPES` at equal stamps). At each drive time: an Odometry (x, y, the
        heading as a yaw quaternion; twist ``linear.x = v_mps``, ``angular.z = omega_radps``;
        covariances zero), the left and right currents (A) when the log has them, a BatteryState
        when it has ``battery_voltage_v`` (``current`` the pack current with its sign turned:
        negative discharging, as BatteryState says; NaN without one; float32 fields, so the
        values are rounded to float32, about 7 digits, as a subscriber receives them) and, with
        ``lonlat_deg``, the NavSatFix; at each IMU time an Imu
        (``linear_acceleration.z = accel_z_mps2``, ``angular_velocity.z = gyro_z_radps``, or
        ``angular_velocity_covariance[0] = -1`` without a gyro; orientation unknown:
        ``orientation_covariance[0] = -1``). Header stamps are the message stamps.

    Raises
    ------
    InvalidParameterError
        Not an InteractionLog, no ``pose_xyh``, ``lonlat_deg`` of the wrong shape or range, a
        ``time_zero_ns`` that puts a stamp at or before the epoch or past :data:`MAX_STAMP_NS`.
    """
    if not isinstance(log, InteractionLog):
        raise InvalidParameterError(f"log must be an InteractionLog, got {type(log).__name__!r}")
    if log.pose_xyh is None:
        raise InvalidParameterError("log has no pose_xyh: a drive's odometry needs the pose (x_m, y_m, heading_rad)")
    if not isinstance(topics, DriveBagTopics):
        raise InvalidParameterError(f"topics must be a DriveBagTopics, got {type(topics).__name__!r}")
    lonlat = None if lonlat_deg is None else check_lonlat("lonlat_deg", lonlat_deg, len(log))
    if time_zero_ns is None:
        time_zero_ns = log.meta.start_time_ns if log.meta.start_time_ns is not None else DEFAULT_START_TIME_NS
    zero = check_int("time_zero_ns", time_zero_ns, low=-MAX_STAMP_NS, high=MAX_STAMP_NS)
    drive_ns, imu_ns = _stamp_ns(zero, log.time_s), _stamp_ns(zero, log.accel_time_s)
    first, last = min(int(drive_ns[0]), int(imu_ns[0])), max(int(drive_ns[-1]), int(imu_ns[-1]))
    if first <= 0 or last > MAX_STAMP_NS:
        raise InvalidParameterError(
            f"time_zero_ns {zero!r} puts the log's stamps in [{first}, {last}] ns; ROS stamps must lie in "
            f"(0, {MAX_STAMP_NS}] ns (a zero stamp reads as 'no stamp')"
        )
    build = _Builder(typestore, topics)
    out: list[tuple[int, int, str, str, Any]] = []
    pose, v, w = log.pose_xyh.tolist(), log.v_mps.tolist(), log.omega_radps.tolist()
    for k, ns in enumerate(drive_ns.tolist()):
        out.append((ns, 0, topics.odom_topic, DRIVE_MESSAGE_TYPES["odom_topic"],
                    build.odometry(ns, pose[k], v[k], w[k])))
    gyro = None if log.gyro_z_radps is None else log.gyro_z_radps.tolist()
    for k, (ns, az) in enumerate(zip(imu_ns.tolist(), log.accel_z_mps2.tolist(), strict=True)):
        out.append((ns, 1, topics.imu_topic, DRIVE_MESSAGE_TYPES["imu_topic"],
                    build.imu(ns, az, None if gyro is None else gyro[k])))
    if log.has_currents:
        for rank, topic, values in ((2, topics.current_topics[0], log.current_left_a),
                                    (3, topics.current_topics[1], log.current_right_a)):
            for ns, value in zip(drive_ns.tolist(), values.tolist(), strict=True):
                out.append((ns, rank, topic, DRIVE_MESSAGE_TYPES["current_topics"], build.scalar(value)))
    if log.battery_voltage_v is not None:
        pack = (np.full(len(log), math.nan) if log.battery_current_a is None else -log.battery_current_a).tolist()
        for ns, volts, amps in zip(drive_ns.tolist(), log.battery_voltage_v.tolist(), pack, strict=True):
            out.append((ns, 4, topics.battery_topic, DRIVE_MESSAGE_TYPES["battery_topic"],
                        build.battery(ns, volts, amps)))
    if lonlat is not None:
        for ns, (lon, lat) in zip(drive_ns.tolist(), lonlat.tolist(), strict=True):
            out.append((ns, 5, topics.navsat_topic, DRIVE_MESSAGE_TYPES["navsat_topic"], build.navsat(ns, lon, lat)))
    out.sort(key=lambda item: (item[0], item[1]))
    return [(ns, topic, msgtype, msg) for ns, _, topic, msgtype, msg in out]


class _Builder:
    """The message classes of one typestore, filled for a drive's streams."""

    def __init__(self, typestore: Any, topics: DriveBagTopics) -> None:
        try:
            self.types = typestore.types
            header_fields = [f[0] for f in typestore.fielddefs["std_msgs/msg/Header"][1]]
        except (AttributeError, KeyError, TypeError) as exc:
            raise InvalidParameterError(
                f"typestore must be a rosbags Typestore, got {type(typestore).__name__!r}") from exc
        self.ros1 = "seq" in header_fields
        self.topics = topics
        self.zeros9 = np.zeros(9)
        self.zeros36 = np.zeros(36)
        self.unknown9 = np.r_[-1.0, np.zeros(8)]

    def header(self, ns: int, frame_id: str) -> Any:
        stamp = self.types["builtin_interfaces/msg/Time"](sec=ns // _NS, nanosec=ns % _NS)
        if self.ros1:
            return self.types["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame_id)
        return self.types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id)

    def vector(self, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Any:
        return self.types["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)

    def quaternion(self, yaw_rad: float) -> Any:
        return self.types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw_rad / 2.0),
                                                          w=math.cos(yaw_rad / 2.0))

    def odometry(self, ns: int, pose_xyh: list[float], v_mps: float, omega_radps: float) -> Any:
        t = self.types
        x, y, heading = pose_xyh
        pose = t["geometry_msgs/msg/Pose"](position=t["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                                           orientation=self.quaternion(heading))
        twist = t["geometry_msgs/msg/Twist"](linear=self.vector(x=v_mps), angular=self.vector(z=omega_radps))
        return t["nav_msgs/msg/Odometry"](
            header=self.header(ns, self.topics.map_frame), child_frame_id=self.topics.base_frame,
            pose=t["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=self.zeros36),
            twist=t["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=self.zeros36))

    def imu(self, ns: int, accel_z_mps2: float, gyro_z_radps: float | None) -> Any:
        return self.types["sensor_msgs/msg/Imu"](
            header=self.header(ns, self.topics.base_frame),
            orientation=self.types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            orientation_covariance=self.unknown9,
            angular_velocity=self.vector(z=0.0 if gyro_z_radps is None else gyro_z_radps),
            angular_velocity_covariance=self.unknown9 if gyro_z_radps is None else self.zeros9,
            linear_acceleration=self.vector(z=accel_z_mps2), linear_acceleration_covariance=self.zeros9)

    def scalar(self, value: float) -> Any:
        return self.types["std_msgs/msg/Float64"](data=value)

    def battery(self, ns: int, voltage_v: float, ros_current_a: float) -> Any:
        nan = math.nan
        f32 = np.float32  # BatteryState's fields are float32: the message holds what a subscriber receives
        return self.types["sensor_msgs/msg/BatteryState"](
            header=self.header(ns, self.topics.base_frame), voltage=float(f32(voltage_v)), temperature=nan,
            current=float(f32(ros_current_a)),
            charge=nan, capacity=nan, design_capacity=nan, percentage=nan, power_supply_status=0,
            power_supply_health=0, power_supply_technology=0, present=True,
            cell_voltage=np.zeros(0, dtype=np.float32), cell_temperature=np.zeros(0, dtype=np.float32),
            location="", serial_number="")

    def navsat(self, ns: int, lon_deg: float, lat_deg: float) -> Any:
        t = self.types
        return t["sensor_msgs/msg/NavSatFix"](
            header=self.header(ns, self.topics.base_frame),
            status=t["sensor_msgs/msg/NavSatStatus"](status=0, service=1),  # STATUS_FIX, SERVICE_GPS
            latitude=lat_deg, longitude=lon_deg, altitude=math.nan, position_covariance=self.zeros9,
            position_covariance_type=0)


def _has(msg: Any, path: str) -> bool:
    for part in path.split("."):
        if not hasattr(msg, part):
            return False
        msg = getattr(msg, part)
    return True


def _stream(source: str, role: str, topic: str, value: Any) -> list[tuple[int, Any]]:
    """One stream's ``(stamp_ns, message)`` pairs, checked: a non-empty sequence, int stamps in order."""
    where = f"{source}: topic {topic!r} ({role})"
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
        raise InvalidParameterError(
            f"{where} must be a list of (stamp_ns, message) pairs, got {type(value).__name__!r}")
    if len(value) == 0:
        raise DataError(f"{where} has no messages")
    pairs: list[tuple[int, Any]] = []
    for i, item in enumerate(value):
        if not (isinstance(item, (tuple, list)) and len(item) == 2):
            raise InvalidParameterError(f"{where}: item {i} must be a (stamp_ns, message) pair, got {item!r:.80}")
        pairs.append((check_int(f"{role}[{i}] stamp_ns", item[0], low=0), item[1]))
    missing = [f for f in _NEEDS[role] if not _has(pairs[0][1], f)]
    if missing:
        raise InvalidParameterError(f"{where}: the messages lack field(s) {missing!r}; expected a "
                                    f"{_role_type(role)} message, got {type(pairs[0][1]).__name__!r}")
    stamps = np.array([ns for ns, _ in pairs], dtype=np.int64)
    back = np.diff(stamps) < 0
    if back.any():
        i = int(np.argmax(back)) + 1
        raise DataError(f"{where}: receive stamps are not sorted; {int(back.sum())} step(s) go backwards, first at "
                        f"index {i} ({stamps[i]} ns after {stamps[i - 1]} ns); give the messages in receive order")
    return pairs


def _role_type(role: str) -> str:
    key = {"odom": "odom_topic", "imu": "imu_topic", "battery": "battery_topic"}.get(role, "current_topics")
    return DRIVE_MESSAGE_TYPES[key]


def log_from_messages(
    odom: Sequence[tuple[int, Any]],
    imu: Sequence[tuple[int, Any]],
    current_left: Sequence[tuple[int, Any]] | None = None,
    current_right: Sequence[tuple[int, Any]] | None = None,
    battery: Sequence[tuple[int, Any]] | None = None,
    *,
    topics: DriveBagTopics = DriveBagTopics(),
    robot: str = "unknown",
    ground_label: str | None = None,
    source: str = "ROS messages",
    drive_clock: str = "currents",
    current_unit: str = "A",
    accel_unit: str = "m/s^2",
    timing: BagTiming | None = None,
    cleaning: LogCleaning | None = None,
) -> InteractionLog:
    """The interaction log of a chunk of live messages: the log a bag of the same messages gives.

    Each stream is a list of ``(stamp_ns, message)`` pairs in receive order, ``stamp_ns`` the
    receive time (ns, as a bag records it: e.g. the node's clock when the callback ran) and the
    message a ``rosbags`` dataclass or an rclpy message (only field names are read). The streams
    go through the bag reader's own steps (:func:`energy.io.rosbag.log_from_topic_messages`, as
    :func:`~energy.io.read_rosbag` with the odometry as velocity topic): times from the header
    stamps (near the receive times, see ``max_clock_offset_s``) or the receive times, the
    cleaning and unit checks of :mod:`energy.io.cleaning`, alignment on the overlap of the
    streams, the drive stream on the left current's times (``drive_clock``).

    Parameters
    ----------
    odom : list of (int, nav_msgs/Odometry)
        Measured velocity (``twist.twist``) and pose (``pose.pose``: ``pose_xyh``).
    imu : list of (int, sensor_msgs/Imu)
    current_left, current_right : list of (int, std_msgs/Float64 or Float32), optional
        Drive currents in ``current_unit``: both or neither (a log without currents).
    battery : list of (int, sensor_msgs/BatteryState), optional
        Pack voltage and current (``battery_voltage_v``, ``battery_current_a``).
    topics : DriveBagTopics
        The topic of each stream, for messages and notes (the names a bag of them would have).
    robot, ground_label : metadata
    source : str
        ``meta.source`` and the name in messages.
    drive_clock, current_unit, accel_unit
        As the fields of :class:`~energy.io.BagTopics`.
    timing, cleaning
        As :func:`~energy.io.read_rosbag` (:class:`~energy.io.BagTiming`: the header stamps and the
        largest clock offset apply; :class:`~energy.io.cleaning.LogCleaning`).

    Returns
    -------
    InteractionLog
        ``meta.velocity_source`` is ``"measured"``; ``meta.start_time_ns`` the earliest time used.

    Raises
    ------
    InvalidParameterError
        A stream that is not a list of ``(stamp_ns, message)`` pairs (int stamps >= 0), messages
        without the fields of their type, one current stream without the other, bad options.
    DataError
        An empty stream, receive stamps out of order (both name the topic); as
        :func:`~energy.io.read_rosbag` (unsorted or duplicated header stamps, NaNs, gaps, no overlap).
    UnitError
        As :func:`~energy.io.read_rosbag` with ``cleaning.check_units``.

    Examples
    --------
    Usage (a node that buffers its callbacks' messages)::

        log = log_from_messages(odom=odom_buffer, imu=imu_buffer, current_left=left_buffer,
                                current_right=right_buffer, robot="husky")
    """
    if not isinstance(topics, DriveBagTopics):
        raise InvalidParameterError(f"topics must be a DriveBagTopics, got {type(topics).__name__!r}")
    check_text("source", source)
    if (current_left is None) != (current_right is None):
        raise InvalidParameterError(
            "current_left and current_right must both be given or both be None, got "
            f"{'None' if current_left is None else 'messages'} and {'None' if current_right is None else 'messages'}"
        )
    left_topic, right_topic = topics.current_topics
    streams = {"odom": (topics.odom_topic, odom), "imu": (topics.imu_topic, imu),
               "current_left": (left_topic, current_left), "current_right": (right_topic, current_right),
               "battery": (topics.battery_topic, battery)}
    raw: dict[str, list[tuple[int, Any]]] = {}
    types: dict[str, str] = {}
    for role, (topic, value) in streams.items():
        if value is None:
            continue
        raw[topic] = _stream(source, role, topic, value)
        types[topic] = _role_type(role)
    bag = BagTopics(topics.odom_topic, topics.imu_topic, topics.current_topics,
                    battery_topic=topics.battery_topic if battery is not None else None, drive_clock=drive_clock,
                    current_unit=current_unit, accel_unit=accel_unit)
    return log_from_topic_messages(TopicMessages(source, raw, types, container="the messages"), bag, timing=timing,
                                   robot=robot, ground_label=ground_label, cleaning=cleaning)
