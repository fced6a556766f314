"""Tests of planner.replan: the incremental (D* Lite) lattice search equals a full search after every change."""

from __future__ import annotations

import numpy as np
import pytest

from planner import CostTables, EnergyCost, IncrementalPlanner, Lattice, plan_route
from planner.heading_lattice import heading_shortest_path
from terrain import BlockedPositionError, InvalidParameterError, OutOfBoundsError, TerrainMap
from terrain.procedural import procedural_map

N_ROWS = 3  # ground classes of the test maps


def _tables(scale: np.ndarray | None = None, n_grade: int = 33) -> tuple[np.ndarray, np.ndarray]:
    grades = np.linspace(-0.4, 0.4, n_grade)
    base = 40.0 + 10.0 * np.arange(N_ROWS)[:, None]
    grade = base + 300.0 * np.maximum(grades, 0.0)[None, :] - 20.0 * np.minimum(grades, 0.0)[None, :]
    if scale is not None:
        grade = grade * np.asarray(scale, dtype=float)[:, None]
    turn = np.tile(np.linspace(0.0, 30.0, 9), (grade.shape[0], 1))
    return grade, turn


def _cost(seed: int, shape: tuple[int, int] = (36, 44), obstacle_fraction: float = 0.05) -> EnergyCost:
    tmap = procedural_map(shape, 1.0, seed=seed, grounds=("a", "b", "c"), obstacle_fraction=obstacle_fraction)
    grade, turn = _tables()
    return EnergyCost(tmap, np.asarray(tmap.ground), CostTables(grade, turn), speed_mps=0.5, max_slope_rad=np.arctan(0.4), battery_voltage_v=24.0, turn_rate_radps=0.5)


def _free_point(cost: EnergyCost, rng: np.random.Generator) -> tuple[float, float]:
    """A random point of a free cell: its centre (a lattice node at stride 1: a join of 0 J) or off it."""
    free = np.argwhere(~cost.blocked)
    r, c = free[rng.integers(len(free))]
    x, y = cost.terrain.xy(r, c)
    if rng.random() < 0.5:
        return float(x), float(y)
    return float(x + rng.uniform(-0.4, 0.4)), float(y + rng.uniform(-0.4, 0.4))


def _check_equal(planner: IncrementalPlanner, start: tuple[float, float], stride: int) -> None:
    """The incremental answer equals a fresh lattice's full search on the current cost (over heading, drive and
    turns, or heading-free, as the planner searches)."""
    got = planner.plan(start)
    fresh = Lattice(planner.cost, stride)
    goal = tuple(planner.goal_xy_m)
    ref = heading_shortest_path(fresh, start, goal) if planner.heading else fresh.shortest_path(start, goal)
    assert got.found == ref.found
    if ref.found:
        assert got.objective == pytest.approx(ref.objective, rel=1e-9)
        if planner.heading:  # the price every route reports, turns included
            assert planner.cost.path_energy_j(got.waypoints_m) == pytest.approx(got.objective, rel=1e-9)
        # the route's own energy (its joins and moves) is the objective it reports
        assert got.waypoints_m[0].tolist() == list(start) and np.allclose(got.waypoints_m[-1], planner.goal_xy_m)
    else:
        assert got.objective == np.inf and got.waypoints_m.shape == (0, 2)


def _updates(cost: EnergyCost, rng: np.random.Generator) -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]:
    """A random sequence of table updates: (kind, grade table, turn table, ground rows)."""
    base_rows = np.asarray(cost.ground_rows)
    out = []
    for kind in ("class", "cells", "class", "blocked", "unblocked", "cells", "patch"):
        grade, turn = _tables(rng.uniform(0.4, 1.8, N_ROWS))
        rows = base_rows.copy()
        if kind in ("cells", "patch"):  # a few cells, or a square patch, move to an extra table row
            if kind == "cells":
                idx = rng.integers(0, rows.size, size=int(rng.integers(1, 12)))
                rows.ravel()[idx] = N_ROWS
            else:
                r, c = rng.integers(0, rows.shape[0] - 6), rng.integers(0, rows.shape[1] - 6)
                rows[r:r + 6, c:c + 6] = N_ROWS
            extra = grade[:1] * rng.choice([0.3, 3.0])
            grade, turn = np.vstack([grade, extra]), np.vstack([turn, turn[:1]])
        elif kind == "blocked":  # a ground can no longer be driven steeply uphill: edges vanish
            grade[int(rng.integers(N_ROWS)), grade.shape[1] // 2 + 2:] = np.inf
        out.append((kind, grade, turn, rows))
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("stride", [1, 2])
@pytest.mark.parametrize("heading, refresh_share", [(True, IncrementalPlanner.REFRESH_SHARE), (True, np.inf),
                                                    (False, IncrementalPlanner.REFRESH_SHARE)])
def test_incremental_replans_equal_full_searches_after_random_updates(seed, stride, heading, refresh_share,
                                                                      monkeypatch):
    """``refresh_share`` inf: the heading planner's heuristic is never computed again, only kept valid."""
    monkeypatch.setattr(IncrementalPlanner, "REFRESH_SHARE", refresh_share)
    rng = np.random.default_rng(100 * seed + stride)
    cost = _cost(seed)
    goal = _free_point(cost, rng)
    planner = IncrementalPlanner(Lattice.for_cost(cost, stride), goal, heading=heading)
    for _ in range(3):  # a moving start, no change of energies
        _check_equal(planner, _free_point(cost, rng), stride)
    for kind, grade, turn, rows in _updates(cost, rng):
        new = planner.cost.with_tables(CostTables(grade, turn), rows)
        lat = Lattice.for_cost(new, stride)
        if kind == "blocked":
            assert lat.n_edges < Lattice(cost, stride).n_edges  # the structure changed
        planner.update(lat)
        assert planner.lattice is lat and planner.cost is new
        for _ in range(2):
            _check_equal(planner, _free_point(cost, rng), stride)


def test_update_from_a_lattice_that_skipped_versions_and_back():
    rng = np.random.default_rng(7)
    cost = _cost(3)
    planner = IncrementalPlanner(Lattice.for_cost(cost, 1), _free_point(cost, rng))
    start = _free_point(cost, rng)
    _check_equal(planner, start, 1)
    mid = cost.with_tables(CostTables(*_tables([1.0, 2.5, 1.0])))
    last = mid.with_tables(CostTables(*_tables([0.5, 2.5, 1.0])))
    planner.update(Lattice.for_cost(last, 1))  # two refreshes at once: compared move by move
    _check_equal(planner, start, 1)
    planner.update(Lattice.for_cost(cost, 1))  # back to the first energies
    _check_equal(planner, start, 1)
    same = planner.update(Lattice.for_cost(cost, 1))
    assert same is planner and planner.touched <= 2 * 9  # only the goal's joins were looked at


def test_a_repair_far_from_the_route_expands_little():
    cost = _cost(4, shape=(60, 60), obstacle_fraction=0.0)
    start, goal = (5.5, 30.5), (54.5, 30.5)
    planner = IncrementalPlanner(Lattice.for_cost(cost, 1), goal, heading=False)  # the incremental (D* Lite) search
    planner.plan(start)
    first = planner.expanded
    rows = np.asarray(cost.ground_rows).copy()
    rows[:3, :3] = N_ROWS  # a corner far from the route becomes more expensive
    grade, turn = _tables()
    new = cost.with_tables(CostTables(np.vstack([grade, 2.0 * grade[:1]]), np.vstack([turn, turn[:1]])), rows)
    planner.update(Lattice.for_cost(new, 1))
    _check_equal(planner, start, 1)
    assert 0 < planner.touched < 100 and planner.expanded < first / 10


def test_unreachable_goal_is_not_found_like_shortest_path():
    obstacle = np.zeros((20, 30), bool)
    obstacle[:, 15] = True  # a wall across the map
    tmap = TerrainMap(np.zeros((20, 30)), 1.0, obstacle=obstacle)
    grade, turn = _tables()
    cost = EnergyCost(tmap, np.zeros((20, 30), int), CostTables(grade, turn), speed_mps=0.5, battery_voltage_v=24.0, turn_rate_radps=0.5)
    lat = Lattice(cost, 1)
    planner = IncrementalPlanner(lat, (25.5, 10.5))
    got, ref = planner.plan((3.5, 4.5)), lat.shortest_path((3.5, 4.5), (25.5, 10.5))
    assert not got.found and not ref.found and got.objective == ref.objective == np.inf
    assert planner.route((3.5, 4.5)).status == "infeasible"
    assert planner.plan((20.5, 4.5)).found  # the goal's side is still reachable
    # a start on the wall: no joins, nothing found (shortest_path's answer); route() refuses it
    assert not planner.plan((15.5, 4.5)).found and not lat.shortest_path((15.5, 4.5), (25.5, 10.5)).found
    with pytest.raises(BlockedPositionError, match="start_xy_m"):
        planner.route((15.5, 4.5))


def test_route_equals_plan_route_lattice():
    rng = np.random.default_rng(11)
    cost = _cost(5)
    goal = _free_point(cost, rng)
    planner = IncrementalPlanner(Lattice.for_cost(cost, 1), goal)
    for _ in range(2):
        start = _free_point(cost, rng)
        got = planner.route(start, seed=3)
        ref = plan_route(cost.terrain, start, goal, cost=cost, planner="lattice", seed=3)
        assert got.status == ref.status and got.planner == ref.planner
        if ref.status == "exact":
            assert got.energy_j == pytest.approx(ref.energy_j, rel=1e-9)
    assert planner.route(start, refine=False).planner == "lattice"


def test_the_heading_planner_reuses_an_answer_only_while_nothing_changed():
    rng = np.random.default_rng(3)
    cost = _cost(6)
    goal, start = _free_point(cost, rng), _free_point(cost, rng)
    planner = IncrementalPlanner(Lattice.for_cost(cost, 1), goal)
    first = planner.plan(start)
    assert planner.plan(start).objective == first.objective  # reused
    dearer = cost.with_tables(CostTables(*_tables([3.0, 3.0, 3.0])))
    planner.update(Lattice.for_cost(dearer, 1))
    again = planner.plan(start)
    assert again.objective == pytest.approx(heading_shortest_path(Lattice(dearer, 1), start, goal).objective, rel=1e-12)
    assert again.objective > first.objective


def test_bad_input():
    cost = _cost(0)
    lat = Lattice(cost, 1)
    with pytest.raises(InvalidParameterError, match="lattice must be a Lattice"):
        IncrementalPlanner(cost, (3.0, 3.0))
    with pytest.raises(OutOfBoundsError, match="goal_xy_m"):
        IncrementalPlanner(lat, (-5.0, 3.0))
    planner = IncrementalPlanner(lat, (30.5, 20.5))
    with pytest.raises(InvalidParameterError, match="start_xy_m"):
        planner.plan((np.nan, 3.0))
    with pytest.raises(OutOfBoundsError, match="start_xy_m"):
        planner.plan((3.0, 300.0))
    with pytest.raises(InvalidParameterError, match="same grid"):
        planner.update(Lattice(cost, 2))
    with pytest.raises(InvalidParameterError, match="lattice must be a Lattice"):
        planner.update(cost)
    with pytest.raises(InvalidParameterError, match="start equals goal"):
        planner.route((30.5, 20.5))
    with pytest.raises(InvalidParameterError, match="settings"):
        planner.route((3.5, 3.5), settings={"refine_rounds": 1})


def test_the_adaptive_loop_replans_incrementally_with_the_same_lattice_optimum(monkeypatch):
    import planner.missions.navigator as adaptive_module
    from energy import Battery, LinearCurrentModel, TruthSimulator, excitation_commands, ground_preset, robot_preset
    from planner import AdaptiveSettings, run_adaptive_mission
    from planner.missions import Navigator, NavigatorModels
    from planner.registry import CellModelRegistry

    robot = robot_preset("husky")
    truth = TruthSimulator(robot, {"asphalt": ground_preset("asphalt"), "sand": ground_preset("sand")}, seed=0)
    ground = np.zeros((16, 40), int)
    ground[4:12, 12:34] = 1
    tmap = TerrainMap(np.zeros((16, 40)), 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"})
    a = excitation_commands(20.0, speed_levels_mps=(0.2, 0.5, 0.8), omega_levels_radps=(0.0,), rest_s=0.0, seed=1)
    b = excitation_commands(8.0, speed_levels_mps=(0.0,), omega_levels_radps=(0.5,), omega_sign="both",
                            hold_s=(2.0, 3.0), rest_s=0.0, seed=2)
    prior = LinearCurrentModel().fit([truth.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="asphalt",
                                                              seed=3 + i) for i, p in enumerate((a, b))])
    calls = []
    route = IncrementalPlanner.route

    def checked_route(self, start_xy_m, **kwargs):
        path = self.plan(start_xy_m)  # the repaired search answers as a full search of the refreshed cost
        ref = Lattice(self.cost, 1).shortest_path(start_xy_m, tuple(self.goal_xy_m))
        assert path.objective == pytest.approx(ref.objective, rel=1e-9)
        calls.append(self.touched)
        return route(self, start_xy_m, **kwargs)

    monkeypatch.setattr(adaptive_module.IncrementalPlanner, "route", checked_route)
    res = run_adaptive_mission(Navigator(tmap, CellModelRegistry.from_terrain(tmap, prior), robot, Battery(20.0, 24.0),
                                         (37.5, 8.0),
                                         settings=AdaptiveSettings(leg_length_m=8.0, seed=0, max_updates=2),
                                         models=NavigatorModels(physics_ground=ground_preset("asphalt"))), truth, (2.5, 8.0))
    assert res.status == "completed" and res.accepted_updates >= 1
    assert len(calls) == len(res.replans) - 1 >= 1 and all(t > 0 for t in calls)  # every replan, after an update
