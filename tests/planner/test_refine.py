"""Tests of planner.refine: relax_path straightens, keeps routes valid and refracts at a ground boundary."""

from __future__ import annotations

import math

import numpy as np
import pytest
from edge_cost_samples import LinearModel, flat_terrain

from planner import CostSpec
from terrain import TerrainMap


def test_relax_path_straightens_zigzag_and_never_raises_energy():
    cost = CostSpec(energy_model=LinearModel(a=50.0, c=30.0), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain())
    zigzag = np.array([[1.0, 1.0], [6.0, 4.0], [11.0, 1.0], [16.0, 4.0], [25.0, 1.0]])
    out = cost.relax_path(zigzag)
    assert cost.path_energy_j(out) <= cost.path_energy_j(zigzag)
    np.testing.assert_allclose(out, [[1.0, 1.0], [25.0, 1.0]], atol=0.05)
    assert cost.path_energy_j(out) == pytest.approx(50.0 * 24.0, rel=1e-3)


def test_relax_path_keeps_route_valid_around_obstacle():
    obstacle = np.zeros((20, 30), bool)
    obstacle[0:15, 15] = True
    cost = CostSpec(energy_model=LinearModel(a=50.0, c=5.0), grounds={"g": 1.0}, speed_mps=0.5).build(flat_terrain(obstacle=obstacle))
    route = np.array([[5.5, 5.5], [10.5, 17.5], [20.5, 17.5], [25.5, 5.5]])
    out = cost.relax_path(route)
    assert np.isfinite(cost.path_energy_j(out))
    assert cost.path_energy_j(out) < cost.path_energy_j(route)
    np.testing.assert_array_equal(out[[0, -1]], route[[0, -1]])


def test_relax_path_refracts_at_a_ground_boundary_like_snell():
    """Fast ground (y < 20 m) and ground twice as costly above: the optimum bends at the
    boundary where 1 * sin(a1) = 2 * sin(a2); the crossing point is found by a 1-D search."""
    from scipy.optimize import minimize_scalar

    ground = np.zeros((40, 60), int)
    ground[20:, :] = 1
    tmap = TerrainMap(np.zeros((40, 60)), 1.0, ground=ground, ground_names={0: "fast", 1: "slow"})
    model = LinearModel(a=50.0, c=0.5)
    cost = CostSpec(energy_model=model, grounds={"fast": 1.0, "slow": 2.0}, speed_mps=0.5).build(tmap)
    a, b = np.array([5.0, 2.0]), np.array([50.0, 38.0])

    def energy(x: float) -> float:
        p = np.array([x, 20.0])
        u, v = p - a, b - p
        turn = abs(math.atan2(u[0] * v[1] - u[1] * v[0], u @ v))
        return 50.0 * np.hypot(*u) + 100.0 * np.hypot(*v) + 0.5 * turn

    best = minimize_scalar(energy, bounds=(a[0], b[0]), method="bounded", options={"xatol": 1e-6})
    one = cost.relax_path([a, b], levels=1)
    out = cost.relax_path([a, b])
    assert cost.path_energy_j(out) <= cost.path_energy_j(one) <= cost.path_energy_j([a, b])
    assert cost.path_energy_j(out) == pytest.approx(best.fun, rel=2e-4)
    crossing = np.interp(20.0, out[:, 1], out[:, 0])  # y rises along the route
    assert crossing == pytest.approx(best.x, abs=0.3)
