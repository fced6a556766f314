"""Which model serves which cell: the cell map, its versioned history and exact rollback."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np

from terrawatt_base.checks import check_int, readonly
from terrawatt_base.errors import InvalidParameterError

from .cells import unflat
from .records import PRIOR_MODEL_ID, RegistryVersion

__all__ = ["CellAssignment"]


class CellAssignment:
    """The model id of every cell of a grid, changed only through numbered versions.

    Every cell starts on the prior (id :data:`~planner.registry.records.PRIOR_MODEL_ID`).
    :meth:`apply` gives a set of cells a model as a new :class:`RegistryVersion` that
    remembers each cell's previous id; :meth:`rollback` pops versions and restores those
    ids, so any earlier state comes back exactly. Version numbers only grow, even after a
    rollback. This class knows nothing of evidence: both methods return the flat indices of
    the cells whose model changed, for the caller to reset what it keeps about them.

    Examples
    --------
    >>> import numpy as np
    >>> cells = CellAssignment((2, 3))
    >>> version, changed = cells.apply(np.array([0, 4]), 1, kind="assign", reason="sand")
    >>> version.version, changed.tolist(), cells.cell_model.tolist()
    (1, [0, 4], [[1, 0, 0], [0, 1, 0]])
    >>> undone, changed = cells.rollback()
    >>> [v.version for v in undone], int(cells.cell_model.sum()), cells.version
    ([1], 0, 0)
    """

    def __init__(self, shape: tuple[int, int]) -> None:
        self._shape = (int(shape[0]), int(shape[1]))
        self._cell_model = np.full(self._shape, PRIOR_MODEL_ID, dtype=np.int32)
        self._history: list[RegistryVersion] = []
        self._next_version = 1

    @property
    def cell_model(self) -> np.ndarray:
        """Model id of every cell (``int32``; a read-only copy)."""
        return readonly(self._cell_model)

    def model_at(self, row: int, col: int) -> int:
        """Model id of one cell (the caller checks the cell is inside the grid)."""
        return int(self._cell_model[row, col])

    def model_ids_at(self, flat: np.ndarray) -> np.ndarray:
        """Model ids of cells given by flat index."""
        return self._cell_model.reshape(-1)[flat]

    @property
    def history(self) -> list[RegistryVersion]:
        """The versions since the start, oldest first (a copy of the list)."""
        return list(self._history)

    @property
    def version(self) -> int:
        """Number of the newest version in :attr:`history`, 0 when there is none."""
        return self._history[-1].version if self._history else 0

    @property
    def next_version(self) -> int:
        """The number the next version will get."""
        return self._next_version

    def apply(
        self,
        flat: np.ndarray,
        model_id: int,
        *,
        kind: Literal["assign", "update"],
        reason: str,
        error_new: float | None = None,
        error_old: float | None = None,
    ) -> tuple[RegistryVersion, np.ndarray]:
        """Give the cells ``flat`` (sorted unique flat indices) model ``model_id`` as a new version.

        The caller has checked the cells and the model id. Returns the version and the flat
        indices of the cells whose model actually changed.
        """
        cm = self._cell_model.reshape(-1)
        previous = cm[flat].copy()
        rows, cols = unflat(self._shape, flat)
        version = RegistryVersion(
            version=self._next_version,
            kind=kind,
            model_id=model_id,
            rows=readonly(rows),
            cols=readonly(cols),
            previous_model_ids=readonly(previous.astype(np.int32)),
            cell_count=int(flat.size),
            reason=reason,
            validation_error_new=error_new,
            validation_error_old=error_old,
        )
        cm[flat] = model_id
        self._history.append(version)
        self._next_version += 1
        return version, flat[previous != model_id]

    def rollback(self, version: int | None = None) -> tuple[list[RegistryVersion], np.ndarray]:
        """Undo versions; return them (newest first) and the flat indices of the cells that changed.

        ``None`` undoes the newest version; an integer restores the state right after that
        version; ``0`` restores the initial state (all cells on the prior).

        Raises
        ------
        InvalidParameterError
            Nothing to roll back, or ``version`` is neither 0 nor a version in the history.
        """
        if not self._history:
            raise InvalidParameterError("the history is empty; there is nothing to roll back")
        if version is None:
            target = self._history[-2].version if len(self._history) > 1 else 0
        else:
            target = check_int("version", version, low=0)
            known = [v.version for v in self._history]
            if target != 0 and target not in known:
                raise InvalidParameterError(f"version must be 0 or one of {known!r}, got {version!r}")
        before = self._cell_model.copy()
        undone: list[RegistryVersion] = []
        while self._history and self._history[-1].version > target:
            v = self._history.pop()
            self._cell_model[v.rows, v.cols] = v.previous_model_ids
            undone.append(v)
        return undone, np.flatnonzero(before != self._cell_model)

    def restore(self, cell_model: np.ndarray, history: Sequence[RegistryVersion], next_version: int) -> None:
        """Set the state read from a saved registry (the store has checked it is consistent)."""
        self._cell_model[...] = np.asarray(cell_model).astype(np.int32)
        self._history = list(history)
        self._next_version = int(next_version)
