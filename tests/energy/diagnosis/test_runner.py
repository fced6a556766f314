"""Tests of energy.diagnosis.runner: SetRunner scores effect sets in order, serially or on a dask client."""

import numpy as np
import pytest
from gain_samples import gained_logs_and_model

from energy.diagnosis import effect, make_split
from energy.diagnosis.fit import prepare_data, score_effect_set
from energy.diagnosis.runner import SetRunner
from terrawatt_base.errors import InvalidParameterError


@pytest.fixture(scope="module")
def case():
    logs, model = gained_logs_and_model()
    effects = [effect("current_gain"), effect("idle_current")]
    return effects, prepare_data(model, logs, effects), make_split(logs, "runs", n_blocks=4)


def test_serial_scores_are_the_scores_of_each_set_in_order(case):
    effects, data, split = case
    sets = [[], [effects[0]], [effects[1]], effects]
    runner = SetRunner(data, split)
    scores = runner.score(sets)
    assert len(scores) == 4
    for got, s in zip(scores, sets):
        np.testing.assert_array_equal(got.sse_units, score_effect_set(s, data, split).sse_units)
    assert scores[1].sse_units.sum() < scores[0].sse_units.sum()  # the gain explains the gap
    runner.close()  # nothing scattered: nothing to release


def test_a_client_that_is_not_one_is_refused(case):
    _, data, split = case
    with pytest.raises(InvalidParameterError):
        SetRunner(data, split, client="tcp://localhost:8786")


def test_on_a_dask_client_equals_serial(case):
    distributed = pytest.importorskip("distributed", reason="the client path needs the distributed extra")
    effects, data, split = case
    sets = [[effects[0]], [effects[1]]]
    with distributed.Client(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=":0") as client:
        runner = SetRunner(data, split, client=client)
        remote = runner.score(sets)
        runner.close()
    serial = SetRunner(data, split).score(sets)
    for a, b in zip(remote, serial):
        np.testing.assert_array_equal(a.sse_units, b.sse_units)
