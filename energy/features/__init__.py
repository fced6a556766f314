"""Vibration and motion features for learned current models: windows, spectra, normalisers.

Three kinds of features feed the vibration-conditioned current estimator:

- **Windows** of the drive stream (:class:`WindowSpec`, :mod:`~energy.features.windows`):
  ``t_interval`` stated in seconds *and* samples at a stated rate (the paper's 0.1 s = 10
  samples at 100 Hz).
- **Whole-run spectrum** (:func:`whole_run_spectrum`, :mod:`~energy.features.spectra`): the
  source method's FFT amplitude spectrum of the vertical acceleration over a whole
  interaction run, 0–50 Hz on a fixed grid of 8000 bins (one spectrum per run; the FFT bins
  of runs longer than the grid's resolution are pooled into it by power), and its compact
  form (:func:`whole_run_band_spectrum`), the band RMS averaged over the run (Welch), which
  does not depend on the run length.
- **Local spectra** (:func:`band_rms_spectra`): the RMS vertical acceleration in
  log-spaced frequency bands over a short window (e.g. 1 s) around given times.

- **Yaw-rate slip** (:func:`yaw_slip_features`, :mod:`~energy.features.yaw_slip`): the
  gyro's yaw rate against the wheel-derived one over each window — how much a ground
  makes a skid-steer robot skid, beside how it makes it vibrate.

Every spectrum is computed at its stream's own rate; the **band** of the features
(:data:`DEFAULT_BAND_HZ`, :func:`check_band_hz`, :mod:`~energy.features.band`) is stated in
Hz, so a model serves any IMU whose Nyquist frequency reaches its band
(:func:`band_served`) and refuses the others with a :class:`BandNotServedError`.

:class:`MinMaxNormaliser` (:mod:`~energy.features.normalise`) holds the min-max scaling:
the source ranges (v 0–1 m/s, omega 0–1 rad/s, current 0–10 000 mA, absolute values) as
constants, spectrum ranges fitted on training data; both are stored with a model.
"""

from .band import DEFAULT_BAND_HZ, BandNotServedError, band_served, check_band_hz, check_model_band, require_band
from .normalise import (
    SOURCE_CURRENT_RANGE_A,
    SOURCE_OMEGA_RANGE_RADPS,
    SOURCE_SPEED_RANGE_MPS,
    MinMaxNormaliser,
)
from .spectra import (
    NYQUIST_TOLERANCE,
    SPECTRUM_SCALINGS,
    accel_rate_hz,
    band_rms_spectra,
    log_band_edges_hz,
    whole_run_band_spectrum,
    whole_run_spectrum,
)
from .windows import DEFAULT_T_INTERVAL_S, WindowSpec, sliding_windows, window_starts
from .yaw_slip import YAW_SLIP_FEATURES, YAW_SLIP_FLOOR_RADPS, yaw_slip_features

__all__ = [
    "DEFAULT_T_INTERVAL_S",
    "SOURCE_SPEED_RANGE_MPS",
    "SOURCE_OMEGA_RANGE_RADPS",
    "SOURCE_CURRENT_RANGE_A",
    "SPECTRUM_SCALINGS",
    "NYQUIST_TOLERANCE",
    "WindowSpec",
    "window_starts",
    "sliding_windows",
    "accel_rate_hz",
    "whole_run_spectrum",
    "log_band_edges_hz",
    "band_rms_spectra",
    "whole_run_band_spectrum",
    "MinMaxNormaliser",
    "DEFAULT_BAND_HZ",
    "BandNotServedError",
    "check_band_hz",
    "check_model_band",
    "band_served",
    "require_band",
    "YAW_SLIP_FLOOR_RADPS",
    "YAW_SLIP_FEATURES",
    "yaw_slip_features",
]
