"""Interaction logs: one robot run's drive, current, vibration and gyro streams on one clock.

Modules: :mod:`~energy.logs.meta` (run metadata), :mod:`~energy.logs.gaps` (the gap rule
shared with the readers), :mod:`~energy.logs.arrays` (the stream fields and the validation
of the log's arrays), :mod:`~energy.logs.joining` (concatenation),
:mod:`~energy.logs.interaction_log` (the log itself), :mod:`~energy.logs.rest` (which samples
stand still), :mod:`~energy.logs.slope` (the pitch under a run's poses on a map). Readers of files live in
:mod:`energy.io`.
"""

from .arrays import DRIVE_FIELDS, IMU_FIELDS, OPTIONAL_FIELDS
from .gaps import DEFAULT_GAP_FACTOR, check_gap_factor, gap_steps, median_period_s
from .interaction_log import RESAMPLE_METHODS, InteractionLog
from .meta import UNLABELLED, VELOCITY_SOURCES, LogMeta, ground_name, named_robots, robot_matches, run_names
from .rest import REST_ACCEL_MPS2, REST_ALPHA_RADPS2, REST_OMEGA_RADPS, REST_SPEED_MPS, at_rest, rest_samples
from .slope import log_slope_rad

__all__ = [
    "LogMeta",
    "robot_matches",
    "named_robots",
    "run_names",
    "ground_name",
    "UNLABELLED",
    "InteractionLog",
    "VELOCITY_SOURCES",
    "RESAMPLE_METHODS",
    "DEFAULT_GAP_FACTOR",
    "check_gap_factor",
    "gap_steps",
    "median_period_s",
    "DRIVE_FIELDS",
    "IMU_FIELDS",
    "OPTIONAL_FIELDS",
    "at_rest",
    "rest_samples",
    "log_slope_rad",
    "REST_ACCEL_MPS2",
    "REST_ALPHA_RADPS2",
    "REST_SPEED_MPS",
    "REST_OMEGA_RADPS",
]
