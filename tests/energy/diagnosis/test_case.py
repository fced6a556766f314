"""Tests of energy.diagnosis.case: the folds (disjoint, every sample held out once, contiguous blocks), the checked
case and its prepared data."""

import numpy as np
import pytest
from gain_samples import gained_logs_and_model
from power_samples import small_power_scenario

from energy import InteractionLog
from energy.diagnosis import FitSettings, Fold, make_split
from energy.diagnosis.case import diagnosis_case
from energy.diagnosis.model_source import ModelUnderDiagnosis
from terrawatt_base.errors import DataError, InvalidParameterError, UnknownNameError


# ---------------------------------------------------------------- folds
def _split_log(n, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.1
    return InteractionLog(t, rng.random(n), np.zeros(n), rng.random(n) + 1, rng.random(n) + 1, t, np.full(n, 9.81))


@pytest.mark.parametrize("kind", ["runs", "blocks"])
def test_folds_are_disjoint_and_cover_every_sample_once(kind):
    logs = [_split_log(50, 1), _split_log(37, 2), _split_log(64, 3)]
    sp = make_split(logs, kind, n_blocks=4)
    counts = [np.zeros(len(log), dtype=int) for log in logs]
    for fold in sp.folds:
        for k, (c, h) in enumerate(zip(fold.calibration, fold.held_out)):
            assert not np.any(c & h)  # never scored on the data it was fitted on
            assert np.all(c | h)
            counts[k] += h
        assert fold.n_held_out > 0 and fold.n_calibration > 0
    assert all(np.all(c == 1) for c in counts)


def test_blocks_are_contiguous():
    sp = make_split([_split_log(100)], "blocks", n_blocks=5)
    assert sp.n_units == 5
    for fold in sp.folds:
        idx = np.flatnonzero(fold.held_out[0])
        assert np.all(np.diff(idx) == 1) and idx.size == 20


def test_runs_fold_whole_runs():
    sp = make_split([_split_log(10, k) for k in range(7)], "runs", n_blocks=3)
    assert len(sp.folds) == 3
    for fold in sp.folds:
        assert all(h.all() or not h.any() for h in fold.held_out)


def test_bad_splits():
    with pytest.raises(DataError, match="at least 2 runs"):
        make_split([_split_log(10)], "runs")
    with pytest.raises(DataError, match="no held-out data"):
        make_split([_split_log(3)], "blocks", n_blocks=5)
    with pytest.raises(UnknownNameError, match="split"):
        make_split([_split_log(10)], "interleaved")
    with pytest.raises(InvalidParameterError, match="n_blocks"):
        make_split([_split_log(10)], "blocks", n_blocks=1)
    with pytest.raises(InvalidParameterError, match="both calibration and held out"):
        Fold((np.ones(3, bool),), (np.ones(3, bool),))


# ---------------------------------------------------------------- the case
def test_the_case_prepares_each_stage_once_on_one_split():
    sc = small_power_scenario("control")
    logs, model = sc.make_logs(0), sc.make_model(0)
    case = diagnosis_case(model, logs, effects=["idle_current", "sensor", "control"],
                          settings=FitSettings(split="blocks", n_blocks=3))
    assert case.split.kind == "blocks" and case.power.split is case.split  # both stages scored on one split
    assert [e.name for e in case.candidates] == ["idle_current"] and case.learned is None  # named: no learned one
    assert [e.name for e in case.power_candidates] == ["sensor", "control"]
    assert set(case.data.prepared) == {"idle_current"} and set(case.power.prepared) == {"sensor", "control"}
    assert case.data.n_columns == 2 and case.power.n_columns == 1 and case.data.stopped is None
    assert len(case.power.stopped) == len(logs) and case.power.basis is case.data.basis
    for log, pred, measured in zip(logs, case.predictions, case.data.measured):
        assert pred.shape == measured.shape == (len(log), 2)
    np.testing.assert_array_equal(case.predictions[0], model.predict(logs[0]))  # the model as it predicts


def test_the_catalogue_brings_the_learned_correction_and_says_what_it_skips():
    logs, model = gained_logs_and_model()
    case = diagnosis_case(model, logs)
    assert case.learned is not None and not case.learned_requested
    assert "learned_residual" in case.data.prepared and case.power is None  # no battery power logged
    assert "slope" in case.skipped  # no map


def test_the_case_checks_what_it_is_given():
    logs, model = gained_logs_and_model()
    with pytest.raises(InvalidParameterError, match="settings must be a FitSettings"):
        diagnosis_case(model, logs, settings={"split": "runs"})
    with pytest.raises(InvalidParameterError, match="robot must be None with a ModelUnderDiagnosis"):
        diagnosis_case(ModelUnderDiagnosis(model, "a note", "file"), logs, robot="husky")
    g = logs[1]
    one = InteractionLog(g.time_s[:1], g.v_mps[:1], g.omega_radps[:1], g.current_left_a[:1], g.current_right_a[:1],
                         g.time_s[:1], g.accel_z_mps2[:1])
    with pytest.raises(DataError, match="needs at least 2 per log"):
        diagnosis_case(model, [logs[0], one])
