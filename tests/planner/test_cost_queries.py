"""Tests of planner.cost_queries (the queries of an EnergyCost): turns and path energy, surface length, the admissible lower bound, bad points."""

from __future__ import annotations

import math

import numpy as np
import pytest

from energy import PhysicsEnergyModel, ground_preset, robot_preset
from planner import EnergyCost, Lattice
from terrain import InvalidParameterError, OutOfBoundsError

from edge_cost_samples import LinearModel, flat_terrain, ramp_terrain, rough_terrain


def test_turn_energies_and_path_energy():
    cost = EnergyCost.from_model(flat_terrain(), LinearModel(a=50.0, c=30.0), {"g": 1.0}, speed_mps=0.5)
    pts = np.array([[1.0, 1.0], [11.0, 1.0], [11.0, 1.0], [11.0, 6.0], [6.0, 1.0]])
    angles, turns = cost.turn_energies_j(pts)
    # Repeated point: the 90 degree turn is taken where the new heading starts (index 2).
    np.testing.assert_allclose(angles, [0, 0, math.pi / 2, 3 * math.pi / 4, 0], atol=1e-12)
    np.testing.assert_allclose(turns, 30.0 * angles, rtol=1e-9, atol=1e-12)
    length = 10 + 5 + math.hypot(5, 5)
    assert cost.path_energy_j(pts) == pytest.approx(50.0 * length + 30.0 * (math.pi / 2 + 3 * math.pi / 4), rel=1e-9)


def test_surface_length_on_ramp():
    grade = 0.2
    cost = EnergyCost.from_model(ramp_terrain(grade), LinearModel(), {"asphalt": 1.0}, speed_mps=0.5)
    assert cost.surface_length_m([[5.0, 3.0], [25.0, 3.0], [25.0, 13.0]]) == pytest.approx(
        20 * math.sqrt(1 + grade**2) + 10, rel=1e-9
    )


def test_lower_bound_is_admissible():
    tmap = rough_terrain(seed=3, n=40, cell=1.0)
    model = PhysicsEnergyModel(robot_preset("husky"))
    grounds = {"a": ground_preset("asphalt"), "b": ground_preset("grass")}
    cost = EnergyCost.from_model(tmap, model, grounds, speed_mps=0.5, max_slope_rad=0.6)
    assert cost.min_energy_per_metre_j > 0
    lattice = Lattice(cost)
    rng = np.random.default_rng(4)
    free = np.argwhere(~cost.blocked)
    xs, ys = tmap.cell_centres()
    checked = 0
    for _ in range(25):
        (r0, c0), (r1, c1) = free[rng.choice(len(free), 2, replace=False)]
        a, b = np.array([xs[c0], ys[r0]]), np.array([xs[c1], ys[r1]])
        bound = cost.lower_bound_j(a, b)[0]
        path = lattice.shortest_path(a, b)
        if path.found:
            assert bound <= path.objective * (1 + 1e-12)
            checked += 1
        e = cost.segment_energy_j(a, b)[0]
        assert bound <= e * (1 + 1e-12)
    assert checked >= 10
    # Random (valid) polylines cost at least the bound too.
    pts = rng.uniform([xs[0], ys[0]], [xs[-1], ys[-1]], size=(200, 3, 2))
    for poly in pts:
        e = cost.segment_energy_j(poly[:-1], poly[1:]).sum()
        if np.isfinite(e):
            assert cost.lower_bound_j(poly[0], poly[-1])[0] <= e * (1 + 1e-12)


@pytest.mark.parametrize(
    ("a", "b", "exc", "match"),
    [
        ([[math.nan, 1.0]], [[2.0, 2.0]], InvalidParameterError, "finite"),
        ([[1.0, 1.0]], [[2.0, math.inf]], InvalidParameterError, "finite"),
        ([[1.0, 1.0]], [[31.0, 2.0]], OutOfBoundsError, "outside"),
        ([[1.0, 1.0, 1.0]], [[2.0, 2.0, 2.0]], InvalidParameterError, "shape"),
        ([[1.0, 1.0], [2.0, 2.0]], [[2.0, 2.0]], InvalidParameterError, "equal shapes"),
    ],
)
def test_segment_energy_rejects_bad_points(a, b, exc, match):
    cost = EnergyCost.from_model(flat_terrain(), LinearModel(), {"g": 1.0}, speed_mps=0.5)
    with pytest.raises(exc, match=match):
        cost.segment_energy_j(a, b)


@pytest.mark.parametrize("name", ["starts_xy_m", "ends_xy_m"])
def test_segment_energy_names_a_non_numeric_point(name):
    cost = EnergyCost.from_model(flat_terrain(), LinearModel(), {"g": 1.0}, speed_mps=0.5)
    points = {"starts_xy_m": [[1.0, 1.0]], "ends_xy_m": [[2.0, 2.0]]}
    points[name] = [["one", "two"]]
    with pytest.raises(InvalidParameterError, match=f"{name} must be a real number or an array of them"):
        cost.segment_energy_j(points["starts_xy_m"], points["ends_xy_m"])
