"""Tests of energy.models.ensemble: the members trained in lockstep end as if trained one after another."""

import numpy as np
import pytest
import torch

from energy.features import WindowSpec
from energy.models import CurrentNet, CurrentNetConfig, TrainConfig, WindowDataset, train_ensemble, train_network
from terrain import InvalidParameterError


def _data(seed: int, n: int = 120, n_run: int = 0) -> WindowDataset:
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, 4))
    y = np.column_stack([x[:, 0] - 0.5 * x[:, 1], np.abs(x[:, 2])]) + 0.05 * rng.normal(size=(n, 2))
    runs = np.arange(n) % 3
    return WindowDataset(x, rng.normal(size=(3, n_run)), runs, np.arange(n), WindowSpec(1, 1, 1.0), y=y)


@pytest.mark.parametrize(("dropout", "n_run", "patience"), [(0.2, 0, 3), (0.0, 2, None), (0.1, 2, 2)])
def test_lockstep_members_equal_members_trained_one_after_another(dropout, n_run, patience):
    train, val = _data(0, 64, n_run=n_run), _data(1, 24, n_run=n_run)
    cfg = TrainConfig(max_epochs=12, batch_size=32, learning_rate=0.05, weight_decay=1e-3, patience=patience)
    net_cfg = CurrentNetConfig(4, n_run, 2, hidden_sizes=(8, 8), dropout=dropout)
    seeds = [11, 12, 13]
    alone = [CurrentNet(net_cfg, seed=s) for s in seeds]
    together = [CurrentNet(net_cfg, seed=s) for s in seeds]
    h_alone = [train_network(n, train, val, cfg, s) for n, s in zip(alone, seeds)]
    h_together = train_ensemble(together, train, val, cfg, seeds)
    x = val.inputs(slice(None))
    for a, b, ha, hb in zip(alone, together, h_alone, h_together):
        with torch.no_grad():
            assert torch.allclose(a(*x), b(*x), atol=1e-5)
        assert ha.best_epoch == hb.best_epoch and ha.stopped_early == hb.stopped_early
        np.testing.assert_allclose(ha.train_loss, hb.train_loss, rtol=1e-4)
        np.testing.assert_allclose(ha.validation_loss, hb.validation_loss, rtol=1e-4)
    assert not any(n.training for n in together)


def test_huber_loss_and_no_validation():
    train = _data(2)
    cfg = TrainConfig(max_epochs=5, batch_size=64, patience=None, loss="huber")
    net_cfg = CurrentNetConfig(4, 0, 2, hidden_sizes=(6,))
    a, b = CurrentNet(net_cfg, seed=1), CurrentNet(net_cfg, seed=1)
    ha = train_network(a, train, None, cfg, 3)
    (hb,) = train_ensemble([b], train, None, cfg, [3])
    assert hb.best_epoch == ha.best_epoch == 4 and hb.validation_loss == ()
    x = train.inputs(slice(None))
    with torch.no_grad():
        assert torch.allclose(a(*x), b(*x), atol=1e-5)


def test_bad_ensembles():
    train = _data(3)
    cfg = TrainConfig(max_epochs=2, patience=None)
    net = CurrentNet(CurrentNetConfig(4, 0, 2, hidden_sizes=(6,)), seed=0)
    other = CurrentNet(CurrentNetConfig(4, 0, 2, hidden_sizes=(7,)), seed=0)
    with pytest.raises(InvalidParameterError, match="at least one CurrentNet"):
        train_ensemble([], train, None, cfg, [])
    with pytest.raises(InvalidParameterError, match="one CurrentNetConfig"):
        train_ensemble([net, other], train, None, cfg, [0, 1])
    with pytest.raises(InvalidParameterError, match="one seed per member"):
        train_ensemble([net], train, None, cfg, [0, 1])
    with pytest.raises(InvalidParameterError, match="validation"):
        train_ensemble([net], train, None, TrainConfig(patience=2), [0])


def test_a_member_never_learns_from_the_runs_of_its_fold():
    cfg = TrainConfig(max_epochs=4, batch_size=32, patience=None)
    net_cfg = CurrentNetConfig(4, 0, 2, hidden_sizes=(6,))
    folds = np.array([0, 1, 1])  # run 0 is left out of member 0, runs 1 and 2 out of member 1
    plain, moved = _data(4), _data(4)
    moved.y[moved.run_index == 0] += 5.0  # the targets of run 0 changed
    a = [CurrentNet(net_cfg, seed=s) for s in (1, 2)]
    b = [CurrentNet(net_cfg, seed=s) for s in (1, 2)]
    train_ensemble(a, plain, None, cfg, [5, 6], run_folds=folds)
    train_ensemble(b, moved, None, cfg, [5, 6], run_folds=folds)
    x = plain.inputs(slice(None))
    with torch.no_grad():
        assert torch.equal(a[0](*x), b[0](*x))  # member 0 never saw run 0
        assert not torch.allclose(a[1](*x), b[1](*x))  # member 1 learned from it
    with pytest.raises(InvalidParameterError, match="run_folds must be one fold index >= 0 per run") as bad:
        train_ensemble(a, plain, None, cfg, [5, 6], run_folds=np.array([0, 1]))
    assert bad.value.parameter == "run_folds"
    with pytest.raises(InvalidParameterError, match="leave a member without a training window"):
        train_ensemble(a, plain, None, cfg, [5, 6], run_folds=np.array([0, 0, 0]))
