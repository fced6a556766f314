"""What a robot measured, as the navigator takes it: a chunk of sensor data checked against the map and the clock.

:func:`observation_log` turns one chunk — an :class:`energy.InteractionLog` slice, or plain
arrays in a mapping — into an :class:`energy.InteractionLog` with map poses, and refuses
what the loop must not learn from: no poses, NaN, time going backwards within the chunk or
against the last chunk, poses off the map, currents in the wrong unit. Nothing is repaired
or dropped: a chunk is taken whole or refused with a :class:`terrain.TerrawattError` that
names the input.

Plain arrays (keys of :data:`CHUNK_FIELDS`): ``time_s``; the pose as ``pose_xyh`` (N, 3) in
map metres, or ``lon_deg`` / ``lat_deg`` (degrees, WGS 84; projected through the map's CRS)
with ``heading_rad``; ``v_mps`` / ``omega_radps`` (commanded or measured); optionally
``current_left_a`` / ``current_right_a`` (A), ``accel_time_s`` / ``accel_z_mps2`` /
``gyro_z_radps`` (the IMU stream; without it the vertical acceleration is taken as
``+9.81 m/s^2`` at the drive timestamps and the log says so), ``battery_voltage_v`` /
``battery_current_a``, ``ground`` (labels).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from energy import InteractionLog, LogMeta
from energy.io.cleaning import check_current
from terrain import DataError, InvalidParameterError, OutOfBoundsError, TerrainMap
from terrawatt_base.checks import fmt_number

__all__ = ["CHUNK_FIELDS", "STANDARD_GRAVITY_MPS2", "observation_log"]

#: Keys a chunk of plain arrays may hold.
CHUNK_FIELDS = ("time_s", "pose_xyh", "lon_deg", "lat_deg", "heading_rad", "v_mps", "omega_radps",
                "current_left_a", "current_right_a", "accel_time_s", "accel_z_mps2", "gyro_z_radps",
                "battery_voltage_v", "battery_current_a", "ground")
#: The vertical acceleration a chunk without an IMU stream is given (m/s^2).
STANDARD_GRAVITY_MPS2 = 9.80665


def observation_log(chunk: Any, terrain: TerrainMap, *, previous_time_s: float | None = None,
                    name: str = "chunk", robot: str = "unknown") -> InteractionLog:
    """One chunk of measurements as an :class:`~energy.InteractionLog` on the map, checked.

    Parameters
    ----------
    chunk : InteractionLog or mapping of arrays
        What the robot measured since the last chunk (see the module docstring).
    terrain : TerrainMap
        The map its poses must lie on.
    previous_time_s : float, optional
        The last drive timestamp of the previous chunk: this chunk must start after it.
    name : str
        How messages name the chunk (e.g. ``"chunk 12"`` or a file name).
    robot : str
        The robot's name for a chunk of plain arrays.

    Returns
    -------
    InteractionLog
        With ``pose_xyh`` in map metres.

    Raises
    ------
    InvalidParameterError
        Not a log or a mapping; unknown keys; missing ``time_s`` / ``v_mps`` / ``omega_radps``;
        lon/lat without a map CRS or without ``heading_rad``.
    DataError
        No poses; NaN or infinite values; time not strictly increasing within the chunk, or
        not after ``previous_time_s``.
    OutOfBoundsError
        A pose off the map (the first such sample named).
    UnitError
        Currents that look like mA where A are expected.
    """
    log = chunk if isinstance(chunk, InteractionLog) else _from_arrays(chunk, terrain, name, robot)
    if log.pose_xyh is None:
        raise DataError(f"{name} holds no poses (pose_xyh, or lon_deg / lat_deg with heading_rad): the navigator "
                        "needs to know where each sample was measured")
    t0 = float(log.time_s[0])
    if previous_time_s is not None and not t0 > previous_time_s:
        raise DataError(f"{name} starts at t = {fmt_number(t0, 9)} s, not after the last chunk's end at "
                        f"{fmt_number(float(previous_time_s), 9)} s: time went backwards between chunks")
    xy = log.pose_xyh[:, :2]
    lo_x, lo_y, hi_x, hi_y = terrain.bounds
    off = ~np.asarray(terrain.contains(xy[:, 0], xy[:, 1]), dtype=bool)
    if np.any(off):
        i = int(np.argmax(off))
        raise OutOfBoundsError(
            f"{name}: the pose at t = {fmt_number(float(log.time_s[i]), 9)} s, ({fmt_number(float(xy[i, 0]))}, "
            f"{fmt_number(float(xy[i, 1]))}) m, lies off the map (x in [{fmt_number(lo_x)}, {fmt_number(hi_x)}], "
            f"y in [{fmt_number(lo_y)}, {fmt_number(hi_y)}] m); {int(off.sum())} of {len(log)} samples are off it")
    if log.has_currents:
        for side in ("current_left_a", "current_right_a"):
            check_current(name, side, np.asarray(getattr(log, side)), "A")
    return log


def _array(chunk: Mapping[str, Any], key: str, name: str, n: int | None = None) -> np.ndarray | None:
    if key not in chunk or chunk[key] is None:
        return None
    try:
        values = np.asarray(chunk[key], dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name}: {key} must be an array of numbers, got {chunk[key]!r:.80}") from None
    if not np.all(np.isfinite(values)):
        i = int(np.argmax(~np.isfinite(values).reshape(values.shape[0], -1).all(axis=1))) if values.ndim else 0
        raise DataError(f"{name}: {key} holds a NaN or infinite value (first at index {i})")
    if n is not None and values.shape[:1] != (n,):
        raise InvalidParameterError(f"{name}: {key} must hold {n} values (one per time_s), got shape {values.shape}")
    return values


def _from_arrays(chunk: Any, terrain: TerrainMap, name: str, robot: str) -> InteractionLog:
    """An InteractionLog from a mapping of plain arrays (see the module docstring)."""
    if not isinstance(chunk, Mapping):
        raise InvalidParameterError(f"{name} must be an InteractionLog or a mapping of arrays, got "
                                    f"{type(chunk).__name__!r}")
    unknown = sorted(set(chunk) - set(CHUNK_FIELDS))
    if unknown:
        raise InvalidParameterError(f"{name}: unknown field(s) {unknown!r}; expected some of {list(CHUNK_FIELDS)!r}")
    for key in ("time_s", "v_mps", "omega_radps"):
        if chunk.get(key) is None:
            raise InvalidParameterError(f"{name}: {key} is missing")
    t = _array(chunk, "time_s", name)
    if t.ndim != 1 or t.size == 0:
        raise InvalidParameterError(f"{name}: time_s must be a non-empty 1-D array, got shape {t.shape}")
    n = t.size
    pose = _array(chunk, "pose_xyh", name, n)
    lon, lat = _array(chunk, "lon_deg", name, n), _array(chunk, "lat_deg", name, n)
    if pose is None and (lon is not None or lat is not None):
        heading = _array(chunk, "heading_rad", name, n)
        if lon is None or lat is None or heading is None:
            raise InvalidParameterError(f"{name}: a pose from GPS needs lon_deg, lat_deg and heading_rad")
        x, y = terrain.lonlat_to_xy(lon, lat)
        pose = np.column_stack([x, y, heading])
    elif pose is not None and (lon is not None or lat is not None):
        raise InvalidParameterError(f"{name}: give the pose as pose_xyh or as lon_deg / lat_deg, not both")
    accel_t = _array(chunk, "accel_time_s", name)
    accel_z = _array(chunk, "accel_z_mps2", name)
    notes = ""
    if (accel_t is None) != (accel_z is None):
        raise InvalidParameterError(f"{name}: give accel_time_s and accel_z_mps2 together")
    if accel_t is None:
        accel_t, accel_z = t, np.full(n, STANDARD_GRAVITY_MPS2)
        notes = "no IMU stream: vertical acceleration taken as standard gravity"
    ground = chunk.get("ground")
    return InteractionLog(
        time_s=t, v_mps=_array(chunk, "v_mps", name, n), omega_radps=_array(chunk, "omega_radps", name, n),
        current_left_a=_array(chunk, "current_left_a", name, n),
        current_right_a=_array(chunk, "current_right_a", name, n),
        accel_time_s=accel_t, accel_z_mps2=accel_z, pose_xyh=pose,
        ground=None if ground is None else np.asarray(ground, dtype=str),
        meta=replace(LogMeta(), robot=robot, source=name, notes=notes, velocity_source="measured"),
        gyro_z_radps=_array(chunk, "gyro_z_radps", name, accel_t.size),
        battery_voltage_v=_array(chunk, "battery_voltage_v", name, n),
        battery_current_a=_array(chunk, "battery_current_a", name, n),
    )
