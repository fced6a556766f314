"""Interaction logs: one robot run's drive, current and vibration streams on one clock.

Modules: :mod:`~energy.logs.meta` (run metadata), :mod:`~energy.logs.gaps` (the gap rule
shared with the readers), :mod:`~energy.logs.arrays` (validation of the log's arrays),
:mod:`~energy.logs.interaction_log` (the log itself). Readers of files live in
:mod:`energy.io`.
"""

from .gaps import DEFAULT_GAP_FACTOR, check_gap_factor, gap_steps, median_period_s
from .interaction_log import RESAMPLE_METHODS, InteractionLog
from .meta import VELOCITY_SOURCES, LogMeta

__all__ = [
    "LogMeta",
    "InteractionLog",
    "VELOCITY_SOURCES",
    "RESAMPLE_METHODS",
    "DEFAULT_GAP_FACTOR",
    "check_gap_factor",
    "gap_steps",
    "median_period_s",
]
