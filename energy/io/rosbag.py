"""ROS 1 bags, ROS 2 bags (sqlite3 or MCAP) into interaction logs, in named steps.

:func:`read_rosbag` reads the messages of the wanted topics (:func:`_read_messages`), puts
each topic on one clock (:func:`_topic_times`), builds the velocity, IMU and current
streams, checks and cleans them like every reader (:mod:`energy.io.cleaning`) and aligns them
on their overlap (:func:`_align`).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from terrain.checks import check_choice, check_optional_real, check_real, check_text, fmt_number
from terrain.errors import DataError, FileFormatError, InvalidParameterError, OptionalDependencyError

from ..logs import DEFAULT_GAP_FACTOR, InteractionLog, LogMeta, check_gap_factor
from .cleaning import (
    MAX_OMEGA_RADPS,
    MAX_SPEED_MPS,
    UNIT_FACTORS,
    bracket_accel,
    check_accel,
    check_current,
    check_limit,
    check_timing,
    clean_stream,
    parse_repair,
)

__all__ = ["MAX_CLOCK_OFFSET_S", "read_rosbag"]

#: Default largest median (receive time - header stamp) a bag topic may show before
#: ``read_rosbag`` refuses to mix its header stamps with receive times (s).
MAX_CLOCK_OFFSET_S = 0.5

_TWIST_TYPES = ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped")
_ODOM_TYPES = ("nav_msgs/msg/Odometry",)
_IMU_TYPES = ("sensor_msgs/msg/Imu",)
_SCALAR_TYPES = ("std_msgs/msg/Float64", "std_msgs/msg/Float32")
_ARRAY_TYPES = ("std_msgs/msg/Float64MultiArray", "std_msgs/msg/Float32MultiArray")

Messages = dict[str, list[tuple[int, Any]]]


def read_rosbag(
    path: str | os.PathLike[str],
    cmd_vel_topic: str = "/cmd_vel",
    imu_topic: str = "/imu/data",
    current_topics: str | Sequence[str] = ("/drive/current_left", "/drive/current_right"),
    *,
    current_unit: str = "A",
    robot: str = "unknown",
    ground_label: str | None = None,
    use_header_stamps: bool = True,
    max_clock_offset_s: float = MAX_CLOCK_OFFSET_S,
    cmd_vel_timeout_s: float | None = 0.5,
    repair: str | Iterable[str] = (),
    allow_gaps: bool = False,
    gap_factor: float = DEFAULT_GAP_FACTOR,
    check_units: bool = True,
) -> InteractionLog:
    """Read an interaction log from a ROS 1 ``.bag``, a ROS 2 bag (sqlite3 ``.db3`` or MCAP).

    Needs the ``ros`` extra (``pip install 'terrawatt[ros]'``, i.e. ``rosbags``).

    Topics and message types (conventions of this reader):

    - ``cmd_vel_topic``: ``geometry_msgs/msg/Twist`` or ``TwistStamped`` (commanded;
      ``linear.x`` m/s, ``angular.z`` rad/s), or ``nav_msgs/msg/Odometry`` (measured
      ``twist.twist``; its pose becomes ``pose_xyh`` with the yaw of the orientation).
    - ``imu_topic``: ``sensor_msgs/msg/Imu``; ``linear_acceleration.z`` (gravity included).
    - per-side drive current, in ``current_unit`` (``"A"`` or ``"mA"``): either two topics
      ``(left, right)`` of ``std_msgs/msg/Float64`` or ``Float32`` (``data``), or one topic
      of ``std_msgs/msg/Float64MultiArray`` / ``Float32MultiArray`` whose ``data`` is
      exactly ``[left, right]``.

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
    overlap of the current and IMU streams (and of the odometry stream, if used).
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
    cmd_vel_topic, imu_topic, current_topics : str
        Topic names (see above).
    current_unit : {"A", "mA"}
    robot, ground_label : metadata
    use_header_stamps : bool
    max_clock_offset_s : float
        Largest tolerated |median(receive time - header stamp)| of a topic read on header
        stamps (s, finite, > 0).
    cmd_vel_timeout_s : float or None
    repair, allow_gaps, gap_factor, check_units
        See :mod:`energy.io`.

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
        A topic is missing or has no messages, has an unexpected type, a multi-array of
        the wrong length; header stamps more than ``max_clock_offset_s`` away from the
        receive times; streams that do not overlap; plus the checks of the module
        docstring (unsorted or duplicated timestamps, NaNs, gaps; ``repair`` and
        ``allow_gaps`` work as in the CSV readers).
    UnitError, UnknownNameError, InvalidParameterError
        As documented in :mod:`energy.io` (with ``check_units``, also a current or IMU
        topic whose rate lies outside [1 Hz, 10 kHz]); unknown ``current_unit``; bad
        timeout or ``max_clock_offset_s``.
    """
    topics_cur = _check_arguments(current_unit, cmd_vel_timeout_s, max_clock_offset_s, ground_label, current_topics)
    repairs = parse_repair(repair)
    gap_factor = check_gap_factor(gap_factor)
    bag = _bag_path(path)
    src = str(bag)
    wanted = (cmd_vel_topic, imu_topic, *topics_cur)
    raw, types = _read_messages(bag, wanted)
    vel_type = _expect(src, raw, types, cmd_vel_topic, _TWIST_TYPES + _ODOM_TYPES)
    _expect(src, raw, types, imu_topic, _IMU_TYPES)
    arrays = _current_arrays(src, raw, types, topics_cur)
    notes: list[str] = []
    times_ns = {t: _topic_times(src, t, raw[t], use_header_stamps, max_clock_offset_s, notes) for t in wanted}
    origin = int(min(s.min() for s in times_ns.values()))
    secs = {t: (s - origin).astype(np.float64) / 1e9 for t, s in times_ns.items()}
    clean = dict(repairs=repairs, gap_factor=gap_factor)
    measured = vel_type in _ODOM_TYPES
    vcols = _velocity_columns(vel_type, [m for _, m in raw[cmd_vel_topic]])
    tv, vc, _ = clean_stream(src, cmd_vel_topic, secs[cmd_vel_topic], vcols, allow_gaps=allow_gaps or not measured, **clean)
    az = np.array([m.linear_acceleration.z for _, m in raw[imu_topic]], dtype=np.float64)
    ti, ic, _ = clean_stream(src, imu_topic, secs[imu_topic], {"accel_z": az}, allow_gaps=allow_gaps, **clean)
    scale = UNIT_FACTORS["current"][current_unit]
    if arrays is not None:
        stacked = np.vstack(arrays) * scale
        tc, cc, _ = clean_stream(src, topics_cur[0], secs[topics_cur[0]], {"left": stacked[:, 0], "right": stacked[:, 1]},
                                 allow_gaps=allow_gaps, **clean)
        cur_l, cur_r, t_right = cc["left"], cc["right"], tc
    else:
        left, right = (np.array([m.data for _, m in raw[t]], dtype=np.float64) * scale for t in topics_cur)
        tc, cl, _ = clean_stream(src, topics_cur[0], secs[topics_cur[0]], {"left": left}, allow_gaps=allow_gaps, **clean)
        t_right, cr, _ = clean_stream(src, topics_cur[1], secs[topics_cur[1]], {"right": right}, allow_gaps=allow_gaps,
                                      **clean)
        cur_l, cur_r = cl["left"], cr["right"]
    if check_units:
        check_current(src, f"{topics_cur[0]} (left)", cur_l, current_unit)
        check_current(src, f"{topics_cur[-1]} (right)", cur_r, current_unit)
        check_limit(src, f"{cmd_vel_topic} linear.x", vc["v"], MAX_SPEED_MPS, "m/s", "speeds look like mm/s or cm/s")
        check_limit(src, f"{cmd_vel_topic} angular.z", vc["omega"], MAX_OMEGA_RADPS, "rad/s", "yaw rates look like deg/s")
        check_accel(src, f"{imu_topic} linear_acceleration.z", ic["accel_z"])
        check_timing(src, topics_cur[0], tc)
        check_timing(src, imu_topic, ti)
    log = _align(
        src, (tc, cur_l), (t_right, cur_r, len(topics_cur) == 2), (tv, vc, measured), (ti, ic["accel_z"]),
        cmd_vel_timeout_s, notes,
    )
    meta = LogMeta(
        robot=robot,
        source=src,
        ground_label=ground_label,
        velocity_source="measured" if measured else "commanded",
        notes="; ".join(notes),
        start_time_ns=origin,
    )
    return InteractionLog(**log, meta=meta)


def _import_rosbags() -> tuple[Any, Any, Any]:
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError as exc:
        raise OptionalDependencyError(
            "read_rosbag needs the optional dependency 'rosbags': pip install 'terrawatt[ros]'"
        ) from exc
    return AnyReader, Stores, get_typestore


def _check_arguments(
    current_unit: Any, cmd_vel_timeout_s: Any, max_clock_offset_s: Any, ground_label: Any, current_topics: Any
) -> tuple[str, ...]:
    """Check the options (after the optional dependency); return the current topics as a tuple."""
    _import_rosbags()
    check_choice("current_unit", current_unit, tuple(UNIT_FACTORS["current"]))
    check_optional_real("cmd_vel_timeout_s", cmd_vel_timeout_s, low=0.0, low_inclusive=False)
    check_real("max_clock_offset_s", max_clock_offset_s, low=0.0, low_inclusive=False)
    if ground_label is not None:
        check_text("ground_label", ground_label)
    topics_cur = (current_topics,) if isinstance(current_topics, str) else tuple(current_topics)
    if len(topics_cur) not in (1, 2) or not all(isinstance(x, str) for x in topics_cur):
        raise InvalidParameterError(
            f"current_topics must be one topic name (a [left, right] multi-array) or two (left, right), got {current_topics!r}"
        )
    return topics_cur


def _bag_path(path: str | os.PathLike[str]) -> Path:
    bag = Path(path)
    if bag.is_file() and bag.suffix in (".db3", ".mcap") and (bag.parent / "metadata.yaml").exists():
        bag = bag.parent
    if not bag.exists():
        raise FileFormatError(f"bag {str(bag)!r} does not exist")
    return bag


def _read_messages(bag: Path, wanted: tuple[str, ...]) -> tuple[Messages, dict[str, str]]:
    """Deserialised messages (receive time in ns, message) and the type of each wanted topic."""
    any_reader, stores, get_typestore = _import_rosbags()
    raw: Messages = {t: [] for t in wanted}
    try:
        with any_reader([bag], default_typestore=get_typestore(stores.LATEST)) as reader:
            available = {c.topic: c.msgtype for c in reader.connections}
            missing = [t for t in wanted if t not in available]
            if missing:
                raise DataError(f"{bag}: topic(s) {missing!r} not in the bag; it has {available!r}")
            conns = [c for c in reader.connections if c.topic in raw]
            for conn, ts_ns, data in reader.messages(connections=conns):
                raw[conn.topic].append((ts_ns, reader.deserialize(data, conn.msgtype)))
    except (DataError, OptionalDependencyError):
        raise
    except Exception as exc:  # rosbags raises its own error classes per format
        raise FileFormatError(f"cannot read bag {str(bag)!r}: {type(exc).__name__}: {exc}") from exc
    return raw, {t: available[t] for t in wanted}


def _expect(src: str, raw: Messages, types: dict[str, str], topic: str, allowed: tuple[str, ...]) -> str:
    if types[topic] not in allowed:
        raise DataError(f"{src}: topic {topic!r} has type {types[topic]!r}; expected one of {allowed!r}")
    if not raw[topic]:
        raise DataError(f"{src}: topic {topic!r} has no messages")
    return types[topic]


def _current_arrays(src: str, raw: Messages, types: dict[str, str], topics_cur: tuple[str, ...]) -> list[np.ndarray] | None:
    """The [left, right] arrays of a multi-array current topic; None with two scalar topics."""
    if len(topics_cur) == 2:
        for t in topics_cur:
            _expect(src, raw, types, t, _SCALAR_TYPES)
        return None
    _expect(src, raw, types, topics_cur[0], _ARRAY_TYPES)
    arrays = [np.asarray(m.data, dtype=np.float64).reshape(-1) for _, m in raw[topics_cur[0]]]
    bad = [i for i, a in enumerate(arrays) if a.size != 2]
    if bad:
        raise DataError(
            f"{src}: topic {topics_cur[0]!r}: {len(bad)} message(s) do not hold exactly [left, right], first at "
            f"index {bad[0]} with {arrays[bad[0]].size} value(s)"
        )
    return arrays


def _stamp_ns(msg: Any) -> int:
    stamp = msg.header.stamp
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _topic_times(
    src: str, topic: str, msgs: list[tuple[int, Any]], use_header_stamps: bool, max_clock_offset_s: float,
    notes: list[str],
) -> np.ndarray:
    """One topic's times (ns): header stamps when asked, all non-zero and near the receive
    times; else the receive times. Appends which to ``notes``."""
    received = np.array([ts for ts, _ in msgs], dtype=np.int64)
    if not (use_header_stamps and hasattr(msgs[0][1], "header")):
        notes.append(f"{topic}: receive time")
        return received
    hdr = np.array([_stamp_ns(m) for _, m in msgs], dtype=np.int64)
    if not (hdr != 0).all():
        notes.append(f"{topic}: receive time ({int((hdr == 0).sum())} zero header stamp(s))")
        return received
    offset_s = float(np.median((received - hdr).astype(np.float64))) / 1e9
    if abs(offset_s) > max_clock_offset_s:
        raise DataError(
            f"{src}: topic {topic!r}: median (receive time - header stamp) is {fmt_number(offset_s, 6)} s, "
            f"expected within +/-{fmt_number(max_clock_offset_s)} s (max_clock_offset_s): the publisher's "
            f"and the recorder's clocks disagree, and the receive-time current topics would be "
            f"shifted against this topic; pass use_header_stamps=False to put every topic on the "
            f"receive time"
        )
    notes.append(f"{topic}: header stamps (median receive time - stamp {offset_s:.3g} s)")
    return hdr


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


def _align(
    src: str,
    left: tuple[np.ndarray, np.ndarray],
    right: tuple[np.ndarray, np.ndarray, bool],
    velocity: tuple[np.ndarray, dict[str, np.ndarray], bool],
    imu: tuple[np.ndarray, np.ndarray],
    cmd_vel_timeout_s: float | None,
    notes: list[str],
) -> dict[str, Any]:
    """The streams on the drive times: the left current's times inside the overlap.

    Returns the keyword arguments of :class:`InteractionLog` but its ``meta``.
    """
    tc, cur_l = left
    t_right, cur_r, two_topics = right
    tv, vc, measured = velocity
    ti, az = imu
    spans = [(tc[0], tc[-1]), (t_right[0], t_right[-1]), (ti[0], ti[-1])]
    if measured:
        spans.append((tv[0], tv[-1]))
    t0 = max(s[0] for s in spans)
    t1 = min(s[1] for s in spans)
    if not measured and cmd_vel_timeout_s is None:
        t0 = max(t0, tv[0])
    keep = (tc >= t0) & (tc <= t1)
    if t1 < t0 or not keep.any():
        def span(a: float, b: float) -> str:
            return f"[{fmt_number(float(a), 9)}, {fmt_number(float(b), 9)}] s"

        raise DataError(
            f"{src}: the streams do not overlap (current {span(*spans[0])}, IMU {span(*spans[2])}, "
            f"velocity {span(tv[0], tv[-1])})"
        )
    td = tc[keep]
    cur_r = np.interp(td, t_right, cur_r) if two_topics else cur_r[keep]
    pose = None
    if measured:
        v = np.interp(td, tv, vc["v"])
        omega = np.interp(td, tv, vc["omega"])
        h = np.interp(td, tv, np.unwrap(vc["heading"]))
        pose = np.column_stack([np.interp(td, tv, vc["x"]), np.interp(td, tv, vc["y"]), np.pi - np.mod(np.pi - h, 2 * np.pi)])
    else:
        idx = np.searchsorted(tv, td, side="right") - 1
        valid = idx >= 0
        if cmd_vel_timeout_s is not None:
            valid &= (td - tv[np.maximum(idx, 0)]) <= cmd_vel_timeout_s
        v = np.where(valid, vc["v"][np.maximum(idx, 0)], 0.0)
        omega = np.where(valid, vc["omega"][np.maximum(idx, 0)], 0.0)
        notes.append(
            "commands held from the last message" + (
                f", zero after {cmd_vel_timeout_s:g} s without one ({int((~valid).sum())} drive sample(s))"
                if cmd_vel_timeout_s is not None else ""
            )
        )
    acc = bracket_accel(td, ti)
    notes.append(
        f"aligned on the overlap [{t0:g}, {t1:g}] s: dropped {int((~keep).sum())} drive sample(s) outside it and "
        f"{ti.size - (acc.stop - acc.start)} IMU sample(s) outside the kept drive span (bracketing samples kept)"
    )
    return dict(
        time_s=td, v_mps=v, omega_radps=omega, current_left_a=cur_l[keep], current_right_a=cur_r,
        accel_time_s=ti[acc], accel_z_mps2=az[acc], pose_xyh=pose,
    )
