"""Tests of energy.features.spectra: whole-run and local (band RMS) spectra of the vertical acceleration."""

import numpy as np
import pytest

from energy.features import band_rms_spectra, log_band_edges_hz, whole_run_band_spectrum, whole_run_spectrum
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError


# ---------------------------------------------------------------- whole-run spectrum
def test_whole_run_spectrum_finds_a_sinusoid_and_ignores_gravity():
    t = np.arange(16000) / 100.0
    f, amp = whole_run_spectrum(t, 9.81 + 0.3 * np.sin(2 * np.pi * 7.5 * t))
    assert f.size == 8000 and f[0] == pytest.approx(50.0 / 8000) and f[-1] == pytest.approx(50.0)
    assert f[np.argmax(amp)] == pytest.approx(7.5)
    assert amp.max() == pytest.approx(0.3, rel=1e-3)
    assert np.median(amp) < 1e-3


@pytest.mark.parametrize("freq_hz, amplitude", [(12.5, 0.3), (50.0, 0.5)])  # a mid bin; the Nyquist bin
def test_one_sided_scaling_of_a_cosine_at_a_mid_bin_and_at_nyquist(freq_hz, amplitude):
    t = np.arange(16000) / 100.0  # 160 s at 100 Hz: one FFT bin per output bin, 50 Hz is Nyquist
    a = 9.81 + amplitude * np.cos(2 * np.pi * freq_hz * t)
    f, amp = whole_run_spectrum(t, a)
    peak = int(np.argmax(amp))
    assert f[peak] == pytest.approx(freq_hz)
    assert amp[peak] == pytest.approx(amplitude, rel=1e-6)  # not 2 * amplitude at Nyquist
    assert np.delete(amp, peak).max() < 1e-6
    # density: ASD^2 times the bin width is the signal's mean square (A^2 / 2, but A^2 at
    # Nyquist, where the cosine samples are +-A)
    _, asd = whole_run_spectrum(t, a, scaling="density")
    mean_square = amplitude**2 if freq_hz == 50.0 else amplitude**2 / 2
    assert asd[peak] ** 2 * (100.0 / t.size) == pytest.approx(mean_square, rel=1e-6)


def test_a_long_run_pools_every_fft_bin_into_the_grid():
    # 640 s: four FFT bins per output bin; this sinusoid lies on an FFT bin between two grid
    # frequencies, which picking the FFT bin at each grid frequency would miss entirely
    t = np.arange(64000) / 100.0
    step_hz = 50.0 / 8000
    f, amp = whole_run_spectrum(t, 9.81 + 0.3 * np.sin(2 * np.pi * (12.0 + step_hz / 4) * t))
    assert f[np.argmax(amp)] == pytest.approx(12.0)
    assert amp.max() == pytest.approx(0.3, rel=1e-6)
    assert np.sort(amp)[-2] < 1e-6


def test_broadband_level_depends_on_run_length_only_below_the_grid_resolution():
    # the 8000-bin grid has the resolution of a 160 s run
    rng = np.random.default_rng(1)
    power = {}
    for n in (3000, 24000, 64000):  # 30 s, 240 s, 640 s at 100 Hz
        t = np.arange(n) / 100.0
        a = 9.81 + rng.standard_normal(n)
        power[n] = {s: float(np.mean(whole_run_spectrum(t, a, scaling=s)[1] ** 2)) for s in ("amplitude", "density")}
    for n in (3000, 64000):
        assert power[n]["density"] == pytest.approx(power[24000]["density"], rel=0.1)
    assert power[64000]["amplitude"] == pytest.approx(power[24000]["amplitude"], rel=0.1)
    assert power[24000]["amplitude"] == pytest.approx(4.0 / 16000, rel=0.1)  # E(2|X|/M)^2 = 4 sigma^2 / M, M = 160 s
    assert power[3000]["amplitude"] > 3.0 * power[24000]["amplitude"]  # a 30 s run is interpolated, not pooled


def test_whole_run_spectrum_validates():
    t = np.arange(1000) / 50.0  # 50 Hz IMU: Nyquist 25 Hz
    with pytest.raises(InvalidParameterError, match="Nyquist"):
        whole_run_spectrum(t, np.zeros(1000))
    t = np.arange(1000) / 100.0
    with pytest.raises(UnknownNameError, match="scaling"):
        whole_run_spectrum(t, np.zeros(1000), scaling="power")
    with pytest.raises(InvalidParameterError, match="n_bins"):
        whole_run_spectrum(t, np.zeros(1000), n_bins=0)
    with pytest.raises(DataError, match="strictly increasing"):
        whole_run_spectrum(t[::-1], np.zeros(1000))


# -------------------------------------------------------------------- band spectra
def test_log_band_edges_give_every_band_a_bin():
    edges = log_band_edges_hz(12, 1.0, 50.0, 1.0)
    assert edges.size == 13
    assert np.all(np.diff(edges) >= 1.0 - 1e-12)
    assert edges[0] == 1.0 and edges[-1] == 50.0
    assert np.allclose(edges / 1.0, np.round(edges))  # on the bin grid
    assert log_band_edges_hz(4, 1.0, 16.0, 1.0).tolist() == [1.0, 2.0, 4.0, 8.0, 16.0]
    with pytest.raises(InvalidParameterError, match="do not fit"):
        log_band_edges_hz(60, 1.0, 50.0, 1.0)
    with pytest.raises(InvalidParameterError, match="max_frequency_hz"):
        log_band_edges_hz(4, 10.0, 5.0, 1.0)


def test_a_jittered_imu_rate_keeps_its_bands():
    """An IMU whose median rate is a hair above 100 Hz (bins of 1.00015 Hz) gets the 12 bands of 1-12 Hz a 100 Hz one gets."""
    nominal = log_band_edges_hz(12, 1.0, 12.0, 1.0)
    for rate in (100.005, 100.015, 100.08):
        res = rate / 100
        jittered = log_band_edges_hz(12, max(1.0, res), 12.0, res)
        assert jittered.size == nominal.size == 13
        np.testing.assert_allclose(jittered, nominal, rtol=1e-3)
    with pytest.raises(InvalidParameterError, match="do not fit"):
        log_band_edges_hz(12, 1.0, 12.0, 1.01)  # a whole percent short of the last bin is still short


def test_band_rms_places_a_sinusoid_in_its_band():
    t = np.arange(3000) / 100.0
    a = 9.81 + np.sqrt(2.0) * np.sin(2 * np.pi * 10.0 * t)  # RMS 1 at 10 Hz
    rms = band_rms_spectra(t, a, [5.0, 15.0, 25.0], 2.0, [1.0, 5.0, 20.0, 50.0])
    assert rms.shape == (3, 3)
    assert np.allclose(rms[:, 1], 1.0, atol=0.02)
    assert np.all(rms[:, [0, 2]] < 0.02)


def test_band_rms_obeys_parseval_for_white_noise():
    rng = np.random.default_rng(2)
    t = np.arange(20000) / 100.0
    a = 9.81 + 0.7 * rng.standard_normal(t.size)
    edges = log_band_edges_hz(10, 1.0, 50.0, 1.0)
    edges[0] = 0.5  # include everything but DC
    rms = band_rms_spectra(t, a, np.arange(5.0, 195.0, 10.0), 1.0, edges)
    total = np.mean(np.sum(rms**2, axis=1))
    assert total == pytest.approx(0.49, rel=0.1)


def test_band_rms_tracks_a_change_of_ground():
    t = np.arange(4000) / 100.0
    rng = np.random.default_rng(3)
    a = 9.81 + np.where(t < 20.0, 0.1, 1.0) * rng.standard_normal(t.size)
    edges = log_band_edges_hz(6, 1.0, 50.0, 1.0)
    rms = band_rms_spectra(t, a, [10.0, 30.0], 1.0, edges)
    assert np.all(rms[1] > 4.0 * rms[0])


def test_band_rms_validates():
    t = np.arange(50) / 100.0
    with pytest.raises(DataError, match="shorter than the spectrum window"):
        band_rms_spectra(t, np.zeros(50), [0.2], 1.0, [1.0, 10.0])
    t = np.arange(500) / 100.0
    with pytest.raises(InvalidParameterError, match="hold no FFT bin"):
        band_rms_spectra(t, np.zeros(500), [2.0], 1.0, [1.2, 1.5, 10.0])
    with pytest.raises(InvalidParameterError, match="band_edges_hz"):
        band_rms_spectra(t, np.zeros(500), [2.0], 1.0, [10.0, 1.0])
    with pytest.raises(InvalidParameterError, match="Nyquist"):
        band_rms_spectra(t, np.zeros(500), [2.0], 1.0, [1.0, 10.0, 80.0])


def test_whole_run_band_spectrum_is_the_average_rms():
    t = np.arange(6000) / 100.0
    a = 9.81 + np.sqrt(2.0) * 0.5 * np.sin(2 * np.pi * 25.0 * t)
    edges = log_band_edges_hz(8, 1.0, 50.0, 1.0)
    spec = whole_run_band_spectrum(t, a, 1.0, edges)
    assert spec.shape == (8,)
    k = int(np.searchsorted(edges, 25.0, side="right")) - 1
    assert spec[k] == pytest.approx(0.5, rel=0.05)
    assert spec.sum() == pytest.approx(spec[k], rel=0.1)

