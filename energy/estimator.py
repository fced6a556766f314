"""Learned drive-current models: the shared model contract and the vibration-conditioned estimator.

Everything that predicts the left and right drive currents of an :class:`InteractionLog`
derives from :class:`CurrentModel` (scikit-learn contract: the constructor stores its
arguments; ``fit(logs)`` validates, sets attributes ending in ``_`` and returns ``self``;
``predict(log)`` returns an ``(N, 2)`` array of ``[left, right]`` currents in A at
``log.time_s``; ``score`` is R²; one checkpoint file per model, written atomically, with a
format version). The baselines live in :mod:`energy.baselines`.

:class:`VibrationCurrentEstimator` is the torch (CPU) estimator of "End-to-end current
consumption estimation for a driving system of a mobile robot considering geology", in
three parts after minGPT:

1. the model, :class:`CurrentNet`, configured by the frozen :class:`CurrentNetConfig`: an
   MLP whose first layer sums a projection of *window* features (the drive stream over one
   window) and of *run-level* features (the whole-run spectrum), the latter computed once
   per run and gathered per sample — algebraically the paper's single first layer over
   ``[spectrum, v, omega]`` (8020 inputs) without copying 8000 numbers into every window;
2. the windowed dataset, :class:`WindowDataset` (window length and stride stated in samples
   and seconds through :class:`~energy.features.WindowSpec`);
3. the training loop, :func:`train_network`, which knows nothing about the model: it calls
   ``net(*inputs)`` on batches, seeded by ``torch.manual_seed`` and a ``torch.Generator``.

Sampling rates: the paper's 0.1 s windows of 10 samples assume drive streams at 100 Hz;
BorealTC's drive streams run at 6.5 Hz. Both presets resample explicitly with
:meth:`InteractionLog.resample` onto a uniform grid at ``rate_hz``: the ``"paper"`` preset
at 100 Hz (linear interpolation between drive samples — the 10-sample windows then hold
interpolated values, not measurements), the ``"default"`` preset at the training logs'
own median drive rate (no new samples are invented), with 1 s windows (6–7 samples at
6.5 Hz, stride one sample) and the local vibration spectrum of the 100 Hz IMU over each
window.

The ``"default"`` preset departs from the paper where leave-one-run-out on the BorealTC
logs said so: a physics prior (the physics model with rolling resistance, lateral friction
and idle current fitted to the training logs; the networks learn the residual), signed v
and omega (|omega| cannot tell the inner side of a turn), local spectra (12 log-spaced
bands, 1–50 Hz, over 1 s) instead of the whole-run spectrum (with few training runs the
8000-bin — or even a 12-band — whole-run spectrum acts as a run identifier the network
memorises; held-out runs got worse), an ensemble of 5 members, dropout and weight decay,
early stopping on the tail of each run, and predictions clipped to the training current
range.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import logging
import math
import os
import platform
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import torch
from torch import nn

from terrain.atomic import atomic_open
from terrain.errors import (
    DataError,
    FileFormatError,
    FormatVersionError,
    InvalidParameterError,
    NotFittedError,
    UnknownNameError,
)

from .features import (
    DEFAULT_T_INTERVAL_S,
    SOURCE_CURRENT_RANGE_A,
    SOURCE_OMEGA_RANGE_RADPS,
    SOURCE_SPEED_RANGE_MPS,
    SPECTRUM_SCALINGS,
    MinMaxNormaliser,
    WindowSpec,
    band_rms_spectra,
    log_band_edges_hz,
    sliding_windows,
    whole_run_band_spectrum,
    whole_run_spectrum,
    window_starts,
)
from .logs import InteractionLog
from .params import ROBOT_PRESETS

__all__ = [
    "CURRENT_MODEL_FORMAT",
    "CURRENT_MODEL_FORMAT_VERSION",
    "CurrentModel",
    "load_current_model",
    "CurrentNetConfig",
    "CurrentNet",
    "WindowDataset",
    "TrainConfig",
    "TrainingHistory",
    "train_network",
    "EstimatorConfig",
    "ESTIMATOR_PRESETS",
    "estimator_preset",
    "VibrationCurrentEstimator",
]

_LOG = logging.getLogger(__name__)

#: ``format`` field of every current-model checkpoint.
CURRENT_MODEL_FORMAT = "terrawatt-current-model"
#: Version of the checkpoint layout; loading another version raises FormatVersionError.
CURRENT_MODEL_FORMAT_VERSION = 1

_SIDES = ("left", "right")
_LOG_FLOOR_MPS2 = 1e-4  # floor of band RMS before log10 (m/s^2)


# =========================================================================== contract
def _as_log_list(logs: Any, name: str = "logs") -> list[InteractionLog]:
    if isinstance(logs, InteractionLog):
        return [logs]
    if isinstance(logs, (str, bytes)) or not isinstance(logs, Sequence):
        raise InvalidParameterError(f"{name} must be an InteractionLog or a sequence of them, got {logs!r:.80}")
    items = list(logs)
    if not items:
        raise InvalidParameterError(f"{name} must hold at least one InteractionLog, got an empty sequence")
    for i, log in enumerate(items):
        if not isinstance(log, InteractionLog):
            raise InvalidParameterError(f"{name}[{i}] must be an InteractionLog, got {log!r:.80}")
    return items


def _currents(log: InteractionLog) -> np.ndarray:
    return np.column_stack([log.current_left_a, log.current_right_a])


def _package_versions() -> dict[str, str]:
    try:
        own = importlib.metadata.version("terrawatt")
    except importlib.metadata.PackageNotFoundError:
        own = "unknown"
    return {"terrawatt": own, "torch": str(torch.__version__), "numpy": str(np.__version__),
            "python": platform.python_version()}





def _read_checkpoint(path: str | os.PathLike[str]) -> dict[str, Any]:
    p = Path(path)
    if not p.is_file():
        raise FileFormatError(f"current-model file {str(p)!r} does not exist or is not a file")
    try:
        data = torch.load(p, map_location="cpu", weights_only=True)
    except Exception as exc:  # corrupt zip, truncated pickle, foreign format...
        raise FileFormatError(f"{str(p)!r} is not a readable terrawatt current-model file: {exc}") from exc
    if not isinstance(data, dict) or data.get("format") != CURRENT_MODEL_FORMAT:
        raise FileFormatError(f"{str(p)!r} is not a terrawatt current-model file (no format {CURRENT_MODEL_FORMAT!r})")
    version = data.get("format_version")
    if version != CURRENT_MODEL_FORMAT_VERSION:
        raise FormatVersionError(
            f"{str(p)!r} has current-model format version {version!r}; this release reads version "
            f"{CURRENT_MODEL_FORMAT_VERSION}"
        )
    for key in ("model_class", "params", "state"):
        if key not in data:
            raise FileFormatError(f"{str(p)!r} lacks the {key!r} entry of a current-model file")
    return data


class CurrentModel:
    """Base of every drive-current model: fit on logs, predict ``[left, right]`` currents.

    Subclasses set ``_param_names`` (the constructor arguments), implement ``_fit``,
    ``_predict``, ``_state`` / ``_load_state`` and, for non-plain parameters,
    ``_params_to_plain`` / ``_params_from_plain``. Every subclass is registered by class
    name for :func:`load_current_model`.
    """

    _param_names: ClassVar[tuple[str, ...]] = ()
    _registry: ClassVar[dict[str, type[CurrentModel]]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        CurrentModel._registry[cls.__name__] = cls

    # -------------------------------------------------------------- parameters
    def get_params(self) -> dict[str, Any]:
        """The constructor arguments, by name."""
        return {name: getattr(self, name) for name in self._param_names}

    def clone(self) -> CurrentModel:
        """An unfitted model with the same parameters (scikit-learn's ``clone``)."""
        return type(self)(**self.get_params())

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        return f"{type(self).__name__}({args})"

    @property
    def is_fitted(self) -> bool:
        """Whether ``fit`` has run (some attribute ending in ``_`` is set)."""
        return any(k.endswith("_") and not k.startswith("_") for k in vars(self))

    def _check_fitted(self) -> None:
        if not self.is_fitted:
            raise NotFittedError(
                f"this {type(self).__name__} is not fitted yet; call fit(logs) before predict, score or save"
            )

    # ---------------------------------------------------------------- fit / predict
    def fit(self, logs: InteractionLog | Sequence[InteractionLog]) -> CurrentModel:
        """Fit the model to one or more interaction logs.

        Parameters
        ----------
        logs : InteractionLog or sequence of InteractionLog
            Training runs (each keeps its own time axis; runs are never joined across).

        Returns
        -------
        self

        Raises
        ------
        InvalidParameterError
            ``logs`` is not an InteractionLog or a non-empty sequence of them.
        DataError
            The logs are too short or otherwise unusable for this model.
        """
        items = _as_log_list(logs)
        self._clear_fitted()  # refit from scratch
        try:
            self._fit(items)
        except BaseException:
            self._clear_fitted()  # never leave a half-fitted model behind
            raise
        return self

    def _clear_fitted(self) -> None:
        for k in [k for k in vars(self) if k.endswith("_") and not k.startswith("_")]:
            delattr(self, k)

    def predict(self, log: InteractionLog) -> np.ndarray:
        """Predicted drive currents at the log's drive timestamps.

        Parameters
        ----------
        log : InteractionLog
            Uses ``time_s``, ``v_mps``, ``omega_radps`` (and the acceleration stream when
            the model is conditioned on vibration); the logged currents are ignored.

        Returns
        -------
        numpy.ndarray, shape (N, 2)
            ``[left, right]`` current (A) at ``log.time_s``.

        Raises
        ------
        NotFittedError
            Before :meth:`fit`.
        InvalidParameterError
            ``log`` is not an InteractionLog.
        DataError
            The log is too short for the model's windows.
        """
        self._check_fitted()
        if not isinstance(log, InteractionLog):
            raise InvalidParameterError(f"log must be an InteractionLog, got {log!r:.80}")
        out = np.asarray(self._predict(log), dtype=np.float64)
        if out.shape != (len(log), 2):  # internal contract of subclasses
            raise RuntimeError(f"{type(self).__name__}._predict returned shape {out.shape!r}, expected {(len(log), 2)!r}")
        return out

    def score(self, logs: InteractionLog | Sequence[InteractionLog]) -> float:
        """Coefficient of determination R² of the per-sample currents, both sides pooled.

        Raises
        ------
        NotFittedError, InvalidParameterError, DataError
            As :meth:`predict`; DataError also when the logged currents are constant.
        """
        self._check_fitted()
        items = _as_log_list(logs)
        truth = np.concatenate([_currents(log) for log in items])
        pred = np.concatenate([self.predict(log) for log in items])
        ss_tot = float(np.sum((truth - truth.mean()) ** 2))
        if ss_tot == 0:
            raise DataError("score needs logged currents that vary; they are all equal")
        return 1.0 - float(np.sum((truth - pred) ** 2)) / ss_tot

    def _fit(self, logs: list[InteractionLog]) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _predict(self, log: InteractionLog) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    # -------------------------------------------------------------- persistence
    def _params_to_plain(self) -> dict[str, Any]:
        return self.get_params()

    @classmethod
    def _params_from_plain(cls, params: dict[str, Any]) -> dict[str, Any]:
        return dict(params)

    def _state(self) -> dict[str, Any]:  # pragma: no cover - abstract
        raise NotImplementedError

    def _load_state(self, state: dict[str, Any]) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the fitted model to one file, atomically (temporary file, then rename).

        The file (``torch.save`` of plain types and tensors, readable with
        ``weights_only=True``) holds the format and its version, the model class, the
        constructor parameters, the fitted state (weights, normalisers, ranges) and the
        package versions.

        Returns
        -------
        pathlib.Path

        Raises
        ------
        NotFittedError
            Before :meth:`fit`.
        """
        self._check_fitted()
        p = Path(path)
        payload = {
            "format": CURRENT_MODEL_FORMAT,
            "format_version": CURRENT_MODEL_FORMAT_VERSION,
            "model_class": type(self).__name__,
            "params": self._params_to_plain(),
            "state": self._state(),
            "versions": _package_versions(),
        }
        with atomic_open(p, "wb") as fh:
            torch.save(payload, fh)
        return p

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> CurrentModel:
        """Read a model written by :meth:`save` (the class must match, or be this base).

        Raises
        ------
        FileFormatError
            Missing, corrupt or foreign file; a model of another class.
        FormatVersionError
            A file of another format version.
        """
        data = _read_checkpoint(path)
        name = data["model_class"]
        target = CurrentModel._registry.get(name)
        if target is None:
            raise FileFormatError(f"{str(path)!r} holds an unknown model class {name!r}; known: {sorted(CurrentModel._registry)!r}")
        if cls is not CurrentModel and target is not cls:
            raise FileFormatError(f"{str(path)!r} holds a {name}, not a {cls.__name__}")
        try:
            model = target(**target._params_from_plain(data["params"]))
            model._load_state(data["state"])
        except (KeyError, TypeError, ValueError, RuntimeError) as exc:
            raise FileFormatError(f"{str(path)!r}: the {name} state is incomplete or inconsistent: {exc}") from exc
        return model


def load_current_model(path: str | os.PathLike[str]) -> CurrentModel:
    """Read any current model written by :meth:`CurrentModel.save`.

    Raises
    ------
    FileFormatError, FormatVersionError
        As :meth:`CurrentModel.load`.
    """
    return CurrentModel.load(path)


# ============================================================================= model
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
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
                raise InvalidParameterError(f"CurrentNetConfig.{name} must be an int >= {low}, got {v!r}")
        hs = tuple(self.hidden_sizes)
        if not hs or any(isinstance(h, bool) or not isinstance(h, (int, np.integer)) or h < 1 for h in hs):
            raise InvalidParameterError(f"CurrentNetConfig.hidden_sizes must be a non-empty tuple of ints >= 1, got {self.hidden_sizes!r}")
        object.__setattr__(self, "hidden_sizes", tuple(int(h) for h in hs))
        if not (isinstance(self.dropout, (int, float)) and 0.0 <= self.dropout < 1.0):
            raise InvalidParameterError(f"CurrentNetConfig.dropout must be in [0, 1), got {self.dropout!r}")


class CurrentNet(nn.Module):
    """MLP from window features (+ run-level features) to the currents of the window.

    ``forward(x_window, run_table, run_index)``: ``x_window`` (B, n_window_inputs),
    ``run_table`` (R, n_run_inputs) — one row per run — and ``run_index`` (B,) long, the
    run of each sample. The first hidden layer is
    ``W_w x_window + (W_r run_table)[run_index] + b``, i.e. one dense layer over the
    concatenation ``[run features, window features]`` computed without repeating the run
    features per sample. ReLU activations, optional dropout, linear output.
    """

    def __init__(self, config: CurrentNetConfig) -> None:
        super().__init__()
        self.config = config
        h0 = config.hidden_sizes[0]
        self.window_in = nn.Linear(config.n_window_inputs, h0)
        self.run_in = nn.Linear(config.n_run_inputs, h0, bias=False) if config.n_run_inputs else None
        layers: list[nn.Module] = [nn.ReLU()]
        if config.dropout:
            layers.append(nn.Dropout(config.dropout))
        for a, b in zip(config.hidden_sizes[:-1], config.hidden_sizes[1:]):
            layers += [nn.Linear(a, b), nn.ReLU()]
            if config.dropout:
                layers.append(nn.Dropout(config.dropout))
        layers.append(nn.Linear(config.hidden_sizes[-1], config.n_outputs))
        self.body = nn.Sequential(*layers)

    @property
    def n_inputs(self) -> int:
        """Inputs of the equivalent single first layer (run + window features)."""
        return self.config.n_run_inputs + self.config.n_window_inputs

    def forward(self, x_window: torch.Tensor, run_table: torch.Tensor, run_index: torch.Tensor) -> torch.Tensor:
        h = self.window_in(x_window)
        if self.run_in is not None:
            h = h + self.run_in(run_table)[run_index]
        return self.body(h)


# =========================================================================== dataset
class WindowDataset:
    """Windows of one or more runs: window features, run features, targets.

    Parameters
    ----------
    x_window : array_like, shape (n, F)
        Normalised window features.
    run_table : array_like, shape (R, G)
        Normalised run-level features, one row per run (G may be 0).
    run_index : array_like of int, shape (n,)
        Run of each window (row of ``run_table``).
    start : array_like of int, shape (n,)
        First sample of each window within its run.
    y : array_like, shape (n, O), optional
        Normalised targets (absent at prediction time).
    spec : WindowSpec
        Window length and stride (samples and seconds).
    """

    def __init__(self, x_window: Any, run_table: Any, run_index: Any, start: Any, spec: WindowSpec,
                 y: Any = None) -> None:
        self.x_window = torch.as_tensor(np.asarray(x_window, dtype=np.float32))
        self.run_table = torch.as_tensor(np.asarray(run_table, dtype=np.float32))
        self.run_index = torch.as_tensor(np.asarray(run_index, dtype=np.int64))
        self.start = np.asarray(start, dtype=np.int64)
        self.y = None if y is None else torch.as_tensor(np.asarray(y, dtype=np.float32))
        self.spec = spec
        n = self.x_window.shape[0]
        if self.run_index.shape != (n,) or self.start.shape != (n,) or (self.y is not None and self.y.shape[0] != n):
            raise InvalidParameterError(
                f"WindowDataset arrays disagree in length: x_window {n}, run_index {tuple(self.run_index.shape)!r}, "
                f"start {self.start.shape!r}, y {None if self.y is None else tuple(self.y.shape)!r}"
            )

    def __len__(self) -> int:
        return int(self.x_window.shape[0])

    def inputs(self, index: torch.Tensor | slice) -> tuple[torch.Tensor, ...]:
        """The model inputs of the windows at ``index``."""
        return self.x_window[index], self.run_table, self.run_index[index]

    def targets(self, index: torch.Tensor | slice) -> torch.Tensor:
        """The targets of the windows at ``index``."""
        if self.y is None:
            raise DataError("this WindowDataset has no targets")
        return self.y[index]

    def subset(self, mask: np.ndarray) -> WindowDataset:
        """The windows where ``mask`` is true (run table kept whole)."""
        idx = torch.as_tensor(np.flatnonzero(mask))
        return WindowDataset(
            self.x_window[idx].numpy(), self.run_table.numpy(), self.run_index[idx].numpy(), self.start[mask],
            self.spec, None if self.y is None else self.y[idx].numpy(),
        )

    def split_tail(self, fraction: float) -> tuple[WindowDataset, WindowDataset | None]:
        """Hold out the last ``fraction`` of every run as validation.

        Training windows that overlap a validation window are dropped, so no sample is
        seen by both. ``fraction == 0`` returns ``(self, None)``.
        """
        if fraction == 0:
            return self, None
        runs = self.run_index.numpy()
        val = np.zeros(len(self), dtype=bool)
        train = np.zeros(len(self), dtype=bool)
        for r in np.unique(runs):
            rows = np.flatnonzero(runs == r)
            first = self.start[rows]
            end = int(first.max()) + self.spec.length_samples
            cut = int(round(end * (1.0 - fraction)))
            v = first >= cut
            if not v.any() or v.all():
                train[rows] = True
                continue
            val[rows[v]] = True
            train[rows[first + self.spec.length_samples <= int(first[v].min())]] = True
        if not val.any():
            return self, None
        return self.subset(train), self.subset(val)


# ========================================================================== training
_LOSSES = ("mse", "huber")


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
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise InvalidParameterError(f"TrainConfig.{name} must be an int >= 1, got {v!r}")
        if not (isinstance(self.learning_rate, (int, float)) and math.isfinite(self.learning_rate) and self.learning_rate > 0):
            raise InvalidParameterError(f"TrainConfig.learning_rate must be a finite number > 0, got {self.learning_rate!r}")
        if not (isinstance(self.weight_decay, (int, float)) and math.isfinite(self.weight_decay) and self.weight_decay >= 0):
            raise InvalidParameterError(f"TrainConfig.weight_decay must be a finite number >= 0, got {self.weight_decay!r}")
        if self.patience is not None and (isinstance(self.patience, bool) or not isinstance(self.patience, (int, np.integer)) or self.patience < 1):
            raise InvalidParameterError(f"TrainConfig.patience must be an int >= 1 or None, got {self.patience!r}")
        if self.loss not in _LOSSES:
            raise UnknownNameError(f"TrainConfig.loss must be one of {_LOSSES!r}, got {self.loss!r}")


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
        return cls(tuple(d["train_loss"]), tuple(d["validation_loss"]), int(d["best_epoch"]),
                   bool(d["stopped_early"]), float(d["duration_s"]))


def _loss_fn(name: str) -> nn.Module:
    return nn.MSELoss() if name == "mse" else nn.HuberLoss(delta=0.1)


def train_network(
    net: nn.Module,
    train: WindowDataset,
    validation: WindowDataset | None,
    config: TrainConfig,
    seed: int,
    progress: bool = False,
    description: str = "training",
) -> TrainingHistory:
    """Train any module that maps ``dataset.inputs(idx)`` to ``dataset.targets(idx)``.

    AdamW on shuffled mini-batches (shuffled by a ``torch.Generator`` seeded with ``seed``;
    dropout draws from torch's global generator, which is seeded with ``seed`` too). The
    loop knows nothing about the model beyond ``net(*inputs)``. Uses the thread count
    torch is set to (``torch.set_num_threads``).

    Parameters
    ----------
    net : torch.nn.Module
    train : WindowDataset
    validation : WindowDataset or None
        Scored after every epoch; required for early stopping.
    config : TrainConfig
    seed : int
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
        Early stopping requested without validation windows; empty training set.
    """
    if len(train) == 0:
        raise InvalidParameterError("train_network needs at least one training window")
    if config.patience is not None and (validation is None or len(validation) == 0):
        raise InvalidParameterError("early stopping (patience) needs validation windows; got none")
    from tqdm.auto import tqdm

    torch.manual_seed(seed)
    gen = torch.Generator().manual_seed(seed)
    opt = torch.optim.AdamW(net.parameters(), lr=config.learning_rate, weight_decay=config.weight_decay)
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


# ========================================================================= estimator
_RUN_FEATURES = ("bins", "bands", "none")
_RESAMPLE = ("linear", "previous")


@dataclass(frozen=True)
class EstimatorConfig:
    """Everything that defines a :class:`VibrationCurrentEstimator`: features, network, training.

    The field defaults are the ``"default"`` preset; ``ESTIMATOR_PRESETS["paper"]`` sets
    every field the paper fixes.

    Parameters
    ----------
    name : str
        Label (presets use their key).
    rate_hz : float or None
        Rate (Hz) of the uniform grid the drive stream is resampled onto; ``None`` takes
        the median drive rate of the training logs (no invented samples).
    resample_method : {"linear", "previous"}
        Interpolation of :meth:`InteractionLog.resample`.
    window_s : float
        ``t_interval``: window length (s); samples = ``round(window_s * rate)``, >= 1.
    train_stride_s, predict_stride_s : float or None
        Stride between windows when training / predicting (s, rounded to >= 1 sample);
        ``None`` = ``window_s`` (tiling windows, as in the paper). Overlapping predicted
        windows are averaged per sample.
    absolute_inputs : bool
        Feed |v| and |omega| (the paper) instead of signed values (which tell the left
        side from the right in turns).
    absolute_currents : bool
        Learn |current| (the paper) instead of the signed current.
    run_features : {"bins", "bands", "none"}
        Whole-run vibration features: the paper's FFT spectrum on ``n_spectrum_bins`` bins
        (``"bins"``), the log10 band RMS averaged over the run (``"bands"``), or nothing;
        both min-max scaled by one range over all bins/bands of the training runs.
    n_spectrum_bins : int
        Bins of the ``"bins"`` spectrum (paper: 8000).
    spectrum_scaling : {"amplitude", "density"}
        Scaling of the ``"bins"`` spectrum (see :func:`~energy.features.whole_run_spectrum`).
    max_frequency_hz : float
        Top of every spectrum (Hz; paper: 50).
    local_spectrum : bool
        Add each window's local spectrum: log10 band RMS of the vertical acceleration over
        ``spectrum_span_s`` seconds centred on the window.
    spectrum_span_s : float
        Segment length of local spectra and of the ``"bands"`` Welch average (s).
    n_bands : int
        Log-spaced bands between ``min_band_hz`` and ``max_frequency_hz``.
    min_band_hz : float
        Lowest band edge (Hz).
    hidden_sizes : tuple of int
        Hidden layer widths (paper: 3 x 100).
    dropout : float
        Dropout after each hidden layer.
    n_members : int
        Ensemble size; members differ in seed, predictions are averaged.
    max_epochs, batch_size, learning_rate, weight_decay, patience, loss
        Training settings (see :class:`TrainConfig`).
    validation_fraction : float
        Tail fraction of every training run held out for validation, in [0, 0.5]; > 0
        when ``patience`` is set. Without early stopping (``patience=None``) the tail is
        only scored (``TrainingHistory.validation_loss``), never trained on: 0 trains on
        every window (the ``"paper"`` preset).
    clip_output : bool
        Clip predictions to the per-side range of the training currents (stored with the
        model as ``current_range_a_``).
    physics_prior : str or None
        Robot preset name (:data:`~energy.params.ROBOT_PRESETS`) of a physics prior: a
        :class:`~energy.baselines.PhysicsCurrentModel` is fitted to the training logs
        first (rolling resistance, lateral friction, idle current) and the networks learn
        the residual current on top of it. ``None`` learns the currents directly (the
        paper).
    """

    name: str = "custom"
    rate_hz: float | None = None
    resample_method: str = "linear"
    window_s: float = 1.0
    train_stride_s: float | None = 0.1
    predict_stride_s: float | None = 0.1
    absolute_inputs: bool = False
    absolute_currents: bool = False
    run_features: str = "none"
    n_spectrum_bins: int = 8000
    spectrum_scaling: str = "amplitude"
    max_frequency_hz: float = 50.0
    local_spectrum: bool = True
    spectrum_span_s: float = 1.0
    n_bands: int = 12
    min_band_hz: float = 1.0
    hidden_sizes: tuple[int, ...] = (64, 64)
    dropout: float = 0.1
    n_members: int = 5
    max_epochs: int = 60
    batch_size: int = 256
    learning_rate: float = 2e-3
    weight_decay: float = 1e-3
    patience: int | None = 10
    loss: str = "mse"
    validation_fraction: float = 0.15
    clip_output: bool = True
    physics_prior: str | None = "husky"

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InvalidParameterError(f"EstimatorConfig.name must be a non-empty str, got {self.name!r}")
        if self.rate_hz is not None:
            _pos("rate_hz", self.rate_hz)
        if self.resample_method not in _RESAMPLE:
            raise UnknownNameError(f"EstimatorConfig.resample_method must be one of {_RESAMPLE!r}, got {self.resample_method!r}")
        for name in ("window_s", "max_frequency_hz", "spectrum_span_s", "min_band_hz"):
            _pos(name, getattr(self, name))
        for name in ("train_stride_s", "predict_stride_s"):
            if getattr(self, name) is not None:
                _pos(name, getattr(self, name))
        for name in ("absolute_inputs", "absolute_currents", "local_spectrum", "clip_output"):
            if not isinstance(getattr(self, name), bool):
                raise InvalidParameterError(f"EstimatorConfig.{name} must be a bool, got {getattr(self, name)!r}")
        if self.run_features not in _RUN_FEATURES:
            raise UnknownNameError(f"EstimatorConfig.run_features must be one of {_RUN_FEATURES!r}, got {self.run_features!r}")
        if self.spectrum_scaling not in SPECTRUM_SCALINGS:
            raise UnknownNameError(f"EstimatorConfig.spectrum_scaling must be one of {SPECTRUM_SCALINGS!r}, got {self.spectrum_scaling!r}")
        for name in ("n_spectrum_bins", "n_bands", "n_members"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise InvalidParameterError(f"EstimatorConfig.{name} must be an int >= 1, got {v!r}")
        if not self.min_band_hz < self.max_frequency_hz:
            raise InvalidParameterError(
                f"EstimatorConfig.min_band_hz must be < max_frequency_hz={self.max_frequency_hz!r}, got {self.min_band_hz!r}"
            )
        if not (isinstance(self.validation_fraction, (int, float)) and 0.0 <= self.validation_fraction <= 0.5):
            raise InvalidParameterError(f"EstimatorConfig.validation_fraction must be in [0, 0.5], got {self.validation_fraction!r}")
        if self.physics_prior is not None and self.physics_prior not in ROBOT_PRESETS:
            raise UnknownNameError(
                f"EstimatorConfig.physics_prior must be None or a robot preset from {sorted(ROBOT_PRESETS)!r}, "
                f"got {self.physics_prior!r}"
            )
        if self.physics_prior is not None and self.absolute_currents:
            raise InvalidParameterError(
                "EstimatorConfig.absolute_currents cannot be combined with a physics_prior (the networks "
                "learn a signed residual); set physics_prior=None or absolute_currents=False"
            )
        if self.patience is not None and self.validation_fraction == 0:
            raise InvalidParameterError("EstimatorConfig.patience (early stopping) needs validation_fraction > 0")
        object.__setattr__(self, "hidden_sizes", tuple(self.hidden_sizes))
        self.net_config(1, 0, 1)  # validates hidden_sizes and dropout
        self.train_config()  # validates the training settings

    def net_config(self, n_window_inputs: int, n_run_inputs: int, n_outputs: int) -> CurrentNetConfig:
        """The :class:`CurrentNetConfig` for given input/output sizes."""
        return CurrentNetConfig(n_window_inputs, n_run_inputs, n_outputs, self.hidden_sizes, self.dropout)

    def train_config(self) -> TrainConfig:
        """The :class:`TrainConfig` part."""
        return TrainConfig(self.max_epochs, self.batch_size, self.learning_rate, self.weight_decay,
                           self.patience, self.loss)

    def replace(self, **changes: Any) -> EstimatorConfig:
        """A copy with some fields changed (validated)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """Plain-types form (for checkpoints and JSON)."""
        d = dataclasses.asdict(self)
        d["hidden_sizes"] = list(self.hidden_sizes)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> EstimatorConfig:
        """Rebuild from :meth:`to_dict` output (unknown keys raise InvalidParameterError)."""
        known = {f.name for f in dataclasses.fields(cls)}
        extra = set(d) - known
        if extra:
            raise InvalidParameterError(f"unknown EstimatorConfig field(s) {sorted(extra)!r}")
        d = dict(d)
        if "hidden_sizes" in d:
            d["hidden_sizes"] = tuple(d["hidden_sizes"])
        return cls(**d)


def _pos(name: str, value: Any) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise InvalidParameterError(f"EstimatorConfig.{name} must be a finite number > 0, got {value!r}")


#: Named configurations: ``"paper"`` reproduces the source network (8000-bin whole-run
#: spectrum + 10 |v| + 10 |omega| at 100 Hz -> 3 x 100 ReLU -> 10 + 10 currents, trained
#: on every window of the training runs; the paper does not state its optimiser, epochs or
#: batch size: Adam, 50 epochs, batch 256 here); ``"default"`` is the improved estimator
#: (see the module docstring).
ESTIMATOR_PRESETS: dict[str, EstimatorConfig] = {
    "paper": EstimatorConfig(
        name="paper", rate_hz=100.0, resample_method="linear", window_s=DEFAULT_T_INTERVAL_S,
        train_stride_s=None, predict_stride_s=None, absolute_inputs=True, absolute_currents=True,
        run_features="bins", n_spectrum_bins=8000, spectrum_scaling="amplitude",
        local_spectrum=False, hidden_sizes=(100, 100, 100), dropout=0.0, n_members=1,
        max_epochs=50, batch_size=256, learning_rate=1e-3, weight_decay=0.0, patience=None,
        loss="mse", validation_fraction=0.0, clip_output=False, physics_prior=None,
    ),
    "default": EstimatorConfig(name="default"),
}


def estimator_preset(name: str) -> EstimatorConfig:
    """The :class:`EstimatorConfig` preset called ``name``.

    Raises
    ------
    UnknownNameError
        ``name`` is not a key of :data:`ESTIMATOR_PRESETS`.
    """
    try:
        return ESTIMATOR_PRESETS[name]
    except (KeyError, TypeError):
        raise UnknownNameError(f"estimator preset {name!r} is unknown; expected one of {sorted(ESTIMATOR_PRESETS)!r}") from None


def _source_normaliser(source_range: tuple[float, float], absolute: bool) -> MinMaxNormaliser:
    """The source range for absolute values; mirrored (-high..high) for signed values."""
    if absolute:
        return MinMaxNormaliser(*source_range, absolute=True)
    return MinMaxNormaliser(-source_range[1], source_range[1], absolute=False)


def _member_seed(seed: int, member: int) -> int:
    return int(np.random.SeedSequence([int(seed), int(member)]).generate_state(1)[0])


class VibrationCurrentEstimator(CurrentModel):
    """Drive currents from velocity commands and the vertical vibration of the ground.

    Parameters
    ----------
    config : str or EstimatorConfig
        A preset name (``"default"``, ``"paper"``) or a configuration; change presets with
        ``estimator_preset("default").replace(n_members=3)``.
    seed : int
        Seed of weight initialisation, shuffling and dropout (members use derived seeds).
        The same seed, data and thread count give the same model.
    progress : bool
        Show a tqdm progress bar with the training and validation loss.
    n_threads : int or None
        ``torch.set_num_threads`` while fitting and predicting (restored after);
        ``None`` leaves torch's setting alone.

    Attributes
    ----------
    config_ : EstimatorConfig
        The resolved configuration.
    rate_hz_ : float
        Rate of the uniform grid the model works on (Hz).
    window_ : WindowSpec
        Training windows (length and stride in samples and seconds).
    band_edges_hz_ : numpy.ndarray or None
        Edges of the spectrum bands.
    normalisers_ : dict of str to MinMaxNormaliser
        ``"v"``, ``"omega"``, ``"current"`` (source ranges) and the fitted spectrum ranges
        (``"run"``, ``"local"`` when used).
    current_range_a_ : numpy.ndarray, shape (2, 2)
        ``[[min_left, min_right], [max_left, max_right]]`` of the training currents.
    networks_ : list of CurrentNet
        The ensemble members.
    history_ : tuple of TrainingHistory
        One per member.
    n_train_windows_ : int
    physics_ : PhysicsCurrentModel or None
        The fitted physics prior (``config.physics_prior``), or None.

    Examples
    --------
    Usage (needs data or fitted models, so not run as a doctest)::

        est = VibrationCurrentEstimator("default", seed=0)
        est.fit(train_logs).predict(test_log)
    """

    _param_names = ("config", "seed", "progress", "n_threads")

    def __init__(self, config: str | EstimatorConfig = "default", seed: int = 0, progress: bool = False,
                 n_threads: int | None = None) -> None:
        self.config = config
        self.seed = seed
        self.progress = progress
        self.n_threads = n_threads

    # -------------------------------------------------------------- validation
    def _resolved_config(self) -> EstimatorConfig:
        if isinstance(self.config, EstimatorConfig):
            return self.config
        if isinstance(self.config, str):
            return estimator_preset(self.config)
        raise InvalidParameterError(f"config must be a preset name or an EstimatorConfig, got {self.config!r:.80}")

    def _check_params(self) -> EstimatorConfig:
        cfg = self._resolved_config()
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise InvalidParameterError(f"seed must be an int >= 0, got {self.seed!r}")
        if not isinstance(self.progress, bool):
            raise InvalidParameterError(f"progress must be a bool, got {self.progress!r}")
        if self.n_threads is not None and (isinstance(self.n_threads, bool) or not isinstance(self.n_threads, (int, np.integer)) or self.n_threads < 1):
            raise InvalidParameterError(f"n_threads must be an int >= 1 or None, got {self.n_threads!r}")
        return cfg

    # ---------------------------------------------------------------- features
    def _grid_log(self, log: InteractionLog, rate_hz: float, method: str) -> InteractionLog:
        return log.resample(rate_hz, method)

    def _run_vector(self, log: InteractionLog, cfg: EstimatorConfig) -> np.ndarray:
        if cfg.run_features == "bins":
            return whole_run_spectrum(log.accel_time_s, log.accel_z_mps2, cfg.n_spectrum_bins,
                                      cfg.max_frequency_hz, cfg.spectrum_scaling)[1]
        if cfg.run_features == "bands":
            rms = whole_run_band_spectrum(log.accel_time_s, log.accel_z_mps2, cfg.spectrum_span_s, self.band_edges_hz_)
            return np.log10(np.maximum(rms, _LOG_FLOOR_MPS2))
        return np.zeros(0)

    def _window_features(self, grid: InteractionLog, spec: WindowSpec, starts: np.ndarray,
                         cfg: EstimatorConfig) -> tuple[np.ndarray, np.ndarray | None]:
        """Raw (unnormalised-spectrum) window features and local spectra of one gridded run."""
        nv, nw = self.normalisers_["v"], self.normalisers_["omega"]
        v = sliding_windows(nv.transform(grid.v_mps), spec, starts)
        w = sliding_windows(nw.transform(grid.omega_radps), spec, starts)
        motion = np.concatenate([v, w], axis=1)
        local = None
        if cfg.local_spectrum:
            t = grid.time_s
            centre = 0.5 * (t[starts] + t[starts + spec.length_samples - 1])
            rms = band_rms_spectra(grid.accel_time_s, grid.accel_z_mps2, centre, cfg.spectrum_span_s, self.band_edges_hz_)
            local = np.log10(np.maximum(rms, _LOG_FLOOR_MPS2))
        return motion, local

    def _targets(self, grid: InteractionLog, spec: WindowSpec, starts: np.ndarray) -> np.ndarray:
        cur = self.normalisers_["current"].transform(_currents(grid))  # (N, 2)
        win = sliding_windows(cur, spec, starts)  # (n, W, 2)
        return np.concatenate([win[:, :, 0], win[:, :, 1]], axis=1)  # left window, right window

    def _dataset(self, grids: list[InteractionLog], spec: WindowSpec, cfg: EstimatorConfig,
                 with_targets: bool) -> WindowDataset:
        xs, idx, starts_all, ys, locals_, runs = [], [], [], [], [], []
        for r, g in enumerate(grids):
            starts = window_starts(len(g), spec)
            motion, local = self._window_features(g, spec, starts, cfg)
            xs.append(motion)
            if local is not None:
                locals_.append(local)
            idx.append(np.full(starts.size, r))
            starts_all.append(starts)
            runs.append(self._run_vector(g, cfg))
            if with_targets:
                ys.append(self._targets(g, spec, starts))
        x = np.concatenate(xs)
        if locals_:
            if "local" not in self.normalisers_:
                self.normalisers_["local"] = MinMaxNormaliser.from_data(np.concatenate(locals_), per_column=True)
            x = np.concatenate([x, self.normalisers_["local"].transform(np.concatenate(locals_))], axis=1)
        table = np.stack(runs)
        if table.shape[1]:
            if "run" not in self.normalisers_:
                # one range over all bins/bands: per-column ranges over a handful of runs
                # would blow run-to-run noise up to the full [0, 1] span
                self.normalisers_["run"] = MinMaxNormaliser.from_data(table, per_column=False)
            table = self.normalisers_["run"].transform(table)
        y = np.concatenate(ys) if with_targets else None
        return WindowDataset(x, table, np.concatenate(idx), np.concatenate(starts_all), spec, y)

    # ------------------------------------------------------------------- fit
    def _fit(self, logs: list[InteractionLog]) -> None:
        cfg = self._check_params()
        with _threads(self.n_threads):
            cur = np.concatenate([_currents(lg) for lg in logs])
            if cfg.absolute_currents:
                cur = np.abs(cur)
            self.current_range_a_ = np.stack([cur.min(axis=0), cur.max(axis=0)])
            self.physics_ = None
            if cfg.physics_prior is not None:
                from .baselines import (
                    PhysicsCurrentModel,  # baselines import this module
                )

                self.physics_ = PhysicsCurrentModel(robot=cfg.physics_prior).fit(logs)
                logs = [self._residual_log(lg) for lg in logs]
            rate = cfg.rate_hz if cfg.rate_hz is not None else float(np.median([lg.drive_rate_hz for lg in logs]))
            grids = [self._grid_log(lg, rate, cfg.resample_method) for lg in logs]
            spec = WindowSpec.from_seconds(cfg.window_s, rate, cfg.train_stride_s)
            self.config_ = cfg
            self.rate_hz_ = rate
            self.window_ = spec
            self.band_edges_hz_ = None
            if cfg.local_spectrum or cfg.run_features == "bands":
                acc_rate = float(np.median([g.accel_rate_hz for g in grids]))
                n_fft = int(round(cfg.spectrum_span_s * acc_rate))
                self.band_edges_hz_ = log_band_edges_hz(cfg.n_bands, cfg.min_band_hz, cfg.max_frequency_hz, acc_rate / n_fft)
            self.normalisers_ = {
                "v": _source_normaliser(SOURCE_SPEED_RANGE_MPS, cfg.absolute_inputs),
                "omega": _source_normaliser(SOURCE_OMEGA_RANGE_RADPS, cfg.absolute_inputs),
                "current": MinMaxNormaliser(*SOURCE_CURRENT_RANGE_A, absolute=cfg.absolute_currents),
            }
            data = self._dataset(grids, spec, cfg, with_targets=True)
            train, val = data.split_tail(cfg.validation_fraction)
            if cfg.patience is not None and val is None:
                raise DataError(
                    f"the training logs are too short for a {cfg.validation_fraction:g} validation tail of "
                    f"{spec.length_s:.3g} s windows; give longer logs or set patience=None"
                )
            net_cfg = cfg.net_config(data.x_window.shape[1], data.run_table.shape[1], data.y.shape[1])
            networks, histories = [], []
            for m in range(cfg.n_members):
                s = _member_seed(self.seed, m)
                torch.manual_seed(s)
                net = CurrentNet(net_cfg)
                histories.append(train_network(net, train, val, cfg.train_config(), s, self.progress,
                                               f"{cfg.name} member {m + 1}/{cfg.n_members}"))
                networks.append(net)
            self.networks_ = networks
            self.history_ = tuple(histories)
            self.n_train_windows_ = len(train)

    def _residual_log(self, log: InteractionLog) -> InteractionLog:
        prior = self.physics_.predict(log)
        return dataclasses.replace(log, current_left_a=log.current_left_a - prior[:, 0],
                                   current_right_a=log.current_right_a - prior[:, 1])

    # --------------------------------------------------------------- predict
    def _predict_grid(self, grid: InteractionLog) -> np.ndarray:
        cfg = self.config_
        spec = WindowSpec.from_seconds(cfg.window_s, self.rate_hz_, cfg.predict_stride_s)
        data = self._dataset([grid], spec, cfg, with_targets=False)
        with torch.no_grad():
            outs = [net(*data.inputs(slice(None))).numpy().astype(np.float64) for net in self.networks_]
        y = self.normalisers_["current"].inverse_transform(np.mean(outs, axis=0))  # (n, 2W)
        w = spec.length_samples
        per_window = np.stack([y[:, :w], y[:, w:]], axis=2)  # (n, W, 2)
        rows = (data.start[:, None] + np.arange(w)[None, :]).reshape(-1)
        total = np.zeros((len(grid), 2))
        count = np.zeros(len(grid))
        np.add.at(total, rows, per_window.reshape(-1, 2))
        np.add.at(count, rows, 1.0)
        return total / count[:, None]

    def _predict(self, log: InteractionLog) -> np.ndarray:
        with _threads(self.n_threads):
            grid = self._grid_log(log, self.rate_hz_, self.config_.resample_method)
            pred = self._predict_grid(grid)
        # back onto the log's own timestamps; drive samples outside the overlap of the
        # drive and acceleration streams take the nearest grid value (np.interp holds ends)
        out = np.column_stack([np.interp(log.time_s, grid.time_s, pred[:, k]) for k in range(2)])
        if self.physics_ is not None:
            out = out + self.physics_.predict(log)
        if self.config_.clip_output:
            out = np.clip(out, self.current_range_a_[0], self.current_range_a_[1])
        return out

    def predict(self, log: InteractionLog) -> np.ndarray:
        """Predicted drive currents at the log's drive timestamps.

        The drive stream is resampled onto the model's uniform grid (``rate_hz_``) over the
        overlap of the drive and acceleration streams, predicted there window by window
        (overlapping windows averaged per sample) and interpolated linearly back onto
        ``log.time_s``. Drive samples outside that grid — before the acceleration stream
        starts, after it ends, or after the last grid time — take the nearest grid
        prediction (the ends are held, not extrapolated). The physics prior, when
        configured, is then added at ``log.time_s``, and ``clip_output`` clips the result
        to ``current_range_a_``.

        Parameters, returns and errors as :meth:`CurrentModel.predict`; the ``DataError``
        here means the streams do not overlap, or overlap for less than one window.
        """
        return super().predict(log)

    # ------------------------------------------------------------ persistence
    def _params_to_plain(self) -> dict[str, Any]:
        p = self.get_params()
        p["config"] = self.config if isinstance(self.config, str) else {"__config__": self.config.to_dict()}
        return p

    @classmethod
    def _params_from_plain(cls, params: dict[str, Any]) -> dict[str, Any]:
        p = dict(params)
        if isinstance(p.get("config"), dict):
            p["config"] = EstimatorConfig.from_dict(p["config"]["__config__"])
        return p

    def _state(self) -> dict[str, Any]:
        return {
            "config": self.config_.to_dict(),
            "rate_hz": self.rate_hz_,
            "window": {"length_samples": self.window_.length_samples, "stride_samples": self.window_.stride_samples,
                       "rate_hz": self.window_.rate_hz},
            "band_edges_hz": None if self.band_edges_hz_ is None else torch.as_tensor(self.band_edges_hz_),
            "normalisers": {k: v.to_dict() for k, v in self.normalisers_.items()},
            "current_range_a": torch.as_tensor(self.current_range_a_),
            "net_config": dataclasses.asdict(self.networks_[0].config) | {"hidden_sizes": list(self.networks_[0].config.hidden_sizes)},
            "weights": [net.state_dict() for net in self.networks_],
            "history": [h.to_dict() for h in self.history_],
            "n_train_windows": self.n_train_windows_,
            "physics": None if self.physics_ is None else {"params": self.physics_._params_to_plain(),
                                                           "state": self.physics_._state()},
        }

    def _load_state(self, state: dict[str, Any]) -> None:
        self.config_ = EstimatorConfig.from_dict(state["config"])
        self.rate_hz_ = float(state["rate_hz"])
        self.window_ = WindowSpec(**state["window"])
        edges = state["band_edges_hz"]
        self.band_edges_hz_ = None if edges is None else edges.numpy().astype(np.float64)
        self.normalisers_ = {k: MinMaxNormaliser.from_dict(v) for k, v in state["normalisers"].items()}
        self.current_range_a_ = state["current_range_a"].numpy().astype(np.float64)
        nc = dict(state["net_config"])
        nc["hidden_sizes"] = tuple(nc["hidden_sizes"])
        net_cfg = CurrentNetConfig(**nc)
        nets = []
        for weights in state["weights"]:
            net = CurrentNet(net_cfg)
            net.load_state_dict(weights)
            net.eval()
            nets.append(net)
        if not nets:
            raise ValueError("no ensemble member weights")
        self.networks_ = nets
        self.history_ = tuple(TrainingHistory.from_dict(h) for h in state["history"])
        self.n_train_windows_ = int(state["n_train_windows"])
        self.physics_ = None
        if state["physics"] is not None:
            from .baselines import PhysicsCurrentModel  # baselines import this module

            phys = PhysicsCurrentModel(**PhysicsCurrentModel._params_from_plain(state["physics"]["params"]))
            phys._load_state(state["physics"]["state"])
            self.physics_ = phys


class _threads:
    """Context manager: ``torch.set_num_threads(n)`` inside, previous value restored after."""

    def __init__(self, n: int | None) -> None:
        self.n = n
        self.old: int | None = None

    def __enter__(self) -> None:
        if self.n is not None:
            self.old = torch.get_num_threads()
            torch.set_num_threads(int(self.n))

    def __exit__(self, *exc: Any) -> None:
        if self.old is not None:
            torch.set_num_threads(self.old)
