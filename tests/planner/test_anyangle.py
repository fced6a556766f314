"""Tests of planner.anyangle: Theta* on the energy objective in a corridor, its polish, planner="anyangle"."""

from __future__ import annotations

import math

import numpy as np
import pytest

from energy import PhysicsEnergyModel, ground_preset, robot_preset
from planner import PLANNERS, CostSpec, Lattice, PlannerSettings, plan_route
from planner.anyangle import AnyAnglePath, anyangle_path, polish_path
from terrain import BlockedPositionError, InvalidParameterError, OutOfBoundsError, TerrainMap
from terrain.procedural import procedural_map

GRAVITY_MPS2 = 9.80665


def _cost(tmap):
    model = PhysicsEnergyModel(robot_preset("husky"))
    grounds = {name: ground_preset(name) for name in tmap.ground_names.values()}
    return CostSpec(energy_model=model, grounds=grounds, speed_mps=0.5).build(tmap)


def _map(elevation, obstacle=None):
    elevation = np.asarray(elevation, dtype=float)
    return TerrainMap(
        elevation, 1.0, ground=np.zeros(elevation.shape, int), ground_names={0: "asphalt"}, obstacle=obstacle
    )


def _wall_map(gap=True, gap_rows=(40, 45)):
    obstacle = np.zeros((50, 80), bool)
    obstacle[:, 40] = True
    if gap:
        obstacle[gap_rows[0]:gap_rows[1], 40] = False
    return _map(np.zeros((50, 80)), obstacle)


def _crossed_cells(tmap, waypoints):
    """Rows and columns of every cell the polyline's segments cross."""
    rows, cols = [], []
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        r, c, _ = tmap.segment_cells(tuple(a), tuple(b))
        rows.append(r)
        cols.append(c)
    return np.concatenate(rows), np.concatenate(cols)


def _random_queries(cost, seed, n):
    """``n`` seeded start/goal pairs off the cell centres, in the largest free region."""
    labels = cost.components()
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    rr, cc = np.nonzero(labels == np.argmax(sizes))
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        i, j = rng.choice(rr.size, 2, replace=False)
        a = np.array(cost.terrain.xy(rr[i], cc[i])) + rng.uniform(-0.4, 0.4, 2)
        b = np.array(cost.terrain.xy(rr[j], cc[j])) + rng.uniform(-0.4, 0.4, 2)
        out.append((tuple(a), tuple(b)))
    return out


# --------------------------------------------------------------------------- flat plane: the straight line
@pytest.mark.parametrize("refine", [False, True])
@pytest.mark.parametrize("goal", [(55.0, 31.0), (57.3, 6.2), (21.7, 44.9)])  # 25, 3 and 71 deg: off the lattice
def test_flat_plane_route_is_the_straight_segment(refine, goal):
    tmap = _map(np.zeros((50, 60)))
    cost = _cost(tmap)
    start = (3.0, 4.0)
    route = plan_route(tmap, start, goal, cost=cost, planner="anyangle", refine=refine, compare=True)
    assert route.status == "exact"
    assert route.planner == ("anyangle+refine" if refine else "anyangle")
    np.testing.assert_allclose(route.waypoints_m, [start, goal], atol=1e-9)
    straight = float(cost.segment_energy_j(start, goal)[0])
    assert route.drive_energy_j == pytest.approx(straight, rel=1e-12)
    assert route.energy_j == pytest.approx(straight + cost.start_and_stop_j(start, goal), rel=1e-12)  # from rest to rest
    assert route.optimality_ratio <= 1.0 + 1e-12


def test_flat_plane_beyond_a_rock_is_a_taut_string():
    """Level ground with a round rock on the straight line: the route hugs the rock, at any angle."""
    yy, xx = np.mgrid[0:60, 0:90] + 0.5
    rock = (xx - 45.0) ** 2 + (yy - 30.0) ** 2 <= 6.0**2
    tmap = _map(np.zeros((60, 90)), rock)
    cost = _cost(tmap)
    start, goal = (4.2, 27.1), (86.3, 33.4)
    route = plan_route(tmap, start, goal, cost=cost, planner="anyangle", refine=False)
    assert route.status == "exact"
    # taut string around a disc of radius ~6.5 m (blocked cells reach past 6 m) between the two ends
    straight = math.dist(start, goal)
    assert straight < route.length_m < straight + 2.5
    lattice = Lattice.for_cost(cost, 1).shortest_path(start, goal)
    assert route.drive_energy_j < lattice.objective


# --------------------------------------------------------------------------- exact pricing, asymmetry
def test_route_energy_is_the_library_pricing_of_its_segments():
    tmap = procedural_map((80, 80), 1.0, seed=4, obstacle_fraction=0.04)
    cost = _cost(tmap)
    (start, goal), = _random_queries(cost, 4, 1)
    raw = anyangle_path(cost, start, goal)
    segments = cost.segment_energy_j(raw.waypoints_m[:-1], raw.waypoints_m[1:])
    assert raw.drive_energy_j == pytest.approx(float(segments.sum()), rel=1e-12)
    for refine in (False, True):
        route = plan_route(tmap, start, goal, cost=cost, planner="anyangle", refine=refine)
        assert route.energy_j == pytest.approx(cost.path_energy_j(route.waypoints_m), rel=1e-12)
        assert route.drive_energy_j == pytest.approx(
            float(cost.segment_energy_j(route.waypoints_m[:-1], route.waypoints_m[1:]).sum()), rel=1e-12)


def test_uphill_costs_more_than_the_way_back():
    grade = 0.1
    x = np.arange(60) + 0.5
    tmap = _map(np.broadcast_to(grade * x, (30, 60)))
    cost = _cost(tmap)
    a, b = (3.0, 4.0), (57.0, 25.0)
    up = plan_route(tmap, a, b, cost=cost, planner="anyangle")
    down = plan_route(tmap, b, a, cost=cost, planner="anyangle")
    potential_j = robot_preset("husky").mass_kg * GRAVITY_MPS2 * grade * (b[0] - a[0])
    assert up.energy_j - down.energy_j >= potential_j
    # a uniform ramp: the straight line both ways
    np.testing.assert_allclose(up.waypoints_m, [a, b], atol=1e-9)
    np.testing.assert_allclose(down.waypoints_m, [b, a], atol=1e-9)


def test_heuristic_is_a_lower_bound_of_the_route():
    tmap = procedural_map((80, 80), 1.0, seed=2)
    cost = _cost(tmap)
    for start, goal in _random_queries(cost, 2, 4):
        raw = anyangle_path(cost, start, goal)
        assert cost.lower_bound_j(start, goal)[0] <= raw.drive_energy_j


# --------------------------------------------------------------------------- random maps: against the lattice
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_on_random_maps_never_worse_than_the_lattice_and_never_through_a_blocked_cell(seed):
    tmap = procedural_map((96, 96), 1.0, seed=seed, obstacle_fraction=0.05, n_walls=1)
    cost = _cost(tmap)
    lattice = Lattice.for_cost(cost, 1)
    for start, goal in _random_queries(cost, seed, 4):
        raw_lattice = lattice.shortest_path(start, goal)
        assert raw_lattice.found
        exact = anyangle_path(cost, start, goal, guide_stride_cells=1)
        # the 1-cell guide is the lattice optimum itself: the answer is never dearer
        assert exact.drive_energy_j <= raw_lattice.objective * (1.0 + 1e-12)
        for settings in (PlannerSettings(), PlannerSettings(anyangle_guide_stride_cells=1)):
            raw = plan_route(tmap, start, goal, cost=cost, planner="anyangle", refine=False, settings=settings)
            polished = plan_route(tmap, start, goal, cost=cost, planner="anyangle", settings=settings)
            assert raw.status == polished.status == "exact"
            assert raw.drive_energy_j <= raw_lattice.objective * (1.0 + 1e-9)
            assert polished.energy_j <= raw.energy_j * (1.0 + 1e-9)
            for route in (raw, polished):
                np.testing.assert_allclose(route.waypoints_m[[0, -1]], [start, goal])
                rows, cols = _crossed_cells(tmap, route.waypoints_m)
                assert not tmap.obstacle[rows, cols].any()
                assert not cost.blocked[rows, cols].any()


def test_a_passage_too_narrow_for_the_guide_falls_back_to_the_one_cell_lattice():
    tmap = _wall_map(gap_rows=(41, 42))  # a one-cell gap, between the nodes of a 3-cell lattice
    cost = _cost(tmap)
    start, goal = (5.0, 10.0), (75.0, 10.0)
    assert not Lattice.for_cost(cost, 3).shortest_path(start, goal).found
    path = anyangle_path(cost, start, goal, guide_stride_cells=3)
    assert path.found and path.guide_stride_cells == 1
    route = plan_route(tmap, start, goal, cost=cost, planner="anyangle",
                       settings=PlannerSettings(anyangle_guide_stride_cells=3))
    assert route.status == "exact"
    for wp in (path.waypoints_m, route.waypoints_m):
        rows, cols = _crossed_cells(tmap, wp)
        assert not tmap.obstacle[rows, cols].any()
        (x0, y0), (x1, y1) = next((a, b) for a, b in zip(wp[:-1], wp[1:]) if (a[0] - 40.5) * (b[0] - 40.5) <= 0)
        assert 41.0 <= y0 + (40.5 - x0) / (x1 - x0) * (y1 - y0) <= 42.0  # through the gap
    # taut: the two straight legs to the gap's centre
    assert route.length_m <= math.dist(start, (40.5, 41.5)) + math.dist((40.5, 41.5), goal) + 1e-6


# --------------------------------------------------------------------------- statuses and errors: as the lattice
def test_walled_off_goal_is_infeasible_like_the_lattice():
    tmap = _wall_map(gap=False)
    cost = _cost(tmap)
    for planner in ("anyangle", "lattice"):
        route = plan_route(tmap, (5.0, 10.0), (75.0, 10.0), cost=cost, planner=planner)
        assert route.status == "infeasible" and not route.found
        assert route.waypoints_m.shape == (0, 2) and math.isnan(route.energy_j)
    path = anyangle_path(cost, (5.0, 10.0), (75.0, 10.0))
    assert not path.found and path.drive_energy_j == math.inf and path.waypoints_m.shape == (0, 2)


@pytest.mark.parametrize("planner", ["anyangle", "lattice"])
def test_start_or_goal_on_an_obstacle_raises_like_the_lattice(planner):
    tmap = _wall_map()
    cost = _cost(tmap)
    with pytest.raises(BlockedPositionError, match="start_xy_m .* obstacle"):
        plan_route(tmap, (40.5, 10.0), (75.0, 10.0), cost=cost, planner=planner)
    with pytest.raises(BlockedPositionError, match="goal_xy_m .* obstacle"):
        plan_route(tmap, (5.0, 10.0), (40.2, 3.0), cost=cost, planner=planner)
    with pytest.raises(OutOfBoundsError, match="outside the map"):
        plan_route(tmap, (-1.0, 10.0), (75.0, 10.0), cost=cost, planner=planner)
    with pytest.raises(InvalidParameterError, match="start equals goal"):
        plan_route(tmap, (5.0, 10.0), (5.0, 10.0), cost=cost, planner=planner)


def test_anyangle_is_a_registered_untimed_deterministic_planner():
    assert "anyangle" in PLANNERS
    tmap = procedural_map((64, 64), 1.0, seed=3)
    cost = _cost(tmap)
    (start, goal), = _random_queries(cost, 3, 1)
    a = plan_route(tmap, start, goal, cost=cost, planner="anyangle", time_limit_s=None)
    b = plan_route(tmap, start, goal, cost=_cost(tmap), planner="anyangle", seed=9)
    np.testing.assert_array_equal(a.waypoints_m, b.waypoints_m)
    assert a.planning_time_s > 0.0


def test_same_start_and_goal_cell_is_the_direct_segment():
    tmap = _map(np.zeros((10, 10)))
    cost = _cost(tmap)
    path = anyangle_path(cost, (3.1, 3.2), (3.8, 3.9))
    np.testing.assert_allclose(path.waypoints_m, [(3.1, 3.2), (3.8, 3.9)])


# --------------------------------------------------------------------------- settings and checks
@pytest.mark.parametrize("name", ["anyangle_guide_stride_cells", "anyangle_corridor_cells"])
def test_settings_refuse_non_positive_values(name):
    with pytest.raises(InvalidParameterError, match=name):
        PlannerSettings(**{name: 0})


def test_anyangle_path_checks_its_inputs():
    tmap = _map(np.zeros((10, 10)))
    cost = _cost(tmap)
    with pytest.raises(InvalidParameterError, match="cost must be an EnergyCost"):
        anyangle_path(tmap, (1.0, 1.0), (8.0, 8.0))
    with pytest.raises(InvalidParameterError, match="corridor_cells"):
        anyangle_path(cost, (1.0, 1.0), (8.0, 8.0), corridor_cells=0)
    with pytest.raises(InvalidParameterError, match="guide_stride_cells"):
        anyangle_path(cost, (1.0, 1.0), (8.0, 8.0), guide_stride_cells=1.5)
    with pytest.raises(OutOfBoundsError, match="outside the map"):
        anyangle_path(cost, (1.0, 1.0), (18.0, 8.0))
    with pytest.raises(InvalidParameterError, match="waypoints_m has 0 points"):
        AnyAnglePath(True, np.empty((0, 2)), 1.0, 1.0, 1, 0, 0.0)


# --------------------------------------------------------------------------- polish
def test_polish_straightens_a_zigzag_and_never_raises_the_energy():
    tmap = _map(np.zeros((30, 40)))
    cost = _cost(tmap)
    zigzag = np.array([[2.0, 2.0], [10.0, 12.0], [20.0, 3.0], [30.0, 14.0], [37.5, 20.5]])
    out = polish_path(cost, zigzag)
    assert cost.path_energy_j(out) < cost.path_energy_j(zigzag)
    np.testing.assert_array_equal(out[[0, -1]], zigzag[[0, -1]])
    straight = cost.path_energy_j(zigzag[[0, -1]])
    assert cost.path_energy_j(out) == pytest.approx(straight, rel=2e-3)
    # already optimal: returned as it is
    np.testing.assert_array_equal(polish_path(cost, zigzag[[0, -1]]), zigzag[[0, -1]])


def test_polish_keeps_the_route_valid_around_a_wall():
    tmap = _wall_map()
    cost = _cost(tmap)
    rough = np.array([[5.0, 10.0], [20.0, 47.0], [40.5, 42.5], [60.0, 2.0], [75.0, 10.0]])
    out = polish_path(cost, rough, spacings_m=(6.0, 2.0), step_min_m=0.01)
    assert cost.path_energy_j(out) < cost.path_energy_j(rough)
    rows, cols = _crossed_cells(tmap, out)
    assert not tmap.obstacle[rows, cols].any()


def test_polish_refuses_invalid_routes_and_settings():
    tmap = _wall_map()
    cost = _cost(tmap)
    with pytest.raises(InvalidParameterError, match="blocked"):
        polish_path(cost, [[5.0, 10.0], [75.0, 10.0]])
    with pytest.raises(InvalidParameterError, match="spacings_m"):
        polish_path(cost, [[5.0, 10.0], [6.0, 10.0]], spacings_m=())
    with pytest.raises(InvalidParameterError, match="spacings_m"):
        polish_path(cost, [[5.0, 10.0], [6.0, 10.0]], spacings_m=(-1.0,))
    with pytest.raises(InvalidParameterError, match="max_sweeps"):
        polish_path(cost, [[5.0, 10.0], [6.0, 10.0]], max_sweeps=0)
