"""planner.registry.assignment: the cell map's numbered versions and exact rollback."""

from __future__ import annotations

import numpy as np
import pytest

from planner.registry import PRIOR_MODEL_ID
from planner.registry.assignment import CellAssignment
from terrain import InvalidParameterError


def test_every_cell_starts_on_the_prior_with_no_history():
    cells = CellAssignment((2, 3))
    assert cells.cell_model.dtype == np.int32 and np.all(cells.cell_model == PRIOR_MODEL_ID)
    assert (cells.version, cells.next_version, cells.history) == (0, 1, [])


def test_the_cell_map_is_a_read_only_copy():
    cells = CellAssignment((2, 3))
    view = cells.cell_model
    with pytest.raises(ValueError):
        view[0, 0] = 4
    cells.apply(np.array([0]), 1, kind="assign", reason="r")
    assert view[0, 0] == 0 and cells.model_at(0, 0) == 1


def test_apply_records_a_version_with_the_previous_ids_and_reports_changed_cells():
    cells = CellAssignment((2, 3))
    v1, changed = cells.apply(np.array([0, 4]), 1, kind="assign", reason="sand")
    assert (v1.version, v1.kind, v1.model_id, v1.cell_count, v1.reason) == (1, "assign", 1, 2, "sand")
    assert v1.rows.tolist() == [0, 1] and v1.cols.tolist() == [0, 1]
    assert v1.previous_model_ids.tolist() == [0, 0] and changed.tolist() == [0, 4]
    v2, changed = cells.apply(np.array([1, 4]), 1, kind="update", reason="snow", error_new=0.1, error_old=0.2)
    assert v2.previous_model_ids.tolist() == [0, 1]
    assert changed.tolist() == [1]  # cell 4 already had model 1
    assert (v2.validation_error_new, v2.validation_error_old) == (0.1, 0.2)
    assert cells.cell_model.tolist() == [[1, 1, 0], [0, 1, 0]]
    assert cells.model_ids_at(np.array([0, 2, 4])).tolist() == [1, 0, 1]
    assert [v.version for v in cells.history] == [1, 2] and cells.version == 2


def test_rollback_restores_each_earlier_state_exactly():
    cells = CellAssignment((2, 2))
    states = [cells.cell_model.copy()]
    for flat, model_id in ((np.array([0, 1]), 1), (np.array([1, 2]), 2), (np.array([0, 3]), 3)):
        cells.apply(flat, model_id, kind="assign", reason="")
        states.append(cells.cell_model.copy())
    undone, changed = cells.rollback()  # the newest
    assert [v.version for v in undone] == [3] and changed.tolist() == [0, 3]
    assert np.array_equal(cells.cell_model, states[2])
    undone, changed = cells.rollback(1)
    assert [v.version for v in undone] == [2] and changed.tolist() == [1, 2]
    assert np.array_equal(cells.cell_model, states[1])
    undone, _ = cells.rollback(0)
    assert [v.version for v in undone] == [1] and np.array_equal(cells.cell_model, states[0])
    assert cells.version == 0


def test_version_numbers_are_never_reused_after_a_rollback():
    cells = CellAssignment((1, 2))
    cells.apply(np.array([0]), 1, kind="assign", reason="")
    cells.rollback()
    version, _ = cells.apply(np.array([1]), 1, kind="assign", reason="")
    assert version.version == 2 and cells.next_version == 3


def test_rollback_errors():
    cells = CellAssignment((1, 2))
    with pytest.raises(InvalidParameterError, match="the history is empty; there is nothing to roll back"):
        cells.rollback()
    cells.apply(np.array([0]), 1, kind="assign", reason="")
    with pytest.raises(InvalidParameterError, match=r"version must be 0 or one of \[1\], got 5"):
        cells.rollback(5)
    with pytest.raises(InvalidParameterError, match="version"):
        cells.rollback(-1)


def test_restore_sets_a_saved_state():
    saved = CellAssignment((1, 3))
    saved.apply(np.array([2]), 4, kind="assign", reason="x")
    cells = CellAssignment((1, 3))
    cells.restore(saved.cell_model, saved.history, saved.next_version)
    assert cells.cell_model.tolist() == [[0, 0, 4]] and cells.version == 1 and cells.next_version == 2
    cells.rollback()
    assert cells.cell_model.tolist() == [[0, 0, 0]]
