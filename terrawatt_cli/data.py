"""The ``--data`` option and the bag flags of the commands that read logs (:func:`energy.io.read_logs`)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from energy import InteractionLog
from energy.io import DRIVE_CLOCKS, LOG_SUFFIXES, BagTopics, read_logs

__all__ = ["add_data_options", "logs_from_args"]

_DEFAULT = BagTopics()


def add_data_options(parser: Any) -> None:
    """Add ``--data``, ``--ground-label`` and the bag flags (``--cmd-vel-topic``, ``--imu-topic``, ``--current-topics``,
    ``--current-fields``, ``--voltage-field``, ``--current-unit``, ``--drive-clock``) to a subcommand's parser."""
    parser.add_argument(
        "--data", type=Path, required=True, metavar="DIR|FILE",
        help=f"logs: a BorealTC folder (GROUND/imu_NN.csv + pro_NN.csv), a CSV log, a bag "
        f"({', '.join(s for s in sorted(LOG_SUFFIXES) if s != '.csv')}, ROS 2 bag folder), or a folder of CSV logs and "
        f"bags, or of ground folders of them (SNOW/run1.bag: ground 'snow')",
    )
    parser.add_argument("--ground-label", default=None, metavar="NAME",
                        help="ground label of the bags and CSV logs outside ground folders")
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
    bags.add_argument("--current-unit", default=_DEFAULT.current_unit, choices=("A", "mA"),
                      help="unit of the bag's currents (default %(default)s)")
    bags.add_argument("--accel-unit", default=_DEFAULT.accel_unit, choices=("m/s^2", "g"),
                      help="unit of the bag's IMU linear_acceleration (default %(default)s; some drivers publish g)")
    bags.add_argument("--drive-clock", default=_DEFAULT.drive_clock, choices=DRIVE_CLOCKS,
                      help="drive samples at the current messages (default) or at the odometry messages, the "
                      "currents interpolated onto them (e.g. a 1 Hz status message beside 10-50 Hz odometry)")


def logs_from_args(args: argparse.Namespace, require_currents: bool, *, flag: str = "--data") -> list[InteractionLog]:
    """The logs at ``--data`` (or at the path of another ``flag`` read like it, e.g.
    ``--calibration-data``; of ``--grounds`` when the command has it), read with the bag flags.

    Raises
    ------
    TerrawattError
        As :func:`energy.io.read_logs` (messages name ``--data`` and the flags); with
        ``require_currents`` a log without currents.
    """
    bag = BagTopics(
        cmd_vel_topic=args.cmd_vel_topic,
        imu_topic=args.imu_topic,
        current_topics=tuple(args.current_topics),
        current_fields=None if args.current_fields is None else tuple(args.current_fields),
        voltage_field=args.voltage_field,
        current_unit=args.current_unit,
        accel_unit=args.accel_unit,
        drive_clock=args.drive_clock,
    )
    path = getattr(args, flag.lstrip("-").replace("-", "_"))
    return read_logs(path, getattr(args, "grounds", None), bag=bag, require_currents=require_currents,
                     ground_label=args.ground_label, name=flag)
