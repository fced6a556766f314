"""Energy reachability: equal to single lattice routes, obstacles, budgets, round trips, files, figure and CLI."""

from __future__ import annotations

import math

import numpy as np
import pytest
from reach_samples import DEPOT, hilly_cost, hilly_reach, one_way_cost  # noqa: F401  (fixtures)
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

import terrain
from planner import EnergyCost, Lattice, reachability
from planner.cost_spec import CostSpec
from planner.reachability import lattice_move_energies
from terrawatt_base.errors import BlockedPositionError, InvalidParameterError, OutOfBoundsError


def _sample_cells(cost: EnergyCost, n: int, seed: int = 0) -> list[tuple[int, int]]:
    rng = np.random.default_rng(seed)
    rows, cols = cost.shape
    return [(int(rng.integers(rows)), int(rng.integers(cols))) for _ in range(n)]


def _centre(cost: EnergyCost, r: int, c: int) -> tuple[float, float]:
    x, y = cost.terrain.xy(r, c)
    return float(x), float(y)


# ---------------------------------------------------------------- equal to single routes
def test_forward_energy_equals_the_lattice_planners_route_at_sampled_cells(hilly_cost, hilly_reach):
    lat = Lattice(hilly_cost, stride_cells=1)
    through_lattice = 0
    for r, c in _sample_cells(hilly_cost, 25):
        goal = _centre(hilly_cost, r, c)
        path = lat.shortest_path(DEPOT, goal)
        fwd = hilly_reach.forward_energy_j[r, c]
        if not path.found:
            assert fwd == math.inf
            continue
        # the lattice query also tries the straight depot-goal segment; the field is the lattice's
        direct = float(hilly_cost.segment_energy_j(np.array(DEPOT), np.array(goal))[0])
        assert min(fwd, direct) == pytest.approx(path.objective, rel=1e-9)
        assert fwd >= path.objective * (1 - 1e-9)
        through_lattice += fwd < direct
    assert through_lattice >= 10  # most samples are routes through the lattice, not the straight line


def test_round_trip_equals_the_route_there_plus_the_route_back(hilly_cost, hilly_reach):
    lat = Lattice(hilly_cost, stride_cells=1)
    for r, c in _sample_cells(hilly_cost, 15, seed=1):
        cell = _centre(hilly_cost, r, c)
        there = lat.shortest_path(DEPOT, cell)
        back = lat.shortest_path(cell, DEPOT)
        rt = hilly_reach.round_trip_energy_j[r, c]
        if not (there.found and back.found):
            assert rt == math.inf
            continue
        direct_back = float(hilly_cost.segment_energy_j(np.array(cell), np.array(DEPOT))[0])
        assert min(hilly_reach.back_energy_j[r, c], direct_back) == pytest.approx(back.objective, rel=1e-9)
    np.testing.assert_array_equal(hilly_reach.round_trip_energy_j,
                                  hilly_reach.forward_energy_j + hilly_reach.back_energy_j)


def test_every_cell_equals_scipy_dijkstra_on_the_lattice_graph_and_its_transpose(hilly_cost, hilly_reach):
    lat = Lattice(hilly_cost, stride_cells=1)
    g = lat.graph("energy")
    n = lat.n_nodes
    xy = lat.node_xy(np.arange(n))
    near = np.flatnonzero(np.hypot(xy[:, 0] - DEPOT[0], xy[:, 1] - DEPOT[1]) <= 1.5)
    out_j = hilly_cost.segment_energy_j(np.broadcast_to(DEPOT, (near.size, 2)), xy[near])
    back_j = hilly_cost.segment_energy_j(xy[near], np.broadcast_to(DEPOT, (near.size, 2)))
    for graph, links, raster in ((g, out_j, hilly_reach.forward_energy_j), (g.T.tocsr(), back_j,
                                                                           hilly_reach.back_energy_j)):
        ok = np.isfinite(links)
        rows = np.concatenate([graph.tocoo().row, np.full(ok.sum(), n)])
        cols = np.concatenate([graph.tocoo().col, near[ok]])
        data = np.concatenate([graph.tocoo().data, links[ok]])
        ext = csr_matrix((data, (rows, cols)), shape=(n + 1, n + 1))
        expected = dijkstra(ext, directed=True, indices=n)[:n].reshape(hilly_cost.shape)
        np.testing.assert_allclose(raster, expected, rtol=1e-9)
        assert np.array_equal(np.isinf(raster), np.isinf(expected))


def test_a_ramp_too_steep_to_climb_is_reached_only_from_above():
    # Rises 0.12 along +x; every lattice move gaining x climbs at least 0.12 / sqrt(5) = 0.054 (a knight
    # move), above the 0.05 the ground allows: the robot cannot gain height, even by switchbacks.
    tmap = terrain.ramp_map((12, 40), 1.0, grade=0.12)
    cost = one_way_cost(tmap, max_uphill_grade=0.05)
    low = reachability(cost, (2.5, 6.5), round_trip=True)
    assert np.all(np.isfinite(low.forward_energy_j[:, :3])) and np.all(np.isinf(low.forward_energy_j[:, 3:]))
    high = reachability(cost, (39.5, 6.5), round_trip=True)  # the top column
    assert np.all(np.isfinite(high.forward_energy_j))  # everything is downhill or level from the top
    assert np.all(np.isinf(high.round_trip_energy_j[:, :39]))  # but nothing below comes back up
    assert not high.reachable[:, :39].any() and high.reachable[:, 39].all()
    # a ground that climbs 0.1 switchbacks up the same ramp (knight moves climb 0.054)
    zigzag = reachability(one_way_cost(tmap, max_uphill_grade=0.1), (2.5, 6.5))
    assert np.all(np.isfinite(zigzag.forward_energy_j))


# ---------------------------------------------------------------- obstacles and geometry
def test_obstacle_cells_and_cells_cut_off_are_inf(hilly_cost, hilly_reach, wall_map):
    blocked = hilly_cost.blocked
    assert blocked.any()
    for raster in (hilly_reach.forward_energy_j, hilly_reach.back_energy_j, hilly_reach.round_trip_energy_j):
        assert np.all(np.isinf(raster[blocked]))
    assert not hilly_reach.reachable[blocked].any()
    closed = np.array(wall_map.obstacle)
    closed[:, 20] = True  # close the gap: the east half is cut off
    tmap = terrain.TerrainMap(wall_map.elevation_m, 1.0, ground=wall_map.ground, ground_names=wall_map.ground_names,
                              obstacle=closed)
    reach = reachability(CostSpec().build(tmap), (5.5, 5.5), round_trip=True)
    assert np.all(np.isinf(reach.forward_energy_j[:, 21:])) and np.all(np.isinf(reach.back_energy_j[:, 21:]))
    assert np.all(np.isfinite(reach.forward_energy_j[:, :20]))
    assert reach.reachable_area_m2 == 40 * 20


def test_flat_ground_costs_the_same_both_ways_and_grows_with_distance(flat_map):
    cost = CostSpec().build(flat_map)
    reach = reachability(cost, (7.25, 4.75), round_trip=True)
    np.testing.assert_allclose(reach.forward_energy_j, reach.back_energy_j, rtol=1e-12)
    r, c = flat_map.rowcol(7.25, 4.75)
    row = reach.forward_energy_j[r, c:]
    assert np.all(np.diff(row) > 0)  # farther east along the row costs more
    assert reach.farthest_reachable_m == pytest.approx(math.hypot(14.75 - 7.25, 9.75 - 4.75))  # the far corner cell


def test_on_a_ramp_uphill_costs_more_than_downhill(ramp_map):
    cost = CostSpec().build(ramp_map)
    depot = (10.25, 5.25)
    reach = reachability(cost, depot, round_trip=True)
    r, c = ramp_map.rowcol(*depot)
    up, down = reach.forward_energy_j[r, c + 12], reach.forward_energy_j[r, c - 12]  # 6 m east (uphill), west
    assert up > 1.5 * down
    # coming back from the uphill cell is downhill: cheaper than going there
    assert reach.back_energy_j[r, c + 12] < up
    assert reach.back_energy_j[r, c - 12] > down


def test_round_trip_is_at_least_the_way_out(hilly_reach):
    finite = np.isfinite(hilly_reach.round_trip_energy_j)
    assert finite.sum() > 1000
    assert np.all(hilly_reach.round_trip_energy_j[finite] >= hilly_reach.forward_energy_j[finite])
    assert np.all(np.isinf(hilly_reach.forward_energy_j[~finite]) | np.isinf(hilly_reach.back_energy_j[~finite]))


# ---------------------------------------------------------------- budgets
def test_budget_mask_is_monotone_in_the_budget_and_the_reserve_shrinks_it(hilly_cost):
    full = reachability(hilly_cost, DEPOT, round_trip=True)
    top = float(np.max(full.round_trip_energy_j[np.isfinite(full.round_trip_energy_j)]))
    previous = np.zeros(hilly_cost.shape, bool)
    areas = []
    for frac in (0.05, 0.2, 0.5, 0.8, 1.0):
        reach = reachability(hilly_cost, DEPOT, budget_j=frac * top, round_trip=True)
        assert np.all(reach.reachable[previous])  # every cell reachable on a smaller budget still is
        assert np.array_equal(reach.reachable, full.round_trip_energy_j <= frac * top)
        previous = reach.reachable
        areas.append(reach.reachable_area_m2)
    assert areas == sorted(areas) and areas[0] < areas[-1]
    assert np.array_equal(previous, np.isfinite(full.round_trip_energy_j))
    kept = reachability(hilly_cost, DEPOT, budget_j=top, reserve_j=0.5 * top, round_trip=True)
    assert np.array_equal(kept.reachable, full.round_trip_energy_j <= 0.5 * top)
    one_way = reachability(hilly_cost, DEPOT, budget_j=0.5 * top)
    assert one_way.reachable_area_m2 > kept.reachable_area_m2  # one way goes farther on the same energy
    assert one_way.back_energy_j is None and one_way.round_trip_energy_j is None


def test_move_energies_are_cached_on_the_cost(flat_map):
    cost = CostSpec().build(flat_map)
    w, first_s = lattice_move_energies(cost)
    again, cached_s = lattice_move_energies(cost)
    assert again is w and cached_s == 0.0 and first_s > 0.0
    assert w.shape == (flat_map.shape[0] * flat_map.shape[1], 16) and not w.flags.writeable
    assert reachability(cost, (3.0, 3.0)).graph_time_s == 0.0


# ---------------------------------------------------------------- bad input
def test_depot_in_an_obstacle_or_outside_the_map_is_a_clear_error(wall_map):
    cost = CostSpec().build(wall_map)
    with pytest.raises(BlockedPositionError, match=r"depot \(20\.5, 5\.0\) m lies on a blocked cell"):
        reachability(cost, (20.5, 5.0))
    with pytest.raises(OutOfBoundsError, match="depot point .* outside the map"):
        reachability(cost, (41.0, 5.0))
    with pytest.raises(InvalidParameterError, match="depot_xy_m must be finite"):
        reachability(cost, (math.nan, 5.0))
    with pytest.raises(InvalidParameterError, match="depot_xy_m must be one point"):
        reachability(cost, [(1.0, 1.0), (2.0, 2.0)])
    with pytest.raises(InvalidParameterError, match="depot_xy_m must have shape"):
        reachability(cost, (1.0, 2.0, 3.0))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"budget_j": 0.0}, "budget_j"),
        ({"budget_j": -5.0}, "budget_j"),
        ({"budget_j": math.nan}, "budget_j"),
        ({"budget_j": "lots"}, "budget_j"),
        ({"budget_j": 100.0, "reserve_j": -1.0}, "reserve_j"),
        ({"budget_j": 100.0, "reserve_j": 100.0}, "reserve_j must be below budget_j"),
        ({"reserve_j": 10.0}, "needs a budget_j"),
        ({"round_trip": "yes"}, "round_trip"),
    ],
)
def test_bad_budgets_and_flags_are_refused(flat_map, kwargs, message):
    cost = CostSpec().build(flat_map)
    with pytest.raises(InvalidParameterError, match=message):
        reachability(cost, (3.0, 3.0), **kwargs)


def test_a_cost_that_is_not_an_energy_cost_is_refused(flat_map):
    with pytest.raises(InvalidParameterError, match="cost must be an EnergyCost"):
        reachability(flat_map, (3.0, 3.0))
    with pytest.raises(InvalidParameterError, match="cost must be an EnergyCost"):
        lattice_move_energies("cost")
