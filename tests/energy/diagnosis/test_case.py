"""Tests of energy.diagnosis.case: the folds (disjoint, every sample held out once, contiguous blocks), the checked
case and its prepared data."""

import numpy as np
import pytest

from energy import InteractionLog
from energy.diagnosis import Fold, make_split
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
