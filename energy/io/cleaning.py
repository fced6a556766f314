"""Stream cleaning and unit checks shared by every reader: repairs, gaps, plausible magnitudes.

Thresholds are module constants (see :mod:`energy.io` for the rules). Each check raises a
:class:`~terrawatt_base.errors.DataError` (or its subclass :class:`~terrawatt_base.errors.UnitError`)
naming the source, the stream or column, the offending value rounded for people and the way
out (a repair, ``allow_gaps=True`` or ``check_units=False``).
"""

from __future__ import annotations

import logging
import math
import warnings
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_bool, check_real, fmt_number
from terrawatt_base.errors import DataError, DataRepairWarning, InvalidParameterError, UnitError, UnknownNameError

from ..logs import DEFAULT_GAP_FACTOR, check_gap_factor, gap_steps

__all__ = [
    "LogCleaning",
    "REPAIRS",
    "UNIT_FACTORS",
    "MAX_MEDIAN_CURRENT_A",
    "MAX_P99_CURRENT_A",
    "MIN_PEAK_CURRENT_A",
    "MAX_SPEED_MPS",
    "MAX_OMEGA_RADPS",
    "MAX_MEDIAN_ACCEL_MPS2",
    "MIN_STREAM_RATE_HZ",
    "MAX_STREAM_RATE_HZ",
    "MAX_RUN_DURATION_S",
    "MAX_BATTERY_VOLTAGE_V",
    "GRAVITY_REMOVED_MAX_MPS2",
    "parse_repair",
    "clean_stream",
    "check_current",
    "check_limit",
    "check_accel",
    "check_timing",
    "check_track_width",
    "bracket_accel",
    "gravity_note",
]

_LOG = logging.getLogger(__name__)

#: Repairs a caller may ask a reader for, applied in this order.
REPAIRS = ("sort", "drop_duplicates", "interpolate_nans")

#: Unit-check thresholds (see :mod:`energy.io`).
MAX_MEDIAN_CURRENT_A = 100.0
#: No ground robot's drive draws this much most of the time it draws anything (BorealTC's
#: Husky peaks at ~35 A): a 99th percentile of the non-zero |I| above it is mA declared as A.
MAX_P99_CURRENT_A = 300.0
MIN_PEAK_CURRENT_A = 0.05
MAX_SPEED_MPS = 10.0
MAX_OMEGA_RADPS = 20.0
MAX_MEDIAN_ACCEL_MPS2 = 50.0
#: Plausible sampling rates of a recorded drive, current or IMU stream (Hz). BorealTC's
#: drive files run at 6.5 Hz and its IMU at 100 Hz; a Clearpath status message (currents,
#: battery voltage) comes at about 1 Hz, a little less with jitter; times in ms read as s
#: give 0.0065 Hz, times in s declared as ms give 100 kHz.
MIN_STREAM_RATE_HZ = 0.5
MAX_STREAM_RATE_HZ = 10_000.0
#: Longest plausible single run (s): one day. BorealTC's runs last 10 s to 5 min.
MAX_RUN_DURATION_S = 86_400.0
#: Highest plausible battery voltage of a ground robot (V); 12-58 V packs are usual, so a
#: larger value is a voltage in mV.
MAX_BATTERY_VOLTAGE_V = 200.0
#: An IMU whose median vertical acceleration lies within +/- this (m/s^2) reports it with
#: gravity removed (gravity included gives about +9.81, or 8.5 on a 30 deg slope).
GRAVITY_REMOVED_MAX_MPS2 = 3.0
#: |median| of a vertical acceleration that says "in g, gravity included" (1 g give or take a tilt).
G_UNITS_BAND = (0.8, 1.25)

#: Factors to SI of the units a reader accepts, per kind of quantity (the first is SI).
UNIT_FACTORS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9},
    "speed": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3, "km/h": 1.0 / 3.6},
    "omega": {"rad/s": 1.0, "deg/s": math.pi / 180.0},
    "current": {"A": 1.0, "mA": 1e-3},
    "accel": {"m/s^2": 1.0, "m/s2": 1.0, "g": 9.80665},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3},
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
    "voltage": {"V": 1.0, "mV": 1e-3},
}


@dataclass(frozen=True)
class LogCleaning:
    """How every log reader checks and cleans its streams (module docstring of :mod:`energy.io`): one value.

    Parameters
    ----------
    repair : str or iterable of str
        Repairs asked for, from :data:`REPAIRS` (``"sort"``, ``"drop_duplicates"``,
        ``"interpolate_nans"``); none by default: such streams are refused.
    allow_gaps : bool
        Accept steps longer than ``gap_factor`` median periods (split the log later).
    gap_factor : float
        A step longer than this many median periods is a gap (> 1).
    check_units : bool
        Refuse values whose magnitude betrays a wrong unit.

    Raises
    ------
    UnknownNameError, InvalidParameterError
        An unknown repair; a bad flag or gap factor (the message names the parameter).

    Examples
    --------
    >>> LogCleaning(repair="sort").repairs
    frozenset({'sort'})
    """

    repair: str | Iterable[str] = ()
    allow_gaps: bool = False
    gap_factor: float = DEFAULT_GAP_FACTOR
    check_units: bool = True

    def __post_init__(self) -> None:
        repairs = parse_repair(self.repair)
        object.__setattr__(self, "repair", tuple(r for r in REPAIRS if r in repairs))
        object.__setattr__(self, "allow_gaps", check_bool("allow_gaps", self.allow_gaps))
        object.__setattr__(self, "gap_factor", check_gap_factor(self.gap_factor))
        object.__setattr__(self, "check_units", check_bool("check_units", self.check_units))

    @property
    def repairs(self) -> frozenset[str]:
        """The repairs asked for, as :func:`parse_repair` gives them."""
        return frozenset(self.repair)

    @classmethod
    def check(cls, cleaning: LogCleaning | None) -> LogCleaning:
        """``cleaning``, or the default when None; anything else refused (parameter ``cleaning``)."""
        if cleaning is None:
            return cls()
        if not isinstance(cleaning, cls):
            raise InvalidParameterError(f"cleaning must be a LogCleaning, got {type(cleaning).__name__!r}",
                                        parameter="cleaning")
        return cleaning


def parse_repair(repair: str | Iterable[str]) -> frozenset[str]:
    """The set of repairs named by ``repair`` (one name or several, from :data:`REPAIRS`).

    Raises
    ------
    UnknownNameError
        A name that is not one of :data:`REPAIRS`.
    """
    items = (repair,) if isinstance(repair, str) else tuple(repair)
    unknown = [r for r in items if r not in REPAIRS]
    if unknown:
        raise UnknownNameError(f"repair must name only {REPAIRS!r}, got unknown {unknown!r}")
    return frozenset(items)


def _repaired(source: str, message: str) -> None:
    text = f"{source}: {message}"
    _LOG.warning(text)
    warnings.warn(text, DataRepairWarning, stacklevel=5)


def _t(value: float) -> str:
    return f"t={fmt_number(value, 9)} s"


def _sort(where, source, stream, t, cols, extra, repairs):
    d = np.diff(t)
    back = d < 0
    if not back.any():
        return t, cols, extra
    i = int(np.argmax(back)) + 1
    if "sort" not in repairs:
        raise DataError(
            f"{where}: timestamps are not sorted; {int(back.sum())} step(s) go backwards, first at index {i} "
            f"({_t(t[i])} after {_t(t[i - 1])}); pass repair=('sort',) to sort them"
        )
    order = np.argsort(t, kind="stable")
    _repaired(source, f"{stream}: sorted timestamps ({int(back.sum())} backward step(s))")
    return t[order], {k: v[order] for k, v in cols.items()}, {k: v[order] for k, v in extra.items()}


def _drop_duplicates(where, source, stream, t, cols, extra, repairs):
    dup = np.diff(t) == 0
    if not dup.any():
        return t, cols, extra
    i = int(np.argmax(dup)) + 1
    if "drop_duplicates" not in repairs:
        raise DataError(
            f"{where}: {int(dup.sum())} duplicated timestamp(s), first at index {i} ({_t(t[i])}); "
            f"pass repair=('drop_duplicates',) to keep the first sample of each"
        )
    keep = np.concatenate([[True], ~dup])
    _repaired(source, f"{stream}: dropped {int(dup.sum())} sample(s) with a duplicated timestamp")
    return t[keep], {k: v[keep] for k, v in cols.items()}, {k: v[keep] for k, v in extra.items()}


def _fill_nans(where, source, stream, t, cols, repairs):
    for name, values in list(cols.items()):
        bad = ~np.isfinite(values)
        if not bad.any():
            continue
        i = int(np.argmax(bad))
        if "interpolate_nans" not in repairs:
            raise DataError(
                f"{where}: column {name!r} has {int(bad.sum())} missing or non-finite value(s), first at "
                f"index {i} ({_t(t[i])}); pass repair=('interpolate_nans',) to interpolate them"
            )
        if bad.all():
            raise DataError(f"{where}: column {name!r} has no finite value at all; nothing to interpolate from")
        fixed = values.copy()
        fixed[bad] = np.interp(t[bad], t[~bad], values[~bad])
        cols[name] = fixed
        _repaired(source, f"{stream}: interpolated {int(bad.sum())} missing value(s) of column {name!r}")
    return cols


def clean_stream(
    source: str,
    stream: str,
    t: np.ndarray,
    cols: dict[str, np.ndarray],
    repairs: frozenset[str],
    allow_gaps: bool,
    gap_factor: float,
    extra: dict[str, np.ndarray] | None = None,
) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Check (and, when asked, repair) one stream; return its time, numeric and extra columns.

    Checks, in order: samples present, timestamps finite (never repaired), sorted
    (``"sort"``), without duplicates (``"drop_duplicates"``), values finite
    (``"interpolate_nans"``), and no gap longer than ``gap_factor`` median periods unless
    ``allow_gaps``. ``extra`` holds non-numeric columns (labels) that follow the row
    operations but are neither checked for NaN nor interpolated. Each repair is logged and
    warned with :class:`~terrawatt_base.errors.DataRepairWarning`.

    Raises
    ------
    DataError
        The first failed check that was not repaired or allowed.
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
    t, cols, extra = _sort(where, source, stream, t, cols, extra, repairs)
    t, cols, extra = _drop_duplicates(where, source, stream, t, cols, extra, repairs)
    cols = _fill_nans(where, source, stream, t, dict(cols), repairs)
    gaps = gap_steps(t, gap_factor)
    if gaps.size:
        i = int(gaps[0])
        threshold = gap_factor * float(np.median(np.diff(t)))
        msg = (
            f"{where}: {gaps.size} gap(s) longer than {gap_factor:g} median periods ({fmt_number(threshold)} s), "
            f"first from {_t(t[i])} to {_t(t[i + 1])} (after index {i})"
        )
        if not allow_gaps:
            raise DataError(
                msg + "; pass allow_gaps=True to keep them (then split with InteractionLog.split_at_gaps())"
            )
        _LOG.info(msg + " (allowed)")
    return t, cols, extra


def check_current(source: str, name: str, values_a: np.ndarray, unit: str) -> None:
    """UnitError when currents (in A) contradict their declared ``unit`` ("A" or "mA")."""
    mag = np.abs(values_a[np.isfinite(values_a)])
    if mag.size == 0:
        return
    if unit == "A":
        med = float(np.median(mag))
        peak = float(mag.max())
        nonzero = mag[mag > 0]
        p99 = float(np.percentile(nonzero, 99)) if nonzero.size else 0.0
        integers = bool(np.all(mag == np.round(mag)))
        if med > MAX_MEDIAN_CURRENT_A or p99 > MAX_P99_CURRENT_A or (peak >= 100.0 and integers):
            raise UnitError(
                f"{source}: {name} is declared in A but its values look like mA (median |I| = {fmt_number(med)} A, "
                f"99th percentile of the non-zero |I| = {fmt_number(p99)} A, peak {fmt_number(peak)} A, "
                f"integer-valued: {integers}; expected a median <= {MAX_MEDIAN_CURRENT_A:g} A and a "
                f"99th percentile <= {MAX_P99_CURRENT_A:g} A for a ground robot's drive); declare 'mA' "
                f"or pass check_units=False"
            )
    elif unit == "mA":
        peak = float(mag.max())
        if 0.0 < peak < MIN_PEAK_CURRENT_A:
            raise UnitError(
                f"{source}: {name} is declared in mA but its peak is {fmt_number(peak * 1e3)} mA (< "
                f"{MIN_PEAK_CURRENT_A * 1e3:g} mA): the values look like A; declare 'A' or pass check_units=False"
            )


def check_limit(source: str, name: str, values: np.ndarray, limit: float, unit_si: str, hint: str) -> None:
    """UnitError when ``|values|`` exceeds a plausible ``limit`` (in ``unit_si``)."""
    mag = np.abs(values[np.isfinite(values)])
    if mag.size and float(mag.max()) > limit:
        i = int(np.argmax(np.abs(np.where(np.isfinite(values), values, 0.0))))
        raise UnitError(
            f"{source}: |{name}| reaches {fmt_number(float(mag.max()))} {unit_si} (index {i}), above the plausible "
            f"{limit:g} {unit_si} for a ground robot: {hint}; fix the declared unit or pass check_units=False"
        )


def check_accel(source: str, name: str, values: np.ndarray) -> None:
    """UnitError when the median ``|a_z|`` exceeds :data:`MAX_MEDIAN_ACCEL_MPS2`."""
    mag = np.abs(values[np.isfinite(values)])
    if mag.size and float(np.median(mag)) > MAX_MEDIAN_ACCEL_MPS2:
        raise UnitError(
            f"{source}: median |{name}| is {fmt_number(float(np.median(mag)))} m/s^2 (> {MAX_MEDIAN_ACCEL_MPS2:g}): "
            f"the declared unit looks wrong (m/s^2 declared as g, or mm/s^2?); fix it or pass check_units=False"
        )


def check_timing(source: str, stream: str, t_s: np.ndarray) -> None:
    """UnitError when a stream's rate or duration is implausible for a recorded robot run.

    The median rate must lie in [:data:`MIN_STREAM_RATE_HZ`, :data:`MAX_STREAM_RATE_HZ`] and
    the span must not exceed :data:`MAX_RUN_DURATION_S`: times in ms read as s (BorealTC at
    0.0065 Hz over 9,385 s) or in s declared as ms fail here. Streams of one sample have no
    rate; their span is still checked.

    Examples
    --------
    >>> check_timing("run.csv", "IMU stream", np.arange(0.0, 20_000.0, 10.0))
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.UnitError: run.csv: IMU stream: median rate 0.1 Hz is below the plausible 0.5 Hz ...
    """
    if t_s.size == 0:
        return
    duration = float(t_s[-1] - t_s[0])
    hint = "the time unit looks wrong (ms read as s, or s declared as ms?); fix it or pass check_units=False"
    if t_s.size >= 2:
        step = float(np.median(np.diff(t_s)))
        rate = 1.0 / step if step > 0 else math.inf
        if rate < MIN_STREAM_RATE_HZ:
            raise UnitError(
                f"{source}: {stream}: median rate {fmt_number(rate)} Hz is below the plausible "
                f"{MIN_STREAM_RATE_HZ:g} Hz of a recorded robot stream (median step {fmt_number(step)} s); {hint}"
            )
        if rate > MAX_STREAM_RATE_HZ:
            raise UnitError(
                f"{source}: {stream}: median rate {fmt_number(rate)} Hz is above the plausible "
                f"{MAX_STREAM_RATE_HZ:g} Hz of a recorded robot stream (median step {fmt_number(step)} s); {hint}"
            )
    if duration > MAX_RUN_DURATION_S:
        raise UnitError(
            f"{source}: {stream}: spans {fmt_number(duration)} s, longer than the plausible "
            f"{MAX_RUN_DURATION_S:g} s (one day) of one run; {hint}"
        )


def check_track_width(track_width_m: Any) -> float:
    """``track_width_m`` as a float: a finite real number > 0 (InvalidParameterError otherwise)."""
    return check_real("track_width_m", track_width_m, low=0.0, low_inclusive=False)


def bracket_accel(t_drive: np.ndarray, t_acc: np.ndarray) -> slice:
    """Acceleration samples from the last one at or before the first drive time to the first
    one at or after the last drive time (drive times lie inside the acceleration span)."""
    ia = max(int(np.searchsorted(t_acc, t_drive[0], side="right")) - 1, 0)
    ib = min(int(np.searchsorted(t_acc, t_drive[-1], side="left")), t_acc.size - 1)
    return slice(ia, ib + 1)


def gravity_note(name: str, accel_z_mps2: np.ndarray, hint: str = "declare the acceleration's unit as g",
                 check_g: bool = True, parameter: str | None = None) -> str:
    """A note when the vertical acceleration has gravity removed, else ``""``; an IMU in g is refused.

    Gravity-free IMUs (e.g. a driver that publishes ``linear_acceleration`` minus gravity)
    give a median near 0 instead of about +9.81 m/s^2; the log is accepted (the vibration
    features remove each segment's mean) and the note goes to its metadata. A median of
    about 1 (within :data:`G_UNITS_BAND`) is an IMU publishing in g, gravity included: read as
    m/s^2 its vibration would be ten times too small, so it is refused with ``hint`` (how
    to declare the unit; ``parameter``: the reader's parameter it names, which the error carries);
    ``check_g=False`` (the readers' ``check_units=False``) skips that.

    Raises
    ------
    UnitError
        The acceleration looks like it is in g.

    Examples
    --------
    >>> gravity_note("az", np.array([0.05, 0.09, 0.12]))[:48]
    'az has gravity removed (median 0.09 m/s^2, |medi'
    >>> gravity_note("az", np.array([9.7, 9.8, 9.9]))
    ''
    """
    median = float(np.median(accel_z_mps2))
    if check_g and G_UNITS_BAND[0] <= abs(median) <= G_UNITS_BAND[1]:
        raise UnitError(
            f"{name}: median {fmt_number(median, 3)} looks like an acceleration in g with gravity included "
            f"(about 9.81 in m/s^2, about 0 with gravity removed); {hint}", parameter=parameter
        )
    if abs(median) >= GRAVITY_REMOVED_MAX_MPS2:
        return ""
    return (
        f"{name} has gravity removed (median {fmt_number(median, 3)} m/s^2, |median| < "
        f"{GRAVITY_REMOVED_MAX_MPS2:g} m/s^2); accepted: the vibration features remove each segment's mean"
    )
