"""The hilly map, its depot and reachability, and a one-way cost, shared by the reachability tests."""

from __future__ import annotations

import numpy as np
import pytest

import terrain
from planner import CostTables, EnergyCost, Reachability, reachability
from planner.cost_spec import CostSpec

DEPOT = (17.3, 21.6)  # not a cell centre: joined to the nodes within 1.5 cells, like a lattice query's start
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def hilly_cost() -> EnergyCost:
    """36 x 44 cells of 1 m: hills, four grounds, rocks and a wall with a gap."""
    tmap = terrain.procedural_map((36, 44), 1.0, seed=7, obstacle_fraction=0.04, n_walls=1, slope_deg=10.0)
    obstacle = np.array(tmap.obstacle)
    r, c = tmap.rowcol(*DEPOT)
    obstacle[r - 1:r + 2, c - 1:c + 2] = False  # keep the depot free whatever the seed draws
    tmap["obstacle"] = obstacle
    return CostSpec(speed_mps=0.5).build(tmap)


@pytest.fixture(scope="module")
def hilly_reach(hilly_cost) -> Reachability:
    return reachability(hilly_cost, DEPOT, round_trip=True)


def one_way_cost(tmap: terrain.TerrainMap, max_uphill_grade: float) -> EnergyCost:
    """Custom tables: 100 J/m plus 2000 J/m per unit grade uphill, undrivable above ``max_uphill_grade``."""
    grades = np.linspace(-np.tan(np.radians(20.0)), np.tan(np.radians(20.0)), 41)
    table = 100.0 + 2000.0 * np.clip(grades, 0.0, None)
    table[grades > max_uphill_grade] = np.inf
    return EnergyCost(tmap, np.zeros(tmap.shape, np.int32), CostTables(table[None, :], np.ones((1, 5))), speed_mps=0.5, battery_voltage_v=24.0, turn_rate_radps=1.0)
