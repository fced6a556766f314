"""Per-cell current-model registry: which model serves each cell, its observed error, updates.

A :class:`CellModelRegistry` is bound to one grid (``rows x cols``, optionally with the
origin and cell size of a :class:`~terrain.grid.TerrainMap`). It keeps

- a **model table**: models added with :meth:`~CellModelRegistry.add_model` get an integer
  id, a unique name and string/number metadata. Model id ``0`` is the *prior* given to the
  constructor (the physics model or a model trained elsewhere); every cell starts on it.
  Many cells share one model.
- a **cell map** (``int32`` model id per cell), changed only by
  :meth:`~CellModelRegistry.assign`, an accepted :meth:`~CellModelRegistry.propose_update`
  or :meth:`~CellModelRegistry.rollback`. Each change is a :class:`RegistryVersion` in
  :attr:`~CellModelRegistry.history` that remembers the previous id of every cell it
  touched, so a rollback restores the exact previous assignment.
- per-cell **evidence**: measured and predicted charge (integrated current, C) and a sample
  count, accumulated by :meth:`~CellModelRegistry.record`, from which
  :meth:`~CellModelRegistry.relative_error` and, under an :class:`UpdatePolicy` (threshold,
  minimum evidence, hysteresis), :meth:`~CellModelRegistry.flagged` and
  :meth:`~CellModelRegistry.flagged_regions` say which cells need new data.

The registry holds models through :class:`CurrentModelProtocol` and never calls them: the
caller predicts, fits and validates, and passes the numbers in; saving and loading models go
through caller-provided functions. So this module imports nothing from ``energy`` or
``planner``.

Persistence (:meth:`~CellModelRegistry.save` / :meth:`~CellModelRegistry.load`) is one
directory::

    registry.npz    format version, grid, cell map, evidence arrays, flag state,
                    the cells and previous ids of every history version
    history.json    format version, the model table (id, name, meta, file) and the
                    history versions (model, reason, validation errors)
    models/         one file per model, written by the caller's ``save_model``

The directory is written atomically: it is built in a temporary directory beside the target
and renamed into place; an existing registry directory is kept until the new one is complete.
"""

from __future__ import annotations

import json
import math
import numbers
import os
import re
import shutil
import tempfile
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal, Protocol, Union, runtime_checkable

import numpy as np
from scipy import ndimage

from .errors import (
    DataError,
    FileFormatError,
    FormatVersionError,
    GridMismatchError,
    InvalidParameterError,
    OutOfBoundsError,
    RecoveryWarning,
    UnknownNameError,
)
from .formats import check_format_version, read_versioned_npz
from .terrain_map import TerrainMap

__all__ = [
    "CurrentModelProtocol",
    "UpdatePolicy",
    "FlaggedRegion",
    "RegistryVersion",
    "UpdateDecision",
    "ModelRecord",
    "CellModelRegistry",
    "REGISTRY_FORMAT_VERSION",
    "PRIOR_MODEL_ID",
]

#: Version of the registry directory format written by :meth:`CellModelRegistry.save`.
REGISTRY_FORMAT_VERSION = 1
#: Model id of the prior, the model every cell starts on.
PRIOR_MODEL_ID = 0

_MAGIC = "terrawatt-cell-model-registry"
_HISTORY_MAGIC = "terrawatt-cell-model-history"
_REGISTRY_FILE = "registry.npz"
_HISTORY_FILE = "history.json"
_MODELS_DIR = "models"
_MODEL_FILE_RE = re.compile(r"^models/model-[0-9]+[A-Za-z0-9._-]*$")

MetaValue = Union[str, float, int]


@runtime_checkable
class CurrentModelProtocol(Protocol):
    """What the registry needs of a current model: a ``fit`` and a ``predict`` method.

    The registry only stores models that satisfy this protocol (checked with
    ``isinstance``, which tests that both methods exist) and never calls them itself:
    predictions, fitting and validation happen in the caller (e.g. the mission loop in
    ``planner``), and models are written and read through the ``save_model`` /
    ``load_model`` functions given to :meth:`CellModelRegistry.save` and
    :meth:`CellModelRegistry.load`. Any ``energy`` current model
    (``CurrentModel.fit(logs)`` / ``CurrentModel.predict(log)``) satisfies it; so does a
    wrapper around the physics model whose ``fit`` returns ``self``.
    """

    def fit(self, *args: Any, **kwargs: Any) -> Any:
        """Fit the model (scikit-learn contract: returns ``self``)."""
        ...

    def predict(self, *args: Any, **kwargs: Any) -> Any:
        """Predict drive currents (A)."""
        ...


# ----------------------------------------------------------------- validation helpers
def _check_real(owner: str, name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidParameterError(f"{owner}{name} must be a real number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise InvalidParameterError(f"{owner}{name} must be finite, got {value!r}")
    return v


def _check_int(owner: str, name: str, value: object, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InvalidParameterError(f"{owner}{name} must be an integer, got {value!r}")
    v = int(value)
    if v < low:
        raise InvalidParameterError(f"{owner}{name} must be >= {low}, got {value!r}")
    return v


def _check_text(name: str, value: object) -> str:
    if not isinstance(value, str) or not value.strip():
        raise InvalidParameterError(f"{name} must be a non-empty string, got {value!r}")
    return value


def _check_meta(meta: Mapping[str, MetaValue] | None) -> Mapping[str, MetaValue]:
    if meta is None:
        return MappingProxyType({})
    if not isinstance(meta, Mapping):
        raise InvalidParameterError(f"meta must be a mapping of str to str/int/float, got {meta!r}")
    clean: dict[str, MetaValue] = {}
    for key, value in meta.items():
        if not isinstance(key, str) or not key:
            raise InvalidParameterError(f"meta keys must be non-empty strings, got {key!r}")
        if isinstance(value, bool) or not isinstance(value, (str, numbers.Integral, numbers.Real)):
            raise InvalidParameterError(
                f"meta[{key!r}] must be a str, int or float, got {value!r} ({type(value).__name__})"
            )
        if isinstance(value, numbers.Integral):
            clean[key] = int(value)
        elif isinstance(value, numbers.Real):
            if not math.isfinite(float(value)):
                raise InvalidParameterError(f"meta[{key!r}] must be finite, got {value!r}")
            clean[key] = float(value)
        else:
            clean[key] = value
    return MappingProxyType(clean)


def _readonly(arr: np.ndarray) -> np.ndarray:
    out = np.array(arr, copy=True)
    out.setflags(write=False)
    return out


# --------------------------------------------------------------------------- results
@dataclass(frozen=True, kw_only=True)
class UpdatePolicy:
    """When a cell's observed error says its model needs new data.

    A cell's error is the relative error of integrated current over the samples recorded
    there, ``(predicted - measured) / |measured|`` (see
    :meth:`CellModelRegistry.relative_error`); the policy compares its magnitude, in per
    cent, with the threshold.

    Parameters
    ----------
    threshold_pct : float
        A cell with enough evidence becomes flagged when ``|error| > threshold_pct`` (%)
        (strictly above; > 0).
    min_samples : int
        A cell is never newly flagged with fewer recorded samples than this (>= 1).
    hysteresis_pct : float
        A flagged cell is cleared only when ``|error| < threshold_pct - hysteresis_pct``;
        between the two it keeps its previous state (>= 0 and < ``threshold_pct``).
    min_region_cells : int
        :meth:`CellModelRegistry.flagged_regions` leaves out connected regions with fewer
        flagged cells than this (>= 1; the cells stay flagged in :meth:`~CellModelRegistry.flagged`).

    Raises
    ------
    InvalidParameterError
        Non-finite or out-of-range values.

    Examples
    --------
    >>> from terrain import UpdatePolicy
    >>> UpdatePolicy(threshold_pct=10.0, min_samples=20, hysteresis_pct=3.0).clear_below_pct
    7.0
    """

    threshold_pct: float = 10.0
    min_samples: int = 10
    hysteresis_pct: float = 2.0
    min_region_cells: int = 1

    def __post_init__(self) -> None:
        owner = "UpdatePolicy."
        threshold = _check_real(owner, "threshold_pct", self.threshold_pct)
        if threshold <= 0:
            raise InvalidParameterError(f"UpdatePolicy.threshold_pct must be > 0, got {self.threshold_pct!r}")
        hysteresis = _check_real(owner, "hysteresis_pct", self.hysteresis_pct)
        if hysteresis < 0 or hysteresis >= threshold:
            raise InvalidParameterError(
                f"UpdatePolicy.hysteresis_pct must be >= 0 and < threshold_pct ({threshold!r}), "
                f"got {self.hysteresis_pct!r}"
            )
        object.__setattr__(self, "threshold_pct", threshold)
        object.__setattr__(self, "hysteresis_pct", hysteresis)
        object.__setattr__(self, "min_samples", _check_int(owner, "min_samples", self.min_samples, 1))
        object.__setattr__(
            self, "min_region_cells", _check_int(owner, "min_region_cells", self.min_region_cells, 1)
        )

    @property
    def clear_below_pct(self) -> float:
        """Error (%) below which a flagged cell is cleared: ``threshold_pct - hysteresis_pct``."""
        return self.threshold_pct - self.hysteresis_pct


@dataclass(frozen=True, eq=False)
class ModelRecord:
    """One entry of the model table: id, unique name and metadata (the model itself is
    returned by :meth:`CellModelRegistry.model`)."""

    model_id: int
    name: str
    meta: Mapping[str, MetaValue] = field(default_factory=lambda: MappingProxyType({}))


@dataclass(frozen=True, eq=False)
class FlaggedRegion:
    """A connected region of flagged cells (from :meth:`CellModelRegistry.flagged_regions`).

    Attributes
    ----------
    region_id : int
        Label of the region (1-based, in raster scan order of its first cell).
    rows, cols : numpy.ndarray of int64
        The region's cells (read-only, sorted by flat index).
    cell_count : int
        Number of cells.
    bbox_rows_cols : (int, int, int, int)
        ``(row_min, col_min, row_max, col_max)``, inclusive.
    representative_row_col : (int, int)
        The member cell nearest the centroid of the member cells (always inside the region,
        even for non-convex shapes; ties go to the lowest flat index).
    representative_xy_m : (float, float) or None
        World coordinates of that cell's centre, when the registry knows its georeferencing.
    bounds_m : (float, float, float, float) or None
        ``(xmin, ymin, xmax, ymax)`` of the bounding box in metres, when georeferenced.
    relative_error : float
        Relative error of integrated current over the whole region,
        ``(sum predicted - sum measured) / |sum measured|``.
    sample_count : int
        Samples recorded in the region.
    model_ids : tuple of int
        Models currently serving the region's cells.

    A region can be passed wherever the registry accepts cells (``assign``,
    ``propose_update``, ``reset_evidence``).
    """

    region_id: int
    rows: np.ndarray
    cols: np.ndarray
    cell_count: int
    bbox_rows_cols: tuple[int, int, int, int]
    representative_row_col: tuple[int, int]
    representative_xy_m: tuple[float, float] | None
    bounds_m: tuple[float, float, float, float] | None
    relative_error: float
    sample_count: int
    model_ids: tuple[int, ...]

    def mask(self, shape: tuple[int, int]) -> np.ndarray:
        """Boolean mask of the region on a grid of ``shape``."""
        out = np.zeros(shape, bool)
        out[self.rows, self.cols] = True
        return out


@dataclass(frozen=True, eq=False)
class RegistryVersion:
    """One change of the cell map, as kept in :attr:`CellModelRegistry.history`.

    Attributes
    ----------
    version : int
        Version number (>= 1, strictly increasing, never reused even after a rollback).
    kind : {"assign", "update"}
        ``"assign"`` for :meth:`CellModelRegistry.assign`, ``"update"`` for an accepted
        :meth:`CellModelRegistry.propose_update`.
    model_id : int
        The model the cells were given.
    rows, cols : numpy.ndarray of int64
        The cells the change covered (read-only, sorted by flat index).
    previous_model_ids : numpy.ndarray of int32
        Each of those cells' model id before the change (read-only).
    cell_count : int
        Number of cells covered.
    reason : str
        Why the change was made.
    validation_error_new, validation_error_old : float or None
        The validation errors that decided an update (``None`` for an assignment).
    """

    version: int
    kind: Literal["assign", "update"]
    model_id: int
    rows: np.ndarray
    cols: np.ndarray
    previous_model_ids: np.ndarray
    cell_count: int
    reason: str
    validation_error_new: float | None = None
    validation_error_old: float | None = None

    def __post_init__(self) -> None:
        n = len(self.rows)
        if len(self.cols) != n or len(self.previous_model_ids) != n or self.cell_count != n:
            raise InvalidParameterError(
                f"RegistryVersion {self.version!r}: rows, cols, previous_model_ids and cell_count "
                f"must agree, got {len(self.rows)}, {len(self.cols)}, "
                f"{len(self.previous_model_ids)}, {self.cell_count!r}"
            )
        if self.kind not in ("assign", "update"):
            raise InvalidParameterError(f"RegistryVersion.kind must be 'assign' or 'update', got {self.kind!r}")


@dataclass(frozen=True)
class UpdateDecision:
    """Outcome of :meth:`CellModelRegistry.propose_update`.

    Attributes
    ----------
    accepted : bool
        Whether the new model was swapped in (``validation_error_new < validation_error_old``).
    validation_error_new, validation_error_old : float
        The errors the decision compared (same metric, lower is better).
    improvement : float
        ``validation_error_old - validation_error_new`` (negative or zero when rejected).
    cell_count : int
        Cells in the proposed region.
    model_id : int or None
        Id of the new model when accepted, else ``None`` (a rejected model is not stored).
    version : int or None
        History version created when accepted, else ``None``.
    name, reason : str
        As given.
    """

    accepted: bool
    validation_error_new: float
    validation_error_old: float
    improvement: float
    cell_count: int
    model_id: int | None
    version: int | None
    name: str
    reason: str


Cells = Union[np.ndarray, tuple[Any, Any], FlaggedRegion]


# -------------------------------------------------------------------------- registry
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
        Lower-left corner of cell (0, 0) (same convention as :class:`~terrain.grid.TerrainMap`).

    Raises
    ------
    InvalidParameterError
        Bad shape, a prior that is not a :class:`CurrentModelProtocol`, only one of
        ``cell_size_m`` / ``origin_xy_m``, non-finite georeferencing.

    Examples
    --------
    >>> import numpy as np
    >>> from terrain import CellModelRegistry, UpdatePolicy
    >>> class Const:
    ...     def __init__(self, current_a): self.current_a = current_a
    ...     def fit(self, *a, **k): return self
    ...     def predict(self, n): return np.full(n, self.current_a)
    >>> reg = CellModelRegistry((3, 4), Const(1.0), prior_name="physics")
    >>> reg.record([1, 1], [2, 2], measured_current_a=[2.0, 2.0],
    ...            predicted_current_a=[1.0, 1.0], dt_s=0.1)
    >>> float(reg.relative_error()[1, 2])
    -0.5
    >>> int(reg.flagged(UpdatePolicy(threshold_pct=10.0, min_samples=2)).sum())
    1
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
        try:
            rows, cols = (int(v) for v in shape)
            ok = all(isinstance(v, numbers.Integral) and not isinstance(v, bool) for v in shape)
        except (TypeError, ValueError):
            ok = False
        if not ok or rows < 1 or cols < 1:
            raise InvalidParameterError(f"shape must be (rows, cols) of positive integers, got {shape!r}")
        self._shape = (rows, cols)
        if (cell_size_m is None) != (origin_xy_m is None):
            raise InvalidParameterError(
                "cell_size_m and origin_xy_m must be given together (or neither), got "
                f"cell_size_m={cell_size_m!r}, origin_xy_m={origin_xy_m!r}"
            )
        self._cell_size_m: float | None = None
        self._origin_xy_m: tuple[float, float] | None = None
        if cell_size_m is not None and origin_xy_m is not None:
            cell = _check_real("", "cell_size_m", cell_size_m)
            if cell <= 0:
                raise InvalidParameterError(f"cell_size_m must be > 0, got {cell_size_m!r}")
            try:
                ox, oy = origin_xy_m
            except (TypeError, ValueError) as exc:
                raise InvalidParameterError(f"origin_xy_m must be (x, y), got {origin_xy_m!r}") from exc
            self._cell_size_m = cell
            self._origin_xy_m = (_check_real("", "origin_xy_m[0]", ox), _check_real("", "origin_xy_m[1]", oy))
        self._models: dict[int, Any] = {}
        self._records: dict[int, ModelRecord] = {}
        self._cell_model = np.full(self._shape, PRIOR_MODEL_ID, dtype=np.int32)
        self._measured_c = np.zeros(self._shape, np.float64)
        self._predicted_c = np.zeros(self._shape, np.float64)
        self._count = np.zeros(self._shape, np.int64)
        self._flag = np.zeros(self._shape, bool)
        self._history: list[RegistryVersion] = []
        self._next_version = 1
        self.add_model(prior, name=prior_name, meta=prior_meta)

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
        return cls(
            terrain.shape,
            prior,
            prior_name=prior_name,
            prior_meta=prior_meta,
            cell_size_m=terrain.cell_size_m,
            origin_xy_m=terrain.origin_xy_m,
        )

    # -------------------------------------------------------------------- grid
    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)`` of the grid."""
        return self._shape

    @property
    def cell_size_m(self) -> float | None:
        """Cell size (m), or ``None`` when not georeferenced."""
        return self._cell_size_m

    @property
    def origin_xy_m(self) -> tuple[float, float] | None:
        """Lower-left corner of cell (0, 0) (m), or ``None`` when not georeferenced."""
        return self._origin_xy_m

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
            raise GridMismatchError(
                f"terrain has shape {terrain.shape!r}; this registry's grid is {self._shape!r}"
            )
        if self._cell_size_m is not None and (
            terrain.cell_size_m != self._cell_size_m or terrain.origin_xy_m != self._origin_xy_m
        ):
            raise GridMismatchError(
                f"terrain has cell size {terrain.cell_size_m!r} m and origin {terrain.origin_xy_m!r}; "
                f"this registry's grid has {self._cell_size_m!r} m and {self._origin_xy_m!r}"
            )

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
        if not isinstance(model, CurrentModelProtocol):
            raise InvalidParameterError(
                f"model must have fit() and predict() methods (CurrentModelProtocol), got "
                f"{type(model).__name__}"
            )
        _check_text("name", name)
        clean_meta = _check_meta(meta)
        if any(rec.name == name for rec in self._records.values()):
            raise InvalidParameterError(
                f"a model named {name!r} is already in the registry; names must be unique"
            )
        model_id = len(self._records)
        self._models[model_id] = model
        self._records[model_id] = ModelRecord(model_id, name, clean_meta)
        return model_id

    @property
    def prior_id(self) -> int:
        """Id of the prior model (always :data:`PRIOR_MODEL_ID`)."""
        return PRIOR_MODEL_ID

    @property
    def model_ids(self) -> tuple[int, ...]:
        """Ids of every model in the table, in order."""
        return tuple(self._records)

    def model(self, model_id: int) -> CurrentModelProtocol:
        """The model with id ``model_id``.

        Raises
        ------
        UnknownNameError
            No such id.
        """
        return self._models[self._check_model_id(model_id)]

    def model_record(self, model_id: int) -> ModelRecord:
        """Id, name and metadata of a model.

        Raises
        ------
        UnknownNameError
            No such id.
        """
        return self._records[self._check_model_id(model_id)]

    def model_id(self, name: str) -> int:
        """Id of the model called ``name``.

        Raises
        ------
        UnknownNameError
            No model has that name.
        """
        for rec in self._records.values():
            if rec.name == name:
                return rec.model_id
        raise UnknownNameError(
            f"no model named {name!r}; known: {[r.name for r in self._records.values()]!r}"
        )

    def model_ids_in_use(self) -> np.ndarray:
        """Sorted ids of the models that serve at least one cell."""
        return np.unique(self._cell_model).astype(np.int64)

    @property
    def model_id_map(self) -> np.ndarray:
        """Model id of every cell (``int32``, shape :attr:`shape`; a read-only copy)."""
        return _readonly(self._cell_model)

    def model_for(self, row: int, col: int) -> CurrentModelProtocol:
        """The model serving cell ``(row, col)``.

        Raises
        ------
        OutOfBoundsError
            The cell is outside the grid.
        """
        rows, cols = self._check_rows_cols(row, col)
        return self._models[int(self._cell_model[rows[0], cols[0]])]

    def _check_model_id(self, model_id: object) -> int:
        mid = int(model_id) if isinstance(model_id, numbers.Integral) and not isinstance(model_id, bool) else None
        if mid is None or mid not in self._records:
            raise UnknownNameError(f"no model with id {model_id!r}; known ids: {list(self._records)!r}")
        return mid

    # ------------------------------------------------------------------ cells
    def _check_rows_cols(self, rows: Any, cols: Any) -> tuple[np.ndarray, np.ndarray]:
        r = np.atleast_1d(np.asarray(rows))
        c = np.atleast_1d(np.asarray(cols))
        for name, arr in (("rows", r), ("cols", c)):
            if arr.ndim != 1:
                raise InvalidParameterError(f"{name} must be 1-D, got shape {arr.shape!r}")
            if arr.size and (arr.dtype == bool or not np.issubdtype(arr.dtype, np.integer)):
                raise InvalidParameterError(f"{name} must hold integer cell indices, got dtype {arr.dtype}")
        if r.shape != c.shape:
            raise InvalidParameterError(f"rows and cols must have the same length, got {r.size} and {c.size}")
        r = r.astype(np.int64)
        c = c.astype(np.int64)
        bad = (r < 0) | (r >= self._shape[0]) | (c < 0) | (c >= self._shape[1])
        if np.any(bad):
            i = int(np.flatnonzero(bad)[0])
            raise OutOfBoundsError(
                f"cell (row={int(r[i])!r}, col={int(c[i])!r}) at index {i} lies outside the grid "
                f"{self._shape!r}"
            )
        return r, c

    def _flat_cells(self, cells: Cells, what: str = "cells") -> np.ndarray:
        """Sorted unique flat indices of ``cells`` (mask, (rows, cols) or FlaggedRegion)."""
        if isinstance(cells, FlaggedRegion):
            r, c = self._check_rows_cols(cells.rows, cells.cols)
        elif isinstance(cells, tuple):
            if len(cells) != 2:
                raise InvalidParameterError(f"{what} as a tuple must be (rows, cols), got {len(cells)} items")
            r, c = self._check_rows_cols(*cells)
        else:
            mask = np.asarray(cells)
            if mask.dtype != bool:
                raise InvalidParameterError(
                    f"{what} must be a boolean mask, a (rows, cols) tuple or a FlaggedRegion, got an "
                    f"array of dtype {mask.dtype}"
                )
            if mask.shape != self._shape:
                raise GridMismatchError(
                    f"{what} mask has shape {mask.shape!r}; this registry's grid is {self._shape!r}"
                )
            return np.flatnonzero(mask)
        return np.unique(r * self._shape[1] + c)

    def _unflat(self, flat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rows, cols = np.divmod(flat.astype(np.int64), self._shape[1])
        return rows, cols

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
        mid = self._check_model_id(model_id)
        _check_text("reason", reason)
        flat = self._flat_cells(cells)
        if flat.size == 0:
            raise InvalidParameterError("cells selects no cell; expected at least one cell to assign")
        return self._apply(flat, mid, kind="assign", reason=reason)

    def _apply(
        self,
        flat: np.ndarray,
        model_id: int,
        *,
        kind: Literal["assign", "update"],
        reason: str,
        error_new: float | None = None,
        error_old: float | None = None,
    ) -> RegistryVersion:
        cm = self._cell_model.reshape(-1)
        previous = cm[flat].copy()
        rows, cols = self._unflat(flat)
        version = RegistryVersion(
            version=self._next_version,
            kind=kind,
            model_id=model_id,
            rows=_readonly(rows),
            cols=_readonly(cols),
            previous_model_ids=_readonly(previous.astype(np.int32)),
            cell_count=int(flat.size),
            reason=reason,
            validation_error_new=error_new,
            validation_error_old=error_old,
        )
        cm[flat] = model_id
        self._clear_evidence_flat(flat[previous != model_id])
        self._history.append(version)
        self._next_version += 1
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
        err_new = _check_real("", "validation_error_new", validation_error_new)
        err_old = _check_real("", "validation_error_old", validation_error_old)
        for label, v, raw in (("validation_error_new", err_new, validation_error_new),
                              ("validation_error_old", err_old, validation_error_old)):
            if v < 0:
                raise InvalidParameterError(f"{label} must be >= 0 (an error magnitude), got {raw!r}")
        if not isinstance(new_model, CurrentModelProtocol):
            raise InvalidParameterError(
                f"new_model must have fit() and predict() methods (CurrentModelProtocol), got "
                f"{type(new_model).__name__}"
            )
        _check_text("name", name)
        _check_text("reason", reason)
        clean_meta = _check_meta(meta)
        if any(rec.name == name for rec in self._records.values()):
            raise InvalidParameterError(
                f"a model named {name!r} is already in the registry; names must be unique"
            )
        flat = self._flat_cells(region, "region")
        if flat.size == 0:
            raise InvalidParameterError("region selects no cell; expected at least one cell to update")
        if not err_new < err_old:
            return UpdateDecision(
                False, err_new, err_old, err_old - err_new, int(flat.size), None, None, name, reason
            )
        model_id = self.add_model(new_model, name=name, meta=clean_meta)
        version = self._apply(
            flat, model_id, kind="update", reason=reason, error_new=err_new, error_old=err_old
        )
        return UpdateDecision(
            True, err_new, err_old, err_old - err_new, int(flat.size), model_id, version.version, name, reason
        )

    @property
    def history(self) -> list[RegistryVersion]:
        """The changes of the cell map since the start, oldest first (a copy of the list)."""
        return list(self._history)

    @property
    def version(self) -> int:
        """Current version: that of the newest change in :attr:`history`, 0 when there is none."""
        return self._history[-1].version if self._history else 0

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
        if not self._history:
            raise InvalidParameterError("the history is empty; there is nothing to roll back")
        if version is None:
            target = self._history[-2].version if len(self._history) > 1 else 0
        else:
            target = _check_int("", "version", version, 0)
            known = [v.version for v in self._history]
            if target != 0 and target not in known:
                raise InvalidParameterError(f"version must be 0 or one of {known!r}, got {version!r}")
        before = self._cell_model.copy()
        cm = self._cell_model
        undone: list[RegistryVersion] = []
        while self._history and self._history[-1].version > target:
            v = self._history.pop()
            cm[v.rows, v.cols] = v.previous_model_ids
            undone.append(v)
        self._clear_evidence_flat(np.flatnonzero(before != cm))
        return undone

    # --------------------------------------------------------------- evidence
    def record(
        self,
        rows: Any,
        cols: Any,
        measured_current_a: Any,
        predicted_current_a: Any,
        dt_s: Any,
    ) -> None:
        """Accumulate measured and predicted charge per cell from driving samples.

        Each sample ``i`` adds ``measured_current_a[i] * dt_s[i]`` to the measured charge
        (C) of cell ``(rows[i], cols[i])``, ``predicted_current_a[i] * dt_s[i]`` to its
        predicted charge and 1 to its sample count. Vectorised (``np.add.at``).

        Parameters
        ----------
        rows, cols : array_like of int, shape (N,)
            Cell of each sample (e.g. from :meth:`TerrainMap.rowcol` of the robot's position).
        measured_current_a, predicted_current_a : array_like of float, shape (N,) or (N, k)
            Drive current (A); a 2-D array is summed over its ``k`` channels (e.g. left and
            right motors). Pass the quantity to compare, e.g. absolute currents.
        dt_s : float or array_like of float, shape (N,)
            Duration each sample stands for (s, > 0).

        Raises
        ------
        InvalidParameterError
            Arrays whose lengths differ, non-integer cells, arrays of the wrong rank.
        OutOfBoundsError
            Cells outside the grid.
        DataError
            NaN/inf currents or durations, non-positive durations.
        """
        r, c = self._check_rows_cols(rows, cols)
        n = r.size
        meas = self._current_array("measured_current_a", measured_current_a, n)
        pred = self._current_array("predicted_current_a", predicted_current_a, n)
        dt = np.asarray(dt_s, dtype=np.float64)
        if dt.ndim > 1 or (dt.ndim == 1 and dt.size != n):
            raise InvalidParameterError(
                f"dt_s must be a scalar or have one value per sample ({n}), got shape {dt.shape!r}"
            )
        if not np.all(np.isfinite(dt)) or np.any(dt <= 0):
            bad = np.flatnonzero(~(np.isfinite(np.atleast_1d(dt)) & (np.atleast_1d(dt) > 0)))
            raise DataError(
                f"dt_s must be finite and > 0; {bad.size} value(s) are not, first "
                f"{np.atleast_1d(dt)[bad[0]]!r} at index {int(bad[0])}"
            )
        if n == 0:
            return
        flat = r * self._shape[1] + c
        np.add.at(self._measured_c.reshape(-1), flat, meas * dt)
        np.add.at(self._predicted_c.reshape(-1), flat, pred * dt)
        np.add.at(self._count.reshape(-1), flat, 1)

    @staticmethod
    def _current_array(name: str, value: Any, n: int) -> np.ndarray:
        try:
            arr = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(f"{name} must be an array of numbers: {exc}") from exc
        if arr.ndim not in (1, 2) or arr.shape[0] != n:
            raise InvalidParameterError(
                f"{name} must have shape ({n},) or ({n}, k) to match rows/cols, got {arr.shape!r}"
            )
        finite = np.isfinite(arr)
        if not np.all(finite):
            bad = np.flatnonzero(~finite.reshape(n, -1).all(axis=1))
            raise DataError(
                f"{name} holds NaN/inf in {bad.size} sample(s), first at index {int(bad[0])}; "
                "expected finite currents (repair or drop them before recording)"
            )
        return arr if arr.ndim == 1 else arr.sum(axis=1)

    @property
    def measured_charge_c(self) -> np.ndarray:
        """Measured charge (C, integral of measured current) per cell (read-only copy)."""
        return _readonly(self._measured_c)

    @property
    def predicted_charge_c(self) -> np.ndarray:
        """Predicted charge (C) per cell (read-only copy)."""
        return _readonly(self._predicted_c)

    @property
    def sample_count(self) -> np.ndarray:
        """Samples recorded per cell since its evidence was last reset (read-only copy)."""
        return _readonly(self._count)

    def relative_error(self) -> np.ndarray:
        """Relative error of integrated current per cell, ``(predicted - measured) / |measured|``.

        Positive when the model over-predicts. ``NaN`` where the cell has no samples; where
        the measured charge is exactly 0 it is 0 if the predicted charge is 0 too, else
        ``±inf``.

        Returns
        -------
        numpy.ndarray of float64, shape :attr:`shape`
        """
        return _relative_error(self._predicted_c, self._measured_c, self._count)

    def relative_error_over(self, cells: Cells) -> float:
        """Relative error of the charge integrated over a set of cells (NaN without samples).

        Raises
        ------
        InvalidParameterError, GridMismatchError, OutOfBoundsError
            Bad ``cells``.
        """
        flat = self._flat_cells(cells)
        p = float(self._predicted_c.reshape(-1)[flat].sum())
        m = float(self._measured_c.reshape(-1)[flat].sum())
        n = int(self._count.reshape(-1)[flat].sum())
        return float(_relative_error(np.array(p), np.array(m), np.array(n)))

    def reset_evidence(self, cells: Cells | None = None) -> None:
        """Forget the evidence (charges, counts) and flag state of ``cells`` (all when ``None``).

        Call it after data were collected and a model updated by other means than
        :meth:`propose_update` / :meth:`assign` (which reset the cells they change).
        """
        if cells is None:
            flat = np.arange(self._count.size)
        else:
            flat = self._flat_cells(cells)
        self._clear_evidence_flat(flat)

    def _clear_evidence_flat(self, flat: np.ndarray) -> None:
        self._measured_c.reshape(-1)[flat] = 0.0
        self._predicted_c.reshape(-1)[flat] = 0.0
        self._count.reshape(-1)[flat] = 0
        self._flag.reshape(-1)[flat] = False

    # ---------------------------------------------------------------- flags
    def flagged(self, policy: UpdatePolicy) -> np.ndarray:
        """Cells whose model needs new data under ``policy``, with hysteresis.

        A cell becomes flagged when it has at least ``policy.min_samples`` samples and
        ``|relative error| > threshold_pct``; a flagged cell stays flagged until its error
        falls below ``threshold_pct - hysteresis_pct``. The state is kept between calls, so
        each call advances it (and :meth:`reset_evidence` clears it).

        Returns
        -------
        numpy.ndarray of bool, shape :attr:`shape` (a copy)

        Raises
        ------
        InvalidParameterError
            ``policy`` is not an :class:`UpdatePolicy`.
        """
        if not isinstance(policy, UpdatePolicy):
            raise InvalidParameterError(f"policy must be an UpdatePolicy, got {type(policy).__name__}")
        with np.errstate(invalid="ignore"):
            err_pct = 100.0 * np.abs(self.relative_error())
            enough = self._count >= policy.min_samples
            above = enough & (err_pct > policy.threshold_pct)
            cleared = err_pct < policy.clear_below_pct
        self._flag = above | (self._flag & ~cleared)
        return self._flag.copy()

    @property
    def flag_state(self) -> np.ndarray:
        """The flags as of the last :meth:`flagged` call (read-only copy)."""
        return _readonly(self._flag)

    def flagged_regions(self, policy: UpdatePolicy, *, connectivity: Literal[4, 8] = 8) -> list[FlaggedRegion]:
        """Connected regions of flagged cells (advances the flag state like :meth:`flagged`).

        Parameters
        ----------
        policy : UpdatePolicy
            Regions with fewer than ``policy.min_region_cells`` cells are left out.
        connectivity : {4, 8}
            Cells touching by an edge (4) or also by a corner (8) belong to one region.

        Returns
        -------
        list of FlaggedRegion
            In label order (raster scan order of each region's first cell).

        Raises
        ------
        InvalidParameterError
            Bad policy or connectivity.
        """
        if connectivity not in (4, 8):
            raise InvalidParameterError(f"connectivity must be 4 or 8, got {connectivity!r}")
        mask = self.flagged(policy)
        structure = ndimage.generate_binary_structure(2, 1 if connectivity == 4 else 2)
        labels, n_regions = ndimage.label(mask, structure=structure)
        if n_regions == 0:
            return []
        flat_labels = labels.reshape(-1)
        members = np.flatnonzero(flat_labels)  # sorted flat indices
        members = members[np.argsort(flat_labels[members], kind="stable")]  # grouped by label
        seg = flat_labels[members] - 1  # region index of each member, 0-based
        sizes = np.bincount(seg, minlength=n_regions)
        starts = np.concatenate(([0], np.cumsum(sizes)))
        rows, cols = self._unflat(members)
        # per-region statistics in one pass (no Python loop over cells)
        heads = starts[:-1]
        row_min, row_max = np.minimum.reduceat(rows, heads), np.maximum.reduceat(rows, heads)
        col_min, col_max = np.minimum.reduceat(cols, heads), np.maximum.reduceat(cols, heads)
        centre_r = np.add.reduceat(rows, heads) / sizes
        centre_c = np.add.reduceat(cols, heads) / sizes
        dist2 = (rows - centre_r[seg]) ** 2 + (cols - centre_c[seg]) ** 2
        rep_idx = np.lexsort((dist2, seg))[heads]  # nearest member; ties -> lowest flat index
        pred_sum = np.add.reduceat(self._predicted_c.reshape(-1)[members], heads)
        meas_sum = np.add.reduceat(self._measured_c.reshape(-1)[members], heads)
        n_sum = np.add.reduceat(self._count.reshape(-1)[members], heads)
        errors = _relative_error(pred_sum, meas_sum, n_sum)
        n_models = len(self._records)
        pairs = np.unique(seg * n_models + self._cell_model.reshape(-1)[members])
        pair_seg, pair_model = np.divmod(pairs, n_models)
        pair_starts = np.searchsorted(pair_seg, np.arange(n_regions + 1))
        regions: list[FlaggedRegion] = []
        for k in np.flatnonzero(sizes >= policy.min_region_cells):
            sl = slice(starts[k], starts[k + 1])
            rep = (int(rows[rep_idx[k]]), int(cols[rep_idx[k]]))
            bbox = (int(row_min[k]), int(col_min[k]), int(row_max[k]), int(col_max[k]))
            rep_xy: tuple[float, float] | None = None
            bounds: tuple[float, float, float, float] | None = None
            if self._cell_size_m is not None and self._origin_xy_m is not None:
                d = self._cell_size_m
                x0, y0 = self._origin_xy_m
                rep_xy = (x0 + (rep[1] + 0.5) * d, y0 + (rep[0] + 0.5) * d)
                bounds = (x0 + bbox[1] * d, y0 + bbox[0] * d, x0 + (bbox[3] + 1) * d, y0 + (bbox[2] + 1) * d)
            regions.append(
                FlaggedRegion(
                    region_id=int(k) + 1,
                    rows=_readonly(rows[sl]),
                    cols=_readonly(cols[sl]),
                    cell_count=int(sizes[k]),
                    bbox_rows_cols=bbox,
                    representative_row_col=rep,
                    representative_xy_m=rep_xy,
                    bounds_m=bounds,
                    relative_error=float(errors[k]),
                    sample_count=int(n_sum[k]),
                    model_ids=tuple(pair_model[pair_starts[k]:pair_starts[k + 1]].tolist()),
                )
            )
        return regions

    def __repr__(self) -> str:
        return (
            f"CellModelRegistry(shape={self._shape}, models={len(self._records)}, "
            f"in_use={self.model_ids_in_use().tolist()}, version={self.version}, "
            f"cells_with_evidence={int(np.count_nonzero(self._count))})"
        )

    # ------------------------------------------------------------ persistence
    def save(
        self,
        directory: str | os.PathLike[str],
        save_model: Callable[[Any, Path], None],
        *,
        model_suffix: str = "",
    ) -> Path:
        """Write the registry to a directory, atomically.

        The directory is built beside the target under a temporary name and renamed into
        place. If the target already holds a registry, it is moved aside only once the new
        directory is complete and deleted after the new one is in place; on any failure the
        previous directory is left (or put back) where it was. (Between the two renames the
        old registry sits for an instant in a ``.<name>.*.old`` directory beside the target.)

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
        target = Path(directory)
        suffix_ok = isinstance(model_suffix, str) and (
            not model_suffix or re.fullmatch(r"[A-Za-z0-9._-]+", model_suffix) is not None
        )
        if not suffix_ok:
            raise InvalidParameterError(
                f"model_suffix must be letters, digits, '.', '_' or '-', got {model_suffix!r}"
            )
        if target.exists() and not _replaceable(target):
            raise InvalidParameterError(
                f"{str(target)!r} exists and is not a registry directory (no {_REGISTRY_FILE}); "
                "refusing to replace it"
            )
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent))
        try:
            self._write_into(tmp, save_model, model_suffix)
            os.chmod(tmp, 0o755)  # mkdtemp makes it owner-only
            _fsync_dir(tmp)
            if target.exists():
                holder = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".old", dir=target.parent))
                old = holder / target.name
                try:
                    os.rename(target, old)
                except BaseException:
                    shutil.rmtree(holder, ignore_errors=True)
                    raise
                try:
                    os.rename(tmp, target)
                except BaseException:
                    os.rename(old, target)
                    shutil.rmtree(holder, ignore_errors=True)
                    raise
                _fsync_dir(target.parent)
                shutil.rmtree(holder, ignore_errors=True)
            else:
                os.rename(tmp, target)
                _fsync_dir(target.parent)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return target

    def _write_into(self, tmp: Path, save_model: Callable[[Any, Path], None], suffix: str) -> None:
        models_dir = tmp / _MODELS_DIR
        models_dir.mkdir()
        model_entries = []
        for mid, rec in self._records.items():
            rel = f"{_MODELS_DIR}/model-{mid:04d}{suffix}"
            path = tmp / rel
            save_model(self._models[mid], path)
            if not path.exists():
                raise InvalidParameterError(
                    f"save_model wrote nothing at {str(path)!r} for model {mid} ({rec.name!r}); "
                    "it must write the model to exactly the path it is given"
                )
            model_entries.append({"model_id": mid, "name": rec.name, "meta": dict(rec.meta), "file": rel})
        payload: dict[str, np.ndarray] = {
            "__magic__": np.array(_MAGIC),
            "__version__": np.array(REGISTRY_FORMAT_VERSION),
            "shape": np.array(self._shape, dtype=np.int64),
            "georeferenced": np.array(self._cell_size_m is not None),
            "cell_size_m": np.array(np.nan if self._cell_size_m is None else self._cell_size_m),
            "origin_xy_m": np.array((np.nan, np.nan) if self._origin_xy_m is None else self._origin_xy_m),
            "model_id_map": self._cell_model,
            "measured_charge_c": self._measured_c,
            "predicted_charge_c": self._predicted_c,
            "sample_count": self._count,
            "flag_state": self._flag,
        }
        versions = []
        for v in self._history:
            payload[f"version_{v.version}_cells"] = v.rows * self._shape[1] + v.cols
            payload[f"version_{v.version}_previous"] = v.previous_model_ids
            versions.append({
                "version": v.version,
                "kind": v.kind,
                "model_id": v.model_id,
                "cell_count": v.cell_count,
                "reason": v.reason,
                "validation_error_new": v.validation_error_new,
                "validation_error_old": v.validation_error_old,
            })
        with open(tmp / _REGISTRY_FILE, "wb") as fh:
            np.savez_compressed(fh, **payload)
            fh.flush()
            os.fsync(fh.fileno())
        history = {
            "format": _HISTORY_MAGIC,
            "format_version": REGISTRY_FORMAT_VERSION,
            "next_version": self._next_version,
            "models": model_entries,
            "versions": versions,
        }
        with open(tmp / _HISTORY_FILE, "w", encoding="utf-8") as fh:
            json.dump(history, fh, indent=1, allow_nan=False)
            fh.flush()
            os.fsync(fh.fileno())

    @classmethod
    def load(
        cls,
        directory: str | os.PathLike[str],
        load_model: Callable[[Path], Any],
        *,
        terrain: TerrainMap | None = None,
    ) -> CellModelRegistry:
        """Read a registry written by :meth:`save`.

        Parameters
        ----------
        directory : path
            The registry directory.
        load_model : callable ``(path) -> model``
            Reads one model written by the ``save_model`` given to :meth:`save`.
        terrain : TerrainMap, optional
            When given, the registry must be on its grid (see :meth:`check_grid`).

        A :meth:`save` interrupted between moving the old registry aside and moving the new
        one in (a crash in that instant) leaves no directory under the name but the previous
        registry in a hidden ``.NAME.*.old`` folder beside it; ``load`` then moves that one
        back, with a :class:`~terrain.errors.RecoveryWarning`, and reads it.

        Raises
        ------
        FileFormatError
            Missing directory; a missing, corrupt or inconsistent ``registry.npz``,
            ``history.json`` or model file (the message names the piece); ``load_model``
            failing or returning something without fit/predict.
        FormatVersionError
            ``registry.npz`` or ``history.json`` of another format version, or
            ``load_model`` raising FormatVersionError.
        GridMismatchError
            ``terrain`` is on another grid.
        """
        root = Path(directory)
        if not root.is_dir():
            _recover_interrupted_save(root)
        if not root.is_dir():
            raise FileFormatError(f"registry directory {str(root)!r} does not exist")
        arrays = _read_npz(root / _REGISTRY_FILE)
        history = _read_history(root / _HISTORY_FILE)
        npz = str(root / _REGISTRY_FILE)
        hist = str(root / _HISTORY_FILE)
        try:
            shape = tuple(int(v) for v in arrays["shape"])
            georef = bool(arrays["georeferenced"])
            cell_size = float(arrays["cell_size_m"])
            origin = tuple(float(v) for v in arrays["origin_xy_m"])
            cell_model = np.asarray(arrays["model_id_map"])
            measured = np.asarray(arrays["measured_charge_c"])
            predicted = np.asarray(arrays["predicted_charge_c"])
            count = np.asarray(arrays["sample_count"])
            flag = np.asarray(arrays["flag_state"])
        except KeyError as exc:
            raise FileFormatError(f"{npz!r} lacks entry {exc.args[0]!r}") from exc
        except (TypeError, ValueError) as exc:
            raise FileFormatError(f"{npz!r} has a malformed grid description: {exc}") from exc
        if len(shape) != 2:
            raise FileFormatError(f"{npz!r}: shape must have 2 entries, got {shape!r}")
        for key, arr, kind in (("model_id_map", cell_model, "i"), ("measured_charge_c", measured, "f"),
                               ("predicted_charge_c", predicted, "f"), ("sample_count", count, "i"),
                               ("flag_state", flag, "b")):
            if arr.shape != shape or arr.dtype.kind != kind:
                raise FileFormatError(
                    f"{npz!r}: {key} has shape {arr.shape!r} and dtype {arr.dtype}; "
                    f"expected {shape!r} of kind {kind!r}"
                )
        if not (np.all(np.isfinite(measured)) and np.all(np.isfinite(predicted)) and np.all(count >= 0)):
            raise FileFormatError(f"{npz!r}: evidence arrays hold NaN/inf charges or negative counts")

        try:
            entries = history["models"]
            version_entries = history["versions"]
            next_version = int(history["next_version"])
            ids = [int(e["model_id"]) for e in entries]
        except (KeyError, TypeError, ValueError) as exc:
            raise FileFormatError(f"{hist!r} is malformed: {exc!r}") from exc
        if ids != list(range(len(ids))) or not ids:
            raise FileFormatError(
                f"{hist!r}: model ids must be 0, 1, 2, ... with at least the prior, got {ids!r}"
            )
        if cell_model.size and (cell_model.min() < 0 or cell_model.max() >= len(ids)):
            raise FileFormatError(f"{npz!r}: model_id_map holds ids outside the model table 0..{len(ids) - 1}")

        models: list[Any] = []
        for e in entries:
            rel = e.get("file") if isinstance(e, dict) else None
            if not isinstance(rel, str) or not _MODEL_FILE_RE.match(rel):
                raise FileFormatError(f"{hist!r}: model entry {e!r} has no valid 'file' inside {_MODELS_DIR}/")
            path = root / rel
            if not path.exists():
                raise FileFormatError(
                    f"model file {str(path)!r} (model {e['model_id']}, {e.get('name')!r}) is missing"
                )
            try:
                model = load_model(path)
            except FormatVersionError as exc:
                raise FormatVersionError(f"model file {str(path)!r}: {exc}") from exc
            except Exception as exc:
                raise FileFormatError(f"model file {str(path)!r} could not be loaded: {exc!r}") from exc
            if not isinstance(model, CurrentModelProtocol):
                raise FileFormatError(
                    f"load_model returned a {type(model).__name__} for {str(path)!r}; "
                    "expected a model with fit/predict"
                )
            models.append(model)

        try:
            first = entries[0]
            reg = cls(
                shape,  # type: ignore[arg-type]
                models[0],
                prior_name=first["name"],
                prior_meta=first.get("meta") or None,
                cell_size_m=cell_size if georef else None,
                origin_xy_m=origin if georef else None,  # type: ignore[arg-type]
            )
            for e, model in zip(entries[1:], models[1:]):
                reg.add_model(model, name=e["name"], meta=e.get("meta") or None)
        except (KeyError, InvalidParameterError) as exc:
            raise FileFormatError(f"{hist!r} or {npz!r} holds an invalid registry: {exc}") from exc

        n_cells = shape[0] * shape[1]
        last = 0
        for ve in version_entries:
            try:
                vnum = int(ve["version"])
                cells = np.asarray(arrays[f"version_{vnum}_cells"])
                previous = np.asarray(arrays[f"version_{vnum}_previous"])
                if vnum <= last or vnum >= next_version:
                    raise ValueError(f"version {vnum} out of order (previous {last}, next {next_version})")
                if cells.dtype.kind != "i" or previous.dtype.kind != "i" or cells.shape != previous.shape \
                        or cells.ndim != 1 or cells.size != int(ve["cell_count"]):
                    raise ValueError(f"version {vnum} cell arrays do not match its cell_count")
                if cells.size and (cells.min() < 0 or cells.max() >= n_cells
                                   or previous.min() < 0 or previous.max() >= len(ids)):
                    raise ValueError(f"version {vnum} refers to cells or models that do not exist")
                model_id = int(ve["model_id"])
                if not 0 <= model_id < len(ids):
                    raise ValueError(f"version {vnum} refers to model {model_id} not in the table")
                rows, cols = reg._unflat(cells)
                err_new, err_old = ve.get("validation_error_new"), ve.get("validation_error_old")
                reg._history.append(RegistryVersion(
                    version=vnum,
                    kind=ve["kind"],
                    model_id=model_id,
                    rows=_readonly(rows),
                    cols=_readonly(cols),
                    previous_model_ids=_readonly(previous.astype(np.int32)),
                    cell_count=int(cells.size),
                    reason=str(ve["reason"]),
                    validation_error_new=None if err_new is None else float(err_new),
                    validation_error_old=None if err_old is None else float(err_old),
                ))
                last = vnum
            except KeyError as exc:
                raise FileFormatError(f"{hist!r}/{npz!r}: a history version lacks {exc.args[0]!r}") from exc
            except (TypeError, ValueError, InvalidParameterError) as exc:
                raise FileFormatError(f"{hist!r}/{npz!r}: invalid history: {exc}") from exc
        reg._next_version = max(next_version, last + 1)
        reg._cell_model[...] = cell_model.astype(np.int32)
        reg._measured_c[...] = measured
        reg._predicted_c[...] = predicted
        reg._count[...] = count
        reg._flag[...] = flag
        if terrain is not None:
            reg.check_grid(terrain)
        return reg


# ------------------------------------------------------------------ module helpers
def _relative_error(predicted: np.ndarray, measured: np.ndarray, count: np.ndarray) -> np.ndarray:
    predicted = np.asarray(predicted, dtype=np.float64)
    measured = np.asarray(measured, dtype=np.float64)
    diff = predicted - measured
    denom = np.abs(measured)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(denom > 0, diff / np.where(denom > 0, denom, 1.0), np.sign(diff) * np.inf)
    out = np.where((denom == 0) & (diff == 0), 0.0, out)
    return np.where(np.asarray(count) > 0, out, np.nan)


def _replaceable(target: Path) -> bool:
    """Whether ``target`` may be replaced by :meth:`CellModelRegistry.save`."""
    if not target.is_dir():
        return False
    return (target / _REGISTRY_FILE).is_file() or not any(target.iterdir())


def _recover_interrupted_save(target: Path) -> None:
    """Move back the registry a crashed :meth:`CellModelRegistry.save` left aside (see ``load``)."""
    holders = sorted(target.parent.glob(f".{target.name}.*.old"), key=lambda p: p.stat().st_mtime, reverse=True)
    for holder in holders:
        old = holder / target.name
        if (old / _REGISTRY_FILE).is_file():
            os.rename(old, target)
            _fsync_dir(target.parent)
            shutil.rmtree(holder, ignore_errors=True)
            warnings.warn(
                f"registry {str(target)!r} was missing after an interrupted save; restored the previous "
                f"version from {str(holder)!r}",
                RecoveryWarning,
                stacklevel=3,
            )
            return


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms without directory handles
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


def _read_npz(path: Path) -> dict[str, np.ndarray]:
    return read_versioned_npz(path, magic=_MAGIC, version=REGISTRY_FORMAT_VERSION, what="cell-model registry")


def _read_history(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise FileFormatError(f"registry history {str(path)!r} is missing")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise FileFormatError(f"registry history {str(path)!r} is corrupt: {exc}") from exc
    if not isinstance(data, dict) or data.get("format") != _HISTORY_MAGIC:
        raise FileFormatError(f"{str(path)!r} is not a terrawatt registry history")
    check_format_version(data.get("format_version"), REGISTRY_FORMAT_VERSION, "registry history", path)
    return data
