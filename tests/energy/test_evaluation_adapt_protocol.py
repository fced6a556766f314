"""Tests of energy.evaluation.adapt_protocol: adapt on a run's first seconds, score its remainder (AdaptSettings, the trigger)."""

import json

import numpy as np
import pytest
from evaluation_samples import adapt_log, adapt_logs, adapt_settings

from energy import InteractionLog, LinearCurrentModel
from energy.evaluation import (
    TRIGGER_SCHEDULE,
    AdaptSettings,
    EvaluationResult,
    adaptation_scores,
    evaluate_adaptation,
    evaluate_few_shot,
)
from terrain import UnknownNameError
from terrawatt_base.errors import DataError, InvalidParameterError


@pytest.fixture(scope="module")
def logs():
    return adapt_logs()


@pytest.fixture(scope="module")
def result(logs):
    return evaluate_adaptation(logs, LinearCurrentModel(), name="linear", settings=adapt_settings())


def test_every_run_side_and_schedule_is_scored(result):
    assert isinstance(result, EvaluationResult) and result.protocol == "adapt"
    schedules = {"10 s", "20 s", TRIGGER_SCHEDULE}
    assert {r.schedule for r in result.runs} == schedules
    assert len(result.runs) == 6 * 2 * 3
    assert {(s.ground, s.schedule) for s in result.rows} == {(g, s) for g in ("grass", "sand", "all") for s in schedules}
    row = result.row_for("all", "linear", schedule="20 s")
    assert row.n_values == 12
    with pytest.raises(UnknownNameError, match="no row"):
        result.row_for("all", "linear", schedule="30 s")


def test_adapting_removes_a_run_offset_the_model_cannot_know(result):
    for g in ("grass", "sand"):
        row = result.row_for(g, "linear", schedule="20 s")
        assert row.unadapted_median_pct > 3.0
        assert row.adapted_median_pct < 0.5 * row.unadapted_median_pct
        assert row.adapted_rmse_median_a < row.unadapted_rmse_median_a
    trig = result.row_for("all", "linear", schedule=TRIGGER_SCHEDULE)
    assert trig.updates_mean > 0.5 and trig.adapted_median_pct < trig.unadapted_median_pct


def test_scores_match_a_direct_adaptation(logs, result):
    test, train = logs[0], logs[1:3]
    model = LinearCurrentModel().fit(train)
    adapted = model.adapt(test.slice(0.0, 20.0))
    rem = test.time_s >= 20.0
    pred = adapted.predict(test)[rem, 0]
    q_true = np.trapezoid(test.current_left_a[rem], test.time_s[rem])
    q_pred = np.trapezoid(pred, test.time_s[rem])
    row = next(r for r in result.runs if (r.run, r.schedule, r.side) == ("grass/pro_00", "20 s", "left"))
    assert row.adapted_whole_pct == pytest.approx(100 * abs(q_pred - q_true) / q_true, rel=1e-6)
    assert row.scored_s == pytest.approx(test.duration_s - 20.0)
    base = model.predict(test)
    head = ~rem
    gain = np.trapezoid(test.current_left_a[head], test.time_s[head]) / np.trapezoid(base[head, 0], test.time_s[head])
    q_gain = np.trapezoid(gain * base[rem, 0], test.time_s[rem])
    assert row.gain_whole_pct == pytest.approx(100 * abs(q_gain - q_true) / q_true, rel=1e-6)


def test_trigger_never_updates_a_model_within_the_threshold(logs):
    exact = [adapt_log(i, "grass") for i in range(2)]
    model = LinearCurrentModel().fit(exact[:1])
    scores, totals, skipped = adaptation_scores(model, exact[1], run="r", model_name="m",
                                        settings=AdaptSettings(adapt_seconds=(20.0,), threshold_pct=5.0))
    trig = [s for s in scores if s.schedule == TRIGGER_SCHEDULE]
    assert len(trig) == 2 and all(s.n_updates == 0 for s in trig) and not skipped
    assert all(s.adapted_whole_pct == pytest.approx(s.unadapted_whole_pct) for s in trig)


def test_short_runs_are_skipped_and_said_so(logs):
    model = LinearCurrentModel().fit(logs[:2])
    short = adapt_log(30, "grass", duration_s=25.0)
    scores, totals, skipped = adaptation_scores(model, short, run="grass/short", model_name="m", settings=adapt_settings())
    assert {s.schedule for s in scores} == {"10 s"}
    assert len(skipped) == 2 and all("min_remainder_s=10" in s for s in skipped)


@pytest.mark.parametrize(("kw", "match"), [
    ({"adapt_seconds": ()}, "adapt_seconds"),
    ({"adapt_seconds": (0.0,)}, "adapt_seconds"),
    ({"adapt_seconds": "20"}, "adapt_seconds"),
    ({"threshold_pct": -1.0}, "threshold_pct"),
    ({"check_s": 0.0}, "check_s"),
    ({"min_remainder_s": float("nan")}, "min_remainder_s"),
    ({"prior_s": 0.0}, "prior_s"),
    ({"trigger": "yes"}, "trigger"),
])
def test_bad_settings(kw, match):
    with pytest.raises(InvalidParameterError, match=match):
        AdaptSettings(**kw)
    with pytest.raises(UnknownNameError, match="method"):
        AdaptSettings(method="retrain")


def test_bad_inputs(logs, tmp_path):
    with pytest.raises(InvalidParameterError, match="settings must be an AdaptSettings"):
        evaluate_adaptation(logs, LinearCurrentModel(), settings={"adapt_seconds": [20]})
    with pytest.raises(InvalidParameterError, match="CurrentModel"):
        evaluate_adaptation(logs, "linear")
    with pytest.raises(InvalidParameterError, match="sequence of InteractionLog"):
        evaluate_adaptation(logs[0], LinearCurrentModel())
    unlabelled = InteractionLog(logs[0].time_s, logs[0].v_mps, logs[0].omega_radps, logs[0].current_left_a,
                                logs[0].current_right_a, logs[0].accel_time_s, logs[0].accel_z_mps2)
    with pytest.raises(DataError, match="ground_label"):
        evaluate_adaptation([unlabelled, logs[1]], LinearCurrentModel())
    with pytest.raises(DataError, match="at least 2 runs"):
        evaluate_adaptation([logs[0], logs[3]], LinearCurrentModel())
    with pytest.raises(InvalidParameterError, match="client"):
        evaluate_adaptation(logs, LinearCurrentModel(), client="tcp://nowhere")
    (tmp_path / "afile").write_text("x")
    with pytest.raises(InvalidParameterError):
        evaluate_adaptation(logs, LinearCurrentModel(), out_dir=tmp_path / "afile")
    with pytest.raises(DataError, match="at least 2 grounds"):
        evaluate_few_shot(logs[:3], LinearCurrentModel())
    with pytest.raises(DataError, match="target ground 'mud' has 0 runs"):
        evaluate_few_shot(logs, LinearCurrentModel(), target_grounds=["mud"])
    with pytest.raises(InvalidParameterError, match="target_grounds"):
        evaluate_few_shot(logs, LinearCurrentModel(), target_grounds="sand")


def _write_borealtc(folder, logs_by_ground):
    for ground, logs in logs_by_ground.items():
        d = folder / ground.upper()
        d.mkdir(parents=True)
        for k, log in enumerate(logs):
            half = 0.5 * 0.555 * log.omega_radps
            pro = np.column_stack([log.time_s, log.current_left_a, log.current_right_a, log.v_mps - half, log.v_mps + half])
            np.savetxt(d / f"pro_{k:02d}.csv", pro, delimiter=",", header="time,curL,curR,velL,velR", comments="")
            ta = log.accel_time_s
            imu = np.column_stack([ta, np.zeros((ta.size, 5)), log.accel_z_mps2])
            np.savetxt(d / f"imu_{k:02d}.csv", imu, delimiter=",", header="time,wx,wy,wz,ax,ay,az", comments="")


def test_cli_evaluate_protocol_adapt_and_few_shot(logs, tmp_path, capsys):
    from terrawatt_cli import main

    data = tmp_path / "logs"
    _write_borealtc(data, {"grass": logs[:3], "sand": logs[3:]})
    rc = main(["evaluate", "--data", str(data), "--model", "linear", "--protocol", "adapt", "--adapt-seconds", "20",
               "--out", str(tmp_path / "out")])
    assert rc == 0
    res = json.loads((tmp_path / "out" / "adapt.json").read_text())
    assert {r["schedule"] for r in res["runs"]} == {"20 s", TRIGGER_SCHEDULE}
    assert {r["model"] for r in res["runs"]} == {"linear"}
    printed = capsys.readouterr().out
    assert "| per_ground | grass | linear | 20 s |" in printed and "adapt.md" in printed
    rc = main(["evaluate", "--data", str(data), "--model", "linear", "--protocol", "few-shot", "--adapt-seconds", "10",
               "--out", str(tmp_path / "few")])
    assert rc == 0
    few = json.loads((tmp_path / "few" / "adapt.json").read_text())
    assert {r["protocol"] for r in few["runs"]} == {"few_shot"} and {r["schedule"] for r in few["runs"]} == {"10 s"}


@pytest.mark.parametrize(("extra", "match"), [
    (["--adapt-seconds", "0"], "--adapt-seconds"),
    (["--adapt-threshold", "-3"], "--adapt-threshold"),
    # longer than every run: the table was empty and the exit 0
    (["--adapt-seconds", "20", "1e9"], "--adapt-seconds 1e+09: no run lasts 1e+09 s plus the 10 s scored after"),
])
def test_cli_bad_adapt_options_exit_2(logs, tmp_path, capsys, extra, match):
    from terrawatt_cli import main

    data = tmp_path / "logs"
    _write_borealtc(data, {"grass": logs[:2]})
    rc = main(["evaluate", "--data", str(data), "--model", "linear", "--protocol", "adapt", *extra,
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert match in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_folds_on_a_dask_client_give_the_serial_scores(logs, result):
    distributed = pytest.importorskip("distributed", reason="the client path needs the distributed extra")
    with distributed.Client(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=":0") as client:
        on_cluster = evaluate_adaptation(logs, LinearCurrentModel(), name="linear", settings=adapt_settings(), client=client)
    assert on_cluster.runs == result.runs
