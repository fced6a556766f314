"""The generic CSV layout of an interaction log: a column map with declared units, read and written."""

from __future__ import annotations

import logging
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.atomic import write_text_atomic
from terrawatt_base.checks import fmt_number
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError

from ..logs import VELOCITY_SOURCES, InteractionLog, LogMeta
from .cleaning import (
    MAX_OMEGA_RADPS,
    MAX_SPEED_MPS,
    UNIT_FACTORS,
    LogCleaning,
    check_accel,
    check_current,
    check_limit,
    check_timing,
    check_track_width,
    clean_stream,
    gravity_note,
)
from .csv_header import CSV_LOG_FORMAT_VERSION, LOG_HEADER_PREFIX, format_log_header, parse_log_header
from .csv_table import CsvText, read_csv_text, read_table

__all__ = [
    "CSV_FIELDS",
    "CSV_UNITS",
    "DEFAULT_CSV_COLUMNS",
    "CSV_LOG_FORMAT_VERSION",
    "CSV_RATES",
    "csv_field_map",
    "CsvLayout",
    "read_csv_log",
    "write_csv_log",
]

_LOG = logging.getLogger(__name__)

_FIELD_KIND = {
    "time": "time",
    "v": "speed",
    "omega": "omega",
    "speed_left": "speed",
    "speed_right": "speed",
    "current_left": "current",
    "current_right": "current",
    "accel_z": "accel",
    "gyro_z": "omega",
    "battery_voltage": "voltage",
    "battery_current": "current",
    "x": "length",
    "y": "length",
    "heading": "angle",
    "ground": "",
}
#: Canonical field names accepted in ``read_csv_log``'s column map.
CSV_FIELDS = tuple(_FIELD_KIND)
#: Units accepted per field of ``read_csv_log`` (the first of each is the SI default).
CSV_UNITS: dict[str, tuple[str, ...]] = {
    f: tuple(UNIT_FACTORS[k]) for f, k in _FIELD_KIND.items() if k
}
#: Column names of the generic layout written by :func:`write_csv_log` (and read by
#: :func:`read_csv_log` when ``columns`` is None).
DEFAULT_CSV_COLUMNS: dict[str, str] = {
    "time": "time_s",
    "v": "v_mps",
    "omega": "omega_radps",
    "current_left": "current_left_a",
    "current_right": "current_right_a",
    "accel_z": "accel_z_mps2",
    "gyro_z": "gyro_z_radps",
    "battery_voltage": "battery_voltage_v",
    "battery_current": "battery_current_a",
    "x": "x_m",
    "y": "y_m",
    "heading": "heading_rad",
    "ground": "ground",
}
#: Values of ``read_csv_log``'s ``rates``: one row per sample of both streams, or two
#: streams of different rates interleaved by time (the layout :func:`write_csv_log` writes).
CSV_RATES = ("mixed", "single")
#: Fields that go together: all mapped (or, in the default layout, all in the header) or none.
_GROUPS = (("current_left", "current_right"), ("x", "y", "heading"), ("gyro_z",), ("battery_voltage",),
           ("battery_current",))
#: Fields of the IMU stream (the rest but time belong to the drive stream).
_IMU = ("accel_z", "gyro_z")


def _unit_factor(field: str, unit: str) -> float:
    table = UNIT_FACTORS[_FIELD_KIND[field]]
    if unit not in table:
        raise UnknownNameError(f"unit {unit!r} is not known for field {field!r}; expected one of {tuple(table)!r}")
    return table[unit]


@dataclass(frozen=True)
class CsvLayout:
    """How a CSV log names its columns and units (:func:`read_csv_log`, :func:`~energy.io.read_logs`); the default
    is the layout :func:`write_csv_log` writes.

    Parameters
    ----------
    columns : mapping field -> column name, optional
        The column of each field (:data:`~energy.io.CSV_FIELDS`: ``time``, ``accel_z``, ``v`` and
        ``omega`` or ``speed_left`` and ``speed_right``, ``current_left`` and ``current_right``,
        optional ``x`` / ``y`` / ``heading``, ``gyro_z``, ``battery_voltage``, ``battery_current``,
        ``ground``).
    units : mapping field -> unit, optional
        Declared units of the mapped fields, or of the default layout's (:data:`~energy.io.CSV_UNITS`);
        undeclared fields are SI.
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
        if self.columns is not None or self.units:
            columns, units, _ = csv_field_map(self.columns, self.units)
            object.__setattr__(self, "columns", None if self.columns is None else columns)
            object.__setattr__(self, "units", units)
        if self.rates not in CSV_RATES:
            raise UnknownNameError(f"rates must be one of {CSV_RATES!r}, got {self.rates!r}", parameter="rates")
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
            f"track_width_m {self.track_width_m:g} derives omega from wheel speeds (speed_left / "
            f"speed_right columns), but {whose} velocities are v and omega ({columns.get('v')!r}, "
            f"{columns.get('omega')!r}): there is no omega to derive; drop the track width, or map the wheel speeds "
            "instead (`columns` speed_left=COLUMN speed_right=COLUMN)", parameter=("track_width_m", "columns"))

    def read(self, path: str | os.PathLike[str], **options: Any) -> InteractionLog:
        """:func:`read_csv_log` of ``path`` in this layout (``options``: its other keywords).

        Raises
        ------
        InvalidParameterError
            A track width with the default layout (v and omega columns), refused here rather
            than when the layout was made, as it may be meant for logs of another kind.
        """
        self._check_track_width()
        return read_csv_log(path, self, **options)


def read_csv_log(
    path: str | os.PathLike[str],
    layout: CsvLayout | None = None,
    *,
    robot: str | None = None,
    ground_label: str | None = None,
    velocity_source: str | None = None,
    cleaning: LogCleaning | None = None,
) -> InteractionLog:
    """Read an interaction log from one CSV file with a column map and declared units.

    Layout: a header line (lines starting with ``#`` before or between rows are comments),
    one row per timestamp. Missing fields are empty or ``nan``. ``rates`` says how rows map
    to the drive and acceleration streams:

    - ``"single"``: every row is a sample of both streams, so any missing field is a NaN
      of its stream (DataError unless ``repair=("interpolate_nans",)``). Use it for
      single-rate files: nothing is ever moved out of a stream.
    - ``"mixed"`` (default; the layout :func:`write_csv_log` writes): the two streams have
      different rates and are interleaved by time. A row is an IMU sample (acceleration,
      gyro) when its acceleration field is present, and a drive sample when any drive field (a pose field
      or a ground label included) is present, or when the acceleration field is missing
      too; a missing value among present drive fields is a NaN. So a row whose drive
      fields are all empty is an IMU-only row and one without acceleration a drive-only
      row; how many of each were split is logged (INFO) and written to ``meta.notes``.
      In a single-rate file such rows are lost samples: read it with ``rates="single"``.

    Parameters
    ----------
    path : path-like
    layout : CsvLayout, optional
        The file's columns, units, rates and track width (default ``CsvLayout()``: the layout
        :func:`write_csv_log` writes). Its fields:

        - ``columns`` (mapping field -> column name, optional):
          Fields (:data:`CSV_FIELDS`): ``time``, ``accel_z`` (required); ``v`` and ``omega``,
          or ``speed_left`` and ``speed_right`` (wheel speeds, with ``track_width_m``; v =
          mean, omega = (right - left) / track_width_m); ``current_left`` and
          ``current_right`` (both, or neither for a log to predict from only); optional ``x``,
          ``y``, ``heading`` (all three), ``gyro_z`` (IMU yaw rate), ``battery_voltage``,
          ``battery_current`` (pack current, A; needs ``battery_voltage``) and ``ground`` (text labels). Default: :data:`DEFAULT_CSV_COLUMNS`, the layout written by
          :func:`write_csv_log` (optional columns, the currents included, used when present).
        - ``units`` (mapping field -> unit, optional):
          Declared unit per field (:data:`CSV_UNITS`: current ``"A"``/``"mA"``; speed
          ``"m/s"``, ``"cm/s"``, ``"mm/s"``, ``"km/h"``; omega ``"rad/s"``/``"deg/s"``; time
          ``"s"``, ``"ms"``, ``"us"``, ``"ns"``; accel ``"m/s^2"``/``"g"``; x/y ``"m"``,
          ``"cm"``, ``"mm"``; heading ``"rad"``/``"deg"``; gyro_z as omega; battery_voltage
          ``"V"``/``"mV"``; battery_current as current). Undeclared fields are SI.
        - ``track_width_m`` (float, optional):
          With wheel speeds, the track width that gives omega (default: the header's).
        - ``rates`` ({"mixed", "single"}):
          Whether the file interleaves streams of different rates (see above).
    robot, ground_label, velocity_source : optional
        Metadata. ``None`` takes the value from a :func:`write_csv_log` header when the file
        has one; otherwise robot ``"unknown"``, velocity ``"measured"`` for wheel speeds and
        ``"commanded"`` for v/omega.
    cleaning : LogCleaning, optional
        Repairs, gaps and unit checks (:class:`~energy.io.cleaning.LogCleaning`; see :mod:`energy.io`).

    Returns
    -------
    InteractionLog

    Raises
    ------
    UnknownNameError
        An unknown field, unit, ``rates`` or repair name.
    InvalidParameterError
        An incomplete column map (e.g. wheel speeds without ``track_width_m``).
    FileFormatError, FormatVersionError
        Missing/unparsable file, a corrupt terrawatt header, another layout version.
    DataError, UnitError
        As in the module docstring.

    Examples
    --------
    Usage (needs data or fitted models, so not run as a doctest)::

        log = read_csv_log("run.csv", CsvLayout(columns={"time": "t", "v": "cmd_v", "omega": "cmd_w",
            "current_left": "iL", "current_right": "iR", "accel_z": "az"},
            units={"current_left": "mA", "current_right": "mA"}))
    """
    path = Path(path)
    src = str(path)
    if layout is None:
        layout = CsvLayout()
    if not isinstance(layout, CsvLayout):
        raise InvalidParameterError(f"layout must be a CsvLayout, got {type(layout).__name__!r}", parameter="layout")
    cleaning = LogCleaning.check(cleaning)
    repairs, allow_gaps, gap_factor = cleaning.repairs, cleaning.allow_gaps, cleaning.gap_factor
    check_units = cleaning.check_units
    columns, units, rates, track_width_m = layout.columns, layout.units, layout.rates, layout.track_width_m
    explicit = columns is not None
    colmap, units, factors = csv_field_map(columns, units)
    text = read_csv_text(path)
    file_meta = _file_meta(text)
    has_wheels, vel_fields, required = _velocity_fields(colmap)
    if track_width_m is None and has_wheels:
        track_width_m = file_meta["track_width_m"]
    if has_wheels:
        if track_width_m is None:
            raise InvalidParameterError("wheel speeds (speed_left/speed_right) need track_width_m to derive omega")
        track_width_m = check_track_width(track_width_m)
    present_fields = _present_fields(colmap, explicit, text.names, src)
    optional_fields = [] if explicit else present_fields
    numeric_fields = required + (present_fields if explicit else [])
    text_fields = ["ground"] if "ground" in colmap else []
    if not explicit:  # a file of another layout: say how to map it
        missing = [colmap[f] for f in numeric_fields if colmap[f] not in text.names]
        if missing:
            raise DataError(
                f"{src!r}: missing column(s) {missing!r} of the layout terrawatt writes; the header has {text.names!r}: "
                "map the fields to your columns and declare their units: `columns` (time=COLUMN v=COLUMN ...) and "
                "`units` (time=ms ...) of the CSV layout", parameter=("columns", "units")
            )
    table = read_table(
        text,
        [colmap[f] for f in numeric_fields],
        optional=[colmap[f] for f in optional_fields],
        columns_text=[colmap[f] for f in text_fields],
    )
    if text_fields and colmap["ground"] not in table:
        raise DataError(f"{src}: missing column {colmap['ground']!r}; the header has {text.names!r}")
    order = ("time", "accel_z", "current_left", "current_right")  # the first columns checked
    fields = sorted(numeric_fields + optional_fields, key=lambda f: order.index(f) if f in order else len(order))
    num = {f: table[colmap[f]] * factors[f] for f in fields}
    labels = table[colmap["ground"]] if text_fields else None
    drive_fields = [f for f in num if f not in ("time", *_IMU)]
    imu_fields = [f for f in num if f in _IMU]
    drive_rows, acc_rows, split_note = _split_rows(num, drive_fields, labels, rates, src)
    t_all = num["time"]
    td, dc, de = clean_stream(
        src, "drive stream", t_all[drive_rows], {f: num[f][drive_rows] for f in drive_fields},
        repairs, allow_gaps, gap_factor, None if labels is None else {"ground": labels[drive_rows]},
    )
    ta, ac, _ = clean_stream(
        src, "acceleration stream", t_all[acc_rows], {f: num[f][acc_rows] for f in imu_fields},
        repairs, allow_gaps, gap_factor,
    )
    ground = None if labels is None else _ground_labels(de["ground"], td, src)
    if check_units:
        _check_csv_units(src, colmap, units, vel_fields, td, dc, ta, ac)
    if has_wheels:
        v = 0.5 * (dc["speed_left"] + dc["speed_right"])
        omega = (dc["speed_right"] - dc["speed_left"]) / track_width_m
    else:
        v, omega = dc["v"], dc["omega"]
    pose = np.column_stack([dc["x"], dc["y"], dc["heading"]]) if "x" in dc else None
    if velocity_source is None:
        velocity_source = file_meta["velocity_source"] or ("measured" if has_wheels else "commanded")
    if velocity_source not in VELOCITY_SOURCES:
        raise InvalidParameterError(f"velocity_source must be one of {VELOCITY_SOURCES!r}, got {velocity_source!r}")
    notes = [file_meta["notes"] or "", f"read from {src}", split_note]
    if file_meta["source"]:
        notes.append(f"original source: {file_meta['source']}")
    gravity = gravity_note(colmap["accel_z"], ac["accel_z"], "declare it: units={'accel_z': 'g'}", check_units)
    if file_meta["gravity_removed"] is None and gravity:
        notes.append(gravity)
    declared = {f: u for f, u in units.items() if factors[f] != 1.0}
    if declared:
        notes.append(f"converted to SI from {declared!r}")
    return InteractionLog(
        time_s=td,
        v_mps=v,
        omega_radps=omega,
        current_left_a=dc.get("current_left"),
        current_right_a=dc.get("current_right"),
        battery_voltage_v=dc.get("battery_voltage"),
        battery_current_a=dc.get("battery_current"),
        accel_time_s=ta,
        accel_z_mps2=ac["accel_z"],
        gyro_z_radps=ac.get("gyro_z"),
        pose_xyh=pose,
        ground=ground,
        meta=LogMeta(
            robot=robot if robot is not None else (file_meta["robot"] or "unknown"),
            source=src,
            ground_label=ground_label if ground_label is not None else file_meta["ground_label"],
            velocity_source=velocity_source,
            track_width_m=track_width_m if track_width_m is not None else file_meta["track_width_m"],
            notes="; ".join(n for n in notes if n),
            start_time_ns=file_meta["start_time_ns"],
            gravity_removed=bool(gravity) if file_meta["gravity_removed"] is None else file_meta["gravity_removed"],
            missing_currents=file_meta["missing_currents"] or ("" if "current_left" in dc else f"no current columns in {src}"),
        ),
    )


def csv_field_map(
    columns: Mapping[str, str] | None, units: Mapping[str, str] | None
) -> tuple[dict[str, str], dict[str, str], dict[str, float]]:
    """A CSV log's column map and declared units, checked before any file is read (as :func:`read_csv_log` takes
    them): (field -> column, field -> declared unit, field -> factor to SI).

    Raises
    ------
    UnknownNameError
        A field that is not one of :data:`CSV_FIELDS`, a unit for a field that is not mapped, an
        unknown unit.
    InvalidParameterError
        ``columns`` or ``units`` not a mapping; a column name that is not a non-empty string; two
        fields mapped to one column.
    """
    for what, value in (("columns", columns), ("units", units)):
        if value is not None and not isinstance(value, Mapping):
            raise InvalidParameterError(f"{what} must be a mapping of field names, got {type(value).__name__!r}")
    colmap = dict(DEFAULT_CSV_COLUMNS if columns is None else columns)
    unknown = [f for f in colmap if f not in _FIELD_KIND]
    if unknown:
        raise UnknownNameError(f"columns has unknown field(s) {unknown!r}; expected fields from {CSV_FIELDS!r}")
    bad = {f: c for f, c in colmap.items() if not isinstance(c, str) or not c}
    if bad:
        raise InvalidParameterError(f"columns must map fields to non-empty column names, got {bad!r}")
    shared = {c: sorted(f for f, col in colmap.items() if col == c) for c in set(colmap.values())}
    shared = {c: fields for c, fields in shared.items() if len(fields) > 1}
    if shared:
        raise InvalidParameterError(f"columns maps several fields to one column: {shared!r}; each field needs its "
                                    "own column")
    units = dict(units or {})
    unknown = [f for f in units if f not in colmap or f == "ground"]
    if unknown:
        raise UnknownNameError(f"units given for field(s) {unknown!r} that are not numeric columns of the map {colmap!r}")
    factors = {f: _unit_factor(f, units.get(f, next(iter(UNIT_FACTORS[_FIELD_KIND[f]])))) for f in colmap if f != "ground"}
    return colmap, units, factors


def _file_meta(text: CsvText) -> dict[str, Any]:
    """The checked metadata of the file's terrawatt-log header, all ``None`` without one."""
    for line in text.comments:
        if line.startswith(LOG_HEADER_PREFIX):
            return parse_log_header(line, text.source)
    return dict.fromkeys(
        ("robot", "source", "notes", "ground_label", "velocity_source", "track_width_m", "start_time_ns",
         "gravity_removed", "missing_currents")
    )


def _velocity_fields(colmap: dict[str, str]) -> tuple[bool, tuple[str, str], list[str]]:
    """(wheel speeds?, the two velocity fields, every required field)."""
    has_v = "v" in colmap or "omega" in colmap
    has_wheels = "speed_left" in colmap or "speed_right" in colmap
    if has_v and has_wheels:
        raise InvalidParameterError("columns must map either v/omega or speed_left/speed_right, not both")
    if not has_v and not has_wheels:
        raise InvalidParameterError("columns must map v and omega, or speed_left and speed_right")
    vel_fields = ("speed_left", "speed_right") if has_wheels else ("v", "omega")
    required = ["time", "accel_z", *vel_fields]
    absent = [f for f in required if f not in colmap]
    if absent:
        raise InvalidParameterError(f"columns lacks required field(s) {absent!r}; got {colmap!r}")
    return has_wheels, vel_fields, required


def _present_fields(colmap: dict[str, str], explicit: bool, header: list[str], src: str) -> list[str]:
    """The optional numeric fields to read (currents, pose, gyro, voltage), whole groups only;
    the default layout drops those the file lacks (and the ground column if absent)."""
    out: list[str] = []
    for group in _GROUPS:
        have = [f for f in group if f in colmap and (explicit or colmap[f] in header)]
        if have and len(have) != len(group):
            if explicit:
                raise InvalidParameterError(
                    f"columns lacks required field(s) {[f for f in group if f not in have]!r}: map all of "
                    f"{', '.join(group)} or none, got {colmap!r}"
                )
            raise DataError(f"{src}: the header has only {[colmap[f] for f in have]!r} of the columns "
                            f"{[colmap[f] for f in group]!r}")
        out += have
    if not explicit and colmap["ground"] not in header:
        del colmap["ground"]
    return out


def _split_rows(
    num: dict[str, np.ndarray], drive_fields: list[str], labels: np.ndarray | None, rates: str, src: str
) -> tuple[np.ndarray, np.ndarray, str]:
    """(drive rows, acceleration rows, a note of the split) of the file's rows."""
    n = num["time"].size
    if rates == "single":
        every = np.ones(n, dtype=bool)
        return every, every, ""
    present = [np.isfinite(num[f]) for f in drive_fields]
    if labels is not None:
        present.append(np.char.str_len(labels) > 0)
    acc_rows = np.isfinite(num["accel_z"])
    drive_rows = np.column_stack(present).any(axis=1) | ~acc_rows
    note = (
        f"rates='mixed': {n} row(s) split into {int((drive_rows & acc_rows).sum())} drive+IMU, "
        f"{int((drive_rows & ~acc_rows).sum())} drive-only and {int((acc_rows & ~drive_rows).sum())} IMU-only "
        f"(all drive fields empty) row(s)"
    )
    _LOG.info("%s: %s", src, note)
    return drive_rows, acc_rows, note


def _ground_labels(ground: np.ndarray, td: np.ndarray, src: str) -> np.ndarray:
    empty = np.char.str_len(ground) == 0
    if empty.any():
        i = int(np.argmax(empty))
        raise DataError(
            f"{src}: drive stream: {int(empty.sum())} empty ground label(s), first at index {i} "
            f"(t={fmt_number(float(td[i]), 9)} s)"
        )
    return ground


def _check_csv_units(
    src: str, colmap: dict[str, str], units: dict[str, str], vel_fields: tuple[str, str],
    td: np.ndarray, dc: dict[str, np.ndarray], ta: np.ndarray, ac: dict[str, np.ndarray],
) -> None:
    for f in ("current_left", "current_right", "battery_current"):
        if f in dc:
            check_current(src, colmap[f], dc[f], units.get(f, "A"))
    if "gyro_z" in ac:
        check_limit(src, colmap["gyro_z"], ac["gyro_z"], MAX_OMEGA_RADPS, "rad/s",
                    f"declared {units.get('gyro_z', 'rad/s')!r} looks like deg/s")
    for f in vel_fields:
        if _FIELD_KIND[f] == "speed":
            check_limit(src, colmap[f], dc[f], MAX_SPEED_MPS, "m/s", f"declared {units.get(f, 'm/s')!r} looks like mm/s or cm/s")
        else:
            check_limit(src, colmap[f], dc[f], MAX_OMEGA_RADPS, "rad/s", f"declared {units.get(f, 'rad/s')!r} looks like deg/s")
    check_accel(src, colmap["accel_z"], ac["accel_z"])
    check_timing(src, "drive stream", td)
    check_timing(src, "acceleration stream", ta)


def write_csv_log(log: InteractionLog, path: str | os.PathLike[str]) -> Path:
    """Write a log in the generic CSV layout, atomically (temporary file, then rename).

    The first line is ``# terrawatt-log {json}`` with the format version and the metadata;
    then the header ``time_s,v_mps,omega_radps,current_left_a,current_right_a,accel_z_mps2``
    (the currents only when the log has them; + ``gyro_z_radps`` and
    ``battery_voltage_v`` / ``battery_current_a`` when it has them, + ``x_m,y_m,heading_rad`` with a pose,
    + ``ground`` with labels) and one row per
    distinct timestamp of either stream, fields of the stream not sampled at that time left
    empty. Floats are written with ``repr`` so :func:`read_csv_log` reads back the exact
    values.

    Returns
    -------
    pathlib.Path
        The written path.

    Raises
    ------
    InvalidParameterError
        ``log`` is not an InteractionLog, or a ground label holds a comma, quote or newline.
    """
    if not isinstance(log, InteractionLog):
        raise InvalidParameterError(f"log must be an InteractionLog, got {log!r:.80}")
    path = Path(path)
    if log.ground is not None:
        bad = [g for g in np.unique(log.ground).tolist() if re.search(r"[,\"\r\n#]", g) or g != g.strip()]
        if bad:
            raise InvalidParameterError(
                f"ground labels {bad!r} cannot be written to CSV (no commas, quotes, '#', newlines or outer spaces)"
            )
    t = np.union1d(log.time_s, log.accel_time_s)
    rows = t.size
    di = np.searchsorted(t, log.time_s)
    ai = np.searchsorted(t, log.accel_time_s)
    streams = [(n, di) for n in ("v_mps", "omega_radps", "current_left_a", "current_right_a")]
    streams += [("accel_z_mps2", ai), ("gyro_z_radps", ai), ("battery_voltage_v", di), ("battery_current_a", di)]
    cols = [(n, getattr(log, n), where) for n, where in streams if getattr(log, n) is not None]
    if log.pose_xyh is not None:
        cols += [(n, log.pose_xyh[:, k], di) for k, n in enumerate(("x_m", "y_m", "heading_rad"))]
    table = [[repr(x) for x in t.tolist()]]
    for _, values, where in cols:
        column = [""] * rows
        for i, x in zip(where.tolist(), values.tolist()):
            column[i] = repr(x)
        table.append(column)
    names = ["time_s"] + [c[0] for c in cols]
    if log.ground is not None:
        column = [""] * rows
        for i, g in zip(di.tolist(), log.ground.tolist()):
            column[i] = g
        table.append(column)
        names.append("ground")
    lines = [format_log_header(log.meta), ",".join(names)]
    lines += [",".join(r) for r in zip(*table)]
    write_text_atomic(path, "\n".join(lines) + "\n")
    return path
