"""Readers and writers of interaction logs: BorealTC CSV, generic CSV, ROS 1/2 bags and MCAP, live ROS messages.

:func:`read_logs` reads every log at a path whatever its layout (a BorealTC folder, a CSV
log, a bag, or a folder of them); the command line's logs go through it.

Every reader returns :class:`~energy.logs.InteractionLog` objects in SI units and refuses
bad input with a clear error instead of guessing, as its ``cleaning`` (:class:`LogCleaning`:
``repair``, ``allow_gaps``, ``gap_factor``, ``check_units``) says; a bag's topics, fields and
units are one :class:`BagTopics`, its clocks one :class:`BagTiming`, a CSV log's columns and
units one :class:`CsvLayout`:

- unsorted timestamps, duplicated timestamps, NaNs (empty fields or ``nan``) -> DataError
  naming the stream, the first offending index and time, and the count; each can be
  repaired on request with ``repair=("sort", "drop_duplicates", "interpolate_nans")``
  (applied in that order; each repair is logged through ``logging.getLogger(__name__)`` and
  warned with :class:`~terrawatt_base.errors.DataRepairWarning` giving the count). NaN timestamps
  are never repaired; ``interpolate_nans`` interpolates linearly in time from the nearest
  finite samples and holds the first/last finite value at the ends.
- gaps: a step between consecutive samples of one stream larger than ``gap_factor``
  (default :data:`~energy.logs.DEFAULT_GAP_FACTOR` = 5) median periods -> DataError unless
  ``allow_gaps=True``; split such logs with :meth:`InteractionLog.split_at_gaps`.
- missing columns / topics, empty files -> DataError; a missing, unreadable or corrupt file
  (not UTF-8: the message gives the byte offset and line; a ragged row; a bad
  ``# terrawatt-log`` header) -> FileFormatError.
- unit checks (``check_units=True``), made after conversion to SI; the thresholds are
  constants of :mod:`energy.io.cleaning`:

  * current declared in A whose median |I| exceeds ``MAX_MEDIAN_CURRENT_A`` (100 A), or
    whose values are all integers reaching 100 or more, or whose 99th percentile of the
    non-zero |I| exceeds ``MAX_P99_CURRENT_A`` (300 A; zeros say nothing about the
    unit, so a side idle most of the time is still caught) -> UnitError "looks like mA";
  * current declared in mA whose peak |I| is below ``MIN_PEAK_CURRENT_A`` (0.05 A = 50 mA)
    while not all zero -> UnitError "looks like A";
  * |v| (or a wheel speed) above ``MAX_SPEED_MPS`` (10 m/s, implausible for a ground
    robot) -> UnitError "looks like mm/s or cm/s";
  * |omega| (or an IMU's gyro yaw rate) above ``MAX_OMEGA_RADPS`` (20 rad/s) -> UnitError
    "looks like deg/s"; a battery voltage above ``MAX_BATTERY_VOLTAGE_V`` (200 V) ->
    UnitError "looks like mV";
  * median |a_z| above ``MAX_MEDIAN_ACCEL_MPS2`` (50 m/s^2) -> UnitError (e.g. m/s^2
    declared as g, or mm/s^2);
  * a drive, current or IMU stream whose median rate lies outside
    [``MIN_STREAM_RATE_HZ``, ``MAX_STREAM_RATE_HZ``] (0.5 Hz to 10 kHz), or that spans more
    than ``MAX_RUN_DURATION_S`` (one day) -> UnitError "the time unit looks wrong" (e.g.
    BorealTC times in ms read as s: 0.0065 Hz over 9,385 s). Commands are event-like and
    not rate-checked.

- an IMU whose vertical acceleration has gravity removed (median within
  +/-``GRAVITY_REMOVED_MAX_MPS2`` = 3 m/s^2 instead of about +9.81) is accepted:
  ``meta.gravity_removed`` is set and ``meta.notes`` says so (the vibration features remove
  each segment's mean, so they do not need gravity) — except a median of about 1
  (``G_UNITS_BAND``): an IMU publishing in g, refused with a UnitError naming how to
  declare the unit (CSV ``units={'accel_z': 'g'}``, bags ``accel_unit='g'``).
- currents are optional where a source may lack them (a bag without current topics, a
  CSV without current columns): the log's ``has_currents`` is False and
  ``meta.missing_currents`` says what was missing; training and scoring refuse such logs
  (:meth:`~energy.logs.InteractionLog.require_currents`).
- the gyro yaw rate (``gyro_z_radps``, on the IMU clock) and the battery voltage
  (``battery_voltage_v``, on the drive clock) are read where the source has them.

Writers: :func:`write_csv_log`, and :func:`write_drive_bag` — logs (a drive or its legs, one
after another on one clock) as a ROS 2 MCAP file or a ROS 1 bag of odometry, IMU, current,
battery and GPS topics (:class:`DriveBagTopics`), which :func:`read_rosbag` reads back and
:func:`read_navsat` reads the GPS fixes of. :func:`log_from_messages` makes the log of live
ROS messages (a robot node's buffers), the log a bag of the same messages gives.

Modules: :mod:`~energy.io.cleaning` (the checks above), :mod:`~energy.io.csv_table` (CSV
decoding and parsing), :mod:`~energy.io.borealtc`, :mod:`~energy.io.csv_log` (+ its header
line, :mod:`~energy.io.csv_header`), :mod:`~energy.io.rosbag` (+ :mod:`~energy.io.bag_messages`,
:mod:`~energy.io.bag_align`), :mod:`~energy.io.layouts` (:func:`read_logs`),
:mod:`~energy.io.ros_messages` (logs to messages and back), :mod:`~energy.io.drive_bag`.
"""

from .borealtc import BOREALTC_TRACK_WIDTH_M, read_borealtc, read_borealtc_run
from .cleaning import (
    GRAVITY_REMOVED_MAX_MPS2,
    MAX_BATTERY_VOLTAGE_V,
    MAX_MEDIAN_ACCEL_MPS2,
    MAX_MEDIAN_CURRENT_A,
    MAX_OMEGA_RADPS,
    MAX_P99_CURRENT_A,
    MAX_RUN_DURATION_S,
    MAX_SPEED_MPS,
    MAX_STREAM_RATE_HZ,
    MIN_PEAK_CURRENT_A,
    MIN_STREAM_RATE_HZ,
    REPAIRS,
    LogCleaning,
)
from .csv_header import CSV_LOG_FORMAT_VERSION
from .csv_log import CSV_FIELDS, CSV_RATES, CSV_UNITS, DEFAULT_CSV_COLUMNS, CsvLayout, read_csv_log, write_csv_log
from .drive_bag import NavSatTrack, read_navsat, write_drive_bag
from .layouts import LOG_SUFFIXES, read_logs
from .ros_messages import DriveBagTopics, log_from_messages
from .rosbag import DRIVE_CLOCKS, MAX_CLOCK_OFFSET_S, BagTiming, BagTopics, read_rosbag

__all__ = [
    "REPAIRS",
    "BOREALTC_TRACK_WIDTH_M",
    "CSV_FIELDS",
    "CSV_UNITS",
    "DEFAULT_CSV_COLUMNS",
    "CSV_LOG_FORMAT_VERSION",
    "CSV_RATES",
    "MAX_MEDIAN_CURRENT_A",
    "MAX_P99_CURRENT_A",
    "MIN_PEAK_CURRENT_A",
    "MAX_SPEED_MPS",
    "MAX_OMEGA_RADPS",
    "MAX_MEDIAN_ACCEL_MPS2",
    "MIN_STREAM_RATE_HZ",
    "MAX_STREAM_RATE_HZ",
    "MAX_RUN_DURATION_S",
    "MAX_CLOCK_OFFSET_S",
    "DRIVE_CLOCKS",
    "MAX_BATTERY_VOLTAGE_V",
    "GRAVITY_REMOVED_MAX_MPS2",
    "read_borealtc_run",
    "read_borealtc",
    "read_csv_log",
    "write_csv_log",
    "read_rosbag",
    "LOG_SUFFIXES",
    "BagTopics",
    "BagTiming",
    "CsvLayout",
    "LogCleaning",
    "read_logs",
    "DriveBagTopics",
    "write_drive_bag",
    "NavSatTrack",
    "read_navsat",
    "log_from_messages",
]
