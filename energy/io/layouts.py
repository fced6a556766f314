"""Every log at a path, whatever its layout: a BorealTC folder, a CSV log, a bag, or a folder of them."""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from terrawatt_base.checks import check_bool, check_choice, check_text
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError

from ..logs import DEFAULT_GAP_FACTOR, InteractionLog
from .borealtc import BOREALTC_TRACK_WIDTH_M, read_borealtc
from .cleaning import UNIT_FACTORS, check_track_width
from .csv_log import CSV_RATES, DEFAULT_CSV_COLUMNS, csv_field_map, read_csv_log
from .rosbag import DRIVE_CLOCKS, read_rosbag

__all__ = ["LOG_SUFFIXES", "BagTopics", "CsvLayout", "read_logs"]

#: File suffixes :func:`read_logs` reads, and the reader of each.
LOG_SUFFIXES = {".csv": "csv", ".bag": "bag", ".db3": "bag", ".mcap": "bag"}
#: What needs measured currents, for the message of :func:`read_logs` with ``require_currents``.
_NEEDS_CURRENTS = "training, evaluation or diagnosis"


@dataclass(frozen=True)
class BagTopics:
    """Where a bag keeps its streams: the topics and message fields :func:`~energy.io.read_rosbag` reads,
    and whose times the drive stream takes.

    Parameters
    ----------
    cmd_vel_topic : str
        Commands (``geometry_msgs/Twist``) or wheel odometry (``nav_msgs/Odometry``).
    imu_topic : str
        ``sensor_msgs/Imu``.
    current_topics : tuple of str
        Two ``std_msgs/Float*`` topics (left, right), or one multi-array or status topic.
    current_fields : (str, str) or None
        Left and right current fields of a status message on the one current topic, e.g.
        ``("left_driver_current", "right_driver_current")`` for ``husky_msgs/HuskyStatus``.
    voltage_field : str or None
        Battery voltage field of that status message (e.g. ``"battery_voltage"``).
    current_unit : {"A", "mA"}
    accel_unit : {"m/s^2", "m/s2", "g"}
        Unit of the IMU's ``linear_acceleration`` (some drivers publish g).
    drive_clock : {"currents", "velocity"}
        The drive stream on the current messages' times, or on the odometry's (currents
        interpolated onto them: a 1 Hz status message beside 10-50 Hz odometry).
    battery_topic : str or None
        A ``sensor_msgs/BatteryState`` topic: battery voltage and pack current on the drive
        clock, read when the bag has it (see :func:`~energy.io.read_rosbag`).

    Raises
    ------
    InvalidParameterError, UnknownNameError
        Empty or non-string names, the wrong number of topics or fields, a voltage field
        without current fields, a voltage field beside a battery topic, an unknown unit.

    Examples
    --------
    >>> BagTopics(cmd_vel_topic="/odometry/filtered", current_topics=("/status",),
    ...           current_fields=("left_driver_current", "right_driver_current")).current_topics
    ('/status',)
    """

    cmd_vel_topic: str = "/cmd_vel"
    imu_topic: str = "/imu/data"
    current_topics: tuple[str, ...] = ("/drive/current_left", "/drive/current_right")
    current_fields: tuple[str, str] | None = None
    voltage_field: str | None = None
    current_unit: str = "A"
    accel_unit: str = "m/s^2"
    drive_clock: str = "currents"
    battery_topic: str | None = None

    def __post_init__(self) -> None:
        check_text("cmd_vel_topic", self.cmd_vel_topic)
        check_text("imu_topic", self.imu_topic)
        topics = _names("current_topics", self.current_topics, (1, 2))
        object.__setattr__(self, "current_topics", topics)
        if self.current_fields is not None:
            object.__setattr__(self, "current_fields", _names("current_fields", self.current_fields, (2,)))
            if len(topics) != 1:
                raise InvalidParameterError(
                    f"current_fields (--current-fields) read one status topic; give one current topic "
                    f"(current_topics, --current-topics), got {topics!r}"
                )
        if self.voltage_field is not None:
            check_text("voltage_field", self.voltage_field)
            if self.current_fields is None:
                raise InvalidParameterError(
                    "voltage_field (--voltage-field) is read beside the currents of a status message: name them "
                    "too with current_fields (--current-fields)"
                )
        check_choice("current_unit", self.current_unit, tuple(UNIT_FACTORS["current"]))
        check_choice("accel_unit", self.accel_unit, tuple(UNIT_FACTORS["accel"]))
        check_choice("drive_clock", self.drive_clock, DRIVE_CLOCKS)
        if self.battery_topic is not None:
            check_text("battery_topic", self.battery_topic)
            if self.voltage_field is not None:
                raise InvalidParameterError(
                    f"battery_topic {self.battery_topic!r} and voltage_field {self.voltage_field!r} (--voltage-field) "
                    "both give the battery voltage; name one of them"
                )


def _names(name: str, value: Any, counts: tuple[int, ...]) -> tuple[str, ...]:
    items = (value,) if isinstance(value, str) else tuple(value) if isinstance(value, Iterable) else (value,)
    if len(items) not in counts or not all(isinstance(x, str) and x for x in items):
        raise InvalidParameterError(
            f"{name} must be {' or '.join(map(str, counts))} non-empty name(s), got {value!r:.80}"
        )
    return items


@dataclass(frozen=True)
class CsvLayout:
    """How the CSV logs :func:`read_logs` meets name their columns and units (as :func:`~energy.io.read_csv_log`
    takes them); the default is the layout :func:`~energy.io.write_csv_log` writes.

    Parameters
    ----------
    columns : mapping field -> column name, optional
        The column of each field (:data:`~energy.io.CSV_FIELDS`: ``time``, ``accel_z``, ``v`` and
        ``omega`` or ``speed_left`` and ``speed_right``, ``current_left`` and ``current_right``,
        optional ``x`` / ``y`` / ``heading``, ``gyro_z``, ``battery_voltage``, ``battery_current``,
        ``ground``).
    units : mapping field -> unit, optional
        Declared units of the mapped fields (:data:`~energy.io.CSV_UNITS`); undeclared fields are SI.
    rates : {"mixed", "single"}
        Streams of different rates interleaved by time (default), or one row per sample of both.
    track_width_m : float, optional
        With wheel speeds (``speed_left`` / ``speed_right``): the track width that gives omega.
        Only then: a layout of ``v`` and ``omega`` has no omega to derive, so a track width
        there is refused (when the layout is made; with the default layout, when a CSV log is
        read) rather than recorded as the one omega came from.

    Raises
    ------
    UnknownNameError, InvalidParameterError
        An unknown field, unit or ``rates``, an empty column name, a unit for a field not mapped, a
        bad track width or one beside ``v`` / ``omega`` columns; checked when the layout is made,
        before any log is read (a track width with the default layout: by :meth:`read`).

    Examples
    --------
    >>> CsvLayout({"time": "stamp_ms", "v": "cmd_v", "omega": "cmd_w", "accel_z": "az"}, {"time": "ms"}).rates
    'mixed'
    """

    columns: dict[str, str] | None = None
    units: dict[str, str] | None = None
    rates: str = "mixed"
    track_width_m: float | None = None

    def __post_init__(self) -> None:
        if self.columns is None and self.units:
            raise InvalidParameterError("units need columns: the default layout's columns are in SI units")
        if self.columns is not None:
            columns, units, _ = csv_field_map(self.columns, self.units)
            object.__setattr__(self, "columns", columns)
            object.__setattr__(self, "units", units)
        check_choice("rates", self.rates, CSV_RATES)
        if self.track_width_m is not None:
            object.__setattr__(self, "track_width_m", check_track_width(self.track_width_m))
            if self.columns is not None:
                self._check_track_width()

    def _check_track_width(self) -> None:
        """Refuse a track width beside v / omega columns: there is no omega to derive with it."""
        columns = DEFAULT_CSV_COLUMNS if self.columns is None else self.columns
        if self.track_width_m is None or "speed_left" in columns or "speed_right" in columns:
            return
        whose = "the default layout's" if self.columns is None else "the layout's"
        raise InvalidParameterError(
            f"track_width_m (--track-width) {self.track_width_m:g} derives omega from wheel speeds (speed_left / "
            f"speed_right columns), but {whose} velocities are v and omega ({columns.get('v')!r}, "
            f"{columns.get('omega')!r}): there is no omega to derive; drop the track width, or map the wheel speeds "
            "instead (--csv-columns speed_left=COLUMN speed_right=COLUMN)")

    def read(self, path: str | os.PathLike[str], **options: Any) -> InteractionLog:
        """:func:`~energy.io.read_csv_log` of ``path`` in this layout (``options``: its other keywords).

        Raises
        ------
        InvalidParameterError
            A track width with the default layout (v and omega columns), refused here rather
            than when the layout was made, as it may be meant for logs of another kind.
        """
        self._check_track_width()
        return read_csv_log(path, self.columns, self.units, rates=self.rates, track_width_m=self.track_width_m,
                            **options)


def read_logs(
    path: str | os.PathLike[str],
    grounds: Sequence[str] | None = None,
    *,
    bag: BagTopics | None = None,
    csv: CsvLayout | None = None,
    require_currents: bool = False,
    robot: str = "unknown",
    ground_label: str | None = None,
    repair: str | Iterable[str] = (),
    allow_gaps: bool = False,
    gap_factor: float = DEFAULT_GAP_FACTOR,
    check_units: bool = True,
    name: str = "path",
) -> list[InteractionLog]:
    """Every interaction log at ``path``, whatever its layout.

    ``path`` may be a BorealTC folder (``GROUND/imu_NN.csv`` + ``pro_NN.csv``), a generic
    CSV log (:func:`~energy.io.read_csv_log`), a bag (``.bag``, ``.db3``, ``.mcap`` or a ROS 2
    bag folder, read with ``bag``'s topics by :func:`~energy.io.read_rosbag`), or a folder of
    CSV logs and bags (read in name order) — or of ground folders of them (``SNOW/run1.bag``:
    the folder name, lowercased, is their ground label).

    Parameters
    ----------
    path : path-like
    grounds : sequence of str, optional
        Grounds to keep (case-insensitive): BorealTC ground folders, or the ground labels
        of the other logs. All by default.
    bag : BagTopics, optional
        Topics and fields of the bags (default :class:`BagTopics`).
    csv : CsvLayout, optional
        Columns and units of the CSV logs (default: the layout :func:`~energy.io.write_csv_log` writes);
        refused where no CSV log is read.
    require_currents : bool
        Refuse a log without drive currents (for training, evaluation and diagnosis); by
        default such logs (a bag with no current topic) are read, enough to predict from.
    robot : str
        Robot name of the bags' and CSV logs' metadata (when the file does not say).
    ground_label : str, optional
        Ground label of the bags and CSV logs outside ground folders (a CSV header's label
        otherwise; BorealTC runs take their folder's).
    repair, allow_gaps, gap_factor, check_units
        See :mod:`energy.io`.
    name : str
        The name of ``path`` in messages (the CLI passes ``"--data"``).

    Returns
    -------
    list of InteractionLog

    Raises
    ------
    DataError
        ``path`` does not exist, a folder without logs, an unknown file type; with
        ``require_currents`` a log without currents (the message names what its source
        lacked and the options that read currents); plus everything the readers raise.
    UnknownNameError
        A requested ground that no log has.
    InvalidParameterError
        ``bag`` not a BagTopics, ``csv`` not a CsvLayout, bad flags; a ``csv`` layout other
        than the default where no CSV log is read (a BorealTC folder, bags only), which it
        would not apply to.

    Examples
    --------
    Usage (needs data, so not run as a doctest)::

        logs = read_logs("husky.bag", bag=BagTopics(cmd_vel_topic="/odometry/filtered",
            current_topics=("/status",), current_fields=("left_driver_current", "right_driver_current"),
            voltage_field="battery_voltage"))
    """
    check_text("name", name)
    if ground_label is not None:
        check_text("ground_label", ground_label)
    require_currents = check_bool("require_currents", require_currents)
    if bag is None:
        bag = BagTopics()
    if not isinstance(bag, BagTopics):
        raise InvalidParameterError(f"bag must be a BagTopics, got {bag!r:.80}")
    if csv is None:
        csv = CsvLayout()
    if not isinstance(csv, CsvLayout):
        raise InvalidParameterError(f"csv must be a CsvLayout, got {csv!r:.80}")
    wanted = _grounds(grounds)
    root = Path(path)
    common = dict(repair=repair, allow_gaps=allow_gaps, gap_factor=gap_factor, check_units=check_units)
    if not root.exists():
        raise DataError(f"{name} {str(root)!r} does not exist; expected a log file or a folder of logs")
    if not (root.is_file() or root.is_dir()):  # a FIFO, a socket, a device: reading would block or never end
        raise DataError(f"{name} {str(root)!r} is neither a regular file nor a folder; expected a log file or a "
                        "folder of logs")

    def one(item: Path, label: str | None = ground_label) -> InteractionLog:
        if LOG_SUFFIXES.get(item.suffix.lower()) == "csv":
            return csv.read(item, robot=None if robot == "unknown" else robot, ground_label=label, **common)
        return read_rosbag(item, bag.cmd_vel_topic, bag.imu_topic, bag.current_topics, battery_topic=bag.battery_topic,
                           current_fields=bag.current_fields,
                           voltage_field=bag.voltage_field, current_unit=bag.current_unit, accel_unit=bag.accel_unit,
                           drive_clock=bag.drive_clock, robot=robot,
                           ground_label=label, **common)

    if root.is_file():
        if root.suffix.lower() not in LOG_SUFFIXES:
            raise DataError(f"{name} {str(root)!r}: unknown log file type {root.suffix!r}; expected one of "
                            f"{sorted(LOG_SUFFIXES)!r} or a folder")
        items = [(root, ground_label)]
    elif (root / "metadata.yaml").exists():
        items = [(root, ground_label)]  # a ROS 2 bag folder
    elif any(sub.is_dir() and any(sub.glob("imu_*.csv")) for sub in root.iterdir()):
        _no_csv_layout(csv, f"{name} {str(root)!r} is read as a BorealTC folder (GROUND/imu_NN.csv + pro_NN.csv), "
                            f"whose columns, units and track width ({BOREALTC_TRACK_WIDTH_M:g} m) are the format's own")
        return _required(read_borealtc(root, grounds=grounds, **common), require_currents)
    else:
        items = [(p, ground_label) for p in _log_items(root)]
        for sub in sorted(p for p in root.iterdir() if p.is_dir() and not (p / "metadata.yaml").exists()):
            items += [(p, sub.name.lower()) for p in _log_items(sub)]  # a ground folder
        if not items:
            raise DataError(f"{name} {str(root)!r} holds no logs: expected BorealTC ground folders, log files "
                            f"({', '.join(sorted(LOG_SUFFIXES))}), ROS 2 bag folders, or ground folders of them")
    if not any(LOG_SUFFIXES.get(p.suffix.lower()) == "csv" for p, _ in items):
        _no_csv_layout(csv, f"{name} {str(root)!r} holds no CSV log, only bags (read with the bag options)")
    logs = [one(p, label) for p, label in items]
    if wanted is not None:
        labels = sorted({str(log.meta.ground_label) for log in logs})
        unknown = [g for g in wanted if g not in {label.lower() for label in labels}]
        if unknown:
            raise UnknownNameError(f"grounds {unknown!r}: no log at {name} {str(root)!r} has that ground label; "
                                   f"the logs' labels: {labels!r}")
        logs = [log for log in logs if log.meta.ground_label is not None and log.meta.ground_label.lower() in wanted]
    return _required(logs, require_currents)


def _no_csv_layout(csv: CsvLayout, why: str) -> None:
    """Refuse a CSV layout other than the default for logs that no CSV reader reads (``why`` says what they are)."""
    default = CsvLayout()
    if csv == default:
        return
    given = {"columns": csv.columns, "units": csv.units, "rates": csv.rates, "track_width_m": csv.track_width_m}
    got = ", ".join(f"{k}={v!r}" for k, v in given.items() if v and v != getattr(default, k))
    raise InvalidParameterError(
        f"csv (--csv-columns, --csv-units, --csv-rates, --track-width) applies to CSV logs only, and {why}; give no "
        f"CSV layout for them (got {got})")


def _log_items(folder: Path) -> list[Path]:
    """The log files and ROS 2 bag folders directly in ``folder``, in name order."""
    return [p for p in sorted(folder.iterdir())
            if (p.is_dir() and (p / "metadata.yaml").exists()) or (p.is_file() and p.suffix.lower() in LOG_SUFFIXES)]


def _grounds(grounds: Any) -> set[str] | None:
    if grounds is None:
        return None
    items = [grounds] if isinstance(grounds, str) else list(grounds) if isinstance(grounds, Iterable) else None
    if not items or not all(isinstance(g, str) and g for g in items):
        raise InvalidParameterError(f"grounds must be ground names, got {grounds!r:.80}")
    return {g.lower() for g in items}


def _required(logs: list[InteractionLog], require_currents: bool) -> list[InteractionLog]:
    if require_currents:
        for log in logs:
            log.require_currents(_NEEDS_CURRENTS)
    return logs
