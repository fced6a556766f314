"""The interaction log: time-aligned drive, current and vibration streams of one robot run.

An :class:`InteractionLog` holds two streams that share one clock:

- the **drive stream** (``time_s``, N samples): linear speed ``v_mps``, yaw rate
  ``omega_radps`` (commanded or measured, see :attr:`LogMeta.velocity_source`), the left and
  right drive currents ``current_left_a`` / ``current_right_a`` (A; both ``None`` in a log
  read for prediction only, see :attr:`InteractionLog.has_currents`), and optionally the
  battery voltage ``battery_voltage_v`` and pack current ``battery_current_a``, the pose ``pose_xyh`` (x_m, y_m, heading_rad) and
  a per-sample ground label ``ground``;
- the **acceleration (IMU) stream** (``accel_time_s``, M samples, usually at a higher
  rate): the vertical acceleration ``accel_z_mps2`` as recorded, gravity included (about
  +9.81 m/s^2 at rest on level ground) unless ``meta.gravity_removed``; vibration features
  remove the mean themselves; and optionally the gyro's yaw rate ``gyro_z_radps`` (rad/s,
  counter-clockwise positive), the IMU's own measure of turning, against which the
  wheel-derived ``omega_radps`` shows skid.

Both time vectors are strictly increasing and finite; all arrays are float64 copies made
read-only. Changing rate is always explicit: :meth:`InteractionLog.resample` puts the drive
stream on a uniform grid over the overlap of both streams, :meth:`InteractionLog.accel_on`
interpolates the acceleration onto other timestamps. Readers for files live in
:mod:`energy.io`.
"""

from __future__ import annotations

import logging
import math
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from terrawatt_base.checks import check_choice, check_real, fmt_number
from terrawatt_base.errors import DataError, DataRepairWarning, InvalidParameterError

from .arrays import DRIVE_FIELDS, IMU_FIELDS, check_increasing, ground_array, log_vector, pose_array, stream_vector
from .gaps import DEFAULT_GAP_FACTOR, check_gap_factor, median_period_s, merged_gaps
from .joining import concatenated_fields, join_notes
from .meta import LogMeta

__all__ = ["RESAMPLE_METHODS", "InteractionLog"]

_LOG = logging.getLogger(__name__)

#: Allowed ``method`` values of :meth:`InteractionLog.resample`.
RESAMPLE_METHODS = ("linear", "previous")
#: Timestamps closer than this are the same instant for zero-order holds (s).
_TIME_TOL_S = 1e-9


@dataclass(frozen=True, eq=False, repr=False)
class InteractionLog:
    """One robot run: drive commands/speeds, drive currents, vertical acceleration and gyro yaw rate.

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Drive-stream timestamps (s), strictly increasing.
    v_mps, omega_radps : array_like, shape (N,)
        Linear speed (m/s) and yaw rate (rad/s, counter-clockwise positive); commanded or
        measured according to ``meta.velocity_source``.
    current_left_a, current_right_a : array_like, shape (N,), or None
        Left and right drive current (A). Negative values (regeneration) are allowed.
        Both ``None``: a log without currents, enough to predict from but not to train or
        score on (:meth:`require_currents`).
    accel_time_s : array_like, shape (M,)
        Acceleration-stream timestamps (s), strictly increasing, same clock as ``time_s``.
    accel_z_mps2 : array_like, shape (M,)
        Vertical acceleration (m/s^2) as recorded, gravity included.
    pose_xyh : array_like, shape (N, 3), optional
        x_m, y_m, heading_rad at the drive timestamps.
    ground : array_like of str, shape (N,), optional
        Ground label of each drive sample.
    meta : LogMeta
        Run-level metadata.
    gyro_z_radps : array_like, shape (M,), optional
        Gyro yaw rate (rad/s, counter-clockwise positive) at the acceleration timestamps.
    battery_voltage_v : array_like, shape (N,), optional
        Battery voltage (V, >= 0) at the drive timestamps; current x voltage is the battery power.
    battery_current_a : array_like, shape (N,), optional
        Pack current at the battery (A) at the drive timestamps, positive when discharging;
        it includes the electronics. Needs ``battery_voltage_v``: their product is the
        measured battery power (:attr:`battery_power_w`).

    Raises
    ------
    InvalidParameterError
        Wrong shapes, lengths or types; a pack current without a battery voltage.
    DataError
        Empty streams, non-finite values, timestamps not strictly increasing, a negative
        battery voltage.

    Notes
    -----
    Arrays are copied to float64 and made read-only. Equality is identity (``eq=False``):
    compare the arrays themselves. ``len(log)`` is the number of drive samples.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(5) * 0.1
    >>> log = InteractionLog(t, np.full(5, 0.5), np.zeros(5), np.full(5, 2.0), np.full(5, 2.1),
    ...                      np.arange(50) * 0.01, np.full(50, 9.81))
    >>> len(log), round(log.drive_rate_hz, 6), round(log.accel_rate_hz, 6)
    (5, 10.0, 100.0)
    """

    time_s: np.ndarray
    v_mps: np.ndarray
    omega_radps: np.ndarray
    current_left_a: np.ndarray
    current_right_a: np.ndarray
    accel_time_s: np.ndarray
    accel_z_mps2: np.ndarray
    pose_xyh: np.ndarray | None = None
    ground: np.ndarray | None = None
    meta: LogMeta = field(default_factory=LogMeta)
    gyro_z_radps: np.ndarray | None = None
    battery_voltage_v: np.ndarray | None = None
    battery_current_a: np.ndarray | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for clock, names in (("time_s", DRIVE_FIELDS), ("accel_time_s", IMU_FIELDS)):
            t = log_vector(clock, getattr(self, clock))
            check_increasing(clock, t)
            set_(self, clock, t)
            for name in names:
                set_(self, name, stream_vector(name, getattr(self, name), t.size, clock))
        if (self.current_left_a is None) != (self.current_right_a is None):
            raise InvalidParameterError(
                "current_left_a and current_right_a must both be arrays or both be None, got "
                f"{'None' if self.current_left_a is None else 'an array'} and "
                f"{'None' if self.current_right_a is None else 'an array'}"
            )
        if self.battery_current_a is not None and self.battery_voltage_v is None:
            raise InvalidParameterError(
                "battery_current_a (the pack current) needs battery_voltage_v too: the battery power is their "
                "product; give both or neither"
            )
        if self.battery_voltage_v is not None and np.any(self.battery_voltage_v < 0):
            i = int(np.argmax(self.battery_voltage_v < 0))
            raise DataError(f"battery_voltage_v must be >= 0 V; index {i} holds "
                            f"{fmt_number(float(self.battery_voltage_v[i]), 6)} V")
        n = len(self.time_s)
        if self.pose_xyh is not None:
            set_(self, "pose_xyh", pose_array(self.pose_xyh, n))
        if self.ground is not None:
            set_(self, "ground", ground_array(self.ground, n))
        if not isinstance(self.meta, LogMeta):
            raise InvalidParameterError(f"meta must be a LogMeta, got {self.meta!r}")

    # ------------------------------------------------------------------ basics
    def __len__(self) -> int:
        return int(self.time_s.size)

    def __repr__(self) -> str:
        def rate(t: np.ndarray) -> str:
            return f"{1.0 / median_period_s(t):.4g} Hz" if t.size > 1 else "single sample"

        return (
            f"InteractionLog(robot={self.meta.robot!r}, ground={self.meta.ground_label!r}, "
            f"velocity={self.meta.velocity_source}, drive={len(self)} samples @ {rate(self.time_s)}, "
            f"accel={self.accel_time_s.size} samples @ {rate(self.accel_time_s)}, "
            f"t=[{self.time_s[0]:.3f}, {self.time_s[-1]:.3f}] s, source={self.meta.source!r})"
        )

    @property
    def has_currents(self) -> bool:
        """Whether the log holds measured drive currents (a log read for prediction may not)."""
        return self.current_left_a is not None

    @property
    def has_battery_power(self) -> bool:
        """Whether the log holds battery voltage and pack current (the measured battery power)."""
        return self.battery_current_a is not None

    @property
    def battery_power_w(self) -> np.ndarray | None:
        """Measured battery power ``battery_voltage_v * battery_current_a`` (W), or None."""
        if self.battery_current_a is None:
            return None
        return self.battery_voltage_v * self.battery_current_a

    def require_currents(self, purpose: str) -> None:
        """Raise unless the log holds drive currents.

        Parameters
        ----------
        purpose : str
            What needs them, for the message (e.g. ``"training"``: "training needs measured
            drive currents, and ...").

        Raises
        ------
        DataError
            The log has no currents; the message names the source, what it lacked
            (``meta.missing_currents``) and the options that read currents.
        """
        if self.current_left_a is None:
            lacked = f" ({self.meta.missing_currents})" if self.meta.missing_currents else ""
            raise DataError(
                f"{self.meta.source}: {purpose} needs measured drive currents, and this log has none{lacked}; "
                f"read it with its current topics (current_topics) or the status message's current fields "
                f"(current_fields)", parameter=("current_topics", "current_fields")
            )

    @property
    def duration_s(self) -> float:
        """Span of the drive stream, last minus first timestamp (s)."""
        return float(self.time_s[-1] - self.time_s[0])

    @property
    def drive_rate_hz(self) -> float:
        """Drive-stream rate: 1 / median sampling period (Hz). DataError with < 2 samples."""
        if self.time_s.size < 2:
            raise DataError("drive_rate_hz needs at least 2 drive samples, the log has 1")
        return 1.0 / median_period_s(self.time_s)

    @property
    def accel_rate_hz(self) -> float:
        """Acceleration-stream rate: 1 / median sampling period (Hz). DataError with < 2 samples."""
        if self.accel_time_s.size < 2:
            raise DataError("accel_rate_hz needs at least 2 acceleration samples, the log has 1")
        return 1.0 / median_period_s(self.accel_time_s)

    @property
    def ground_labels(self) -> np.ndarray | None:
        """Ground label per drive sample: ``ground`` if set, else ``meta.ground_label``
        repeated, else ``None``."""
        if self.ground is not None:
            return self.ground
        if self.meta.ground_label is not None:
            out = np.full(len(self), self.meta.ground_label)
            out.setflags(write=False)
            return out
        return None

    def overlap_s(self) -> tuple[float, float]:
        """Time interval covered by both streams, ``(start_s, end_s)``.

        Raises
        ------
        DataError
            The streams do not overlap.
        """
        t0 = max(float(self.time_s[0]), float(self.accel_time_s[0]))
        t1 = min(float(self.time_s[-1]), float(self.accel_time_s[-1]))
        if t1 < t0:
            raise DataError(
                f"drive stream [{fmt_number(float(self.time_s[0]), 9)}, {fmt_number(float(self.time_s[-1]), 9)}] s and acceleration stream "
                f"[{fmt_number(float(self.accel_time_s[0]), 9)}, {fmt_number(float(self.accel_time_s[-1]), 9)}] s do not overlap"
            )
        return t0, t1

    # --------------------------------------------------------------- resampling
    def accel_on(self, time_s: Any) -> np.ndarray:
        """Vertical acceleration linearly interpolated onto other timestamps.

        Parameters
        ----------
        time_s : array_like
            Timestamps (s) within ``[accel_time_s[0], accel_time_s[-1]]``.

        Returns
        -------
        numpy.ndarray
            Acceleration (m/s^2), same shape as ``time_s``.

        Raises
        ------
        DataError
            A timestamp is non-finite or outside the acceleration record (no extrapolation).
        """
        t = np.asarray(time_s, dtype=np.float64)
        bad = ~np.isfinite(t) | (t < self.accel_time_s[0]) | (t > self.accel_time_s[-1])
        if bad.any():
            flat = t.reshape(-1)
            i = int(np.argmax(bad.reshape(-1)))
            raise DataError(
                f"accel_on: {int(bad.sum())} timestamp(s) outside the acceleration record "
                f"[{fmt_number(float(self.accel_time_s[0]), 9)}, {fmt_number(float(self.accel_time_s[-1]), 9)}] s, first at index {i} "
                f"(t={fmt_number(float(flat[i]), 9)}); the acceleration is not extrapolated"
            )
        return np.interp(t, self.accel_time_s, self.accel_z_mps2)

    def gyro_z_on(self, time_s: Any) -> np.ndarray:
        """Gyro yaw rate (rad/s) linearly interpolated onto other timestamps (e.g. the drive
        times, to set it against ``omega_radps``).

        Raises
        ------
        DataError
            The log has no gyro stream, or a timestamp outside the IMU record (as
            :meth:`accel_on`).
        """
        if self.gyro_z_radps is None:
            raise DataError(
                f"{self.meta.source}: the log has no gyro yaw rate (gyro_z_radps); read it from an IMU "
                f"that records angular_velocity.z (BorealTC 'wz', a bag's sensor_msgs/Imu)"
            )
        self.accel_on(time_s)  # the same range check
        return np.interp(np.asarray(time_s, dtype=np.float64), self.accel_time_s, self.gyro_z_radps)

    def resample(self, rate_hz: float, method: str = "linear") -> InteractionLog:
        """The drive stream on a uniform grid over the overlap of both streams.

        The grid is ``t0 + k / rate_hz`` for ``k = 0, 1, ...`` while ``<= t1``, with
        ``[t0, t1]`` the overlap of the drive and acceleration streams. Speeds, currents,
        battery voltage and pack current and x/y are interpolated linearly (``"linear"``) or held from the last sample at or
        before each grid time (``"previous"``, zero-order hold, right for commands; a sample
        less than 1 ns after a grid time counts as at it, absorbing float rounding);
        heading is unwrapped before interpolation and wrapped to (-pi, pi] after; ground
        labels are always held (``"previous"``). The IMU stream (acceleration, gyro) keeps its own rate:
        its samples from the last one at or before ``t0`` to the first one at or after the
        last grid time are kept, so :meth:`accel_on` works on every new drive time.
        Interpolation does not know about gaps: split at gaps first if the log has any.

        Parameters
        ----------
        rate_hz : float
            New drive rate (Hz), > 0.
        method : {"linear", "previous"}

        Returns
        -------
        InteractionLog

        Raises
        ------
        InvalidParameterError
            ``rate_hz`` not a finite number > 0.
        UnknownNameError
            ``method`` is not one of :data:`RESAMPLE_METHODS`.
        DataError
            The streams do not overlap.
        """
        rate_hz = check_real("rate_hz", rate_hz, low=0.0, low_inclusive=False)
        check_choice("method", method, RESAMPLE_METHODS)
        t0, t1 = self.overlap_s()
        n = int(math.floor((t1 - t0) * rate_hz + 1e-9)) + 1
        grid = t0 + np.arange(n, dtype=np.float64) / float(rate_hz)
        # a sample up to _TIME_TOL_S after a grid time counts as at it (float rounding of
        # e.g. k * 0.1 vs k / 10); >= 0 since grid >= time_s[0]
        held = np.searchsorted(self.time_s, grid + _TIME_TOL_S, side="right") - 1

        def take(values: np.ndarray | None) -> np.ndarray | None:
            if values is None:
                return None
            if method == "linear":
                return np.interp(grid, self.time_s, values)
            return values[held]

        pose = None
        if self.pose_xyh is not None:
            heading = np.unwrap(self.pose_xyh[:, 2])
            h = take(heading)
            h = np.pi - np.mod(np.pi - h, 2 * np.pi)  # wrap to (-pi, pi]
            pose = np.column_stack([take(self.pose_xyh[:, 0]), take(self.pose_xyh[:, 1]), h])
        ground = None if self.ground is None else self.ground[held]
        ia = max(int(np.searchsorted(self.accel_time_s, grid[0], side="right")) - 1, 0)
        ib = min(int(np.searchsorted(self.accel_time_s, grid[-1], side="left")), self.accel_time_s.size - 1)
        note = f"resampled drive stream to {float(rate_hz):g} Hz ({method}) over [{t0:g}, {t1:g}] s"
        imu = {name: None if getattr(self, name) is None else getattr(self, name)[ia : ib + 1] for name in IMU_FIELDS}
        return InteractionLog(
            time_s=grid,
            **{name: take(getattr(self, name)) for name in DRIVE_FIELDS},
            accel_time_s=self.accel_time_s[ia : ib + 1],
            **imu,
            pose_xyh=pose,
            ground=ground,
            meta=replace(self.meta, notes=join_notes(self.meta.notes, note)),
        )

    # ---------------------------------------------------------- cutting, joining
    def slice(self, t0_s: float, t1_s: float) -> InteractionLog:
        """The samples of both streams with ``t0_s <= t < t1_s`` (times are not shifted).

        Raises
        ------
        InvalidParameterError
            Non-finite bounds or ``t1_s <= t0_s``.
        DataError
            The window holds no drive or no acceleration sample.
        """
        t0_s = check_real("t0_s", t0_s)
        t1_s = check_real("t1_s", t1_s)
        if not t1_s > t0_s:
            raise InvalidParameterError(f"t1_s must be > t0_s, got t0_s={t0_s!r}, t1_s={t1_s!r}")
        # both clocks are strictly increasing: the window is a contiguous range of each (no mask over the run)
        d = slice(*np.searchsorted(self.time_s, [t0_s, t1_s], side="left").tolist())
        a = slice(*np.searchsorted(self.accel_time_s, [t0_s, t1_s], side="left").tolist())
        if d.stop <= d.start or a.stop <= a.start:
            which = "drive" if d.stop <= d.start else "acceleration"
            raise DataError(f"slice [{t0_s!r}, {t1_s!r}) s holds no {which} sample")
        return self._subset(d, a)

    def _subset(self, d: np.ndarray | slice, a: np.ndarray | slice, note: str = "") -> InteractionLog:
        def cut(name: str, mask: np.ndarray | slice) -> np.ndarray | None:
            values = getattr(self, name)
            return None if values is None else values[mask]

        return InteractionLog(
            time_s=self.time_s[d],
            **{name: cut(name, d) for name in (*DRIVE_FIELDS, "pose_xyh", "ground")},
            accel_time_s=self.accel_time_s[a],
            **{name: cut(name, a) for name in IMU_FIELDS},
            meta=replace(self.meta, notes=join_notes(self.meta.notes, note)) if note else self.meta,
        )

    def shifted(self, offset_s: float) -> InteractionLog:
        """The same log with ``offset_s`` added to both time vectors (e.g. before
        :meth:`concatenate` of runs that each start at zero)."""
        offset_s = check_real("offset_s", offset_s)
        return replace(self, time_s=self.time_s + offset_s, accel_time_s=self.accel_time_s + offset_s)

    def split_at_gaps(self, gap_factor: float = DEFAULT_GAP_FACTOR) -> list[InteractionLog]:
        """Split the run where either stream has a gap.

        A gap is a step between consecutive samples of one stream larger than
        ``gap_factor`` times that stream's median period. The run is cut inside every gap
        of either stream; samples of the other stream lying strictly inside a gap, and
        pieces left without a drive or an acceleration sample, are dropped — counted,
        logged and warned with :class:`DataRepairWarning` (the caller asked for the split).

        Returns
        -------
        list of InteractionLog
            The pieces in time order (a single element when there is no gap).

        Raises
        ------
        InvalidParameterError
            ``gap_factor`` not a number > 1.
        DataError
            No piece keeps both streams.
        """
        gap_factor = check_gap_factor(gap_factor)
        merged = merged_gaps((self.time_s, self.accel_time_s), gap_factor)
        if not merged:
            return [self]
        starts = [-math.inf] + [b for _, b in merged]
        ends = [a for a, _ in merged] + [math.inf]
        pieces: list[InteractionLog] = []
        kept_d = kept_a = 0
        empty = 0
        for k, (lo, hi) in enumerate(zip(starts, ends)):
            d = (self.time_s >= lo) & (self.time_s <= hi)
            a = (self.accel_time_s >= lo) & (self.accel_time_s <= hi)
            if not d.any() or not a.any():
                empty += 1
                continue
            kept_d += int(d.sum())
            kept_a += int(a.sum())
            pieces.append(self._subset(d, a, f"piece {k} of a split at gaps > {gap_factor:g} median periods"))
        dropped_d = len(self) - kept_d
        dropped_a = self.accel_time_s.size - kept_a
        msg = (
            f"split_at_gaps: {len(merged)} gap(s) (> {gap_factor:g} median periods) -> {len(pieces)} piece(s); "
            f"dropped {dropped_d} drive and {dropped_a} acceleration sample(s) inside gaps or in "
            f"{empty} piece(s) lacking one stream"
        )
        if not pieces:
            raise DataError(msg + "; no piece keeps both streams")
        _LOG.info(msg)
        if dropped_d or dropped_a or empty:
            warnings.warn(msg, DataRepairWarning, stacklevel=2)
        return pieces

    @classmethod
    def concatenate(cls, logs: Sequence[InteractionLog] | Iterable[InteractionLog]) -> InteractionLog:
        """Join logs of one robot, in time order, into one log.

        Each log must start (both streams) after the previous one ends; use
        :meth:`shifted` to put separate runs that each start at zero one after another.
        The joined log keeps the gaps between them. Pose, per-sample ground, currents,
        battery voltage, pack current and gyro must be present in all logs or in none; a log without ``ground`` but with a
        ``meta.ground_label`` contributes that label. The metadata keep the common robot,
        velocity source and track width (these must agree), the ground label when all
        agree (else ``None``), and the distinct sources joined by ``"; "``.

        Raises
        ------
        InvalidParameterError
            No logs, or an element that is not an InteractionLog.
        DataError
            Overlapping or out-of-order logs; disagreeing robot, velocity source or track
            width; pose, ground, currents, voltage or gyro present in some logs only.
        """
        items = list(logs)
        if not items:
            raise InvalidParameterError("concatenate needs at least one InteractionLog, got none")
        for i, log in enumerate(items):
            if not isinstance(log, InteractionLog):
                raise InvalidParameterError(f"logs[{i}] must be an InteractionLog, got {log!r:.80}")
        return cls(**concatenated_fields(items))
