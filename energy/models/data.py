"""The windowed dataset of the estimator: window features, run features and targets of one or more runs."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from terrawatt_base.errors import DataError, InvalidParameterError

from ..features import WindowSpec

__all__ = ["WindowDataset"]


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
