"""CellModelRegistry: which current model serves each cell, how wrong it is there, and its updates."""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from terrain.grid import Grid
from terrain.terrain_map import TerrainMap
from terrawatt_base.checks import check_real, check_shape, check_text
from terrawatt_base.errors import GridMismatchError, InvalidParameterError

from .assignment import CellAssignment
from .cells import check_rows_cols, flat_cells
from .evidence import CellEvidence
from .records import (
    PRIOR_MODEL_ID,
    Cells,
    CurrentModelProtocol,
    MetaValue,
    ModelEntry,
    RegistryVersion,
    UpdateDecision,
)
from .store import RegistryParts, load_registry, save_registry
from .table import ModelTable

__all__ = ["CellModelRegistry"]


class CellModelRegistry:
    """Which current model serves each cell of a grid, how wrong it is there, and its updates.

    Parameters
    ----------
    shape : (int, int)
        ``(rows, cols)`` of the grid.
    prior : CurrentModelProtocol
        The model every cell starts on (id :data:`PRIOR_MODEL_ID`, i.e. 0).
    prior_name : str
        Name of the prior in the model table.
    prior_meta : mapping of str to str/int/float, optional
        Metadata of the prior.
    cell_size_m : float, optional
        Cell size, with ``origin_xy_m``: lets regions report world coordinates.
    origin_xy_m : (float, float), optional
        Lower-left corner of cell (0, 0) (same convention as :class:`~terrain.terrain_map.TerrainMap`).

    Raises
    ------
    InvalidParameterError
        Bad shape, a prior that is not a :class:`CurrentModelProtocol`, only one of
        ``cell_size_m`` / ``origin_xy_m``, non-finite georeferencing.

    Examples
    --------
    >>> import numpy as np
    >>> from planner.registry import CellModelRegistry, UpdatePolicy
    >>> class Const:
    ...     def __init__(self, current_a): self.current_a = current_a
    ...     def fit(self, *a, **k): return self
    ...     def predict(self, n): return np.full(n, self.current_a)
    >>> reg = CellModelRegistry((3, 4), Const(1.0), prior_name="physics")
    >>> reg.evidence.record([1, 1], [2, 2], measured_current_a=[2.0, 2.0],
    ...                     predicted_current_a=[1.0, 1.0], dt_s=0.1)
    >>> float(reg.evidence.relative_error()[1, 2])
    -0.5
    >>> int(reg.evidence.flagged(UpdatePolicy(threshold_pct=10.0, min_samples=2)).sum())
    1

    Notes
    -----
    A facade over the parts of :mod:`planner.registry` (model table, cell assignment,
    evidence, store); what was recorded where, the errors and the flags are its
    :attr:`evidence` (a :class:`~planner.registry.evidence.CellEvidence`).
    """

    def __init__(
        self,
        shape: tuple[int, int],
        prior: CurrentModelProtocol,
        *,
        prior_name: str = "prior",
        prior_meta: Mapping[str, MetaValue] | None = None,
        cell_size_m: float | None = None,
        origin_xy_m: tuple[float, float] | None = None,
    ) -> None:
        self._shape = check_shape("shape", shape)
        if (cell_size_m is None) != (origin_xy_m is None):
            raise InvalidParameterError(
                "cell_size_m and origin_xy_m must be given together (or neither), got "
                f"cell_size_m={cell_size_m!r}, origin_xy_m={origin_xy_m!r}"
            )
        self._grid: Grid | None = None
        if cell_size_m is not None and origin_xy_m is not None:
            self._grid = Grid(self._shape, cell_size_m, origin_xy_m)
        self._table = ModelTable()
        self._assignment = CellAssignment(self._shape)
        self._evidence = CellEvidence(self._shape, grid=self._grid, assignment=self._assignment)
        self.add_model(prior, name=prior_name, meta=prior_meta)

    @classmethod
    def _from_parts(cls, parts: RegistryParts) -> CellModelRegistry:
        reg = cls.__new__(cls)
        reg._shape = parts.shape
        reg._grid = parts.grid
        reg._table = parts.table
        reg._assignment = parts.assignment
        reg._evidence = parts.evidence
        return reg

    def _parts(self) -> RegistryParts:
        return RegistryParts(self._shape, self._grid, self._table, self._assignment, self._evidence)

    @classmethod
    def from_terrain(
        cls,
        terrain: TerrainMap,
        prior: CurrentModelProtocol,
        *,
        prior_name: str = "prior",
        prior_meta: Mapping[str, MetaValue] | None = None,
    ) -> CellModelRegistry:
        """A registry on the grid of ``terrain`` (shape, cell size and origin).

        Raises
        ------
        InvalidParameterError
            ``terrain`` is not a TerrainMap, or the prior is not a model.
        """
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__}")
        g = terrain.grid
        return cls(g.shape, prior, prior_name=prior_name, prior_meta=prior_meta,
                   cell_size_m=g.cell_size_m, origin_xy_m=g.origin_xy_m)

    # -------------------------------------------------------------------- grid
    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)`` of the grid."""
        return self._shape

    @property
    def grid(self) -> Grid | None:
        """The registry's :class:`~terrain.grid.Grid`, or ``None`` when not georeferenced."""
        return self._grid

    @property
    def cell_size_m(self) -> float | None:
        """Cell size (m), or ``None`` when not georeferenced."""
        return None if self._grid is None else self._grid.cell_size_m

    @property
    def origin_xy_m(self) -> tuple[float, float] | None:
        """Lower-left corner of cell (0, 0) (m), or ``None`` when not georeferenced."""
        return None if self._grid is None else self._grid.origin_xy_m

    def check_grid(self, terrain: TerrainMap) -> None:
        """Raise unless ``terrain`` is on this registry's grid.

        The shape must match; when the registry is georeferenced, cell size and origin too.

        Raises
        ------
        GridMismatchError
            If the grids differ.
        """
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__}")
        if terrain.shape != self._shape:
            raise GridMismatchError(f"terrain has shape {terrain.shape!r}; this registry's grid is {self._shape!r}")
        if self._grid is not None and terrain.grid != self._grid:
            raise GridMismatchError(
                f"terrain has cell size {terrain.cell_size_m!r} m and origin {terrain.origin_xy_m!r}; "
                f"this registry's grid has {self._grid.cell_size_m!r} m and {self._grid.origin_xy_m!r}"
            )

    @property
    def evidence(self) -> CellEvidence:
        """The evidence per cell: record driving samples, read the errors, flag the cells that need new data.

        A cell whose model changes (:meth:`assign`, an accepted :meth:`propose_update`,
        :meth:`rollback`) loses its evidence.
        """
        return self._evidence

    # ------------------------------------------------------------- model table
    def add_model(
        self,
        model: CurrentModelProtocol,
        *,
        name: str,
        meta: Mapping[str, MetaValue] | None = None,
    ) -> int:
        """Add a model to the table (no cell uses it until :meth:`assign`); return its id.

        Parameters
        ----------
        model : CurrentModelProtocol
            Any object with ``fit`` and ``predict`` methods.
        name : str
            Unique, non-empty name.
        meta : mapping of str to str/int/float, optional
            Free metadata (ground name, training run, ...); floats must be finite.

        Returns
        -------
        int
            The new model id (ids count up from 0, the prior).

        Raises
        ------
        InvalidParameterError
            ``model`` lacks ``fit``/``predict``; empty or duplicate name; bad metadata.
        """
        return self._table.add(model, name=name, meta=meta)

    @property
    def prior_id(self) -> int:
        """Id of the prior model (always :data:`PRIOR_MODEL_ID`)."""
        return PRIOR_MODEL_ID

    @property
    def model_ids(self) -> tuple[int, ...]:
        """Ids of every model in the table, in order."""
        return self._table.ids

    def model(self, model_id: int) -> CurrentModelProtocol:
        """The model with id ``model_id``.

        Raises
        ------
        UnknownNameError
            No such id.
        """
        return self._table.model(model_id)

    def model_record(self, model_id: int) -> ModelEntry:
        """Id, name and metadata of a model.

        Raises
        ------
        UnknownNameError
            No such id.
        """
        return self._table.record(model_id)

    def model_id(self, name: str) -> int:
        """Id of the model called ``name``.

        Raises
        ------
        UnknownNameError
            No model has that name.
        """
        return self._table.id_of(name)

    def model_ids_in_use(self) -> np.ndarray:
        """Sorted ids of the models that serve at least one cell."""
        return np.unique(self._assignment.cell_model).astype(np.int64)

    @property
    def model_id_map(self) -> np.ndarray:
        """Model id of every cell (``int32``, shape :attr:`shape`; a read-only copy)."""
        return self._assignment.cell_model

    def model_for(self, row: int, col: int) -> CurrentModelProtocol:
        """The model serving cell ``(row, col)``.

        Raises
        ------
        OutOfBoundsError
            The cell is outside the grid.
        """
        rows, cols = check_rows_cols(self._shape, row, col)
        return self._table.model(self._assignment.model_at(rows[0], cols[0]))

    # ----------------------------------------------------------- assignment
    def assign(self, cells: Cells, model_id: int, *, reason: str = "assign") -> RegistryVersion:
        """Make ``model_id`` serve ``cells``, as a new history version.

        Evidence and flag state are reset in the cells whose model actually changes (their
        evidence compared measurements with a model that no longer serves them).

        Parameters
        ----------
        cells : bool mask of the grid's shape, (rows, cols) tuple, or FlaggedRegion
            Cells to assign (duplicates are counted once).
        model_id : int
            A model in the table.
        reason : str
            Stored in the history.

        Returns
        -------
        RegistryVersion
            The version created (it can be undone with :meth:`rollback`).

        Raises
        ------
        UnknownNameError
            Unknown model id.
        InvalidParameterError
            No cells, bad cell arrays, empty reason.
        GridMismatchError
            A mask of another shape.
        OutOfBoundsError
            Cells outside the grid.
        """
        mid = self._table.check_id(model_id)
        check_text("reason", reason)
        flat = flat_cells(self._shape, cells)
        if flat.size == 0:
            raise InvalidParameterError("cells selects no cell; expected at least one cell to assign")
        version, changed = self._assignment.apply(flat, mid, kind="assign", reason=reason)
        self._evidence.clear(changed)
        return version

    def propose_update(
        self,
        region: Cells,
        new_model: CurrentModelProtocol,
        validation_error_new: float,
        validation_error_old: float,
        *,
        name: str,
        reason: str,
        meta: Mapping[str, MetaValue] | None = None,
    ) -> UpdateDecision:
        """Swap ``new_model`` into ``region`` only if it validates better than what serves it now.

        The caller fits the new model on data collected in the region and measures both
        models on the same held-back samples with the same metric (lower is better, e.g.
        the absolute relative error of integrated current); the registry decides and, when
        ``validation_error_new < validation_error_old``, adds the model, assigns it to the
        region as a new history version (kind ``"update"``) and resets the region's
        evidence and flags. A rejected model is not stored and nothing changes.

        Parameters
        ----------
        region : bool mask, (rows, cols) tuple or FlaggedRegion
            Cells the new model would serve.
        new_model : CurrentModelProtocol
            The candidate model.
        validation_error_new, validation_error_old : float
            Validation errors (finite, >= 0) of the candidate and of the current model(s).
        name : str
            Unique name for the model table.
        reason : str
            Stored in the history (e.g. ``"error 23 % > 10 % in region 2"``).
        meta : mapping, optional
            Metadata of the new model.

        Returns
        -------
        UpdateDecision

        Raises
        ------
        InvalidParameterError
            Non-finite or negative errors, empty region, a model without fit/predict,
            empty or duplicate name, empty reason.
        GridMismatchError, OutOfBoundsError
            As :meth:`assign`.
        """
        err_new = check_real("validation_error_new", validation_error_new, low=0.0)
        err_old = check_real("validation_error_old", validation_error_old, low=0.0)
        clean_meta = self._table.check_new(new_model, name, meta, what="new_model")
        check_text("reason", reason)
        flat = flat_cells(self._shape, region, "region")
        if flat.size == 0:
            raise InvalidParameterError("region selects no cell; expected at least one cell to update")
        if not err_new < err_old:
            return UpdateDecision(False, err_new, err_old, err_old - err_new, int(flat.size), None, None, name, reason)
        model_id = self._table.add(new_model, name=name, meta=clean_meta)
        version, changed = self._assignment.apply(
            flat, model_id, kind="update", reason=reason, error_new=err_new, error_old=err_old
        )
        self._evidence.clear(changed)
        return UpdateDecision(
            True, err_new, err_old, err_old - err_new, int(flat.size), model_id, version.version, name, reason
        )

    @property
    def history(self) -> list[RegistryVersion]:
        """The changes of the cell map since the start, oldest first (a copy of the list)."""
        return self._assignment.history

    @property
    def version(self) -> int:
        """Current version: that of the newest change in :attr:`history`, 0 when there is none."""
        return self._assignment.version

    def rollback(self, version: int | None = None) -> list[RegistryVersion]:
        """Undo changes of the cell map, restoring the exact previous assignment.

        Parameters
        ----------
        version : int, optional
            ``None`` undoes the newest version only. An integer restores the state as it was
            right after that version (every newer version is undone); ``0`` restores the
            initial state (all cells on the prior).

        Returns
        -------
        list of RegistryVersion
            The versions undone, newest first; they leave :attr:`history`. The models they
            added stay in the model table. Evidence and flags are reset in every cell
            whose model changes.

        Raises
        ------
        InvalidParameterError
            Nothing to roll back, or ``version`` is neither 0 nor a version in the history.
        """
        undone, changed = self._assignment.rollback(version)
        self._evidence.clear(changed)
        return undone

    def __repr__(self) -> str:
        return (
            f"CellModelRegistry(shape={self._shape}, models={len(self._table)}, "
            f"in_use={self.model_ids_in_use().tolist()}, version={self.version}, "
            f"cells_with_evidence={self._evidence.cells_with_evidence})"
        )

    # ------------------------------------------------------------ persistence
    def save(
        self,
        directory: str | os.PathLike[str],
        save_model: Callable[[Any, Path], None],
        *,
        model_suffix: str = "",
    ) -> Path:
        """Write the registry to a directory, atomically (layout: :mod:`planner.registry.store`).

        The directory is built beside the target under a temporary name and renamed into
        place; a registry already there is replaced only once the new one is complete, and
        is kept (or put back) on any failure. Temporaries of earlier saves of the same
        target killed mid-way are removed.

        Parameters
        ----------
        directory : path
            Target directory. If it exists it must be empty or hold a registry (this method
            refuses to replace anything else).
        save_model : callable ``(model, path) -> None``
            Writes one model to exactly ``path`` (a file, or a directory if it prefers);
            called once per model in the table, with ``path`` inside ``models/``.
        model_suffix : str
            Appended to each model's file name (e.g. ``".pt"``).

        Returns
        -------
        pathlib.Path
            The directory.

        Raises
        ------
        InvalidParameterError
            The target exists and is not a registry directory; a bad suffix; ``save_model``
            wrote nothing at the path it was given.
        """
        return save_registry(directory, self._parts(), save_model, model_suffix=model_suffix)

    @classmethod
    def load(
        cls,
        directory: str | os.PathLike[str],
        load_model: Callable[[Path], Any],
        *,
        terrain: TerrainMap | None = None,
    ) -> CellModelRegistry:
        """Read a registry written by :meth:`save`.

        A registry that a :meth:`save` killed between its two renames left aside is moved
        back first (with a :class:`~terrawatt_base.errors.RecoveryWarning`), and temporaries of
        dead saves of the same target are removed.

        Parameters
        ----------
        directory : path
            The registry directory.
        load_model : callable ``(path) -> model``
            Reads one model written by the ``save_model`` given to :meth:`save`.
        terrain : TerrainMap, optional
            When given, the registry must be on its grid (see :meth:`check_grid`).

        Raises
        ------
        FileFormatError, FormatVersionError
            As :func:`planner.registry.store.load_registry` (the message names the piece).
        GridMismatchError
            ``terrain`` is on another grid.
        """
        parts = load_registry(directory, load_model)
        reg = cls._from_parts(parts)
        if terrain is not None:
            reg.check_grid(terrain)
        return reg
