"""Atomic writes: complete file or the old one, readable permissions, no temporary left."""

from __future__ import annotations

import json
import math
import stat

import numpy as np
import pytest

from terrawatt_base.atomic import FILE_MODE, atomic_open, atomic_path, json_finite, write_json_atomic, write_text_atomic


def _leftovers(directory):
    return sorted(p.name for p in directory.iterdir() if p.name.startswith("."))


def test_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "data.txt"
    write_text_atomic(target, "old")
    with pytest.raises(RuntimeError, match="disk full"), atomic_open(target, "w") as fh:
        fh.write("half of the new")
        raise RuntimeError("disk full")
    assert target.read_text() == "old"
    assert _leftovers(tmp_path) == []


def test_written_file_is_complete_with_readable_permissions(tmp_path):
    target = tmp_path / "sub" / "dir" / "plot.bin"  # parents are created
    with atomic_path(target) as tmp:
        assert tmp.parent == target.parent and tmp != target
        tmp.write_bytes(b"\x00" * 1000)
    assert target.read_bytes() == b"\x00" * 1000
    assert stat.S_IMODE(target.stat().st_mode) == FILE_MODE
    assert _leftovers(target.parent) == []


def test_json_is_strict_with_numpy_values_and_non_finite_as_null(tmp_path):
    target = write_json_atomic(
        tmp_path / "r.json", {"a": np.arange(3), "b": np.float32(1.5), "c": math.nan, "d": [math.inf, 2.0]}
    )
    text = target.read_text()
    assert "NaN" not in text and "Infinity" not in text
    assert json.loads(text) == {"a": [0, 1, 2], "b": 1.5, "c": None, "d": [None, 2.0]}


def test_atomic_open_refuses_read_modes(tmp_path):
    with pytest.raises(ValueError, match="write mode"), atomic_open(tmp_path / "x", "r"):
        pass


def test_json_of_something_unserialisable_is_a_parameter_error_and_writes_nothing(tmp_path):
    from terrain import InvalidParameterError

    target = tmp_path / "x.json"
    with pytest.raises(InvalidParameterError, match="cannot be written as JSON"):
        write_json_atomic(target, {"a": object()})
    assert not target.exists() and list(tmp_path.iterdir()) == []


def test_json_finite_turns_nan_into_null_and_tuples_into_lists():
    assert json_finite({"a": (1.0, math.nan), "b": [math.inf, {"c": 2}]}) == {"a": [1.0, None], "b": [None, {"c": 2}]}
