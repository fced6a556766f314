"""Tests of energy.models.training: TrainConfig, TrainingHistory and the model-agnostic train_network loop."""

import numpy as np
import pytest
import torch

from energy.features import WindowSpec
from energy.models import TrainConfig, TrainingHistory, WindowDataset, train_network
from terrawatt_base.errors import InvalidParameterError, UnknownNameError


def test_training_loop_knows_nothing_about_the_model():
    class Affine(torch.nn.Module):
        def __init__(self):
            super().__init__()
            self.lin = torch.nn.Linear(1, 1)

        def forward(self, x, table, index):
            return self.lin(x)

    x = np.linspace(-1, 1, 64)[:, None]
    ds = WindowDataset(x, np.zeros((1, 0)), np.zeros(64, int), np.arange(64), WindowSpec(1, 1, 1.0), y=2.0 * x + 0.5)
    net = Affine()
    hist = train_network(net, ds, None, TrainConfig(max_epochs=300, batch_size=16, learning_rate=0.05), seed=0)
    assert net.lin.weight.item() == pytest.approx(2.0, abs=0.02)
    assert net.lin.bias.item() == pytest.approx(0.5, abs=0.02)
    assert hist.train_loss[-1] < hist.train_loss[0]
    with pytest.raises(InvalidParameterError, match="validation"):
        train_network(Affine(), ds, None, TrainConfig(patience=2), seed=0)


@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(max_epochs=0), "max_epochs"),
    (dict(batch_size=0), "batch_size"),
    (dict(learning_rate=0.0), "learning_rate"),
    (dict(weight_decay=-1.0), "weight_decay"),
    (dict(patience=0), "patience"),
])
def test_train_config_rejects_bad_values(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        TrainConfig(**kwargs)


def test_train_config_loss_names():
    assert TrainConfig(loss="huber").loss == "huber"
    with pytest.raises(UnknownNameError, match="TrainConfig.loss"):
        TrainConfig(loss="l1")


def test_training_history_round_trips_and_validates():
    hist = TrainingHistory((1.0, 0.5), (), 1, False, 0.25)
    assert TrainingHistory.from_dict(hist.to_dict()) == hist
    with pytest.raises(InvalidParameterError, match="TrainingHistory.train_loss must be a list of numbers, got str"):
        TrainingHistory.from_dict(hist.to_dict() | {"train_loss": "1.0"})
    with pytest.raises(InvalidParameterError, match="TrainingHistory.validation_loss must be a list of numbers"):
        TrainingHistory.from_dict(hist.to_dict() | {"validation_loss": [True]})
    with pytest.raises(InvalidParameterError, match="best_epoch"):
        TrainingHistory.from_dict(hist.to_dict() | {"best_epoch": -1})
