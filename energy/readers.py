"""Readers and writers of interaction logs: BorealTC CSV, generic CSV, ROS 1/2 bags and MCAP.

Every reader returns :class:`~energy.logs.InteractionLog` objects in SI units and refuses
bad input with a clear error instead of guessing:

- unsorted timestamps, duplicated timestamps, NaNs (empty fields or ``nan``) -> DataError
  naming the stream, the first offending index and time, and the count; each can be
  repaired on request with ``repair=("sort", "drop_duplicates", "interpolate_nans")``
  (applied in that order; each repair is logged through ``logging.getLogger(__name__)`` and
  warned with :class:`DataRepairWarning` giving the count). NaN timestamps are never repaired;
  ``interpolate_nans`` interpolates linearly in time from the nearest finite samples and
  holds the first/last finite value at the ends.
- gaps: a step between consecutive samples of one stream larger than ``gap_factor``
  (default :data:`~energy.logs.DEFAULT_GAP_FACTOR` = 5) median periods -> DataError unless
  ``allow_gaps=True``; split such logs with :meth:`InteractionLog.split_at_gaps`.
- missing columns / topics, empty files -> DataError; a missing or unparsable file ->
  FileFormatError.
- unit checks (``check_units=True``), made after conversion to SI; the thresholds are
  module constants:

  * current declared in A whose median |I| exceeds :data:`MAX_MEDIAN_CURRENT_A` (100 A), or
    whose values are all integers reaching 100 or more, or whose 99th percentile of the
    non-zero |I| exceeds :data:`MAX_P99_CURRENT_A` (300 A; zeros say nothing about the
    unit, so a side idle most of the time is still caught) -> UnitError "looks like mA";
  * current declared in mA whose peak |I| is below :data:`MIN_PEAK_CURRENT_A` (0.05 A = 50 mA)
    while not all zero -> UnitError "looks like A";
  * |v| (or a wheel speed) above :data:`MAX_SPEED_MPS` (10 m/s, implausible for a ground
    robot) -> UnitError "looks like mm/s or cm/s";
  * |omega| above :data:`MAX_OMEGA_RADPS` (20 rad/s) -> UnitError "looks like deg/s";
  * median |a_z| above :data:`MAX_MEDIAN_ACCEL_MPS2` (50 m/s^2) -> UnitError (e.g. m/s^2
    declared as g, or mm/s^2).
"""

from __future__ import annotations

import csv
import json
import logging
import math
import os
import re
import warnings
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from terrain.atomic import write_text_atomic
from terrain.errors import (
    DataError,
    DataRepairWarning,
    FileFormatError,
    FormatVersionError,
    InvalidParameterError,
    OptionalDependencyError,
    UnitError,
    UnknownNameError,
)

from .logs import (
    DEFAULT_GAP_FACTOR,
    VELOCITY_SOURCES,
    InteractionLog,
    LogMeta,
    _check_gap_factor,
    _gap_steps,
)

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
    "MAX_CLOCK_OFFSET_S",
    "read_borealtc_run",
    "read_borealtc",
    "read_csv_log",
    "write_csv_log",
    "read_rosbag",
]

_LOG = logging.getLogger(__name__)

#: Repairs a caller may ask a reader for, applied in this order.
REPAIRS = ("sort", "drop_duplicates", "interpolate_nans")
#: Nominal (geometric) track width of the Clearpath Husky A200 used by the BorealTC reader.
#: A skid-steer robot's effective track width is larger and ground-dependent; pass a
#: fitted value as ``track_width_m`` when you have one.
BOREALTC_TRACK_WIDTH_M = 0.555

#: Unit-check thresholds (see the module docstring).
MAX_MEDIAN_CURRENT_A = 100.0
#: No ground robot's drive draws this much most of the time it draws anything (BorealTC's
#: Husky peaks at ~35 A): a 99th percentile of the non-zero |I| above it is mA declared as A.
MAX_P99_CURRENT_A = 300.0
MIN_PEAK_CURRENT_A = 0.05
MAX_SPEED_MPS = 10.0
MAX_OMEGA_RADPS = 20.0
MAX_MEDIAN_ACCEL_MPS2 = 50.0
#: Default largest median (receive time - header stamp) a bag topic may show before
#: ``read_rosbag`` refuses to mix its header stamps with receive times (s).
MAX_CLOCK_OFFSET_S = 0.5

_UNIT_TABLES: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9},
    "speed": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3, "km/h": 1.0 / 3.6},
    "omega": {"rad/s": 1.0, "deg/s": math.pi / 180.0},
    "current": {"A": 1.0, "mA": 1e-3},
    "accel": {"m/s^2": 1.0, "m/s2": 1.0, "g": 9.80665},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3},
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
}
_FIELD_KIND = {
    "time": "time",
    "v": "speed",
    "omega": "omega",
    "speed_left": "speed",
    "speed_right": "speed",
    "current_left": "current",
    "current_right": "current",
    "accel_z": "accel",
    "x": "length",
    "y": "length",
    "heading": "angle",
    "ground": "",
}
#: Canonical field names accepted in ``read_csv_log``'s column map.
CSV_FIELDS = tuple(_FIELD_KIND)
#: Units accepted per field of ``read_csv_log`` (the first of each is the SI default).
CSV_UNITS: dict[str, tuple[str, ...]] = {
    f: tuple(_UNIT_TABLES[k]) for f, k in _FIELD_KIND.items() if k
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
    "x": "x_m",
    "y": "y_m",
    "heading": "heading_rad",
    "ground": "ground",
}
#: Version of the generic CSV layout written by :func:`write_csv_log`.
CSV_LOG_FORMAT_VERSION = 1
#: Values of ``read_csv_log``'s ``rates``: one row per sample of both streams, or two
#: streams of different rates interleaved by time (the layout :func:`write_csv_log` writes).
CSV_RATES = ("mixed", "single")
_CSV_MAGIC = "# terrawatt-log "
_MISSING_TOKENS = frozenset({"", "nan", "NaN", "NAN", "NA", "null", "None"})


# ----------------------------------------------------------------------------- helpers
def _parse_repair(repair: str | Iterable[str]) -> frozenset[str]:
    items = (repair,) if isinstance(repair, str) else tuple(repair)
    unknown = [r for r in items if r not in REPAIRS]
    if unknown:
        raise UnknownNameError(f"repair must name only {REPAIRS!r}, got unknown {unknown!r}")
    return frozenset(items)


def _repaired(source: str, message: str) -> None:
    text = f"{source}: {message}"
    _LOG.warning(text)
    warnings.warn(text, DataRepairWarning, stacklevel=4)


def _clean_stream(
    source: str,
    stream: str,
    t: np.ndarray,
    cols: dict[str, np.ndarray],
    repairs: frozenset[str],
    allow_gaps: bool,
    gap_factor: float,
    extra: dict[str, np.ndarray] | None = None,
) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Check (and, when asked, repair) one stream; returns time, numeric and extra columns.

    ``extra`` holds non-numeric columns (labels) that follow the row operations but are
    neither checked for NaN nor interpolated.
    """
    extra = dict(extra or {})
    where = f"{source}: {stream}"
    if t.size == 0:
        raise DataError(f"{where} has no samples (empty file, topic or column)")
    bad = ~np.isfinite(t)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(
            f"{where}: {int(bad.sum())} timestamp(s) are missing or non-finite, first at index {i}; "
            f"timestamps are never repaired"
        )
    d = np.diff(t)
    back = d < 0
    if back.any():
        i = int(np.argmax(back)) + 1
        if "sort" not in repairs:
            raise DataError(
                f"{where}: timestamps are not sorted; {int(back.sum())} step(s) go backwards, first at "
                f"index {i} (t={float(t[i])!r} s after t={float(t[i - 1])!r} s); pass repair=('sort',) to sort them"
            )
        order = np.argsort(t, kind="stable")
        t = t[order]
        cols = {k: v[order] for k, v in cols.items()}
        extra = {k: v[order] for k, v in extra.items()}
        _repaired(source, f"{stream}: sorted timestamps ({int(back.sum())} backward step(s))")
        d = np.diff(t)
    dup = d == 0
    if dup.any():
        i = int(np.argmax(dup)) + 1
        if "drop_duplicates" not in repairs:
            raise DataError(
                f"{where}: {int(dup.sum())} duplicated timestamp(s), first at index {i} (t={float(t[i])!r} s); "
                f"pass repair=('drop_duplicates',) to keep the first sample of each"
            )
        keep = np.concatenate([[True], ~dup])
        t = t[keep]
        cols = {k: v[keep] for k, v in cols.items()}
        extra = {k: v[keep] for k, v in extra.items()}
        _repaired(source, f"{stream}: dropped {int(dup.sum())} sample(s) with a duplicated timestamp")
    for name, values in list(cols.items()):
        bad = ~np.isfinite(values)
        if not bad.any():
            continue
        i = int(np.argmax(bad))
        if "interpolate_nans" not in repairs:
            raise DataError(
                f"{where}: column {name!r} has {int(bad.sum())} missing or non-finite value(s), first at "
                f"index {i} (t={float(t[i])!r} s); pass repair=('interpolate_nans',) to interpolate them"
            )
        if bad.all():
            raise DataError(f"{where}: column {name!r} has no finite value at all; nothing to interpolate from")
        fixed = values.copy()
        fixed[bad] = np.interp(t[bad], t[~bad], values[~bad])
        cols[name] = fixed
        _repaired(source, f"{stream}: interpolated {int(bad.sum())} missing value(s) of column {name!r}")
    gaps = _gap_steps(t, gap_factor)
    if gaps.size:
        i = int(gaps[0])
        threshold = gap_factor * float(np.median(np.diff(t)))
        msg = (
            f"{where}: {gaps.size} gap(s) longer than {gap_factor:g} median periods ({threshold:.4g} s), "
            f"first from t={float(t[i])!r} s to t={float(t[i + 1])!r} s (after index {i})"
        )
        if not allow_gaps:
            raise DataError(
                msg + "; pass allow_gaps=True to keep them (then split with InteractionLog.split_at_gaps())"
            )
        _LOG.info(msg + " (allowed)")
    return t, cols, extra


def _check_current(source: str, name: str, values_a: np.ndarray, unit: str) -> None:
    mag = np.abs(values_a[np.isfinite(values_a)])
    if mag.size == 0:
        return
    if unit == "A":
        med = float(np.median(mag))
        peak = float(mag.max())
        nonzero = mag[mag > 0]
        p99 = float(np.percentile(nonzero, 99)) if nonzero.size else 0.0
        if (
            med > MAX_MEDIAN_CURRENT_A
            or p99 > MAX_P99_CURRENT_A
            or (peak >= 100.0 and np.all(mag == np.round(mag)))
        ):
            raise UnitError(
                f"{source}: {name} is declared in A but its values look like mA (median |I| = {med:.6g} A, "
                f"99th percentile of the non-zero |I| = {p99:.6g} A, peak {peak:.6g} A, integer-valued: "
                f"{bool(np.all(mag == np.round(mag)))}; expected a median <= {MAX_MEDIAN_CURRENT_A:g} A and a "
                f"99th percentile <= {MAX_P99_CURRENT_A:g} A for a ground robot's drive); declare 'mA' "
                f"or pass check_units=False"
            )
    elif unit == "mA":
        peak = float(mag.max())
        if 0.0 < peak < MIN_PEAK_CURRENT_A:
            raise UnitError(
                f"{source}: {name} is declared in mA but its peak is {peak * 1e3:.6g} mA (< "
                f"{MIN_PEAK_CURRENT_A * 1e3:g} mA): the values look like A; declare 'A' or pass check_units=False"
            )


def _check_limit(source: str, name: str, values: np.ndarray, limit: float, unit_si: str, hint: str) -> None:
    mag = np.abs(values[np.isfinite(values)])
    if mag.size and float(mag.max()) > limit:
        i = int(np.argmax(np.abs(np.where(np.isfinite(values), values, 0.0))))
        raise UnitError(
            f"{source}: |{name}| reaches {float(mag.max()):.6g} {unit_si} (index {i}), above the plausible "
            f"{limit:g} {unit_si} for a ground robot: {hint}; fix the declared unit or pass check_units=False"
        )


def _check_accel(source: str, name: str, values: np.ndarray) -> None:
    mag = np.abs(values[np.isfinite(values)])
    if mag.size and float(np.median(mag)) > MAX_MEDIAN_ACCEL_MPS2:
        raise UnitError(
            f"{source}: median |{name}| is {float(np.median(mag)):.6g} m/s^2 (> {MAX_MEDIAN_ACCEL_MPS2:g}): "
            f"the declared unit looks wrong (m/s^2 declared as g, or mm/s^2?); fix it or pass check_units=False"
        )


def _check_track_width(track_width_m: Any) -> float:
    if (
        isinstance(track_width_m, bool)
        or not isinstance(track_width_m, (int, float))
        or not math.isfinite(track_width_m)
        or track_width_m <= 0
    ):
        raise InvalidParameterError(f"track_width_m must be a finite number > 0, got {track_width_m!r}")
    return float(track_width_m)


def _bracket_accel(t_drive: np.ndarray, t_acc: np.ndarray) -> slice:
    """Acceleration samples from the last one at or before the first drive time to the first
    one at or after the last drive time (drive times lie inside the acceleration span)."""
    ia = max(int(np.searchsorted(t_acc, t_drive[0], side="right")) - 1, 0)
    ib = min(int(np.searchsorted(t_acc, t_drive[-1], side="left")), t_acc.size - 1)
    return slice(ia, ib + 1)


# --------------------------------------------------------------------------- CSV tables
def _scan_header(path: Path) -> tuple[int, list[str], list[str]]:
    """(index of the header line, column names, comment lines before it)."""
    if not path.exists():
        raise FileFormatError(f"file {str(path)!r} does not exist")
    if not path.is_file():
        raise FileFormatError(f"{str(path)!r} is not a file")
    comments: list[str] = []
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            for lineno, line in enumerate(fh):
                stripped = line.strip()
                if not stripped:
                    continue
                if stripped.startswith("#"):
                    comments.append(stripped)
                    continue
                names = [n.strip() for n in next(csv.reader([stripped]))]
                return lineno, names, comments
    except UnicodeDecodeError as exc:
        raise FileFormatError(f"{str(path)!r} is not a UTF-8 text CSV file: {exc}") from exc
    raise DataError(f"{str(path)!r} is empty: no header line and no data")


def _read_table(
    path: Path, wanted: Sequence[str], optional: Sequence[str] = (), text: Sequence[str] = ()
) -> tuple[dict[str, np.ndarray], list[str]]:
    """Numeric columns ``wanted`` (+ ``optional`` when present) and text columns ``text``.

    Missing numeric fields (empty, ``nan``, ``NA``) become NaN; text columns keep strings
    (missing -> ""). Returns the columns and the comment lines above the header.
    """
    header_line, names, comments = _scan_header(path)
    dupes = sorted({n for n in names if names.count(n) > 1} & set(wanted))
    if dupes:
        raise DataError(f"{str(path)!r}: column(s) {dupes!r} appear more than once in the header {names!r}")
    missing = [w for w in wanted if w not in names]
    if missing:
        raise DataError(f"{str(path)!r}: missing column(s) {missing!r}; the header has {names!r}")
    numeric = list(wanted) + [o for o in optional if o in names and o not in wanted]
    text_cols = [c for c in text if c in names]
    idx = [names.index(c) for c in numeric]
    out: dict[str, np.ndarray] = {}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # numpy warns on an empty data section
            data = np.loadtxt(
                path, delimiter=",", skiprows=header_line + 1, usecols=idx, ndmin=2, comments="#",
                dtype=np.float64, encoding="utf-8-sig",
            )
            tdata = [
                np.loadtxt(path, delimiter=",", skiprows=header_line + 1, usecols=[names.index(c)], ndmin=1,
                           comments="#", dtype=str, encoding="utf-8-sig")
                for c in text_cols
            ]
        for j, c in enumerate(numeric):
            out[c] = np.ascontiguousarray(data[:, j])
        for c, arr in zip(text_cols, tdata):
            out[c] = np.char.strip(arr.astype(str))
    except (ValueError, UserWarning, IndexError):
        out = _read_table_slow(path, header_line, names, numeric, text_cols)
    n = next(iter(out.values())).size
    if n == 0:
        raise DataError(f"{str(path)!r} is empty: a header {names!r} but no data rows")
    return out, comments


def _read_table_slow(
    path: Path, header_line: int, names: list[str], numeric: list[str], text_cols: list[str]
) -> dict[str, np.ndarray]:
    """csv-module parser: exact diagnostics for ragged rows and non-numbers, NaN for missing."""
    idx = {c: names.index(c) for c in numeric + text_cols}
    need = max(idx.values()) + 1
    values: dict[str, list[Any]] = {c: [] for c in idx}
    with open(path, encoding="utf-8-sig", newline="") as fh:
        for lineno, row in enumerate(csv.reader(fh)):
            if lineno <= header_line or not row or (len(row) == 1 and not row[0].strip()):
                continue
            if row[0].lstrip().startswith("#"):
                continue
            if len(row) < need:
                raise FileFormatError(
                    f"{str(path)!r}, line {lineno + 1}: {len(row)} field(s), expected {len(names)} as in the header"
                )
            for c in numeric:
                token = row[idx[c]].strip()
                if token in _MISSING_TOKENS:
                    values[c].append(math.nan)
                    continue
                try:
                    values[c].append(float(token))
                except ValueError:
                    raise FileFormatError(
                        f"{str(path)!r}, line {lineno + 1}, column {c!r}: {token!r} is not a number"
                    ) from None
            for c in text_cols:
                values[c].append(row[idx[c]].strip())
    out = {c: np.asarray(values[c], dtype=np.float64) for c in numeric}
    out.update({c: np.asarray(values[c], dtype=str) for c in text_cols})
    return out


# ----------------------------------------------------------------------------- BorealTC
_BOREALTC_FILE = re.compile(r"^(imu|pro)_(\d+)\.csv$")


def read_borealtc_run(
    imu_csv: str | os.PathLike[str],
    pro_csv: str | os.PathLike[str],
    track_width_m: float = BOREALTC_TRACK_WIDTH_M,
    ground_label: str | None = None,
    *,
    robot: str = "husky_a200",
    repair: str | Iterable[str] = (),
    allow_gaps: bool = False,
    gap_factor: float = DEFAULT_GAP_FACTOR,
    check_units: bool = True,
) -> InteractionLog:
    """Read one BorealTC run (``imu_NN.csv`` + ``pro_NN.csv``) into an InteractionLog.

    ``pro_NN.csv`` (``time,curL,curR,velL,velR``, ~6.5 Hz) gives the drive stream:
    measured wheel speeds (m/s) turned into ``v = (velL + velR) / 2`` and
    ``omega = (velR - velL) / track_width_m`` (``meta.velocity_source = "measured"``) and the
    motor currents (A). ``imu_NN.csv`` (``time,wx,wy,wz,ax,ay,az``, ~100 Hz) gives
    ``accel_z_mps2 = az`` (gravity included). Both clocks start at zero but the files end
    at different times; they are aligned on the overlap ``[max(starts), min(ends)]``: drive
    samples outside it are dropped, and the IMU keeps the samples from the last one at or
    before the first kept drive time to the first one at or after the last kept drive
    time, so every drive time lies inside the acceleration record. The counts dropped are
    written to ``meta.notes``.

    Parameters
    ----------
    imu_csv, pro_csv : path-like
        The two files of one run.
    track_width_m : float
        Track width B used for omega (m). The default is the Husky's geometric 0.555 m; a
        skid-steer robot's effective track width is larger (fit it when you can).
    ground_label : str, optional
        Run-level ground label (``read_borealtc`` passes the folder name, lowercased).
    robot : str
        Robot name for the metadata.
    repair, allow_gaps, gap_factor, check_units
        See the module docstring.

    Returns
    -------
    InteractionLog

    Raises
    ------
    FileFormatError
        A file is missing or unparsable.
    DataError
        Missing columns, empty files, unsorted/duplicated timestamps, NaNs or gaps (unless
        repaired/allowed), streams that do not overlap.
    UnitError
        Currents or speeds whose magnitude contradicts A or m/s.
    InvalidParameterError, UnknownNameError
        Bad ``track_width_m``, ``ground_label``, ``gap_factor`` or repair names.

    Examples
    --------
    Usage (needs data or fitted models, so not run as a doctest)::

        log = read_borealtc_run("SNOW/imu_00.csv", "SNOW/pro_00.csv", ground_label="snow")
    """
    track_width_m = _check_track_width(track_width_m)
    if ground_label is not None and (not isinstance(ground_label, str) or not ground_label):
        raise InvalidParameterError(f"ground_label must be a non-empty str or None, got {ground_label!r}")
    repairs = _parse_repair(repair)
    gap_factor = _check_gap_factor(gap_factor)
    imu_path, pro_path = Path(imu_csv), Path(pro_csv)
    pro, _ = _read_table(pro_path, ("time", "curL", "curR", "velL", "velR"))
    imu, _ = _read_table(imu_path, ("time", "az"))
    src_p, src_i = str(pro_path), str(imu_path)
    tp, pc, _ = _clean_stream(
        src_p, "drive stream", pro["time"], {k: pro[k] for k in ("curL", "curR", "velL", "velR")},
        repairs, allow_gaps, gap_factor,
    )
    ti, ic, _ = _clean_stream(src_i, "IMU stream", imu["time"], {"az": imu["az"]}, repairs, allow_gaps, gap_factor)
    if check_units:
        _check_current(src_p, "curL", pc["curL"], "A")
        _check_current(src_p, "curR", pc["curR"], "A")
        for k in ("velL", "velR"):
            _check_limit(src_p, k, pc[k], MAX_SPEED_MPS, "m/s", "wheel speeds look like mm/s or cm/s")
        _check_accel(src_i, "az", ic["az"])
    t0, t1 = max(tp[0], ti[0]), min(tp[-1], ti[-1])
    keep = (tp >= t0) & (tp <= t1)
    if t1 < t0 or not keep.any():
        raise DataError(
            f"{src_p} spans [{float(tp[0])!r}, {float(tp[-1])!r}] s and {src_i} spans [{float(ti[0])!r}, {float(ti[-1])!r}] s: "
            f"they do not overlap"
        )
    td = tp[keep]
    acc = _bracket_accel(td, ti)
    dropped_d = int((~keep).sum())
    dropped_a = ti.size - (acc.stop - acc.start)
    vl, vr = pc["velL"][keep], pc["velR"][keep]
    notes = (
        f"BorealTC run; imu={src_i}; aligned on the overlap [{t0:g}, {t1:g}] s: dropped {dropped_d} drive "
        f"sample(s) outside it and {dropped_a} IMU sample(s) outside the kept drive span "
        f"[{td[0]:g}, {td[-1]:g}] s (bracketing samples kept); v=(velL+velR)/2, omega=(velR-velL)/{track_width_m:g} m"
    )
    if dropped_d or dropped_a:
        _LOG.debug("%s: %s", src_p, notes)
    return InteractionLog(
        time_s=td,
        v_mps=0.5 * (vl + vr),
        omega_radps=(vr - vl) / track_width_m,
        current_left_a=pc["curL"][keep],
        current_right_a=pc["curR"][keep],
        accel_time_s=ti[acc],
        accel_z_mps2=ic["az"][acc],
        meta=LogMeta(
            robot=robot,
            source=src_p,
            ground_label=ground_label,
            velocity_source="measured",
            track_width_m=track_width_m,
            notes=notes,
        ),
    )


def read_borealtc(
    directory: str | os.PathLike[str],
    grounds: Iterable[str] | None = None,
    **kwargs: Any,
) -> list[InteractionLog]:
    """Read every run of a BorealTC-layout directory (``GROUND/imu_NN.csv`` + ``GROUND/pro_NN.csv``).

    Parameters
    ----------
    directory : path-like
        Directory holding one sub-directory per ground (e.g. ``ASPHALT``, ``SNOW``).
    grounds : iterable of str, optional
        Ground folders to read (case-insensitive); all folders with run files by default.
    **kwargs
        Passed to :func:`read_borealtc_run` (``track_width_m``, ``repair``, ...).

    Returns
    -------
    list of InteractionLog
        Sorted by ground folder name, then run number; ``meta.ground_label`` is the folder
        name lowercased.

    Raises
    ------
    FileFormatError
        ``directory`` does not exist or is not a directory.
    UnknownNameError
        A requested ground has no folder.
    DataError
        No runs found, or an ``imu_NN.csv`` without its ``pro_NN.csv`` (or the reverse);
        plus everything :func:`read_borealtc_run` raises.
    """
    root = Path(directory)
    if not root.is_dir():
        raise FileFormatError(f"BorealTC directory {str(root)!r} does not exist or is not a directory")
    if "ground_label" in kwargs:
        raise InvalidParameterError("read_borealtc takes ground labels from the folder names; do not pass ground_label")
    folders = {
        p.name: p for p in sorted(root.iterdir())
        if p.is_dir() and any(_BOREALTC_FILE.match(f.name) for f in p.iterdir())
    }
    if grounds is None:
        chosen = sorted(folders)
    else:
        wanted = [grounds] if isinstance(grounds, str) else list(grounds)
        by_lower = {name.lower(): name for name in folders}
        unknown = [g for g in wanted if not isinstance(g, str) or g.lower() not in by_lower]
        if unknown:
            raise UnknownNameError(
                f"grounds {unknown!r} have no folder in {str(root)!r}; available: {sorted(folders)!r}"
            )
        chosen = sorted({by_lower[g.lower()] for g in wanted})
    logs: list[InteractionLog] = []
    for name in chosen:
        runs: dict[int, dict[str, Path]] = {}
        for f in folders[name].iterdir():
            m = _BOREALTC_FILE.match(f.name)
            if m:
                runs.setdefault(int(m.group(2)), {})[m.group(1)] = f
        unpaired = sorted(str(p) for pair in runs.values() if len(pair) != 2 for p in pair.values())
        if unpaired:
            raise DataError(f"BorealTC files without their imu/pro partner: {unpaired!r}")
        for nn in sorted(runs):
            logs.append(read_borealtc_run(runs[nn]["imu"], runs[nn]["pro"], ground_label=name.lower(), **kwargs))
    if not logs:
        raise DataError(f"no BorealTC runs (GROUND/imu_NN.csv + pro_NN.csv) found in {str(root)!r}")
    return logs


# -------------------------------------------------------------------------- generic CSV
def _unit_factor(field: str, unit: str) -> float:
    table = _UNIT_TABLES[_FIELD_KIND[field]]
    if unit not in table:
        raise UnknownNameError(f"unit {unit!r} is not known for field {field!r}; expected one of {tuple(table)!r}")
    return table[unit]


def read_csv_log(
    path: str | os.PathLike[str],
    columns: Mapping[str, str] | None = None,
    units: Mapping[str, str] | None = None,
    *,
    robot: str | None = None,
    ground_label: str | None = None,
    velocity_source: str | None = None,
    track_width_m: float | None = None,
    rates: str = "mixed",
    repair: str | Iterable[str] = (),
    allow_gaps: bool = False,
    gap_factor: float = DEFAULT_GAP_FACTOR,
    check_units: bool = True,
) -> InteractionLog:
    """Read an interaction log from one CSV file with a column map and declared units.

    Layout: a header line (lines starting with ``#`` before or between rows are comments),
    one row per timestamp. Missing fields are empty or ``nan``. ``rates`` says how rows map
    to the drive and acceleration streams:

    - ``"single"``: every row is a sample of both streams, so any missing field is a NaN
      of its stream (DataError unless ``repair=("interpolate_nans",)``). Use it for
      single-rate files: nothing is ever moved out of a stream.
    - ``"mixed"`` (default; the layout :func:`write_csv_log` writes): the two streams have
      different rates and are interleaved by time. A row is an acceleration sample when its
      acceleration field is present, and a drive sample when any drive field (a pose field
      or a ground label included) is present, or when the acceleration field is missing
      too; a missing value among present drive fields is a NaN. So a row whose drive
      fields are all empty is an IMU-only row and one without acceleration a drive-only
      row; how many of each were split is logged (INFO) and written to ``meta.notes``.
      In a single-rate file such rows are lost samples: read it with ``rates="single"``.

    Parameters
    ----------
    path : path-like
    columns : mapping field -> column name, optional
        Fields (:data:`CSV_FIELDS`): ``time``, ``accel_z``, ``current_left``,
        ``current_right`` (required); ``v`` and ``omega``, or ``speed_left`` and
        ``speed_right`` (wheel speeds, with ``track_width_m``; v = mean, omega =
        (right - left) / track_width_m); optional ``x``, ``y``, ``heading`` (all three) and
        ``ground`` (text labels). Default: :data:`DEFAULT_CSV_COLUMNS`, the layout written by
        :func:`write_csv_log` (optional columns used when present).
    units : mapping field -> unit, optional
        Declared unit per field (:data:`CSV_UNITS`: current ``"A"``/``"mA"``; speed
        ``"m/s"``, ``"cm/s"``, ``"mm/s"``, ``"km/h"``; omega ``"rad/s"``/``"deg/s"``; time
        ``"s"``, ``"ms"``, ``"us"``, ``"ns"``; accel ``"m/s^2"``/``"g"``; x/y ``"m"``,
        ``"cm"``, ``"mm"``; heading ``"rad"``/``"deg"``). Undeclared fields are SI.
    robot, ground_label, velocity_source, track_width_m : optional
        Metadata. ``None`` takes the value from a :func:`write_csv_log` header when the file
        has one; otherwise robot ``"unknown"``, velocity ``"measured"`` for wheel speeds and
        ``"commanded"`` for v/omega.
    rates : {"mixed", "single"}
        Whether the file interleaves streams of different rates (see above).
    repair, allow_gaps, gap_factor, check_units
        See the module docstring.

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

        log = read_csv_log("run.csv", columns={"time": "t", "v": "cmd_v", "omega": "cmd_w",
            "current_left": "iL", "current_right": "iR", "accel_z": "az"},
            units={"current_left": "mA", "current_right": "mA"})
    """
    path = Path(path)
    src = str(path)
    if rates not in CSV_RATES:
        raise UnknownNameError(f"rates must be one of {CSV_RATES!r}, got {rates!r}")
    repairs = _parse_repair(repair)
    gap_factor = _check_gap_factor(gap_factor)
    explicit = columns is not None
    colmap = dict(DEFAULT_CSV_COLUMNS if columns is None else columns)
    unknown = [f for f in colmap if f not in _FIELD_KIND]
    if unknown:
        raise UnknownNameError(f"columns has unknown field(s) {unknown!r}; expected fields from {CSV_FIELDS!r}")
    units = dict(units or {})
    unknown = [f for f in units if f not in colmap or f == "ground"]
    if unknown:
        raise UnknownNameError(f"units given for field(s) {unknown!r} that are not numeric columns of the map {colmap!r}")
    factors = {f: _unit_factor(f, units.get(f, next(iter(_UNIT_TABLES[_FIELD_KIND[f]])))) for f in colmap if f != "ground"}

    header_line, header, comments = _scan_header(path)
    file_meta: dict[str, Any] = {}
    for line in comments:
        if line.startswith(_CSV_MAGIC.strip()):
            try:
                file_meta = json.loads(line[len(_CSV_MAGIC.strip()):].strip())
                if not isinstance(file_meta, dict):
                    raise ValueError("not a JSON object")
            except ValueError as exc:
                raise FileFormatError(f"{src}: corrupt terrawatt-log header line {line!r}: {exc}") from exc
            version = file_meta.get("format_version")
            if version != CSV_LOG_FORMAT_VERSION:
                raise FormatVersionError(
                    f"{src} has terrawatt-log format version {version!r}; this terrawatt reads version "
                    f"{CSV_LOG_FORMAT_VERSION}"
                )
            break

    has_v = "v" in colmap or "omega" in colmap
    has_wheels = "speed_left" in colmap or "speed_right" in colmap
    if has_v and has_wheels:
        raise InvalidParameterError("columns must map either v/omega or speed_left/speed_right, not both")
    if not has_v and not has_wheels:
        raise InvalidParameterError("columns must map v and omega, or speed_left and speed_right")
    vel_fields = ("speed_left", "speed_right") if has_wheels else ("v", "omega")
    required = ["time", "accel_z", "current_left", "current_right", *vel_fields]
    absent = [f for f in required if f not in colmap]
    if absent:
        raise InvalidParameterError(f"columns lacks required field(s) {absent!r}; got {colmap!r}")
    if track_width_m is None and has_wheels:
        track_width_m = file_meta.get("track_width_m")
    if has_wheels:
        if track_width_m is None:
            raise InvalidParameterError("wheel speeds (speed_left/speed_right) need track_width_m to derive omega")
        track_width_m = _check_track_width(track_width_m)
    pose_fields = [f for f in ("x", "y", "heading") if f in colmap]
    optional_fields: list[str] = []
    if explicit:
        if pose_fields and len(pose_fields) != 3:
            raise InvalidParameterError(f"columns must map all of x, y, heading or none, got {pose_fields!r}")
    else:  # default layout: pose and ground only when the file has them
        pose_fields = [f for f in ("x", "y", "heading") if colmap[f] in header]
        if pose_fields and len(pose_fields) != 3:
            raise DataError(f"{src}: the header has only {pose_fields!r} of the pose columns x_m, y_m, heading_rad")
        optional_fields = pose_fields
        if colmap["ground"] not in header:
            del colmap["ground"]
    numeric_fields = required + (pose_fields if explicit else [])
    text_fields = ["ground"] if "ground" in colmap else []
    table, _ = _read_table(
        path,
        [colmap[f] for f in numeric_fields],
        optional=[colmap[f] for f in optional_fields],
        text=[colmap[f] for f in text_fields],
    )
    if text_fields and colmap["ground"] not in table:
        raise DataError(f"{src}: missing column {colmap['ground']!r}; the header has {header!r}")
    num = {f: table[colmap[f]] * factors[f] for f in numeric_fields + optional_fields}
    drive_fields = [f for f in num if f not in ("time", "accel_z")]
    t_all = num["time"]
    split_note = ""
    if rates == "single":
        acc_rows = drive_rows = np.ones(t_all.size, dtype=bool)
    else:
        present = [np.isfinite(num[f]) for f in drive_fields]
        if text_fields:
            present.append(np.char.str_len(table[colmap["ground"]]) > 0)
        acc_rows = np.isfinite(num["accel_z"])
        drive_rows = np.column_stack(present).any(axis=1) | ~acc_rows
        split_note = (
            f"rates='mixed': {t_all.size} row(s) split into {int((drive_rows & acc_rows).sum())} drive+IMU, "
            f"{int((drive_rows & ~acc_rows).sum())} drive-only and {int((acc_rows & ~drive_rows).sum())} IMU-only "
            f"(all drive fields empty) row(s)"
        )
        _LOG.info("%s: %s", src, split_note)
    extra = {"ground": table[colmap["ground"]][drive_rows]} if text_fields else None
    td, dc, de = _clean_stream(
        src, "drive stream", t_all[drive_rows], {f: num[f][drive_rows] for f in drive_fields},
        repairs, allow_gaps, gap_factor, extra,
    )
    ta, ac, _ = _clean_stream(
        src, "acceleration stream", t_all[acc_rows], {"accel_z": num["accel_z"][acc_rows]},
        repairs, allow_gaps, gap_factor,
    )
    ground = None
    if text_fields:
        ground = de["ground"]
        empty = np.char.str_len(ground) == 0
        if empty.any():
            i = int(np.argmax(empty))
            raise DataError(
                f"{src}: drive stream: {int(empty.sum())} empty ground label(s), first at index {i} (t={float(td[i])!r} s)"
            )
    if check_units:
        for f in ("current_left", "current_right"):
            _check_current(src, colmap[f], dc[f], units.get(f, "A"))
        for f in vel_fields:
            if _FIELD_KIND[f] == "speed":
                _check_limit(src, colmap[f], dc[f], MAX_SPEED_MPS, "m/s", f"declared {units.get(f, 'm/s')!r} looks like mm/s or cm/s")
            else:
                _check_limit(src, colmap[f], dc[f], MAX_OMEGA_RADPS, "rad/s", f"declared {units.get(f, 'rad/s')!r} looks like deg/s")
        _check_accel(src, colmap["accel_z"], ac["accel_z"])
    if has_wheels:
        v = 0.5 * (dc["speed_left"] + dc["speed_right"])
        omega = (dc["speed_right"] - dc["speed_left"]) / track_width_m
    else:
        v, omega = dc["v"], dc["omega"]
    pose = np.column_stack([dc["x"], dc["y"], dc["heading"]]) if pose_fields else None
    if velocity_source is None:
        velocity_source = file_meta.get("velocity_source") or ("measured" if has_wheels else "commanded")
    if velocity_source not in VELOCITY_SOURCES:
        raise InvalidParameterError(f"velocity_source must be one of {VELOCITY_SOURCES!r}, got {velocity_source!r}")
    notes = [file_meta.get("notes") or "", f"read from {src}", split_note]
    if file_meta.get("source"):
        notes.append(f"original source: {file_meta['source']}")
    declared = {f: u for f, u in units.items() if factors[f] != 1.0}
    if declared:
        notes.append(f"converted to SI from {declared!r}")
    start_ns = file_meta.get("start_time_ns")
    return InteractionLog(
        time_s=td,
        v_mps=v,
        omega_radps=omega,
        current_left_a=dc["current_left"],
        current_right_a=dc["current_right"],
        accel_time_s=ta,
        accel_z_mps2=ac["accel_z"],
        pose_xyh=pose,
        ground=ground,
        meta=LogMeta(
            robot=robot if robot is not None else str(file_meta.get("robot") or "unknown"),
            source=src,
            ground_label=ground_label if ground_label is not None else file_meta.get("ground_label"),
            velocity_source=velocity_source,
            track_width_m=track_width_m if track_width_m is not None else file_meta.get("track_width_m"),
            notes="; ".join(n for n in notes if n),
            start_time_ns=int(start_ns) if isinstance(start_ns, int) else None,
        ),
    )


def write_csv_log(log: InteractionLog, path: str | os.PathLike[str]) -> Path:
    """Write a log in the generic CSV layout, atomically (temporary file, then rename).

    The first line is ``# terrawatt-log {json}`` with the format version and the metadata;
    then the header ``time_s,v_mps,omega_radps,current_left_a,current_right_a,accel_z_mps2``
    (+ ``x_m,y_m,heading_rad`` with a pose, + ``ground`` with labels) and one row per
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
    cols: list[tuple[str, np.ndarray, np.ndarray]] = [
        ("v_mps", log.v_mps, di),
        ("omega_radps", log.omega_radps, di),
        ("current_left_a", log.current_left_a, di),
        ("current_right_a", log.current_right_a, di),
        ("accel_z_mps2", log.accel_z_mps2, ai),
    ]
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
    meta = log.meta
    head = {
        "format_version": CSV_LOG_FORMAT_VERSION,
        "robot": meta.robot,
        "source": meta.source,
        "ground_label": meta.ground_label,
        "velocity_source": meta.velocity_source,
        "track_width_m": meta.track_width_m,
        "notes": meta.notes,
        "start_time_ns": None if meta.start_time_ns is None else int(meta.start_time_ns),
    }
    lines = [_CSV_MAGIC + json.dumps(head), ",".join(names)]
    lines += [",".join(r) for r in zip(*table)]
    write_text_atomic(path, "\n".join(lines) + "\n")
    return path


# ----------------------------------------------------------------------------- ROS bags
_TWIST_TYPES = ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped")
_ODOM_TYPES = ("nav_msgs/msg/Odometry",)
_IMU_TYPES = ("sensor_msgs/msg/Imu",)
_SCALAR_TYPES = ("std_msgs/msg/Float64", "std_msgs/msg/Float32")
_ARRAY_TYPES = ("std_msgs/msg/Float64MultiArray", "std_msgs/msg/Float32MultiArray")


def _stamp_ns(msg: Any) -> int:
    stamp = msg.header.stamp
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def read_rosbag(
    path: str | os.PathLike[str],
    cmd_vel_topic: str = "/cmd_vel",
    imu_topic: str = "/imu/data",
    current_topics: str | Sequence[str] = ("/drive/current_left", "/drive/current_right"),
    *,
    current_unit: str = "A",
    robot: str = "unknown",
    ground_label: str | None = None,
    use_header_stamps: bool = True,
    max_clock_offset_s: float = MAX_CLOCK_OFFSET_S,
    cmd_vel_timeout_s: float | None = 0.5,
    repair: str | Iterable[str] = (),
    allow_gaps: bool = False,
    gap_factor: float = DEFAULT_GAP_FACTOR,
    check_units: bool = True,
) -> InteractionLog:
    """Read an interaction log from a ROS 1 ``.bag``, a ROS 2 bag (sqlite3 ``.db3`` or MCAP).

    Needs the ``ros`` extra (``pip install 'terrawatt[ros]'``, i.e. ``rosbags``).

    Topics and message types (conventions of this reader):

    - ``cmd_vel_topic``: ``geometry_msgs/msg/Twist`` or ``TwistStamped`` (commanded;
      ``linear.x`` m/s, ``angular.z`` rad/s), or ``nav_msgs/msg/Odometry`` (measured
      ``twist.twist``; its pose becomes ``pose_xyh`` with the yaw of the orientation).
    - ``imu_topic``: ``sensor_msgs/msg/Imu``; ``linear_acceleration.z`` (gravity included).
    - per-side drive current, in ``current_unit`` (``"A"`` or ``"mA"``): either two topics
      ``(left, right)`` of ``std_msgs/msg/Float64`` or ``Float32`` (``data``), or one topic
      of ``std_msgs/msg/Float64MultiArray`` / ``Float32MultiArray`` whose ``data`` is
      exactly ``[left, right]``.

    Timestamps: a topic whose messages carry a header uses the header stamps when
    ``use_header_stamps`` and every stamp is non-zero; otherwise (and for std_msgs
    topics) the bag receive time; ``meta.notes`` says which. Header stamps come from the
    publishers' clocks and receive times from the recorder's, and the current topics are
    always on receive time, so a clock offset would shift vibration (and odometry) against
    current. For each topic read on header stamps the reader takes the median of
    (receive time - header stamp), written to ``meta.notes``; if its magnitude exceeds
    ``max_clock_offset_s`` (default :data:`MAX_CLOCK_OFFSET_S` = 0.5 s, well above
    transport latency) it raises DataError rather than guess: pass
    ``use_header_stamps=False`` to put every topic on the receive time. Times are seconds
    since the earliest timestamp used (``meta.start_time_ns`` keeps that absolute time).

    Alignment: the drive stream is sampled at the current messages (the left topic's with
    two topics; the right current is interpolated linearly onto them), inside the
    overlap of the current and IMU streams (and of the odometry stream, if used).
    Commands are held (zero-order hold) from the last message at or before each drive
    time; with ``cmd_vel_timeout_s`` set, a command older than that — or no command yet —
    counts as zero (robots stop when commands stop). With ``cmd_vel_timeout_s=None`` the
    command is held indefinitely and drive samples before the first command are
    dropped. Commands are event-like, so pauses between them are not gaps; the gap check
    applies to the current, IMU and odometry streams. Odometry is interpolated linearly
    (heading unwrapped). The IMU stream keeps the samples bracketing the drive stream.

    Parameters
    ----------
    path : path-like
        ``.bag`` file, ROS 2 bag directory, or the ``.db3`` / ``.mcap`` file inside one.
    cmd_vel_topic, imu_topic, current_topics : str
        Topic names (see above).
    current_unit : {"A", "mA"}
    robot, ground_label : metadata
    use_header_stamps : bool
    max_clock_offset_s : float
        Largest tolerated |median(receive time - header stamp)| of a topic read on header
        stamps (s, finite, > 0).
    cmd_vel_timeout_s : float or None
    repair, allow_gaps, gap_factor, check_units
        See the module docstring.

    Returns
    -------
    InteractionLog

    Raises
    ------
    OptionalDependencyError
        ``rosbags`` is not installed.
    FileFormatError
        Missing or unreadable bag.
    DataError
        A topic is missing or has no messages, has an unexpected type, a multi-array of
        the wrong length; header stamps more than ``max_clock_offset_s`` away from the
        receive times; streams that do not overlap; plus the checks of the module
        docstring (unsorted or duplicated timestamps, NaNs, gaps; ``repair`` and
        ``allow_gaps`` work as in the CSV readers).
    UnitError, UnknownNameError, InvalidParameterError
        As documented in the module docstring; unknown ``current_unit``; bad timeout or
        ``max_clock_offset_s``.
    """
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError as exc:
        raise OptionalDependencyError(
            "read_rosbag needs the optional dependency 'rosbags': pip install 'terrawatt[ros]'"
        ) from exc
    if current_unit not in _UNIT_TABLES["current"]:
        raise UnknownNameError(f"current_unit must be one of {tuple(_UNIT_TABLES['current'])!r}, got {current_unit!r}")
    if cmd_vel_timeout_s is not None and (
        isinstance(cmd_vel_timeout_s, bool)
        or not isinstance(cmd_vel_timeout_s, (int, float))
        or not math.isfinite(cmd_vel_timeout_s)
        or cmd_vel_timeout_s <= 0
    ):
        raise InvalidParameterError(f"cmd_vel_timeout_s must be a finite number > 0 or None, got {cmd_vel_timeout_s!r}")
    if (
        isinstance(max_clock_offset_s, bool)
        or not isinstance(max_clock_offset_s, (int, float))
        or not math.isfinite(max_clock_offset_s)
        or max_clock_offset_s <= 0
    ):
        raise InvalidParameterError(f"max_clock_offset_s must be a finite number > 0, got {max_clock_offset_s!r}")
    if ground_label is not None and (not isinstance(ground_label, str) or not ground_label):
        raise InvalidParameterError(f"ground_label must be a non-empty str or None, got {ground_label!r}")
    topics_cur = (current_topics,) if isinstance(current_topics, str) else tuple(current_topics)
    if len(topics_cur) not in (1, 2) or not all(isinstance(x, str) for x in topics_cur):
        raise InvalidParameterError(
            f"current_topics must be one topic name (a [left, right] multi-array) or two (left, right), got {current_topics!r}"
        )
    repairs = _parse_repair(repair)
    gap_factor = _check_gap_factor(gap_factor)
    bag = Path(path)
    if bag.is_file() and bag.suffix in (".db3", ".mcap") and (bag.parent / "metadata.yaml").exists():
        bag = bag.parent
    if not bag.exists():
        raise FileFormatError(f"bag {str(bag)!r} does not exist")
    src = str(bag)
    wanted = (cmd_vel_topic, imu_topic, *topics_cur)
    raw: dict[str, list[tuple[int, Any]]] = {t: [] for t in wanted}
    types: dict[str, str] = {}
    try:
        with AnyReader([bag], default_typestore=get_typestore(Stores.LATEST)) as reader:
            available = {c.topic: c.msgtype for c in reader.connections}
            missing = [t for t in wanted if t not in available]
            if missing:
                raise DataError(f"{src}: topic(s) {missing!r} not in the bag; it has {available!r}")
            types = {t: available[t] for t in wanted}
            conns = [c for c in reader.connections if c.topic in raw]
            for conn, ts_ns, data in reader.messages(connections=conns):
                raw[conn.topic].append((ts_ns, reader.deserialize(data, conn.msgtype)))
    except (DataError, OptionalDependencyError):
        raise
    except Exception as exc:  # rosbags raises its own error classes per format
        raise FileFormatError(f"cannot read bag {src!r}: {type(exc).__name__}: {exc}") from exc

    def expect(topic: str, allowed: tuple[str, ...]) -> str:
        if types[topic] not in allowed:
            raise DataError(f"{src}: topic {topic!r} has type {types[topic]!r}; expected one of {allowed!r}")
        if not raw[topic]:
            raise DataError(f"{src}: topic {topic!r} has no messages")
        return types[topic]

    notes: list[str] = []

    def stamps(topic: str) -> np.ndarray:
        msgs = raw[topic]
        received = np.array([ts for ts, _ in msgs], dtype=np.int64)
        if use_header_stamps and hasattr(msgs[0][1], "header"):
            hdr = np.array([_stamp_ns(m) for _, m in msgs], dtype=np.int64)
            if (hdr != 0).all():
                offset_s = float(np.median(received - hdr)) / 1e9
                if abs(offset_s) > max_clock_offset_s:
                    raise DataError(
                        f"{src}: topic {topic!r}: median (receive time - header stamp) is {offset_s!r} s, "
                        f"expected within +/-{max_clock_offset_s!r} s (max_clock_offset_s): the publisher's "
                        f"and the recorder's clocks disagree, and the receive-time current topics would be "
                        f"shifted against this topic; pass use_header_stamps=False to put every topic on the "
                        f"receive time"
                    )
                notes.append(f"{topic}: header stamps (median receive time - stamp {offset_s:.3g} s)")
                return hdr
            notes.append(f"{topic}: receive time ({int((hdr == 0).sum())} zero header stamp(s))")
        else:
            notes.append(f"{topic}: receive time")
        return received

    vel_type = expect(cmd_vel_topic, _TWIST_TYPES + _ODOM_TYPES)
    expect(imu_topic, _IMU_TYPES)
    if len(topics_cur) == 2:
        for t in topics_cur:
            expect(t, _SCALAR_TYPES)
    else:
        expect(topics_cur[0], _ARRAY_TYPES)
        arrays = [np.asarray(m.data, dtype=np.float64).reshape(-1) for _, m in raw[topics_cur[0]]]
        bad = [i for i, a in enumerate(arrays) if a.size != 2]
        if bad:
            raise DataError(
                f"{src}: topic {topics_cur[0]!r}: {len(bad)} message(s) do not hold exactly [left, right], first at "
                f"index {bad[0]} with {arrays[bad[0]].size} value(s)"
            )
    streams_ns = {t: stamps(t) for t in wanted}
    origin = int(min(s.min() for s in streams_ns.values()))

    def secs(topic: str) -> np.ndarray:
        return (streams_ns[topic] - origin).astype(np.float64) / 1e9

    # velocity stream
    vmsgs = [m for _, m in raw[cmd_vel_topic]]
    measured = vel_type in _ODOM_TYPES
    if measured:
        tw = [m.twist.twist for m in vmsgs]
    elif vel_type == "geometry_msgs/msg/TwistStamped":
        tw = [m.twist for m in vmsgs]
    else:
        tw = vmsgs
    vcols = {
        "v": np.array([x.linear.x for x in tw], dtype=np.float64),
        "omega": np.array([x.angular.z for x in tw], dtype=np.float64),
    }
    if measured:
        pos = [m.pose.pose for m in vmsgs]
        q = np.array([[p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z] for p in pos])
        vcols["x"] = np.array([p.position.x for p in pos], dtype=np.float64)
        vcols["y"] = np.array([p.position.y for p in pos], dtype=np.float64)
        vcols["heading"] = np.arctan2(2 * (q[:, 0] * q[:, 3] + q[:, 1] * q[:, 2]), 1 - 2 * (q[:, 2] ** 2 + q[:, 3] ** 2))
    tv, vc, _ = _clean_stream(src, cmd_vel_topic, secs(cmd_vel_topic), vcols, repairs, allow_gaps or not measured, gap_factor)
    # IMU stream
    ti, ic, _ = _clean_stream(
        src, imu_topic, secs(imu_topic),
        {"accel_z": np.array([m.linear_acceleration.z for _, m in raw[imu_topic]], dtype=np.float64)},
        repairs, allow_gaps, gap_factor,
    )
    # current stream(s)
    scale = _UNIT_TABLES["current"][current_unit]
    if len(topics_cur) == 1:
        stacked = np.vstack(arrays) * scale
        tc, cc, _ = _clean_stream(
            src, topics_cur[0], secs(topics_cur[0]), {"left": stacked[:, 0], "right": stacked[:, 1]},
            repairs, allow_gaps, gap_factor,
        )
        cur_l, cur_r = cc["left"], cc["right"]
        t_right = tc
    else:
        tc, cl, _ = _clean_stream(
            src, topics_cur[0], secs(topics_cur[0]),
            {"left": np.array([m.data for _, m in raw[topics_cur[0]]], dtype=np.float64) * scale},
            repairs, allow_gaps, gap_factor,
        )
        t_right, cr, _ = _clean_stream(
            src, topics_cur[1], secs(topics_cur[1]),
            {"right": np.array([m.data for _, m in raw[topics_cur[1]]], dtype=np.float64) * scale},
            repairs, allow_gaps, gap_factor,
        )
        cur_l, cur_r = cl["left"], cr["right"]
    if check_units:
        _check_current(src, f"{topics_cur[0]} (left)", cur_l, current_unit)
        _check_current(src, f"{topics_cur[-1]} (right)", cur_r, current_unit)
        _check_limit(src, f"{cmd_vel_topic} linear.x", vc["v"], MAX_SPEED_MPS, "m/s", "speeds look like mm/s or cm/s")
        _check_limit(src, f"{cmd_vel_topic} angular.z", vc["omega"], MAX_OMEGA_RADPS, "rad/s", "yaw rates look like deg/s")
        _check_accel(src, f"{imu_topic} linear_acceleration.z", ic["accel_z"])

    spans = [(tc[0], tc[-1]), (t_right[0], t_right[-1]), (ti[0], ti[-1])]
    if measured:
        spans.append((tv[0], tv[-1]))
    t0 = max(s[0] for s in spans)
    t1 = min(s[1] for s in spans)
    if not measured and cmd_vel_timeout_s is None:
        t0 = max(t0, tv[0])
    keep = (tc >= t0) & (tc <= t1)
    if t1 < t0 or not keep.any():
        raise DataError(
            f"{src}: the streams do not overlap (current [{float(spans[0][0])!r}, {float(spans[0][1])!r}] s, IMU [{float(spans[2][0])!r}, {float(spans[2][1])!r}] s, "
            f"velocity [{float(tv[0])!r}, {float(tv[-1])!r}] s)"
        )
    td = tc[keep]
    cur_l = cur_l[keep]
    cur_r = np.interp(td, t_right, cur_r) if len(topics_cur) == 2 else cur_r[keep]
    pose = None
    if measured:
        v = np.interp(td, tv, vc["v"])
        omega = np.interp(td, tv, vc["omega"])
        h = np.interp(td, tv, np.unwrap(vc["heading"]))
        pose = np.column_stack([np.interp(td, tv, vc["x"]), np.interp(td, tv, vc["y"]), np.pi - np.mod(np.pi - h, 2 * np.pi)])
    else:
        idx = np.searchsorted(tv, td, side="right") - 1
        valid = idx >= 0
        if cmd_vel_timeout_s is not None:
            valid &= (td - tv[np.maximum(idx, 0)]) <= cmd_vel_timeout_s
        v = np.where(valid, vc["v"][np.maximum(idx, 0)], 0.0)
        omega = np.where(valid, vc["omega"][np.maximum(idx, 0)], 0.0)
        notes.append(
            "commands held from the last message" + (
                f", zero after {cmd_vel_timeout_s:g} s without one ({int((~valid).sum())} drive sample(s))"
                if cmd_vel_timeout_s is not None else ""
            )
        )
    acc = _bracket_accel(td, ti)
    notes.append(
        f"aligned on the overlap [{t0:g}, {t1:g}] s: dropped {int((~keep).sum())} drive sample(s) outside it and "
        f"{ti.size - (acc.stop - acc.start)} IMU sample(s) outside the kept drive span (bracketing samples kept)"
    )
    return InteractionLog(
        time_s=td,
        v_mps=v,
        omega_radps=omega,
        current_left_a=cur_l,
        current_right_a=cur_r,
        accel_time_s=ti[acc],
        accel_z_mps2=ic["accel_z"][acc],
        pose_xyh=pose,
        meta=LogMeta(
            robot=robot,
            source=src,
            ground_label=ground_label,
            velocity_source="measured" if measured else "commanded",
            notes="; ".join(notes),
            start_time_ns=origin,
        ),
    )
