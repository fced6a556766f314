"""ResultCache: a small least-recently-used mapping for results derived from an edge cost."""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from typing import Any

__all__ = ["ResultCache", "CACHE_SIZE"]

#: Default entries of an EnergyCost's per-query result cache; the least recently used are dropped.
CACHE_SIZE = 64


class ResultCache(OrderedDict):
    """A small least-recently-used mapping (at most ``maxsize`` entries) for results cached on a cost."""

    def __init__(self, maxsize: int = CACHE_SIZE) -> None:
        super().__init__()
        self.maxsize = maxsize

    def __getitem__(self, key: Any) -> Any:
        value = super().__getitem__(key)
        self.move_to_end(key)
        return value

    def get(self, key: Any, default: Any = None) -> Any:
        return self[key] if key in self else default

    def __setitem__(self, key: Any, value: Any) -> None:
        super().__setitem__(key, value)
        self.move_to_end(key)
        while len(self) > self.maxsize:
            self.popitem(last=False)

    def get_or_make(self, key: Any, make: Callable[[], Any]) -> Any:
        """The result cached under ``key``, or ``make()`` computed, cached and returned."""
        if key in self:
            return self[key]
        value = make()
        self[key] = value
        return value
