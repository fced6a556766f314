"""Figures of the current estimator: Fig. 6 (currents) and Fig. 7 (spectra)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from energy import InteractionLog, LogMeta, plot_current_estimate, plot_vibration_spectra
from energy.plots import ground_spectra
from terrain import DataError, FigureWarning, GridMismatchError, InvalidParameterError

PNG = b"\x89PNG\r\n\x1a\n"


def _log(ground: str | None, freq_hz: float, seconds: float = 20.0, seed: int = 0) -> InteractionLog:
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 0.1)
    ta = np.arange(0.0, seconds, 0.01)
    az = 9.81 + np.sin(2 * np.pi * freq_hz * ta) + 0.05 * rng.standard_normal(ta.size)
    cur = 2.0 + 0.2 * rng.standard_normal(t.size)
    return InteractionLog(t, np.full(t.size, 0.3), np.zeros(t.size), cur, cur + 0.5, ta, az,
                          meta=LogMeta(source=f"run_{ground}_{seed}", ground_label=ground))


def test_current_figure_is_written_atomically(tmp_path: Path) -> None:
    log = _log("asphalt", 8.0)
    pred = np.column_stack([log.current_left_a, log.current_right_a]) * 1.1
    out = plot_current_estimate(log, pred, tmp_path / "figs" / "current.png", window_samples=10)
    assert out.read_bytes()[:8] == PNG
    assert [p.name for p in out.parent.iterdir()] == ["current.png"]  # no temporary left


def test_current_figure_refuses_mismatched_or_nan_estimates(tmp_path: Path) -> None:
    log = _log("asphalt", 8.0)
    with pytest.raises(GridMismatchError, match=r"shape \(200, 2\)"):
        plot_current_estimate(log, np.zeros((199, 2)), tmp_path / "x.png")
    bad = np.zeros((200, 2))
    bad[5, 1] = np.nan
    with pytest.raises(InvalidParameterError, match="NaN"):
        plot_current_estimate(log, bad, tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()


def test_ground_spectra_average_runs_and_find_each_grounds_peak() -> None:
    logs = [_log("wood", 8.0, seed=0), _log("wood", 8.0, seed=1), _log("snow", 21.0, seed=2)]
    freq, spectra = ground_spectra(logs, n_bins=500)
    assert list(spectra) == ["wood", "snow"] and freq.shape == (500,)
    assert freq[np.argmax(spectra["wood"])] == pytest.approx(8.0, abs=0.2)
    assert freq[np.argmax(spectra["snow"])] == pytest.approx(21.0, abs=0.2)
    one = ground_spectra(logs[:1], n_bins=500)[1]["wood"]
    two = ground_spectra(logs[1:2], n_bins=500)[1]["wood"]
    np.testing.assert_allclose(spectra["wood"], (one + two) / 2)


def test_spectra_figure_from_logs_or_precomputed(tmp_path: Path) -> None:
    logs = [_log("wood", 8.0), _log("snow", 21.0, seed=1)]
    assert plot_vibration_spectra(logs, tmp_path / "a.png").read_bytes()[:8] == PNG
    freq, spectra = ground_spectra(logs, n_bins=300)
    assert plot_vibration_spectra(spectra, tmp_path / "b.png", frequency_hz=freq).read_bytes()[:8] == PNG
    with pytest.raises(InvalidParameterError, match="frequency_hz is required"):
        plot_vibration_spectra(spectra, tmp_path / "c.png")
    with pytest.raises(GridMismatchError, match="'wood'"):
        plot_vibration_spectra(spectra, tmp_path / "c.png", frequency_hz=freq[:-1])
    with pytest.raises(InvalidParameterError, match="smoothing_bins"):
        plot_vibration_spectra(logs, tmp_path / "c.png", smoothing_bins=0)


def test_spectra_need_a_ground_label(tmp_path: Path) -> None:
    with pytest.raises(DataError, match="no ground label"):
        ground_spectra([_log(None, 8.0)])
    with pytest.raises(InvalidParameterError, match="at least one"):
        ground_spectra([])


def _log_at(ground: str, imu_hz: float, peak_hz: float, seconds: float = 20.0) -> InteractionLog:
    t = np.arange(0.0, seconds, 0.1)
    ta = np.arange(0.0, seconds, 1.0 / imu_hz)
    az = 9.81 + np.sin(2 * np.pi * peak_hz * ta)
    cur = np.full(t.size, 2.0)
    return InteractionLog(t, np.full(t.size, 0.3), np.zeros(t.size), cur, cur, ta, az,
                          meta=LogMeta(source=f"imu_{imu_hz:g}hz.csv", ground_label=ground))


def test_spectra_figure_of_a_50_hz_imu_draws_up_to_its_nyquist(tmp_path: Path) -> None:
    # the estimator's default 0-50 Hz band needs a 100 Hz IMU; a 50 Hz IMU has data up to 25 Hz
    logs = [_log_at("wood", 50.0, 8.0), _log_at("snow", 100.0, 21.0)]
    with pytest.raises(InvalidParameterError, match=r"exceeds the Nyquist frequency 25 Hz"):
        ground_spectra(logs, n_bins=500)  # the library function still refuses to invent data
    with pytest.warns(FigureWarning, match=r"drawn up to 25 Hz, not 50 Hz: the IMU of 'imu_50hz\.csv' samples at 50 Hz"):
        out = plot_vibration_spectra(logs, tmp_path / "spectra.png", max_frequency_hz=50.0)
    assert out.read_bytes()[:8] == PNG
    assert [p.name for p in tmp_path.iterdir()] == ["spectra.png"]
    # within the data's band nothing is clipped and nothing is warned
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        plot_vibration_spectra(logs, tmp_path / "low.png", max_frequency_hz=25.0)
    with pytest.raises(InvalidParameterError, match="max_frequency_hz must be > 0"):
        plot_vibration_spectra(logs, tmp_path / "bad.png", max_frequency_hz=0.0)


# ------------------------------------------------------------------ drawn into the caller's axes
def test_current_figure_draws_into_the_callers_axes(tmp_path: Path) -> None:
    from matplotlib.figure import Figure

    log = _log("asphalt", 8.0)
    pred = np.column_stack([log.current_left_a, log.current_right_a]) * 1.1
    fig = Figure()
    panels = fig.subplots(2, 1)
    out = plot_current_estimate(log, pred, ax=panels, window_samples=10, title="mine")
    assert out == tuple(panels)
    assert [len(ax.lines) for ax in out] == [3, 3]
    assert [ax.get_ylabel() for ax in out] == ["left current (A)", "right current (A)"]
    assert out[0].get_title() == "mine" and fig.get_suptitle() == ""  # the caller's figure keeps its own title
    with pytest.raises(InvalidParameterError, match=r"ax must hold 2 matplotlib Axes \(left, right current\), got 1"):
        plot_current_estimate(log, pred, ax=[panels[0]])
    assert list(tmp_path.iterdir()) == []


def test_spectra_figure_draws_one_ground_per_axes_with_the_note_on_the_axes(tmp_path: Path) -> None:
    from matplotlib.figure import Figure

    logs = [_log_at("wood", 50.0, 8.0), _log_at("snow", 100.0, 21.0)]
    panels = Figure().subplots(1, 2)
    with pytest.warns(FigureWarning, match="drawn up to 25 Hz"):
        out = plot_vibration_spectra(logs, ax=panels)
    assert out == tuple(panels)
    assert [ax.get_title(loc="left") for ax in out] == ["wood", "snow"]
    assert all(len(ax.lines) == 2 and "spectral density" in ax.get_ylabel() for ax in out)
    assert "drawn up to 25 Hz" in out[-1].get_xlabel()
    with pytest.raises(InvalidParameterError, match=r"3 matplotlib Axes \(one per ground: 'wood', 'snow', 'grass'\)"):
        plot_vibration_spectra([*logs, _log_at("grass", 100.0, 5.0)], ax=panels, max_frequency_hz=25.0)
    assert list(tmp_path.iterdir()) == []


def test_figures_take_a_path_or_axes_not_both_nor_neither(tmp_path: Path) -> None:
    from matplotlib.figure import Figure

    log = _log("asphalt", 8.0)
    pred = np.column_stack([log.current_left_a, log.current_right_a])
    panels = Figure().subplots(2, 1)
    with pytest.raises(InvalidParameterError, match="got neither"):
        plot_current_estimate(log, pred)
    with pytest.raises(InvalidParameterError, match="not both"):
        plot_current_estimate(log, pred, tmp_path / "c.png", ax=panels)
    with pytest.raises(InvalidParameterError, match="got neither"):
        plot_vibration_spectra([log])
    with pytest.raises(InvalidParameterError, match="not both"):
        plot_vibration_spectra([log], tmp_path / "s.png", ax=panels[:1])
    assert list(tmp_path.iterdir()) == []
