"""Shared samples of the tour tests: a cost with a known run-level spread, a map of hills on two grounds, a snow ridge."""

from __future__ import annotations

import numpy as np
import pytest

from planner import CostTables, EnergyCost
from planner.cost_spec import CostSpec
from terrain import TerrainMap

__all__ = ["with_interval", "hills_map", "hills_cost", "ridge_map"]


def with_interval(cost: EnergyCost, rel_sd: float = 0.15) -> EnergyCost:
    """``cost`` with a run-level spread of ``rel_sd`` of every mean entry (one ground's spreads shared by the run)."""
    sd = np.nan_to_num(np.abs(rel_sd * cost.tables.grade_table_j_per_m), nan=0.0, posinf=0.0)
    return cost.with_tables(CostTables(cost.tables.grade_table_j_per_m, cost.tables.turn_table_j, ground_labels=cost.tables.ground_labels, grade_sd_table_j_per_m=sd, turn_sd_table_j=np.abs(rel_sd * cost.tables.turn_table_j)))


def hills_map() -> TerrainMap:
    """40 x 40 cells of 1 m: two round hills on asphalt, sand on the east half (two grounds)."""
    y, x = np.mgrid[0:40, 0:40] + 0.5
    z = 3.0 * np.exp(-((x - 14) ** 2 + (y - 26) ** 2) / 60.0) + 2.0 * np.exp(-((x - 28) ** 2 + (y - 12) ** 2) / 40.0)
    ground = np.where(x > 20, 1, 0)
    return TerrainMap(z, 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"})


@pytest.fixture(scope="module")
def hills_cost() -> EnergyCost:
    return with_interval(CostSpec().build(hills_map()))


def ridge_map() -> TerrainMap:
    """40 x 40 cells of 1 m of snow: a north-south ridge (y >= 10) whose west face (grade 0.25) snow cannot climb
    but can descend, and whose east face is gentle (grade 0.075); flat south of y = 10."""
    y, x = np.mgrid[0:40, 0:40] + 0.5
    prof = np.where(x < 12, 0.0, np.where(x < 18, 0.25 * (x - 12), np.maximum(1.5 - 0.075 * (x - 18), 0.0)))
    return TerrainMap(np.where(y >= 10, prof, 0.0), 1.0, ground=np.zeros((40, 40), int), ground_names={0: "snow"})
