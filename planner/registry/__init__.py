"""Per-cell current-model registry: which model serves each cell, its observed error, updates.

A :class:`CellModelRegistry` is bound to one grid (``rows x cols``, optionally with the
cell size and origin of a :class:`~terrain.grid.Grid`). It keeps

- a **model table**: models added with :meth:`~CellModelRegistry.add_model` get an integer
  id, a unique name and string/number metadata. Model id ``0`` is the *prior* given to the
  constructor (the physics model or a model trained elsewhere); every cell starts on it.
  Many cells share one model.
- a **cell map** (``int32`` model id per cell), changed only by
  :meth:`~CellModelRegistry.assign`, an accepted :meth:`~CellModelRegistry.propose_update`
  or :meth:`~CellModelRegistry.rollback`. Each change is a :class:`RegistryVersion` in
  :attr:`~CellModelRegistry.history` that remembers the previous id of every cell it
  touched, so a rollback restores the exact previous assignment.
- per-cell **evidence** (:attr:`~CellModelRegistry.evidence`, a
  :class:`~planner.registry.evidence.CellEvidence`): measured and predicted charge
  (integrated current, C) and a sample count, accumulated by its ``record``, from which its
  ``relative_error`` and, under an :class:`UpdatePolicy` (threshold, minimum evidence,
  hysteresis), its ``flagged`` and ``flagged_regions`` say which cells need new data.

The registry holds models through :class:`CurrentModelProtocol` and never calls them: the
caller predicts, fits and validates, and passes the numbers in; saving and loading models go
through caller-provided functions. So this package imports nothing from ``energy`` nor from the
rest of ``planner`` (it lives here, beside its users: the learned edge costs and the navigator).

How it is built (one idea per module, composed in :mod:`~planner.registry.registry`):

- :mod:`~planner.registry.records` — the value types: the model protocol, the update
  policy, model records, history versions, update decisions, flagged regions.
- :mod:`~planner.registry.cells` — cell selections (mask, ``(rows, cols)``, region) as flat
  indices, checked against the grid.
- :mod:`~planner.registry.table` — :class:`~planner.registry.table.ModelTable`, models by id.
- :mod:`~planner.registry.assignment` — :class:`~planner.registry.assignment.CellAssignment`,
  the cell map, its numbered versions and exact rollback.
- :mod:`~planner.registry.evidence` — :class:`~planner.registry.evidence.CellEvidence`,
  charges, counts, flags with hysteresis and flagged regions: the registry's
  :attr:`~CellModelRegistry.evidence`, which its callers use directly.
- :mod:`~planner.registry.store` — the directory format, atomic save, load, and recovery
  of a save killed between its two renames.
- :mod:`~planner.registry.registry` — :class:`CellModelRegistry`, a facade that owns one of
  each part (composition), checks the caller's arguments, converts cell selections, and
  keeps the parts consistent: a cell whose model changes loses its evidence.
"""

from .evidence import CellEvidence
from .records import (
    PRIOR_MODEL_ID,
    CurrentModelProtocol,
    FlaggedRegion,
    ModelEntry,
    RegistryVersion,
    UpdateDecision,
    UpdatePolicy,
)
from .registry import CellModelRegistry
from .store import REGISTRY_FORMAT_VERSION

__all__ = [
    "CellModelRegistry",
    "CellEvidence",
    "CurrentModelProtocol",
    "UpdatePolicy",
    "FlaggedRegion",
    "RegistryVersion",
    "UpdateDecision",
    "ModelEntry",
    "REGISTRY_FORMAT_VERSION",
    "PRIOR_MODEL_ID",
]
