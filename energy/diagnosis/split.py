"""Calibration / held-out splits of logs: leave-runs-out folds, or contiguous blocks of each run."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from terrawatt_base.checks import check_choice, check_int, readonly
from terrawatt_base.errors import DataError, InvalidParameterError

from ..logs import InteractionLog

__all__ = ["SPLITS", "Fold", "Split", "make_split"]

#: Split kinds: whole runs held out, or contiguous blocks of every run.
SPLITS = ("runs", "blocks")


@dataclass(frozen=True, eq=False)
class Fold:
    """One fold: per log, boolean masks of the calibration and the held-out samples (never both)."""

    calibration: tuple[np.ndarray, ...]
    held_out: tuple[np.ndarray, ...]

    def __post_init__(self) -> None:
        if len(self.calibration) != len(self.held_out):
            raise InvalidParameterError("a Fold needs one calibration and one held-out mask per log")
        for k, (c, h) in enumerate(zip(self.calibration, self.held_out)):
            if c.shape != h.shape or c.dtype != bool or h.dtype != bool:
                raise InvalidParameterError(f"fold masks of log {k} must be boolean arrays of one shape")
            if np.any(c & h):
                raise InvalidParameterError(f"log {k}: a sample is both calibration and held out")
        object.__setattr__(self, "calibration", tuple(readonly(c) for c in self.calibration))
        object.__setattr__(self, "held_out", tuple(readonly(h) for h in self.held_out))

    @property
    def n_calibration(self) -> int:
        """Number of calibration samples."""
        return int(sum(int(c.sum()) for c in self.calibration))

    @property
    def n_held_out(self) -> int:
        """Number of held-out samples."""
        return int(sum(int(h.sum()) for h in self.held_out))


@dataclass(frozen=True, eq=False)
class Split:
    """Folds that hold out every sample exactly once, and the bootstrap unit of each sample.

    Attributes
    ----------
    kind : {"runs", "blocks"}
    folds : tuple of Fold
    units : tuple of numpy.ndarray
        Per log, the integer unit (a run, or a block of a run) of each sample; the
        bootstrap intervals resample these units.
    n_units : int
    """

    kind: str
    folds: tuple[Fold, ...]
    units: tuple[np.ndarray, ...]
    n_units: int

    def __post_init__(self) -> None:
        seen = [np.zeros(u.shape, dtype=np.int64) for u in self.units]
        for fold in self.folds:
            for k, h in enumerate(fold.held_out):
                seen[k] += h
        if any(np.any(s != 1) for s in seen):
            raise InvalidParameterError("a Split must hold out every sample exactly once")


def make_split(logs: Sequence[InteractionLog], kind: str = "runs", n_blocks: int = 5) -> Split:
    """Split ``logs`` into calibration and held-out parts.

    ``"runs"``: ``min(n_blocks, len(logs))`` folds of whole runs (run ``i`` in fold
    ``i % K``); ``"blocks"``: every run cut into ``n_blocks`` contiguous blocks of equal
    duration, fold ``k`` holding out block ``k`` of every run (never interleaved samples,
    which leak through autocorrelation).

    Raises
    ------
    UnknownNameError
        ``kind`` not in :data:`SPLITS`.
    InvalidParameterError
        ``n_blocks`` not an integer >= 2.
    DataError
        A split that leaves no held-out or no calibration data: ``"runs"`` with a single
        log, ``"blocks"`` with a run shorter than ``n_blocks`` samples.
    """
    check_choice("split", kind, SPLITS)
    n_blocks = check_int("n_blocks", n_blocks, low=2)
    sizes = [len(log) for log in logs]
    if kind == "runs":
        if len(logs) < 2:
            raise DataError(
                f"split='runs' needs at least 2 runs to hold one out, got {len(logs)}; use split='blocks' for a single run"
            )
        k = min(n_blocks, len(logs))
        units = tuple(np.full(n, i, dtype=np.int64) for i, n in enumerate(sizes))
        fold_of = [i % k for i in range(len(logs))]
        folds = tuple(
            Fold(tuple(np.full(n, fold_of[i] != f) for i, n in enumerate(sizes)),
                 tuple(np.full(n, fold_of[i] == f) for i, n in enumerate(sizes)))
            for f in range(k)
        )
        return Split("runs", folds, units, len(logs))
    short = [i for i, n in enumerate(sizes) if n < n_blocks]
    if short:
        raise DataError(
            f"split='blocks' with n_blocks={n_blocks} leaves no held-out data for run(s) {short!r} "
            f"({[sizes[i] for i in short]!r} samples)"
        )
    blocks = []
    for log in logs:
        t = log.time_s
        edges = np.linspace(t[0], t[-1], n_blocks + 1)
        b = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, n_blocks - 1)
        if np.unique(b).size != n_blocks:  # uneven clocks: fall back to equal sample counts
            b = (np.arange(len(log)) * n_blocks) // len(log)
        blocks.append(b)
    units = tuple(i * n_blocks + b for i, b in enumerate(blocks))
    folds = tuple(Fold(tuple(b != f for b in blocks), tuple(b == f for b in blocks)) for f in range(n_blocks))
    return Split("blocks", folds, units, len(logs) * n_blocks)
