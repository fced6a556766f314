"""The ``terrawatt evaluate`` command (terrawatt_cli.evaluate): results files, workers, a failing figure; the adapt
protocol's options and the settings they give."""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import sys

import pytest
from cli_samples import FIXTURES, is_png

from terrain import InvalidParameterError, TerrawattWarning
from terrawatt_cli import error_message, main
from terrawatt_cli.evaluate import FLAGS, PROTOCOLS, adapt_settings_from_args, add_adapt_options


def test_evaluate_writes_json_and_markdown(tmp_path, capsys):
    data = tmp_path / "logs"
    shutil.copytree(FIXTURES, data)
    # a second asphalt run, so leave-one-run-out has something to train on per ground
    for kind in ("imu", "pro"):
        shutil.copy(data / "ASPHALT" / f"{kind}_00.csv", data / "ASPHALT" / f"{kind}_01.csv")
    with pytest.warns(TerrawattWarning, match="'snow' has 1 run"):
        rc = main(["evaluate", "--data", str(data), "--model", "constant", "linear", "--out", str(tmp_path / "out")])
    assert rc == 0
    result = json.loads((tmp_path / "out" / "evaluation.json").read_text())
    assert result["models"] == ["constant", "linear"]
    assert result["skipped"] == ["ground 'snow' has 1 run; per-ground leave-one-run-out needs 2"]
    rows = {(r["variant"], r["ground"], r["model"]): r for r in result["summary"]}
    # each asphalt run is held out against its identical copy: the constant model's charge is exact
    assert rows[("per_ground", "asphalt", "constant")]["whole_run_median_pct"] == pytest.approx(0.0, abs=1e-9)
    assert rows[("ground_agnostic", "snow", "constant")]["n_runs"] == 1
    assert rows[("ground_agnostic", "snow", "constant")]["whole_run_median_pct"] > 10.0  # trained on asphalt only
    md = (tmp_path / "out" / "evaluation.md").read_text()
    assert "| per_ground | asphalt | constant | 2 |" in md
    assert is_png(tmp_path / "out" / "spectra.png")
    capsys.readouterr()


@pytest.fixture
def dask_environ_restored():
    """Undo what dask's nanny writes into this process's environment before it spawns a
    worker (``OMP_NUM_THREADS=1`` & co.), so later tests see the environment they started with."""
    dask = pytest.importorskip("dask", reason="--workers needs the distributed extra (dask[distributed])")
    pytest.importorskip("distributed", reason="--workers needs the distributed extra (dask[distributed])")
    keys = [*dask.config.get("distributed.nanny.pre-spawn-environ"), "PYTHONHASHSEED"]
    before = {k: os.environ.get(k) for k in keys}
    yield
    for k, v in before.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


def test_evaluate_on_two_local_workers_gives_the_serial_scores(tmp_path, capsys, dask_environ_restored):
    data = tmp_path / "logs"
    shutil.copytree(FIXTURES, data)
    for kind in ("imu", "pro"):
        shutil.copy(data / "ASPHALT" / f"{kind}_00.csv", data / "ASPHALT" / f"{kind}_01.csv")
    runs = {}
    for workers in ("1", "2"):
        with pytest.warns(TerrawattWarning, match="'snow' has 1 run"):
            rc = main(["evaluate", "--data", str(data), "--model", "constant", "linear", "--workers", workers,
                       "--out", str(tmp_path / workers)])
        assert rc == 0
        assert f"on {workers} {'worker (serial)' if workers == '1' else 'dask workers'}" in capsys.readouterr().out
        runs[workers] = json.loads((tmp_path / workers / "evaluation.json").read_text())["runs"]
    assert len(runs["2"]) == len(runs["1"]) == 20
    for serial, parallel in zip(runs["1"], runs["2"]):
        for key, value in serial.items():
            # same rows in the same order; worker processes run one BLAS thread, so allow last-bit differences
            if key != "fit_duration_s":
                assert parallel[key] == (value if isinstance(value, str) else pytest.approx(value, rel=1e-12, abs=1e-12))


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--workers", "2", "--scheduler", "tcp://127.0.0.1:8786"],
         "--workers 2 and --scheduler 'tcp://127.0.0.1:8786' exclude each other"),
        (["--workers", "0"], "--workers must be a positive number of processes, got 0"),
        # the library names its parameters, the command line says them by its flags
        (["--robot", "jackal"], "--robot applies to the physics model only, got --model constant"),
        (["--band", "1", "20"], "--band applies to the estimator and paper models only, got --model constant"),
        (["--seed", "-1"], "--seed must be None or an integer in [0, 2**32), got -1"),
    ],
)
def test_evaluate_refuses_bad_worker_options(tmp_path, capsys, extra, message):
    rc = main(["evaluate", "--data", str(FIXTURES), "--model", "constant", "--out", str(tmp_path / "out"), *extra])
    assert rc == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_evaluate_on_workers_without_distributed_names_the_extra(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # `import distributed` now raises ImportError
    rc = main(["evaluate", "--data", str(FIXTURES), "--model", "constant", "--workers", "2",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert "--workers 2 needs dask.distributed; install it with: pip install 'terrawatt[distributed]'" in (
        capsys.readouterr().err
    )
    assert not (tmp_path / "out").exists()


def test_evaluate_whose_figure_fails_still_succeeds_with_its_results(tmp_path, capsys, monkeypatch):
    from energy.evaluation import results
    from terrain import InvalidParameterError

    def no_spectra(*args, **kwargs):
        raise InvalidParameterError("band (0.5, 50.0) Hz exceeds the Nyquist frequency 25 Hz of a 50 Hz IMU")

    monkeypatch.setattr(results, "plot_vibration_spectra", no_spectra)
    data = tmp_path / "logs"
    shutil.copytree(FIXTURES, data)
    for kind in ("imu", "pro"):
        shutil.copy(data / "ASPHALT" / f"{kind}_00.csv", data / "ASPHALT" / f"{kind}_01.csv")
    with pytest.warns(TerrawattWarning, match="'snow' has 1 run"):
        rc = main(["evaluate", "--data", str(data), "--model", "constant", "--out", str(tmp_path / "out")])
    assert rc == 0
    assert json.loads((tmp_path / "out" / "evaluation.json").read_text())["models"] == ["constant"]
    err = capsys.readouterr().err
    assert "warning: could not draw" in err and "spectra.png" in err and "Nyquist" in err
    assert not (tmp_path / "out" / "spectra.png").exists()


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_adapt_options(parser)
    return parser.parse_args(list(argv))


def test_defaults_give_the_leave_one_out_protocol_and_the_adapt_defaults_elsewhere():
    args = _parse()
    assert args.protocol == "loo" and PROTOCOLS[0] == "loo"
    assert adapt_settings_from_args(args) is None
    s = adapt_settings_from_args(_parse("--protocol", "few-shot"))
    assert s.adapt_seconds == (10.0, 20.0, 40.0) and s.threshold_pct == 10.0 and not s.trigger


def test_the_update_follows_its_prefix_by_the_learned_share_unless_told_otherwise():
    assert adapt_settings_from_args(_parse("--protocol", "few-shot")).shrink == "prior"
    assert adapt_settings_from_args(_parse("--protocol", "few-shot", "--adapt-shrink", "evidence")).shrink == "evidence"
    s = adapt_settings_from_args(_parse("--protocol", "few-shot", "--adapt-method", "regime_gain"))
    assert s.method == "regime_gain" and s.update_options()["method"] == "regime_gain"
    with pytest.raises(SystemExit):
        _parse("--protocol", "few-shot", "--no-adapt-shrink")


def test_the_adapt_protocol_triggers_on_its_threshold():
    s = adapt_settings_from_args(_parse("--protocol", "adapt", "--adapt-seconds", "8", "--adapt-threshold", "3"))
    assert s.trigger and s.adapt_seconds == (8.0,) and s.threshold_pct == 3.0


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--protocol", "adapt", "--adapt-seconds", "10", "0"], "--adapt-seconds must be seconds > 0, got 0.0"),
        (["--protocol", "adapt", "--adapt-threshold", "-1"], "--adapt-threshold must be a percentage >= 0, got -1.0"),
        # the update's own minimum: no run could adapt on 5 s, the table would be empty
        (["--protocol", "few-shot", "--adapt-seconds", "5"], "--adapt-seconds 5: the update needs more than 5 s"),
        # given with the default protocol, they were ignored
        (["--adapt-seconds", "20"], "--adapt-seconds applies to --protocol adapt or few-shot, not to loo"),
        (["--adapt-method", "bayes", "--adapt-threshold", "3"], "--adapt-method, --adapt-threshold apply to"),
        (["--protocol", "few-shot", "--adapt-threshold", "3"], "few-shot has none"),
    ],
)
def test_bad_adapt_flags_are_refused_naming_the_flag(argv, match):
    with pytest.raises(InvalidParameterError) as caught:
        adapt_settings_from_args(_parse(*argv))
    assert re.search(match, error_message(caught.value, FLAGS))  # the library names the parameter, the command its flag
