"""The registry's value types: the model protocol, the update policy and its results."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Literal, Protocol, Union, runtime_checkable

import numpy as np

from terrawatt_base.checks import check_int, check_real
from terrawatt_base.errors import InvalidParameterError

__all__ = [
    "PRIOR_MODEL_ID",
    "MetaValue",
    "Cells",
    "CurrentModelProtocol",
    "UpdatePolicy",
    "ModelEntry",
    "FlaggedRegion",
    "RegistryVersion",
    "UpdateDecision",
]

#: Model id of the prior, the model every cell starts on.
PRIOR_MODEL_ID = 0

#: A metadata value of a model: a string or a finite number.
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





# --------------------------------------------------------------------------- results
@dataclass(frozen=True, kw_only=True)
class UpdatePolicy:
    """When a cell's observed error says its model needs new data.

    A cell's error is the relative error of integrated current over the samples recorded
    there, ``(predicted - measured) / |measured|`` (see :meth:`CellEvidence.relative_error` of
    :attr:`CellModelRegistry.evidence`); the policy compares its magnitude, in per cent, with
    the threshold.

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
        :meth:`CellEvidence.flagged_regions` leaves out connected regions with fewer
        flagged cells than this (>= 1; the cells stay flagged in :meth:`CellEvidence.flagged`).

    Raises
    ------
    InvalidParameterError
        Non-finite or out-of-range values.

    Examples
    --------
    >>> from planner.registry import UpdatePolicy
    >>> UpdatePolicy(threshold_pct=10.0, min_samples=20, hysteresis_pct=3.0).clear_below_pct
    7.0
    """

    threshold_pct: float = 10.0
    min_samples: int = 10
    hysteresis_pct: float = 2.0
    min_region_cells: int = 1

    def __post_init__(self) -> None:
        owner = "UpdatePolicy"
        threshold = check_real("threshold_pct", self.threshold_pct, low=0.0, low_inclusive=False, owner=owner)
        hysteresis = check_real("hysteresis_pct", self.hysteresis_pct, low=0.0, owner=owner)
        if hysteresis >= threshold:
            raise InvalidParameterError(
                f"UpdatePolicy.hysteresis_pct must be >= 0 and < threshold_pct ({threshold!r}), "
                f"got {self.hysteresis_pct!r}"
            )
        object.__setattr__(self, "threshold_pct", threshold)
        object.__setattr__(self, "hysteresis_pct", hysteresis)
        object.__setattr__(self, "min_samples", check_int("min_samples", self.min_samples, low=1, owner=owner))
        object.__setattr__(
            self, "min_region_cells", check_int("min_region_cells", self.min_region_cells, low=1, owner=owner)
        )

    @property
    def clear_below_pct(self) -> float:
        """Error (%) below which a flagged cell is cleared: ``threshold_pct - hysteresis_pct``."""
        return self.threshold_pct - self.hysteresis_pct


@dataclass(frozen=True, eq=False)
class ModelEntry:
    """One entry of the model table: id, unique name and metadata (the model itself is
    returned by :meth:`CellModelRegistry.model`)."""

    model_id: int
    name: str
    meta: Mapping[str, MetaValue] = field(default_factory=lambda: MappingProxyType({}))


@dataclass(frozen=True, eq=False)
class FlaggedRegion:
    """A connected region of flagged cells (from :meth:`CellEvidence.flagged_regions`).

    A region can be passed wherever the registry accepts cells (``assign``,
    ``propose_update``, ``evidence.reset``).

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


#: Cells as the registry accepts them: a boolean mask of the grid's shape, a
#: ``(rows, cols)`` tuple of integer arrays, or a :class:`FlaggedRegion`.
Cells = Union[np.ndarray, tuple[Any, Any], FlaggedRegion]
