"""The heading lattice: its A* equals scipy's Dijkstra over the same state graph, and its optimum is the reported price."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from energy import ground_preset, robot_preset
from planner import CostTables, EnergyCost, Lattice, plan_route
from planner.cost_spec import CostSpec
from planner.heading_lattice import (
    HEADING_COUNT,
    HeadingWorkspace,
    heading_cost_to_go,
    heading_shortest_path,
    lower_cost_to_go,
    move_turn_angles,
)
from planner.kernels.heading import backward_cost_to_go
from planner.lattice import LATTICE_OFFSETS
from planner.route import evaluate_route
from terrain import example_map, procedural_map
from terrawatt_base.errors import InvalidParameterError, UnknownNameError


def _turn_family():
    """benchmarks/turn_family.py: the issue's seeded robot family, shared with the benchmark."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "benchmarks" / "turn_family.py"
    spec = importlib.util.spec_from_file_location("turn_family", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def family_cost(tmap, seed: int) -> EnergyCost:
    family = _turn_family()
    robot, lateral = family.robot_family(seed)
    return family.family_cost(tmap, robot, lateral)


def _free_points(cost, rng, n):
    free = np.argwhere(~cost.blocked)
    xc, yc = cost.terrain.cell_centres()
    picks = free[rng.choice(len(free), size=2 * n, replace=False)]
    jitter = rng.uniform(-0.3, 0.3, size=(2 * n, 2)) * cost.terrain.cell_size_m
    pts = np.column_stack([xc[picks[:, 1]], yc[picks[:, 0]]]) + jitter
    return [(tuple(pts[2 * k]), tuple(pts[2 * k + 1])) for k in range(n)]


def scipy_optimum(lattice, start, goal) -> float:
    """The reference the compiled A* is checked against: scipy's Dijkstra over the explicit state graph
    (``16 x`` the heading-free graph: small maps only), or the route of no lattice move if cheaper; inf: none.
    Plus the start from rest and the stop at rest, which every route between the two points pays."""
    return _state_graph_optimum(lattice, start, goal) + lattice.cost.start_and_stop_j(start, goal)


def _state_graph_optimum(lattice, start, goal) -> float:
    from planner.heading_lattice import _no_move_route, _Query

    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    q = _Query(lattice, start, goal)
    best, _ = _no_move_route(lattice.cost, q, start, goal)
    if not (q.src.size and q.dst.size):
        return best
    n, nj = lattice.n_nodes, lattice._nj
    ns = n * HEADING_COUNT
    moves = lattice.move_energies_j()  # (n, 16), inf: no move
    u, k = np.nonzero(np.isfinite(moves))
    v = u + LATTICE_OFFSETS[k, 0] * nj + LATTICE_OFFSETS[k, 1]
    h = np.arange(HEADING_COUNT)
    # arcs (u, h) -> (v, k) for every heading h of u
    tail = (u[:, None] * HEADING_COUNT + h[None, :]).ravel()
    head = np.repeat(v * HEADING_COUNT + k, HEADING_COUNT)
    weight = (q.turn[q.node_row[u][:, None], h[None, :], k[:, None]] + moves[u, k][:, None]).ravel()
    # the virtual start (state ns) enters (v, k) from a start-joined node; the virtual goal is ns + 1
    si, sk = np.nonzero(np.isfinite(moves[q.src]))
    sv = q.src[si] + LATTICE_OFFSETS[sk, 0] * nj + LATTICE_OFFSETS[sk, 1]
    s_weight = q.e_src[si] + q.turn_src[si, sk] + moves[q.src[si], sk]
    g_tail = (q.dst[:, None] * HEADING_COUNT + h[None, :]).ravel()
    rows = np.concatenate([tail, np.full(si.size, ns), g_tail])
    cols = np.concatenate([head, sv * HEADING_COUNT + sk, np.full(g_tail.size, ns + 1)])
    w = np.concatenate([weight, s_weight, q.exit_cost.ravel()])
    # scipy keeps the smallest of duplicate (row, col) entries only via an explicit reduction
    order = np.lexsort((w, cols, rows))
    rows, cols, w = rows[order], cols[order], w[order]
    first = np.concatenate([[True], (np.diff(rows) != 0) | (np.diff(cols) != 0)])
    graph = csr_matrix((w[first], (rows[first], cols[first])), shape=(ns + 2, ns + 2))
    return min(best, float(dijkstra(graph, directed=True, indices=ns)[ns + 1]))


def test_the_turn_between_two_moves_is_their_heading_change():
    ang = move_turn_angles()
    assert ang.shape == (HEADING_COUNT, HEADING_COUNT)
    np.testing.assert_allclose(np.diag(ang), 0.0)
    np.testing.assert_allclose(ang[np.arange(8), np.arange(8) + 8], math.pi)  # a move and its reverse
    np.testing.assert_allclose(ang[0, 2], math.pi / 4)  # east, then north-east (row +1, col +1)
    np.testing.assert_allclose(ang, ang.T)


@pytest.mark.parametrize("seed", range(6))
def test_astar_equals_the_scipy_dijkstra_over_the_state_graph_and_the_price_of_its_route(seed):
    rng = np.random.default_rng(100 + seed)
    tmap = procedural_map((26, 34), 1.0, seed=seed)
    cost = family_cost(tmap, seed)
    lattice = Lattice(cost, stride_cells=1 + seed % 2)
    for start, goal in _free_points(cost, rng, 3):
        fast = heading_shortest_path(lattice, start, goal)
        ref = scipy_optimum(lattice, start, goal)
        assert fast.found == math.isfinite(ref)
        if not fast.found:
            continue
        assert fast.objective == pytest.approx(ref, rel=1e-9, abs=1e-9)
        # the optimum is exactly what a route is priced at: its drive and its turns
        assert cost.path_energy_j(fast.waypoints_m) == pytest.approx(fast.objective, rel=1e-9)
        # and no heading-free lattice route priced with its turns is cheaper
        free = lattice.shortest_path(start, goal, weight="energy")
        assert free.objective <= fast.objective * (1 + 1e-12)
        assert fast.objective <= cost.path_energy_j(free.waypoints_m) * (1 + 1e-12)


def test_a_slow_turning_robot_trades_drive_energy_for_fewer_turns():
    tmap = procedural_map((40, 40), 1.0, seed=3)
    husky = robot_preset("husky")
    grounds = {g: ground_preset(g) for g in set(tmap.ground_names.values())}
    slow = CostSpec(robot=husky.replace(turn_rate_radps=0.02), grounds=grounds, speed_mps=0.5).build(tmap)
    lattice = Lattice(slow, 1)
    start, goal = (2.5, 3.0), (36.0, 31.5)
    free = lattice.shortest_path(start, goal)
    heading = heading_shortest_path(lattice, start, goal)
    _, free_turns = slow.turn_energies_j(free.waypoints_m)
    _, turns = slow.turn_energies_j(heading.waypoints_m)
    assert turns.sum() < free_turns.sum()  # fewer or gentler turns ...
    assert heading.objective < slow.path_energy_j(free.waypoints_m)  # ... for less energy in all


def test_direct_and_single_node_routes_are_candidates():
    tmap = procedural_map((20, 20), 1.0, seed=1)
    cost = CostSpec().build(tmap)
    lattice = Lattice(cost, 1)
    start = (5.5, 5.5)
    path = heading_shortest_path(lattice, start, (6.2, 5.9))  # neighbours: the straight segment
    assert path.found and path.waypoints_m.shape == (2, 2)
    assert path.objective == pytest.approx(cost.path_energy_j(path.waypoints_m))


@pytest.mark.parametrize("seed", range(4))
def test_the_min_energy_route_costs_no_more_than_the_shortest_or_the_heading_free_route(seed):
    """The issue's family on the bundled map and procedural maps (the benchmark runs 20 maps)."""
    rng = np.random.default_rng(seed)
    tmap = example_map() if seed == 0 else procedural_map((48, 48), 1.0, seed=seed)
    cost = family_cost(tmap, seed)
    for start, goal in _free_points(cost, rng, 2):
        route = plan_route(tmap, start, goal, cost=cost, planner="lattice", compare=True)
        if route.status != "exact":
            continue
        free = Lattice.for_cost(cost, 1).shortest_path(start, goal)
        assert route.energy_j <= route.shortest_energy_j * (1 + 1e-9)
        assert route.energy_j <= evaluate_route(cost, free.waypoints_m).energy_j * (1 + 1e-9)
        assert route.optimality_ratio <= 1.0 + 1e-9  # refined from the heading lattice's optimum


def test_refinement_never_returns_repeated_waypoints():
    from planner.refine import drop_repeats

    pts = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [2.0, 1.0], [3.0, 1.0], [3.0, 1.0]])
    np.testing.assert_array_equal(drop_repeats(pts), [[0, 0], [1, 0], [2, 1], [3, 1]])
    clean = pts[[0, 1, 3]]
    assert drop_repeats(clean) is clean


def test_each_planner_says_what_its_search_minimised():
    from planner.planning import PLANNERS, search_objective

    assert search_objective("lattice").startswith("drive and turn energy")
    for name in PLANNERS:
        if name != "lattice":
            assert search_objective(name).startswith("drive energy (a search without heading cannot see turns)")
    with pytest.raises(UnknownNameError):
        search_objective("dijkstra")


def _exact_cost_to_go(lattice, goal):
    """Each node's heading-free cost to ``goal`` (an unbounded backward Dijkstra), and the goal's joins."""
    dst, e_dst = lattice.joins(np.asarray(goal, float), to_point=True)
    return backward_cost_to_go(lattice._pos, lattice._energy_data(), LATTICE_OFFSETS, lattice._ni, lattice._nj,
                               dst, e_dst, math.inf), dst, e_dst


def _assert_consistent_lower_bound(h, lattice, goal):
    exact, dst, e_dst = _exact_cost_to_go(lattice, goal)
    assert np.all(h <= exact * (1 + 1e-12) + 1e-9)  # a lower bound of the cost-to-go (inf: unreachable)
    moves = lattice.move_energies_j()
    u, k = np.nonzero(np.isfinite(moves))
    v = u + LATTICE_OFFSETS[k, 0] * lattice._nj + LATTICE_OFFSETS[k, 1]
    assert np.all(h[u] <= moves[u, k] + h[v] + 1e-9)  # consistent along every move
    assert np.all(h[dst] <= e_dst + 1e-9)  # and on the goal's joins


@pytest.mark.parametrize("seed", range(4))
def test_a_kept_cost_to_go_stays_a_consistent_lower_bound_through_rises_and_drops(seed):
    """The replanner's heuristic after updates: lowered where moves got cheaper, kept where dearer; the A* with it
    (and a reused workspace) still finds the heading optimum."""
    rng = np.random.default_rng(500 + seed)
    tmap = procedural_map((30, 38), 1.0, seed=seed, obstacle_fraction=0.04)
    cost = family_cost(tmap, seed)
    lattice = Lattice(cost, 1)
    (start, goal), = _free_points(cost, rng, 1)
    h = heading_cost_to_go(lattice, start, goal)
    _assert_consistent_lower_bound(h, lattice, goal)
    ws = HeadingWorkspace(lattice.n_nodes)
    lowered = 0
    route = heading_shortest_path(lattice, start, goal)
    for step in range(6):
        rows = np.asarray(cost.ground_rows).copy()
        # a patch about a point of the route (where the bound is exact), or anywhere
        x, y = route.waypoints_m[rng.integers(len(route.waypoints_m))] if step < 3 else (np.inf, np.inf)
        r, c = (np.clip(np.array(cost.terrain.rowcol(x, y)) - 4, 0, np.array(rows.shape) - 8) if np.isfinite(x)
                else (rng.integers(0, rows.shape[0] - 8), rng.integers(0, rows.shape[1] - 8)))
        rows[r:r + 8, c:c + 8] = cost.tables.grade_table_j_per_m.shape[0]  # a patch moves to a new table row
        factor = (0.2, 4.0)[step % 2]  # cheaper, then dearer ground
        grade = np.vstack([cost.tables.grade_table_j_per_m, factor * cost.tables.grade_table_j_per_m[:1]])
        turn = np.vstack([cost.tables.turn_table_j, cost.tables.turn_table_j[:1]])
        new = cost.with_tables(CostTables(grade, turn), rows)
        new_lattice = Lattice(new, 1)
        lowered += lower_cost_to_go(h, new_lattice, new_lattice.changed_moves_since(lattice), goal)
        cost, lattice = new, new_lattice
        _assert_consistent_lower_bound(h, lattice, goal)
        s = _free_points(cost, rng, 1)[0][0]
        got = heading_shortest_path(lattice, s, goal, cost_to_go=h, workspace=ws)
        ref = scipy_optimum(lattice, s, goal)
        assert got.found == math.isfinite(ref)
        if got.found:
            assert got.objective == pytest.approx(ref, rel=1e-9)
        assert np.all(np.isinf(ws.g)) and np.all(ws.pred == -2) and not ws.closed.any() and np.all(ws.where == -1)
    assert lowered > 0  # the cheaper patches lowered the bound somewhere


def test_a_cost_to_go_or_workspace_of_another_lattice_is_refused():
    tmap = procedural_map((20, 24), 1.0, seed=1)
    cost = family_cost(tmap, 1)
    lattice = Lattice(cost, 1)
    start, goal = (3.5, 3.5), (18.5, 15.5)
    with pytest.raises(InvalidParameterError, match="cost_to_go"):
        heading_shortest_path(lattice, start, goal, cost_to_go=np.zeros(5))
    with pytest.raises(InvalidParameterError, match="workspace"):
        heading_shortest_path(lattice, start, goal, workspace=HeadingWorkspace(7))


@pytest.mark.parametrize("seed", range(3))
def test_the_last_answer_bounds_the_next_search_along_the_drive(seed):
    """A workspace keeps the last answer: re-priced from where the moved start joins it (the same price on an
    unchanged lattice), it bounds the next A*, whose answer still equals scipy's Dijkstra after energies change."""
    from planner.heading_lattice import _incumbent, _Query

    rng = np.random.default_rng(700 + seed)
    tmap = procedural_map((30, 38), 1.0, seed=seed, obstacle_fraction=0.12)  # obstacles: routes of lattice moves, not the direct segment
    cost = family_cost(tmap, seed)
    lattice = Lattice(cost, 1)
    ws = HeadingWorkspace(lattice.n_nodes)
    for start, goal in sorted(_free_points(cost, rng, 12), key=lambda p: -math.dist(*p)):
        first = heading_shortest_path(lattice, start, goal, workspace=ws)
        if ws.incumbent.size >= 8:
            break  # a lattice route of many moves to drive along (not the direct segment)
    assert first.found and ws.incumbent.size >= 8
    bound, nodes = _incumbent(lattice, _Query(lattice, np.asarray(start), np.asarray(goal)), ws.incumbent)
    bound += cost.start_and_stop_j(start, goal)  # the search's objective leaves out the ends, the price holds them
    assert bound == pytest.approx(first.objective, rel=1e-9) and nodes == list(ws.incumbent)
    chain = ws.incumbent.copy()
    used = 0
    for step in range(min(5, (chain.size - 2) // 2)):
        # drive along the first route, then a patch across it gets cheaper or dearer
        s = tuple(lattice.node_xy(chain[2 * step + 2:2 * step + 3])[0] + rng.uniform(-0.2, 0.2, 2))
        rows = np.asarray(cost.ground_rows).copy()
        r, c = np.clip(np.array(cost.terrain.rowcol(*s)) - 3, 0, np.array(rows.shape) - 6)
        rows[r:r + 6, c:c + 6] = cost.tables.grade_table_j_per_m.shape[0]
        grade = np.vstack([cost.tables.grade_table_j_per_m, (0.3, 3.0)[step % 2] * cost.tables.grade_table_j_per_m[:1]])
        cost = cost.with_tables(CostTables(grade, np.vstack([cost.tables.turn_table_j, cost.tables.turn_table_j[:1]])), rows)
        lattice = Lattice(cost, 1)
        q = _Query(lattice, np.asarray(s), np.asarray(goal))
        used += math.isfinite(_incumbent(lattice, q, ws.incumbent)[0])
        got = heading_shortest_path(lattice, s, goal, workspace=ws)
        ref = scipy_optimum(lattice, s, goal)
        assert got.found == math.isfinite(ref)
        if got.found:
            assert got.objective == pytest.approx(ref, rel=1e-9)
            assert lattice.cost.path_energy_j(got.waypoints_m) == pytest.approx(got.objective, rel=1e-9)
    assert used >= 1  # the moved starts joined the last route: its price bounded the search
    q = _Query(lattice, np.asarray(start), np.asarray(goal))
    assert math.isfinite(_incumbent(lattice, q, chain)[0])
    chain[1] = chain[0] + 3 * lattice._nj  # no lattice move between the first two nodes
    assert _incumbent(lattice, q, chain) == (math.inf, [])


def test_a_search_that_pays_each_stop_turns_less_often():
    """The stop-turn-go tables (a stop, a ramped pivot and a start per turn) against the same map with steady pivots:
    the heading lattice's optimum on the stop-turn-go cost turns no more often, and less often somewhere."""
    from planner.tables import turn_grid

    fewer = 0
    for seed in range(4):
        tmap = procedural_map((40, 48), 1.0, seed=seed, obstacle_fraction=0.1)
        driven = CostSpec().build(tmap)
        steady_turns = np.array([driven.physics_model.turn_energy_j(turn_grid(driven.tables.turn_table_j.shape[1]), g)
                                 for g in driven.ground_params])
        steady = driven.with_tables(CostTables(driven.tables.grade_table_j_per_m, steady_turns))
        start, goal = (2.5, 2.5), (44.5, 36.5)
        turns = []
        for cost in (driven, steady):
            path = heading_shortest_path(Lattice(cost, 1), start, goal)
            assert path.found
            turns.append(int(np.count_nonzero(cost.turn_energies_j(path.waypoints_m)[0] > 1e-6)))
        assert turns[0] <= turns[1], seed
        fewer += turns[0] < turns[1]
    assert fewer >= 1
