"""The vibration band as an option: validation, any IMU rate, refusal of too slow streams, --band."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import resample_poly

from energy import (
    EstimatorConfig,
    VibrationCurrentEstimator,
    estimator_preset,
    load_current_model,
    new_current_model,
    read_borealtc,
)
from energy.features import DEFAULT_BAND_HZ, BandNotServedError, band_rms_spectra, band_served, check_band_hz
from energy.models import training_report
from terrain import InvalidParameterError
from terrawatt_cli import main

SHARED = Path(__file__).resolve().parents[3] / "shared" / "data" / "borealtc"
FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "borealtc"
needs_shared = pytest.mark.skipif(not (SHARED / "FLOORING").is_dir(),
                                  reason=f"the shared BorealTC logs are not at {SHARED}")
TINY = dict(n_members=1, max_epochs=4, hidden_sizes=(16, 16), patience=None, validation_fraction=0.0)
CROP_S = 45.0


# ------------------------------------------------------------------ fixtures
def _write_run(folder: Path, run: str, imu: np.ndarray, pro: np.ndarray) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    np.savetxt(folder / f"imu_{run}.csv", imu, delimiter=",", header="time,wx,wy,wz,ax,ay,az", comments="")
    np.savetxt(folder / f"pro_{run}.csv", pro, delimiter=",", header="time,curL,curR,velL,velR", comments="")


def _copy_run(run: str, out: Path, imu_hz: float | None = None, drive_hz: float | None = None) -> None:
    """The first CROP_S seconds of a shared FLOORING run, its IMU resampled (anti-aliased
    polyphase filter) to ``imu_hz`` and its drive stream interpolated onto ``drive_hz``."""
    imu = np.loadtxt(SHARED / "FLOORING" / f"imu_{run}.csv", delimiter=",", skiprows=1)
    pro = np.loadtxt(SHARED / "FLOORING" / f"pro_{run}.csv", delimiter=",", skiprows=1)
    imu, pro = imu[imu[:, 0] <= CROP_S], pro[pro[:, 0] <= CROP_S]
    if imu_hz is not None:
        src_hz = round(1.0 / float(np.median(np.diff(imu[:, 0]))))
        g = math.gcd(int(imu_hz), int(src_hz))
        cols = resample_poly(imu[:, 1:], int(imu_hz) // g, src_hz // g, axis=0)
        imu = np.column_stack([imu[0, 0] + np.arange(len(cols)) / imu_hz, cols])
    if drive_hz is not None:
        t = np.arange(pro[0, 0], pro[-1, 0], 1.0 / drive_hz)
        pro = np.column_stack([t] + [np.interp(t, pro[:, 0], pro[:, k]) for k in range(1, 5)])
    _write_run(out / "FLOORING", run, imu, pro)


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """Training runs at 100 Hz, and one held-out run at 100 Hz / 6.5 Hz, 50 Hz / 15 Hz and 30 Hz / 15 Hz."""
    if not (SHARED / "FLOORING").is_dir():
        pytest.skip(f"the shared BorealTC logs are not at {SHARED}")
    root = tmp_path_factory.mktemp("band")
    for run in ("00", "03"):
        _copy_run(run, root / "train")
    _copy_run("05", root / "native")
    _copy_run("05", root / "imu50", imu_hz=50.0, drive_hz=15.0)
    _copy_run("05", root / "imu30", imu_hz=30.0, drive_hz=15.0)
    return {name: read_borealtc(root / name) for name in ("train", "native", "imu50", "imu30")} | {"root": root}


@pytest.fixture(scope="module")
def model(logs):
    cfg = estimator_preset("default").replace(**TINY)
    return VibrationCurrentEstimator(cfg, seed=3, n_threads=1).fit(logs["train"])


# ------------------------------------------------------------------ validation
def test_check_band_hz_accepts_pairs():
    assert check_band_hz([1, 12]) == (1.0, 12.0)
    assert check_band_hz((0.0, 14.0)) == (0.0, 14.0)
    assert check_band_hz(np.array([2.0, 25.0])) == (2.0, 25.0)


@pytest.mark.parametrize(
    "band, message",
    [((12.0, 1.0), "low_hz < high_hz"), ((5.0, 5.0), "low_hz < high_hz"), ((-1.0, 12.0), "must be >= 0"),
     ((float("nan"), 12.0), "must be finite"), ((1.0, float("inf")), "must be finite"),
     ((1.0,), "pair"), ((1.0, 2.0, 3.0), "pair"), ("1-12", "pair"), (None, "pair"), ((1.0, "12"), "real number")],
)
def test_bad_bands_are_refused_by_name(band, message):
    with pytest.raises(InvalidParameterError, match="band_hz") as info:
        check_band_hz(band)
    assert message in str(info.value)
    with pytest.raises(InvalidParameterError, match=f"EstimatorConfig.band_hz.*{message}"):
        EstimatorConfig(band_hz=band)


def test_a_band_too_narrow_for_its_bands_is_refused_early(tmp_path, capsys):
    with pytest.raises(InvalidParameterError, match=r"holds 3 frequency bin\(s\) of 1 Hz.*n_bands=12"):
        EstimatorConfig(band_hz=(1.0, 3.0))
    assert EstimatorConfig(band_hz=(1.0, 3.0), n_bands=2).band_hz == (1.0, 3.0)
    assert EstimatorConfig(band_hz=(1.0, 3.0), local_spectrum=False).band_hz == (1.0, 3.0)  # no bands to fit
    rc = main(["train", "--data", str(FIXTURES), "--band", "1", "3", "--out", str(tmp_path / "m.zip")])
    err = capsys.readouterr().err
    assert rc == 2 and "n_bands=12" in err and "--band" in err and not (tmp_path / "m.zip").exists()


def test_the_default_band_is_served_by_common_imus():
    assert EstimatorConfig().band_hz == DEFAULT_BAND_HZ == estimator_preset("default").band_hz
    assert all(band_served(DEFAULT_BAND_HZ[1], rate) for rate in (25.0, 30.0, 50.0, 100.0))
    assert not band_served(DEFAULT_BAND_HZ[1], 20.0)
    assert estimator_preset("paper").band_hz == (0.0, 50.0)  # the paper's 0-50 Hz spectrum


def test_config_round_trip_and_configs_saved_before_band_hz():
    cfg = EstimatorConfig(band_hz=(2.0, 20.0))
    assert EstimatorConfig.from_dict(cfg.to_dict()) == cfg
    old = cfg.to_dict()
    del old["band_hz"]
    old |= {"min_band_hz": 1.0, "max_frequency_hz": 50.0}
    assert EstimatorConfig.from_dict(old).band_hz == (1.0, 50.0)
    with pytest.raises(InvalidParameterError, match="not both"):
        EstimatorConfig.from_dict(old | {"band_hz": [1.0, 12.0]})


def test_new_current_model_takes_a_band_for_learned_models_only():
    est = new_current_model("estimator", band_hz=(0.0, 14.0))
    assert est.config.band_hz == (0.0, 14.0) and est.config.name == "default"
    assert new_current_model("estimator").config == "default"  # a preset name, as before
    with pytest.raises(InvalidParameterError, match="band_hz applies to the estimator and paper models only"):
        new_current_model("linear", band_hz=(1.0, 12.0))
    with pytest.raises(InvalidParameterError, match="band_hz"):
        new_current_model("paper", band_hz=(3.0, 1.0))


# ------------------------------------------------------------------ any IMU rate
def test_band_features_do_not_depend_on_the_imu_rate():
    rng = np.random.default_rng(0)
    t = np.arange(6000) / 100.0
    a = 9.81 + rng.normal(0.0, 0.3, t.size) + 0.4 * np.sin(2 * np.pi * 7.3 * t)
    a50 = resample_poly(a - 9.81, 1, 2) + 9.81
    edges = np.arange(1.0, 14.0)
    centres = np.arange(2.0, 58.0, 1.0)
    rms100 = band_rms_spectra(t, a, centres, 1.0, edges)
    rms50 = band_rms_spectra(np.arange(a50.size) / 50.0, a50, centres, 1.0, edges)
    ratio = np.median(rms50 / rms100, axis=0)
    assert np.all(np.abs(ratio - 1.0) < 0.05), ratio.round(3)


@needs_shared
def test_a_model_trained_on_100hz_logs_predicts_50hz_and_30hz_logs(model, logs):
    native = logs["native"][0]
    assert round(native.accel_rate_hz) == 100 and round(native.drive_rate_hz, 1) == 6.5
    assert model.config_.band_hz == DEFAULT_BAND_HZ
    truth = model.predict(native)
    for name, imu_hz in (("imu50", 50), ("imu30", 30)):
        log = logs[name][0]
        assert round(log.accel_rate_hz) == imu_hz and round(log.drive_rate_hz) == 15
        pred = model.predict(log)
        assert pred.shape == (len(log), 2) and np.all(np.isfinite(pred))
        # the same run at another IMU and drive rate: the same currents
        ref = np.column_stack([np.interp(log.time_s, native.time_s, truth[:, k]) for k in range(2)])
        assert np.median(np.abs(pred - ref)) < 0.15, name
        assert abs(pred.mean() / ref.mean() - 1.0) < 0.03, name


@needs_shared
def test_a_stream_too_slow_for_the_band_is_refused_with_the_fix(logs):
    wide = estimator_preset("default").replace(band_hz=(1.0, 40.0), **TINY)
    est = VibrationCurrentEstimator(wide, seed=0, n_threads=1).fit(logs["train"])
    est.predict(logs["native"][0])  # 100 Hz serves 40 Hz
    with pytest.raises(BandNotServedError) as info:
        est.predict(logs["imu50"][0])
    message = str(info.value)
    for part in ("band 1-40 Hz", "Nyquist frequency 25 Hz", "IMU at 50 Hz", "band_hz LO HI", "pro_05.csv"):
        assert part in message, (part, message)
    assert info.value.parameter == "band_hz" and "--" not in message  # the command line says its --band
    with pytest.raises(BandNotServedError, match="Nyquist frequency 15 Hz"):
        VibrationCurrentEstimator(wide, seed=0, n_threads=1).fit(logs["imu30"])


@needs_shared
def test_the_saved_model_keeps_its_band(model, logs, tmp_path):
    path = model.save(tmp_path / "m.zip")
    loaded = load_current_model(path)
    assert loaded.config_.band_hz == DEFAULT_BAND_HZ
    assert np.array_equal(loaded.band_edges_hz_, model.band_edges_hz_)
    log = logs["imu50"][0]
    assert np.array_equal(loaded.predict(log), model.predict(log))


# ------------------------------------------------------------------ CLI
def test_cli_train_band_is_stored_and_predict_checks_it(tmp_path, capsys, monkeypatch):
    real = training_report.new_current_model

    def small(kind, **kwargs):  # the estimator the flags ask for, trained for a few epochs only
        model = real(kind, **kwargs)
        model.config = model.config.replace(**TINY)
        return model

    monkeypatch.setattr(training_report, "new_current_model", small)
    path = tmp_path / "est.zip"
    assert main(["train", "--data", str(FIXTURES), "--quiet", "--band", "0", "25", "--out", str(path)]) == 0
    assert "vibration band 0-25 Hz" in capsys.readouterr().out
    assert load_current_model(path).config_.band_hz == (0.0, 25.0)
    assert main(["predict", "--model", str(path), "--data", str(FIXTURES), "--band", "0", "25",
                 "--out", str(tmp_path / "ok")]) == 0
    assert (tmp_path / "ok" / "predictions.json").is_file()
    capsys.readouterr()
    rc = main(["predict", "--model", str(path), "--data", str(FIXTURES), "--band", "0", "15",
               "--out", str(tmp_path / "narrow")])
    err = capsys.readouterr().err
    assert rc == 2 and "band 0-25 Hz" in err and "--band 0 15" in err and "train it again with a --band inside" in err
    assert not (tmp_path / "narrow" / "predictions.json").exists()


@needs_shared
def test_cli_predicts_50hz_logs_with_a_model_trained_on_100hz_logs(model, logs, tmp_path, capsys):
    path = model.save(tmp_path / "est.zip")
    out = tmp_path / "pred"
    assert main(["predict", "--model", str(path), "--data", str(logs["root"] / "imu50"), "--out", str(out)]) == 0
    assert "imu_05" in capsys.readouterr().out or (out / "predictions.json").is_file()
    assert (out / "predictions.json").is_file()


@needs_shared
def test_cli_evaluate_band_reaches_the_learned_models(logs, tmp_path, capsys, monkeypatch):
    real, made = training_report.new_current_model, []

    def small(kind, **kwargs):
        model = real(kind, **kwargs)
        if kind == "estimator":
            model.config = model.config.replace(**TINY)
        made.append((kind, kwargs["band_hz"]))
        return model

    monkeypatch.setattr(training_report, "new_current_model", small)
    out = tmp_path / "eval"
    assert main(["evaluate", "--data", str(logs["root"] / "train"), "--model", "estimator", "linear",
                 "--variants", "per_ground", "--band", "0", "14", "--out", str(out)]) == 0
    assert made == [("estimator", (0.0, 14.0)), ("linear", None)]
    assert (out / "evaluation.json").is_file()
    capsys.readouterr()
    rc = main(["evaluate", "--data", str(FIXTURES), "--model", "linear", "--band", "1", "12", "--out", str(out / "x")])
    assert rc == 2 and "--band applies to the estimator and paper models only" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["train", "evaluate", "predict"])
@pytest.mark.parametrize(
    "band, message",
    [(["12", "1"], "low_hz < high_hz"), (["5", "5"], "low_hz < high_hz"), (["-1", "12"], "must be >= 0"),
     (["nan", "12"], "must be finite"), (["1", "inf"], "must be finite")],
)
def test_cli_bad_bands_exit_2(tmp_path, capsys, command, band, message):
    out = tmp_path / ("m.zip" if command == "train" else "out")
    model_args = ["--model", "estimator"] if command != "predict" else ["--model", str(tmp_path / "missing.zip")]
    rc = main([command, "--data", str(FIXTURES), *model_args, "--band", *band, "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2 and "--band" in err and message in err, err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_cli_band_with_a_baseline_exits_2(tmp_path, capsys):
    rc = main(["train", "--data", str(FIXTURES), "--model", "linear", "--band", "1", "12",
               "--out", str(tmp_path / "m.zip")])
    assert rc == 2 and "--band applies to the estimator and paper models only" in capsys.readouterr().err
    path = new_current_model("linear").fit(read_borealtc(FIXTURES)).save(tmp_path / "lin.zip")
    rc = main(["predict", "--model", str(path), "--data", str(FIXTURES), "--band", "1", "12",
               "--out", str(tmp_path / "out")])
    assert rc == 2 and "holds a LinearCurrentModel" in capsys.readouterr().err


def test_check_model_band_refuses_a_model_outside_the_served_band():
    from energy.features import check_model_band

    est = new_current_model("estimator", band_hz=(0.0, 25.0))
    est.config_ = est.config  # as fitted: the band is the config's
    check_model_band(est, None)
    check_model_band(est, (0.0, 30.0), "--band", "est.zip")
    with pytest.raises(BandNotServedError, match=r"'est.zip' was trained on the vibration band 0-25 Hz.*--band 0 15"):
        check_model_band(est, (0.0, 15.0), "--band", "est.zip")
    with pytest.raises(InvalidParameterError, match="--band applies to estimator and paper model files; 'lin.zip' "
                       "holds a LinearCurrentModel"):
        check_model_band(new_current_model("linear"), (0.0, 15.0), "--band", "lin.zip")
    with pytest.raises(InvalidParameterError, match="band_hz"):
        check_model_band(est, (15.0, 0.0))
