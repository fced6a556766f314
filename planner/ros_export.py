"""ROS 2 out: a planned route as a ``nav_msgs/msg/Path`` with its energy and the map's CRS, in an MCAP bag.

:func:`write_route_bag` writes one message on each of four topics (``topic_prefix``
``/terrawatt`` by default), all logged at ``stamp_ns``:

- ``<prefix>/route`` — ``nav_msgs/msg/Path`` in ``frame_id`` (``map``): one
  ``geometry_msgs/msg/PoseStamped`` per waypoint, x and y the waypoint in the map frame
  (map metres minus ``frame_origin_xy_m``), z the DEM's elevation there (bilinear, m), the
  orientation the yaw of the segment leaving the waypoint (the last one keeps the yaw of
  the segment arriving); each pose stamped ``stamp_ns`` plus the planned time at which the
  robot leaves that waypoint (when the :class:`~planner.EnergyCost` is given).
- ``<prefix>/route_energy`` — ``std_msgs/msg/Float64MultiArray``: the cumulative energy (J)
  per pose, segments and turns spent on leaving it (as in the GeoJSON files); the last
  equals the route's ``energy_j``.
- ``<prefix>/map_crs`` — ``std_msgs/msg/String``: JSON with the map's CRS (string, WKT, EPSG
  code), the map frame's origin in CRS coordinates, the frame and the map's bounds.
- ``<prefix>/route_summary`` — ``std_msgs/msg/String``: JSON of :meth:`planner.Route.summary`.

The bag is a single ``.mcap`` file, or a ROS 2 bag directory (``metadata.yaml`` and one MCAP
file) for any other name; message definitions are those of ROS 2 Jazzy (the same for these
types in every distribution) and the bag metadata is version 9, which ``ros2 bag`` reads
from Jazzy on (Humble: ``ros2 bag reindex`` the directory first). Written atomically,
byte-identical for the same inputs. :func:`read_route_bag` reads it back.

The pieces are public for the other bags of the package (:mod:`planner.replay_bag`): the rosbags
seam (:func:`rosbags_api`), a header and a waypoint Path (:func:`header_message`,
:func:`path_message`, read back by :func:`path_poses`), the checks of a prefix and a frame origin,
the atomic writer of a ``.mcap`` file or bag directory (:func:`write_bag_messages`) and the reader
of a prefix's topics (:func:`read_bag_topics`).
"""

from __future__ import annotations

import json
import math
import os
import shutil
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrain.georef import parse_crs
from terrawatt_base.atomic import atomic_directory, atomic_path, check_output_path
from terrawatt_base.checks import check_int, check_real, check_text, readonly
from terrawatt_base.errors import FileFormatError, InvalidParameterError, OptionalDependencyError

from .edge_cost import EnergyCost
from .route import Route
from .route_time import waypoint_times_s

__all__ = [
    "ROUTE_BAG_FORMAT_VERSION",
    "DEFAULT_TOPIC_PREFIX",
    "RouteBag",
    "route_pose_times_s",
    "check_route_bag_path",
    "write_route_bag",
    "read_route_bag",
    "rosbags_api",
    "check_topic_prefix",
    "check_frame_origin",
    "MAX_FRAME_ORIGIN_DISTANCE_M",
    "header_message",
    "path_message",
    "path_poses",
    "write_bag_messages",
    "read_bag_topics",
]

#: Version of the ``terrawatt`` JSON messages (map CRS, summary) of the bags written here.
ROUTE_BAG_FORMAT_VERSION = 1
#: Topic prefix of the four topics.
DEFAULT_TOPIC_PREFIX = "/terrawatt"
#: Farthest a map frame origin other than (0, 0) may lie from the map's bounds (m): 10 000 km, a quarter of the way
#: round the Earth. A frame origin is a point of the site's neighbourhood (its corner, a survey mark, a UTM zone's
#: (500000, 0)); one farther away is a unit or typing slip, and poses relative to it lose their precision.
MAX_FRAME_ORIGIN_DISTANCE_M = 1.0e7
_PATH, _ENERGY, _CRS, _SUMMARY = "/route", "/route_energy", "/map_crs", "/route_summary"
_TYPES = {_PATH: "nav_msgs/msg/Path", _ENERGY: "std_msgs/msg/Float64MultiArray",
          _CRS: "std_msgs/msg/String", _SUMMARY: "std_msgs/msg/String"}
_NS = 1_000_000_000


def rosbags_api() -> tuple[Any, Any, Any, Any]:
    """``(Writer, StoragePlugin, AnyReader, typestore)`` of rosbags (the Jazzy typestore).

    Raises
    ------
    OptionalDependencyError
        rosbags (the ``ros`` extra) is not installed.
    """
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore
    except ImportError as exc:
        raise OptionalDependencyError(
            "ROS 2 bags need the optional dependency 'rosbags': pip install 'terrawatt[ros]'"
        ) from exc
    return Writer, StoragePlugin, AnyReader, get_typestore(Stores.ROS2_JAZZY)


@dataclass(frozen=True)
class RouteBag:
    """A route read back from a bag written by :func:`write_route_bag`.

    Attributes
    ----------
    frame_id : str
        The Path's frame.
    stamp_ns : int
        The Path's header stamp (ns).
    positions_m : ndarray, shape (K, 3)
        Pose positions in the map frame: x, y (m), z the elevation (m).
    yaw_rad : ndarray, shape (K,)
        Pose yaw from the orientation quaternion (rad, counter-clockwise from +x).
    pose_stamps_ns : ndarray of int64, shape (K,)
        Pose header stamps (ns).
    cumulative_energy_j : ndarray, shape (K,)
        Energy spent on leaving each pose (J).
    crs : str or None
        The map's CRS (None: local map metres).
    crs_wkt : str or None
        Its WKT (None without a CRS, or when the writer had no rasterio).
    frame_origin_xy_m : (float, float)
        The map frame's origin in map (CRS) coordinates.
    summary : dict
        The route's :meth:`~planner.Route.summary` (flat JSON values).
    """

    frame_id: str
    stamp_ns: int
    positions_m: np.ndarray
    yaw_rad: np.ndarray
    pose_stamps_ns: np.ndarray
    cumulative_energy_j: np.ndarray
    crs: str | None
    crs_wkt: str | None
    frame_origin_xy_m: tuple[float, float]
    summary: dict[str, Any]

    @property
    def waypoints_m(self) -> np.ndarray:
        """The poses' x, y back in map (CRS) coordinates: the route's waypoints."""
        return self.positions_m[:, :2] + np.asarray(self.frame_origin_xy_m)


def _check_route(route: Any) -> Route:
    if not isinstance(route, Route):
        raise InvalidParameterError(f"route must be a planner.Route, got {type(route).__name__!r}")
    if not route.found:
        raise InvalidParameterError(f"route has status {route.status!r} and no waypoints; only found routes are written")
    return route


def route_pose_times_s(route: Route, cost: EnergyCost) -> np.ndarray:
    """Planned time (s) at which the robot leaves each waypoint, driving the route stop-turn-go at the cost's
    speed and turn rate (:func:`planner.route_time.waypoint_times_s`: after the pivot where it turns, as it passes
    where it drives through).

    The last equals ``route.duration_s`` (the start's is 0: no turn there).

    Raises
    ------
    InvalidParameterError
        Not a found Route or not an EnergyCost; a cost whose speed and turn rate do not give
        the route's duration (the route was planned with another cost).
    """
    _check_route(route)
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    times = waypoint_times_s(route.waypoints_m, cost.speed_mps, cost.turn_rate_radps)
    if not math.isclose(times[-1], route.duration_s, rel_tol=1e-9, abs_tol=1e-9):
        raise InvalidParameterError(
            f"cost gives the route a duration of {times[-1]!r} s, the route says {route.duration_s!r} s: "
            "give the EnergyCost the route was planned with"
        )
    return times


def _map_info(tmap: TerrainMap, frame_id: str, frame_origin: tuple[float, float]) -> dict[str, Any]:
    """The ``map_crs`` message's content."""
    crs, wkt, epsg = tmap.crs, None, None
    if crs is not None:
        try:
            parsed = parse_crs(crs, "the map's crs")
        except OptionalDependencyError:  # rasterio (geo extra) missing: the CRS string alone
            parsed = None
        if parsed is not None:
            wkt, epsg = parsed.to_wkt(), parsed.to_epsg()
    return {
        "format_version": ROUTE_BAG_FORMAT_VERSION,
        "frame_id": frame_id,
        "crs": crs,
        "crs_wkt": wkt,
        "epsg": epsg,
        "coordinate_system": (f"x east, y north in metres of {crs} minus the frame origin; z elevation (m)"
                              if crs is not None else "local map metres (x east, y north) minus the frame origin; "
                              "z elevation (m); the map has no CRS"),
        "map_frame_origin_crs": list(frame_origin),
        "map_bounds_crs": list(tmap.bounds),
        "cell_size_m": tmap.cell_size_m,
    }


def header_message(ts: Any, stamp_ns: int, frame_id: str) -> Any:
    """A ``std_msgs/msg/Header`` stamped ``stamp_ns`` (ns, >= 0) in ``frame_id``, of the typestore ``ts``."""
    types = ts.types
    stamp = types["builtin_interfaces/msg/Time"](sec=int(stamp_ns // _NS), nanosec=int(stamp_ns % _NS))
    return types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id)


def path_message(ts: Any, tmap: TerrainMap, waypoints_m: np.ndarray, *, stamp_ns: int, pose_stamps_ns: Any,
                 frame_id: str, frame_origin_xy_m: tuple[float, float]) -> Any:
    """Waypoints as a ``nav_msgs/msg/Path``: one pose each, on the DEM, heading along its segment.

    Parameters
    ----------
    ts : rosbags typestore
        The message types (:func:`rosbags_api`).
    tmap : TerrainMap
        The map: z is its elevation at each waypoint (bilinear, m).
    waypoints_m : ndarray, shape (K, 2)
        Waypoints in map (CRS) coordinates (m), K >= 1.
    stamp_ns : int
        The Path's header stamp (ns).
    pose_stamps_ns : array_like of int, shape (K,)
        Each pose's header stamp (ns).
    frame_id : str
        Frame of the Path and its poses.
    frame_origin_xy_m : (float, float)
        The frame's origin in map coordinates: pose x, y are the waypoints minus it.

    Returns
    -------
    nav_msgs/msg/Path
        Each pose's yaw is that of the segment leaving its waypoint (the last keeps the yaw of
        the segment arriving; a single pose has yaw 0).

    Raises
    ------
    OutOfBoundsError
        A waypoint off the map.
    """
    types = ts.types
    pts = np.asarray(waypoints_m, dtype=np.float64).reshape(-1, 2)
    z = np.atleast_1d(tmap.sample("elevation", pts[:, 0], pts[:, 1], method="bilinear")).astype(np.float64)
    d = np.diff(pts, axis=0)
    yaw = np.arctan2(d[:, 1], d[:, 0])
    yaw = np.concatenate([yaw, yaw[-1:]]) if yaw.size else np.zeros(pts.shape[0])
    pose_ns = np.asarray(pose_stamps_ns, dtype=np.int64).reshape(-1)
    poses = []
    for (x, y), h, psi, ns in zip(pts.tolist(), z.tolist(), yaw.tolist(), pose_ns.tolist(), strict=True):
        position = types["geometry_msgs/msg/Point"](x=x - frame_origin_xy_m[0], y=y - frame_origin_xy_m[1], z=h)
        quat = types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(psi / 2.0), w=math.cos(psi / 2.0))
        poses.append(types["geometry_msgs/msg/PoseStamped"](
            header=header_message(ts, ns, frame_id),
            pose=types["geometry_msgs/msg/Pose"](position=position, orientation=quat)))
    return types["nav_msgs/msg/Path"](header=header_message(ts, stamp_ns, frame_id), poses=poses)


def path_poses(path_msg: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A ``nav_msgs/msg/Path``'s poses: positions (K, 3) (m), yaw (K,) from the quaternion (rad), header stamps (K,) (ns)."""
    poses = path_msg.poses
    positions = np.array([[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in poses], dtype=np.float64)
    q = np.array([[p.pose.orientation.z, p.pose.orientation.w] for p in poses], dtype=np.float64).reshape(-1, 2)
    stamps = np.array([int(p.header.stamp.sec) * _NS + int(p.header.stamp.nanosec) for p in poses], dtype=np.int64)
    return positions.reshape(-1, 3), 2.0 * np.arctan2(q[:, 0], q[:, 1]), stamps


def _messages(route: Route, tmap: TerrainMap, ts: Any, *, cost: EnergyCost | None, stamp_ns: int, frame_id: str,
              frame_origin: tuple[float, float]) -> dict[str, Any]:
    """The four messages, by topic suffix."""
    types = ts.types
    pts = route.waypoints_m
    times = route_pose_times_s(route, cost) if cost is not None else np.zeros(pts.shape[0])
    pose_ns = stamp_ns + np.rint(times * _NS).astype(np.int64)
    path = path_message(ts, tmap, pts, stamp_ns=stamp_ns, pose_stamps_ns=pose_ns, frame_id=frame_id,
                        frame_origin_xy_m=frame_origin)
    n_poses = len(path.poses)
    cumulative = np.cumsum(route.turn_energy_j) + np.concatenate([[0.0], np.cumsum(route.segment_energy_j)])
    dim = types["std_msgs/msg/MultiArrayDimension"](label="pose_energy_j", size=n_poses, stride=n_poses)
    energy = types["std_msgs/msg/Float64MultiArray"](
        layout=types["std_msgs/msg/MultiArrayLayout"](dim=[dim], data_offset=0), data=cumulative.astype(np.float64))
    text = types["std_msgs/msg/String"]
    summary = {"format_version": ROUTE_BAG_FORMAT_VERSION, **{  # JSON has no NaN: a quantity not computed is null
        k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in route.summary().items()}}
    return {
        _PATH: path,
        _ENERGY: energy,
        _CRS: text(data=json.dumps(_map_info(tmap, frame_id, frame_origin), allow_nan=False)),
        _SUMMARY: text(data=json.dumps(summary, allow_nan=False)),
    }


def _write_bag(bag_dir: Path, topics: Sequence[tuple[str, str]], messages: Iterable[tuple[str, int, Any]],
               ts: Any) -> None:
    """A ROS 2 bag directory (MCAP storage): the messages in order, each topic's connection added at its first
    message, the topics without messages last (in the order of ``topics``)."""
    writer_cls, plugin, _, _ = rosbags_api()
    types = dict(topics)
    with writer_cls(bag_dir, version=9, storage_plugin=plugin.MCAP) as writer:
        conns: dict[str, Any] = {}
        for topic, log_ns, msg in messages:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, types[topic], typestore=ts)
            writer.write(conns[topic], log_ns, ts.serialize_cdr(msg, types[topic]))
        for topic, msgtype in topics:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=ts)


def _fsync(path: Path) -> None:
    with open(path, "rb") as fh:
        os.fsync(fh.fileno())


def check_topic_prefix(topic_prefix: Any, name: str = "topic_prefix") -> str:
    """A topic namespace: a string that starts with ``/`` and does not end with it.

    Raises
    ------
    InvalidParameterError
        Anything else.
    """
    if not isinstance(topic_prefix, str) or not topic_prefix.startswith("/") or topic_prefix.endswith("/"):
        raise InvalidParameterError(f"{name} must start with '/' and not end with it, got {topic_prefix!r}")
    return topic_prefix


def check_frame_origin(frame_origin_xy_m: Any, *,
                       bounds: tuple[float, float, float, float] | None = None) -> tuple[float, float]:
    """A frame origin ``(x, y)`` in metres, both finite, as two floats; with ``bounds``, near the map.

    Parameters
    ----------
    frame_origin_xy_m : (float, float)
        The map frame's origin in the map's coordinates (m).
    bounds : (xmin, ymin, xmax, ymax), optional
        The map's bounds (m): an origin other than ``(0, 0)`` (the map's own coordinates,
        always accepted) must then lie within :data:`MAX_FRAME_ORIGIN_DISTANCE_M` of them.

    Raises
    ------
    InvalidParameterError
        Not a pair, or a coordinate not a finite real (the message names
        ``frame_origin_xy_m[i]``); with ``bounds``, an origin farther from the map than
        :data:`MAX_FRAME_ORIGIN_DISTANCE_M`. The error's parameter is ``frame_origin_xy_m``.

    Examples
    --------
    >>> check_frame_origin((500_000.0, 5_100_000.0), bounds=(500_000.0, 5_100_000.0, 501_000.0, 5_101_000.0))
    (500000.0, 5100000.0)
    >>> check_frame_origin((1e308, 0.0), bounds=(0.0, 0.0, 100.0, 100.0))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: frame_origin_xy_m (1e+308, 0) lies 1e+308 m from the map ...
    """
    name = "frame_origin_xy_m"
    try:
        fx, fy = frame_origin_xy_m
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"{name} must be (x, y) in metres, got {frame_origin_xy_m!r}",
                                    parameter=name) from exc
    try:
        fx, fy = check_real(f"{name}[0]", fx), check_real(f"{name}[1]", fy)
    except InvalidParameterError as exc:
        raise InvalidParameterError(str(exc), parameter=name) from None
    if bounds is None or (fx == 0.0 and fy == 0.0):
        return fx, fy
    xmin, ymin, xmax, ymax = (float(b) for b in bounds)
    distance = math.hypot(max(xmin - fx, 0.0, fx - xmax), max(ymin - fy, 0.0, fy - ymax))
    if not distance <= MAX_FRAME_ORIGIN_DISTANCE_M:  # an overflow to inf included
        raise InvalidParameterError(
            f"{name} ({fx:g}, {fy:g}) lies {distance:.3g} m from the map (x {xmin:g} to {xmax:g}, y {ymin:g} to "
            f"{ymax:g} m); a map frame origin other than (0, 0) must lie within {MAX_FRAME_ORIGIN_DISTANCE_M:g} m of "
            "the map's bounds: give it in the map's coordinates, in metres", parameter=name)
    return fx, fy


def write_bag_messages(path: str | os.PathLike[str], topics: Sequence[tuple[str, str]],
                       messages: Iterable[tuple[str, int, Any]], ts: Any) -> Path:
    """Write messages as a ROS 2 bag (MCAP) atomically: one ``.mcap`` file, or a bag directory for any other name.

    Parameters
    ----------
    path : path-like
        Checked by :func:`check_route_bag_path` (an existing directory is replaced only if it
        is a bag).
    topics : sequence of (str, str)
        ``(topic, message type)`` of every connection. A topic's connection is added at its
        first message; the topics without messages are declared all the same, last, in this
        order.
    messages : iterable of (str, int, message)
        ``(topic, log time in ns, message)``, written in this order (each topic one of ``topics``).
    ts : rosbags typestore
        The types the messages are serialised with (:func:`rosbags_api`).

    Returns
    -------
    Path
        The file or bag directory written; byte-identical for the same arguments.

    Raises
    ------
    InvalidParameterError
        A path refused by :func:`check_route_bag_path`.
    OptionalDependencyError
        rosbags (the ``ros`` extra) is not installed.
    """
    target, single = check_route_bag_path(path)
    name = target.stem if single else target.name  # the MCAP file inside is named after the target
    if single:
        with atomic_path(target) as tmp:
            work = tmp.with_name(tmp.name[: -len(".tmp")] + "_bag.tmp")  # a temporary of the same target
            try:
                _write_bag(work / name, topics, messages, ts)
                os.replace(work / name / f"{name}.mcap", tmp)
            finally:
                shutil.rmtree(work, ignore_errors=True)
        return target
    with atomic_directory(target) as tmp:
        _write_bag(tmp / name, topics, messages, ts)
        for item in sorted((tmp / name).iterdir()):
            os.replace(item, tmp / item.name)
            _fsync(tmp / item.name)
        (tmp / name).rmdir()
    return target


def read_bag_topics(path: str | os.PathLike[str], topic_prefix: str) -> dict[str, tuple[str, list[tuple[int, Any]]]]:
    """The topics under ``topic_prefix`` of a bag (``.mcap`` file or bag directory), deserialised.

    Returns
    -------
    dict
        By topic suffix (the name less the prefix): ``(message type, [(log time in ns,
        message), ...])`` in bag order; a topic declared without messages has an empty list.

    Raises
    ------
    FileFormatError
        The bag does not exist or cannot be read.
    OptionalDependencyError
        rosbags (the ``ros`` extra) is not installed.
    """
    _, _, any_reader, ts = rosbags_api()
    bag = Path(path)
    if not bag.exists():
        raise FileFormatError(f"bag {str(bag)!r} does not exist")
    found: dict[str, tuple[str, list[tuple[int, Any]]]] = {}
    try:
        with any_reader([bag], default_typestore=ts) as reader:
            for conn in reader.connections:
                if conn.topic.startswith(topic_prefix):
                    found.setdefault(conn.topic[len(topic_prefix):], (conn.msgtype, []))
            for conn, log_ns, raw in reader.messages():
                if conn.topic.startswith(topic_prefix):
                    found[conn.topic[len(topic_prefix):]][1].append((int(log_ns), reader.deserialize(raw, conn.msgtype)))
    except Exception as exc:  # rosbags raises its own error classes per format
        raise FileFormatError(f"cannot read bag {str(bag)!r}: {type(exc).__name__}: {exc}") from exc
    return found


def check_route_bag_path(path: str | os.PathLike[str], name: str = "path") -> tuple[Path, bool]:
    """Check, before any work, that a route bag can be written at ``path``; return it and whether it is one ``.mcap`` file.

    A name ending in ``.mcap`` is a single MCAP file; any other name a ROS 2 bag directory,
    which may replace an existing directory only if that is a bag (holds ``metadata.yaml``).

    Raises
    ------
    InvalidParameterError
        A ``.bag`` / ``.db3`` name; a path of the wrong kind; a directory that is not a bag; the message names
        ``name`` (as :func:`terrawatt_base.atomic.check_output_path`).
    """
    target = Path(path)
    suffix = target.suffix.lower()
    if suffix in (".bag", ".db3"):
        raise InvalidParameterError(f"{name} {str(target)!r}: ROS 1 .bag and sqlite3 .db3 are not written; give a "
                                    "'.mcap' file or a bag directory name", parameter=name.strip("`"))
    single = suffix == ".mcap"
    check_output_path(target, name, directory=not single)
    if not single and target.is_dir() and not (target / "metadata.yaml").is_file():
        raise InvalidParameterError(f"{name} {str(target)!r} is a directory that is not a ROS 2 bag (no metadata.yaml); "
                                    "give a new name or a '.mcap' file", parameter=name.strip("`"))
    return target, single


def write_route_bag(
    path: str | os.PathLike[str],
    route: Route,
    tmap: TerrainMap,
    *,
    cost: EnergyCost | None = None,
    stamp_ns: int = 0,
    frame_id: str = "map",
    topic_prefix: str = DEFAULT_TOPIC_PREFIX,
    frame_origin_xy_m: tuple[float, float] = (0.0, 0.0),
) -> Path:
    """Write a planned route, its energy and the map's CRS as a ROS 2 bag (MCAP), atomically.

    Parameters
    ----------
    path : path-like
        A ``.mcap`` file, or a ROS 2 bag directory for any other name (an existing one is
        replaced only if it is a bag: it holds a ``metadata.yaml``).
    route : Route
        A found route (``exact`` or ``approximate``).
    tmap : TerrainMap
        The map it was planned on (elevations for z, the CRS).
    cost : EnergyCost, optional
        The edge costs it was planned with: the poses are then stamped with the planned time
        of leaving each waypoint (:func:`route_pose_times_s`); without it, all with ``stamp_ns``.
    stamp_ns : int
        Time of the Path's header and of every message in the bag (ns since the epoch, >= 0).
    frame_id : str
        Frame of the Path and its poses.
    topic_prefix : str
        Namespace of the four topics (starts with ``/``).
    frame_origin_xy_m : (float, float)
        The map frame's origin in map (CRS) coordinates: poses are waypoints minus it. The
        default puts the map frame on the map's coordinates; a local origin (e.g. the map's
        lower-left corner) keeps UTM-sized numbers out of the poses. Any other origin must lie
        within :data:`MAX_FRAME_ORIGIN_DISTANCE_M` of the map's bounds (:func:`check_frame_origin`).

    Returns
    -------
    Path
        The file or bag directory written.

    Raises
    ------
    InvalidParameterError
        A route not found or not a Route; bad stamp, frame, prefix or origin (not finite, or
        farther than :data:`MAX_FRAME_ORIGIN_DISTANCE_M` from the map); a ``.bag`` / ``.db3``
        name; an existing directory that is not a bag; a cost that does not give the route's
        duration.
    OutOfBoundsError
        A waypoint off the map.
    GridMismatchError
        ``cost`` priced on another grid than ``tmap``.
    OptionalDependencyError
        rosbags (the ``ros`` extra) is not installed.
    """
    target, _ = check_route_bag_path(path)
    _check_route(route)
    if not isinstance(tmap, TerrainMap):
        raise InvalidParameterError(f"tmap must be a TerrainMap, got {type(tmap).__name__!r}")
    if cost is not None:
        if not isinstance(cost, EnergyCost):
            raise InvalidParameterError(f"cost must be an EnergyCost or None, got {type(cost).__name__!r}")
        tmap.grid.check_same(cost.terrain.grid, "cost")
    stamp = check_int("stamp_ns", stamp_ns, low=0)
    check_text("frame_id", frame_id)
    check_topic_prefix(topic_prefix)
    origin = check_frame_origin(frame_origin_xy_m, bounds=tmap.bounds)
    _, _, _, ts = rosbags_api()
    messages = _messages(route, tmap, ts, cost=cost, stamp_ns=stamp, frame_id=frame_id, frame_origin=origin)
    return write_bag_messages(target, [(topic_prefix + suffix, _TYPES[suffix]) for suffix in messages],
                              [(topic_prefix + suffix, stamp, msg) for suffix, msg in messages.items()], ts)


def read_route_bag(path: str | os.PathLike[str], *, topic_prefix: str = DEFAULT_TOPIC_PREFIX) -> RouteBag:
    """Read a route written by :func:`write_route_bag` (a ``.mcap`` file or a bag directory).

    Raises
    ------
    FileFormatError
        Not a readable bag; a missing topic or not one message on it; energies and poses of
        different counts; a CRS message that is not terrawatt's JSON, or of a newer version.
    OptionalDependencyError
        rosbags (the ``ros`` extra) is not installed.
    """
    bag = Path(path)
    found = {suffix: [msg for _, msg in messages] for suffix, (_, messages) in read_bag_topics(bag, topic_prefix).items()}
    for suffix in _TYPES:
        if len(found.get(suffix, [])) != 1:
            raise FileFormatError(f"bag {str(bag)!r} has {len(found.get(suffix, []))} messages on "
                                  f"{topic_prefix + suffix!r}; a terrawatt route bag has one")
    path_msg, energy_msg = found[_PATH][0], found[_ENERGY][0]
    try:
        info = json.loads(found[_CRS][0].data)
        summary = json.loads(found[_SUMMARY][0].data)
        version = int(info["format_version"])
        origin = tuple(float(v) for v in info["map_frame_origin_crs"])
    except (ValueError, KeyError, TypeError) as exc:
        raise FileFormatError(f"bag {str(bag)!r}: {topic_prefix + _CRS!r} is not terrawatt's map JSON: {exc}") from exc
    if not 1 <= version <= ROUTE_BAG_FORMAT_VERSION or len(origin) != 2:
        raise FileFormatError(f"bag {str(bag)!r} has route bag format version {version!r}; this release reads 1 to "
                              f"{ROUTE_BAG_FORMAT_VERSION}")
    positions, yaw, stamps = path_poses(path_msg)
    n_poses = positions.shape[0]
    energy = np.asarray(energy_msg.data, dtype=np.float64)
    if energy.shape != (n_poses,) or n_poses < 2:
        raise FileFormatError(f"bag {str(bag)!r} has {n_poses} poses and {energy.size} energies; expected as many "
                              "energies as poses, at least 2")
    stamp = int(path_msg.header.stamp.sec) * _NS + int(path_msg.header.stamp.nanosec)
    return RouteBag(
        frame_id=str(path_msg.header.frame_id),
        stamp_ns=stamp,
        positions_m=readonly(positions),
        yaw_rad=readonly(yaw),
        pose_stamps_ns=readonly(stamps),
        cumulative_energy_j=readonly(energy),
        crs=info.get("crs"),
        crs_wkt=info.get("crs_wkt"),
        frame_origin_xy_m=(origin[0], origin[1]),
        summary=summary,
    )
