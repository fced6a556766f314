"""A recorded drive as a real ROS bag: logs written as a ROS 2 MCAP file or a ROS 1 bag; its GPS fixes read back.

:func:`write_drive_bag` writes one or more :class:`~energy.logs.InteractionLog` (a drive, or the
consecutive legs of one) with the topics of :class:`~energy.io.ros_messages.DriveBagTopics`
(odometry, IMU, drive currents, battery, GPS; the messages of
:func:`~energy.io.ros_messages.messages_from_log`), on one clock (:func:`drive_bag_time_zeros_ns`).
:func:`~energy.io.read_rosbag` reads it back (``DriveBagTopics().bag_topics()`` names the topics)
and :func:`read_navsat` its ``sensor_msgs/NavSatFix`` fixes, on the same clock as the log.

A ``.mcap`` name is a single ROS 2 MCAP file (message definitions of ROS 2 Jazzy), a ``.bag``
name a ROS 1 bag (ROS 1 Noetic definitions). Written atomically (a temporary beside the target,
then one rename; :mod:`terrawatt_base.atomic`) and byte-identical for the same input and file
name (an MCAP's rosbag2 metadata names its file).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.atomic import atomic_path, check_output_path
from terrawatt_base.checks import check_int, check_text, readonly
from terrawatt_base.errors import FileFormatError, InvalidParameterError, OptionalDependencyError

from ..logs import DEFAULT_GAP_FACTOR, InteractionLog, median_period_s
from .bag_messages import bag_path, expect_type, import_rosbags, read_messages, topic_times
from .cleaning import clean_stream, parse_repair
from .ros_messages import DEFAULT_START_TIME_NS, DriveBagTopics, check_lonlat, messages_from_log
from .rosbag import MAX_CLOCK_OFFSET_S

__all__ = [
    "DRIVE_BAG_SUFFIXES",
    "NavSatTrack",
    "drive_bag_time_zeros_ns",
    "write_drive_bag",
    "read_navsat",
]

#: What :func:`write_drive_bag` writes, by the target's suffix.
DRIVE_BAG_SUFFIXES = {".mcap": "ROS 2 MCAP file", ".bag": "ROS 1 bag"}
_NS = 1_000_000_000
_NAVSAT_TYPES = ("sensor_msgs/msg/NavSatFix",)


@dataclass(frozen=True, eq=False)
class NavSatTrack:
    """The fixes of a ``sensor_msgs/NavSatFix`` topic, read by :func:`read_navsat`.

    Attributes
    ----------
    time_s : ndarray, shape (K,)
        Fix times (s) since ``start_time_ns``: with the ``start_time_ns`` of a log read from the
        same bag, on that log's clock.
    lon_deg, lat_deg : ndarray, shape (K,)
        Longitude and latitude (degrees, WGS 84); NaN where the receiver had none.
    alt_m : ndarray, shape (K,)
        Altitude above the WGS 84 ellipsoid (m); NaN when not known.
    status : ndarray of int8, shape (K,)
        ``NavSatStatus.status`` (-2 unknown, -1 no fix, 0 fix, 1 SBAS, 2 GBAS).
    start_time_ns : int
        Absolute time (ns since the epoch) of ``time_s == 0``.
    topic : str
        The topic read.
    source : str
        The bag read.
    """

    time_s: np.ndarray
    lon_deg: np.ndarray
    lat_deg: np.ndarray
    alt_m: np.ndarray
    status: np.ndarray
    start_time_ns: int
    topic: str
    source: str

    def __len__(self) -> int:
        return int(self.time_s.size)

    @property
    def has_fix(self) -> np.ndarray:
        """Whether each message is a fix (``status >= 0``)."""
        return self.status >= 0

    @property
    def lonlat_deg(self) -> np.ndarray:
        """Longitude and latitude (degrees) as an ``(K, 2)`` array, the layout :func:`write_drive_bag` takes."""
        return np.column_stack([self.lon_deg, self.lat_deg])


def _check_logs(logs: Any) -> list[InteractionLog]:
    """``logs`` as a non-empty list of InteractionLogs of 2 drive samples or more."""
    items = [logs] if isinstance(logs, InteractionLog) else list(logs) if isinstance(logs, Iterable) else None
    if not items:
        raise InvalidParameterError(f"logs must be an InteractionLog or a non-empty sequence of them, got {logs!r:.80}")
    for i, log in enumerate(items):
        if not isinstance(log, InteractionLog):
            raise InvalidParameterError(f"logs[{i}] must be an InteractionLog, got {type(log).__name__!r}")
        if len(log) < 2:
            raise InvalidParameterError(f"logs[{i}] has {len(log)} drive sample; a drive bag needs 2 or more (its "
                                        "drive period places the next leg)")
    return items


def drive_bag_time_zeros_ns(logs: InteractionLog | Iterable[InteractionLog],
                            start_time_ns: int | None = None) -> np.ndarray:
    """The bag time (ns since the epoch) of each log's ``time_s == 0``: the legs one after another on one clock.

    The first log's ``time_s == 0`` is at ``start_time_ns``. Each later log starts (its first
    drive or IMU sample, whichever is earlier) one drive period (the median step of the earlier
    log's drive stream) after the earlier log ends (its last drive or IMU sample). A sample at
    ``t`` seconds of log ``k`` is stamped ``zeros[k] + round(t * 1e9)`` ns.

    Parameters
    ----------
    logs : InteractionLog or sequence of InteractionLog
        Each with 2 drive samples or more.
    start_time_ns : int, optional
        By default the first log's ``meta.start_time_ns`` (a log read from a bag keeps its
        time), else :data:`~energy.io.ros_messages.DEFAULT_START_TIME_NS`.

    Returns
    -------
    ndarray of int64, shape (len(logs),)

    Raises
    ------
    InvalidParameterError
        No log, a log of fewer than 2 drive samples, ``start_time_ns`` not an integer.

    Examples
    --------
    >>> import numpy as np
    >>> from energy import InteractionLog
    >>> t = np.arange(5) * 0.1
    >>> leg = InteractionLog(t, np.ones(5), np.zeros(5), np.ones(5), np.ones(5), t, np.full(5, 9.81))
    >>> drive_bag_time_zeros_ns([leg, leg], start_time_ns=10**18).tolist()
    [1000000000000000000, 1000000000500000000]
    """
    items = _check_logs(logs)
    if start_time_ns is None:
        own = items[0].meta.start_time_ns
        start_time_ns = own if own is not None else DEFAULT_START_TIME_NS
    zeros = [check_int("start_time_ns", start_time_ns)]
    for prev, log in zip(items, items[1:]):
        end_ns = zeros[-1] + int(np.rint(max(prev.time_s[-1], prev.accel_time_s[-1]) * _NS))
        period_ns = int(np.rint(median_period_s(prev.time_s) * _NS))
        first_ns = int(np.rint(min(log.time_s[0], log.accel_time_s[0]) * _NS))
        zeros.append(end_ns + period_ns - first_ns)
    return np.array(zeros, dtype=np.int64)


def _rosbags(ros1: bool) -> tuple[Any, Any, Any]:
    """``(writer class, writer keywords, typestore)`` of rosbags for a ROS 1 bag or a ROS 2 MCAP."""
    try:
        from rosbags.typesys import Stores, get_typestore
        if ros1:
            from rosbags.rosbag1 import Writer
            return Writer, {}, get_typestore(Stores.ROS1_NOETIC)
        from rosbags.rosbag2 import StoragePlugin, Writer
    except ImportError as exc:
        raise OptionalDependencyError(
            "write_drive_bag needs the optional dependency 'rosbags': pip install 'terrawatt[ros]'"
        ) from exc
    return Writer, {"version": 9, "storage_plugin": StoragePlugin.MCAP}, get_typestore(Stores.ROS2_JAZZY)


def _write_messages(bag: Path, messages: list[tuple[int, str, str, Any]], writer_cls: Any, options: dict[str, Any],
                    ts: Any, ros1: bool) -> None:
    """Write the messages (in the given order) into a new bag at ``bag`` (a ROS 1 file or a ROS 2 bag directory)."""
    serialize = ts.serialize_ros1 if ros1 else ts.serialize_cdr
    with writer_cls(bag, **options) as writer:
        conns: dict[str, Any] = {}
        for ns, topic, msgtype, msg in messages:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=ts)
            writer.write(conns[topic], ns, serialize(msg, msgtype))


def _is_table(value: Any) -> bool:
    """Whether ``value`` reads as one 2-D array (not a list of them)."""
    try:
        return np.ndim(value) == 2
    except ValueError:  # ragged
        return False


def _lonlat_per_log(lonlat_deg: Any, logs: list[InteractionLog], single: bool) -> list[np.ndarray | None]:
    if lonlat_deg is None:
        return [None] * len(logs)
    if single and _is_table(lonlat_deg):
        return [check_lonlat("lonlat_deg", lonlat_deg, len(logs[0]))]
    items = list(lonlat_deg) if isinstance(lonlat_deg, Iterable) and not isinstance(lonlat_deg, str) else None
    if items is None or len(items) != len(logs):
        raise InvalidParameterError(
            f"lonlat_deg must hold one (N, 2) array of lon, lat (degrees) per log ({len(logs)}), got "
            f"{'a ' + type(lonlat_deg).__name__ if items is None else f'{len(items)} item(s)'}"
        )
    return [check_lonlat(f"lonlat_deg[{i}]", ll, len(log)) for i, (ll, log) in enumerate(zip(items, logs))]


def write_drive_bag(
    logs: InteractionLog | Iterable[InteractionLog],
    path: str | os.PathLike[str],
    *,
    lonlat_deg: Any = None,
    topics: DriveBagTopics = DriveBagTopics(),
    start_time_ns: int | None = None,
) -> Path:
    """Write a drive (one log, or the consecutive legs of one) as a ROS 2 MCAP file or a ROS 1 bag, atomically.

    The logs are put one after another on one clock (:func:`drive_bag_time_zeros_ns`): the
    first log's ``time_s == 0`` at ``start_time_ns``, each later log starting one drive period
    (of the earlier log) after the earlier one ends, whatever its own ``time_s`` starts at.
    Topics (:class:`~energy.io.ros_messages.DriveBagTopics`; the messages of
    :func:`~energy.io.ros_messages.messages_from_log`): ``nav_msgs/Odometry`` (pose from
    ``pose_xyh``, twist ``linear.x = v_mps``, ``angular.z = omega_radps``; frames ``map`` /
    ``base_link``) and ``std_msgs/Float64`` left / right currents (A, when the log has them) at
    the drive times, ``sensor_msgs/Imu`` at the IMU's own times, ``sensor_msgs/BatteryState``
    (voltage and pack current, when the log has them) and ``sensor_msgs/NavSatFix`` (with
    ``lonlat_deg``) at the drive times. Receive times equal the header stamps. The same input
    gives the same bytes (for the same file name: an MCAP's rosbag2 metadata names its file).

    Read it back with ``read_rosbag(path, t.bag_topics())`` (or ``read_logs(path, bag=t.bag_topics())``): the same
    streams (times to the nanosecond, the battery to float32 precision), the drive stream
    inside the IMU's span; several legs read as one log whose IMU has a gap between legs
    (``allow_gaps=True``, then :meth:`~energy.logs.InteractionLog.split_at_gaps`). The GPS
    fixes: :func:`read_navsat`.

    Parameters
    ----------
    logs : InteractionLog or sequence of InteractionLog
        Each with ``pose_xyh`` and 2 drive samples or more.
    path : path-like
        A ``.mcap`` file (ROS 2, MCAP storage) or a ``.bag`` file (ROS 1); an existing file is replaced.
    lonlat_deg : array_like or sequence of array_like, optional
        Per log, an ``(N, 2)`` array of longitude, latitude (degrees) at its drive timestamps
        (the caller projects the map poses through the map's CRS); one array for a single log.
    topics : DriveBagTopics
        Topic names and frames.
    start_time_ns : int, optional
        Bag time (ns since the epoch) of the first log's ``time_s == 0``; by default its
        ``meta.start_time_ns``, else :data:`~energy.io.ros_messages.DEFAULT_START_TIME_NS`.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    InvalidParameterError
        ``path`` a directory (checked first, before any work), not ``.mcap`` or ``.bag``; a log
        without ``pose_xyh`` or with fewer than 2 drive samples (the message names its index);
        ``lonlat_deg`` not one ``(N, 2)`` array of valid degrees per log; a stamp at or before
        the epoch or past :data:`~energy.io.ros_messages.MAX_STAMP_NS`.
    OptionalDependencyError
        rosbags (the ``ros`` extra) is not installed.

    Examples
    --------
    Usage (needs rosbags, so not run as a doctest)::

        write_drive_bag([leg1, leg2], "drive.mcap", lonlat_deg=[ll1, ll2])
        log = read_rosbag("drive.mcap", BagTopics("/odom", battery_topic="/battery"),
                          cleaning=LogCleaning(allow_gaps=True))
    """
    target = check_output_path(path)
    suffix = target.suffix.lower()
    if suffix not in DRIVE_BAG_SUFFIXES:
        raise InvalidParameterError(f"path {str(target)!r}: a drive bag is a '.mcap' file (ROS 2) or a '.bag' file "
                                    f"(ROS 1), got suffix {target.suffix!r}")
    if not isinstance(topics, DriveBagTopics):
        raise InvalidParameterError(f"topics must be a DriveBagTopics, got {type(topics).__name__!r}")
    items = _check_logs(logs)
    for i, log in enumerate(items):
        if log.pose_xyh is None:
            raise InvalidParameterError(f"logs[{i}] has no pose_xyh: a drive bag's odometry needs the pose "
                                        "(x_m, y_m, heading_rad)")
    lonlats = _lonlat_per_log(lonlat_deg, items, isinstance(logs, InteractionLog))
    zeros = drive_bag_time_zeros_ns(items, start_time_ns)
    ros1 = suffix == ".bag"
    writer_cls, options, ts = _rosbags(ros1)
    messages: list[tuple[int, str, str, Any]] = []
    for i, (log, zero, lonlat) in enumerate(zip(items, zeros.tolist(), lonlats, strict=True)):
        try:
            messages += messages_from_log(log, ts, time_zero_ns=zero, lonlat_deg=lonlat, topics=topics)
        except InvalidParameterError as exc:
            raise InvalidParameterError(f"logs[{i}]: {exc}") from None
    with atomic_path(target) as tmp:
        work = tmp.with_name(tmp.name[: -len(".tmp")] + "_bag.tmp")  # a temporary of the same target
        try:
            work.mkdir()
            name = target.stem or "drive"
            _write_messages(work / (name + ".bag" if ros1 else name), messages, writer_cls, options, ts, ros1)
            os.replace(work / f"{name}.bag" if ros1 else work / name / f"{name}.mcap", tmp)
        finally:
            shutil.rmtree(work, ignore_errors=True)
    return target


def _bag_start_ns(bag: Path) -> int:
    """The earliest receive time of the bag (ns)."""
    any_reader, stores, get_typestore = import_rosbags()
    try:
        with any_reader([bag], default_typestore=get_typestore(stores.LATEST)) as reader:
            return int(reader.start_time)
    except Exception as exc:  # rosbags raises its own error classes per format
        raise FileFormatError(f"cannot read bag {str(bag)!r}: {type(exc).__name__}: {exc}") from exc


def read_navsat(
    path: str | os.PathLike[str],
    topic: str = "/gps/fix",
    *,
    start_time_ns: int | None = None,
    use_header_stamps: bool = True,
    max_clock_offset_s: float = MAX_CLOCK_OFFSET_S,
    repair: str | Iterable[str] = (),
) -> NavSatTrack:
    """The GPS fixes of a bag's ``sensor_msgs/NavSatFix`` topic, on a log's clock.

    Times are the header stamps (the receive times with ``use_header_stamps=False``, or when a
    stamp is zero), as :func:`~energy.io.read_rosbag` takes them, in seconds since
    ``start_time_ns``. Give the ``meta.start_time_ns`` of the log read from the same bag to put
    the fixes on that log's clock (``read_rosbag`` counts from the earliest time of the topics it
    reads). By default the bag's earliest message: the same origin for a bag written by
    :func:`write_drive_bag`, whose first message is an odometry or IMU one. Messages without a
    fix are kept (``status`` -1, their coordinates often NaN): :attr:`NavSatTrack.has_fix`.

    Parameters
    ----------
    path : path-like
        A bag (``.bag``, ``.mcap``, ``.db3`` or a ROS 2 bag folder).
    topic : str
    start_time_ns : int, optional
        Absolute time (ns) of ``time_s == 0``.
    use_header_stamps, max_clock_offset_s : as :func:`~energy.io.read_rosbag`
    repair : str or sequence of str
        ``"sort"`` and ``"drop_duplicates"`` of :data:`~energy.io.REPAIRS` (NaN coordinates are
        kept, never interpolated).

    Returns
    -------
    NavSatTrack

    Raises
    ------
    OptionalDependencyError
        rosbags is not installed.
    FileFormatError
        A missing or unreadable bag.
    DataError
        The topic is not in the bag, has no messages or another type; header stamps far from the
        receive times; unsorted or duplicated times (unless repaired).
    InvalidParameterError, UnknownNameError
        Bad ``topic``, ``start_time_ns``, ``max_clock_offset_s`` or ``repair`` (``"interpolate_nans"``
        does not apply).
    """
    import_rosbags()
    check_text("topic", topic)
    repairs = parse_repair(repair)
    if "interpolate_nans" in repairs:
        raise InvalidParameterError("repair 'interpolate_nans' does not apply to GPS fixes: messages without a fix "
                                    "keep their NaN coordinates (NavSatTrack.has_fix)")
    if start_time_ns is not None:
        start_time_ns = check_int("start_time_ns", start_time_ns)
    bag = bag_path(path)
    src = str(bag)
    raw, types = read_messages(bag, (topic,))
    expect_type(src, raw, types, topic, _NAVSAT_TYPES)
    notes: list[str] = []
    times_ns = topic_times(src, topic, raw[topic], use_header_stamps, max_clock_offset_s, notes)
    origin = _bag_start_ns(bag) if start_time_ns is None else start_time_ns
    msgs = [m for _, m in raw[topic]]
    extra = {
        "lon": np.array([m.longitude for m in msgs], dtype=np.float64),
        "lat": np.array([m.latitude for m in msgs], dtype=np.float64),
        "alt": np.array([m.altitude for m in msgs], dtype=np.float64),
        "status": np.array([m.status.status for m in msgs], dtype=np.int8),
    }
    secs = (times_ns - origin).astype(np.float64) / 1e9
    t, _, cols = clean_stream(src, topic, secs, {}, repairs=repairs, allow_gaps=True, gap_factor=DEFAULT_GAP_FACTOR,
                              extra=extra)
    return NavSatTrack(
        time_s=readonly(t), lon_deg=readonly(cols["lon"]), lat_deg=readonly(cols["lat"]),
        alt_m=readonly(cols["alt"]), status=readonly(cols["status"]), start_time_ns=int(origin), topic=topic,
        source=src,
    )
