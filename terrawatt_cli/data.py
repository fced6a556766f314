"""The options of the commands that read logs: ``--data``, the bag and CSV flags (:func:`energy.io.read_logs`), ``--band``."""

from __future__ import annotations

import argparse
import dataclasses
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from energy import InteractionLog
from energy.features import DEFAULT_BAND_HZ, check_band_hz
from energy.io import CSV_FIELDS, CSV_RATES, DRIVE_CLOCKS, LOG_SUFFIXES, BagTopics, CsvLayout, read_logs
from terrain import InvalidParameterError, TerrawattError

from .common import Checked, positive

__all__ = ["DATA_FLAGS", "add_data_options", "logs_from_args", "add_band_option", "band_from_args"]

_DEFAULT = BagTopics()
#: The flags of the log readers' parameters (:class:`energy.io.BagTopics`' fields, :class:`energy.io.CsvLayout`'s and
#: the ``csv`` layout as a whole), which their errors name.
DATA_FLAGS = {**{f.name: f"--{f.name.replace('_', '-')}" for f in dataclasses.fields(BagTopics)},
              "columns": "--csv-columns", "units": "--csv-units", "rates": "--csv-rates", "track_width_m": "--track-width",
              "csv": "--csv-columns / --csv-units / --csv-rates / --track-width"}


def add_data_options(parser: Any, *, grounds: bool = False) -> None:
    """Add ``--data``, ``--ground-label`` (and with ``grounds`` ``--grounds``) and the bag flags (``--cmd-vel-topic``,
    ``--imu-topic``, ``--current-topics``, ``--current-fields``, ``--voltage-field``, ``--current-unit``,
    ``--accel-unit``, ``--drive-clock``, ``--battery-topic``: the fields of :class:`energy.io.BagTopics`) and the CSV flags
    (``--csv-columns``, ``--csv-units``, ``--csv-rates``, ``--track-width``: :class:`energy.io.CsvLayout`) to a
    subcommand's parser."""
    parser.add_argument(
        "--data", type=Path, required=True, metavar="DIR|FILE",
        help=f"logs: a BorealTC folder (GROUND/imu_NN.csv + pro_NN.csv), a CSV log, a bag "
        f"({', '.join(s for s in sorted(LOG_SUFFIXES) if s != '.csv')}, ROS 2 bag folder), or a folder of CSV logs and "
        f"bags, or of ground folders of them (SNOW/run1.bag: ground 'snow')",
    )
    parser.add_argument("--ground-label", default=None, metavar="NAME",
                        help="ground label of the bags and CSV logs outside ground folders")
    if grounds:
        parser.add_argument("--grounds", nargs="+", metavar="NAME",
                            help="ground folders (or the logs' ground labels) to use (default all)")
    bags = parser.add_argument_group("bags (--data .bag, .db3, .mcap or a ROS 2 bag folder)")
    bags.add_argument("--cmd-vel-topic", default=_DEFAULT.cmd_vel_topic, metavar="TOPIC",
                      help="geometry_msgs/Twist commands or nav_msgs/Odometry (default %(default)s)")
    bags.add_argument("--imu-topic", default=_DEFAULT.imu_topic, metavar="TOPIC",
                      help="sensor_msgs/Imu (default %(default)s)")
    bags.add_argument("--current-topics", nargs="+", default=list(_DEFAULT.current_topics), metavar="TOPIC",
                      help="two std_msgs/Float64 topics (left right), or one [left, right] multi-array or status topic "
                      "(default: %(default)s); a bag without them reads without currents: enough to predict from")
    bags.add_argument("--current-fields", nargs=2, default=None, metavar=("LEFT", "RIGHT"),
                      help="current fields of the status message on the one --current-topics topic, e.g. "
                      "left_driver_current right_driver_current (husky_msgs/HuskyStatus on /status)")
    bags.add_argument("--voltage-field", default=None, metavar="FIELD",
                      help="battery voltage field of that status message, e.g. battery_voltage")
    bags.add_argument("--battery-topic", default=None, metavar="TOPIC",
                      help="sensor_msgs/BatteryState (voltage, current): the measured battery power (default none)")
    bags.add_argument("--current-unit", default=_DEFAULT.current_unit, choices=("A", "mA"),
                      help="unit of the bag's currents (default %(default)s)")
    bags.add_argument("--accel-unit", default=_DEFAULT.accel_unit, choices=("m/s^2", "g"),
                      help="unit of the bag's IMU linear_acceleration (default %(default)s; some drivers publish g)")
    bags.add_argument("--drive-clock", default=_DEFAULT.drive_clock, choices=DRIVE_CLOCKS,
                      help="drive samples at the current messages (default) or at the odometry messages, the "
                      "currents interpolated onto them (e.g. a 1 Hz status message beside 10-50 Hz odometry)")
    csv = parser.add_argument_group("CSV logs of another layout (default: the layout terrawatt writes)")
    csv.add_argument("--csv-columns", nargs="+", default=None, metavar="FIELD=COLUMN", action=Checked, check=_pairs,
                     help=f"the column of each field, e.g. time=stamp_ms v=cmd_v omega=cmd_w current_left=iL "
                     f"current_right=iR accel_z=az (fields: {', '.join(CSV_FIELDS)})")
    csv.add_argument("--csv-units", nargs="+", default=None, metavar="FIELD=UNIT", action=Checked, check=_pairs,
                     help="declared units of mapped fields, e.g. time=ms current_left=mA current_right=mA "
                     "omega=deg/s accel_z=g (default SI)")
    csv.add_argument("--csv-rates", choices=CSV_RATES, default="mixed",
                     help="mixed: IMU and drive rows of different rates interleaved by time (default); single: "
                     "one row per sample of both")
    csv.add_argument("--track-width", type=float, default=None, metavar="M", action=Checked, check=positive,
                     help="with wheel speeds (--csv-columns speed_left=... speed_right=...): the track width (m) "
                     "that derives omega; refused with v / omega columns")


def _pairs(values: Sequence[str], flag: str) -> dict[str, str]:
    """``FIELD=VALUE`` words as a mapping (each field once), or an error naming ``flag``."""
    out: dict[str, str] = {}
    for word in values:
        key, sep, value = word.partition("=")
        if not sep or not key or not value or key in out:
            raise InvalidParameterError(f"{flag} takes FIELD=VALUE words, each field once; got {word!r}")
        out[key] = value
    return out


def _csv_layout(args: argparse.Namespace) -> CsvLayout:
    """The :class:`energy.io.CsvLayout` of the CSV flags; its errors name them (a ``--track-width`` beside ``v`` /
    ``omega`` columns: its own message names it)."""
    try:
        layout = CsvLayout(args.csv_columns, args.csv_units, args.csv_rates)
    except TerrawattError as exc:
        raise type(exc)(f"--csv-columns / --csv-units: {exc}") from None
    return layout if args.track_width is None else dataclasses.replace(layout, track_width_m=args.track_width)


def logs_from_args(args: argparse.Namespace, require_currents: bool, *, flag: str = "--data") -> list[InteractionLog]:
    """The logs at ``--data`` (or at another ``flag`` read like it; of ``--grounds`` if given), read with the bag flags
    (:func:`energy.io.read_logs`: errors name the flags; with ``require_currents`` a log without currents)."""
    bag = BagTopics(**{f.name: getattr(args, f.name) for f in dataclasses.fields(BagTopics)})
    path = getattr(args, flag.lstrip("-").replace("-", "_"))
    try:
        return read_logs(path, getattr(args, "grounds", None), bag=bag, csv=_csv_layout(args),
                         require_currents=require_currents, ground_label=args.ground_label)
    except TerrawattError as exc:  # the library names its parameter `path`; here it is the flag that gave it
        names = (exc.parameter,) if isinstance(exc.parameter, str) else tuple(exc.parameter or ())
        if "path" not in names:
            raise
        others = tuple(n for n in names if n != "path")
        raise type(exc)(re.sub(r"(?<![\w-])path(?![\w-])", flag, str(exc), count=1),
                        parameter=others or None) from None


def add_band_option(parser: Any, help_text: str | None = None) -> None:
    """Add ``--band LO HI`` (two frequencies in Hz) to a subcommand's parser."""
    lo, hi = DEFAULT_BAND_HZ
    parser.add_argument("--band", nargs=2, type=float, metavar=("LO", "HI"), help=help_text or (
        f"frequency band (Hz) of the vibration features of the estimator and paper models, 0 <= LO < HI "
        f"(default: the estimator's {lo:g} {hi:g}, served by any IMU of {2 * hi:g} Hz or more; the paper's 0 50)"))


def band_from_args(args: argparse.Namespace) -> tuple[float, float] | None:
    """The checked ``--band`` (errors name it), or None without it."""
    if args.band is None:
        return None
    return check_band_hz(tuple(args.band), "--band")
