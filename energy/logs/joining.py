"""Joining interaction logs: the checks and the joined arrays and metadata of a concatenation."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from terrawatt_base.checks import fmt_number
from terrawatt_base.errors import DataError

from .arrays import DRIVE_FIELDS, IMU_FIELDS

__all__ = ["join_notes", "concatenated_fields"]


def join_notes(*parts: str) -> str:
    """The non-empty parts joined by ``"; "``.

    Examples
    --------
    >>> join_notes("read from a.csv", "", "resampled")
    'read from a.csv; resampled'
    """
    return "; ".join(p for p in parts if p)


def concatenated_fields(items: Sequence[Any]) -> dict[str, Any]:
    """The constructor arguments of the log joining ``items`` (interaction logs, in time order).

    See :meth:`~energy.logs.InteractionLog.concatenate` for the rules.

    Raises
    ------
    DataError
        Overlapping or out-of-order logs; disagreeing robot, velocity source or track
        width; pose, ground or an optional stream (currents, battery voltage, gyro) present
        in some logs only.
    """
    first = items[0]
    for i, log in enumerate(items[1:], start=1):
        prev = items[i - 1]
        for attr in ("robot", "velocity_source", "track_width_m"):
            if getattr(log.meta, attr) != getattr(first.meta, attr):
                raise DataError(
                    f"cannot concatenate: logs[{i}].meta.{attr}={getattr(log.meta, attr)!r} differs from "
                    f"logs[0].meta.{attr}={getattr(first.meta, attr)!r}"
                )
        if log.time_s[0] <= prev.time_s[-1] or log.accel_time_s[0] <= prev.accel_time_s[-1]:
            raise DataError(
                f"cannot concatenate: logs[{i}] starts at t={fmt_number(float(log.time_s[0]), 9)} s (accel "
                f"{fmt_number(float(log.accel_time_s[0]), 9)} s), not after logs[{i - 1}] ends at t={fmt_number(float(prev.time_s[-1]), 9)} s "
                f"(accel {fmt_number(float(prev.accel_time_s[-1]), 9)} s); shift it with .shifted(offset_s)"
            )
    out: dict[str, Any] = {}
    for name in ("time_s", "accel_time_s", "pose_xyh", *DRIVE_FIELDS, *IMU_FIELDS):
        present = [getattr(log, name) is not None for log in items]
        if any(present) and not all(present):
            hint = " (read every run with its current topics or fields)" if name.startswith("current") else ""
            raise DataError(f"cannot concatenate: {name} present in logs {present!r} (need all or none){hint}")
        out[name] = np.concatenate([getattr(log, name) for log in items]) if all(present) else None
    out["ground"] = None
    if any(log.ground is not None for log in items):
        labels = [log.ground_labels for log in items]
        missing = [i for i, g in enumerate(labels) if g is None]
        if missing:
            raise DataError(
                f"cannot concatenate: logs {missing!r} have neither per-sample ground nor "
                f"meta.ground_label while others have ground labels"
            )
        out["ground"] = np.concatenate([np.asarray(g, dtype=str) for g in labels])
    run_labels = {log.meta.ground_label for log in items}
    sources = list(dict.fromkeys(log.meta.source for log in items))
    notes = list(dict.fromkeys(log.meta.notes for log in items if log.meta.notes))
    missing_currents = list(dict.fromkeys(log.meta.missing_currents for log in items if log.meta.missing_currents))
    out["meta"] = replace(
        first.meta,
        source="; ".join(sources),
        ground_label=run_labels.pop() if len(run_labels) == 1 else None,
        notes=join_notes(*notes, f"concatenation of {len(items)} logs"),
        gravity_removed=any(log.meta.gravity_removed for log in items),
        missing_currents="; ".join(missing_currents),
    )
    return out
