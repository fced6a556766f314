"""Every log at a path, whatever its layout: a BorealTC folder, a CSV log, a bag, or a folder of them."""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from terrawatt_base.checks import check_bool, check_text
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError

from ..logs import InteractionLog
from .borealtc import BOREALTC_TRACK_WIDTH_M, read_borealtc
from .cleaning import LogCleaning
from .csv_log import CsvLayout
from .rosbag import BagTopics, read_rosbag

__all__ = ["LOG_SUFFIXES", "read_logs"]

#: File suffixes :func:`read_logs` reads, and the reader of each.
LOG_SUFFIXES = {".csv": "csv", ".bag": "bag", ".db3": "bag", ".mcap": "bag"}
#: What needs measured currents, for the message of :func:`read_logs` with ``require_currents``.
_NEEDS_CURRENTS = "training, evaluation or diagnosis"


def read_logs(
    path: str | os.PathLike[str],
    grounds: Sequence[str] | None = None,
    *,
    bag: BagTopics | None = None,
    csv: CsvLayout | None = None,
    require_currents: bool = False,
    robot: str = "unknown",
    ground_label: str | None = None,
    cleaning: LogCleaning | None = None,
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
    cleaning : LogCleaning, optional
        Repairs, gaps and unit checks of every reader (:class:`~energy.io.cleaning.LogCleaning`;
        see :mod:`energy.io`).

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
    common = dict(cleaning=LogCleaning.check(cleaning))
    if not root.exists():
        raise DataError(f"path {str(root)!r} does not exist; expected a log file or a folder of logs",
                        parameter="path")
    if not (root.is_file() or root.is_dir()):  # a FIFO, a socket, a device: reading would block or never end
        raise DataError(f"path {str(root)!r} is neither a regular file nor a folder; expected a log file or a "
                        "folder of logs", parameter="path")

    def one(item: Path, label: str | None = ground_label) -> InteractionLog:
        if LOG_SUFFIXES.get(item.suffix.lower()) == "csv":
            return csv.read(item, robot=None if robot == "unknown" else robot, ground_label=label, **common)
        return read_rosbag(item, bag, robot=robot, ground_label=label, **common)

    if root.is_file():
        if root.suffix.lower() not in LOG_SUFFIXES:
            raise DataError(f"path {str(root)!r}: unknown log file type {root.suffix!r}; expected one of "
                            f"{sorted(LOG_SUFFIXES)!r} or a folder", parameter="path")
        items = [(root, ground_label)]
    elif (root / "metadata.yaml").exists():
        items = [(root, ground_label)]  # a ROS 2 bag folder
    elif any(sub.is_dir() and any(sub.glob("imu_*.csv")) for sub in root.iterdir()):
        _no_csv_layout(csv, f"path {str(root)!r} is read as a BorealTC folder (GROUND/imu_NN.csv + pro_NN.csv), "
                            f"whose columns, units and track width ({BOREALTC_TRACK_WIDTH_M:g} m) are the format's own")
        return _required(read_borealtc(root, grounds=grounds, **common), require_currents)
    else:
        items = [(p, ground_label) for p in _log_items(root)]
        for sub in sorted(p for p in root.iterdir() if p.is_dir() and not (p / "metadata.yaml").exists()):
            items += [(p, sub.name.lower()) for p in _log_items(sub)]  # a ground folder
        if not items:
            raise DataError(f"path {str(root)!r} holds no logs: expected BorealTC ground folders, log files "
                            f"({', '.join(sorted(LOG_SUFFIXES))}), ROS 2 bag folders, or ground folders of them",
                            parameter="path")
    if not any(LOG_SUFFIXES.get(p.suffix.lower()) == "csv" for p, _ in items):
        _no_csv_layout(csv, f"path {str(root)!r} holds no CSV log, only bags (read with the bag options)")
    logs = [one(p, label) for p, label in items]
    if wanted is not None:
        labels = sorted({str(log.meta.ground_label) for log in logs})
        unknown = [g for g in wanted if g not in {label.lower() for label in labels}]
        if unknown:
            raise UnknownNameError(f"grounds {unknown!r}: no log at path {str(root)!r} has that ground label; "
                                   f"the logs' labels: {labels!r}", parameter="path")
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
        f"`csv` applies to CSV logs only, and {why}; give no CSV layout for them (got {got})",
        parameter=("path", "csv"))


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
