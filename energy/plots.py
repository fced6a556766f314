"""Figures of the current estimator: measured vs estimated current (Fig. 6), vibration spectra (Fig. 7).

Both follow the layout of the vibration-current paper's figures. A figure draws what the
data has: spectra of logs whose IMU is too slow for the requested band are drawn up to the
data's Nyquist frequency, with a warning and a note on the figure, instead of failing after
the results that the figure illustrates are done.

Where a figure goes (the rule of every terrawatt figure, :mod:`terrawatt_base.plot_target`): give
exactly one of ``path`` or ``ax=``. With ``path`` the function makes its own figure
(:func:`terrawatt_base.plot_target.new_figure`: matplotlib's object API on an Agg canvas, no
pyplot, the user's backend left alone), writes it as a PNG atomically
(:func:`terrawatt_base.atomic.save_figure`) and returns the path, so this works on a robot or a
CI machine without a display. With ``ax=`` (a sequence of matplotlib Axes, one per panel) it draws
into the caller's axes, writes nothing, leaves the caller's figure layout alone (no
``tight_layout``) and returns the axes as a tuple, so figures can be composed. The figure's
own title belongs to the figure and is drawn only with ``path``; with ``ax`` a ``title``
you give goes on the first axes, and what is needed to read the panels (the spectra's axis
unit, the note of a clipped band) is written on the axes themselves.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy.ndimage import uniform_filter1d

from terrawatt_base import plot_target
from terrawatt_base.atomic import save_figure
from terrawatt_base.checks import check_int, check_real, fmt_number
from terrawatt_base.errors import DataError, FigureWarning, GridMismatchError, InvalidParameterError
from terrawatt_base.plot_target import check_axes, check_plot_target

from .features import NYQUIST_TOLERANCE, accel_rate_hz, whole_run_spectrum
from .logs import InteractionLog
from .metrics import DEFAULT_SMOOTHING_SAMPLES, moving_median

__all__ = ["plot_current_estimate", "plot_vibration_spectra", "ground_spectra"]

_SIDES = ("left", "right")


def _band_for_data(logs: Sequence[Any], max_frequency_hz: float) -> tuple[float, str]:
    """``max_frequency_hz`` clipped to the lowest Nyquist frequency of the logs' IMU streams,
    and a note saying so ("" when nothing was clipped)."""
    slowest: tuple[float, str] | None = None
    for log in logs:
        if isinstance(log, InteractionLog) and log.accel_time_s.size >= 2:
            rate = accel_rate_hz(log.accel_time_s)
            if slowest is None or rate < slowest[0]:
                slowest = (rate, log.meta.source)
    if slowest is None or max_frequency_hz <= slowest[0] / 2.0 * (1.0 + NYQUIST_TOLERANCE):
        return max_frequency_hz, ""
    nyquist = slowest[0] / 2.0
    note = (
        f"spectra drawn up to {fmt_number(nyquist)} Hz, not {fmt_number(max_frequency_hz)} Hz: the IMU of "
        f"{Path(slowest[1]).name or slowest[1]!r} samples at {fmt_number(slowest[0])} Hz (Nyquist {fmt_number(nyquist)} Hz)"
    )
    warnings.warn(f"plot_vibration_spectra: {note}", FigureWarning, stacklevel=3)
    return nyquist, note


def plot_current_estimate(
    log: InteractionLog,
    predicted_a: Any,
    path: str | os.PathLike[str] | None = None,
    *,
    ax: Sequence[Any] | None = None,
    window_samples: int = DEFAULT_SMOOTHING_SAMPLES,
    label: str = "estimate",
    title: str | None = None,
    dpi: int = 100,
) -> Path | tuple[Any, ...]:
    """The paper's Fig. 6: measured current, its moving median and the estimate's, per side.

    One panel per drive side (left above right): the measured current in a light colour,
    its median moving average over ``window_samples`` samples, and the moving median of
    the estimate over the same window (:func:`energy.metrics.moving_median`).

    Parameters
    ----------
    log : InteractionLog
        The run with its measured currents.
    predicted_a : array_like, shape (N, 2)
        Estimated ``[left, right]`` current (A) at ``log.time_s`` (``model.predict(log)``).
    path : str or os.PathLike, optional
        PNG file to write (or give ``ax``).
    ax : sequence of 2 matplotlib Axes, optional
        Draw the left and right panels into these instead of writing a file.
    window_samples : int
        Moving-median window in drive samples (default 100, the paper's).
    label : str
        Name of the estimate in the legend.
    title : str, optional
        Figure title (default: the log's source and ground); with ``ax``, the first
        axes' title (none by default).
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    pathlib.Path or tuple of 2 Axes
        The written file, or the axes drawn into.

    Raises
    ------
    GridMismatchError
        ``predicted_a`` is not of shape ``(len(log.time_s), 2)``.
    InvalidParameterError
        Both or neither of ``path`` and ``ax``, a bad ``path`` or not 2 axes; ``log`` is
        not an InteractionLog, ``predicted_a`` holds non-finite values, or a bad
        ``window_samples``.
    """
    target = check_plot_target(path, ax)
    if not isinstance(log, InteractionLog):
        raise InvalidParameterError(f"log must be an InteractionLog, got {type(log).__name__!r}")
    pred = np.asarray(predicted_a, dtype=float)
    if pred.shape != (log.time_s.size, 2):
        raise GridMismatchError(
            f"predicted_a must have shape ({log.time_s.size}, 2) (one [left, right] row per drive sample), "
            f"got {pred.shape!r}"
        )
    if not np.all(np.isfinite(pred)):
        raise InvalidParameterError("predicted_a holds NaN or infinite currents")
    measured = np.column_stack([log.current_left_a, log.current_right_a])
    smooth_meas = moving_median(measured, window_samples)
    smooth_pred = moving_median(pred, window_samples)
    t = log.time_s - log.time_s[0]
    if target is None:
        panels = check_axes(ax, 2, what="left, right current")
        _draw_currents(panels, t, measured, smooth_meas, smooth_pred, window_samples, label)
        if title:
            panels[0].set_title(title)
        return panels

    fig, panels = plot_target.new_figure((10, 6.5), 2, 1, sharex=True)
    _draw_currents(panels, t, measured, smooth_meas, smooth_pred, window_samples, label)
    ground = log.meta.ground_label or "unknown ground"
    fig.suptitle(title or f"drive current: {Path(log.meta.source).name or 'run'} on {ground}")
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi)


def _draw_currents(panels: Sequence[Any], t: np.ndarray, measured: np.ndarray, smooth_meas: np.ndarray,
                   smooth_pred: np.ndarray, window_samples: int, label: str) -> None:
    """Fig. 6's left and right panels, drawn into ``panels``."""
    for k, (ax, side) in enumerate(zip(panels, _SIDES)):
        ax.plot(t, measured[:, k], color="#9ecae1", lw=0.8, label="measured")
        ax.plot(t, smooth_meas[:, k], color="#08519c", lw=1.8, label=f"measured, moving median ({window_samples})")
        ax.plot(t, smooth_pred[:, k], color="#d94801", lw=1.8, label=f"{label}, moving median ({window_samples})")
        ax.set_ylabel(f"{side} current (A)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    panels[-1].set_xlabel("time (s)")


def ground_spectra(
    logs: Sequence[InteractionLog],
    *,
    n_bins: int = 2000,
    max_frequency_hz: float = 50.0,
    scaling: str = "density",
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Mean vertical-vibration spectrum of each ground's runs, on one frequency grid.

    Every run's whole-run spectrum (:func:`energy.features.whole_run_spectrum`) is computed on the
    same ``n_bins`` frequencies and the runs of a ground (``log.meta.ground_label``) are
    averaged. ``"density"`` scaling (default) gives broadband vibration the same level
    whatever the run length, so runs of different lengths can be averaged; with
    ``"amplitude"`` the level of runs shorter than ``n_bins / max_frequency_hz`` seconds
    (40 s at the defaults) grows as ``1 / sqrt(duration)``.

    Returns
    -------
    frequency_hz : ndarray, shape (n_bins,)
    spectra : dict of str to ndarray, shape (n_bins,)
        Ground label -> mean spectrum, in the order grounds first appear.

    Raises
    ------
    InvalidParameterError
        No logs, or an entry that is not an InteractionLog.
    DataError
        A log without a ground label.
    """
    items = list(logs)
    if not items:
        raise InvalidParameterError("logs must hold at least one InteractionLog, got none")
    sums: dict[str, np.ndarray] = {}
    counts: dict[str, int] = {}
    freq = np.empty(0)
    for i, log in enumerate(items):
        if not isinstance(log, InteractionLog):
            raise InvalidParameterError(f"logs[{i}] must be an InteractionLog, got {type(log).__name__!r}")
        ground = log.meta.ground_label
        if not ground:
            raise DataError(f"logs[{i}] ({log.meta.source!r}) has no ground label; spectra are grouped by ground")
        freq, spec = whole_run_spectrum(log.accel_time_s, log.accel_z_mps2, n_bins, max_frequency_hz, scaling)
        sums[ground] = sums.get(ground, 0.0) + spec
        counts[ground] = counts.get(ground, 0) + 1
    return freq, {g: sums[g] / counts[g] for g in sums}


def plot_vibration_spectra(
    logs: Sequence[InteractionLog] | Mapping[str, np.ndarray],
    path: str | os.PathLike[str] | None = None,
    *,
    ax: Sequence[Any] | None = None,
    frequency_hz: Any = None,
    smoothing_bins: int = 25,
    n_bins: int = 2000,
    max_frequency_hz: float = 50.0,
    scaling: str = "density",
    title: str | None = None,
    dpi: int = 100,
) -> Path | tuple[Any, ...]:
    """The paper's Fig. 7: vertical-vibration spectrum per ground with a moving average.

    One panel per ground, sharing the axes: the spectrum in a light colour and its
    centred moving average over ``smoothing_bins`` bins.

    The paper plots amplitude spectra of runs of one length (160 s). This figure plots the
    amplitude spectral density by default, because runs differ in length (the BorealTC
    runs last from about 10 s to over 4 min): the amplitude of broadband vibration — most
    of what the ground does — falls as ``1 / sqrt(duration)`` for runs shorter than the
    frequency grid's resolution (``n_bins / max_frequency_hz`` seconds), so amplitude
    spectra would rank grounds by run length as much as by roughness, while the density's
    level does not depend on the duration. Sinusoidal peaks (wheel or motor harmonics)
    keep their amplitude only in ``scaling="amplitude"``, which reproduces the paper's
    axis for runs of equal length. The y-axis label names the scaling and this reason.

    Parameters
    ----------
    logs : sequence of InteractionLog, or mapping of str to ndarray
        Runs (grouped by ground with :func:`ground_spectra`), or precomputed spectra per
        ground together with ``frequency_hz``.
    path : str or os.PathLike, optional
        PNG file to write (or give ``ax``).
    ax : sequence of matplotlib Axes, optional
        One per ground, in the order grounds first appear in ``logs`` (or the mapping's
        order): draw into these instead of writing a file. Each gets the y-axis label; the
        note of a clipped band is added to the last one's x-axis label.
    frequency_hz : array_like, optional
        Frequencies of precomputed spectra (required with a mapping, ignored otherwise).
    smoothing_bins : int
        Moving-average width in bins (>= 1).
    n_bins, max_frequency_hz, scaling :
        Frequency grid and scaling (``"density"``, the default, or ``"amplitude"``, see
        :func:`energy.features.whole_run_spectrum`) when spectra are computed from logs; ``scaling``
        also names the y axis (say which one precomputed spectra use).
    title : str, optional
        Figure title (default "vertical vibration spectra by ground"); with ``ax``, the
        first axes' title (none by default).
    dpi : int
        Resolution of the PNG (with ``path``).

    Returns
    -------
    pathlib.Path or tuple of Axes
        The written file, or the axes drawn into.

    Raises
    ------
    InvalidParameterError
        Both or neither of ``path`` and ``ax``, a bad ``path``, or not one axes per
        ground; bad ``smoothing_bins``; a mapping without ``frequency_hz``; empty input.
    GridMismatchError
        A precomputed spectrum whose length differs from ``frequency_hz``.

    Warns
    -----
    FigureWarning
        ``max_frequency_hz`` lies above the Nyquist frequency of a log's IMU stream (e.g.
        the 50 Hz default band of 50 Hz IMU logs): the spectra are drawn up to the lowest
        Nyquist frequency of the logs instead, and a note on the figure says so.
    """
    target = check_plot_target(path, ax)
    check_int("smoothing_bins", smoothing_bins, low=1)
    note = ""
    if isinstance(logs, Mapping):
        if frequency_hz is None:
            raise InvalidParameterError("frequency_hz is required with precomputed spectra")
        freq = np.asarray(frequency_hz, dtype=float)
        spectra = {str(g): np.asarray(s, dtype=float) for g, s in logs.items()}
        if not spectra:
            raise InvalidParameterError("spectra must hold at least one ground, got none")
        for g, s in spectra.items():
            if s.shape != freq.shape:
                raise GridMismatchError(f"spectrum of {g!r} has shape {s.shape!r}; frequency_hz has {freq.shape!r}")
    else:
        logs = list(logs)
        band_hz, note = _band_for_data(logs, check_real("max_frequency_hz", max_frequency_hz, low=0.0, low_inclusive=False))
        freq, spectra = ground_spectra(logs, n_bins=n_bins, max_frequency_hz=band_hz, scaling=scaling)
    if scaling == "density":
        ylabel = "amplitude spectral density (m/s²/√Hz)\nlevel independent of run length (runs differ in length)"
    else:
        ylabel = "amplitude (m/s²)"
    if target is None:
        panels = check_axes(ax, len(spectra), what="one per ground: " + ", ".join(map(repr, spectra)))
        _draw_spectra(panels, freq, spectra, smoothing_bins)
        for panel in panels:
            panel.set_ylabel(ylabel, fontsize=9)
        if note:
            panels[-1].set_xlabel(f"frequency (Hz)\n{note}")
        if title:
            panels[0].set_title(title)
        return panels

    fig, grid = plot_target.new_figure((10, 2.4 * len(spectra) + 0.8), len(spectra), 1, sharex=True, sharey=True,
                                       squeeze=False)
    _draw_spectra(grid[:, 0], freq, spectra, smoothing_bins)
    fig.supylabel(ylabel, fontsize=9)
    fig.suptitle(title or "vertical vibration spectra by ground")
    if note:
        fig.text(0.5, 0.005, note, ha="center", va="bottom", fontsize=8, color="#a50f15")
    fig.tight_layout(rect=(0, 0.03 if note else 0, 1, 1))
    return save_figure(fig, target, dpi=dpi)


def _draw_spectra(panels: Sequence[Any], freq: np.ndarray, spectra: Mapping[str, np.ndarray],
                  smoothing_bins: int) -> None:
    """Fig. 7's panels, one per ground, drawn into ``panels``."""
    for ax, (ground, spec) in zip(panels, spectra.items()):
        ax.plot(freq, spec, color="#bdbdbd", lw=0.6, label="spectrum")
        ax.plot(freq, uniform_filter1d(spec, smoothing_bins, mode="nearest"), color="#238b45", lw=1.6,
                label=f"moving average ({smoothing_bins} bins)")
        ax.set_title(ground, fontsize=10, loc="left")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    panels[-1].set_xlabel("frequency (Hz)")
