"""Tests of energy.evaluation.scoring: leave-one-run-out per ground and ground-agnostic, a prefit model scored."""

import dataclasses
import json

import numpy as np
import pytest
from evaluation_samples import score_log, score_logs

from energy import (
    ConstantCurrentModel,
    EvaluationResult,
    InteractionLog,
    LinearCurrentModel,
    evaluate_current_models,
)
from terrain import TerrawattWarning
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError


@pytest.fixture(scope="module")
def logs():
    return score_logs()


@pytest.fixture(scope="module")
def result(logs):
    return evaluate_current_models(logs, {"constant": ConstantCurrentModel(), "linear": LinearCurrentModel()})


def test_every_run_side_model_and_variant_is_scored(result):
    assert isinstance(result, EvaluationResult)
    assert len(result.runs) == 2 * 6 * 2 * 2  # variants x runs x models x sides
    per_ground = [r for r in result.runs if r.variant == "per_ground"]
    assert {r.run for r in per_ground} == {f"grass/pro_0{i}" for i in range(3)} | {f"sand/pro_1{i}" for i in range(3)}
    assert {(r.model, r.side) for r in per_ground} == {(m, s) for m in ("constant", "linear") for s in ("left", "right")}


def test_linear_model_is_exact_per_ground_but_not_across_grounds(result):
    exact = result.row_for("all", "linear", variant="per_ground")
    assert exact.whole_run_median_pct < 1e-6 and exact.rmse_p90_a < 1e-6
    assert exact.n_runs == 6 and exact.n_values == 12
    mixed = result.row_for("all", "linear", variant="ground_agnostic")
    assert mixed.whole_run_median_pct > 10.0
    const = result.row_for("grass", "constant", variant="per_ground")
    assert const.section_median_pct >= const.whole_run_median_pct > 0.0


def test_scores_agree_with_a_direct_fit(logs, result):
    test, train = logs[0], logs[1:3]
    pred = LinearCurrentModel().fit(train).predict(test)
    q_true = np.trapezoid(test.current_left_a, test.time_s) / 3.6
    q_pred = np.trapezoid(pred[:, 0], test.time_s) / 3.6
    row = next(r for r in result.runs if (r.variant, r.model, r.run, r.side) == ("per_ground", "linear", "grass/pro_00", "left"))
    assert row.charge_true_mah == pytest.approx(q_true)
    assert row.charge_predicted_mah == pytest.approx(q_pred)
    assert row.duration_s == pytest.approx(test.duration_s)


class _SpyModel(ConstantCurrentModel):
    """Records, for every prediction, the run predicted and the runs the model was fitted on.

    ``folds`` is a class attribute, so it survives the ``clone()`` the evaluation makes of
    every prototype for every fold.
    """

    folds: list[tuple[str, tuple[str, ...]]] = []

    def _fit(self, logs):
        super()._fit(logs)
        self.train_sources_ = tuple(log.meta.source for log in logs)

    def _predict(self, log):
        _SpyModel.folds.append((log.meta.source, self.train_sources_))
        return super()._predict(log)


@pytest.mark.parametrize("variant", ["per_ground", "ground_agnostic"])
def test_no_fold_trains_on_its_held_out_run(logs, variant):
    _SpyModel.folds.clear()
    evaluate_current_models(logs, {"spy": _SpyModel()}, variants=(variant,))
    ground = {log.meta.source: log.meta.ground_label for log in logs}
    assert sorted(test for test, _ in _SpyModel.folds) == sorted(ground)  # every run held out once
    for test, train in _SpyModel.folds:
        assert test not in train
        if variant == "per_ground":
            assert set(train) == {s for s in ground if ground[s] == ground[test] and s != test}
        else:
            assert set(train) == set(ground) - {test}
        assert len(train) == len(set(train))


def test_single_run_ground_is_skipped_with_a_warning(logs):
    few = logs[:3] + [score_log(20, "ice", 1.0)]
    with pytest.warns(TerrawattWarning, match="'ice' has 1 run"):
        res = evaluate_current_models(few, {"linear": LinearCurrentModel()}, variants=("per_ground",))
    assert res.skipped and "ice" in res.skipped[0]
    assert {r.ground for r in res.runs} == {"grass"}


def test_bad_inputs_raise(logs):
    unlabeled = InteractionLog(logs[0].time_s, logs[0].v_mps, logs[0].omega_radps, logs[0].current_left_a,
                               logs[0].current_right_a, logs[0].accel_time_s, logs[0].accel_z_mps2)
    with pytest.raises(DataError, match="ground_label"):
        evaluate_current_models([unlabeled, logs[1]], {"c": ConstantCurrentModel()})
    with pytest.raises(UnknownNameError, match="variant"):
        evaluate_current_models(logs, {"c": ConstantCurrentModel()}, variants=("cross_robot",))
    with pytest.raises(InvalidParameterError, match="at least one CurrentModel"):
        evaluate_current_models(logs, {})
    with pytest.raises(InvalidParameterError, match="must be a CurrentModel"):
        evaluate_current_models(logs, {"x": object()})
    with pytest.raises(DataError, match="at least 2 runs"):
        evaluate_current_models(logs[:1], {"c": ConstantCurrentModel()})


# ------------------------------------------------------------------ on a dask cluster

_NO_DASK = "evaluation on a cluster needs the distributed extra (dask[distributed])"


@pytest.fixture(scope="module")
def dask_client():
    """A client of an in-process cluster: one worker with two threads, no dashboard."""
    distributed = pytest.importorskip("distributed", reason=_NO_DASK)
    with distributed.LocalCluster(processes=False, n_workers=1, threads_per_worker=2, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            yield client


def _without_fit_time(rows):
    """Every field but the measured fit time (which differs from run to run)."""
    return [{k: v for k, v in dataclasses.asdict(r).items() if not k.startswith("fit_duration")} for r in rows]


class _FailingFitModel(ConstantCurrentModel):
    """Refuses every training set, to see a fold's exception reach the caller."""

    def _fit(self, logs):
        raise DataError(f"refusing to fit on {len(logs)} runs")


def test_cluster_scores_equal_the_serial_scores_in_the_same_order(logs, result, dask_client):
    on_cluster = evaluate_current_models(
        logs, {"constant": ConstantCurrentModel(), "linear": LinearCurrentModel()}, client=dask_client, progress=True
    )
    assert all(np.isfinite(r.whole_run_error_pct) for r in result.runs)  # so == below compares no NaN
    assert _without_fit_time(on_cluster.runs) == _without_fit_time(result.runs)
    assert _without_fit_time(on_cluster.rows) == _without_fit_time(result.rows)
    assert (on_cluster.models, on_cluster.variants, on_cluster.skipped) == (result.models, result.variants, result.skipped)
    assert all(r.fit_duration_s >= 0.0 for r in on_cluster.runs)


def test_a_client_that_is_not_a_dask_client_is_refused(logs, dask_client):
    for bad in ("tcp://127.0.0.1:8786", dask_client.cluster):
        with pytest.raises(InvalidParameterError, match=r"client must be None .* or a distributed\.Client, got"):
            evaluate_current_models(logs, {"c": ConstantCurrentModel()}, client=bad)


def test_an_exception_in_a_fold_reaches_the_caller(logs, dask_client):
    models = {"constant": ConstantCurrentModel(), "failing": _FailingFitModel()}
    with pytest.raises(DataError, match="refusing to fit on 2 runs"):
        evaluate_current_models(logs, models, variants=("per_ground",), client=dask_client)


def test_a_prefit_model_is_scored_like_a_fold(logs, result):
    from energy.evaluation import score_current_model

    model = LinearCurrentModel().fit(logs[1:3])
    scored = score_current_model(model, [logs[0]], name="linear", section_s=result.section_s)
    assert isinstance(scored, EvaluationResult) and scored.variants == ("prefit",) and scored.protocol == "prefit"
    fold = {r.side: r for r in result.runs if (r.variant, r.model, r.run) == ("per_ground", "linear", "grass/pro_00")}
    for row in scored.runs:  # the same fit scored by the one scoring function
        expected = fold[row.side]
        assert row.run == expected.run and row.charge_true_mah == pytest.approx(expected.charge_true_mah)
        assert row.charge_predicted_mah == pytest.approx(expected.charge_predicted_mah)
        assert row.whole_run_error_pct == pytest.approx(expected.whole_run_error_pct)
        assert np.isnan(row.fit_duration_s)
    assert scored.row_for("all", "linear").n_values == 2
    assert scored.summary().splitlines()[1].split()[:2] == ["grass/pro_00", "left"]  # the scores per run and side
    assert scored.to_dict()["model"] == "linear" and scored.to_dict()["variants"] == ["prefit"]
    with pytest.raises(InvalidParameterError, match="section_s"):
        score_current_model(model, logs, section_s="long")
    with pytest.raises(InvalidParameterError, match="CurrentModel"):
        score_current_model("linear", logs)
    with pytest.raises(InvalidParameterError, match="sequence of InteractionLog"):
        score_current_model(model, logs[0])


def test_output_folder_is_checked_before_any_fold_and_written_after(logs, tmp_path):
    _SpyModel.folds.clear()
    blocker = tmp_path / "taken"
    blocker.write_text("a file")
    with pytest.raises(InvalidParameterError, match="is a file"):
        evaluate_current_models(logs, {"spy": _SpyModel()}, out_dir=blocker)
    (tmp_path / "out" / "evaluation.json").mkdir(parents=True)
    with pytest.raises(InvalidParameterError, match="is a directory"):
        evaluate_current_models(logs, {"spy": _SpyModel()}, out_dir=tmp_path / "out")
    with pytest.raises(InvalidParameterError, match="section_s"):
        evaluate_current_models(logs, {"spy": _SpyModel()}, section_s=float("nan"))
    assert _SpyModel.folds == []  # nothing was fitted or scored
    res = evaluate_current_models(logs, {"constant": ConstantCurrentModel()}, variants=("per_ground",),
                                  out_dir=tmp_path / "new")
    data = json.loads((tmp_path / "new" / "evaluation.json").read_text())
    assert len(data["runs"]) == len(res.runs)
    assert (tmp_path / "new" / "evaluation.md").read_text() == res.summary()
