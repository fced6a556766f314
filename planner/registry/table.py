"""The registry's model table: models by integer id, each with a unique name and metadata."""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterator, Mapping
from types import MappingProxyType
from typing import Any

from terrawatt_base.checks import check_text
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from .records import CurrentModelProtocol, MetaValue, ModelEntry

__all__ = ["ModelTable", "check_meta"]


def check_meta(meta: Mapping[str, MetaValue] | None) -> Mapping[str, MetaValue]:
    """Model metadata as a read-only mapping of non-empty strings to strings or finite numbers.

    Raises
    ------
    InvalidParameterError
        Not a mapping; an empty or non-string key; a value that is not a str, int or finite float.
    """
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


def _check_model(name: str, model: object) -> None:
    if not isinstance(model, CurrentModelProtocol):
        raise InvalidParameterError(
            f"{name} must have fit() and predict() methods (CurrentModelProtocol), got {type(model).__name__}"
        )


class ModelTable:
    """Models by id (0, 1, 2, ... in the order added), each with a unique name and metadata.

    Models are only added, never removed: a rolled-back version's model stays in the table.

    Examples
    --------
    >>> class Const:
    ...     def fit(self, *a, **k): return self
    ...     def predict(self, n): return [1.0] * n
    >>> table = ModelTable()
    >>> table.add(Const(), name="physics"), table.add(Const(), name="snow", meta={"epochs": 40})
    (0, 1)
    >>> table.id_of("snow"), dict(table.record(1).meta)
    (1, {'epochs': 40})
    """

    def __init__(self) -> None:
        self._models: dict[int, Any] = {}
        self._records: dict[int, ModelEntry] = {}

    def __len__(self) -> int:
        return len(self._records)

    def __iter__(self) -> Iterator[ModelEntry]:
        return iter(self._records.values())

    @property
    def ids(self) -> tuple[int, ...]:
        """Ids of every model, in order."""
        return tuple(self._records)

    def check_new(
        self, model: object, name: str, meta: Mapping[str, MetaValue] | None, *, what: str = "model"
    ) -> Mapping[str, MetaValue]:
        """Check that ``model`` could be added as ``name`` (nothing is added); return clean metadata.

        ``what`` names the model argument in messages.

        Raises
        ------
        InvalidParameterError
            ``model`` lacks ``fit``/``predict``; empty or duplicate name; bad metadata.
        """
        _check_model(what, model)
        check_text("name", name)
        clean = check_meta(meta)
        if any(rec.name == name for rec in self._records.values()):
            raise InvalidParameterError(f"a model named {name!r} is already in the registry; names must be unique")
        return clean

    def add(self, model: CurrentModelProtocol, *, name: str, meta: Mapping[str, MetaValue] | None = None) -> int:
        """Add ``model`` under a unique ``name``; return its id (see :meth:`check_new` for errors)."""
        clean = self.check_new(model, name, meta)
        model_id = len(self._records)
        self._models[model_id] = model
        self._records[model_id] = ModelEntry(model_id, name, clean)
        return model_id

    def check_id(self, model_id: object) -> int:
        """``model_id`` as an ``int`` when it is in the table.

        Raises
        ------
        UnknownNameError
            No such id (or not an integer).
        """
        ok = isinstance(model_id, numbers.Integral) and not isinstance(model_id, bool)
        mid = int(model_id) if ok else None  # type: ignore[call-overload]
        if mid is None or mid not in self._records:
            raise UnknownNameError(f"no model with id {model_id!r}; known ids: {list(self._records)!r}")
        return mid

    def model(self, model_id: object) -> CurrentModelProtocol:
        """The model with id ``model_id`` (raises :class:`UnknownNameError` for an unknown id)."""
        return self._models[self.check_id(model_id)]

    def record(self, model_id: object) -> ModelEntry:
        """Id, name and metadata of a model (raises :class:`UnknownNameError` for an unknown id)."""
        return self._records[self.check_id(model_id)]

    def id_of(self, name: str) -> int:
        """Id of the model called ``name``.

        Raises
        ------
        UnknownNameError
            No model has that name.
        """
        for rec in self._records.values():
            if rec.name == name:
                return rec.model_id
        raise UnknownNameError(f"no model named {name!r}; known: {[r.name for r in self._records.values()]!r}")
