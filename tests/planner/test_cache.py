"""Tests of planner.cache: ResultCache keeps the most recently used entries."""

from __future__ import annotations

from planner.cache import CACHE_SIZE, ResultCache


def test_the_least_recently_used_entry_is_dropped():
    cache = ResultCache(maxsize=2)
    cache["a"] = 1
    cache["b"] = 2
    assert cache["a"] == 1  # "a" is now the most recently used
    cache["c"] = 3
    assert list(cache) == ["a", "c"] and "b" not in cache


def test_get_counts_as_a_use_and_has_a_default():
    cache = ResultCache(maxsize=2)
    cache["a"], cache["b"] = 1, 2
    assert cache.get("a") == 1 and cache.get("missing") is None and cache.get("missing", 5) == 5
    cache["c"] = 3
    assert list(cache) == ["a", "c"]


def test_setting_a_key_again_refreshes_it_and_the_default_size():
    cache = ResultCache(maxsize=2)
    cache["a"], cache["b"] = 1, 2
    cache["a"] = 10
    cache["c"] = 3
    assert dict(cache) == {"a": 10, "c": 3}
    assert ResultCache().maxsize == CACHE_SIZE == 64
