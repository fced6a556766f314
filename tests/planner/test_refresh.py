"""Tests of table-only refreshes: EnergyCost.with_tables and Lattice.refreshed equal fresh builds."""

from __future__ import annotations

import numpy as np
import pytest

from planner import CostTables, EnergyCost, Lattice
from terrain import InvalidParameterError, TerrainMap
from terrain.procedural import procedural_map


def _tables(n_rows: int, n_grade: int = 33, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    grades = np.linspace(-0.4, 0.4, n_grade)
    base = 40.0 + 10.0 * np.arange(n_rows)[:, None]
    grade = scale * (base + 300.0 * np.maximum(grades, 0.0)[None, :])
    turn = np.tile(np.linspace(0.0, 30.0, 9), (n_rows, 1))
    return grade, turn


def _cost(seed: int = 0, shape: tuple[int, int] = (40, 48)) -> EnergyCost:
    tmap = procedural_map(shape, 1.0, seed=seed, grounds=("a", "b", "c"), obstacle_fraction=0.03)
    grade, turn = _tables(3)
    return EnergyCost(tmap, np.asarray(tmap.ground), CostTables(grade, turn), speed_mps=0.5, max_slope_rad=np.arctan(0.4), battery_voltage_v=24.0, turn_rate_radps=0.5)


def _assert_same_lattice(got: Lattice, ref: Lattice) -> None:
    """Exactly the same directed graph (structure and weights), and the same answers to queries."""
    for weight in ("energy", "length"):
        g, r = got.graph(weight), ref.graph(weight)
        assert g.shape == r.shape
        assert np.array_equal(g.indptr, r.indptr) and np.array_equal(g.indices, r.indices)
        assert np.array_equal(g.data, r.data)  # exact, not approx
    assert got.n_edges == ref.n_edges
    for start, goal in (((2.5, 3.5), (44.5, 36.5)), ((40.5, 2.5), (3.5, 30.5)), ((20.2, 20.7), (30.1, 5.3))):
        a = got.shortest_path(start, goal)
        b = ref.shortest_path(start, goal)
        assert a.found == b.found and a.objective == b.objective and np.array_equal(a.waypoints_m, b.waypoints_m)


def _fresh(old: EnergyCost, grade: np.ndarray, turn: np.ndarray, rows: np.ndarray) -> EnergyCost:
    return EnergyCost(old.terrain, rows, CostTables(grade, turn), speed_mps=old.speed_mps, max_slope_rad=old.max_slope_rad, battery_voltage_v=old.battery_voltage_v, turn_rate_radps=old.turn_rate_radps)


@pytest.mark.parametrize("stride", [1, 2])
def test_refreshed_weights_equal_fresh_build_exactly(stride):
    cost = _cost()
    lat = Lattice.for_cost(cost, stride)
    grade, turn = _tables(3)
    grade[1] *= 1.7  # one ground's model changed
    new = cost.with_tables(CostTables(grade, turn))
    ref = Lattice(_fresh(cost, grade, turn, cost.ground_rows), stride)
    got = Lattice.for_cost(new, stride)
    assert got is not lat and got.cost is new
    _assert_same_lattice(got, ref)
    assert got.shortest_path((2.5, 3.5), (44.5, 36.5)).found
    assert np.array_equal(new.changed_cells, (cost.ground_rows == 1) & ~cost.blocked)
    assert new.min_energy_per_metre_j == _fresh(cost, grade, turn, cost.ground_rows).min_energy_per_metre_j
    # the old cost and lattice are untouched
    _assert_same_lattice(Lattice.for_cost(cost, stride), Lattice(cost, stride))


def test_unchanged_rows_are_not_recomputed():
    cost = _cost()
    lat = Lattice.for_cost(cost, 1)
    grade, turn = _tables(3)
    same = cost.with_tables(CostTables(grade, turn))
    assert Lattice.for_cost(same, 1).edges_computed == 0 and not same.changed_cells.any()
    # one free cell moves to a changed row: only the moves whose cell box holds it are recomputed
    r, c = 20, 24
    assert not cost.blocked[r, c]
    rows = cost.ground_rows.copy()
    grade4, turn4 = np.vstack([grade, 2.0 * grade[:1]]), np.vstack([turn, turn[:1]])
    rows[r, c] = 3
    one = cost.with_tables(CostTables(grade4, turn4), rows)
    got = Lattice.for_cost(one, 1)
    ni, nj = cost.shape
    expected = 0
    for i in range(ni):
        for j in range(nj):
            for di, dj in ((0, 1), (1, 0), (1, 1), (1, -1), (1, 2), (2, 1), (2, -1), (1, -2)):
                ti, tj = i + di, j + dj
                if 0 <= ti < ni and 0 <= tj < nj and min(i, ti) <= r <= max(i, ti) and min(j, tj) <= c <= max(j, tj):
                    expected += 2
    assert got.edges_computed == expected
    assert 0 < got.edges_computed < lat.edges_computed / 100
    _assert_same_lattice(got, Lattice(_fresh(cost, grade4, turn4, rows), 1))


def test_renumbered_rows_with_equal_content_count_as_unchanged():
    cost = _cost()
    Lattice.for_cost(cost, 1)
    grade, turn = _tables(3)
    perm = np.array([2, 0, 1])  # old row k is new row perm[k]
    new = cost.with_tables(CostTables(grade[np.argsort(perm)], turn[np.argsort(perm)]), perm[cost.ground_rows])
    assert not new.changed_cells.any() and Lattice.for_cost(new, 1).edges_computed == 0
    assert np.array_equal(new.segment_energy_j([[1.5, 1.5]], [[40.5, 30.5]]),
                          cost.segment_energy_j([[1.5, 1.5]], [[40.5, 30.5]]))


def test_edges_appearing_or_vanishing_rebuild_the_structure():
    cost = _cost()
    lat = Lattice.for_cost(cost, 1)
    grade, turn = _tables(3)
    grade[2, grade.shape[1] // 2 + 3:] = np.inf  # ground "c" can no longer be driven uphill
    new = cost.with_tables(CostTables(grade, turn))
    got = Lattice.for_cost(new, 1)
    ref = Lattice(_fresh(cost, grade, turn, cost.ground_rows), 1)
    assert got.n_edges == ref.n_edges < lat.n_edges
    _assert_same_lattice(got, ref)


def test_refresh_errors():
    cost = _cost()
    grade, turn = _tables(3, n_grade=17)
    with pytest.raises(InvalidParameterError, match="grade samples"):
        cost.with_tables(CostTables(grade, turn))
    grade, turn = _tables(3)
    with pytest.raises(InvalidParameterError, match="grade_table_j_per_m must hold"):
        cost.with_tables(CostTables(-grade, turn))
    with pytest.raises(InvalidParameterError, match="ground_rows must hold"):
        cost.with_tables(CostTables(grade[:2], turn[:2]))
    lat = Lattice(cost, 1)
    flat = TerrainMap(np.zeros(cost.shape), 1.0)
    other = EnergyCost(flat, np.zeros(cost.shape, int), CostTables(grade[:1], turn[:1]), speed_mps=0.5, max_slope_rad=cost.max_slope_rad, battery_voltage_v=24.0, turn_rate_radps=0.5)
    with pytest.raises(InvalidParameterError, match="geometry"):
        lat.refreshed(other, np.zeros(cost.shape, bool))
    with pytest.raises(InvalidParameterError, match="changed_cells"):
        lat.refreshed(cost.with_tables(CostTables(grade, turn)), np.zeros((3, 3), bool))


def test_graph_is_a_copy_and_names_its_weight():
    from terrain import UnknownNameError

    lat = Lattice(_cost(), 1)
    g = lat.graph()
    g.data[:] = 0.0
    assert lat.graph().data.min() > 0
    with pytest.raises(UnknownNameError, match="weight"):
        lat.graph("time")


@pytest.mark.parametrize("stride", [1, 2])
def test_refresh_reports_exactly_the_moves_whose_energy_changed(stride):
    cost = _cost(seed=1)
    lat = Lattice.for_cost(cost, stride)
    assert lat.changed_moves is None
    grade, turn = _tables(3)
    grade[1] *= 0.6  # cheaper
    grade[2, grade.shape[1] // 2 + 3:] = np.inf  # and edges vanish: the structure is rebuilt
    for g in (grade, _tables(3)[0] * np.array([[1.0], [1.3], [1.0]])):
        new = Lattice.for_cost(cost.with_tables(CostTables(g, turn)), stride)
        before, after = lat.move_energies_j(), new.move_energies_j()
        assert before.shape == (lat.n_nodes, 16)
        expected = np.flatnonzero(before.ravel() != after.ravel())
        assert expected.size > 0 and np.array_equal(new.changed_moves, expected)
        assert np.array_equal(new.changed_moves_since(lat), expected)
        assert np.array_equal(lat.changed_moves_since(new), expected)  # compared move by move
        assert np.array_equal(new.move_energies_j(expected), after.ravel()[expected])
    assert Lattice.for_cost(cost.with_tables(CostTables(*_tables(3))), stride).changed_moves.size == 0
    assert lat.changed_moves_since(lat).size == 0


def test_move_energies_match_the_graph():
    lat = Lattice(_cost(), 1)
    g = lat.graph()
    w = lat.move_energies_j()
    u = 200
    assert np.array_equal(np.sort(w[u][np.isfinite(w[u])]), np.sort(g.data[g.indptr[u]:g.indptr[u + 1]]))
    assert np.isfinite(w).sum() == lat.n_edges
    with pytest.raises(InvalidParameterError, match="same grid"):
        lat.changed_moves_since(Lattice(_cost(), 2))


def test_chained_refreshes_of_small_patches_equal_fresh_builds_and_leave_their_ancestors_alone():
    cost = _cost(seed=2)
    lat = Lattice.for_cost(cost, 1)
    reference = [(cost, lat.move_energies_j())]
    grade, turn = _tables(3)
    rows = cost.ground_rows.copy()
    chain = [lat]
    for step, (r, c) in enumerate(((3, 4), (20, 30), (21, 31), (35, 2), (10, 40))):
        rows = rows.copy()
        rows[r:r + 3, c:c + 3] = 3 + step  # a new table row on a 3 x 3 patch
        grade = np.vstack([grade, (1.5 + 0.2 * step) * grade[:1]])
        turn = np.vstack([turn, turn[:1]])
        new_cost = reference[-1][0].with_tables(CostTables(grade, turn), rows)
        got = Lattice.for_cost(new_cost, 1)
        # only the slice of the recomputed moves is held: the moves read through it
        moves = got.changed_moves
        fresh = Lattice(new_cost, 1).move_energies_j().ravel()
        assert moves.size and np.array_equal(got.move_energies_j(moves), fresh[moves])
        chain.append(got)
        reference.append((new_cost, None))
    for (c, _), got in reversed(list(zip(reference[1:], chain[1:]))):  # made whole in any order
        _assert_same_lattice(got, Lattice(_fresh(c, c.tables.grade_table_j_per_m, c.tables.turn_table_j, c.ground_rows), 1))
    assert np.array_equal(chain[0].move_energies_j(), reference[0][1])  # the first lattice never changes
