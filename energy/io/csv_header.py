"""The ``# terrawatt-log {json}`` header line of the generic CSV layout: version and metadata."""

from __future__ import annotations

import json
import math
from typing import Any

from terrawatt_base.errors import FileFormatError, FormatVersionError

from ..logs import VELOCITY_SOURCES, LogMeta

__all__ = [
    "CSV_LOG_FORMAT_VERSION",
    "LOG_HEADER_PREFIX",
    "MAX_LOG_HEADER_CHARS",
    "format_log_header",
    "parse_log_header",
]

#: Version of the generic CSV layout written by :func:`~energy.io.write_csv_log`.
CSV_LOG_FORMAT_VERSION = 1
#: Start of the header line (a CSV comment), followed by one JSON object.
LOG_HEADER_PREFIX = "# terrawatt-log"
#: Longest header line read (characters); metadata notes are a few hundred.
MAX_LOG_HEADER_CHARS = 1_000_000

_TEXT_KEYS = ("robot", "source", "notes", "missing_currents")


def format_log_header(meta: LogMeta) -> str:
    """The header line of a log with metadata ``meta`` (no trailing newline).

    Examples
    --------
    >>> format_log_header(LogMeta(robot="husky"))[:46]
    '# terrawatt-log {"format_version": 1, "robot":'
    """
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
    if meta.gravity_removed:
        head["gravity_removed"] = True
    if meta.missing_currents:
        head["missing_currents"] = meta.missing_currents
    return f"{LOG_HEADER_PREFIX} {json.dumps(head)}"


def _bad(source: str, key: str, value: Any, expected: str) -> FileFormatError:
    text = repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return FileFormatError(f"{source}: terrawatt-log header: {key!r} must be {expected}, got {text}")


def parse_log_header(line: str, source: str) -> dict[str, Any]:
    """The metadata of a header line, every value checked (``None`` for absent keys).

    Keys: ``robot``, ``source``, ``notes`` (str), ``ground_label`` (non-empty str),
    ``velocity_source`` (one of ``VELOCITY_SOURCES``), ``track_width_m`` (finite > 0),
    ``start_time_ns`` (int), ``gravity_removed`` (bool), ``missing_currents`` (str);
    unknown keys are ignored.

    Raises
    ------
    FileFormatError
        Not one JSON object (too long, too deeply nested, not JSON), or a value of the
        wrong type; the message names the file and the key.
    FormatVersionError
        A ``format_version`` other than :data:`CSV_LOG_FORMAT_VERSION`.

    Examples
    --------
    >>> parse_log_header('# terrawatt-log {"format_version": 1, "notes": 3}', "run.csv")
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.FileFormatError: run.csv: terrawatt-log header: 'notes' must be a string or null, got 3
    """
    payload = line[len(LOG_HEADER_PREFIX):].strip()
    if len(payload) > MAX_LOG_HEADER_CHARS:
        raise FileFormatError(
            f"{source}: corrupt terrawatt-log header line: {len(payload)} characters, more than "
            f"{MAX_LOG_HEADER_CHARS} (expected one JSON object of metadata)"
        )
    try:
        data = json.loads(payload)
    except RecursionError:
        raise FileFormatError(f"{source}: corrupt terrawatt-log header line {line[:60]!r}...: nested too deeply") from None
    except ValueError as exc:
        raise FileFormatError(f"{source}: corrupt terrawatt-log header line {line[:120]!r}: {exc}") from None
    if not isinstance(data, dict):
        raise FileFormatError(f"{source}: corrupt terrawatt-log header line {line[:120]!r}: not a JSON object")
    version = data.get("format_version")
    if isinstance(version, bool) or version != CSV_LOG_FORMAT_VERSION:
        raise FormatVersionError(
            f"{source} has terrawatt-log format version {version!r:.40}; this terrawatt reads version "
            f"{CSV_LOG_FORMAT_VERSION}"
        )
    out: dict[str, Any] = {"format_version": version}
    for key in _TEXT_KEYS:
        value = data.get(key)
        if value is not None and not isinstance(value, str):
            raise _bad(source, key, value, "a string or null")
        out[key] = value
    label = data.get("ground_label")
    if label is not None and (not isinstance(label, str) or not label):
        raise _bad(source, "ground_label", label, "a non-empty string or null")
    out["ground_label"] = label
    vsrc = data.get("velocity_source")
    if vsrc is not None and vsrc not in VELOCITY_SOURCES:
        raise _bad(source, "velocity_source", vsrc, f"one of {list(VELOCITY_SOURCES)!r} or null")
    out["velocity_source"] = vsrc
    tw = data.get("track_width_m")
    if tw is not None:
        number = isinstance(tw, (int, float)) and not isinstance(tw, bool) and abs(tw) < 1e300
        if not number or not math.isfinite(tw) or tw <= 0:
            raise _bad(source, "track_width_m", tw, "a finite number > 0 or null")
        tw = float(tw)
    out["track_width_m"] = tw
    start = data.get("start_time_ns")
    if start is not None and (isinstance(start, bool) or not isinstance(start, int) or not -(2**63) <= start < 2**63):
        raise _bad(source, "start_time_ns", start, "a 64-bit integer or null")
    out["start_time_ns"] = start
    gravity = data.get("gravity_removed")
    if gravity is not None and not isinstance(gravity, bool):
        raise _bad(source, "gravity_removed", gravity, "true, false or null")
    out["gravity_removed"] = gravity
    return out
