"""Run-level metadata of an interaction log: robot, source, ground, velocity source, IMU facts."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.checks import check_optional_real
from terrawatt_base.errors import InvalidParameterError

__all__ = ["VELOCITY_SOURCES", "UNLABELLED", "LogMeta", "robot_matches", "named_robots", "run_names", "ground_name"]

#: Allowed values of :attr:`LogMeta.velocity_source`.
VELOCITY_SOURCES = ("commanded", "measured")
#: Robot names that name no robot (a log that does not say which robot drove it).
UNNAMED_ROBOTS = ("", "unknown")


def robot_matches(preset_name: str, log_robot: str) -> bool:
    """Whether a log's robot name is the robot ``preset_name`` (the preset name contained in it, any case).

    Examples
    --------
    >>> robot_matches("husky", "Husky_A200"), robot_matches("husky", "jackal")
    (True, False)
    """
    return str(preset_name).strip().lower() in str(log_robot).strip().lower()


def named_robots(names: Iterable[str]) -> list[str]:
    """The distinct robot names that name a robot (not :data:`UNNAMED_ROBOTS`), sorted.

    Examples
    --------
    >>> named_robots(["husky", "unknown", "", "husky", "Jackal"])
    ['Jackal', 'husky']
    """
    return sorted({str(n) for n in names if str(n).strip().lower() not in UNNAMED_ROBOTS})


#: The ground name of a log without a ground label (:func:`ground_name`).
UNLABELLED = "unlabelled"


def ground_name(log: Any) -> str:
    """A log's ground label as text, :data:`UNLABELLED` without one (anything with a :class:`LogMeta` ``meta``)."""
    return str(log.meta.ground_label) if log.meta.ground_label is not None else UNLABELLED


def run_names(logs: Iterable[Any]) -> list[str]:
    """A unique name per log (anything with a :class:`LogMeta` ``meta``): ``<ground>/<source file stem>`` (``run``
    without a source; ``#k`` added to repeats).

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> run_names([NS(meta=LogMeta(source="a/pro_00.csv", ground_label="snow")), NS(meta=LogMeta(ground_label="snow")),
    ...            NS(meta=LogMeta(ground_label="snow"))])
    ['snow/pro_00', 'snow/synthetic#0', 'snow/synthetic#1']
    """
    names = []
    for log in logs:
        stem = Path(log.meta.source).stem if log.meta.source else "run"
        names.append(f"{log.meta.ground_label}/{stem}")
    seen: dict[str, int] = {}
    out = []
    for n in names:
        k = seen.get(n, 0)
        seen[n] = k + 1
        out.append(n if names.count(n) == 1 else f"{n}#{k}")
    return out


@dataclass(frozen=True)
class LogMeta:
    """Run-level metadata of an :class:`~energy.logs.InteractionLog`.

    Parameters
    ----------
    robot : str
        Name of the robot (e.g. ``"husky_a200"``).
    source : str
        Where the data came from: a file path, ``"synthetic"``, ...
    ground_label : str or None
        Ground of the whole run (e.g. ``"snow"``), when known.
    velocity_source : {"commanded", "measured"}
        Whether ``v_mps`` / ``omega_radps`` are the commands sent to the robot or speeds
        measured on it (wheel odometry).
    track_width_m : float or None
        Track width used to derive ``omega_radps`` from wheel speeds, when it was derived.
    notes : str
        Free text: alignment, repairs and resampling applied by readers and methods.
    start_time_ns : int or None
        Absolute time of ``time_s == 0`` in ns since the Unix epoch, when the source has one
        (ROS bags); ``None`` for sources whose clock starts at zero.
    gravity_removed : bool
        The IMU's ``accel_z_mps2`` has gravity removed (median about 0 instead of about
        +9.81 m/s^2 at rest); readers set it and say so in ``notes``. The vibration features
        remove each window's mean, so they do not need gravity.
    missing_currents : str
        Why the log has no drive currents (e.g. which topics the bag lacked), empty when
        it has them; part of the error a training or scoring function raises on such a log.

    Raises
    ------
    InvalidParameterError
        Non-string names, an unknown ``velocity_source``, a non-positive track width.
    """

    robot: str = "unknown"
    source: str = "synthetic"
    ground_label: str | None = None
    velocity_source: str = "commanded"
    track_width_m: float | None = None
    notes: str = ""
    start_time_ns: int | None = None
    gravity_removed: bool = False
    missing_currents: str = ""

    def __post_init__(self) -> None:
        for name in ("robot", "source", "notes", "missing_currents"):
            value = getattr(self, name)
            if not isinstance(value, str):
                raise InvalidParameterError(f"LogMeta.{name} must be a str, got {value!r}")
        if self.ground_label is not None and (not isinstance(self.ground_label, str) or not self.ground_label):
            raise InvalidParameterError(
                f"LogMeta.ground_label must be a non-empty str or None, got {self.ground_label!r}"
            )
        if self.velocity_source not in VELOCITY_SOURCES:
            raise InvalidParameterError(
                f"LogMeta.velocity_source must be one of {VELOCITY_SOURCES!r}, got {self.velocity_source!r}"
            )
        tw = check_optional_real("track_width_m", self.track_width_m, low=0.0, low_inclusive=False, owner="LogMeta")
        object.__setattr__(self, "track_width_m", tw)
        if self.start_time_ns is not None and (
            isinstance(self.start_time_ns, bool) or not isinstance(self.start_time_ns, (int, np.integer))
        ):
            raise InvalidParameterError(f"LogMeta.start_time_ns must be an int or None, got {self.start_time_ns!r}")
        if not isinstance(self.gravity_removed, (bool, np.bool_)):
            raise InvalidParameterError(f"LogMeta.gravity_removed must be a bool, got {self.gravity_removed!r}")
        object.__setattr__(self, "gravity_removed", bool(self.gravity_removed))
