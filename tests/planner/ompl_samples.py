"""Small edge costs for the OMPL tests: an open flat map, a ramp and the wall map."""

from __future__ import annotations

import numpy as np

from planner import EnergyCost
from planner.cost_spec import CostSpec
from terrain import TerrainMap


def flat_cost() -> EnergyCost:
    """20 x 30 cells of 1 m of level asphalt."""
    tmap = TerrainMap(np.zeros((20, 30)), 1.0, ground=np.zeros((20, 30), int), ground_names={0: "asphalt"})
    return CostSpec(speed_mps=0.5).build(tmap)


def ramp_cost(grade: float = 0.1) -> EnergyCost:
    """20 x 30 cells of asphalt rising ``grade`` towards +x."""
    x = np.arange(30) + 0.5
    tmap = TerrainMap(np.broadcast_to(grade * x, (20, 30)).copy(), 1.0, ground=np.zeros((20, 30), int),
                      ground_names={0: "asphalt"})
    return CostSpec(speed_mps=0.5).build(tmap)
