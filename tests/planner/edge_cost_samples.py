"""A closed-form stand-in energy model and flat, ramp and rough maps, shared by the edge cost, cost query and refine tests."""

from __future__ import annotations

import numpy as np

from terrain import TerrainMap


class _Robot:
    battery_voltage_v = 24.0
    turn_rate_radps = 0.5


class LinearModel:
    """Stand-in with a closed form: e(s) = a + b * max(s, 0) J per metre travelled, turns c J/rad."""

    robot = _Robot()

    def __init__(self, a: float = 50.0, b: float = 400.0, c: float = 30.0) -> None:
        self.a, self.b, self.c = a, b, c

    def energy_per_metre_j(self, speed_mps, grade, ground):
        g = np.asarray(grade, dtype=float)
        return self.a * ground + self.b * np.maximum(g, 0.0)

    def turn_energy_j(self, heading_change_rad, ground):
        return self.c * np.abs(np.asarray(heading_change_rad, dtype=float))


def flat_terrain(rows=20, cols=30, cell=1.0, origin=(0.0, 0.0), obstacle=None):
    return TerrainMap(
        np.zeros((rows, cols)), cell, origin,
        ground=np.zeros((rows, cols), int), ground_names={0: "g"}, obstacle=obstacle,
    )


def ramp_terrain(grade=0.1, rows=20, cols=40, cell=1.0):
    x = (np.arange(cols) + 0.5) * cell
    return TerrainMap(
        np.broadcast_to(grade * x, (rows, cols)), cell, ground=np.zeros((rows, cols), int), ground_names={0: "asphalt"}
    )


def rough_terrain(seed=0, n=48, cell=0.5):
    rng = np.random.default_rng(seed)
    z = np.cumsum(np.cumsum(rng.normal(0, 0.01, (n, n)), axis=0), axis=1)
    ground = (rng.random((n, n)) < 0.3).astype(int)
    obstacle = rng.random((n, n)) < 0.03
    return TerrainMap(z, cell, (5.0, -3.0), ground=ground, ground_names={0: "a", 1: "b"}, obstacle=obstacle)
