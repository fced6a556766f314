"""Argument validation shared by the whole library: one checker per kind of argument.

Every public function of ``terrain``, ``energy`` and ``planner`` checks its user-facing
arguments through these, so one kind of argument follows one rule everywhere: a seed valid
in one call is valid in every call, a string where a number is expected names the parameter,
and every failure is an :class:`~terrawatt_base.errors.InvalidParameterError` (also a
``ValueError``) whose message names the parameter, shows the value and says what was
expected.

Examples
--------
>>> check_real("speed_mps", 0.5, low=0.0, low_inclusive=False)
0.5
>>> check_real("speed_mps", "fast")
Traceback (most recent call last):
...
terrawatt_base.errors.InvalidParameterError: speed_mps must be a real number, got 'fast' (str)
>>> check_seed(None), check_seed(7)
(None, 7)
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from typing import Any

import numpy as np

from .errors import InvalidParameterError, UnknownNameError

__all__ = [
    "SEED_LIMIT",
    "plain_repr",
    "check_real",
    "check_optional_real",
    "check_int",
    "check_shape",
    "check_seed",
    "check_text",
    "check_choice",
    "check_bool",
    "check_instance",
    "real_array",
    "readonly",
    "fmt_number",
    "fmt_pct",
]

#: Seeds are ``None`` or integers in ``[0, SEED_LIMIT)`` (numpy's and OMPL's common range).
SEED_LIMIT = 2**32


def _label(name: str, owner: str | None) -> str:
    return f"{owner}.{name}" if owner else name


def plain_repr(value: object) -> str:
    """``repr`` for messages, numpy scalars shown as the Python numbers they hold (``10.0``, not ``np.float64(10.0)``).

    Examples
    --------
    >>> plain_repr(np.float64(10.0)), plain_repr(np.int64(3)), plain_repr("a")
    ('10.0', '3', "'a'")
    """
    if isinstance(value, np.generic):
        value = value.item()
    return repr(value)


def _describe(value: object) -> str:
    text = plain_repr(value)
    if len(text) > 80:
        text = text[:77] + "..."
    return f"{text} ({type(value).__name__})"


def fmt_pct(value: float) -> str:
    """A percentage for people: two significant digits, but never fewer than its whole part
    (``-100.3`` reads ``-100``, not ``-1e+02``).

    Examples
    --------
    >>> fmt_pct(-100.3), fmt_pct(5.94), fmt_pct(0.0123), fmt_pct(1234.5)
    ('-100', '5.9', '0.012', '1234')
    """
    v = float(value)
    if not math.isfinite(v) or abs(v) < 1.0:
        return fmt_number(v, 2)
    return fmt_number(v, max(2, len(str(int(abs(v))))))


def fmt_number(value: float, digits: int = 4) -> str:
    """A number rounded for people: ``49.000000000001066`` reads ``49``.

    Examples
    --------
    >>> fmt_number(49.000000000001066), fmt_number(0.0123456), fmt_number(1e308)
    ('49', '0.01235', '1e+308')
    """
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        text = str(abs(int(value)))
        sign = "-" if value < 0 else ""
        return sign + (text if len(text) <= 16 else f"{text[0]}.{text[1:digits]}e+{len(text) - 1}")
    v = float(value)
    if not math.isfinite(v):
        return repr(v)
    return f"{v:.{digits}g}"


def check_real(
    name: str,
    value: Any,
    *,
    low: float | None = None,
    high: float | None = None,
    low_inclusive: bool = True,
    high_inclusive: bool = True,
    owner: str | None = None,
) -> float:
    """A finite real number in an optional range, as ``float``.

    Booleans, strings, ``None``, NaN and infinities are refused (numpy scalars and 0-d
    arrays of a real dtype are accepted).

    Parameters
    ----------
    name : str
        The parameter's name, as the caller spells it.
    value : object
        The value to check.
    low, high : float, optional
        Bounds; ``low_inclusive`` / ``high_inclusive`` say whether they are allowed.
    owner : str, optional
        Prefix of the name in messages (e.g. a dataclass: ``"RobotParams"``).

    Raises
    ------
    InvalidParameterError
        Not a finite real number, or out of range.
    """
    label = _label(name, owner)
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise InvalidParameterError(f"{label} must be a real number, got {_describe(value)}", parameter=name)
    try:
        v = float(value)
    except OverflowError:  # an int beyond float range, e.g. 10**400
        v = math.inf
    if not math.isfinite(v):
        raise InvalidParameterError(f"{label} must be finite, got {fmt_number(value)}", parameter=name)
    if low is not None and (v < low or (v == low and not low_inclusive)):
        op = ">=" if low_inclusive else ">"
        raise InvalidParameterError(f"{label} must be {op} {fmt_number(low)}, got {plain_repr(value)}", parameter=name)
    if high is not None and (v > high or (v == high and not high_inclusive)):
        op = "<=" if high_inclusive else "<"
        raise InvalidParameterError(f"{label} must be {op} {fmt_number(high)}, got {plain_repr(value)}", parameter=name)
    return v


def check_optional_real(name: str, value: Any, **bounds: Any) -> float | None:
    """``None``, or :func:`check_real` of ``value`` with the same keyword bounds."""
    return None if value is None else check_real(name, value, **bounds)


def check_int(
    name: str, value: Any, *, low: int | None = None, high: int | None = None, owner: str | None = None
) -> int:
    """An integer (not a bool, not a float) in the closed range ``[low, high]``, as ``int``.

    Raises
    ------
    InvalidParameterError
        Not an integer, or out of range.
    """
    label = _label(name, owner)
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise InvalidParameterError(f"{label} must be an integer, got {_describe(value)}", parameter=name)
    v = int(value)
    if low is not None and v < low:
        raise InvalidParameterError(f"{label} must be >= {low}, got {plain_repr(value)}", parameter=name)
    if high is not None and v > high:
        raise InvalidParameterError(f"{label} must be <= {high}, got {plain_repr(value)}", parameter=name)
    return v


def check_shape(name: str, value: Any, *, low: int = 1) -> tuple[int, int]:
    """A raster shape: a pair ``(rows, cols)`` of integers (not bools, not floats), each ``>= low``.

    Examples
    --------
    >>> check_shape("shape", (3, 4))
    (3, 4)

    Raises
    ------
    InvalidParameterError
        Not a pair of integers, or an entry below ``low``.
    """
    try:
        rows, cols = value
    except (TypeError, ValueError):
        rows = cols = None
    ok = all(
        isinstance(v, numbers.Integral) and not isinstance(v, (bool, np.bool_)) and int(v) >= low for v in (rows, cols)
    )
    if not ok:
        raise InvalidParameterError(f"{name} must be (rows, cols) of integers >= {low}, got {_describe(value)}")
    return int(rows), int(cols)  # type: ignore[arg-type]


def check_seed(seed: Any, name: str = "seed") -> int | None:
    """The library's one seed rule: ``None`` (fresh entropy) or an integer in ``[0, 2**32)``.

    Raises
    ------
    InvalidParameterError
        Anything else (negative, too large, a float, a bool, a string).
    """
    if seed is None:
        return None
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, numbers.Integral) or not 0 <= int(seed) < SEED_LIMIT:
        raise InvalidParameterError(f"{name} must be None or an integer in [0, 2**32), got {_describe(seed)}")
    return int(seed)


def check_text(name: str, value: Any, *, owner: str | None = None) -> str:
    """A non-empty, non-blank string.

    Raises
    ------
    InvalidParameterError
        Not a string, or blank.
    """
    if not isinstance(value, str) or not value.strip():
        raise InvalidParameterError(f"{_label(name, owner)} must be a non-empty string, got {_describe(value)}",
                                    parameter=name)
    return value


def check_choice(name: str, value: Any, choices: Iterable[str]) -> str:
    """One of ``choices`` (a string).

    Raises
    ------
    UnknownNameError
        Not one of them; the message lists the valid names.
    """
    options = tuple(choices)
    if not isinstance(value, str) or value not in options:
        raise UnknownNameError(f"{name} must be one of {list(options)!r}, got {value!r}", parameter=name)
    return value


def check_instance(name: str, value: Any, kind: type, what: str | None = None) -> Any:
    """``value`` itself if it is a ``kind``, else an :class:`InvalidParameterError` naming ``name``.

    Parameters
    ----------
    name : str
        The parameter's name, as the caller spells it.
    value : object
        The value to check.
    kind : type
        The class it must be an instance of.
    what : str, optional
        How the message names the class (default ``"a <class name>"``).

    Examples
    --------
    >>> check_instance("n", 3, int)
    3
    >>> check_instance("n", "3", int)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: n must be an int, got '3' (str)
    """
    if not isinstance(value, kind):
        if what is None:
            what = ("an " if kind.__name__[:1] in "AEIOUaeiou" else "a ") + kind.__name__
        raise InvalidParameterError(f"{name} must be {what}, got {_describe(value)}", parameter=name)
    return value


def check_bool(name: str, value: Any) -> bool:
    """A real ``bool`` (numpy's too): ``"no"`` or ``0`` are refused rather than read as truth values."""
    if not isinstance(value, (bool, np.bool_)):
        raise InvalidParameterError(f"{name} must be True or False, got {_describe(value)}", parameter=name)
    return bool(value)


def real_array(name: str, value: Any, *, ndim: int | None = None, finite: bool = True) -> np.ndarray:
    """``value`` as a float64 array (a new array), optionally of a given ``ndim``, all finite.

    Only numbers are numbers: strings are refused even when they spell one (``"0.5"``), so a
    column read as text never passes as data.

    Raises
    ------
    InvalidParameterError
        Not numeric (booleans, strings, objects, complex), wrong number of dimensions, or NaN / inf entries
        (with ``finite``); the message counts the bad entries.
    """
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nested sequences
        raise InvalidParameterError(f"{name} must be a real number or an array of them, got {_describe(value)}",
                                    parameter=name) from exc
    if raw.dtype.kind not in "iuf":  # booleans, strings ("0.5" is not parsed), objects, complex
        raise InvalidParameterError(
            f"{name} must be a real number or an array of them, got {_describe(value)} of dtype {raw.dtype}"
        )
    arr = np.array(raw, dtype=np.float64, copy=True)
    if ndim is not None and arr.ndim != ndim:
        raise InvalidParameterError(f"{name} must be a {ndim}-D array, got shape {arr.shape!r}", parameter=name)
    if finite and not np.all(np.isfinite(arr)):
        n_bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise InvalidParameterError(f"{name} has {n_bad} NaN/inf entries of {arr.size}; expected finite values",
                                    parameter=name)
    return arr


def readonly(value: Any, dtype: Any = None) -> np.ndarray:
    """A read-only copy of ``value`` (as ``dtype`` when given): results never alias inputs."""
    out = np.array(value, dtype=dtype, copy=True)
    out.setflags(write=False)
    return out
