"""Tests of energy.models.net: CurrentNetConfig, CurrentNet (seeded, run and window features) and SeededDropout."""

import pytest
import torch

from energy.models import CurrentNet, CurrentNetConfig, SeededDropout
from terrawatt_base.errors import InvalidParameterError


def test_current_net_equals_one_dense_layer_over_run_and_window_features():
    torch.manual_seed(0)
    net = CurrentNet(CurrentNetConfig(3, 5, 2, hidden_sizes=(4,)))
    x = torch.randn(6, 3)
    table = torch.randn(2, 5)
    idx = torch.tensor([0, 1, 1, 0, 0, 1])
    w = torch.cat([net.run_in.weight, net.window_in.weight], dim=1)
    h = torch.relu(torch.cat([table[idx], x], dim=1) @ w.T + net.window_in.bias)
    expected = net.body[-1](h)
    assert torch.allclose(net(x, table, idx), expected, atol=1e-6)


def test_the_same_seed_gives_the_same_weights_without_the_global_generator():
    cfg = CurrentNetConfig(3, 0, 2, hidden_sizes=(4, 4))
    torch.manual_seed(123)
    before = torch.rand(1)
    torch.manual_seed(123)
    a, b = CurrentNet(cfg, seed=7), CurrentNet(cfg, seed=7)
    assert torch.equal(torch.rand(1), before)  # the global generator was not drawn from
    for pa, pb in zip(a.parameters(), b.parameters()):
        assert torch.equal(pa, pb)
    assert a.run_in is None  # no run features: no run layer
    assert not torch.equal(CurrentNet(cfg, seed=8).window_in.weight, a.window_in.weight)
    x = torch.randn(5, 3)
    assert a(x, torch.zeros(1, 0), torch.zeros(5, dtype=torch.long)).shape == (5, 2)


@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(n_window_inputs=0, n_run_inputs=0, n_outputs=1), "n_window_inputs"),
    (dict(n_window_inputs=1, n_run_inputs=-1, n_outputs=1), "n_run_inputs"),
    (dict(n_window_inputs=1, n_run_inputs=0, n_outputs=0), "n_outputs"),
    (dict(n_window_inputs=1, n_run_inputs=0, n_outputs=1, hidden_sizes=()), "hidden_sizes must be a non-empty tuple"),
    (dict(n_window_inputs=1, n_run_inputs=0, n_outputs=1, hidden_sizes=(4, 0)), "hidden_sizes"),
    (dict(n_window_inputs=1, n_run_inputs=0, n_outputs=1, dropout=1.0), "dropout"),
])
def test_current_net_config_rejects_bad_shapes(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        CurrentNetConfig(**kwargs)


def test_seeded_dropout_draws_its_masks_from_its_generator():
    x = torch.ones(1000)
    a = SeededDropout(0.5, torch.Generator().manual_seed(0))
    b = SeededDropout(0.5, torch.Generator().manual_seed(0))
    ya, yb = a(x), b(x)
    assert torch.equal(ya, yb)
    assert set(ya.unique().tolist()) == {0.0, 2.0}  # kept values scaled by 1 / (1 - p)
    assert 400 < int((ya == 0).sum()) < 600
    a.eval()
    assert torch.equal(a(x), x)  # identity in eval mode
    with pytest.raises(InvalidParameterError, match="p"):
        SeededDropout(1.0, torch.Generator())
