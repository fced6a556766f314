"""Vibration spectra of the vertical acceleration: whole-run FFT spectrum, band RMS spectra.

Every spectrum removes the mean of each segment first (so gravity drops out) and resamples
the acceleration onto a uniform grid at its median rate (linear interpolation) before the
FFT.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from terrawatt_base.checks import check_int, check_real, fmt_number, real_array
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError

__all__ = [
    "SPECTRUM_SCALINGS",
    "NYQUIST_TOLERANCE",
    "accel_rate_hz",
    "whole_run_spectrum",
    "log_band_edges_hz",
    "band_rms_spectra",
    "whole_run_band_spectrum",
]

#: ``scaling`` values of :func:`whole_run_spectrum`.
SPECTRUM_SCALINGS = ("amplitude", "density")
#: Bins up to this fraction above the Nyquist frequency are accepted (held at the Nyquist
#: value): a 99.5 Hz IMU still serves a 0-50 Hz spectrum.
NYQUIST_TOLERANCE = 0.02


def _uniform_accel(accel_time_s: Any, accel_z_mps2: Any) -> tuple[np.ndarray, np.ndarray, float]:
    """Acceleration linearly interpolated onto a uniform grid at its median rate."""
    t = real_array("accel_time_s", accel_time_s, finite=False)
    a = real_array("accel_z_mps2", accel_z_mps2, finite=False)
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


def accel_rate_hz(accel_time_s: Any) -> float:
    """Median sampling rate of an acceleration stream (Hz), the rate its spectra resample to.

    Its Nyquist frequency, half of it, bounds every spectrum's ``max_frequency_hz`` (with
    :data:`NYQUIST_TOLERANCE`).

    Raises
    ------
    DataError
        Fewer than 2 timestamps, or a median step that is not positive and finite.

    Examples
    --------
    >>> round(accel_rate_hz(np.arange(100) / 50.0), 9)
    50.0
    """
    t = real_array("accel_time_s", accel_time_s, ndim=1, finite=False)
    if t.size < 2:
        raise DataError(f"a sampling rate needs at least 2 timestamps, got {t.size}")
    step = float(np.median(np.diff(t)))
    if not (math.isfinite(step) and step > 0):
        raise DataError(f"accel_time_s has a median step of {step!r} s; expected finite increasing times")
    return 1.0 / step


def _check_nyquist(max_frequency_hz: float, rate_hz: float) -> None:
    nyquist = rate_hz / 2.0
    if max_frequency_hz > nyquist * (1.0 + NYQUIST_TOLERANCE):
        raise InvalidParameterError(
            f"max_frequency_hz={fmt_number(max_frequency_hz)} Hz exceeds the Nyquist frequency "
            f"{fmt_number(nyquist)} Hz of the acceleration stream ({fmt_number(rate_hz)} Hz); lower "
            f"max_frequency_hz or record faster"
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
    n_bins = check_int("n_bins", n_bins, low=1)
    max_frequency_hz = check_real("max_frequency_hz", max_frequency_hz, low=0.0, low_inclusive=False)
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
    n_bands = check_int("n_bands", n_bands, low=1)
    lo = check_real("min_frequency_hz", min_frequency_hz, low=0.0, low_inclusive=False)
    hi = check_real("max_frequency_hz", max_frequency_hz, low=0.0, low_inclusive=False)
    res = check_real("resolution_hz", resolution_hz, low=0.0, low_inclusive=False)
    if not hi > lo:
        raise InvalidParameterError(f"max_frequency_hz must be > min_frequency_hz={lo!r}, got {hi!r}")
    k = np.round(np.geomspace(lo, hi, n_bands + 1) / res).astype(np.int64)
    k[0] = max(k[0], 1)
    for i in range(1, k.size):  # at most a few dozen edges
        k[i] = max(k[i], k[i - 1] + 1)
    # 0.1 % of slack on the top frequency: the rate of a jittered IMU is measured to about that,
    # and one whose median rate is 100.015 Hz (bins of 1.00015 Hz) keeps the bands of a 100 Hz one
    # instead of losing the last bin to rounding
    top = int(math.floor(hi / res * (1.0 + 1e-3) + 1e-9)) + 1
    if k[-1] > top:
        raise InvalidParameterError(
            f"n_bands={n_bands!r} bands of at least one {res:.4g} Hz bin do not fit between "
            f"{lo!r} and {hi!r} Hz; use fewer bands or a longer spectrum window"
        )
    return k * res


def _band_index(freq: np.ndarray, edges_hz: np.ndarray) -> np.ndarray:
    """Band number of each FFT bin (-1 outside every band); a bin within rounding of an edge
    belongs to the band that edge opens (``edges[k] <= f < edges[k + 1]``)."""
    eps = 1e-9 * max(1.0, float(edges_hz[-1]))
    band = np.searchsorted(edges_hz - eps, freq + 0.0, side="right") - 1
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
    span_s = check_real("span_s", span_s, low=0.0, low_inclusive=False)
    edges = real_array("band_edges_hz", band_edges_hz, finite=False)
    if edges.ndim != 1 or edges.size < 2 or not np.all(np.isfinite(edges)) or np.any(np.diff(edges) <= 0) or edges[0] < 0:
        raise InvalidParameterError(f"band_edges_hz must be >= 2 increasing non-negative edges, got {edges.tolist()!r}")
    centres = np.atleast_1d(real_array("centre_time_s", centre_time_s, finite=False))
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
    span_s = check_real("span_s", span_s, low=0.0, low_inclusive=False)
    hop_s = span_s / 2.0 if hop_s is None else check_real("hop_s", hop_s, low=0.0, low_inclusive=False)
    t = real_array("accel_time_s", accel_time_s, finite=False)
    if t.ndim != 1 or t.size < 4:
        raise DataError(f"a spectrum needs at least 4 acceleration samples, got shape {t.shape!r}")
    first, last = t[0] + span_s / 2.0, t[-1] - span_s / 2.0
    centres = np.arange(first, max(first, last) + 1e-9, hop_s)
    rms = band_rms_spectra(t, accel_z_mps2, centres, span_s, band_edges_hz)
    return np.sqrt(np.mean(rms**2, axis=0))
