"""Aligning a bag's streams on one drive clock: currents (or odometry, or a grid), commands, IMU."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import fmt_number
from terrawatt_base.errors import DataError

from .cleaning import bracket_accel

__all__ = ["CurrentStreams", "align_streams"]


@dataclass(frozen=True)
class CurrentStreams:
    """The cleaned current streams of a bag: the left current (and the battery voltage, from
    the same messages) on ``time_s``, the right one on ``right_time_s``."""

    time_s: np.ndarray
    left_a: np.ndarray
    right_time_s: np.ndarray
    right_a: np.ndarray
    voltage_v: np.ndarray | None = None


def _span(a: float, b: float) -> str:
    return f"[{fmt_number(float(a), 9)}, {fmt_number(float(b), 9)}] s"


def align_streams(
    src: str,
    currents: CurrentStreams | None,
    velocity: tuple[np.ndarray, dict[str, np.ndarray], bool],
    imu: tuple[np.ndarray, dict[str, np.ndarray]],
    cmd_vel_timeout_s: float | None,
    drive_rate_hz: float,
    notes: list[str],
    on_currents: bool = True,
) -> dict[str, Any]:
    """The streams on the drive times, inside the overlap of the current, IMU and odometry streams.

    The drive times are the left current's times (``on_currents``); without currents, or
    with ``on_currents=False``, the odometry's times, or with commands only a uniform grid at
    ``drive_rate_hz`` (the currents and voltage then interpolated linearly onto them). The
    right current is interpolated onto them (when on its own topic), odometry interpolated (heading
    unwrapped), commands held (zero after ``cmd_vel_timeout_s`` without one). The IMU keeps
    the samples bracketing the drive span.

    Returns
    -------
    dict
        The keyword arguments of :class:`~energy.logs.InteractionLog` but its ``meta``.

    Raises
    ------
    DataError
        The streams do not overlap.
    """
    tv, vc, measured = velocity
    ti, ic = imu
    spans = [(ti[0], ti[-1])]
    if currents is not None:
        spans += [(currents.time_s[0], currents.time_s[-1]), (currents.right_time_s[0], currents.right_time_s[-1])]
    if measured:
        spans.append((tv[0], tv[-1]))
    t0 = max(s[0] for s in spans)
    t1 = min(s[1] for s in spans)
    if not measured and cmd_vel_timeout_s is None:
        t0 = max(t0, tv[0])
    on_currents = on_currents and currents is not None
    if on_currents:
        base = currents.time_s
    elif measured:
        base = tv
    else:
        base = t0 + np.arange(int(math.floor(max(t1 - t0, 0.0) * drive_rate_hz + 1e-9)) + 1) / drive_rate_hz
        notes.append(f"drive stream on a {drive_rate_hz:g} Hz grid over the overlap")
    if currents is not None and not on_currents:
        notes.append("currents (and voltage) interpolated linearly onto the velocity stream's drive times")
    keep = (base >= t0) & (base <= t1)
    if t1 < t0 or not keep.any():
        cur = "" if currents is None else f"current {_span(*spans[1])}, "
        raise DataError(
            f"{src}: the streams do not overlap ({cur}IMU {_span(*spans[0])}, velocity {_span(tv[0], tv[-1])})"
        )
    td = base[keep]
    out: dict[str, Any] = dict(time_s=td, current_left_a=None, current_right_a=None, battery_voltage_v=None)
    if currents is not None:
        def at_drive(t: np.ndarray, values: np.ndarray, own: bool) -> np.ndarray:
            return values[keep] if own else np.interp(td, t, values)

        same = on_currents and np.array_equal(currents.right_time_s, currents.time_s)
        out["current_left_a"] = at_drive(currents.time_s, currents.left_a, on_currents)
        out["current_right_a"] = at_drive(currents.right_time_s, currents.right_a, same)
        if currents.voltage_v is not None:
            out["battery_voltage_v"] = at_drive(currents.time_s, currents.voltage_v, on_currents)
    if measured:
        out["v_mps"] = np.interp(td, tv, vc["v"])
        out["omega_radps"] = np.interp(td, tv, vc["omega"])
        h = np.interp(td, tv, np.unwrap(vc["heading"]))
        out["pose_xyh"] = np.column_stack(
            [np.interp(td, tv, vc["x"]), np.interp(td, tv, vc["y"]), np.pi - np.mod(np.pi - h, 2 * np.pi)]
        )
    else:
        idx = np.searchsorted(tv, td, side="right") - 1
        valid = idx >= 0
        if cmd_vel_timeout_s is not None:
            valid &= (td - tv[np.maximum(idx, 0)]) <= cmd_vel_timeout_s
        out["v_mps"] = np.where(valid, vc["v"][np.maximum(idx, 0)], 0.0)
        out["omega_radps"] = np.where(valid, vc["omega"][np.maximum(idx, 0)], 0.0)
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
    out["accel_time_s"] = ti[acc]
    out["accel_z_mps2"] = ic["accel_z"][acc]
    out["gyro_z_radps"] = ic["gyro_z"][acc] if "gyro_z" in ic else None
    return out
