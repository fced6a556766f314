"""The estimator's training loop: :func:`train_network`, its :class:`TrainConfig` and :class:`TrainingHistory`.

The loop knows nothing about the model beyond ``net(*dataset.inputs(idx))``; its shuffling
draws from a local ``torch.Generator`` seeded with the given seed (torch's global generator
is never reseeded). A model that draws random numbers itself (dropout) brings its own
seeded generator, as :class:`~energy.models.net.CurrentNet` does.
"""

from __future__ import annotations

import math
import numbers
import time
from dataclasses import dataclass
from typing import Any

import torch
from torch import nn

from terrawatt_base.checks import check_bool, check_choice, check_int, check_real, check_seed
from terrawatt_base.errors import InvalidParameterError

from .data import WindowDataset

__all__ = ["LOSSES", "TrainConfig", "TrainingHistory", "train_network"]

#: Loss names of :class:`TrainConfig`.
LOSSES = ("mse", "huber")


@dataclass(frozen=True)
class TrainConfig:
    """Settings of :func:`train_network`.

    Parameters
    ----------
    max_epochs : int
        Passes over the training windows (>= 1).
    batch_size : int
        Windows per step (>= 1).
    learning_rate : float
        Adam step size (> 0).
    weight_decay : float
        AdamW decoupled weight decay (>= 0).
    patience : int or None
        Early stopping: stop after this many epochs without a better validation loss and
        restore the best weights; ``None`` trains all epochs and keeps the last weights.
    loss : {"mse", "huber"}
        Loss on the normalised targets (Huber with delta 0.1 = 1 A at the source scale).
    """

    max_epochs: int = 100
    batch_size: int = 64
    learning_rate: float = 1e-3
    weight_decay: float = 0.0
    patience: int | None = None
    loss: str = "mse"

    def __post_init__(self) -> None:
        for name in ("max_epochs", "batch_size"):
            object.__setattr__(self, name, check_int(name, getattr(self, name), low=1, owner="TrainConfig"))
        check_real("learning_rate", self.learning_rate, low=0.0, low_inclusive=False, owner="TrainConfig")
        check_real("weight_decay", self.weight_decay, low=0.0, owner="TrainConfig")
        if self.patience is not None:
            object.__setattr__(self, "patience", check_int("patience", self.patience, low=1, owner="TrainConfig"))
        check_choice("TrainConfig.loss", self.loss, LOSSES)


@dataclass(frozen=True)
class TrainingHistory:
    """What :func:`train_network` did.

    Attributes
    ----------
    train_loss, validation_loss : tuple of float
        Mean loss per epoch (validation empty without validation windows).
    best_epoch : int
        Epoch (0-based) whose weights the network keeps: the best validation epoch with
        early stopping, else the last one.
    stopped_early : bool
    duration_s : float
        Wall-clock training time (s).
    """

    train_loss: tuple[float, ...]
    validation_loss: tuple[float, ...]
    best_epoch: int
    stopped_early: bool
    duration_s: float

    def to_dict(self) -> dict[str, Any]:
        """Plain-types form for checkpoints."""
        return {"train_loss": list(self.train_loss), "validation_loss": list(self.validation_loss),
                "best_epoch": self.best_epoch, "stopped_early": self.stopped_early, "duration_s": self.duration_s}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TrainingHistory:
        """Rebuild from :meth:`to_dict` output."""
        def losses(name: str) -> tuple[float, ...]:
            value = d[name]
            if not isinstance(value, (list, tuple)):
                raise InvalidParameterError(f"TrainingHistory.{name} must be a list of numbers, got {type(value).__name__}")
            if any(isinstance(v, bool) or not isinstance(v, numbers.Real) for v in value):
                raise InvalidParameterError(f"TrainingHistory.{name} must be a list of numbers")
            return tuple(float(v) for v in value)  # NaN stands for an epoch without validation

        return cls(losses("train_loss"), losses("validation_loss"), check_int("TrainingHistory.best_epoch",
                   d["best_epoch"], low=0), check_bool("TrainingHistory.stopped_early", d["stopped_early"]),
                   check_real("TrainingHistory.duration_s", d["duration_s"], low=0.0))


def _loss_fn(name: str) -> nn.Module:
    return nn.MSELoss() if name == "mse" else nn.HuberLoss(delta=0.1)


def train_network(
    net: nn.Module,
    train: WindowDataset,
    validation: WindowDataset | None,
    config: TrainConfig,
    seed: int | None,
    progress: bool = False,
    description: str = "training",
) -> TrainingHistory:
    """Train any module that maps ``dataset.inputs(idx)`` to ``dataset.targets(idx)``.

    AdamW on shuffled mini-batches, shuffled by a local ``torch.Generator`` seeded with
    ``seed`` (torch's global generator is neither seeded nor used; a model with dropout
    brings its own seeded generator, as :class:`~energy.models.net.CurrentNet`). The loop
    knows nothing about the model beyond ``net(*inputs)``. Uses the thread count
    torch is set to (``torch.set_num_threads``).

    Parameters
    ----------
    net : torch.nn.Module
    train : WindowDataset
    validation : WindowDataset or None
        Scored after every epoch; required for early stopping.
    config : TrainConfig
    seed : int or None
        Seed of the shuffling (:func:`terrawatt_base.checks.check_seed`; ``None``: fresh entropy).
    progress : bool
        Show a tqdm bar with the losses.
    description : str
        Label of the progress bar.

    Returns
    -------
    TrainingHistory

    Raises
    ------
    InvalidParameterError
        Early stopping requested without validation windows; empty training set; a bad
        ``seed``.
    """
    seed = check_seed(seed)
    if len(train) == 0:
        raise InvalidParameterError("train_network needs at least one training window")
    if config.patience is not None and (validation is None or len(validation) == 0):
        raise InvalidParameterError("early stopping (patience) needs validation windows; got none")
    from tqdm.auto import tqdm

    gen = torch.Generator()
    if seed is None:
        gen.seed()
    else:
        gen.manual_seed(seed)
    opt = torch.optim.AdamW(net.parameters(), lr=config.learning_rate, weight_decay=config.weight_decay,
                            foreach=True)  # same values as the per-tensor loop, fewer kernel calls
    loss_fn = _loss_fn(config.loss)
    n = len(train)
    t0 = time.perf_counter()
    train_losses: list[float] = []
    val_losses: list[float] = []
    best = math.inf
    best_epoch = 0
    best_state: dict[str, torch.Tensor] | None = None
    stopped = False
    bar = tqdm(range(config.max_epochs), desc=description, disable=not progress, leave=False)
    for epoch in bar:
        net.train()
        perm = torch.randperm(n, generator=gen)
        total = 0.0
        for i in range(0, n, config.batch_size):
            idx = perm[i : i + config.batch_size]
            opt.zero_grad(set_to_none=True)
            loss = loss_fn(net(*train.inputs(idx)), train.targets(idx))
            loss.backward()
            opt.step()
            total += float(loss.detach()) * idx.numel()
        train_losses.append(total / n)
        if validation is not None and len(validation):
            net.eval()
            with torch.no_grad():
                vl = float(loss_fn(net(*validation.inputs(slice(None))), validation.targets(slice(None))))
            val_losses.append(vl)
            if vl < best:
                best, best_epoch = vl, epoch
                if config.patience is not None:
                    best_state = {k: v.detach().clone() for k, v in net.state_dict().items()}
            bar.set_postfix(loss=f"{train_losses[-1]:.4g}", val=f"{vl:.4g}")
            if config.patience is not None and epoch - best_epoch >= config.patience:
                stopped = True
                break
        else:
            best_epoch = epoch
            bar.set_postfix(loss=f"{train_losses[-1]:.4g}")
    bar.close()
    if best_state is not None:
        net.load_state_dict(best_state)
    else:
        best_epoch = len(train_losses) - 1 if config.patience is None else best_epoch
    net.eval()
    return TrainingHistory(tuple(train_losses), tuple(val_losses), int(best_epoch), stopped,
                           time.perf_counter() - t0)
