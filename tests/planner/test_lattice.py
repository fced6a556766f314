"""Tests of planner.lattice: directed 16-connected lattice optimum, length weights, string pulling."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner import CostSpec, Lattice
from planner.lattice import LatticePath
from planner.refine import string_pull
from terrain import InvalidParameterError, TerrainMap, UnknownNameError


class _Robot:
    battery_voltage_v = 24.0
    turn_rate_radps = 0.5


class LinearModel:
    """Stand-in: e(s) = a + b * max(s, 0) J per metre travelled; turns c J/rad."""

    robot = _Robot()

    def __init__(self, a: float = 50.0, b: float = 400.0, c: float = 30.0) -> None:
        self.a, self.b, self.c = a, b, c

    def energy_per_metre_j(self, speed_mps, grade, ground):
        return self.a + self.b * np.maximum(np.asarray(grade, dtype=float), 0.0)

    def turn_energy_j(self, heading_change_rad, ground):
        return self.c * np.abs(np.asarray(heading_change_rad, dtype=float))


def _cost(elevation, obstacle=None, cell=1.0, **kw):
    elevation = np.asarray(elevation, dtype=float)
    tmap = TerrainMap(
        elevation, cell, ground=np.zeros(elevation.shape, int), ground_names={0: "g"}, obstacle=obstacle
    )
    return CostSpec(energy_model=LinearModel(**kw), grounds={"g": None}, speed_mps=0.5).build(tmap)


def test_flat_map_lattice_aligned_route_is_the_straight_line():
    cost = _cost(np.zeros((20, 30)))
    lat = Lattice(cost)
    for goal in [(25.5, 2.5), (20.5, 17.5), (12.5, 14.5)]:  # 0 deg, 45 deg, knight-move direction
        path = lat.shortest_path((2.5, 2.5), goal)
        assert path.found
        np.testing.assert_allclose(path.waypoints_m, [[2.5, 2.5], goal])
        assert path.objective == pytest.approx(50.0 * math.dist((2.5, 2.5), goal), rel=1e-12)


def test_off_lattice_direction_costs_at_most_the_16_connected_excess():
    cost = _cost(np.zeros((40, 40)))
    start, goal = (1.5, 1.5), (38.5, 9.5)  # 12.2 deg: between the 0 and 26.6 deg moves
    path = Lattice(cost).shortest_path(start, goal)
    straight = 50.0 * math.dist(start, goal)
    assert straight < path.objective <= straight / math.cos(math.radians(26.565 / 2)) + 1e-9
    assert np.isfinite(cost.segment_energy_j(path.waypoints_m[:-1], path.waypoints_m[1:])).all()


def test_directed_costs_uphill_differs_from_downhill():
    grade = 0.1
    x = (np.arange(40) + 0.5)
    cost = _cost(np.broadcast_to(grade * x, (10, 40)), a=50.0, b=400.0)
    lat = Lattice(cost)
    up = lat.shortest_path((2.5, 4.5), (37.5, 4.5))
    down = lat.shortest_path((37.5, 4.5), (2.5, 4.5))
    length = 35.0
    factor = math.sqrt(1 + grade**2)
    assert up.objective - down.objective == pytest.approx(400.0 * grade * length * factor, rel=1e-5)


def test_route_goes_through_the_gap_of_a_wall():
    obstacle = np.zeros((30, 30), bool)
    obstacle[:, 15] = True
    obstacle[24:27, 15] = False
    cost = _cost(np.zeros((30, 30)), obstacle=obstacle)
    path = Lattice(cost).shortest_path((3.5, 3.5), (26.5, 3.5))
    assert path.found
    wp = path.waypoints_m
    assert np.isfinite(cost.segment_energy_j(wp[:-1], wp[1:])).all()
    assert wp[:, 1].max() >= 24.0  # it had to climb up to the gap
    closed = obstacle.copy()
    closed[:, 15] = True
    none = Lattice(_cost(np.zeros((30, 30)), obstacle=closed)).shortest_path((3.5, 3.5), (26.5, 3.5))
    assert not none.found and none.waypoints_m.shape == (0, 2) and math.isinf(none.objective)


def test_length_weight_gives_path_length_and_string_pull_shortens():
    obstacle = np.zeros((30, 30), bool)
    obstacle[5:30, 15] = True
    cost = _cost(np.zeros((30, 30)), obstacle=obstacle)
    path = Lattice(cost).shortest_path((3.5, 20.5), (26.5, 20.5), weight="length")
    wp = path.waypoints_m
    assert path.objective == pytest.approx(np.hypot(*np.diff(wp, axis=0).T).sum(), rel=1e-12)
    pulled = string_pull(cost, wp)
    assert np.isfinite(cost.segment_energy_j(pulled[:-1], pulled[1:])).all()
    assert np.hypot(*np.diff(pulled, axis=0).T).sum() <= path.objective + 1e-9
    # Close to the taut string under the wall's end: start -> (15, 5) -> (16, 5) -> goal.
    taut = math.dist((3.5, 20.5), (15, 5)) + 1.0 + math.dist((16, 5), (26.5, 20.5))
    assert taut <= np.hypot(*np.diff(pulled, axis=0).T).sum() <= 1.03 * taut
    free = _cost(np.zeros((30, 30)))
    np.testing.assert_allclose(string_pull(free, wp), wp[[0, -1]])


def test_coarse_stride_lattice_finds_valid_route():
    cost = _cost(np.zeros((40, 40)))
    lat = Lattice(cost, stride_cells=4)
    assert lat.n_nodes == 100
    path = lat.shortest_path((1.2, 1.7), (37.9, 30.3))
    assert path.found
    np.testing.assert_allclose(path.waypoints_m[[0, -1]], [[1.2, 1.7], [37.9, 30.3]])
    assert path.objective >= 50.0 * math.dist((1.2, 1.7), (37.9, 30.3)) - 1e-9


def test_for_cost_caches_per_stride():
    cost = _cost(np.zeros((12, 12)))
    assert Lattice.for_cost(cost, 1) is Lattice.for_cost(cost, 1)
    assert Lattice.for_cost(cost, 2) is not Lattice.for_cost(cost, 1)


def test_bad_arguments():
    cost = _cost(np.zeros((12, 12)))
    with pytest.raises(InvalidParameterError, match="stride_cells"):
        Lattice(cost, stride_cells=0)
    with pytest.raises(InvalidParameterError, match="stride_cells"):
        Lattice(cost, stride_cells=12)
    with pytest.raises(InvalidParameterError, match="stride_cells must be an integer, got 'two'"):
        Lattice(cost, stride_cells="two")  # used to escape as a bare ValueError
    with pytest.raises(InvalidParameterError, match="start/goal must be a real number or an array of them"):
        Lattice(cost, 1).shortest_path(("a", "b"), (3.0, 3.0))
    with pytest.raises(UnknownNameError, match="weight"):
        Lattice(cost).shortest_path((1.0, 1.0), (5.0, 5.0), weight="time")
    with pytest.raises(InvalidParameterError, match="finite"):
        Lattice(cost).shortest_path((math.nan, 1.0), (5.0, 5.0))
    with pytest.raises(InvalidParameterError, match="found"):
        LatticePath(True, np.empty((0, 2)), 1.0, "energy", 0.0)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("weight", ["energy", "length"])
def test_astar_finds_the_same_optimum_as_the_scipy_dijkstra_of_paths_from(seed, weight):
    rng = np.random.default_rng(seed)
    elevation = np.cumsum(rng.normal(0.0, 0.04, (30, 40)), axis=1)  # rough: uphill != downhill
    obstacle = rng.random((30, 40)) < 0.1
    obstacle[:3, :3] = obstacle[-3:, -3:] = False
    lat = Lattice(_cost(elevation, obstacle=obstacle))
    for start, goal in (((1.5, 1.5), (38.5, 28.5)), ((38.5, 28.5), (1.5, 1.5)), ((1.5, 1.5), (2.5, 1.5))):
        a = lat.shortest_path(start, goal, weight)
        (d,) = lat.paths_from(start, [goal], weight)
        assert a.found and d.found
        assert a.objective == pytest.approx(d.objective, rel=1e-12)


def test_astar_and_dijkstra_agree_when_the_goal_is_walled_off():
    obstacle = np.zeros((20, 20), bool)
    obstacle[:, 10] = True  # a closed wall
    lat = Lattice(_cost(np.zeros((20, 20)), obstacle=obstacle))
    for path in (lat.shortest_path((2.5, 2.5), (17.5, 17.5)), *lat.paths_from((2.5, 2.5), [(17.5, 17.5)])):
        assert not path.found and math.isinf(path.objective)
