"""The estimator's network: :class:`CurrentNet` (an MLP over window and run features) and its config.

Its random initialisation and its dropout draw from local ``torch.Generator`` objects
seeded by the ``seed`` given to :class:`CurrentNet`; torch's global generator is never
used or reseeded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import nn

from terrawatt_base.checks import check_int, check_real, check_seed
from terrawatt_base.errors import InvalidParameterError

__all__ = ["CurrentNetConfig", "CurrentNet", "SeededDropout"]


@dataclass(frozen=True)
class CurrentNetConfig:
    """Shape of a :class:`CurrentNet`.

    Parameters
    ----------
    n_window_inputs : int
        Features per window (>= 1).
    n_run_inputs : int
        Run-level features (>= 0; e.g. 8000 spectrum bins).
    n_outputs : int
        Outputs per window (>= 1).
    hidden_sizes : tuple of int
        Widths of the hidden layers (at least one).
    dropout : float
        Dropout after each hidden activation, in [0, 1).
    """

    n_window_inputs: int
    n_run_inputs: int
    n_outputs: int
    hidden_sizes: tuple[int, ...] = (100, 100, 100)
    dropout: float = 0.0

    def __post_init__(self) -> None:
        for name, low in (("n_window_inputs", 1), ("n_run_inputs", 0), ("n_outputs", 1)):
            object.__setattr__(self, name, check_int(name, getattr(self, name), low=low, owner="CurrentNetConfig"))
        hs = self.hidden_sizes
        if isinstance(hs, (str, bytes)) or not hasattr(hs, "__iter__") or not tuple(hs):
            raise InvalidParameterError(f"CurrentNetConfig.hidden_sizes must be a non-empty tuple of ints >= 1, got {hs!r}")
        sizes = tuple(check_int("hidden_sizes", h, low=1, owner="CurrentNetConfig") for h in hs)
        object.__setattr__(self, "hidden_sizes", sizes)
        check_real("dropout", self.dropout, low=0.0, high=1.0, high_inclusive=False, owner="CurrentNetConfig")


class SeededDropout(nn.Module):
    """Dropout whose masks are drawn from a given ``torch.Generator`` (not the global one).

    Same masks as :func:`torch.nn.functional.dropout` would draw from a global generator
    in the same state; identity in eval mode.
    """

    def __init__(self, p: float, generator: torch.Generator) -> None:
        super().__init__()
        self.p = check_real("p", p, low=0.0, high=1.0, high_inclusive=False)
        self.generator = generator

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if not self.training or self.p == 0.0:
            return x
        keep = 1.0 - self.p
        mask = torch.empty_like(x).bernoulli_(keep, generator=self.generator)
        return x * mask.div_(keep)

    def extra_repr(self) -> str:
        return f"p={self.p}"


def _generator(seed: int | None) -> torch.Generator:
    gen = torch.Generator()
    if seed is None:
        gen.seed()  # fresh entropy
    else:
        gen.manual_seed(seed)
    return gen


def _linear(n_in: int, n_out: int, bias: bool = True) -> nn.Linear:
    """An uninitialised ``nn.Linear`` (no draw from torch's global generator)."""
    return torch.nn.utils.skip_init(nn.Linear, n_in, n_out, bias=bias)


class CurrentNet(nn.Module):
    """MLP from window features (+ run-level features) to the currents of the window.

    ``forward(x_window, run_table, run_index)``: ``x_window`` (B, n_window_inputs),
    ``run_table`` (R, n_run_inputs) — one row per run — and ``run_index`` (B,) long, the
    run of each sample. The first hidden layer is
    ``W_w x_window + (W_r run_table)[run_index] + b``, i.e. one dense layer over the
    concatenation ``[run features, window features]`` computed without repeating the run
    features per sample. ReLU activations, optional dropout, linear output.

    ``seed`` seeds the local generators of the initial weights and of the dropout masks
    (``None``: fresh entropy); the same seed gives the same network.
    """

    def __init__(self, config: CurrentNetConfig, seed: int | None = None) -> None:
        super().__init__()
        self.config = config
        self.seed = check_seed(seed)
        init = _generator(self.seed)
        self.dropout_generator = _generator(self.seed)
        h0 = config.hidden_sizes[0]
        self.window_in = _linear(config.n_window_inputs, h0)
        self.run_in = _linear(config.n_run_inputs, h0, bias=False) if config.n_run_inputs else None
        layers: list[nn.Module] = [nn.ReLU()]
        if config.dropout:
            layers.append(SeededDropout(config.dropout, self.dropout_generator))
        for a, b in zip(config.hidden_sizes[:-1], config.hidden_sizes[1:]):
            layers += [_linear(a, b), nn.ReLU()]
            if config.dropout:
                layers.append(SeededDropout(config.dropout, self.dropout_generator))
        layers.append(_linear(config.hidden_sizes[-1], config.n_outputs))
        self.body = nn.Sequential(*layers)
        self.reset_parameters(init)

    def reset_parameters(self, generator: torch.Generator) -> None:
        """Draw every weight and bias from ``generator`` (torch's default ``nn.Linear`` init).

        Layers are drawn in construction order, so a generator seeded with ``s`` gives the
        weights ``torch.manual_seed(s)`` followed by construction gave before.
        """
        with torch.no_grad():
            for layer in self.modules():
                if isinstance(layer, nn.Linear):
                    nn.init.kaiming_uniform_(layer.weight, a=math.sqrt(5), generator=generator)
                    if layer.bias is not None:
                        fan_in = layer.weight.shape[1]
                        bound = 1.0 / math.sqrt(fan_in) if fan_in > 0 else 0.0
                        nn.init.uniform_(layer.bias, -bound, bound, generator=generator)

    @property
    def n_inputs(self) -> int:
        """Inputs of the equivalent single first layer (run + window features)."""
        return self.config.n_run_inputs + self.config.n_window_inputs

    def forward(self, x_window: torch.Tensor, run_table: torch.Tensor, run_index: torch.Tensor) -> torch.Tensor:
        h = self.window_in(x_window)
        if self.run_in is not None:
            h = h + self.run_in(run_table)[run_index]
        return self.body(h)


