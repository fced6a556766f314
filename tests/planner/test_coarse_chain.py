"""Coarse-to-fine from a GeoTIFF in chained fine windows: a corridor bigger than the cell budget is followed window by window."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner import CoarseOptions, Lattice, plan_coarse_to_fine
from planner.cost_spec import CostSpec
from planner.route import evaluate_route
from terrain import InvalidParameterError, procedural_map, read_geotiff, write_geotiff
from terrawatt_base.errors import PlanningError

rasterio = pytest.importorskip("rasterio", reason="GeoTIFF support needs the geo extra (rasterio)")

SIDE = 512


@pytest.fixture(scope="module")
def dem(tmp_path_factory):
    """A 512^2 procedural DEM (1 m cells), its whole-map cost, and free start / goal near opposite corners."""
    tmap = procedural_map((SIDE, SIDE), 1.0, seed=3, origin_xy_m=(0.0, 0.0))
    tmap.crs = "EPSG:32633"
    path = write_geotiff(tmap, tmp_path_factory.mktemp("dem") / "dem.tif")
    cost = CostSpec().build(read_geotiff(path))
    labels = cost.components()
    rr, cc = np.nonzero(labels == np.bincount(labels[labels > 0]).argmax())

    def free_near(col, row):
        k = int(np.argmin((rr - row) ** 2 + (cc - col) ** 2))
        return (float(cc[k]) + 0.5, float(rr[k]) + 0.5)

    return path, cost, free_near(20, 30), free_near(490, 470)


@pytest.fixture(scope="module")
def optimum(dem):
    _, cost, start, goal = dem
    return Lattice(cost, 1).shortest_path(start, goal).objective


@pytest.fixture(scope="module")
def unlimited(dem):
    path, _, start, goal = dem
    return plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=4))


def window_cells(plan):
    return [(r1 - r0) * (c1 - c0) for r0, r1, c0, c1 in plan.fine_windows]


def test_the_default_budget_reads_one_window(unlimited):
    assert unlimited.route.status == "exact" and unlimited.fallback == "none"
    assert len(unlimited.fine_windows) == 1 and unlimited.fine_window_cells == window_cells(unlimited)[0]
    assert unlimited.fine_map is not None
    summary = unlimited.summary()
    assert summary["fine_windows"] == 1 and summary["fine_window_max_cells"] == unlimited.fine_window_cells


@pytest.mark.parametrize("budget", [100 * 100, 60 * 60])
def test_a_small_budget_chains_windows_along_the_route(dem, optimum, unlimited, budget):
    path, cost, start, goal = dem
    plan = plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=4, fine_window_budget_cells=budget))
    route = plan.route
    assert route.status == "exact" and route.planner == "coarse-to-fine" and plan.fallback == "none"
    # the windows read: several, none above the budget, their cells summed
    sizes = window_cells(plan)
    assert len(sizes) > 3 and max(sizes) <= budget
    assert plan.fine_window_cells == sum(sizes) and plan.fine_map is None
    assert plan.summary()["fine_window_max_cells"] == max(sizes)
    # start to goal, no blocked cell crossed: the whole map's cost prices the route alike
    assert np.array_equal(route.waypoints_m[0], start) and np.array_equal(route.waypoints_m[-1], goal)
    whole = evaluate_route(cost, route.waypoints_m)
    assert np.all(np.isfinite(whole.segment_energy_j))
    np.testing.assert_allclose(route.segment_energy_j, whole.segment_energy_j, rtol=1e-12)
    np.testing.assert_allclose(route.turn_energy_j, whole.turn_energy_j, rtol=1e-9, atol=1e-9)
    assert route.energy_j == pytest.approx(whole.energy_j, rel=1e-12)
    assert route.duration_s == pytest.approx(whole.duration_s, rel=1e-12)
    assert route.length_m == pytest.approx(whole.length_m, rel=1e-12)
    assert plan.objective_j == pytest.approx(float(whole.segment_energy_j.sum()), rel=1e-12)
    # within a few % of one window and of the full-resolution lattice optimum (a straight
    # segment from a window's start to its target may beat the lattice: below 1 is possible)
    assert plan.objective_j / unlimited.objective_j == pytest.approx(1.0, abs=0.03)
    assert plan.objective_j / optimum == pytest.approx(1.0, abs=0.03)
    assert route.energy_j / unlimited.route.energy_j == pytest.approx(1.0, abs=0.03)


def test_a_budget_that_holds_the_bounding_window_changes_nothing(dem, unlimited):
    path, _, start, goal = dem
    budget = window_cells(unlimited)[0]
    plan = plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=4, fine_window_budget_cells=budget))
    assert plan.fine_windows == unlimited.fine_windows
    assert np.array_equal(plan.route.waypoints_m, unlimited.route.waypoints_m)
    assert plan.objective_j == unlimited.objective_j
    chained = plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=4, fine_window_budget_cells=budget - 1))
    assert len(chained.fine_windows) > 1 and max(window_cells(chained)) < budget


def test_the_preset_pricer_shortcut_equals_a_general_pricer(dem):
    path, _, start, goal = dem
    preset = CostSpec(robot="jackal", max_slope_deg=math.degrees(0.3))

    def general(tmap):  # not recognised as a preset pricer: an EnergyCost per tile
        return preset.build(tmap)

    options = CoarseOptions(factor=8, fine_window_budget_cells=120 * 120)
    a = plan_coarse_to_fine(path, start, goal, options, cost_from=preset)
    b = plan_coarse_to_fine(path, start, goal, options, cost_from=general)
    assert np.array_equal(a.coarse_map.elevation_m, b.coarse_map.elevation_m)
    assert np.array_equal(a.coarse_map.obstacle, b.coarse_map.obstacle) and a.coarse_map.obstacle.any()
    assert np.array_equal(a.route.waypoints_m, b.route.waypoints_m) and a.fine_windows == b.fine_windows


def wall_dem(path, gap_rows):
    """Flat ground with a one-cell steep wall along column 64 (a coarse block of 8 cells does not see it)."""
    z = np.zeros((128, 128))
    z[:, 64] = 10.0
    if gap_rows is not None:
        z[gap_rows[0]:gap_rows[1], 64] = 0.0
    with rasterio.open(path, "w", driver="GTiff", height=128, width=128, count=1, dtype="float32",
                       crs="EPSG:32633", transform=rasterio.Affine(1.0, 0.0, 0.0, 0.0, -1.0, 128.0)) as dst:
        dst.write(z[::-1].astype("float32"), 1)
    return path


def test_a_stretch_without_route_is_widened(tmp_path):
    path = wall_dem(tmp_path / "wall.tif", (44, 52))
    start, goal = (4.5, 20.5), (124.5, 20.5)
    plan = plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=8, corridor_m=4.0,
                                                                fine_window_budget_cells=60 * 60))
    assert plan.route.status == "exact" and plan.fallback == "wider corridor" and plan.corridor_m == 16.0
    assert len(plan.fine_windows) > 1 and max(window_cells(plan)) <= 60 * 60
    assert plan.route.waypoints_m[:, 1].max() >= 44.0
    cost = CostSpec().build(read_geotiff(path))
    assert np.all(np.isfinite(evaluate_route(cost, plan.route.waypoints_m).segment_energy_j))


def test_no_route_and_a_map_above_the_budget_is_a_planning_error(tmp_path):
    path = wall_dem(tmp_path / "wall.tif", None)
    start, goal = (4.5, 20.5), (124.5, 20.5)
    with pytest.raises(PlanningError, match="holds no full-resolution route"):
        plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=8, corridor_m=4.0,
                                                             fine_window_budget_cells=60 * 60))
    with pytest.raises(PlanningError, match=r"\[32.0\] m not tried, its windows exceed budget_cells=3600"):
        plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=8, corridor_m=8.0,
                                                             fine_window_budget_cells=60 * 60))
    with pytest.raises(PlanningError, match=r"exceeds fine_window_budget_cells=10000"):
        plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=8, corridor_m=8.0,
                                                             fine_window_budget_cells=100 * 100))
    # a budget that holds the whole map: the whole-map fallback proves it infeasible, as before
    plan = plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=8, corridor_m=8.0,
                                                                fine_window_budget_cells=128 * 128))
    assert plan.route.status == "infeasible" and plan.fallback == "whole map"


@pytest.mark.parametrize(("budget", "match"), [
    (0, "fine_window_budget_cells"),
    (2.5, "fine_window_budget_cells"),
    (True, "fine_window_budget_cells"),
    (40 * 40, r"fine_window_budget_cells=1600 cannot hold a window of the corridor \(half-width 12 m at factor 4: "
              r"2116 cells .* expected at least 2116"),
])
def test_bad_budgets(dem, budget, match):
    path, _, start, goal = dem
    with pytest.raises(InvalidParameterError, match=match):
        plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=4, fine_window_budget_cells=budget))
