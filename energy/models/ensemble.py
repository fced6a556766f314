"""Train the members of a :class:`~energy.models.net.CurrentNet` ensemble together, as one batched network.

The members of the estimator's ensemble differ only in their seeds, so their layers stack:
:func:`train_ensemble` holds every member's weights in one tensor per layer (member first)
and runs each optimisation step of all members as one batched matrix product, instead of
one small step per member after another (the Python and dispatch overhead of a step, not
its arithmetic, dominates these small networks on a CPU). Each member keeps what
:func:`~energy.models.training.train_network` gives it on its own: its own shuffling
(a ``torch.Generator`` seeded with its seed), its own dropout masks (drawn from its own
``dropout_generator`` in the same order), AdamW with the same settings (element-wise, so the
stacked update is each member's update), its own validation loss and early stopping (a
stopped member's later epochs are ignored and its best weights restored). Batched and
per-member products may round differently in the last bits, so the weights are not
bit-identical to training the members one after another; the distribution is the same.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np
import torch
from torch import nn
from torch.nn import functional

from terrawatt_base.checks import check_seed
from terrawatt_base.errors import InvalidParameterError

from .data import WindowDataset
from .net import CurrentNet, SeededDropout
from .training import TrainConfig, TrainingHistory

__all__ = ["train_ensemble"]


def _layers(net: CurrentNet) -> list[nn.Module]:
    """The body of ``net`` in order: Linear, ReLU and SeededDropout modules."""
    return list(net.body)


class _Stack:
    """Every member's parameters stacked member-first, and the batched forward pass."""

    def __init__(self, nets: Sequence[CurrentNet]) -> None:
        self.nets = list(nets)
        self.m = len(self.nets)

        def stack(get) -> torch.Tensor:  # type: ignore[no-untyped-def]
            return torch.stack([get(n).detach().clone() for n in self.nets]).requires_grad_(True)

        self.w_in = stack(lambda n: n.window_in.weight)
        self.b_in = stack(lambda n: n.window_in.bias)
        self.w_run = stack(lambda n: n.run_in.weight) if self.nets[0].run_in is not None else None
        self.body: list[tuple[str, torch.Tensor | None, torch.Tensor | None, float]] = []
        for i, layer in enumerate(_layers(self.nets[0])):
            if isinstance(layer, nn.Linear):
                self.body.append(("linear", stack(lambda n, i=i: n.body[i].weight), stack(lambda n, i=i: n.body[i].bias), 0.0))
            elif isinstance(layer, SeededDropout):
                self.body.append(("dropout", None, None, layer.p))
            elif isinstance(layer, nn.ReLU):
                self.body.append(("relu", None, None, 0.0))
            else:  # pragma: no cover - CurrentNet builds only these
                raise InvalidParameterError(f"cannot stack a {type(layer).__name__} layer")

    def parameters(self) -> list[torch.Tensor]:
        out = [self.w_in, self.b_in] + ([self.w_run] if self.w_run is not None else [])
        return out + [t for kind, w, b, _ in self.body if kind == "linear" for t in (w, b)]

    def forward(self, x: torch.Tensor, run_table: torch.Tensor, run_index: torch.Tensor, training: bool) -> torch.Tensor:
        """``x`` (M, B, F), ``run_index`` (M, B) -> (M, B, outputs)."""
        h = torch.baddbmm(self.b_in[:, None, :], x, self.w_in.transpose(1, 2))
        if self.w_run is not None:
            per_run = torch.matmul(run_table[None], self.w_run.transpose(1, 2))  # (M, R, H)
            h = h + per_run[torch.arange(self.m)[:, None], run_index]
        for kind, w, b, p in self.body:
            if kind == "linear":
                h = torch.baddbmm(b[:, None, :], h, w.transpose(1, 2))
            elif kind == "relu":
                h = torch.relu(h)
            elif training and p > 0.0:  # each member's mask from its own generator, as SeededDropout draws it
                keep = 1.0 - p
                masks = [torch.empty(h.shape[1:]).bernoulli_(keep, generator=n.dropout_generator) for n in self.nets]
                h = h * torch.stack(masks).div_(keep)
        return h

    def member_state(self, m: int) -> dict[str, torch.Tensor]:
        """Member ``m``'s weights under its own ``state_dict`` keys."""
        net = self.nets[m]
        state = {"window_in.weight": self.w_in[m], "window_in.bias": self.b_in[m]}
        if self.w_run is not None:
            state["run_in.weight"] = self.w_run[m]
        for i, (kind, w, b, _) in enumerate(self.body):
            if kind == "linear":
                state[f"body.{i}.weight"] = w[m]
                state[f"body.{i}.bias"] = b[m]
        if set(state) != set(net.state_dict()):  # pragma: no cover - guards the key layout
            raise RuntimeError(f"stacked keys {sorted(state)} do not match the network's {sorted(net.state_dict())}")
        return {k: v.detach().clone() for k, v in state.items()}


def _member_losses(out: torch.Tensor, y: torch.Tensor, loss: str, weight: torch.Tensor | None = None) -> torch.Tensor:
    """Per member, the mean loss over its windows (``weight`` (M, B): 1 where the member may see the window)."""
    if loss == "mse":
        per = (out - y) ** 2
    else:
        per = functional.huber_loss(out, y, reduction="none", delta=0.1)
    if weight is None:
        return per.mean(dim=(1, 2))
    return (per.mean(dim=2) * weight).sum(dim=1) / weight.sum(dim=1).clamp(min=1.0)


def _check_run_folds(run_folds: np.ndarray | None, datasets: Sequence[WindowDataset | None]) -> np.ndarray | None:
    """``run_folds`` as a 1-D array of ints >= 0 with one entry per run of the datasets' run indices, or None."""
    if run_folds is None:
        return None
    arr = np.asarray(run_folds)
    runs = max((int(d.run_index.max()) + 1 for d in datasets if d is not None and len(d) > 0), default=0)
    if arr.ndim != 1 or arr.dtype.kind not in "iu" or arr.size < runs or (arr.size and arr.min() < 0):
        raise InvalidParameterError(f"run_folds must be one fold index >= 0 per run ({runs} runs), got "
                                    f"{arr.dtype} {arr.shape!r}", parameter="run_folds")
    return arr


def _fold_weights(run_folds: np.ndarray | None, members: int, data: WindowDataset | None) -> torch.Tensor | None:
    """(members, windows): 1 where the member may learn from the window (its run is not in the member's fold)."""
    if run_folds is None or data is None:
        return None
    run_fold = run_folds[data.run_index.numpy()]
    return torch.as_tensor(run_fold[None, :] != np.arange(members)[:, None], dtype=torch.float32)


def train_ensemble(
    nets: Sequence[CurrentNet],
    train: WindowDataset,
    validation: WindowDataset | None,
    config: TrainConfig,
    seeds: Sequence[int],
    progress: bool = False,
    description: str = "training",
    run_folds: np.ndarray | None = None,
) -> list[TrainingHistory]:
    """Train several CurrentNets of one configuration together; each ends as ``train_network`` would train it.

    With ``run_folds`` each member learns only from the runs not in its fold (a cross-validation
    ensemble: the runs a member never saw give out-of-fold predictions), and is validated on the
    same; without them, every member sees every window.

    Parameters
    ----------
    nets : sequence of CurrentNet
        Members with the same :class:`~energy.models.net.CurrentNetConfig` (trained in place).
    train, validation, config, progress, description
        As :func:`~energy.models.training.train_network`.
    seeds : sequence of int
        One shuffling seed per member.
    run_folds : ndarray of int, shape (runs,), optional
        The fold of each run of the datasets' run table (:attr:`WindowDataset.run_index
        <energy.models.data.WindowDataset.run_index>` indexes it): member ``m`` never sees the runs of
        fold ``m`` (every member keeps at least one training window); ``None``: all.

    Returns
    -------
    list of TrainingHistory
        One per member; ``duration_s`` is the shared wall-clock time of the whole ensemble.

    Raises
    ------
    InvalidParameterError
        No members, members of different shapes, a seed count that differs from the member
        count, an empty training set, early stopping without validation windows, run folds that
        are not one int >= 0 per run or leave a member without a training window.
    """
    members = list(nets)
    if not members or not all(isinstance(n, CurrentNet) for n in members):
        raise InvalidParameterError("train_ensemble needs at least one CurrentNet")
    if any(n.config != members[0].config for n in members):
        raise InvalidParameterError("train_ensemble needs members of one CurrentNetConfig")
    seeds = [check_seed(s) for s in seeds]
    if len(seeds) != len(members):
        raise InvalidParameterError(f"train_ensemble needs one seed per member: {len(seeds)} seeds, {len(members)} members")
    if len(train) == 0:
        raise InvalidParameterError("train_ensemble needs at least one training window")
    has_val = validation is not None and len(validation) > 0
    if config.patience is not None and not has_val:
        raise InvalidParameterError("early stopping (patience) needs validation windows; got none")
    from tqdm.auto import tqdm

    m_count = len(members)
    folds = _check_run_folds(run_folds, [train, validation if has_val else None])
    t_weight = _fold_weights(folds, m_count, train)
    v_weight = _fold_weights(folds, m_count, validation if has_val else None)
    if t_weight is not None and bool((t_weight.sum(dim=1) == 0).any()):
        raise InvalidParameterError("run_folds leave a member without a training window", parameter="run_folds")
    stack = _Stack(members)
    gens = []
    for s in seeds:
        g = torch.Generator()
        if s is None:
            g.seed()
        else:
            g.manual_seed(s)
        gens.append(g)
    opt = torch.optim.AdamW(stack.parameters(), lr=config.learning_rate, weight_decay=config.weight_decay, foreach=True)
    x_all, run_table, idx_all = train.inputs(slice(None))
    y_all = train.targets(slice(None))
    n = len(train)
    t0 = time.perf_counter()
    train_losses: list[list[float]] = [[] for _ in members]
    val_losses: list[list[float]] = [[] for _ in members]
    best = [math.inf] * m_count
    best_epoch = [0] * m_count
    best_state: list[dict[str, torch.Tensor] | None] = [None] * m_count
    active = [True] * m_count
    if has_val:
        vx, vtable, vidx = validation.inputs(slice(None))
        vy = validation.targets(slice(None))
    bar = tqdm(range(config.max_epochs), desc=description, disable=not progress, leave=False)
    for epoch in bar:
        perms = torch.stack([torch.randperm(n, generator=g) for g in gens])  # (M, n)
        total = torch.zeros(m_count)
        for i in range(0, n, config.batch_size):
            idx = perms[:, i : i + config.batch_size]  # (M, B)
            opt.zero_grad(set_to_none=True)
            w = None if t_weight is None else torch.gather(t_weight, 1, idx)
            losses = _member_losses(stack.forward(x_all[idx], run_table, idx_all[idx], True), y_all[idx], config.loss, w)
            losses.sum().backward()
            opt.step()
            total += losses.detach() * (idx.shape[1] if w is None else w.sum(dim=1))
        seen = n if t_weight is None else t_weight.sum(dim=1)
        for m in range(m_count):
            if active[m]:
                train_losses[m].append(float(total[m]) / float(seen if t_weight is None else seen[m]))
        if has_val:
            with torch.no_grad():
                m_in = vx[None].expand(m_count, *vx.shape)
                vl = _member_losses(stack.forward(m_in, vtable, vidx[None].expand(m_count, -1), False),
                                    vy[None].expand(m_count, *vy.shape), config.loss, v_weight)
            for m in range(m_count):
                if not active[m]:
                    continue
                val_losses[m].append(float(vl[m]))
                if float(vl[m]) < best[m]:
                    best[m], best_epoch[m] = float(vl[m]), epoch
                    if config.patience is not None:
                        best_state[m] = stack.member_state(m)
                if config.patience is not None and epoch - best_epoch[m] >= config.patience:
                    active[m] = False
            bar.set_postfix(active=sum(active), val=f"{min(best):.4g}")
        else:
            best_epoch = [epoch] * m_count
        if not any(active):
            break
    bar.close()
    duration = time.perf_counter() - t0
    histories = []
    for m, net in enumerate(members):
        state = best_state[m] if best_state[m] is not None else stack.member_state(m)
        with torch.no_grad():
            net.load_state_dict(state)
        net.eval()
        stopped = not active[m]
        epoch_kept = best_epoch[m] if (best_state[m] is not None or config.patience is not None) else len(train_losses[m]) - 1
        histories.append(TrainingHistory(tuple(train_losses[m]), tuple(val_losses[m]), int(epoch_kept), stopped, duration))
    return histories
