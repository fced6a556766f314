"""Vibration and motion features for learned current models: windows, spectra, normalisers.

Three kinds of features feed :class:`energy.estimator.VibrationCurrentEstimator`:

- **Windows** of the drive stream (:class:`WindowSpec`): ``t_interval`` stated in seconds
  *and* samples at a stated rate (the paper's 0.1 s = 10 samples at 100 Hz).
- **Whole-run spectrum** (:func:`whole_run_spectrum`): the source method's FFT amplitude
  spectrum of the vertical acceleration over a whole interaction run, 0–50 Hz on a fixed
  grid of 8000 bins (one spectrum per run; the FFT bins of runs longer than the grid's
  resolution are pooled into it by power), and its compact form (:func:`whole_run_band_spectrum`),
  the band RMS averaged over the run (Welch), which does not depend on the run length.
- **Local spectra** (:func:`band_rms_spectra`): the RMS vertical acceleration in
  log-spaced frequency bands over a short window (e.g. 1 s) around given times.

Every spectrum removes the mean of each segment first (so gravity drops out) and resamples
the acceleration onto a uniform grid at its median rate (linear interpolation) before the
FFT. :class:`MinMaxNormaliser` holds the min-max scaling: the source ranges (v 0–1 m/s,
omega 0–1 rad/s, current 0–10 000 mA, absolute values) as constants, spectrum ranges fitted
on training data; both are stored with a model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrain.errors import DataError, InvalidParameterError, UnknownNameError

__all__ = [
    "DEFAULT_T_INTERVAL_S",
    "SOURCE_SPEED_RANGE_MPS",
    "SOURCE_OMEGA_RANGE_RADPS",
    "SOURCE_CURRENT_RANGE_A",
    "SPECTRUM_SCALINGS",
    "WindowSpec",
    "window_starts",
    "sliding_windows",
    "whole_run_spectrum",
    "log_band_edges_hz",
    "band_rms_spectra",
    "whole_run_band_spectrum",
    "MinMaxNormaliser",
]

#: The source method's window ``t_interval`` (s): 10 samples at 100 Hz.
DEFAULT_T_INTERVAL_S = 0.1
#: Min-max range of |v| in the source method (m/s).
SOURCE_SPEED_RANGE_MPS = (0.0, 1.0)
#: Min-max range of |omega| in the source method (rad/s).
SOURCE_OMEGA_RANGE_RADPS = (0.0, 1.0)
#: Min-max range of the drive current in the source method (0–10 000 mA, in A).
SOURCE_CURRENT_RANGE_A = (0.0, 10.0)
#: ``scaling`` values of :func:`whole_run_spectrum`.
SPECTRUM_SCALINGS = ("amplitude", "density")

# Bins up to this fraction above the Nyquist frequency are accepted (held at the Nyquist
# value): a 99.5 Hz IMU still serves a 0-50 Hz spectrum.
_NYQUIST_TOLERANCE = 0.02


def _positive(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or not math.isfinite(value) or value <= 0:
        raise InvalidParameterError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def _positive_int(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise InvalidParameterError(f"{name} must be an int >= 1, got {value!r}")
    return int(value)


# ---------------------------------------------------------------------------- windows
@dataclass(frozen=True)
class WindowSpec:
    """A window over a uniformly sampled stream, stated in samples and in seconds.

    Parameters
    ----------
    length_samples : int
        Samples per window (>= 1).
    stride_samples : int
        Samples between window starts (>= 1).
    rate_hz : float
        Sampling rate of the stream the windows cut (Hz, > 0).

    Examples
    --------
    >>> spec = WindowSpec.from_seconds(0.1, rate_hz=100.0)   # the paper's t_interval
    >>> spec.length_samples, spec.stride_samples, spec.length_s
    (10, 10, 0.1)
    """

    length_samples: int
    stride_samples: int
    rate_hz: float

    def __post_init__(self) -> None:
        _positive_int("WindowSpec.length_samples", self.length_samples)
        _positive_int("WindowSpec.stride_samples", self.stride_samples)
        object.__setattr__(self, "rate_hz", _positive("WindowSpec.rate_hz", self.rate_hz))
        object.__setattr__(self, "length_samples", int(self.length_samples))
        object.__setattr__(self, "stride_samples", int(self.stride_samples))

    @classmethod
    def from_seconds(cls, length_s: float = DEFAULT_T_INTERVAL_S, rate_hz: float = 100.0,
                     stride_s: float | None = None) -> WindowSpec:
        """Window of ``length_s`` (default the paper's 0.1 s) and stride ``stride_s``
        (default: the length) at ``rate_hz`` (default 100 Hz).

        Lengths are rounded to the nearest whole sample, at least one.

        Raises
        ------
        InvalidParameterError
            Non-positive or non-finite arguments.
        """
        length_s = _positive("length_s", length_s)
        rate_hz = _positive("rate_hz", rate_hz)
        stride_s = length_s if stride_s is None else _positive("stride_s", stride_s)
        return cls(
            length_samples=max(1, int(round(length_s * rate_hz))),
            stride_samples=max(1, int(round(stride_s * rate_hz))),
            rate_hz=rate_hz,
        )

    @property
    def length_s(self) -> float:
        """Window length (s)."""
        return self.length_samples / self.rate_hz

    @property
    def stride_s(self) -> float:
        """Stride between window starts (s)."""
        return self.stride_samples / self.rate_hz


def window_starts(n_samples: int, spec: WindowSpec) -> np.ndarray:
    """Start indices of the windows that cover ``n_samples`` samples.

    Windows start every ``stride_samples``; when the last regular window stops short of the
    end, one more window is aligned with the end, so every sample is covered when the
    stride does not exceed the length.

    Raises
    ------
    DataError
        ``n_samples`` is shorter than one window.
    """
    n = int(n_samples)
    if n < spec.length_samples:
        raise DataError(
            f"the record has {n} samples ({n / spec.rate_hz:.3g} s), shorter than one window of "
            f"{spec.length_samples} samples ({spec.length_s:.3g} s)"
        )
    last = n - spec.length_samples
    starts = np.arange(0, last + 1, spec.stride_samples, dtype=np.intp)
    if starts[-1] != last:
        starts = np.append(starts, last)
    return starts


def sliding_windows(values: Any, spec: WindowSpec, starts: np.ndarray | None = None) -> np.ndarray:
    """Windows of a uniformly sampled array, shape ``(n_windows, length_samples, *rest)``.

    Parameters
    ----------
    values : array_like, shape (N, ...)
    spec : WindowSpec
    starts : numpy.ndarray, optional
        Start indices; default :func:`window_starts`.

    Returns
    -------
    numpy.ndarray
        A copy (safe to modify).
    """
    x = np.asarray(values)
    if starts is None:
        starts = window_starts(x.shape[0], spec)
    idx = starts[:, None] + np.arange(spec.length_samples)[None, :]
    return x[idx]


# --------------------------------------------------------------------------- spectra
def _uniform_accel(accel_time_s: Any, accel_z_mps2: Any) -> tuple[np.ndarray, np.ndarray, float]:
    """Acceleration linearly interpolated onto a uniform grid at its median rate."""
    t = np.asarray(accel_time_s, dtype=np.float64)
    a = np.asarray(accel_z_mps2, dtype=np.float64)
    if t.ndim != 1 or a.shape != t.shape:
        raise InvalidParameterError(
            f"accel_time_s and accel_z_mps2 must be 1-D of one length, got shapes {t.shape!r} and {a.shape!r}"
        )
    if t.size < 4:
        raise DataError(f"a spectrum needs at least 4 acceleration samples, got {t.size}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(a))):
        raise DataError("accel_time_s and accel_z_mps2 must be finite")
    d = np.diff(t)
    if np.any(d <= 0):
        raise DataError(f"accel_time_s must be strictly increasing; first offending index {int(np.argmax(d <= 0)) + 1}")
    rate = 1.0 / float(np.median(d))
    n = int(math.floor((t[-1] - t[0]) * rate + 1e-9)) + 1
    grid = t[0] + np.arange(n) / rate
    return grid, np.interp(grid, t, a), rate


def _check_nyquist(max_frequency_hz: float, rate_hz: float) -> None:
    nyquist = rate_hz / 2.0
    if max_frequency_hz > nyquist * (1.0 + _NYQUIST_TOLERANCE):
        raise InvalidParameterError(
            f"max_frequency_hz={max_frequency_hz!r} exceeds the Nyquist frequency {nyquist:.4g} Hz of "
            f"the acceleration stream ({rate_hz:.4g} Hz); lower max_frequency_hz or record faster"
        )


def whole_run_spectrum(
    accel_time_s: Any,
    accel_z_mps2: Any,
    n_bins: int = 8000,
    max_frequency_hz: float = 50.0,
    scaling: str = "amplitude",
) -> tuple[np.ndarray, np.ndarray]:
    """FFT spectrum of the vertical acceleration over a whole run, on a fixed frequency grid.

    The source method's feature: one spectrum per interaction run. The acceleration (mean
    removed) is resampled onto a uniform grid at its median rate and transformed with one
    real FFT over the whole run (no window function). The one-sided spectrum is then put on
    ``n_bins`` frequencies ``k * max_frequency_hz / n_bins``, ``k = 1..n_bins`` (the paper's
    160 s at 100 Hz gives exactly one FFT bin per output bin):

    - a run shorter than ``n_bins / max_frequency_hz`` seconds has coarser FFT bins than
      the grid: the spectrum is linearly interpolated onto it;
    - a longer run has finer FFT bins: each output bin pools the FFT bins nearest to it
      (ties go to the higher bin) by power, not by picking one of them, so no FFT bin is
      skipped. ``"amplitude"`` takes the root of the summed squared amplitudes, so a
      sinusoid keeps its amplitude wherever its energy falls among the pooled bins (a plain
      mean of the amplitudes would divide it by the number of bins pooled, i.e. by the run
      length); ``"density"`` takes the root of the mean power spectral density, which keeps
      the level of broadband vibration.

    Parameters
    ----------
    accel_time_s, accel_z_mps2 : array_like, shape (M,)
        Acceleration stream (s, m/s^2; gravity may be included).
    n_bins : int
        Number of output bins (default 8000).
    max_frequency_hz : float
        Highest frequency (default 50 Hz); must not exceed the stream's Nyquist frequency
        by more than 2 %.
    scaling : {"amplitude", "density"}
        ``"amplitude"`` (default, the paper's): single-sided amplitude in m/s^2,
        ``2 |X_k| / M`` and ``|X_k| / M`` for the 0 Hz and (even ``M``) Nyquist bins, which
        have no mirror image — a sinusoid of amplitude A shows a peak A whatever the run
        length. Broadband vibration falls as ``1 / sqrt(M)`` for runs shorter than
        ``n_bins / max_frequency_hz`` seconds (longer runs are pooled to the grid's
        resolution), so short runs are not comparable with long ones. ``"density"``:
        amplitude spectral density ``sqrt(2 |X_k|^2 / (M f_s))`` (no factor 2 at 0 Hz and
        Nyquist) in (m/s^2)/sqrt(Hz), independent of the run length for broadband vibration.

    Returns
    -------
    frequency_hz : numpy.ndarray, shape (n_bins,)
    spectrum : numpy.ndarray, shape (n_bins,)

    Raises
    ------
    InvalidParameterError
        Bad ``n_bins`` / ``max_frequency_hz``; ``max_frequency_hz`` above the Nyquist
        frequency.
    UnknownNameError
        Unknown ``scaling``.
    DataError
        Fewer than 4 samples, non-finite or unsorted timestamps.

    Examples
    --------
    >>> t = np.arange(16000) / 100.0                      # 160 s at 100 Hz
    >>> f, amp = whole_run_spectrum(t, 9.81 + 0.5 * np.sin(2 * np.pi * 12.0 * t))
    >>> f.size, float(f[np.argmax(amp)]), round(float(amp.max()), 3)
    (8000, 12.0, 0.5)
    """
    n_bins = _positive_int("n_bins", n_bins)
    max_frequency_hz = _positive("max_frequency_hz", max_frequency_hz)
    if scaling not in SPECTRUM_SCALINGS:
        raise UnknownNameError(f"scaling must be one of {SPECTRUM_SCALINGS!r}, got {scaling!r}")
    _, a, rate = _uniform_accel(accel_time_s, accel_z_mps2)
    _check_nyquist(max_frequency_hz, rate)
    m = a.size
    x2 = np.abs(np.fft.rfft(a - a.mean())) ** 2
    freq = np.fft.rfftfreq(m, 1.0 / rate)
    one_sided = np.full(freq.size, 2.0)  # every bin but 0 Hz and Nyquist stands for +f and -f
    one_sided[0] = 1.0
    if m % 2 == 0:
        one_sided[-1] = 1.0
    if scaling == "amplitude":
        power = (one_sided * np.sqrt(x2) / m) ** 2  # squared amplitude, summed when pooled
    else:
        power = one_sided * x2 / (m * rate)  # power spectral density, averaged when pooled
    step_hz = max_frequency_hz / n_bins
    grid = step_hz * np.arange(1, n_bins + 1)
    spec = np.interp(grid, freq, np.sqrt(power))
    if freq[1] <= step_hz * (1.0 + 1e-9):  # FFT bins at least as fine as the grid: pool them
        k = np.floor(freq / step_hz + 0.5).astype(np.int64) - 1  # output bin of each FFT bin
        inside = (k >= 0) & (k < n_bins)
        count = np.bincount(k[inside], minlength=n_bins)
        total = np.bincount(k[inside], weights=power[inside], minlength=n_bins)
        pooled = total if scaling == "amplitude" else total / np.maximum(count, 1)
        # bins above the Nyquist frequency (within its tolerance) hold no FFT bin: keep the
        # interpolated (held Nyquist) value there
        spec = np.where(count > 0, np.sqrt(pooled), spec)
    return grid, spec


def log_band_edges_hz(
    n_bands: int, min_frequency_hz: float, max_frequency_hz: float, resolution_hz: float
) -> np.ndarray:
    """Log-spaced band edges, each band at least one FFT bin wide.

    Edges start from ``numpy.geomspace(min, max, n_bands + 1)`` snapped to multiples of
    ``resolution_hz``; where two low edges would fall into one bin the upper one moves up
    by a bin, so every band holds at least one bin (low bands become linear-spaced when the
    resolution is coarse).

    Parameters
    ----------
    n_bands : int
    min_frequency_hz, max_frequency_hz : float
        0 < min < max.
    resolution_hz : float
        FFT bin spacing (1 / window length in s).

    Returns
    -------
    numpy.ndarray, shape (n_bands + 1,)
        Edges (Hz); band ``k`` holds the bins with ``edges[k] <= f < edges[k + 1]``.

    Raises
    ------
    InvalidParameterError
        Bad arguments, or more bands than bins between the limits.

    Examples
    --------
    >>> log_band_edges_hz(4, 1.0, 16.0, 1.0).tolist()
    [1.0, 2.0, 4.0, 8.0, 16.0]
    """
    n_bands = _positive_int("n_bands", n_bands)
    lo = _positive("min_frequency_hz", min_frequency_hz)
    hi = _positive("max_frequency_hz", max_frequency_hz)
    res = _positive("resolution_hz", resolution_hz)
    if not hi > lo:
        raise InvalidParameterError(f"max_frequency_hz must be > min_frequency_hz={lo!r}, got {hi!r}")
    k = np.round(np.geomspace(lo, hi, n_bands + 1) / res).astype(np.int64)
    k[0] = max(k[0], 1)
    for i in range(1, k.size):  # at most a few dozen edges
        k[i] = max(k[i], k[i - 1] + 1)
    top = int(math.floor(hi / res + 1e-9)) + 1
    if k[-1] > top:
        raise InvalidParameterError(
            f"n_bands={n_bands!r} bands of at least one {res:.4g} Hz bin do not fit between "
            f"{lo!r} and {hi!r} Hz; use fewer bands or a longer spectrum window"
        )
    return k * res


def _band_index(freq: np.ndarray, edges_hz: np.ndarray) -> np.ndarray:
    """Band number of each FFT bin (-1 outside every band)."""
    eps = 1e-9 * max(1.0, float(edges_hz[-1]))
    band = np.searchsorted(edges_hz + eps, freq + 0.0, side="right") - 1
    band[(freq < edges_hz[0] - eps) | (freq >= edges_hz[-1] - eps)] = -1
    return band


def _band_power(segments: np.ndarray, rate_hz: float, edges_hz: np.ndarray) -> np.ndarray:
    """Mean-square acceleration per band of Hann-windowed segments, shape (n, n_bands)."""
    n = segments.shape[1]
    w = np.hanning(n + 2)[1:-1]  # no zero end points
    seg = segments - segments.mean(axis=1, keepdims=True)
    spec = np.abs(np.fft.rfft(seg * w, axis=1)) ** 2
    # one-sided power per bin, normalised so that sum over bins = mean square of the segment
    power = spec * (2.0 / (n * np.sum(w**2)))
    power[:, 0] *= 0.5
    if n % 2 == 0:
        power[:, -1] *= 0.5
    freq = np.fft.rfftfreq(n, 1.0 / rate_hz)
    band = _band_index(freq, edges_hz)
    n_bands = edges_hz.size - 1
    counts = np.bincount(band[band >= 0], minlength=n_bands)
    if np.any(counts == 0):
        raise InvalidParameterError(
            f"band(s) {np.flatnonzero(counts == 0).tolist()!r} of edges {edges_hz.tolist()!r} Hz hold no FFT bin "
            f"at {rate_hz / n:.4g} Hz resolution; build the edges with log_band_edges_hz for this window"
        )
    onehot = np.zeros((freq.size, n_bands))
    onehot[band >= 0, band[band >= 0]] = 1.0
    return power @ onehot


def band_rms_spectra(
    accel_time_s: Any,
    accel_z_mps2: Any,
    centre_time_s: Any,
    span_s: float,
    band_edges_hz: Any,
) -> np.ndarray:
    """Local spectra: RMS vertical acceleration per frequency band around given times.

    For each centre time, a segment of ``span_s`` seconds of the acceleration (uniformly
    resampled at its median rate) centred on it — shifted to stay inside the record near
    its ends — has its mean removed, a Hann window applied, and its power summed per band;
    the result is the band RMS (m/s^2), whose squares add up to the segment's mean-square
    acceleration (Parseval) when the bands cover 0 Hz to Nyquist.

    Parameters
    ----------
    accel_time_s, accel_z_mps2 : array_like, shape (M,)
        Acceleration stream.
    centre_time_s : array_like, shape (K,)
        Times (s) at which to take the spectra; vectorised over all of them.
    span_s : float
        Segment length (s); sets the resolution ``1 / span_s`` Hz.
    band_edges_hz : array_like, shape (B + 1,)
        Increasing band edges, e.g. from :func:`log_band_edges_hz`.

    Returns
    -------
    numpy.ndarray, shape (K, B)
        Band RMS (m/s^2).

    Raises
    ------
    InvalidParameterError
        Bad ``span_s`` or edges; a band with no FFT bin; edges above the Nyquist frequency.
    DataError
        The acceleration record is shorter than ``span_s``; non-finite or unsorted input.

    Examples
    --------
    >>> t = np.arange(2000) / 100.0
    >>> a = 9.81 + np.sqrt(2) * np.sin(2 * np.pi * 10.0 * t)      # RMS 1 at 10 Hz
    >>> rms = band_rms_spectra(t, a, [10.0], 2.0, [1.0, 5.0, 20.0, 50.0])
    >>> np.round(rms, 2).tolist()
    [[0.0, 1.0, 0.0]]
    """
    span_s = _positive("span_s", span_s)
    edges = np.asarray(band_edges_hz, dtype=np.float64)
    if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0) or edges[0] < 0:
        raise InvalidParameterError(f"band_edges_hz must be >= 2 increasing non-negative edges, got {edges.tolist()!r}")
    centres = np.atleast_1d(np.asarray(centre_time_s, dtype=np.float64))
    if centres.ndim != 1 or not np.all(np.isfinite(centres)):
        raise InvalidParameterError("centre_time_s must be a finite 1-D array")
    grid, a, rate = _uniform_accel(accel_time_s, accel_z_mps2)
    n = int(round(span_s * rate))
    if n < 4:
        raise InvalidParameterError(f"span_s={span_s!r} holds fewer than 4 acceleration samples at {rate:.4g} Hz")
    # the top edge is exclusive: it may lie one bin above the highest frequency used
    _check_nyquist(float(edges[-1]) - rate / n, rate)
    if a.size < n:
        raise DataError(
            f"the acceleration record lasts {a.size / rate:.3g} s, shorter than the spectrum window span_s={span_s!r}"
        )
    start = np.round((centres - span_s / 2.0 - grid[0]) * rate).astype(np.int64)
    start = np.clip(start, 0, a.size - n)
    out = np.empty((centres.size, edges.size - 1))
    chunk = max(1, 2_000_000 // n)  # bound memory of the gathered segments
    for i in range(0, centres.size, chunk):
        idx = start[i : i + chunk, None] + np.arange(n)[None, :]
        out[i : i + chunk] = np.sqrt(_band_power(a[idx], rate, edges))
    return out


def whole_run_band_spectrum(
    accel_time_s: Any,
    accel_z_mps2: Any,
    span_s: float,
    band_edges_hz: Any,
    hop_s: float | None = None,
) -> np.ndarray:
    """Band RMS of the vertical acceleration averaged over a whole run (Welch).

    The mean power of :func:`band_rms_spectra` segments every ``hop_s`` (default
    ``span_s / 2``) across the run, then the square root: a compact whole-run spectrum
    whose level does not depend on the run length.

    Returns
    -------
    numpy.ndarray, shape (B,)
        Band RMS (m/s^2).

    Raises
    ------
    As :func:`band_rms_spectra`.
    """
    span_s = _positive("span_s", span_s)
    hop_s = span_s / 2.0 if hop_s is None else _positive("hop_s", hop_s)
    t = np.asarray(accel_time_s, dtype=np.float64)
    if t.ndim != 1 or t.size < 4:
        raise DataError(f"a spectrum needs at least 4 acceleration samples, got shape {t.shape!r}")
    first, last = t[0] + span_s / 2.0, t[-1] - span_s / 2.0
    centres = np.arange(first, max(first, last) + 1e-9, hop_s)
    rms = band_rms_spectra(t, accel_z_mps2, centres, span_s, band_edges_hz)
    return np.sqrt(np.mean(rms**2, axis=0))


# ----------------------------------------------------------------------- normalisers
@dataclass(frozen=True, eq=False)
class MinMaxNormaliser:
    """Min-max scaling ``(x' - low) / (high - low)`` with ``x' = |x|`` when ``absolute``.

    Values outside ``[low, high]`` map outside ``[0, 1]``; nothing is clipped. A column
    with ``high == low`` is scaled by 1 (only shifted).

    Parameters
    ----------
    low, high : array_like
        Per-column (or scalar) range, ``high >= low``.
    absolute : bool
        Take absolute values first (the source method's convention for v, omega, current).

    Examples
    --------
    >>> speed = MinMaxNormaliser(*SOURCE_SPEED_RANGE_MPS, absolute=True)
    >>> speed.transform(np.array([-0.5, 0.25])).tolist()
    [0.5, 0.25]
    """

    low: np.ndarray
    high: np.ndarray
    absolute: bool = False

    def __post_init__(self) -> None:
        low = np.array(self.low, dtype=np.float64)
        high = np.array(self.high, dtype=np.float64)
        if low.shape != high.shape or low.ndim > 1:
            raise InvalidParameterError(f"low and high must be scalars or 1-D of one shape, got {low.shape!r} and {high.shape!r}")
        if not (np.all(np.isfinite(low)) and np.all(np.isfinite(high))) or np.any(high < low):
            raise InvalidParameterError(f"low and high must be finite with high >= low, got low={low!r}, high={high!r}")
        if not isinstance(self.absolute, (bool, np.bool_)):
            raise InvalidParameterError(f"absolute must be a bool, got {self.absolute!r}")
        low.setflags(write=False)
        high.setflags(write=False)
        object.__setattr__(self, "low", low)
        object.__setattr__(self, "high", high)
        object.__setattr__(self, "absolute", bool(self.absolute))

    @property
    def span(self) -> np.ndarray:
        """``high - low`` with zero spans replaced by 1."""
        s = self.high - self.low
        return np.where(s > 0, s, 1.0)

    @classmethod
    def from_data(cls, values: Any, absolute: bool = False, per_column: bool = True) -> MinMaxNormaliser:
        """Fit the range to data: per column of a 2-D array, or one range over everything.

        Raises
        ------
        DataError
            Empty or non-finite data.
        """
        x = np.asarray(values, dtype=np.float64)
        if x.size == 0 or not np.all(np.isfinite(x)):
            raise DataError(f"cannot fit a normaliser to empty or non-finite data (shape {x.shape!r})")
        if absolute:
            x = np.abs(x)
        if per_column and x.ndim == 2:
            return cls(x.min(axis=0), x.max(axis=0), absolute)
        return cls(float(x.min()), float(x.max()), absolute)

    def transform(self, values: Any) -> np.ndarray:
        """Scale values (broadcast over the last axis)."""
        x = np.asarray(values, dtype=np.float64)
        if self.absolute:
            x = np.abs(x)
        return (x - self.low) / self.span

    def inverse_transform(self, values: Any) -> np.ndarray:
        """Undo :meth:`transform` (absolute values stay absolute)."""
        return np.asarray(values, dtype=np.float64) * self.span + self.low

    def to_dict(self) -> dict[str, Any]:
        """Plain-types form for checkpoints."""
        return {"low": self.low.tolist(), "high": self.high.tolist(), "absolute": self.absolute}

    @classmethod
    def from_dict(cls, data: Any) -> MinMaxNormaliser:
        """Rebuild from :meth:`to_dict` output.

        Raises
        ------
        InvalidParameterError
            Missing keys or bad values.
        """
        try:
            return cls(data["low"], data["high"], data["absolute"])
        except (KeyError, TypeError) as exc:
            raise InvalidParameterError(f"a normaliser needs keys 'low', 'high', 'absolute', got {data!r:.120}") from exc
