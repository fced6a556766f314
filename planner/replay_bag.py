"""ROS 2 out: a replayed drive's routes, remaining-energy forecasts and decisions, on the drive's clock, in an MCAP bag.

:func:`write_replay_bag` writes what the navigator said during a recorded drive, so that
Foxglove or RViz play it beside the drive's own bag. Every message is logged (and its header,
if it has one, stamped) at ``start_time_ns`` plus its time in seconds × 1e9, rounded to the
nanosecond: with ``start_time_ns`` the drive bag's first stamp and the times those of the
replay, the two bags share one clock. Three topics under ``topic_prefix`` (``/terrawatt``):

- ``<prefix>/route`` — ``nav_msgs/msg/Path`` per replan, in ``frame_id``: one pose per
  waypoint, x and y the waypoint minus ``frame_origin_xy_m`` (m), z the DEM's elevation there
  (bilinear, m), the yaw that of the segment leaving the waypoint (as
  :func:`planner.ros_export.path_message`); the Path and its poses stamped at the replan.
- ``<prefix>/remaining_energy`` — ``std_msgs/msg/Float64MultiArray`` per forecast: the five
  values of :data:`FORECAST_VALUES`, [energy_j, low_j, high_j, actual_j, soc] — the forecast
  remaining energy (J), its interval at the risk level (J), the remaining energy actually
  measured (J) and the state of charge (0-1); NaN where a value is unknown (as a rule the
  measured remaining energy, known only once the drive is over).
- ``<prefix>/decision`` — ``std_msgs/msg/String`` per decision: the decision's dict as JSON
  (its order kept, NaN as null).

A topic without input is declared all the same, with no message. The bag is a single
``.mcap`` file, or a ROS 2 bag directory for any other name, written atomically and
byte-identical for the same inputs, as :func:`planner.ros_export.write_route_bag` writes
(whose pieces it uses). :func:`read_replay_bag` reads it back as a :class:`ReplayBag`.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrawatt_base.atomic import json_finite
from terrawatt_base.checks import check_int, check_real, check_text, plain_repr, readonly, real_array
from terrawatt_base.errors import DataError, FileFormatError, InvalidParameterError, OutOfBoundsError

from .ros_export import (
    DEFAULT_TOPIC_PREFIX,
    check_frame_origin,
    check_route_bag_path,
    check_topic_prefix,
    path_message,
    path_poses,
    read_bag_topics,
    rosbags_api,
    write_bag_messages,
)

__all__ = [
    "FORECAST_FIELDS",
    "FORECAST_VALUES",
    "ReplayBag",
    "write_replay_bag",
    "read_replay_bag",
]

#: The values of one ``remaining_energy`` message, in order (the label of its layout).
FORECAST_VALUES = ("energy_j", "low_j", "high_j", "actual_j", "soc")
#: The keys of :func:`write_replay_bag`'s ``forecasts``: the time (s) and the five values.
FORECAST_FIELDS = ("time_s", *FORECAST_VALUES)
_ROUTE, _REMAINING, _DECISION = "/route", "/remaining_energy", "/decision"
_TYPES = {_ROUTE: "nav_msgs/msg/Path", _REMAINING: "std_msgs/msg/Float64MultiArray",
          _DECISION: "std_msgs/msg/String"}
_NS = 1_000_000_000
_MAX_NS = 2**63 - 1


@dataclass(frozen=True)
class ReplayBag:
    """What :func:`write_replay_bag` wrote, read back by :func:`read_replay_bag`.

    Attributes
    ----------
    frame_id : str or None
        The routes' frame (None: the bag holds no route).
    route_stamps_ns : ndarray of int64, shape (R,)
        Stamp of each replan's Path (ns).
    route_positions_m : tuple of R ndarrays, shape (K, 3)
        Each route's poses in the frame: x, y (m), z the elevation (m).
    route_yaw_rad : tuple of R ndarrays, shape (K,)
        Each route's pose yaw (rad, counter-clockwise from +x).
    forecast_stamps_ns : ndarray of int64, shape (F,)
        Stamp of each forecast (ns).
    forecast_energy_j, forecast_low_j, forecast_high_j, forecast_actual_j : ndarray, shape (F,)
        Forecast remaining energy, its interval, the remaining energy measured (J; NaN: unknown).
    forecast_soc : ndarray, shape (F,)
        State of charge (0-1; NaN: unknown).
    decision_stamps_ns : ndarray of int64, shape (D,)
        Stamp of each decision (ns).
    decisions : tuple of D dicts
        The decisions as written (JSON values: NaN came back as None).
    """

    frame_id: str | None
    route_stamps_ns: np.ndarray
    route_positions_m: tuple[np.ndarray, ...]
    route_yaw_rad: tuple[np.ndarray, ...]
    forecast_stamps_ns: np.ndarray
    forecast_energy_j: np.ndarray
    forecast_low_j: np.ndarray
    forecast_high_j: np.ndarray
    forecast_actual_j: np.ndarray
    forecast_soc: np.ndarray
    decision_stamps_ns: np.ndarray
    decisions: tuple[dict[str, Any], ...]

    def as_inputs(self, *, start_time_ns: int = 0,
                  frame_origin_xy_m: tuple[float, float] | None = None) -> dict[str, Any]:
        """The ``replans``, ``forecasts`` and ``decisions`` arguments of :func:`write_replay_bag` back.

        Times are the stamps less ``start_time_ns`` (s, exact to the ns); waypoints are the
        poses' x, y plus ``frame_origin_xy_m`` (map coordinates, m). Written again with the same
        map, frame, origin and start, they give the same bag, byte for byte.
        """
        start = check_int("start_time_ns", start_time_ns, low=0)
        origin = np.asarray((0.0, 0.0) if frame_origin_xy_m is None else check_frame_origin(frame_origin_xy_m))

        def times_s(stamps: np.ndarray) -> np.ndarray:
            return (stamps - start) / _NS

        forecasts = {"time_s": times_s(self.forecast_stamps_ns)} | {
            name: np.array(getattr(self, f"forecast_{name}")) for name in FORECAST_VALUES}
        return {
            "replans": [(float(t), p[:, :2] + origin)
                        for t, p in zip(times_s(self.route_stamps_ns), self.route_positions_m, strict=True)],
            "forecasts": forecasts,
            "decisions": [(float(t), dict(d)) for t, d in zip(times_s(self.decision_stamps_ns), self.decisions,
                                                               strict=True)],
        }


# ------------------------------------------------------------------ checks
def _stamps_ns(name: str, times_s: np.ndarray, start_ns: int) -> np.ndarray:
    """Log times (ns) of non-decreasing times (s) on the clock that starts at ``start_ns``."""
    if times_s.size > 1 and np.any(np.diff(times_s) < 0):
        i = int(np.flatnonzero(np.diff(times_s) < 0)[0]) + 1
        raise DataError(f"{name} times must not decrease: {name}[{i}] at {plain_repr(times_s[i])} s follows "
                        f"{name}[{i - 1}] at {plain_repr(times_s[i - 1])} s")
    offsets = np.rint(times_s * _NS)
    bad = np.flatnonzero((start_ns + offsets < 0) | (start_ns + offsets > _MAX_NS))
    if bad.size:
        raise DataError(f"{name}[{int(bad[0])}] at {plain_repr(times_s[bad[0]])} s is off the bag's clock (start_time_ns="
                        f"{start_ns}): stamps must lie in [0, 2**63) ns")
    return start_ns + offsets.astype(np.int64)


def _pairs(name: str, value: Any) -> list[tuple[float, Any]]:
    """``(time_s, item)`` pairs of a sequence, times checked finite."""
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Sequence):
        raise InvalidParameterError(f"{name} must be a sequence of (time_s, ...) pairs, got {type(value).__name__!r}")
    out = []
    for i, item in enumerate(value):
        if isinstance(item, (str, bytes)) or not isinstance(item, Sequence) or len(item) != 2:
            raise InvalidParameterError(f"{name}[{i}] must be a pair (time_s, ...), got {item!r:.80}")
        out.append((check_real(f"{name}[{i}][0] (time_s)", item[0]), item[1]))
    return out


def _check_replans(replans: Any) -> list[tuple[float, np.ndarray]]:
    out = []
    for i, (t, waypoints) in enumerate(_pairs("replans", replans)):
        pts = real_array(f"replans[{i}][1] (waypoints_m)", waypoints, ndim=2)
        if pts.shape[0] < 1 or pts.shape[1] != 2:
            raise InvalidParameterError(f"replans[{i}][1] (waypoints_m) must have shape (N, 2) with N >= 1, "
                                        f"got shape {pts.shape!r}")
        out.append((t, pts))
    return out


def _check_forecasts(forecasts: Any) -> dict[str, np.ndarray]:
    if not isinstance(forecasts, Mapping):
        raise InvalidParameterError(f"forecasts must be a mapping of {FORECAST_FIELDS!r} to 1-D arrays, "
                                    f"got {type(forecasts).__name__!r}")
    if not forecasts:
        return {name: np.empty(0) for name in FORECAST_FIELDS}
    missing = [k for k in FORECAST_FIELDS if k not in forecasts]
    unknown = sorted(str(k) for k in forecasts if k not in FORECAST_FIELDS)
    if missing or unknown:
        raise InvalidParameterError(f"forecasts must have exactly the keys {FORECAST_FIELDS!r}; missing {missing!r}, "
                                    f"unknown {unknown!r}")
    out = {}
    for name in FORECAST_FIELDS:
        column = real_array(f"forecasts[{name!r}]", forecasts[name], ndim=1, finite=name == "time_s")
        if np.any(np.isinf(column)):
            raise InvalidParameterError(f"forecasts[{name!r}] has infinite entries; expected finite values or NaN")
        out[name] = column
    lengths = {name: column.size for name, column in out.items()}
    if len(set(lengths.values())) != 1:
        raise InvalidParameterError(f"forecasts' arrays must have equal lengths, got {lengths!r}")
    return out


def _check_decisions(decisions: Any) -> list[tuple[float, str]]:
    out = []
    for i, (t, decision) in enumerate(_pairs("decisions", decisions)):
        if not isinstance(decision, Mapping):
            raise InvalidParameterError(f"decisions[{i}][1] must be a dict (Decision.to_dict()), "
                                        f"got {type(decision).__name__!r}")
        try:
            text = json.dumps(json_finite(dict(decision)), allow_nan=False)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(f"decisions[{i}][1] is not JSON-able: {exc}") from exc
        out.append((t, text))
    return out


# ------------------------------------------------------------------ write and read
def write_replay_bag(
    path: str | os.PathLike[str],
    terrain: TerrainMap,
    *,
    replans: Sequence[tuple[float, Any]],
    forecasts: Mapping[str, Any],
    decisions: Sequence[tuple[float, Mapping[str, Any]]],
    frame_id: str = "map",
    frame_origin_xy_m: tuple[float, float] | None = None,
    topic_prefix: str = DEFAULT_TOPIC_PREFIX,
    start_time_ns: int = 0,
) -> Path:
    """Write a replayed drive's routes, forecasts and decisions as a ROS 2 bag (MCAP), atomically.

    Parameters
    ----------
    path : path-like
        A ``.mcap`` file, or a ROS 2 bag directory for any other name (an existing one is
        replaced only if it is a bag: it holds a ``metadata.yaml``).
    terrain : TerrainMap
        The map driven on (elevations for the poses' z).
    replans : sequence of (float, array_like)
        ``(time_s, waypoints_m)`` per new route: the drive's time (s) and the waypoints, shape
        (N, 2), N >= 1, in map coordinates (m). Times non-decreasing.
    forecasts : mapping of str to array_like
        Equal-length 1-D arrays under the keys of :data:`FORECAST_FIELDS`: ``time_s`` (s,
        finite, non-decreasing), ``energy_j``, ``low_j``, ``high_j``, ``actual_j`` (J) and
        ``soc`` (0-1), each NaN where unknown (never infinite). An empty mapping: no forecasts.
    decisions : sequence of (float, dict)
        ``(time_s, decision)`` per decision, the decision a JSON-able dict
        (``Decision.to_dict()``; NaN becomes null). Times non-decreasing.
    frame_id : str
        Frame of the Paths and their poses.
    frame_origin_xy_m : (float, float), optional
        The frame's origin in map coordinates: poses are waypoints minus it. None: (0, 0), the
        frame on the map's coordinates. Any other origin must lie within
        :data:`~planner.ros_export.MAX_FRAME_ORIGIN_DISTANCE_M` of the map's bounds.
    topic_prefix : str
        Namespace of the three topics (starts with ``/``).
    start_time_ns : int
        The drive's clock at time 0 (ns since the epoch, >= 0): a message at ``t`` s is logged
        at ``start_time_ns + round(t * 1e9)``.

    Returns
    -------
    Path
        The file or bag directory written; byte-identical for the same inputs.

    Raises
    ------
    InvalidParameterError
        A ``.bag`` / ``.db3`` name or an existing directory that is not a bag; not a
        TerrainMap; a bad frame, prefix, origin (not finite, or too far from the map) or
        start; an input of the wrong kind or shape (waypoints not (N, 2), forecast arrays not
        1-D, of unequal lengths, missing or unknown keys, a time not finite, an infinite
        value); a decision not a JSON-able dict.
    DataError
        The times of an input decrease, or put a message before the clock's 0 (or past 2**63 ns).
    OutOfBoundsError
        A waypoint off the map (the message names the replan).
    OptionalDependencyError
        rosbags (the ``ros`` extra) is not installed.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np, terrain
    >>> folder = tempfile.TemporaryDirectory()
    >>> bag = write_replay_bag(pathlib.Path(folder.name) / "replay.mcap", terrain.flat_map((20, 20), 1.0),
    ...                        replans=[(0.0, np.array([[1.0, 1.0], [10.0, 5.0]]))], forecasts={},
    ...                        decisions=[(0.5, {"action": "continue"})], start_time_ns=1_700_000_000_000_000_000)
    >>> read_replay_bag(bag).decision_stamps_ns.tolist()
    [1700000000500000000]
    >>> folder.cleanup()
    """
    check_route_bag_path(path)
    if not isinstance(terrain, TerrainMap):
        raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
    check_text("frame_id", frame_id)
    check_topic_prefix(topic_prefix)
    origin = (0.0, 0.0) if frame_origin_xy_m is None else check_frame_origin(frame_origin_xy_m, bounds=terrain.bounds)
    start = check_int("start_time_ns", start_time_ns, low=0)
    routes = _check_replans(replans)
    columns = _check_forecasts(forecasts)
    texts = _check_decisions(decisions)
    route_ns = _stamps_ns("replans", np.array([t for t, _ in routes], dtype=np.float64), start)
    forecast_ns = _stamps_ns("forecasts['time_s']", columns["time_s"], start)
    decision_ns = _stamps_ns("decisions", np.array([t for t, _ in texts], dtype=np.float64), start)

    _, _, _, ts = rosbags_api()
    types = ts.types
    queue: list[tuple[int, int, int, str, Any]] = []  # (log ns, topic rank, index, suffix, message)
    for i, ((_, pts), ns) in enumerate(zip(routes, route_ns.tolist(), strict=True)):
        try:
            msg = path_message(ts, terrain, pts, stamp_ns=ns, pose_stamps_ns=np.full(pts.shape[0], ns),
                               frame_id=frame_id, frame_origin_xy_m=origin)
        except OutOfBoundsError as exc:
            raise OutOfBoundsError(f"replans[{i}][1] (waypoints_m): {exc}") from exc
        queue.append((ns, 0, i, _ROUTE, msg))
    n_values = len(FORECAST_VALUES)
    layout = types["std_msgs/msg/MultiArrayLayout"](dim=[types["std_msgs/msg/MultiArrayDimension"](
        label=",".join(FORECAST_VALUES), size=n_values, stride=n_values)], data_offset=0)
    values = np.column_stack([columns[name] for name in FORECAST_VALUES]).reshape(-1, n_values)
    for i, (row, ns) in enumerate(zip(values, forecast_ns.tolist(), strict=True)):
        queue.append((ns, 1, i, _REMAINING,
                      types["std_msgs/msg/Float64MultiArray"](layout=layout, data=np.array(row, dtype=np.float64))))
    for i, ((_, text), ns) in enumerate(zip(texts, decision_ns.tolist(), strict=True)):
        queue.append((ns, 2, i, _DECISION, types["std_msgs/msg/String"](data=text)))
    queue.sort(key=lambda item: item[:3])  # one clock: in time, then by topic, then in input order
    return write_bag_messages(path, [(topic_prefix + suffix, msgtype) for suffix, msgtype in _TYPES.items()],
                              [(topic_prefix + suffix, ns, msg) for ns, _, _, suffix, msg in queue], ts)


def read_replay_bag(path: str | os.PathLike[str], *, topic_prefix: str = DEFAULT_TOPIC_PREFIX) -> ReplayBag:
    """Read a bag written by :func:`write_replay_bag` (a ``.mcap`` file or a bag directory).

    Raises
    ------
    FileFormatError
        Not a readable bag; one of the three topics missing or of another type; a forecast
        without five values; a decision that is not a JSON object.
    OptionalDependencyError
        rosbags (the ``ros`` extra) is not installed.
    """
    check_topic_prefix(topic_prefix)
    bag = Path(path)
    found = read_bag_topics(bag, topic_prefix)
    for suffix, msgtype in _TYPES.items():
        declared = found.get(suffix, (None, []))[0]
        if declared != msgtype:
            raise FileFormatError(f"bag {str(bag)!r} has no topic {topic_prefix + suffix!r} of type {msgtype!r} "
                                  f"(found {declared!r}); it is not a terrawatt replay bag")
    routes = found[_ROUTE][1]
    poses = [path_poses(msg) for _, msg in routes]
    forecasts = found[_REMAINING][1]
    rows = [np.asarray(msg.data, dtype=np.float64) for _, msg in forecasts]
    if any(row.shape != (len(FORECAST_VALUES),) for row in rows):
        raise FileFormatError(f"bag {str(bag)!r}: a message on {topic_prefix + _REMAINING!r} does not hold the "
                              f"{len(FORECAST_VALUES)} values {FORECAST_VALUES!r}")
    values = np.array(rows, dtype=np.float64).reshape(-1, len(FORECAST_VALUES))
    decisions = []
    for _, msg in found[_DECISION][1]:
        try:
            decision = json.loads(msg.data)
        except ValueError as exc:
            raise FileFormatError(f"bag {str(bag)!r}: a message on {topic_prefix + _DECISION!r} is not JSON: "
                                  f"{exc}") from exc
        if not isinstance(decision, dict):
            raise FileFormatError(f"bag {str(bag)!r}: a message on {topic_prefix + _DECISION!r} is not a JSON "
                                  f"object: {msg.data!r:.80}")
        decisions.append(decision)

    def stamps(messages: list[tuple[int, Any]]) -> np.ndarray:
        return readonly(np.array([ns for ns, _ in messages], dtype=np.int64))

    return ReplayBag(
        frame_id=str(routes[0][1].header.frame_id) if routes else None,
        route_stamps_ns=stamps(routes),
        route_positions_m=tuple(readonly(p) for p, _, _ in poses),
        route_yaw_rad=tuple(readonly(y) for _, y, _ in poses),
        forecast_stamps_ns=stamps(forecasts),
        forecast_energy_j=readonly(values[:, 0]),
        forecast_low_j=readonly(values[:, 1]),
        forecast_high_j=readonly(values[:, 2]),
        forecast_actual_j=readonly(values[:, 3]),
        forecast_soc=readonly(values[:, 4]),
        decision_stamps_ns=stamps(found[_DECISION][1]),
        decisions=tuple(decisions),
    )
