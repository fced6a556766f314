"""ROS 1 bags, ROS 2 bags (sqlite3 or MCAP) into interaction logs, in named steps.

:func:`read_rosbag` reads the messages of the wanted topics
(:func:`~energy.io.bag_messages.read_messages`, with the message types a ROS 1 bag defines
in its connection headers), puts each topic on one clock
(:func:`~energy.io.bag_messages.topic_times`), builds the velocity, IMU and current streams
(currents from ``std_msgs`` topics or fields of a status message picked by name; battery
voltage and current from a ``sensor_msgs/BatteryState`` topic), checks and cleans them like
every reader (:mod:`energy.io.cleaning`) and aligns them on their overlap
(:func:`~energy.io.bag_align.align_streams`). Everything after the reading is
:func:`log_from_topic_messages`, which :mod:`energy.io.ros_messages` also calls on live
messages: a chunk of messages and a bag of the same messages give the same log.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_bool, check_choice, check_optional_real, check_real, check_text, fmt_number
from terrawatt_base.errors import DataError, InvalidParameterError

from ..logs import InteractionLog, LogMeta
from .bag_align import CurrentStreams, align_streams
from .bag_messages import (
    Messages,
    TopicMessages,
    bag_path,
    expect_type,
    field_values,
    import_rosbags,
    read_messages,
    topic_times,
)
from .cleaning import (
    MAX_BATTERY_VOLTAGE_V,
    MAX_OMEGA_RADPS,
    MAX_SPEED_MPS,
    UNIT_FACTORS,
    LogCleaning,
    check_accel,
    check_current,
    check_limit,
    check_timing,
    clean_stream,
    gravity_note,
)

__all__ = ["MAX_CLOCK_OFFSET_S", "DRIVE_CLOCKS", "BagTopics", "BagTiming", "read_rosbag", "log_from_topic_messages"]

_LOG = logging.getLogger(__name__)

#: Default largest median (receive time - header stamp) a bag topic may show before
#: ``read_rosbag`` refuses to mix its header stamps with receive times (s).
MAX_CLOCK_OFFSET_S = 0.5
#: Values of ``read_rosbag``'s ``drive_clock``: the drive stream on the current messages'
#: times, or on the velocity stream's (odometry messages, or a grid for commands).
DRIVE_CLOCKS = ("currents", "velocity")

_TWIST_TYPES = ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped")
_ODOM_TYPES = ("nav_msgs/msg/Odometry",)
_IMU_TYPES = ("sensor_msgs/msg/Imu",)
_SCALAR_TYPES = ("std_msgs/msg/Float64", "std_msgs/msg/Float32")
_ARRAY_TYPES = ("std_msgs/msg/Float64MultiArray", "std_msgs/msg/Float32MultiArray")
_BATTERY_TYPES = ("sensor_msgs/msg/BatteryState",)
_FIELDS_HINT = (
    "; for a status message (e.g. husky_msgs/msg/HuskyStatus) name its current fields with "
    "current_fields (e.g. left_driver_current right_driver_current)"
)


@dataclass(frozen=True)
class BagTopics:
    """Where a bag keeps its streams: the topics and message fields :func:`read_rosbag` reads, their units,
    and whose times the drive stream takes.

    Parameters
    ----------
    cmd_vel_topic : str
        Commands (``geometry_msgs/Twist``) or wheel odometry (``nav_msgs/Odometry``).
    imu_topic : str
        ``sensor_msgs/Imu``.
    current_topics : tuple of str
        Two ``std_msgs/Float*`` topics (left, right), or one multi-array or status topic.
    current_fields : (str, str) or None
        Left and right current fields of a status message on the one current topic, e.g.
        ``("left_driver_current", "right_driver_current")`` for ``husky_msgs/HuskyStatus``.
    voltage_field : str or None
        Battery voltage field of that status message (e.g. ``"battery_voltage"``).
    current_unit : {"A", "mA"}
    accel_unit : {"m/s^2", "m/s2", "g"}
        Unit of the IMU's ``linear_acceleration`` (some drivers publish g).
    drive_clock : {"currents", "velocity"}
        The drive stream on the current messages' times, or on the odometry's (currents
        interpolated onto them: a 1 Hz status message beside 10-50 Hz odometry).
    battery_topic : str or None
        A ``sensor_msgs/BatteryState`` topic: battery voltage and pack current on the drive
        clock, read when the bag has it (see :func:`read_rosbag`).

    Raises
    ------
    InvalidParameterError, UnknownNameError
        Empty or non-string names, the wrong number of topics or fields, a voltage field
        without current fields, a voltage field beside a battery topic, an unknown unit.

    Examples
    --------
    >>> BagTopics(cmd_vel_topic="/odometry/filtered", current_topics=("/status",),
    ...           current_fields=("left_driver_current", "right_driver_current")).current_topics
    ('/status',)
    """

    cmd_vel_topic: str = "/cmd_vel"
    imu_topic: str = "/imu/data"
    current_topics: tuple[str, ...] = ("/drive/current_left", "/drive/current_right")
    current_fields: tuple[str, str] | None = None
    voltage_field: str | None = None
    current_unit: str = "A"
    accel_unit: str = "m/s^2"
    drive_clock: str = "currents"
    battery_topic: str | None = None

    def __post_init__(self) -> None:
        check_text("cmd_vel_topic", self.cmd_vel_topic)
        check_text("imu_topic", self.imu_topic)
        topics = _names("current_topics", self.current_topics, (1, 2))
        object.__setattr__(self, "current_topics", topics)
        if self.current_fields is not None:
            object.__setattr__(self, "current_fields", _names("current_fields", self.current_fields, (2,)))
            if len(topics) != 1:
                raise InvalidParameterError(
                    f"current_fields read one status topic; give one current topic (current_topics), got {topics!r}",
                    parameter=("current_fields", "current_topics")
                )
        if self.voltage_field is not None:
            check_text("voltage_field", self.voltage_field)
            if self.current_fields is None:
                raise InvalidParameterError(
                    "voltage_field is read beside the currents of a status message: name them too with "
                    "current_fields", parameter=("voltage_field", "current_fields")
                )
        check_choice("current_unit", self.current_unit, tuple(UNIT_FACTORS["current"]))
        check_choice("accel_unit", self.accel_unit, tuple(UNIT_FACTORS["accel"]))
        check_choice("drive_clock", self.drive_clock, DRIVE_CLOCKS)
        if self.battery_topic is not None:
            check_text("battery_topic", self.battery_topic)
            if self.voltage_field is not None:
                raise InvalidParameterError(
                    f"battery_topic {self.battery_topic!r} and voltage_field {self.voltage_field!r} both give the "
                    "battery voltage; name one of them", parameter=("battery_topic", "voltage_field")
                )


def _names(name: str, value: Any, counts: tuple[int, ...]) -> tuple[str, ...]:
    items = (value,) if isinstance(value, str) else tuple(value) if isinstance(value, Iterable) else (value,)
    if len(items) not in counts or not all(isinstance(x, str) and x for x in items):
        raise InvalidParameterError(
            f"{name} must be {' or '.join(map(str, counts))} non-empty name(s), got {value!r:.80}"
        )
    return items


@dataclass(frozen=True)
class BagTiming:
    """How a bag's streams are put on one clock and sampled: header stamps or receive times, commands held.

    Parameters
    ----------
    use_header_stamps : bool
        Read a topic whose messages carry a header on its header stamps (when all are
        non-zero); else every topic on the receive times.
    max_clock_offset_s : float
        Largest tolerated |median(receive time - header stamp)| of a topic read on header
        stamps (s, finite, > 0; default :data:`MAX_CLOCK_OFFSET_S`).
    cmd_vel_timeout_s : float or None
        A command older than this (s, > 0) counts as zero; None holds it indefinitely.
    drive_rate_hz : float
        Rate of the drive grid of a bag without odometry when the drive stream is not on the
        currents (Hz, > 0).

    Raises
    ------
    InvalidParameterError
        A bad value (the message names the parameter).

    Examples
    --------
    >>> BagTiming(use_header_stamps=False).cmd_vel_timeout_s
    0.5
    """

    use_header_stamps: bool = True
    max_clock_offset_s: float = MAX_CLOCK_OFFSET_S
    cmd_vel_timeout_s: float | None = 0.5
    drive_rate_hz: float = 10.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "use_header_stamps", check_bool("use_header_stamps", self.use_header_stamps))
        check_optional_real("cmd_vel_timeout_s", self.cmd_vel_timeout_s, low=0.0, low_inclusive=False)
        check_real("max_clock_offset_s", self.max_clock_offset_s, low=0.0, low_inclusive=False)
        check_real("drive_rate_hz", self.drive_rate_hz, low=0.0, low_inclusive=False)


@dataclass(frozen=True)
class _Options:
    """The checked options of one read."""

    topics_cur: tuple[str, ...]
    current_fields: tuple[str, str] | None
    voltage_field: str | None
    require: bool
    drive_rate_hz: float
    on_currents: bool


def _checked(topics: Any, timing: Any, require_currents: Any, ground_label: Any, cleaning: Any
             ) -> tuple[BagTopics, BagTiming, LogCleaning, _Options]:
    """The values of one read, checked (None: the defaults), and what the steps need of them."""
    topics = BagTopics() if topics is None else topics
    if not isinstance(topics, BagTopics):
        raise InvalidParameterError(f"topics must be a BagTopics, got {type(topics).__name__!r}", parameter="topics")
    timing = BagTiming() if timing is None else timing
    if not isinstance(timing, BagTiming):
        raise InvalidParameterError(f"timing must be a BagTiming, got {type(timing).__name__!r}", parameter="timing")
    cleaning = LogCleaning.check(cleaning)
    require = check_bool("require_currents", require_currents)
    if ground_label is not None:
        check_text("ground_label", ground_label)
    fields = topics.current_fields
    return topics, timing, cleaning, _Options(topics.current_topics, fields, topics.voltage_field,
                                              require or fields is not None, float(timing.drive_rate_hz),
                                              topics.drive_clock == "currents")


def read_rosbag(
    path: str | os.PathLike[str],
    topics: BagTopics | None = None,
    *,
    timing: BagTiming | None = None,
    require_currents: bool = False,
    robot: str = "unknown",
    ground_label: str | None = None,
    cleaning: LogCleaning | None = None,
) -> InteractionLog:
    """Read an interaction log from a ROS 1 ``.bag``, a ROS 2 bag (sqlite3 ``.db3`` or MCAP).

    Needs the ``ros`` extra (``pip install 'terrawatt[ros]'``, i.e. ``rosbags``).

    Topics and message types (conventions of this reader):

    - ``cmd_vel_topic``: ``geometry_msgs/msg/Twist`` or ``TwistStamped`` (commanded;
      ``linear.x`` m/s, ``angular.z`` rad/s), or ``nav_msgs/msg/Odometry`` (measured
      ``twist.twist``; its pose becomes ``pose_xyh`` with the yaw of the orientation).
    - ``imu_topic``: ``sensor_msgs/msg/Imu``; ``linear_acceleration.z`` (gravity included;
      an IMU that publishes it with gravity removed — median within +/-3 m/s^2 — is
      accepted, with ``meta.gravity_removed`` set and a note) and ``angular_velocity.z``
      (the gyro yaw rate, ``gyro_z_radps``; left out when the IMU marks it absent with
      ``angular_velocity_covariance[0] == -1``).
    - per-side drive current, in ``current_unit`` (``"A"`` or ``"mA"``): either two topics
      ``(left, right)`` of ``std_msgs/msg/Float64`` or ``Float32`` (``data``), or one topic
      of ``std_msgs/msg/Float64MultiArray`` / ``Float32MultiArray`` whose ``data`` is
      exactly ``[left, right]``, or — with ``current_fields`` — one topic of any message
      type (a vendor status message, e.g. ``husky_msgs/HuskyStatus`` with
      ``current_fields=("left_driver_current", "right_driver_current")`` and
      ``voltage_field="battery_voltage"``) whose named numeric fields (dotted paths for
      nested ones) are the left and right currents. A ROS 1 bag carries the definition of
      every message type in its connection headers, and those are registered before
      reading, so vendor messages need no installed package.
    - currents are optional: when none of the current topics is in the bag, the log has
      no currents (``log.has_currents`` is False, ``meta.missing_currents`` says which
      topics were missing) — enough to predict from; training and scoring refuse it.
      ``require_currents=True`` (implied by ``current_fields`` or ``voltage_field``)
      makes a missing topic an error instead.
    - ``battery_topic`` (optional): ``sensor_msgs/msg/BatteryState``; ``voltage`` (V) goes to
      ``battery_voltage_v`` and ``current`` to ``battery_current_a`` with its sign turned
      (BatteryState's current is negative when discharging, the log's pack current positive);
      a current that is NaN in every message (the ROS mark of "not measured") is left out.
      Read when the topic is in the bag; when it is not, the log has no battery fields and
      ``meta.notes`` says so. A status message's ``voltage_field`` is the other source of
      the voltage: name one of them.

    Timestamps: a topic whose messages carry a header uses the header stamps when
    ``use_header_stamps`` and every stamp is non-zero; otherwise (and for std_msgs
    topics) the bag receive time; ``meta.notes`` says which. Header stamps come from the
    publishers' clocks and receive times from the recorder's, and the current topics are
    always on receive time, so a clock offset would shift vibration (and odometry) against
    current. For each topic read on header stamps the reader takes the median of
    (receive time - header stamp), written to ``meta.notes``; if its magnitude exceeds
    ``max_clock_offset_s`` (default :data:`MAX_CLOCK_OFFSET_S` = 0.5 s, well above
    transport latency) it raises DataError rather than guess: pass
    ``use_header_stamps=False`` to put every topic on the receive time. Times are seconds
    since the earliest timestamp used (``meta.start_time_ns`` keeps that absolute time).

    Alignment: the drive stream is sampled at the current messages (the left topic's with
    two topics; the right current is interpolated linearly onto them), inside the
    overlap of the current and IMU streams (and of the odometry stream, if used); without
    currents, or with ``drive_clock="velocity"``, at the odometry messages, or with
    commands only on a uniform grid at ``drive_rate_hz``, the currents (and voltage) then
    interpolated linearly onto them — for a status message at 1 Hz beside odometry at
    10-50 Hz. The battery topic's voltage and current are interpolated linearly onto the
    drive times too; its span does not cut the overlap: drive samples before its first or
    after its last message take that message's values, within ``gap_factor`` of its median
    periods (further out a DataError, unless ``allow_gaps``).
    Commands are held (zero-order hold) from the last message at or before each drive
    time; with ``cmd_vel_timeout_s`` set, a command older than that — or no command yet —
    counts as zero (robots stop when commands stop). With ``cmd_vel_timeout_s=None`` the
    command is held indefinitely and drive samples before the first command are
    dropped. Commands are event-like, so pauses between them are not gaps; the gap check
    applies to the current, IMU and odometry streams. Odometry is interpolated linearly
    (heading unwrapped). The IMU stream keeps the samples bracketing the drive stream.

    Parameters
    ----------
    path : path-like
        ``.bag`` file, ROS 2 bag directory, or the ``.db3`` / ``.mcap`` file inside one.
    topics : BagTopics, optional
        The topics (``cmd_vel_topic``, ``imu_topic``, ``current_topics``, ``battery_topic``),
        the fields of a status message (``current_fields``, ``voltage_field``: the battery
        voltage, V, to ``battery_voltage_v``), the units (``current_unit``; ``accel_unit`` of
        the IMU's ``linear_acceleration``, sensor_msgs/Imu says m/s^2, some drivers publish g:
        an IMU whose vertical acceleration has a median of about 1 read as m/s^2 is refused,
        UnitError, rather than taken for a gravity-free one) and the ``drive_clock`` (see
        Alignment); default ``BagTopics()``.
    timing : BagTiming, optional
        ``use_header_stamps``, ``max_clock_offset_s``, ``cmd_vel_timeout_s`` and
        ``drive_rate_hz`` (see Timestamps and Alignment); default ``BagTiming()``.
    require_currents : bool
        Refuse a bag without the current topics instead of reading a log without currents.
    robot, ground_label : metadata
    cleaning : LogCleaning, optional
        Repairs, gaps and unit checks (:class:`~energy.io.cleaning.LogCleaning`; see :mod:`energy.io`).

    Returns
    -------
    InteractionLog

    Raises
    ------
    OptionalDependencyError
        ``rosbags`` is not installed.
    FileFormatError
        Missing or unreadable bag.
    DataError
        The velocity or IMU topic is missing (a current topic too with
        ``require_currents``; one of two current topics always), a topic has no messages,
        an unexpected type, a multi-array of the wrong length; a named field the message
        does not have or that is not a number (the message names the option and lists the
        fields it has); header stamps more than ``max_clock_offset_s`` away from the
        receive times; streams that do not overlap; plus the checks of the module
        docstring (unsorted or duplicated timestamps, NaNs, gaps; ``repair`` and
        ``allow_gaps`` work as in the CSV readers).
    UnitError, UnknownNameError, InvalidParameterError
        As documented in :mod:`energy.io` (with ``check_units``, also a current or IMU
        topic whose rate lies outside [0.5 Hz, 10 kHz], a battery voltage above 200 V);
        ``topics`` not a BagTopics, ``timing`` not a BagTiming, ``cleaning`` not a LogCleaning.
    """
    import_rosbags()
    topics, timing, cleaning, opts = _checked(topics, timing, require_currents, ground_label, cleaning)
    bag = bag_path(path)
    battery_topic = topics.battery_topic
    optional = (() if opts.require else opts.topics_cur) + ((battery_topic,) if battery_topic is not None else ())
    wanted = (topics.cmd_vel_topic, topics.imu_topic) + (opts.topics_cur if opts.require else ())
    raw, types = read_messages(bag, wanted, optional)
    return log_from_topic_messages(TopicMessages(str(bag), raw, types), topics, timing=timing,
                                   require_currents=require_currents, robot=robot, ground_label=ground_label,
                                   cleaning=cleaning)


def log_from_topic_messages(
    messages: TopicMessages,
    topics: BagTopics | None = None,
    *,
    timing: BagTiming | None = None,
    require_currents: bool = False,
    robot: str = "unknown",
    ground_label: str | None = None,
    cleaning: LogCleaning | None = None,
) -> InteractionLog:
    """The interaction log of messages grouped by topic, as :func:`read_rosbag` builds it from a bag's.

    The seam between reading a bag and building its log: :func:`read_rosbag` reads the
    messages and calls this; :func:`energy.io.ros_messages.log_from_messages` calls it on
    messages received live, so both give the same log for the same messages. Needs no
    ``rosbags``: messages are read by field name (rosbags dataclasses or rclpy messages).

    Parameters
    ----------
    messages : TopicMessages
        The messages by topic with their receive times (ns) and types, the source's name (in
        messages and ``meta.source``) and what held them (``"the bag"``, in the note of
        missing current topics).
    topics, timing, require_currents, robot, ground_label, cleaning
        As :func:`read_rosbag`: a current or battery topic not in the messages is a missing topic.

    Returns
    -------
    InteractionLog

    Raises
    ------
    DataError, UnitError, UnknownNameError, InvalidParameterError
        As :func:`read_rosbag`; also the velocity or IMU topic not in ``raw``.
    """
    if not isinstance(messages, TopicMessages):
        raise InvalidParameterError(f"messages must be a TopicMessages, got {type(messages).__name__!r}",
                                    parameter="messages")
    topics, timing, cleaning, opts = _checked(topics, timing, require_currents, ground_label, cleaning)
    src, raw, types, container = messages.source, messages.raw, messages.types, messages.container
    cmd_vel_topic, imu_topic, battery_topic = topics.cmd_vel_topic, topics.imu_topic, topics.battery_topic
    current_unit, accel_unit = topics.current_unit, topics.accel_unit
    repairs, allow_gaps, gap_factor = cleaning.repairs, cleaning.allow_gaps, cleaning.gap_factor
    check_units = cleaning.check_units
    needed = (cmd_vel_topic, imu_topic) + (opts.topics_cur if opts.require else ())
    absent = [t for t in needed if t not in raw or t not in types]
    if absent:
        raise DataError(f"{src}: topic(s) {absent!r} not in {container}; it has {sorted(raw)!r}")
    vel_type = expect_type(src, raw, types, cmd_vel_topic, _TWIST_TYPES + _ODOM_TYPES)
    expect_type(src, raw, types, imu_topic, _IMU_TYPES)
    present = [t for t in opts.topics_cur if t in raw]
    if present and len(present) != len(opts.topics_cur):
        raise DataError(f"{src}: current topic {present[0]!r} is in the bag but "
                        f"{[t for t in opts.topics_cur if t not in raw]!r} is not (current_topics)")
    missing_currents = "" if present else (
        f"current topic(s) {list(opts.topics_cur)!r} not in {container}, which has {sorted(types)!r}")
    if missing_currents:
        _LOG.info("%s: no currents: %s", src, missing_currents)
    cur_cols = _current_columns(src, raw, types, opts, current_unit) if present else {}
    notes: list[str] = []
    battery = battery_topic is not None and battery_topic in raw
    if battery:
        expect_type(src, raw, types, battery_topic, _BATTERY_TYPES)
    elif battery_topic is not None:
        notes.append(f"no battery: topic {battery_topic!r} not in {container}")
        _LOG.info("%s: no battery: topic %r not in %s", src, battery_topic, container)
    wanted = (cmd_vel_topic, imu_topic, *present, *((battery_topic,) if battery else ()))
    times_ns = {t: topic_times(src, t, raw[t], timing.use_header_stamps, timing.max_clock_offset_s, notes)
                for t in wanted}
    origin = int(min(s.min() for s in times_ns.values()))
    secs = {t: (s - origin).astype(np.float64) / 1e9 for t, s in times_ns.items()}
    clean = dict(repairs=repairs, gap_factor=gap_factor)
    measured = vel_type in _ODOM_TYPES
    vcols = _velocity_columns(vel_type, [m for _, m in raw[cmd_vel_topic]])
    tv, vc, _ = clean_stream(src, cmd_vel_topic, secs[cmd_vel_topic], vcols, allow_gaps=allow_gaps or not measured, **clean)
    imu_msgs = [m for _, m in raw[imu_topic]]
    icols = {"accel_z": np.array([m.linear_acceleration.z for m in imu_msgs], dtype=np.float64)
             * UNIT_FACTORS["accel"][accel_unit]}
    if not all(float(m.angular_velocity_covariance[0]) == -1.0 for m in imu_msgs):
        icols["gyro_z"] = np.array([m.angular_velocity.z for m in imu_msgs], dtype=np.float64)
    else:
        notes.append(f"{imu_topic}: no gyro (angular_velocity_covariance[0] == -1)")
    ti, ic, _ = clean_stream(src, imu_topic, secs[imu_topic], icols, allow_gaps=allow_gaps, **clean)
    currents = _current_streams(src, cur_cols, secs, dict(allow_gaps=allow_gaps, **clean)) if present else None
    if battery:
        tb, bc, _ = clean_stream(src, battery_topic, secs[battery_topic], _battery_columns(battery_topic, raw, notes),
                                 allow_gaps=allow_gaps, **clean)
    if check_units:
        _check_units(src, currents, opts.topics_cur, current_unit, (cmd_vel_topic, vc), (imu_topic, ti, ic))
        if battery:
            _check_battery_units(src, battery_topic, tb, bc)
    gravity = gravity_note(f"{imu_topic} linear_acceleration.z", ic["accel_z"],
                           "give accel_unit='g' for an IMU driver that publishes in g", check_units,
                           parameter="accel_unit")
    if gravity:
        notes.append(gravity)
    log = align_streams(src, currents, (tv, vc, measured), (ti, ic), timing.cmd_vel_timeout_s, opts.drive_rate_hz,
                        notes, opts.on_currents)
    if battery:
        log.update(_battery_on_drive(src, battery_topic, tb, bc, log["time_s"], gap_factor, allow_gaps, notes))
    if missing_currents:
        notes.append(f"no currents: {missing_currents}")
    meta = LogMeta(
        robot=robot,
        source=src,
        ground_label=ground_label,
        velocity_source="measured" if measured else "commanded",
        notes="; ".join(notes),
        start_time_ns=origin,
        gravity_removed=bool(gravity),
        missing_currents=missing_currents,
    )
    return InteractionLog(**log, meta=meta)


def _current_columns(
    src: str, raw: Messages, types: dict[str, str], opts: _Options, unit: str
) -> dict[str, dict[str, np.ndarray]]:
    """Per current topic, its checked columns in A (``left``, ``right``) and V (``voltage``)."""
    scale = UNIT_FACTORS["current"][unit]
    first = opts.topics_cur[0]
    if len(opts.topics_cur) == 2:
        for t in opts.topics_cur:
            expect_type(src, raw, types, t, _SCALAR_TYPES, _FIELDS_HINT, "current_fields")
        return {t: {side: np.array([m.data for _, m in raw[t]], dtype=np.float64) * scale}
                for t, side in zip(opts.topics_cur, ("left", "right"))}
    if opts.current_fields is None:
        expect_type(src, raw, types, first, _ARRAY_TYPES, _FIELDS_HINT, "current_fields")
        arrays = [np.asarray(m.data, dtype=np.float64).reshape(-1) for _, m in raw[first]]
        bad = [i for i, a in enumerate(arrays) if a.size != 2]
        if bad:
            raise DataError(
                f"{src}: topic {first!r}: {len(bad)} message(s) do not hold exactly [left, right], first at "
                f"index {bad[0]} with {arrays[bad[0]].size} value(s)"
            )
        stacked = np.vstack(arrays) * scale
        return {first: {"left": stacked[:, 0], "right": stacked[:, 1]}}
    if not raw[first]:
        raise DataError(f"{src}: topic {first!r} has no messages")
    cols = {
        side: field_values(src, first, types[first], raw[first], name, "current_fields") * scale
        for side, name in zip(("left", "right"), opts.current_fields)
    }
    if opts.voltage_field is not None:
        cols["voltage"] = field_values(src, first, types[first], raw[first], opts.voltage_field,
                                       "voltage_field")
    return {first: cols}


def _current_streams(
    src: str, cur_cols: dict[str, dict[str, np.ndarray]], secs: dict[str, np.ndarray], clean: dict[str, Any]
) -> CurrentStreams:
    """The cleaned left/right current streams (and battery voltage) of the current topic(s)."""
    streams = [clean_stream(src, topic, secs[topic], cols, **clean)[:2] for topic, cols in cur_cols.items()]
    (tc, cc), (tr, cr) = streams[0], streams[-1]
    return CurrentStreams(tc, cc["left"], tr, cr["right"], cc.get("voltage"))


def _check_units(
    src: str, currents: CurrentStreams | None, topics_cur: tuple[str, ...], unit: str,
    velocity: tuple[str, dict[str, np.ndarray]], imu: tuple[str, np.ndarray, dict[str, np.ndarray]],
) -> None:
    vel_topic, vc = velocity
    imu_topic, ti, ic = imu
    if currents is not None:
        check_current(src, f"{topics_cur[0]} (left)", currents.left_a, unit)
        check_current(src, f"{topics_cur[-1]} (right)", currents.right_a, unit)
        check_timing(src, topics_cur[0], currents.time_s)
        if currents.voltage_v is not None:
            check_limit(src, f"{topics_cur[0]} battery voltage", currents.voltage_v, MAX_BATTERY_VOLTAGE_V, "V",
                        "the voltage looks like mV")
    check_limit(src, f"{vel_topic} linear.x", vc["v"], MAX_SPEED_MPS, "m/s", "speeds look like mm/s or cm/s")
    check_limit(src, f"{vel_topic} angular.z", vc["omega"], MAX_OMEGA_RADPS, "rad/s", "yaw rates look like deg/s")
    check_accel(src, f"{imu_topic} linear_acceleration.z", ic["accel_z"])
    if "gyro_z" in ic:
        check_limit(src, f"{imu_topic} angular_velocity.z", ic["gyro_z"], MAX_OMEGA_RADPS, "rad/s",
                    "gyro rates look like deg/s")
    check_timing(src, imu_topic, ti)


def _battery_columns(topic: str, raw: Messages, notes: list[str]) -> dict[str, np.ndarray]:
    """Voltage (V) and pack current (A, positive discharging) of the BatteryState messages."""
    msgs = [m for _, m in raw[topic]]
    cols = {"voltage": np.array([m.voltage for m in msgs], dtype=np.float64)}
    current = -np.array([m.current for m in msgs], dtype=np.float64)  # BatteryState: negative when discharging
    if np.isnan(current).all():
        notes.append(f"{topic}: no pack current (NaN in every message)")
    else:
        cols["current"] = current
    return cols


def _check_battery_units(src: str, topic: str, tb: np.ndarray, bc: dict[str, np.ndarray]) -> None:
    check_limit(src, f"{topic} voltage", bc["voltage"], MAX_BATTERY_VOLTAGE_V, "V", "the voltage looks like mV")
    if "current" in bc:
        check_current(src, f"{topic} current", bc["current"], "A")
    check_timing(src, topic, tb)


def _battery_on_drive(
    src: str, topic: str, tb: np.ndarray, bc: dict[str, np.ndarray], td: np.ndarray, gap_factor: float,
    allow_gaps: bool, notes: list[str],
) -> dict[str, np.ndarray]:
    """The battery voltage and pack current interpolated onto the drive times ``td``.

    Drive samples outside the battery stream take its first or last value, up to ``gap_factor``
    of its median periods away (a DataError further out, unless ``allow_gaps``).
    """
    reach = gap_factor * float(np.median(np.diff(tb))) if tb.size > 1 else 0.0
    before, after = float(tb[0] - td[0]), float(td[-1] - tb[-1])
    if max(before, after) > reach and not allow_gaps:
        raise DataError(
            f"{src}: topic {topic!r} spans [{fmt_number(float(tb[0]), 9)}, {fmt_number(float(tb[-1]), 9)}] s but the "
            f"drive stream [{fmt_number(float(td[0]), 9)}, {fmt_number(float(td[-1]), 9)}] s, more than {gap_factor:g} "
            "of its median periods further; pass allow_gaps=True to hold its first and last values there"
        )
    held = int(np.sum((td < tb[0]) | (td > tb[-1])))
    notes.append(f"{topic}: battery interpolated linearly onto the drive times"
                 + (f" ({held} drive sample(s) outside its span hold its first or last value)" if held else ""))
    out = {"battery_voltage_v": np.interp(td, tb, bc["voltage"])}
    if "current" in bc:
        out["battery_current_a"] = np.interp(td, tb, bc["current"])
    return out


def _velocity_columns(vel_type: str, msgs: list[Any]) -> dict[str, np.ndarray]:
    """v and omega (+ x, y, heading from odometry) of the velocity topic's messages."""
    if vel_type in _ODOM_TYPES:
        tw = [m.twist.twist for m in msgs]
    elif vel_type == "geometry_msgs/msg/TwistStamped":
        tw = [m.twist for m in msgs]
    else:
        tw = msgs
    cols = {
        "v": np.array([x.linear.x for x in tw], dtype=np.float64),
        "omega": np.array([x.angular.z for x in tw], dtype=np.float64),
    }
    if vel_type in _ODOM_TYPES:
        pos = [m.pose.pose for m in msgs]
        q = np.array([[p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z] for p in pos])
        cols["x"] = np.array([p.position.x for p in pos], dtype=np.float64)
        cols["y"] = np.array([p.position.y for p in pos], dtype=np.float64)
        cols["heading"] = np.arctan2(2 * (q[:, 0] * q[:, 3] + q[:, 1] * q[:, 2]), 1 - 2 * (q[:, 2] ** 2 + q[:, 3] ** 2))
    return cols
